// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file light_dome.cpp
/// Median-cut light domes and the procedural sky probe (light_dome.h).

#include "sss/light/light_dome.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>

#include <glm/geometric.hpp>

#include "sss/util/error.h"
#include "sss/util/math.h"

namespace sss {

namespace {

double luminance(const float* c) {
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

/// A region being cut: pixels [x0, x1) x [y0, y1), and the share of its
/// energy it carries (1, or less for a single pixel cut further).
struct Region {
    int x0, y0, x1, y1;
    double share = 1.0;
};

/// The map's per-pixel quantities the cut needs.
struct Prepared {
    int w = 0, h = 0;
    std::vector<double> energy;    ///< luminance x solid angle per pixel
    std::vector<glm::dvec3> dirs;  ///< pixel centre directions
    std::vector<double> row_omega; ///< solid angle of a pixel per row
};

Prepared prepare(const LatLongImage& image) {
    Prepared p;
    p.w = image.width;
    p.h = image.height;
    p.row_omega.resize(p.h);
    for (int y = 0; y < p.h; ++y) p.row_omega[y] = latlong_pixel_solid_angle(y, p.w, p.h);
    p.energy.resize(static_cast<std::size_t>(p.w) * p.h);
    p.dirs.resize(p.energy.size());
    for (int y = 0; y < p.h; ++y)
        for (int x = 0; x < p.w; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * p.w + x;
            p.energy[i] = luminance(image.pixel(x, y)) * p.row_omega[y];
            p.dirs[i] = latlong_direction((x + 0.5) / p.w, (y + 0.5) / p.h);
        }
    return p;
}

/// Cuts r in two (a, b) along its longer side where the energy is split
/// closest to half (ties: nearest the middle). A single pixel gives two halves.
void cut(const Prepared& p, const Region& r, Region& a, Region& b) {
    const int nx = r.x1 - r.x0, ny = r.y1 - r.y0;
    if (nx == 1 && ny == 1) {
        a = b = r;
        a.share = b.share = r.share * 0.5;
        return;
    }
    const double mid_lat = kPi * (0.5 - 0.5 * (r.y0 + r.y1) / p.h);
    const double wide = nx * (2.0 * kPi / p.w) * std::cos(mid_lat);
    const double tall = ny * (kPi / p.h);
    const bool along_x = ny < 2 || (nx >= 2 && wide >= tall);
    const int lo = along_x ? r.x0 : r.y0, hi = along_x ? r.x1 : r.y1;
    std::vector<double> sums(hi - lo, 0.0);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
            sums[(along_x ? x : y) - lo] +=
                p.energy[static_cast<std::size_t>(y) * p.w + x];
    double total = 0.0;
    for (double s : sums) total += s;
    const double middle = 0.5 * (lo + hi);
    int best = lo + (hi - lo) / 2;
    double best_gap = std::numeric_limits<double>::infinity();
    double cum = 0.0;
    for (int c = lo + 1; c < hi; ++c) {
        cum += sums[c - 1 - lo];
        const double gap = std::abs(cum - 0.5 * total);
        const bool better =
            gap < best_gap ||
            (gap == best_gap && std::abs(c - middle) < std::abs(best - middle));
        if (better) {
            best_gap = gap;
            best = c;
        }
    }
    a = b = r;
    if (along_x) {
        a.x1 = best;
        b.x0 = best;
    } else {
        a.y1 = best;
        b.y0 = best;
    }
}

DomeLight region_light(const Prepared& p, const LatLongImage& image, const Region& r) {
    DomeLight l;
    l.x0 = r.x0;
    l.y0 = r.y0;
    l.x1 = r.x1;
    l.y1 = r.y1;
    glm::dvec3 color(0.0), centroid(0.0);
    double energy = 0.0;
    for (int y = r.y0; y < r.y1; ++y) {
        const double omega = p.row_omega[y];
        for (int x = r.x0; x < r.x1; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * p.w + x;
            const float* c = image.pixel(x, y);
            color += glm::dvec3(c[0], c[1], c[2]) * omega;
            energy += p.energy[i];
            centroid += p.energy[i] * p.dirs[i];
        }
    }
    l.color = color * r.share;
    const double len = glm::length(centroid);
    if (energy > 0.0 && len > 1e-9 * energy)
        l.direction = centroid / len;
    else
        l.direction =
            latlong_direction(0.5 * (r.x0 + r.x1) / p.w, 0.5 * (r.y0 + r.y1) / p.h);
    return l;
}

std::string num(double v) {
    if (v == 0.0) v = 0.0; // no "-0"
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

} // namespace

LatLongImage::LatLongImage(int w, int h) : width(w), height(h) {
    if (h <= 0 || w != 2 * h)
        throw ValueError("a lat-long image must be twice as wide as high, not " +
                         std::to_string(w) + " x " + std::to_string(h));
    rgb.assign(static_cast<std::size_t>(w) * h * 3, 0.0f);
}

glm::dvec3 latlong_direction(double s, double t) {
    const double phi = 2.0 * kPi * (s - 0.5);
    const double theta = kPi * (0.5 - t);
    return {-std::cos(theta) * std::sin(phi), std::sin(theta),
            std::cos(theta) * std::cos(phi)};
}

void latlong_coordinates(const glm::dvec3& d, double& s, double& t) {
    s = std::atan2(-d.x, d.z) / (2.0 * kPi) + 0.5;
    if (s >= 1.0) s -= 1.0;
    t = 0.5 - std::atan2(d.y, std::hypot(d.x, d.z)) / kPi;
}

double latlong_pixel_solid_angle(int y, int w, int h) {
    const double top = kPi * (0.5 - static_cast<double>(y) / h);
    const double bottom = kPi * (0.5 - static_cast<double>(y + 1) / h);
    return 2.0 * kPi / w * (std::sin(top) - std::sin(bottom));
}

glm::dvec3 latlong_integral(const LatLongImage& image) {
    glm::dvec3 sum(0.0);
    for (int y = 0; y < image.height; ++y) {
        glm::dvec3 row(0.0);
        for (int x = 0; x < image.width; ++x) {
            const float* c = image.pixel(x, y);
            row += glm::dvec3(c[0], c[1], c[2]);
        }
        sum += row * latlong_pixel_solid_angle(y, image.width, image.height);
    }
    return sum;
}

std::vector<DomeLight> median_cut(const LatLongImage& image, int count) {
    if (count < 1 || count > 65536 || (count & (count - 1)) != 0)
        throw ValueError(
            "the number of dome lights must be a power of two from 1 to 65536, not " +
            std::to_string(count));
    if (image.height <= 0 || image.width != 2 * image.height ||
        image.rgb.size() != static_cast<std::size_t>(image.width) * image.height * 3)
        throw ValueError("a lat-long image must be twice as wide as high, not " +
                         std::to_string(image.width) + " x " +
                         std::to_string(image.height));
    for (std::size_t i = 0; i < image.rgb.size(); ++i)
        if (!std::isfinite(image.rgb[i]) || image.rgb[i] < 0.0f) {
            const std::size_t px = i / 3;
            throw ValueError("probe pixel (" + std::to_string(px % image.width) + ", " +
                             std::to_string(px / image.width) + ") is " +
                             (std::isfinite(image.rgb[i]) ? "negative" : "not finite") +
                             ": " + std::to_string(image.rgb[i]));
        }
    const Prepared p = prepare(image);
    std::vector<Region> regions = {Region{0, 0, image.width, image.height, 1.0}};
    while (static_cast<int>(regions.size()) < count) {
        std::vector<Region> next;
        next.reserve(regions.size() * 2);
        for (const Region& r : regions) {
            Region a, b;
            cut(p, r, a, b);
            next.push_back(a);
            next.push_back(b);
        }
        regions.swap(next);
    }
    std::vector<DomeLight> lights;
    lights.reserve(regions.size());
    for (const Region& r : regions) lights.push_back(region_light(p, image, r));
    return lights;
}

std::string dome_rib(const std::vector<DomeLight>& lights, const DomeRibOptions& o) {
    glm::dvec3 total(0.0);
    for (const DomeLight& l : lights) total += l.color;
    const double a = o.rotate_degrees * kPi / 180.0;
    const double ca = std::cos(a), sa = std::sin(a);
    std::ostringstream out;
    out << "## envdome: " << lights.size()
        << " distant lights by median cut (Debevec 2005)\n"
        << "## probe: " << (o.probe.empty() ? "(none)" : o.probe) << "\n"
        << "## integral of the probe over the sphere (RGB, radiance x sr): "
        << num(total.x) << " " << num(total.y) << " " << num(total.z) << "\n"
        << "## lightcolor = region integral / pi, intensity = " << num(o.intensity)
        << ", rotation about +y = " << num(o.rotate_degrees) << " degrees\n"
        << "## shadows: "
        << (o.shadows ? "ray traced (distantlight_rts)" : "none (distantlight)") << "\n";
    const char* shader = o.shadows ? "distantlight_rts" : "distantlight";
    int handle = o.first_handle;
    for (const DomeLight& l : lights) {
        const glm::dvec3 d(ca * l.direction.x + sa * l.direction.z, l.direction.y,
                           -sa * l.direction.x + ca * l.direction.z);
        const glm::dvec3 c = l.color / kPi;
        out << "LightSource \"" << shader << "\" \"envdome" << handle++
            << "\" \"intensity\" [" << num(o.intensity) << "] \"lightcolor\" ["
            << num(c.x) << " " << num(c.y) << " " << num(c.z)
            << "] \"from\" [0 0 0] \"to\" [" << num(-d.x) << " " << num(-d.y) << " "
            << num(-d.z) << "]\n";
    }
    return out.str();
}

glm::dvec3 sun_direction(const SkyOptions& o) {
    const double el = o.sun_elevation * kPi / 180.0, az = o.sun_azimuth * kPi / 180.0;
    return {std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el)};
}

LatLongImage sky_probe(int width, int height, const SkyOptions& o) {
    LatLongImage img(width, height);
    const glm::dvec3 sun = sun_direction(o);
    const double cos_sun = std::cos(o.sun_radius * kPi / 180.0);
    const glm::dvec3 zenith(0.25, 0.45, 1.0), horizon(0.85, 0.9, 1.0);
    const glm::dvec3 ground(0.35, 0.3, 0.25), sun_color(1.0, 0.95, 0.85);
    constexpr int kSub = 4;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            glm::dvec3 sum(0.0);
            for (int j = 0; j < kSub; ++j)
                for (int i = 0; i < kSub; ++i) {
                    const glm::dvec3 d = latlong_direction(
                        (x + (i + 0.5) / kSub) / width, (y + (j + 0.5) / kSub) / height);
                    glm::dvec3 c;
                    if (d.y >= 0.0) {
                        const double k = std::pow(d.y, 0.5);
                        c = o.sky_radiance * (horizon * (1.0 - k) + zenith * k);
                        if (glm::dot(d, sun) >= cos_sun) c += o.sun_radiance * sun_color;
                    } else {
                        c = o.ground_radiance * ground;
                    }
                    sum += c;
                }
            sum /= double(kSub * kSub);
            float* px = img.pixel(x, y);
            px[0] = static_cast<float>(sum.x);
            px[1] = static_cast<float>(sum.y);
            px[2] = static_cast<float>(sum.z);
        }
    return img;
}

} // namespace sss

// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file light_dome.h
/// Image-based lighting without ray-traced environment sampling: a lat-long
/// HDR light probe turned into a dome of distant lights by Debevec's median
/// cut ("A Median Cut Algorithm for Light Probe Sampling", 2005), and a
/// procedural sky probe. Pure algorithms on float RGB arrays; reading and
/// writing image files is the caller's business (the envdome tool uses the
/// render module's image_io). docs/lighting.md has the user-facing rules.
///
/// Orientation (the one environment() uses: OpenImageIO's TextureSystem with
/// "y" up, given world-space directions): pixel (s, t) in [0,1]^2, s from
/// left to right, t from the top row down, is the direction
///     longitude phi = 2 pi (s - 0.5), latitude theta = pi (0.5 - t),
///     d = (-cos(theta) sin(phi), sin(theta), cos(theta) cos(phi)):
/// the top row is +y, the bottom row -y, the centre column +z, s = 0.25 is
/// +x, s = 0.75 is -x and the left and right edges are -z.

#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

/// A float RGB lat-long image: width = 2 * height, rows top (+y) to bottom.
struct LatLongImage {
    int width = 0;
    int height = 0;
    std::vector<float> rgb; ///< width * height * 3, row-major

    LatLongImage() = default;
    /// A w x h image, every value 0. Throws ValueError unless w = 2 h > 0.
    LatLongImage(int w, int h);
    const float* pixel(int x, int y) const {
        return rgb.data() + (static_cast<std::size_t>(y) * width + x) * 3;
    }
    float* pixel(int x, int y) {
        return rgb.data() + (static_cast<std::size_t>(y) * width + x) * 3;
    }
};

/// The unit world direction of lat-long coordinates (s, t) (see the file comment).
glm::dvec3 latlong_direction(double s, double t);
/// The lat-long coordinates (s in [0,1), t in [0,1]) of a direction (any length > 0).
void latlong_coordinates(const glm::dvec3& direction, double& s, double& t);
/// The solid angle (steradians) of a pixel of row y in a w x h lat-long image:
/// (2 pi / w) (sin(theta_top) - sin(theta_bottom)); the rows sum to 4 pi.
double latlong_pixel_solid_angle(int y, int w, int h);
/// The integral of the map over the sphere, sum of pixel value x solid angle (RGB).
glm::dvec3 latlong_integral(const LatLongImage& image);

/// One light of a dome: a distant light arriving from `direction`.
struct DomeLight {
    glm::dvec3 direction{0.0, 1.0, 0.0}; ///< unit, from the surface towards the light
    glm::dvec3 color{0.0};               ///< the region's integral of radiance (RGB x sr)
    /// The region of the map it stands for, pixels [x0, x1) x [y0, y1).
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

/// Debevec's median cut of `image` into `count` lights (a power of two, at
/// most 65536): the map is cut k = log2(count) times, every region along its
/// longer side (width measured at the region's middle latitude, times
/// cos(latitude)) where the energy (luminance 0.2126 R + 0.7152 G + 0.0722 B
/// times pixel solid angle) on either side is closest to half. Each region
/// gives one light carrying the region's integral of colour x solid angle,
/// from its energy centroid (the normalised energy-weighted mean of its
/// pixel directions; the region's middle when it has no energy). A region of
/// one pixel that must still be cut gives two lights of half its colour.
/// The lights' colours sum to latlong_integral(image). Lights are ordered by
/// region (deterministic). Throws ValueError for a bad count or image, or
/// non-finite or negative pixels (naming the pixel).
std::vector<DomeLight> median_cut(const LatLongImage& image, int count);

/// Options of a dome written as RIB.
struct DomeRibOptions {
    std::string probe;         ///< probe file name, for the header comment
    double intensity = 1.0;    ///< scale of every light
    double rotate_degrees = 0; ///< rotation of the dome about +y (right-handed)
    bool shadows =
        false; ///< distantlight_rts (ray-traced shadows) instead of distantlight
    int first_handle = 1; ///< light handles: "envdome<N>" numbered from this
};

/// The dome as a RIB archive (for ReadArchive inside a world block, where the
/// current space is world): a comment header then one `LightSource
/// "distantlight" "envdome<i>" "intensity" [s] "lightcolor" [c / pi] "from"
/// [0 0 0] "to" [-d]` per light. With colour c / pi each light gives a
/// diffuse surface (Kd = 1) exactly what a cosine-weighted average of the map
/// over the region would: diffuse(N) = sum c max(0, N.d) / pi ~ the map's
/// cosine-weighted integral / pi, the value envlight gives.
std::string dome_rib(const std::vector<DomeLight>& lights, const DomeRibOptions& options);

/// A procedural sky probe (deterministic): above the horizon a gradient from
/// a pale horizon to a blue zenith, a small bright sun disc, below it a dark
/// ground.
struct SkyOptions {
    double sun_elevation = 45.0; ///< degrees above the horizon
    double sun_azimuth = 30.0;   ///< degrees from +z towards +x (about +y)
    double sun_radius = 2.5;     ///< angular radius in degrees
    double sun_radiance = 400.0; ///< radiance of the disc (times the sun colour)
    double sky_radiance = 1.0;   ///< radiance scale of the sky
    double ground_radiance = 0.15;
};
/// The sky as a w x h lat-long image (w = 2 h), 4 x 4 samples per pixel.
LatLongImage sky_probe(int width, int height, const SkyOptions& options);
/// The unit direction towards the sun of `options`.
glm::dvec3 sun_direction(const SkyOptions& options);

} // namespace sss

// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file camera.cpp
/// The camera's rays in world space (CameraProjection) and the checks that
/// a camera can generate them (check_camera), each failure naming the RIB
/// statement responsible (docs/scene.md, "Coordinate range").

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "sss/scene/scene.h"
#include "sss/util/error.h"
#include "sss/util/math.h"

namespace sss {

namespace {

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Largest |coordinate| of v (infinity when one is NaN).
double reach(const glm::dvec3& v) {
    if (!finite(v)) return std::numeric_limits<double>::infinity();
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

/// "1e+20", "0.5": a number in a message.
std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

/// Throws ValueError "<source>: <what>", or "camera (<fallback>): <what>"
/// when the part is the RI default (no statement set it).
[[noreturn]] void fail_at(const std::string& source, const char* fallback,
                          const std::string& what) {
    throw ValueError(
        (source.empty() ? std::string("camera (") + fallback + ")" : source) + ": " +
        what);
}

/// The statement that decided the screen window.
const std::string& window_source(const Camera& cam, const char** fallback) {
    *fallback = "the default ScreenWindow";
    if (cam.screen_window) return cam.sources.screen_window;
    if (!cam.sources.frame_aspect.empty()) return cam.sources.frame_aspect;
    return cam.sources.format;
}

} // namespace

CameraProjection::CameraProjection(const Camera& cam) : m_cam(cam) {
    m_window = cam.resolved_screen_window();
    m_tan_half = cam.perspective ? std::tan(cam.fov * kPi / 360.0) : 1.0;
    m_to_world = glm::inverse(cam.world_to_camera);
    m_affine = m_to_world[0][3] == 0.0 && m_to_world[1][3] == 0.0 &&
               m_to_world[2][3] == 0.0 && m_to_world[3][3] == 1.0;
    m_lens_radius = cam.lens_radius();
}

CameraProjection::Ray CameraProjection::ray(double x, double y,
                                            const glm::dvec2& lens) const {
    const double sx = m_window[0] + (x / m_cam.xres) * (m_window[1] - m_window[0]);
    const double sy = m_window[3] - (y / m_cam.yres) * (m_window[3] - m_window[2]);
    glm::dvec4 origin(0.0, 0.0, 0.0, 1.0), ahead(0.0, 0.0, 1.0, 0.0);
    if (m_cam.perspective)
        ahead = glm::dvec4(sx * m_tan_half, sy * m_tan_half, 1.0, 0.0);
    else
        origin = glm::dvec4(sx, sy, 0.0, 1.0);
    if (m_lens_radius > 0.0) {
        // ahead.z = 1: the focal point is origin + D * ahead; from the lens
        // point origin + L the direction to it is ahead - L / D.
        const glm::dvec2 l = lens * m_lens_radius;
        origin.x += l.x;
        origin.y += l.y;
        ahead.x -= l.x / m_cam.focal_distance;
        ahead.y -= l.y / m_cam.focal_distance;
    }
    const glm::dvec4 o4 = m_to_world * origin;
    Ray r;
    r.origin = glm::dvec3(o4) / o4.w;
    // The direction is transformed as a vector, not as the difference of two
    // points one camera unit apart: that difference lost the direction's low
    // bits to the camera's distance from the origin in large scenes (1e-9 of
    // it at 1e6 units). Projective camera transforms keep the points.
    glm::dvec3 d;
    if (m_affine) {
        d = glm::dvec3(m_to_world * ahead);
    } else {
        const glm::dvec4 a4 = m_to_world * (origin + ahead); // a point
        d = glm::dvec3(a4) / a4.w - r.origin;
    }
    r.units = glm::length(d);
    r.direction = d / r.units;
    r.tnear = m_cam.near_clip * r.units;
    r.tfar = m_cam.far_clip >= 1e30 ? std::numeric_limits<double>::infinity()
                                    : m_cam.far_clip * r.units;
    return r;
}

void check_camera(const Camera& cam, bool rays) {
    const Camera::Sources& at = cam.sources;
    if (cam.xres < 1 || cam.yres < 1)
        fail_at(at.format, "Format",
                "image size " + std::to_string(cam.xres) + " x " +
                    std::to_string(cam.yres) + " has no pixels");
    if (!(cam.pixel_aspect > 0.0) || !std::isfinite(cam.pixel_aspect))
        fail_at(at.format, "Format",
                "pixel aspect ratio " + num(cam.pixel_aspect) +
                    " is not a positive number");
    const char* window_fallback = nullptr;
    const std::string& window_at = window_source(cam, &window_fallback);
    const std::array<double, 4> sw = cam.resolved_screen_window();
    const double width = sw[1] - sw[0], height = sw[3] - sw[2];
    if (!std::isfinite(width) || !std::isfinite(height) || width == 0.0 || height == 0.0)
        fail_at(window_at, window_fallback,
                "the screen window " + num(sw[0]) + " " + num(sw[1]) + " " + num(sw[2]) +
                    " " + num(sw[3]) + " has no area or no finite size");
    if (cam.perspective && !(cam.fov > 0.0 && cam.fov < 180.0))
        fail_at(at.projection, "Projection",
                "perspective fov must lie in (0, 180) degrees, got " + num(cam.fov));
    if (!(cam.near_clip >= 0.0) || !(cam.far_clip > cam.near_clip) ||
        !std::isfinite(cam.near_clip))
        fail_at(at.clipping, "Clipping",
                "need 0 <= hither < yon, got " + num(cam.near_clip) + " " +
                    num(cam.far_clip));
    if (cam.depth_of_field() &&
        (!(cam.focal_distance > cam.focal_length) || !(cam.fstop > 0.0) ||
         !std::isfinite(cam.focal_distance) || !std::isfinite(cam.lens_radius())))
        fail_at(at.depth_of_field, "DepthOfField",
                "needs fstop > 0 and a finite focaldistance > focallength > 0");

    // The camera transform: finite and invertible, with an inverse that
    // really inverts it (a determinant that underflows, or a transform so
    // ill-conditioned that its inverse is noise, are singular too).
    const Matrix4& m = cam.world_to_camera;
    const char* transform = "the camera transform (the transformation in effect at "
                            "WorldBegin)";
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r]))
                fail_at(at.world_begin, "WorldBegin",
                        std::string(transform) + " has a NaN or infinite entry");
    const double det = glm::determinant(m);
    const Matrix4 inverse = glm::inverse(m);
    bool invertible = det != 0.0 && std::isfinite(det);
    if (invertible) {
        const Matrix4 product = m * inverse;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r)
                invertible = invertible && std::isfinite(inverse[c][r]) &&
                             std::abs(product[c][r] - (c == r ? 1.0 : 0.0)) < 1e-6;
    }
    if (!invertible)
        fail_at(at.world_begin, "WorldBegin",
                std::string(transform) +
                    " is singular (a zero scale, or transforms that cancel a "
                    "dimension)");
    const glm::dvec4 eye4 = inverse * glm::dvec4(0.0, 0.0, 0.0, 1.0);
    const glm::dvec3 eye = glm::dvec3(eye4) / eye4.w;
    if (!(reach(eye) <= kMaxWorldCoordinate))
        fail_at(at.world_begin, "WorldBegin",
                "the camera lies at (" + num(eye.x) + ", " + num(eye.y) + ", " +
                    num(eye.z) + "), beyond the coordinate range of +-" +
                    num(kMaxWorldCoordinate));

    if (!rays) return;
    // The rays at the corners of the screen window, through the rim of the
    // lens: their origins in range, their directions and intervals numbers.
    // Camera-space origins beyond the range blame the screen window or the
    // lens; world-space ones the camera transform.
    const double lens = cam.lens_radius();
    if (!cam.perspective) {
        const double across = std::max({std::abs(sw[0]), std::abs(sw[1]), std::abs(sw[2]),
                                        std::abs(sw[3])}) +
                              lens;
        if (!(across <= kMaxWorldCoordinate))
            fail_at(window_at, window_fallback,
                    "orthographic rays would start up to " + num(across) +
                        " units from the camera, beyond the coordinate range of +-" +
                        num(kMaxWorldCoordinate));
    } else if (!(lens <= kMaxWorldCoordinate)) {
        fail_at(at.depth_of_field, "DepthOfField",
                "the lens radius " + num(lens) + " is beyond the coordinate range of +-" +
                    num(kMaxWorldCoordinate));
    }
    const CameraProjection projection(cam);
    const double xs[2] = {0.0, static_cast<double>(cam.xres)};
    const double ys[2] = {0.0, static_cast<double>(cam.yres)};
    const glm::dvec2 rims[5] = {
        {0.0, 0.0}, {1.0, 0.0}, {-1.0, 0.0}, {0.0, 1.0}, {0.0, -1.0}};
    for (double x : xs)
        for (double y : ys)
            for (const glm::dvec2& rim : rims) {
                const CameraProjection::Ray r = projection.ray(x, y, rim);
                if (!(reach(r.origin) <= kMaxWorldCoordinate))
                    fail_at(at.world_begin, "WorldBegin",
                            "camera rays would start up to " + num(reach(r.origin)) +
                                " units from the world origin, beyond the coordinate "
                                "range of +-" +
                                num(kMaxWorldCoordinate) + " (" + transform + ")");
                if (!finite(r.direction) || !(r.units > 0.0) || !std::isfinite(r.units))
                    fail_at(at.world_begin, "WorldBegin",
                            std::string("camera rays have no direction through ") +
                                transform);
                if (!(r.tnear <= kMaxWorldCoordinate))
                    fail_at(at.clipping, "Clipping",
                            "hither " + num(cam.near_clip) +
                                " puts the start of every camera ray beyond the "
                                "coordinate range of +-" +
                                num(kMaxWorldCoordinate));
            }
}

} // namespace sss

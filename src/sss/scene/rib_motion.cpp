// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_motion.cpp
/// Motion blur in the RIB (RISpec 3.2 section 4.3): `Shutter`, and
/// `MotionBegin [times] ... MotionEnd` blocks of one request per time.
///  - Transformations: the CTM moves; every primitive made under it (and
///    the camera, for a block before WorldBegin) carries its transform at
///    each time. Later transformations apply at every time.
///  - Geometry: one primitive per time, of the same topology; the scene
///    gets one primitive whose shape (positional numbers and parameters)
///    is given at each time (PrimitiveMotion).
///  - Anything else (shader parameters, attributes): not implemented; read
///    leniently, the first time sample is used.

#include "rib_reader.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "rib_args.h"

namespace sss::rib {

namespace {

bool is_transform(std::string_view name) {
    static const std::set<std::string_view> names = {
        "Identity", "Transform", "ConcatTransform", "Translate", "Rotate",
        "Scale",    "Skew",      "Perspective"};
    return names.count(name) > 0;
}

bool is_geometry(std::string_view name) {
    // clang-format off
    static const std::set<std::string_view> names = {
        "Polygon", "GeneralPolygon", "PointsPolygons", "PointsGeneralPolygons",
        "SubdivisionMesh", "HierarchicalSubdivisionMesh", "Sphere", "Cylinder", "Cone",
        "Disk", "Torus", "Hyperboloid", "Paraboloid", "Patch", "PatchMesh", "Points",
        "Curves", "NuPatch", "Blobby"};
    // clang-format on
    return names.count(name) > 0;
}

/// Whether every key is the same matrix (nothing moves).
bool all_equal(const std::vector<Matrix4>& keys) {
    return std::all_of(keys.begin(), keys.end(),
                       [&](const Matrix4& m) { return m == keys.front(); });
}

/// Why sample b cannot be a later time of primitive a, or empty.
std::string topology_difference(const Primitive& a, const Primitive& b) {
    if (a.kind != b.kind) return "a different primitive";
    if (a.nloops != b.nloops || a.nverts != b.nverts || a.verts != b.verts ||
        a.type != b.type || a.nu != b.nu || a.nv != b.nv || a.uwrap != b.uwrap ||
        a.vwrap != b.vwrap || a.uorder != b.uorder || a.vorder != b.vorder ||
        a.uknot != b.uknot || a.vknot != b.vknot || a.tags != b.tags ||
        a.tag_nargs != b.tag_nargs || a.tag_intargs != b.tag_intargs)
        return "a different topology";
    if (a.args.size() != b.args.size()) return "a different number of arguments";
    if (a.params.items.size() != b.params.items.size()) return "different parameters";
    for (const Param& p : a.params.items) {
        const Param* q = b.params.find(p.name);
        if (!q || q->type != p.type || q->storage != p.storage ||
            q->numbers.size() != p.numbers.size())
            return "a different parameter \"" + p.name + "\"";
    }
    if (a.attributes != b.attributes) return "different attributes";
    return {};
}

} // namespace

void Reader::do_shutter(const Statement& s) {
    std::size_t i = 0;
    const auto n = take_numbers(s, i, 2);
    no_more_args(s, i);
    if (!std::isfinite(n[0]) || !std::isfinite(n[1]))
        fail(s, "shutter times must be finite numbers");
    if (n[1] < n[0])
        fail(s, "shutter closes (" + fmt(n[1]) + ") before it opens (" + fmt(n[0]) + ")");
    if (!option_allowed(s)) return;
    Camera& cam = m_scene.options.camera;
    cam.shutter_open = n[0];
    cam.shutter_close = n[1];
    cam.sources.shutter = where(s) + ": " + s.name;
}

void Reader::do_motion_begin(const Statement& s) {
    if (m_in_motion) fail(s, "nested MotionBegin");
    std::size_t i = 0;
    std::vector<double> times = take_float_array(s, i, "times");
    no_more_args(s, i);
    if (times.empty()) fail(s, "no times");
    for (std::size_t k = 0; k < times.size(); ++k) {
        if (!std::isfinite(times[k])) fail(s, "times must be finite numbers");
        if (k > 0 && !(times[k] > times[k - 1]))
            fail(s, "times must increase, got " + fmt(times[k - 1]) + " then " +
                        fmt(times[k]));
    }
    m_in_motion = true;
    m_motion_times = std::move(times);
    m_motion_count = 0;
    m_motion_request.clear();
    m_motion_base = m_ctm;
    m_motion_base_motion = m_ctm_motion;
    m_motion_ctms.clear();
    m_motion_prims.clear();
    m_motion_capture = false;
}

bool Reader::motion_statement(const Statement& s) {
    const std::size_t n = m_motion_times.size();
    if (m_motion_count >= n)
        fail(s, "MotionBegin gives " + std::to_string(n) + " time" + (n == 1 ? "" : "s") +
                    ": its block holds one request per time");
    const std::size_t j = m_motion_count++;
    if (j == 0) {
        m_motion_request = s.name;
        m_motion_kind = is_transform(s.name)  ? MotionKind::Transform
                        : is_geometry(s.name) ? MotionKind::Geometry
                                              : MotionKind::Other;
        if (m_motion_kind == MotionKind::Other && n > 1)
            not_implemented("motion " + s.name, s,
                            "motion blur of " + s.name + " is not supported",
                            "the first time sample is used");
    } else if (s.name != m_motion_request) {
        fail(s, "a motion block holds one kind of request: " + m_motion_request +
                    ", then " + s.name);
    }
    switch (m_motion_kind) {
    case MotionKind::Transform:
        // Each time's transformation applies to the CTM as it is at that time.
        m_ctm = m_motion_base_motion.keys.empty()
                    ? m_motion_base
                    : matrix_at(m_motion_base_motion.times, m_motion_base_motion.keys,
                                m_motion_times[j]);
        m_ctm_motion = {};
        return false;
    case MotionKind::Geometry:
        m_motion_prims.emplace_back();
        m_motion_capture = true;
        return false;
    case MotionKind::Other:
        return j > 0;
    }
    return false;
}

void Reader::after_motion_statement(const Statement& s) {
    if (!m_in_motion || s.name == "MotionEnd" || s.name == "MotionBegin") return;
    if (m_motion_kind == MotionKind::Transform) m_motion_ctms.push_back(m_ctm);
    m_motion_capture = false;
}

void Reader::do_motion_end(const Statement& s) {
    if (!m_in_motion) fail(s, "MotionEnd without MotionBegin");
    m_in_motion = false;
    m_motion_capture = false;
    const std::size_t n = m_motion_times.size();
    if (m_motion_count == 0) return;
    if (m_motion_count != n)
        fail(s, "MotionBegin gave " + std::to_string(n) + " times but its block holds " +
                    std::to_string(m_motion_count) + " request" +
                    (m_motion_count == 1 ? "" : "s"));
    if (m_motion_kind == MotionKind::Transform) {
        m_ctm = m_motion_ctms.front();
        m_ctm_motion = {};
        if (!all_equal(m_motion_ctms)) m_ctm_motion = {m_motion_times, m_motion_ctms};
        return;
    }
    if (m_motion_kind != MotionKind::Geometry) return;
    // One moving primitive per primitive of the first request.
    const std::vector<Primitive>& first = m_motion_prims.front();
    for (std::size_t j = 1; j < n; ++j)
        if (m_motion_prims[j].size() != first.size())
            fail(s, "the requests of the motion block make different primitives");
    for (std::size_t k = 0; k < first.size(); ++k) {
        Primitive p = first[k];
        auto motion = p.motion ? std::make_shared<PrimitiveMotion>(*p.motion)
                               : std::make_shared<PrimitiveMotion>();
        motion->shape_times = m_motion_times;
        for (std::size_t j = 0; j < n; ++j) {
            const Primitive& q = m_motion_prims[j][k];
            const std::string why = topology_difference(p, q);
            if (!why.empty())
                fail(s, "time " + fmt(m_motion_times[j]) + " of the motion block has " +
                            why + " (" + q.source + "): deformation needs the same " +
                            "topology at every time");
            motion->shape_args.push_back(q.args);
            motion->shape_params.push_back(q.params);
        }
        p.motion = std::move(motion);
        store_primitive(std::move(p));
    }
}

void Reader::place(Primitive& p, const Matrix4& object_to_ctm) const {
    const PrimitiveMotion* own = p.motion.get();
    const bool own_moves = own && !own->transform_times.empty();
    if (m_ctm_motion.keys.empty() && !own_moves) {
        p.object_to_world = m_ctm * object_to_ctm;
        return;
    }
    // The CTM's motion and the primitive's own (an instance of an object
    // that moves inside its definition), composed at every time of either.
    std::vector<double> times = m_ctm_motion.times;
    if (own_moves)
        times.insert(times.end(), own->transform_times.begin(),
                     own->transform_times.end());
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end()), times.end());
    auto motion = own ? std::make_shared<PrimitiveMotion>(*own)
                      : std::make_shared<PrimitiveMotion>();
    motion->transform_times = times;
    motion->transforms.clear();
    for (double t : times) {
        const Matrix4 ctm = m_ctm_motion.keys.empty()
                                ? m_ctm
                                : matrix_at(m_ctm_motion.times, m_ctm_motion.keys, t);
        const Matrix4 local = own_moves
                                  ? matrix_at(own->transform_times, own->transforms, t)
                                  : object_to_ctm;
        motion->transforms.push_back(ctm * local);
    }
    p.object_to_world = motion->transforms.front();
    p.motion = std::move(motion);
}

} // namespace sss::rib

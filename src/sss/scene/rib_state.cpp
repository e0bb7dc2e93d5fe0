// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_state.cpp
/// The reader's graphics state: the attribute snapshot, the block stack
/// (World, Attribute, Transform, Solid, Motion and Object blocks) and the
/// transformation requests.

#include "rib_reader.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include "rib_args.h"
#include "sss/util/limits.h"
#include "sss/util/math.h"
#include "sss/util/messages.h"
#include "sss/util/name_table.h"

namespace sss::rib {

namespace {

/// Memory a primitive holds, roughly (its arrays and strings).
uint64_t approx_bytes(const Primitive& p) {
    uint64_t bytes = sizeof(Primitive) + p.source.size() + p.type.size();
    bytes += (p.args.size() + p.tag_floatargs.size()) * sizeof(double);
    bytes += (p.nloops.size() + p.nverts.size() + p.verts.size() + p.tag_nargs.size() +
              p.tag_intargs.size()) *
             sizeof(int);
    for (const std::string& t : p.tags) bytes += sizeof(std::string) + t.size();
    for (const Param& q : p.params.items) {
        bytes += sizeof(Param) + q.name.size() + q.numbers.size() * sizeof(double);
        for (const std::string& t : q.strings) bytes += sizeof(std::string) + t.size();
    }
    return bytes;
}

/// "file.rib:12" where a block opened.
std::string where_saved(const SavedState& s) {
    return *s.file + ":" + std::to_string(s.line);
}

/// The spaces the RI names itself; CoordinateSystem cannot redefine them.
bool predefined_space(std::string_view n) {
    return n == "world" || n == "camera" || n == "object" || n == "shader" ||
           n == "current" || n == "screen" || n == "raster" || n == "NDC";
}

constexpr NameTable<Block, 6> kBlockBeginNames({{
    {Block::Attribute, "AttributeBegin"},
    {Block::Transform, "TransformBegin"},
    {Block::World, "WorldBegin"},
    {Block::Frame, "FrameBegin"},
    {Block::Object, "ObjectBegin"},
    {Block::Solid, "SolidBegin"},
}});

} // namespace

const char* block_begin_name(Block b) {
    return kBlockBeginNames.name(b);
}

// --- graphics state --------------------------------------------------------

Attributes& Reader::attrs_mut() {
    m_attr.snapshot.reset();
    return m_attr.attrs;
}

std::shared_ptr<const Attributes> Reader::snapshot() {
    if (!m_attr.snapshot)
        m_attr.snapshot = std::make_shared<const Attributes>(m_attr.attrs);
    return m_attr.snapshot;
}

void Reader::push(const Statement& s, Block block) {
    m_stack.push_back(SavedState{block, m_ctm, m_attr, s.line, s.file, m_ctm_motion});
}

SavedState Reader::pop(const Statement& s, Block block) {
    if (m_stack.empty())
        fail(s, std::string("without a matching ") + block_begin_name(block));
    if (m_stack.back().block != block)
        fail(s, std::string("does not match the ") +
                    block_begin_name(m_stack.back().block) + " of " +
                    where_saved(m_stack.back()));
    SavedState saved = std::move(m_stack.back());
    m_stack.pop_back();
    return saved;
}

void Reader::restore_all(SavedState& saved) {
    restore_ctm(saved);
    m_attr = std::move(saved.attributes);
}

void Reader::concat(const Matrix4& m) {
    m_ctm = m_ctm * m;
    for (Matrix4& key : m_ctm_motion.keys) key = key * m;
}

bool Reader::current_left_handed() const {
    Matrix4 to_camera = m_in_world ? m_world_to_camera * m_ctm : m_ctm;
    return glm::determinant(to_camera) > 0.0;
}

// --- blocks ----------------------------------------------------------------

void Reader::do_world_begin(const Statement& s) {
    no_more_args(s, 0);
    if (m_in_world) fail(s, "nested WorldBegin");
    if (m_object) fail(s, "WorldBegin inside ObjectBegin");
    push(s, Block::World);
    m_in_world = true;
    ++m_scene.worlds;
    m_world_to_camera = m_ctm;
    Camera& cam = m_scene.options.camera;
    cam.world_to_camera = m_ctm;
    // A camera that moves: its world-to-camera at each time.
    cam.motion_times = m_ctm_motion.times;
    cam.motion_world_to_camera = m_ctm_motion.keys;
    cam.sources.world_begin = where(s) + ": " + s.name;
    if (m_frame_aspect && !cam.screen_window) {
        double a = *m_frame_aspect;
        cam.screen_window = a >= 1.0
                                ? std::array<double, 4>{-a, a, -1.0, 1.0}
                                : std::array<double, 4>{-1.0, 1.0, -1.0 / a, 1.0 / a};
    }
    const Matrix4 camera_to_world = glm::inverse(m_world_to_camera);
    for (const auto& [name, to_camera] : m_camera_spaces)
        m_scene.coordinate_systems[name] = camera_to_world * to_camera;
    // Shaders given among the options were placed in camera space.
    const Attributes& attrs = m_attr.attrs;
    for (auto member :
         {&Attributes::surface, &Attributes::displacement, &Attributes::atmosphere,
          &Attributes::interior, &Attributes::exterior})
        if (attrs.*member) {
            ShaderRef& ref = *(attrs_mut().*member);
            ref.shader_to_world = camera_to_world * ref.shader_to_world;
        }
    if (!attrs.coshaders.empty())
        for (CoshaderRef& c : attrs_mut().coshaders)
            c.shader.shader_to_world = camera_to_world * c.shader.shader_to_world;
    if (m_scene.options.imager) {
        ShaderRef& ref = *m_scene.options.imager;
        ref.shader_to_world = camera_to_world * ref.shader_to_world;
    }
    set_ctm(Matrix4(1.0));
}

void Reader::do_world_end(const Statement& s) {
    no_more_args(s, 0);
    if (!m_in_world) fail(s, "WorldEnd without WorldBegin");
    SavedState saved = pop(s, Block::World);
    restore_all(saved);
    m_in_world = false;
}

void Reader::do_attribute_begin(const Statement& s) {
    push(s, Block::Attribute);
}

void Reader::do_attribute_end(const Statement& s) {
    SavedState saved = pop(s, Block::Attribute);
    restore_all(saved);
}

void Reader::do_transform_begin(const Statement& s) {
    push(s, Block::Transform);
}

void Reader::do_transform_end(const Statement& s) {
    restore_ctm(pop(s, Block::Transform));
}

void Reader::do_solid_begin(const Statement& s) {
    not_implemented("solid", s, "CSG is not supported",
                    "the parts are kept as separate primitives");
    push(s, Block::Solid);
}

void Reader::do_solid_end(const Statement& s) {
    SavedState saved = pop(s, Block::Solid);
    restore_all(saved);
}

void Reader::do_object_begin(const Statement& s) {
    std::size_t i = 0;
    std::string handle = take_handle(s, i);
    if (m_object) fail(s, "nested ObjectBegin");
    push(s, Block::Object);
    m_object_handle = handle;
    m_object = &m_objects[handle];
    m_object->clear(); // redefinition replaces
    set_ctm(Matrix4(1.0));
}

void Reader::do_object_end(const Statement& s) {
    if (!m_object) fail(s, "ObjectEnd without ObjectBegin");
    SavedState saved = pop(s, Block::Object);
    restore_all(saved);
    m_object = nullptr;
}

void Reader::do_object_instance(const Statement& s) {
    std::size_t i = 0;
    std::string handle = take_handle(s, i);
    no_more_args(s, i);
    auto it = m_objects.find(handle);
    if (it == m_objects.end() || (m_object && handle == m_object_handle))
        fail(s, "unknown object handle " + sss::quoted(handle));
    // Each instance copies the object's primitives, and objects that
    // instance others multiply them: check the memory as the copies grow.
    uint64_t bytes = 0;
    for (const Primitive& def : it->second) bytes += approx_bytes(def);
    m_copied_bytes += bytes;
    m_copied_primitives += it->second.size();
    if (m_copied_bytes >= m_next_memory_check) {
        check_memory(bytes + kMemoryCheckStep,
                     where(s) + ": ObjectInstance " + sss::quoted(handle) + " (" +
                         std::to_string(m_copied_primitives) +
                         " primitives copied by instances so far)",
                     "instance fewer objects (each ObjectInstance copies the object's "
                     "primitives)");
        m_next_memory_check = m_copied_bytes + kMemoryCheckStep;
    }
    for (const Primitive& def : it->second) {
        Primitive p = def;
        add_primitive(s, std::move(p), def.object_to_world, def.source);
    }
}

// --- transforms ------------------------------------------------------------

void Reader::do_identity(const Statement& s) {
    no_more_args(s, 0);
    set_ctm(Matrix4(1.0));
}

void Reader::do_transform(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 16);
    no_more_args(s, i);
    set_ctm(matrix_from(n));
}

void Reader::do_concat_transform(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 16);
    no_more_args(s, i);
    concat(matrix_from(n));
}

void Reader::do_translate(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 3);
    no_more_args(s, i);
    concat(glm::translate(Matrix4(1.0), glm::dvec3(n[0], n[1], n[2])));
}

void Reader::do_rotate(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 4);
    no_more_args(s, i);
    glm::dvec3 axis(n[1], n[2], n[3]);
    double len = glm::length(axis);
    if (!(len > 0.0)) fail(s, "rotation axis is zero");
    concat(glm::rotate(Matrix4(1.0), glm::radians(n[0]), axis / len));
}

void Reader::do_scale(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 3);
    no_more_args(s, i);
    concat(glm::scale(Matrix4(1.0), glm::dvec3(n[0], n[1], n[2])));
}

void Reader::do_skew(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 7);
    no_more_args(s, i);
    glm::dvec3 v1(n[1], n[2], n[3]), v2(n[4], n[5], n[6]);
    if (!(glm::length(v2) > 0.0) || !(glm::length(v1) > 0.0)) fail(s, "zero skew vector");
    // Points shift along v2 in proportion to their component along b, the
    // part of v1 orthogonal to v2, so that v1 turns by `angle` towards v2.
    glm::dvec3 a = glm::normalize(v2);
    double alpha = glm::dot(v1, a);
    glm::dvec3 perp = v1 - alpha * a;
    double beta = glm::length(perp);
    if (!(beta > 1e-12 * glm::length(v1))) fail(s, "skew vectors are parallel");
    glm::dvec3 b = perp / beta;
    double theta = std::atan2(alpha, beta) + glm::radians(n[0]);
    if (!(std::abs(theta) < kPi / 2 - 1e-9))
        fail(s, "skew angle turns the vector past the skew axis");
    double k = std::tan(theta) - alpha / beta;
    Matrix4 m(1.0);
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) m[c][r] += k * a[r] * b[c];
    concat(m);
}

void Reader::do_perspective(const Statement& s) {
    std::size_t i = 0;
    double fov = take_number(s, i);
    no_more_args(s, i);
    if (!(fov > 0.0 && fov < 180.0)) fail(s, "fov must lie in (0, 180) degrees");
    warn_once("Perspective", s,
              "Perspective concatenates a projective matrix; geometry under it is "
              "rarely what was meant");
    double t = std::tan(glm::radians(fov) / 2.0);
    Matrix4 m(0.0);
    m[0][0] = 1.0 / t;
    m[1][1] = 1.0 / t;
    m[2][2] = 1.0;
    m[2][3] = 1.0;
    m[3][2] = -1.0;
    concat(m);
}

void Reader::do_coordinate_system(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "coordinate system name");
    no_more_args(s, i);
    if (name.empty()) fail(s, "empty coordinate system name");
    if (predefined_space(name)) fail(s, sss::quoted(name) + " is a predefined space");
    if (m_in_world)
        m_scene.coordinate_systems[name] = m_ctm;
    else
        m_camera_spaces[name] = m_ctm;
}

void Reader::do_coord_sys_transform(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "coordinate system name");
    no_more_args(s, i);
    if (name == "object" || name == "current") return;
    if (name == "world") {
        if (!m_in_world) fail(s, "world space is not defined before WorldBegin");
        set_ctm(Matrix4(1.0));
    } else if (name == "camera") {
        set_ctm(m_in_world ? glm::inverse(m_world_to_camera) : Matrix4(1.0));
    } else if (name == "shader") {
        if (m_attr.attrs.surface) set_ctm(m_attr.attrs.surface->shader_to_world);
    } else if (name == "screen" || name == "raster" || name == "NDC") {
        fail(s, sss::quoted(name) + " space is not supported");
    } else if (m_in_world) {
        auto it = m_scene.coordinate_systems.find(name);
        if (it == m_scene.coordinate_systems.end())
            fail(s, "unknown coordinate system " + sss::quoted(name));
        set_ctm(it->second);
    } else {
        auto it = m_camera_spaces.find(name);
        if (it == m_camera_spaces.end())
            fail(s, "unknown coordinate system " + sss::quoted(name));
        set_ctm(it->second);
    }
}

} // namespace sss::rib

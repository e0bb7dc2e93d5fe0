// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib.cpp
/// ASCII RIB reader: read_rib and parse_rib, and the interpreter's core, which
/// sends each statement to its request's handler (rib_reader.h lists the
/// files that define them). The tokenizer is rib_lexer.cpp.

#include "sss/scene/rib.h"

#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>

#include "rib_args.h"
#include "rib_reader.h"

namespace sss {
namespace rib {

namespace {

using NameSet = std::set<std::string, std::less<>>;

/// The names of a space-separated list.
NameSet name_set(const char* names) {
    NameSet out;
    std::istringstream in(names);
    for (std::string w; in >> w;) out.insert(w);
    return out;
}

/// Requests that do not change what this toolchain computes.
bool ignored(std::string_view name) {
    static const NameSet names =
        name_set("version Version ArchiveRecord Camera "
                 "PixelVariance RelativeDetail ErrorHandler Bound "
                 "GeometricApproximation TextureCoordinates");
    return names.count(name) > 0;
}

/// Requests understood but not supported: one warning each.
bool unsupported(std::string_view name) {
    static const NameSet names =
        name_set("Deformation Detail DetailRange "
                 "ClippingPlane IfBegin ElseIf Else IfEnd MakeBump "
                 "MakeBrickMap System Resource "
                 "ResourceBegin ResourceEnd Bxdf Pattern Integrator DisplayFilter "
                 "SampleFilter Light Volume Matte");
    return names.count(name) > 0;
}

} // namespace

void Reader::read_text(std::string_view text, const std::string& path) {
    m_scene.path = path;
    m_reading.emplace_back(file_key(path), path);
    run_text(text, std::make_shared<const std::string>(path));
    m_reading.pop_back();
}

Scene Reader::finish(const std::string& path) {
    if (m_recording)
        throw RibError(*m_record_file, m_record_line, "ArchiveBegin",
                       "archive \"" + m_record_name + "\" has no ArchiveEnd");
    for (const SavedState& s : m_stack)
        m_scene.warnings.push_back(*s.file + ":" + std::to_string(s.line) + ": " +
                                   block_begin_name(s.block) + " is never closed");
    if (m_skipping)
        m_scene.warnings.push_back(*m_skip_file + ":" + std::to_string(m_skip_line) +
                                   ": FrameBegin is never closed");
    // Without frames, the requests outside them are the scene's.
    if (!m_frames_seen)
        for (MakeRequest& m : m_pending_makes) m_scene.makes.push_back(std::move(m));
    m_pending_makes.clear();
    // A file without frame blocks is the same scene for every frame.
    if (m_options.frame && m_frames_seen && !m_frame_read)
        throw RibError(path, 0, "FrameBegin",
                       "frame " + std::to_string(*m_options.frame) + " not found");
    return std::move(m_scene);
}

bool Reader::diverted(const Statement& s) {
    // Inline archives are recorded, not executed.
    if (m_recording) {
        if (s.name == "ArchiveBegin") {
            ++m_record_depth;
        } else if (s.name == "ArchiveEnd") {
            if (m_record_depth == 0) {
                define_archive(m_record_name, std::move(m_record));
                m_record.clear();
                m_recording = false;
                return true;
            }
            --m_record_depth;
        }
        m_record.push_back(s);
        return true;
    }
    // Frames other than the selected one are skipped entirely.
    if (m_skipping) {
        if (s.name == "FrameEnd")
            m_skipping = false;
        else if (s.name == "FrameBegin")
            fail(s, "nested FrameBegin");
        return true;
    }
    if (m_in_motion && s.name != "MotionEnd" && s.name != "MotionBegin")
        return motion_statement(s);
    return false;
}

const Reader::HandlerTable& Reader::handlers() {
    static const HandlerTable table = {
        // options
        {"Format", &Reader::do_format},
        {"FrameAspectRatio", &Reader::do_frame_aspect},
        {"ScreenWindow", &Reader::do_screen_window},
        {"CropWindow", &Reader::do_crop_window},
        {"Projection", &Reader::do_projection},
        {"Clipping", &Reader::do_clipping},
        {"PixelSamples", &Reader::do_pixel_samples},
        {"Display", &Reader::do_display},
        {"DisplayChannel", &Reader::do_display_channel},
        {"Hider", &Reader::do_hider},
        {"Option", &Reader::do_option},
        {"ColorSamples", &Reader::do_color_samples},
        {"Declare", &Reader::do_declare},
        {"DepthOfField", &Reader::do_depth_of_field},
        {"PixelFilter", &Reader::do_pixel_filter},
        {"Exposure", &Reader::do_exposure},
        {"Quantize", &Reader::do_quantize},
        {"Imager", &Reader::do_imager},
        // blocks
        {"FrameBegin", &Reader::do_frame_begin},
        {"FrameEnd", &Reader::do_frame_end},
        {"WorldBegin", &Reader::do_world_begin},
        {"WorldEnd", &Reader::do_world_end},
        {"AttributeBegin", &Reader::do_attribute_begin},
        {"AttributeEnd", &Reader::do_attribute_end},
        {"TransformBegin", &Reader::do_transform_begin},
        {"TransformEnd", &Reader::do_transform_end},
        {"SolidBegin", &Reader::do_solid_begin},
        {"SolidEnd", &Reader::do_solid_end},
        {"Shutter", &Reader::do_shutter},
        {"MotionBegin", &Reader::do_motion_begin},
        {"MotionEnd", &Reader::do_motion_end},
        {"ObjectBegin", &Reader::do_object_begin},
        {"ObjectEnd", &Reader::do_object_end},
        {"ObjectInstance", &Reader::do_object_instance},
        {"ArchiveBegin", &Reader::do_archive_begin},
        {"ArchiveEnd", &Reader::do_archive_end},
        {"ReadArchive", &Reader::do_read_archive},
        {"Procedural", &Reader::do_procedural},
        // transforms
        {"Identity", &Reader::do_identity},
        {"Transform", &Reader::do_transform},
        {"ConcatTransform", &Reader::do_concat_transform},
        {"Translate", &Reader::do_translate},
        {"Rotate", &Reader::do_rotate},
        {"Scale", &Reader::do_scale},
        {"Skew", &Reader::do_skew},
        {"Perspective", &Reader::do_perspective},
        {"CoordinateSystem", &Reader::do_coordinate_system},
        {"CoordSysTransform", &Reader::do_coord_sys_transform},
        // attributes
        {"Attribute", &Reader::do_attribute},
        {"Color", &Reader::do_color},
        {"Opacity", &Reader::do_opacity},
        {"Sides", &Reader::do_sides},
        {"Orientation", &Reader::do_orientation},
        {"ReverseOrientation", &Reader::do_reverse_orientation},
        {"ShadingRate", &Reader::do_shading_rate},
        {"ShadingInterpolation", &Reader::do_shading_interpolation},
        {"Surface", &Reader::do_surface},
        {"Shader", &Reader::do_coshader},
        {"Displacement", &Reader::do_displacement},
        {"Atmosphere", &Reader::do_volume_shader},
        {"Interior", &Reader::do_volume_shader},
        {"Exterior", &Reader::do_volume_shader},
        {"LightSource", &Reader::do_light_source},
        {"AreaLightSource", &Reader::do_light_source},
        {"Illuminate", &Reader::do_illuminate},
        {"Basis", &Reader::do_basis},
        // geometry
        {"Polygon", &Reader::do_polygon},
        {"GeneralPolygon", &Reader::do_general_polygon},
        {"PointsPolygons", &Reader::do_points_polygons},
        {"PointsGeneralPolygons", &Reader::do_points_general_polygons},
        {"SubdivisionMesh", &Reader::do_subdivision_mesh},
        {"HierarchicalSubdivisionMesh", &Reader::do_subdivision_mesh},
        {"Sphere", &Reader::do_quadric},
        {"Cylinder", &Reader::do_quadric},
        {"Cone", &Reader::do_quadric},
        {"Disk", &Reader::do_quadric},
        {"Torus", &Reader::do_quadric},
        {"Hyperboloid", &Reader::do_quadric},
        {"Paraboloid", &Reader::do_quadric},
        {"Patch", &Reader::do_patch},
        {"PatchMesh", &Reader::do_patch_mesh},
        {"Geometry", &Reader::do_geometry},
        {"Points", &Reader::do_points},
        {"Curves", &Reader::do_curves},
        {"NuPatch", &Reader::do_nupatch},
        {"Blobby", &Reader::do_blobby},
        {"TrimCurve", &Reader::do_trim_curve},
        {"MakeTexture", &Reader::do_make_texture},
        {"MakeLatLongEnvironment", &Reader::do_make_texture},
        {"MakeShadow", &Reader::do_make_shadow},
        {"MakeCubeFaceEnvironment", &Reader::do_make_cube_face_environment},
    };
    return table;
}

void Reader::execute(const Statement& s) {
    if (diverted(s)) return;
    auto it = handlers().find(s.name);
    if (it != handlers().end()) {
        const bool in_motion = m_in_motion;
        (this->*(it->second))(s);
        if (in_motion) after_motion_statement(s);
    } else if (ignored(s.name)) {
        // nothing to do
    } else if (unsupported(s.name)) {
        not_implemented("unsupported " + s.name, s, s.name + " is not supported",
                        "skipped");
    } else {
        // A name is a word of the lexer's (letters, digits, '_'): one line.
        if (!m_options.lenient)
            fail(s, "unknown statement " + truncated(s.name, kMaxEcho) +
                        " (reading leniently: skipped, with a warning)");
        warn_once("unknown " + s.name, s,
                  "unknown statement " + truncated(s.name, kMaxEcho) + ", skipped",
                  "unknown statement");
    }
}

void Reader::not_implemented(const std::string& key, const Statement& s,
                             const std::string& what, const std::string& lenient) {
    if (!m_options.lenient)
        fail(s, what + " (reading leniently: " + lenient + ", with a warning)");
    warn_once(key, s, what + ", " + lenient);
}

void Reader::warn(const Statement& s, const std::string& what, std::string_view kind) {
    if (kind.empty())
        m_scene.warnings.push_back(where(s) + ": " + what);
    else
        m_scene.warnings.add(kind, where(s) + ": " + what);
}

void Reader::warn_once(const std::string& key, const Statement& s,
                       const std::string& what, std::string_view kind) {
    if (m_warned.insert(key).second) warn(s, what, kind);
}

} // namespace rib

Scene read_rib(const std::string& path, const RibReadOptions& options) {
    if (path == kRibStandardInput) {
        Scene scene = parse_rib(rib::slurp_standard_input(), "<stdin>", options);
        if (scene.worlds == 0) throw ValueError("<stdin>: no WorldBegin: not a scene");
        scene.path.clear();
        return scene;
    }
    Scene scene = parse_rib(rib::slurp(path, ""), path, options);
    // Geometry outside a world block is already an error: a file without
    // one is an archive (or not RIB at all), never a scene to render or bake.
    if (scene.worlds == 0)
        throw ValueError(path + ": no WorldBegin: not a scene (an archive is read with "
                                "ReadArchive from a scene's world block)");
    scene.sources.insert(scene.sources.begin(), path);
    scene.source_uses.insert(scene.source_uses.begin(),
                             "the scene file \"" + path + "\"");
    return scene;
}

Scene parse_rib(const std::string& text, const std::string& path,
                const RibReadOptions& options) {
    rib::Reader reader(options);
    reader.read_text(text, path);
    return reader.finish(path);
}

} // namespace sss

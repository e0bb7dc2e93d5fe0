/// \file rib.cpp
/// ASCII RIB reader: a tokenizer that groups tokens into statements (a
/// request name and its arguments), and an interpreter that keeps the RI
/// graphics state and fills the scene layer. Also imports Wavefront OBJ
/// meshes met through ReadArchive.

#include "sss/scene/rib.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include "obj_import.h"
#include "rib_args.h"
#include "rib_lexer.h"
#include "rib_params.h"
#include "sss/util/name_table.h"

namespace sss {
namespace rib {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// The interpreter

/// The element counts a primitive's parameters must have, per storage class.
/// The reader counts facevertex values like facevarying ones (one per face
/// corner), so both get the same number.
ClassCounts counts(std::size_t uniform, std::size_t varying, std::size_t vertex,
                   std::size_t facevarying) {
    return {uniform, varying, vertex, facevarying, facevarying};
}

enum class Block { Attribute, Transform, World, Frame, Object, Solid };

constexpr NameTable<Block, 6> kBlockBeginNames({{
    {Block::Attribute, "AttributeBegin"},
    {Block::Transform, "TransformBegin"},
    {Block::World, "WorldBegin"},
    {Block::Frame, "FrameBegin"},
    {Block::Object, "ObjectBegin"},
    {Block::Solid, "SolidBegin"},
}});

const char* block_begin_name(Block b) {
    return kBlockBeginNames.name(b);
}

/// The attribute half of the graphics state, with a cached immutable
/// snapshot so that primitives made under unchanged attributes share it.
struct AttributeState {
    Attributes attrs;
    std::shared_ptr<const Attributes> snapshot;
};

struct SavedState {
    Block block;
    Matrix4 ctm;
    AttributeState attributes; // unused for TransformBegin
    int line;
    std::shared_ptr<const std::string> file;
};

constexpr int kMaxArchiveDepth = 32;

class Reader {
public:
    explicit Reader(const RibReadOptions& options)
        : m_options(options), m_decls(predeclared()) {}

    void read_text(std::string_view text, const std::string& path) {
        m_scene.path = path;
        run_text(text, std::make_shared<const std::string>(path));
    }

    Scene finish(const std::string& path) {
        if (m_recording)
            throw RibError(*m_record_file, m_record_line, "ArchiveBegin",
                           "archive \"" + m_record_name + "\" has no ArchiveEnd");
        for (const SavedState& s : m_stack)
            m_scene.warnings.push_back(*s.file + ":" + std::to_string(s.line) + ": " +
                                       block_begin_name(s.block) + " is never closed");
        if (m_skipping)
            m_scene.warnings.push_back(*m_skip_file + ":" + std::to_string(m_skip_line) +
                                       ": FrameBegin is never closed");
        // A file without frame blocks is the same scene for every frame.
        if (m_options.frame && m_frames_seen && !m_frame_read)
            throw RibError(path, 0, "FrameBegin",
                           "frame " + std::to_string(*m_options.frame) + " not found");
        return std::move(m_scene);
    }

private:
    using Handler = void (Reader::*)(const Statement&);

    // --- reading -----------------------------------------------------------

    void run_text(std::string_view text, std::shared_ptr<const std::string> path) {
        Lexer lexer(text, std::move(path));
        Statement st;
        while (lexer.next(st)) execute(st);
    }

    void run_file(const Statement& from, const std::string& path) {
        if (m_depth >= kMaxArchiveDepth)
            fail(from, "archives nested more than " + std::to_string(kMaxArchiveDepth) +
                           " deep (does \"" + path + "\" read itself?)");
        const bool obj = ends_with_obj(path);
        if (obj && !m_object && !m_in_world)
            fail(from, "geometry outside WorldBegin/WorldEnd");
        std::string text = slurp(path, " (ReadArchive at " + where(from) + ")");
        if (std::find(m_scene.sources.begin(), m_scene.sources.end(), path) ==
            m_scene.sources.end())
            m_scene.sources.push_back(path);
        ++m_depth;
        if (obj)
            add_obj(text, path);
        else
            run_text(text, std::make_shared<const std::string>(path));
        --m_depth;
    }

    static bool ends_with_obj(const std::string& path) {
        return path.size() >= 4 && lower(path.substr(path.size() - 4)) == ".obj";
    }

    static std::string slurp(const std::string& path, const std::string& context) {
        std::ifstream in(path, std::ios::binary);
        if (!in)
            throw IoError(path, std::string("cannot open") + context + ": " +
                                    std::strerror(errno));
        std::ostringstream ss;
        ss << in.rdbuf();
        if (in.bad()) throw IoError(path, "read error");
        return ss.str();
    }

    /// `name` relative to the folder of the file that names it.
    static std::string resolve_path(const Statement& s, const std::string& name) {
        fs::path p(name);
        if (p.is_absolute()) return name;
        fs::path base = fs::path(*s.file).parent_path();
        return (base / p).lexically_normal().string();
    }

    void execute(const Statement& s) {
        // Inline archives are recorded, not executed.
        if (m_recording) {
            if (s.name == "ArchiveBegin") {
                ++m_record_depth;
            } else if (s.name == "ArchiveEnd") {
                if (m_record_depth == 0) {
                    m_archives[m_record_name] = std::move(m_record);
                    m_record.clear();
                    m_recording = false;
                    return;
                }
                --m_record_depth;
            }
            m_record.push_back(s);
            return;
        }
        // Frames other than the selected one are skipped entirely.
        if (m_skipping) {
            if (s.name == "FrameEnd")
                m_skipping = false;
            else if (s.name == "FrameBegin")
                fail(s, "nested FrameBegin");
            return;
        }
        // Motion blocks: only the first time sample is used.
        if (m_in_motion && s.name != "MotionEnd") {
            if (m_motion_used) return;
            m_motion_used = true;
        }
        static const std::unordered_map<std::string_view, Handler> handlers = {
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
        };
        // Requests that do not change what this toolchain computes.
        static const std::set<std::string_view> ignored = {
            "version",
            "Version",
            "Shutter",
            "ArchiveRecord",
            "Camera",
            "Exposure",
            "Quantize",
            "PixelFilter",
            "PixelVariance",
            "Imager",
            "DepthOfField",
            "RelativeDetail",
            "ErrorHandler",
            "Matte",
            "Bound",
            "GeometricApproximation",
            "TextureCoordinates",
        };
        // Requests understood but not supported: one warning each.
        static const std::set<std::string_view> unsupported = {
            "Displacement",
            "Atmosphere",
            "Interior",
            "Exterior",
            "Deformation",
            "Detail",
            "DetailRange",
            "Points",
            "Curves",
            "Blobby",
            "NuPatch",
            "TrimCurve",
            "HierarchicalSubdivisionMesh",
            "ClippingPlane",
            "IfBegin",
            "ElseIf",
            "Else",
            "IfEnd",
            "MakeTexture",
            "MakeShadow",
            "MakeBump",
            "MakeLatLongEnvironment",
            "MakeCubeFaceEnvironment",
            "MakeBrickMap",
            "System",
            "Resource",
            "ResourceBegin",
            "ResourceEnd",
            "Shader",
            "Bxdf",
            "Pattern",
            "Integrator",
            "DisplayFilter",
            "SampleFilter",
            "Light",
            "Volume"};

        auto it = handlers.find(s.name);
        if (it != handlers.end()) {
            (this->*(it->second))(s);
        } else if (ignored.count(s.name)) {
            // nothing to do
        } else if (unsupported.count(s.name)) {
            warn_once("unsupported " + s.name, s, s.name + " is not supported, skipped");
        } else {
            warn_once("unknown " + s.name, s,
                      "unknown statement " + s.name + ", skipped");
        }
    }

    // --- warnings and parameter lists ---------------------------------------

    void warn(const Statement& s, const std::string& what) {
        m_scene.warnings.push_back(where(s) + ": " + what);
    }

    void warn_once(const std::string& key, const Statement& s, const std::string& what) {
        if (m_warned.insert(key).second) warn(s, what);
    }

    /// The "name" value pairs from argument i on. `single`: every parameter
    /// must hold exactly one element (shader calls, options); otherwise any
    /// whole number of elements (primitives, checked against the topology).
    ParamList take_params(const Statement& s, std::size_t i, bool single) {
        ParamList list;
        while (i < s.args.size()) {
            const Value& key = s.args[i];
            std::string spelled;
            if (key.is_string())
                spelled = key.string;
            else if (key.is_array() && key.strings.size() == 1)
                spelled = key.strings[0];
            else
                fail(s, std::string("expected a parameter name, got ") + describe(key));
            if (i + 1 >= s.args.size())
                fail(s, "parameter \"" + spelled + "\" has no value");
            const Value& value = s.args[i + 1];
            i += 2;

            Param p;
            Decl decl;
            if (spelled.find_first_of(" \t\n") != std::string::npos) {
                std::string err = parse_decl(spelled, true, decl, &p.name);
                if (!err.empty()) fail(s, err);
            } else {
                auto it = m_decls.find(spelled);
                if (it == m_decls.end()) {
                    if (m_warned.insert("undeclared " + spelled).second)
                        warn(s, s.name + ": undeclared parameter \"" + spelled +
                                    "\", skipped");
                    continue;
                }
                p.name = spelled;
                decl = it->second;
            }
            p.type = decl.type;
            p.storage = decl.storage;
            p.array_size = decl.array_size;
            const std::string label = "parameter \"" + p.name + "\"";

            if (p.type == ParamType::String) {
                if (value.is_string())
                    p.strings = {value.string};
                else if (value.is_array() &&
                         (value.string_array || value.numbers.empty()))
                    p.strings = value.strings;
                else
                    fail(s, label + " (string) expects strings, got " + describe(value));
                if (p.strings.empty() ||
                    p.strings.size() % static_cast<std::size_t>(p.array_size))
                    fail(s, label + ": " + std::to_string(p.strings.size()) +
                                " strings is not a whole number of string[" +
                                std::to_string(p.array_size) + "] values");
                if (single && p.strings.size() != static_cast<std::size_t>(p.array_size))
                    fail(s, label + ": expected " + std::to_string(p.array_size) +
                                " string(s), got " + std::to_string(p.strings.size()));
            } else {
                if (value.is_number())
                    p.numbers = {value.number};
                else if (value.is_array() && !value.string_array)
                    p.numbers = value.numbers;
                else
                    fail(s, label + " (" + param_type_name(p.type) +
                                ") expects numbers, got " + describe(value));
                const std::size_t es = static_cast<std::size_t>(p.element_size());
                if (p.numbers.empty() || p.numbers.size() % es)
                    fail(s,
                         label + ": " + std::to_string(p.numbers.size()) +
                             " numbers is not a whole number of " +
                             param_type_name(p.type) +
                             (p.array_size > 1 ? "[" + std::to_string(p.array_size) + "]"
                                               : std::string()) +
                             " values (" + std::to_string(es) + " numbers each)");
                if (single && p.numbers.size() != es)
                    fail(s, label + ": expected " + std::to_string(es) +
                                " numbers, got " + std::to_string(p.numbers.size()));
                if (p.type == ParamType::Integer)
                    for (double d : p.numbers) to_int(s, d, label);
            }
            list.set(std::move(p));
        }
        return list;
    }

    // --- graphics state ------------------------------------------------------

    Attributes& attrs_mut() {
        m_attr.snapshot.reset();
        return m_attr.attrs;
    }

    std::shared_ptr<const Attributes> snapshot() {
        if (!m_attr.snapshot)
            m_attr.snapshot = std::make_shared<const Attributes>(m_attr.attrs);
        return m_attr.snapshot;
    }

    void push(const Statement& s, Block block) {
        m_stack.push_back(SavedState{block, m_ctm, m_attr, s.line, s.file});
    }

    SavedState pop(const Statement& s, Block block) {
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

    static std::string where_saved(const SavedState& s) {
        return *s.file + ":" + std::to_string(s.line);
    }

    void restore_all(SavedState& saved) {
        m_ctm = saved.ctm;
        m_attr = std::move(saved.attributes);
    }

    /// CTM = CTM * m: the new transform applies to points first.
    void concat(const Matrix4& m) { m_ctm = m_ctm * m; }

    /// True when the current space is left-handed (camera space is).
    bool current_left_handed() const {
        Matrix4 to_camera = m_in_world ? m_world_to_camera * m_ctm : m_ctm;
        return glm::determinant(to_camera) > 0.0;
    }

    /// Options are frozen inside the world block: such requests only warn.
    bool option_allowed(const Statement& s) {
        if (!m_in_world) return true;
        warn(s, s.name + " inside WorldBegin/WorldEnd has no effect, ignored");
        return false;
    }

    /// A shader call with its space; before WorldBegin the space is camera-relative
    /// and is converted at WorldBegin.
    ShaderRef make_shader(const Statement& s, const std::string& name, ParamList params) {
        ShaderRef ref;
        ref.name = name;
        ref.params = std::move(params);
        ref.shader_to_world = m_ctm;
        ref.source = where(s);
        return ref;
    }

    // --- options -----------------------------------------------------------

    void do_format(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 3);
        no_more_args(s, i);
        int xres = to_int(s, n[0], "xresolution");
        int yres = to_int(s, n[1], "yresolution");
        if (xres < 1 || yres < 1) fail(s, "resolution must be positive");
        if (!(n[2] > 0.0))
            fail(s, "pixel aspect ratio must be positive, got " + fmt(n[2]));
        if (!option_allowed(s)) return;
        m_scene.options.camera.xres = xres;
        m_scene.options.camera.yres = yres;
        m_scene.options.camera.pixel_aspect = n[2];
    }

    void do_frame_aspect(const Statement& s) {
        std::size_t i = 0;
        double a = take_number(s, i);
        no_more_args(s, i);
        if (!(a > 0.0)) fail(s, "frame aspect ratio must be positive, got " + fmt(a));
        if (option_allowed(s)) m_frame_aspect = a;
    }

    void do_screen_window(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 4);
        no_more_args(s, i);
        if (n[0] == n[1] || n[2] == n[3]) fail(s, "empty screen window");
        if (option_allowed(s))
            m_scene.options.camera.screen_window = {n[0], n[1], n[2], n[3]};
    }

    void do_crop_window(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 4);
        no_more_args(s, i);
        for (double v : n)
            if (v < 0.0 || v > 1.0) fail(s, "crop window values must lie in [0,1]");
        // Only restricts which pixels are rendered: nothing to record here.
    }

    void do_projection(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "projection name");
        ParamList params = take_params(s, i, true);
        if (!option_allowed(s)) return;
        Camera& cam = m_scene.options.camera;
        if (name == "perspective") {
            double fov = params.get_float("fov", cam.fov);
            if (!(fov > 0.0 && fov < 180.0))
                fail(s, "fov must lie in (0, 180) degrees, got " + fmt(fov));
            cam.perspective = true;
            cam.fov = fov;
        } else if (name == "orthographic") {
            cam.perspective = false;
        } else {
            fail(s,
                 "unsupported projection \"" + name + "\" (perspective or orthographic)");
        }
        // RI: the projection marks camera space; the CTM restarts from identity.
        if (m_ctm != Matrix4(1.0))
            warn(s, "transformations before Projection are part of the screen "
                    "transformation and are ignored");
        m_ctm = Matrix4(1.0);
    }

    void do_clipping(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 2);
        no_more_args(s, i);
        if (!(n[0] > 0.0) || !(n[1] > n[0]))
            fail(s, "need 0 < near < far, got " + fmt(n[0]) + " " + fmt(n[1]));
        if (!option_allowed(s)) return;
        m_scene.options.camera.near_clip = n[0];
        m_scene.options.camera.far_clip = n[1];
    }

    void do_pixel_samples(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 2);
        no_more_args(s, i);
        for (double v : n)
            if (!(v >= 1.0 && v <= 1024.0))
                fail(s, "pixel samples must lie in [1, 1024]");
        if (!option_allowed(s)) return;
        m_scene.options.pixel_samples[0] = static_cast<int>(std::ceil(n[0]));
        m_scene.options.pixel_samples[1] = static_cast<int>(std::ceil(n[1]));
    }

    void do_display(const Statement& s) {
        std::size_t i = 0;
        DisplaySpec d;
        d.name = take_string(s, i, "display name");
        d.type = take_string(s, i, "display type");
        d.mode = take_string(s, i, "display mode");
        d.params = take_params(s, i, true);
        if (!d.name.empty() && d.name[0] == '+') {
            d.additional = true;
            d.name.erase(0, 1);
        }
        if (d.name.empty()) fail(s, "empty display name");
        if (!option_allowed(s)) return;
        // A primary display replaces every earlier display.
        if (!d.additional) m_scene.options.displays.clear();
        m_scene.options.displays.push_back(std::move(d));
    }

    void do_display_channel(const Statement& s) {
        std::size_t i = 0;
        std::string text = take_string(s, i, "channel declaration");
        take_params(s, i, true); // per-channel filter settings: not used
        Decl decl;
        std::string name, type_text;
        std::string err = parse_decl(text, true, decl, &name, &type_text);
        if (!err.empty()) fail(s, err);
        if (!option_allowed(s)) return;
        auto& chans = m_scene.options.display_channels;
        auto it = std::find_if(chans.begin(), chans.end(),
                               [&](const auto& c) { return c.first == name; });
        if (it != chans.end())
            it->second = type_text;
        else
            chans.emplace_back(name, type_text);
        m_decls[name] = decl;
    }

    void do_hider(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "hider name");
        take_params(s, i, true);
        if (option_allowed(s)) m_scene.options.hider = name;
    }

    void do_option(const Statement& s) {
        std::size_t i = 0;
        std::string group = take_string(s, i, "option name");
        ParamList params = take_params(s, i, true);
        ParamList& dst = m_scene.options.groups[group];
        for (Param& p : params.items) dst.set(std::move(p));
    }

    void do_color_samples(const Statement& s) {
        std::size_t i = 0;
        auto a = take_float_array(s, i, "nRGB matrix");
        auto b = take_float_array(s, i, "RGBn matrix");
        no_more_args(s, i);
        if (a.size() != 9 || b.size() != 9) fail(s, "only 3 color samples are supported");
    }

    void do_declare(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "name");
        std::string text = take_string(s, i, "declaration");
        no_more_args(s, i);
        if (name.empty() || name.find_first_of(" \t\n[]") != std::string::npos)
            fail(s, "bad parameter name \"" + name + "\"");
        Decl decl;
        std::string err = parse_decl(text, false, decl, nullptr);
        if (!err.empty()) fail(s, err);
        m_decls[name] = decl;
    }

    // --- blocks --------------------------------------------------------------

    void do_frame_begin(const Statement& s) {
        std::size_t i = 0;
        int number = to_int(s, take_number(s, i), "frame number");
        no_more_args(s, i);
        if (m_in_frame) fail(s, "nested FrameBegin");
        if (m_in_world) fail(s, "FrameBegin inside WorldBegin/WorldEnd");
        m_frames_seen = true;
        bool wanted = !m_frame_read && (!m_options.frame || *m_options.frame == number);
        if (!wanted) {
            m_skipping = true;
            m_skip_line = s.line;
            m_skip_file = s.file;
            return;
        }
        m_frame_read = true;
        m_in_frame = true;
        m_scene.options.frame = number;
        push(s, Block::Frame);
    }

    void do_frame_end(const Statement& s) {
        no_more_args(s, 0);
        if (!m_in_frame) fail(s, "FrameEnd without FrameBegin");
        SavedState saved = pop(s, Block::Frame);
        restore_all(saved);
        m_in_frame = false;
    }

    void do_world_begin(const Statement& s) {
        no_more_args(s, 0);
        if (m_in_world) fail(s, "nested WorldBegin");
        if (m_object) fail(s, "WorldBegin inside ObjectBegin");
        push(s, Block::World);
        m_in_world = true;
        m_world_to_camera = m_ctm;
        Camera& cam = m_scene.options.camera;
        cam.world_to_camera = m_ctm;
        if (m_frame_aspect && !cam.screen_window) {
            double a = *m_frame_aspect;
            cam.screen_window = a >= 1.0
                                    ? std::array<double, 4>{-a, a, -1.0, 1.0}
                                    : std::array<double, 4>{-1.0, 1.0, -1.0 / a, 1.0 / a};
        }
        const Matrix4 camera_to_world = glm::inverse(m_world_to_camera);
        for (const auto& [name, to_camera] : m_camera_spaces)
            m_scene.coordinate_systems[name] = camera_to_world * to_camera;
        // A Surface given among the options was placed in camera space.
        if (m_attr.attrs.surface) {
            ShaderRef& ref = *attrs_mut().surface;
            ref.shader_to_world = camera_to_world * ref.shader_to_world;
        }
        m_ctm = Matrix4(1.0);
    }

    void do_world_end(const Statement& s) {
        no_more_args(s, 0);
        if (!m_in_world) fail(s, "WorldEnd without WorldBegin");
        SavedState saved = pop(s, Block::World);
        restore_all(saved);
        m_in_world = false;
    }

    void do_attribute_begin(const Statement& s) { push(s, Block::Attribute); }

    void do_attribute_end(const Statement& s) {
        SavedState saved = pop(s, Block::Attribute);
        restore_all(saved);
    }

    void do_transform_begin(const Statement& s) { push(s, Block::Transform); }

    void do_transform_end(const Statement& s) { m_ctm = pop(s, Block::Transform).ctm; }

    void do_solid_begin(const Statement& s) {
        warn_once("solid", s,
                  "SolidBegin: CSG is not supported, the parts are kept as "
                  "separate primitives");
        push(s, Block::Solid);
    }

    void do_solid_end(const Statement& s) {
        SavedState saved = pop(s, Block::Solid);
        restore_all(saved);
    }

    void do_motion_begin(const Statement& s) {
        if (m_in_motion) fail(s, "nested MotionBegin");
        m_in_motion = true;
        m_motion_used = false;
        warn_once("motion", s,
                  "motion blur is not supported: the first time sample is used");
    }

    void do_motion_end(const Statement& s) {
        if (!m_in_motion) fail(s, "MotionEnd without MotionBegin");
        m_in_motion = false;
    }

    void do_object_begin(const Statement& s) {
        std::size_t i = 0;
        std::string handle = take_handle(s, i);
        if (m_object) fail(s, "nested ObjectBegin");
        push(s, Block::Object);
        m_object_handle = handle;
        m_object = &m_objects[handle];
        m_object->clear(); // redefinition replaces
        m_ctm = Matrix4(1.0);
    }

    void do_object_end(const Statement& s) {
        if (!m_object) fail(s, "ObjectEnd without ObjectBegin");
        SavedState saved = pop(s, Block::Object);
        restore_all(saved);
        m_object = nullptr;
    }

    void do_object_instance(const Statement& s) {
        std::size_t i = 0;
        std::string handle = take_handle(s, i);
        no_more_args(s, i);
        auto it = m_objects.find(handle);
        if (it == m_objects.end() || (m_object && handle == m_object_handle))
            fail(s, "unknown object handle \"" + handle + "\"");
        for (const Primitive& def : it->second) {
            Primitive p = def;
            add_primitive(s, std::move(p), def.object_to_world, def.source);
        }
    }

    void do_archive_begin(const Statement& s) {
        std::size_t i = 0;
        m_record_name = take_string(s, i, "archive name");
        m_recording = true;
        m_record_depth = 0;
        m_record_line = s.line;
        m_record_file = s.file;
        m_record.clear();
    }

    void do_archive_end(const Statement& s) {
        fail(s, "ArchiveEnd without ArchiveBegin");
    }

    void read_archive(const Statement& s, const std::string& name) {
        auto it = m_archives.find(name);
        if (it != m_archives.end()) {
            if (m_depth >= kMaxArchiveDepth)
                fail(s, "archives nested more than " + std::to_string(kMaxArchiveDepth) +
                            " deep (does \"" + name + "\" read itself?)");
            // Copy: the archive may be redefined while it is replayed.
            std::vector<Statement> body = it->second;
            ++m_depth;
            for (const Statement& st : body) execute(st);
            --m_depth;
            return;
        }
        run_file(s, resolve_path(s, name));
    }

    void do_read_archive(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "archive file name");
        take_params(s, i, true);
        read_archive(s, name);
    }

    void do_procedural(const Statement& s) {
        std::size_t i = 0;
        std::string kind = take_string(s, i, "procedural name");
        if (kind != "DelayedReadArchive") {
            warn_once("procedural " + kind, s,
                      "Procedural \"" + kind + "\" is not supported, skipped");
            return;
        }
        auto files = take_string_array(s, i, "archive file name");
        auto bound = take_float_array(s, i, "bound");
        no_more_args(s, i);
        if (files.size() != 1) fail(s, "DelayedReadArchive needs exactly one file name");
        if (bound.size() != 6) fail(s, "bound must have 6 numbers");
        // A procedural runs in a copy of the graphics state.
        push(s, Block::Attribute);
        read_archive(s, files[0]);
        SavedState saved = pop(s, Block::Attribute);
        restore_all(saved);
    }

    // --- transforms ----------------------------------------------------------

    void do_identity(const Statement& s) {
        no_more_args(s, 0);
        m_ctm = Matrix4(1.0);
    }

    void do_transform(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 16);
        no_more_args(s, i);
        m_ctm = matrix_from(n);
    }

    void do_concat_transform(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 16);
        no_more_args(s, i);
        concat(matrix_from(n));
    }

    void do_translate(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 3);
        no_more_args(s, i);
        concat(glm::translate(Matrix4(1.0), glm::dvec3(n[0], n[1], n[2])));
    }

    void do_rotate(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 4);
        no_more_args(s, i);
        glm::dvec3 axis(n[1], n[2], n[3]);
        double len = glm::length(axis);
        if (!(len > 0.0)) fail(s, "rotation axis is zero");
        concat(glm::rotate(Matrix4(1.0), glm::radians(n[0]), axis / len));
    }

    void do_scale(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 3);
        no_more_args(s, i);
        concat(glm::scale(Matrix4(1.0), glm::dvec3(n[0], n[1], n[2])));
    }

    void do_skew(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 7);
        no_more_args(s, i);
        glm::dvec3 v1(n[1], n[2], n[3]), v2(n[4], n[5], n[6]);
        if (!(glm::length(v2) > 0.0) || !(glm::length(v1) > 0.0))
            fail(s, "zero skew vector");
        // Points shift along v2 in proportion to their component along b, the
        // part of v1 orthogonal to v2, so that v1 turns by `angle` towards v2.
        glm::dvec3 a = glm::normalize(v2);
        double alpha = glm::dot(v1, a);
        glm::dvec3 perp = v1 - alpha * a;
        double beta = glm::length(perp);
        if (!(beta > 1e-12 * glm::length(v1))) fail(s, "skew vectors are parallel");
        glm::dvec3 b = perp / beta;
        double theta = std::atan2(alpha, beta) + glm::radians(n[0]);
        if (!(std::abs(theta) < std::numbers::pi / 2 - 1e-9))
            fail(s, "skew angle turns the vector past the skew axis");
        double k = std::tan(theta) - alpha / beta;
        Matrix4 m(1.0);
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) m[c][r] += k * a[r] * b[c];
        concat(m);
    }

    void do_perspective(const Statement& s) {
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

    static bool predefined_space(std::string_view n) {
        return n == "world" || n == "camera" || n == "object" || n == "shader" ||
               n == "current" || n == "screen" || n == "raster" || n == "NDC";
    }

    void do_coordinate_system(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "coordinate system name");
        no_more_args(s, i);
        if (name.empty()) fail(s, "empty coordinate system name");
        if (predefined_space(name)) fail(s, "\"" + name + "\" is a predefined space");
        if (m_in_world)
            m_scene.coordinate_systems[name] = m_ctm;
        else
            m_camera_spaces[name] = m_ctm;
    }

    void do_coord_sys_transform(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "coordinate system name");
        no_more_args(s, i);
        if (name == "object" || name == "current") return;
        if (name == "world") {
            if (!m_in_world) fail(s, "world space is not defined before WorldBegin");
            m_ctm = Matrix4(1.0);
        } else if (name == "camera") {
            m_ctm = m_in_world ? glm::inverse(m_world_to_camera) : Matrix4(1.0);
        } else if (name == "shader") {
            if (m_attr.attrs.surface) m_ctm = m_attr.attrs.surface->shader_to_world;
        } else if (name == "screen" || name == "raster" || name == "NDC") {
            fail(s, "\"" + name + "\" space is not supported");
        } else if (m_in_world) {
            auto it = m_scene.coordinate_systems.find(name);
            if (it == m_scene.coordinate_systems.end())
                fail(s, "unknown coordinate system \"" + name + "\"");
            m_ctm = it->second;
        } else {
            auto it = m_camera_spaces.find(name);
            if (it == m_camera_spaces.end())
                fail(s, "unknown coordinate system \"" + name + "\"");
            m_ctm = it->second;
        }
    }

    // --- attributes ----------------------------------------------------------

    void do_attribute(const Statement& s) {
        std::size_t i = 0;
        std::string group = take_string(s, i, "attribute name");
        ParamList params = take_params(s, i, true);
        ParamList& dst = attrs_mut().groups[group];
        for (Param& p : params.items) dst.set(std::move(p));
    }

    glm::dvec3 take_color(const Statement& s) {
        std::size_t i = 0;
        auto n = take_numbers(s, i, 3);
        no_more_args(s, i);
        return {n[0], n[1], n[2]};
    }

    void do_color(const Statement& s) { attrs_mut().color = take_color(s); }

    void do_opacity(const Statement& s) { attrs_mut().opacity = take_color(s); }

    void do_sides(const Statement& s) {
        std::size_t i = 0;
        double n = take_number(s, i);
        no_more_args(s, i);
        if (n != 1.0 && n != 2.0) fail(s, "sides must be 1 or 2, got " + fmt(n));
        attrs_mut().sides = static_cast<int>(n);
    }

    void do_orientation(const Statement& s) {
        std::size_t i = 0;
        std::string o = take_string(s, i, "orientation");
        no_more_args(s, i);
        bool inside;
        if (o == "outside")
            inside = false;
        else if (o == "inside")
            inside = true;
        else if (o == "lh")
            inside = !current_left_handed();
        else if (o == "rh")
            inside = current_left_handed();
        else
            fail(s, "orientation must be outside, inside, lh or rh, got \"" + o + "\"");
        attrs_mut().orientation_inside = inside;
    }

    void do_reverse_orientation(const Statement& s) {
        no_more_args(s, 0);
        Attributes& a = attrs_mut();
        a.orientation_inside = !a.orientation_inside;
    }

    void do_shading_rate(const Statement& s) {
        std::size_t i = 0;
        double r = take_number(s, i);
        no_more_args(s, i);
        if (!(r > 0.0)) fail(s, "shading rate must be positive, got " + fmt(r));
        attrs_mut().shading_rate = r;
    }

    void do_shading_interpolation(const Statement& s) {
        std::size_t i = 0;
        std::string mode = take_string(s, i, "interpolation");
        no_more_args(s, i);
        if (mode != "constant" && mode != "smooth")
            fail(s, "interpolation must be constant or smooth, got \"" + mode + "\"");
        attrs_mut().shading_interpolation = mode;
    }

    void do_surface(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "shader name");
        ParamList params = take_params(s, i, true);
        attrs_mut().surface = make_shader(s, name, std::move(params));
    }

    void do_light_source(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "shader name");
        // The handle is there when the rest is not a whole number of pairs.
        std::string handle;
        if ((s.args.size() - i) % 2 == 1)
            handle = take_handle(s, i);
        else
            handle = "unnamed " + std::to_string(m_scene.lights.size());
        ParamList params = take_params(s, i, true);
        if (!m_in_world) fail(s, "light sources must be inside WorldBegin/WorldEnd");
        if (m_object) fail(s, "light sources cannot be part of an object definition");
        LightInstance light;
        light.shader = make_shader(s, name, std::move(params));
        light.handle = handle;
        light.area = s.name == "AreaLightSource";
        int index = static_cast<int>(m_scene.lights.size());
        m_scene.lights.push_back(std::move(light));
        m_light_handles[handle] = index;
        set_light(index, true);
    }

    void set_light(int index, bool on) {
        auto& on_list = m_attr.attrs.lights_on;
        auto it = std::lower_bound(on_list.begin(), on_list.end(), index);
        bool present = it != on_list.end() && *it == index;
        if (on == present) return;
        auto& list = attrs_mut().lights_on;
        it = std::lower_bound(list.begin(), list.end(), index);
        if (on)
            list.insert(it, index);
        else
            list.erase(it);
    }

    void do_illuminate(const Statement& s) {
        std::size_t i = 0;
        std::string handle = take_handle(s, i);
        double on = take_number(s, i);
        no_more_args(s, i);
        auto it = m_light_handles.find(handle);
        if (it == m_light_handles.end())
            fail(s, "unknown light handle \"" + handle + "\"");
        set_light(it->second, on != 0.0);
    }

    Basis take_basis(const Statement& s, std::size_t& i, const char* which) {
        need_args(s, i, which);
        Basis b;
        const Value& v = s.args[i];
        if (v.is_string() || (v.is_array() && v.strings.size() == 1)) {
            std::string name = v.is_string() ? v.string : v.strings[0];
            auto nb = named_basis(name);
            if (!nb) fail(s, "unknown basis \"" + name + "\"");
            b = *nb;
            ++i;
        } else {
            auto n = take_numbers(s, i, 16);
            b.matrix = matrix_from(n);
            b.name = "custom";
        }
        b.step = to_int(s, take_number(s, i), std::string(which) + " step");
        if (b.step < 1) fail(s, std::string(which) + " step must be positive");
        return b;
    }

    void do_basis(const Statement& s) {
        std::size_t i = 0;
        Basis u = take_basis(s, i, "ubasis");
        Basis v = take_basis(s, i, "vbasis");
        no_more_args(s, i);
        Attributes& a = attrs_mut();
        a.u_basis = u;
        a.v_basis = v;
    }

    // --- geometry ------------------------------------------------------------

    /// Stores a primitive under the current transform and attributes (or in
    /// the object being defined).
    void add_primitive(const Statement& s, Primitive p, const Matrix4& object_to_ctm,
                       const std::string& source) {
        if (!m_object && !m_in_world) fail(s, "geometry outside WorldBegin/WorldEnd");
        p.object_to_world = m_ctm * object_to_ctm;
        p.source = source;
        if (m_object) {
            p.attributes.reset(); // objects take the attributes of each instance
            m_object->push_back(std::move(p));
        } else {
            p.attributes = snapshot();
            m_scene.primitives.push_back(std::move(p));
        }
    }

    void add_primitive(const Statement& s, Primitive p) {
        add_primitive(s, std::move(p), Matrix4(1.0), where(s));
    }

    /// Makes "P" the position parameter (from Pw or, for patches, Pz) and
    /// checks it holds `n_points` points.
    void resolve_positions(const Statement& s, ParamList& params, std::size_t n_points,
                           int grid_nu = 0, int grid_nv = 0, bool uwrap = false,
                           bool vwrap = false) {
        auto remove = [&](std::string_view name) {
            std::erase_if(params.items, [&](const Param& p) { return p.name == name; });
        };
        const Param* P = params.find("P");
        const Param* Pw = params.find("Pw");
        const Param* Pz = params.find("Pz");
        if ((P != nullptr) + (Pw != nullptr) + (Pz != nullptr) > 1)
            fail(s, "give only one of \"P\", \"Pw\" and \"Pz\"");
        if (P) {
            if (P->type != ParamType::Point || P->array_size != 1)
                fail(s, "\"P\" must be a point, not " +
                            std::string(param_type_name(P->type)));
        } else if (Pw) {
            if (Pw->type != ParamType::HPoint || Pw->array_size != 1)
                fail(s, "\"Pw\" must be an hpoint");
            Param np;
            np.name = "P";
            np.type = ParamType::Point;
            np.storage = ParamClass::Vertex;
            bool uniform_w = true;
            const auto& h = Pw->numbers;
            for (std::size_t k = 0; k + 3 < h.size(); k += 4) {
                double w = h[k + 3];
                if (w == 0.0) fail(s, "\"Pw\" has a point with w = 0");
                if (w != h[3]) uniform_w = false;
                for (int c = 0; c < 3; ++c) np.numbers.push_back(h[k + c] / w);
            }
            if (!uniform_w && grid_nu > 0)
                warn_once("rational " + s.name, s,
                          s.name +
                              ": rational patches are approximated by dividing by w");
            remove("Pw");
            params.items.push_back(std::move(np));
        } else if (Pz) {
            if (grid_nu <= 0) fail(s, "\"Pz\" is only for patches");
            if (Pz->type != ParamType::Float || Pz->array_size != 1)
                fail(s, "\"Pz\" must be a float");
            if (Pz->numbers.size() != n_points)
                fail(s, "\"Pz\" has " + std::to_string(Pz->numbers.size()) +
                            " values, expected " + std::to_string(n_points));
            // A height field over the unit square, u varying fastest.
            Param np;
            np.name = "P";
            np.type = ParamType::Point;
            np.storage = ParamClass::Vertex;
            double du = 1.0 / (uwrap ? grid_nu : grid_nu - 1);
            double dv = 1.0 / (vwrap ? grid_nv : grid_nv - 1);
            for (int v = 0; v < grid_nv; ++v)
                for (int u = 0; u < grid_nu; ++u) {
                    np.numbers.push_back(u * du);
                    np.numbers.push_back(v * dv);
                    np.numbers.push_back(
                        Pz->numbers[static_cast<std::size_t>(v) * grid_nu + u]);
                }
            remove("Pz");
            params.items.push_back(std::move(np));
        } else {
            fail(s, "missing \"P\"");
        }
        const Param* p = params.find("P");
        if (p->element_count() != n_points)
            fail(s, "\"P\" has " + std::to_string(p->element_count()) +
                        " points, expected " + std::to_string(n_points));
    }

    /// Every other parameter must have the number of values its class asks for.
    static void check_counts(const Statement& s, const ParamList& params,
                             const ClassCounts& n) {
        for (const Param& p : params.items) {
            if (p.name == "P") continue;
            std::size_t want = n.of(p.storage);
            if (p.element_count() != want)
                fail(s, "parameter \"" + p.name + "\" (" + param_class_name(p.storage) +
                            " " + param_type_name(p.type) + ") has " +
                            std::to_string(p.element_count()) + " values, expected " +
                            std::to_string(want));
        }
    }

    static std::size_t vertex_count(const std::vector<int>& verts) {
        int m = -1;
        for (int v : verts) m = std::max(m, v);
        return static_cast<std::size_t>(m + 1);
    }

    static std::size_t sum(const std::vector<int>& v) {
        std::size_t total = 0;
        for (int k : v) total += static_cast<std::size_t>(k);
        return total;
    }

    void do_polygon(const Statement& s) {
        ParamList params = take_params(s, 0, false);
        const Param* P = params.find("P");
        const Param* Pw = params.find("Pw");
        std::size_t n = P ? P->element_count() : Pw ? Pw->element_count() : 0;
        if (n < 3)
            fail(s, "a polygon needs \"P\" with at least 3 points, got " +
                        std::to_string(n));
        resolve_positions(s, params, n);
        check_counts(s, params, counts(1, n, n, n));
        Primitive p;
        p.kind = PrimitiveKind::Polygon;
        p.nverts = {static_cast<int>(n)};
        p.params = std::move(params);
        add_primitive(s, std::move(p));
    }

    void do_general_polygon(const Statement& s) {
        std::size_t i = 0;
        Primitive p;
        p.kind = PrimitiveKind::GeneralPolygon;
        p.nverts = take_ints(s, i, "nvertices", 3);
        if (p.nverts.empty()) fail(s, "no loops");
        p.params = take_params(s, i, false);
        std::size_t n = sum(p.nverts);
        resolve_positions(s, p.params, n);
        check_counts(s, p.params, counts(1, n, n, n));
        add_primitive(s, std::move(p));
    }

    void check_indices(const Statement& s, const std::vector<int>& verts,
                       std::size_t expected) {
        if (verts.size() != expected)
            fail(s, "vertices has " + std::to_string(verts.size()) +
                        " indices, the vertex counts add up to " +
                        std::to_string(expected));
    }

    void do_points_polygons(const Statement& s) {
        std::size_t i = 0;
        Primitive p;
        p.kind = PrimitiveKind::PointsPolygons;
        p.nverts = take_ints(s, i, "nvertices", 3);
        p.verts = take_ints(s, i, "vertices", 0);
        p.params = take_params(s, i, false);
        if (p.nverts.empty()) fail(s, "no polygons");
        check_indices(s, p.verts, sum(p.nverts));
        std::size_t nv = vertex_count(p.verts);
        resolve_positions(s, p.params, nv);
        check_counts(s, p.params, counts(p.nverts.size(), nv, nv, p.verts.size()));
        add_primitive(s, std::move(p));
    }

    void do_points_general_polygons(const Statement& s) {
        std::size_t i = 0;
        Primitive p;
        p.kind = PrimitiveKind::PointsGeneralPolygons;
        p.nloops = take_ints(s, i, "nloops", 1);
        p.nverts = take_ints(s, i, "nvertices", 3);
        p.verts = take_ints(s, i, "vertices", 0);
        p.params = take_params(s, i, false);
        if (p.nloops.empty()) fail(s, "no polygons");
        if (p.nverts.size() != sum(p.nloops))
            fail(s, "nvertices has " + std::to_string(p.nverts.size()) +
                        " loops, nloops adds up to " + std::to_string(sum(p.nloops)));
        check_indices(s, p.verts, sum(p.nverts));
        std::size_t nv = vertex_count(p.verts);
        resolve_positions(s, p.params, nv);
        check_counts(s, p.params, counts(p.nloops.size(), nv, nv, p.verts.size()));
        add_primitive(s, std::move(p));
    }

    void do_subdivision_mesh(const Statement& s) {
        std::size_t i = 0;
        Primitive p;
        p.kind = PrimitiveKind::SubdivisionMesh;
        p.type = take_string(s, i, "scheme");
        p.nverts = take_ints(s, i, "nvertices", 3);
        p.verts = take_ints(s, i, "vertices", 0);
        if (i < s.args.size() && s.args[i].is_array()) {
            p.tags = take_string_array(s, i, "tags");
            p.tag_nargs = take_ints(s, i, "nargs", 0);
            p.tag_intargs = take_ints(s, i, "intargs", std::numeric_limits<int>::min());
            p.tag_floatargs = take_float_array(s, i, "floatargs");
        }
        p.params = take_params(s, i, false);
        if (p.nverts.empty()) fail(s, "no faces");
        check_indices(s, p.verts, sum(p.nverts));
        std::size_t nv = vertex_count(p.verts);
        if (p.tag_nargs.size() != 2 * p.tags.size())
            fail(s,
                 "nargs must have 2 numbers per tag: " + std::to_string(p.tags.size()) +
                     " tags, " + std::to_string(p.tag_nargs.size()) + " numbers");
        std::size_t ni = 0, nf = 0;
        for (std::size_t t = 0; t < p.tags.size(); ++t) {
            std::size_t ti = static_cast<std::size_t>(p.tag_nargs[2 * t]);
            std::size_t tf = static_cast<std::size_t>(p.tag_nargs[2 * t + 1]);
            if (ni + ti > p.tag_intargs.size() || nf + tf > p.tag_floatargs.size())
                fail(s, "tag \"" + p.tags[t] + "\" needs more arguments than given");
            const std::string& tag = p.tags[t];
            // Indices of the tags that name vertices or faces must exist.
            std::size_t limit = tag == "hole"                          ? p.nverts.size()
                                : (tag == "crease" || tag == "corner") ? nv
                                                                       : 0;
            if (limit)
                for (std::size_t k = ni; k < ni + ti; ++k)
                    if (p.tag_intargs[k] < 0 ||
                        static_cast<std::size_t>(p.tag_intargs[k]) >= limit)
                        fail(s, "tag \"" + tag + "\": index " +
                                    std::to_string(p.tag_intargs[k]) + " out of range");
            ni += ti;
            nf += tf;
        }
        if (ni != p.tag_intargs.size() || nf != p.tag_floatargs.size())
            fail(s, "tag argument counts do not match intargs/floatargs");
        resolve_positions(s, p.params, nv);
        check_counts(s, p.params, counts(p.nverts.size(), nv, nv, p.verts.size()));
        add_primitive(s, std::move(p));
    }

    void do_quadric(const Statement& s) {
        struct Q {
            std::string_view name;
            PrimitiveKind kind;
            std::size_t count;
        };
        static const Q table[] = {
            {"Sphere", PrimitiveKind::Sphere, 4},
            {"Cylinder", PrimitiveKind::Cylinder, 4},
            {"Cone", PrimitiveKind::Cone, 3},
            {"Disk", PrimitiveKind::Disk, 3},
            {"Torus", PrimitiveKind::Torus, 5},
            {"Hyperboloid", PrimitiveKind::Hyperboloid, 7},
            {"Paraboloid", PrimitiveKind::Paraboloid, 4},
        };
        const Q* q = nullptr;
        for (const Q& e : table)
            if (e.name == s.name) q = &e;
        std::size_t i = 0;
        Primitive p;
        p.kind = q->kind;
        p.args = take_numbers(s, i, q->count);
        p.params = take_params(s, i, false);
        if (p.params.has("P") || p.params.has("Pw") || p.params.has("Pz"))
            fail(s, "quadrics take no \"P\"");
        check_counts(s, p.params, counts(1, 4, 4, 4));
        add_primitive(s, std::move(p));
    }

    void do_patch(const Statement& s) {
        std::size_t i = 0;
        Primitive p;
        p.kind = PrimitiveKind::Patch;
        p.type = take_string(s, i, "patch type");
        p.params = take_params(s, i, false);
        int n;
        if (p.type == "bicubic")
            n = 4;
        else if (p.type == "bilinear")
            n = 2;
        else
            fail(s, "patch type must be bicubic or bilinear, got \"" + p.type + "\"");
        p.nu = p.nv = n;
        resolve_positions(s, p.params, static_cast<std::size_t>(n * n), n, n);
        check_counts(s, p.params, counts(1, 4, static_cast<std::size_t>(n * n), 4));
        add_primitive(s, std::move(p));
    }

    /// Patches and varying values along one direction of a patch mesh.
    void patch_dir(const Statement& s, const char* dir, int n, bool wrap, bool bicubic,
                   int step, std::size_t& patches, std::size_t& varying) {
        if (!bicubic) {
            if (n < 2) fail(s, std::string(dir) + " is too small for a bilinear mesh");
            patches = static_cast<std::size_t>(wrap ? n : n - 1);
            varying = static_cast<std::size_t>(n);
            return;
        }
        if (wrap) {
            if (n < step || n % step != 0)
                fail(s, std::string(dir) + " = " + std::to_string(n) +
                            " must be a positive multiple of the basis step " +
                            std::to_string(step) + " for a periodic mesh");
            patches = static_cast<std::size_t>(n / step);
            varying = patches;
        } else {
            if (n < 4 || (n - 4) % step != 0)
                fail(s, std::string(dir) + " = " + std::to_string(n) +
                            " must be 4 + a multiple of the basis step " +
                            std::to_string(step));
            patches = static_cast<std::size_t>((n - 4) / step + 1);
            varying = patches + 1;
        }
    }

    static bool take_wrap(const Statement& s, std::size_t& i, const char* what) {
        std::string w = take_string(s, i, what);
        if (w == "periodic") return true;
        if (w == "nonperiodic") return false;
        fail(s,
             std::string(what) + " must be periodic or nonperiodic, got \"" + w + "\"");
    }

    void do_patch_mesh(const Statement& s) {
        std::size_t i = 0;
        Primitive p;
        p.kind = PrimitiveKind::PatchMesh;
        p.type = take_string(s, i, "patch type");
        if (p.type != "bicubic" && p.type != "bilinear")
            fail(s, "patch type must be bicubic or bilinear, got \"" + p.type + "\"");
        p.nu = to_int(s, take_number(s, i), "nu");
        p.uwrap = take_wrap(s, i, "uwrap");
        p.nv = to_int(s, take_number(s, i), "nv");
        p.vwrap = take_wrap(s, i, "vwrap");
        p.params = take_params(s, i, false);
        bool bicubic = p.type == "bicubic";
        std::size_t pu, pv, vu, vv;
        patch_dir(s, "nu", p.nu, p.uwrap, bicubic, m_attr.attrs.u_basis.step, pu, vu);
        patch_dir(s, "nv", p.nv, p.vwrap, bicubic, m_attr.attrs.v_basis.step, pv, vv);
        std::size_t nvert =
            static_cast<std::size_t>(p.nu) * static_cast<std::size_t>(p.nv);
        resolve_positions(s, p.params, nvert, p.nu, p.nv, p.uwrap, p.vwrap);
        check_counts(s, p.params, counts(pu * pv, vu * vv, nvert, 4 * pu * pv));
        add_primitive(s, std::move(p));
    }

    void do_geometry(const Statement& s) {
        std::size_t i = 0;
        std::string name = take_string(s, i, "geometry name");
        if (name != "teapot") {
            warn_once("geometry " + name, s,
                      "Geometry \"" + name + "\" is not supported, skipped");
            return;
        }
        Primitive p;
        p.kind = PrimitiveKind::Teapot;
        p.params = take_params(s, i, false);
        for (const Param& q : p.params.items)
            if (q.storage != ParamClass::Constant && q.storage != ParamClass::Uniform)
                fail(s, "parameter \"" + q.name +
                            "\": only constant and uniform parameters "
                            "are allowed on the teapot");
        check_counts(s, p.params, counts(1, 1, 1, 1));
        add_primitive(s, std::move(p));
    }

    // --- Wavefront OBJ -------------------------------------------------------

    /// The mesh of an OBJ file, as a primitive under the current state.
    void add_obj(const std::string& text, const std::string& path) {
        auto mesh = detail::import_obj(text, path, m_scene.warnings);
        if (!mesh) return;
        Statement at;
        at.name = "ReadArchive";
        at.file = std::make_shared<const std::string>(path);
        at.line = mesh->first_face_line;
        add_primitive(at, std::move(mesh->primitive), Matrix4(1.0),
                      path + ":" + std::to_string(mesh->first_face_line));
    }

    // --- state ---------------------------------------------------------------

    RibReadOptions m_options;
    Scene m_scene;
    std::unordered_map<std::string, Decl> m_decls;
    Matrix4 m_ctm{1.0};
    AttributeState m_attr;
    std::vector<SavedState> m_stack;
    bool m_in_world = false;
    Matrix4 m_world_to_camera{1.0};
    std::optional<double> m_frame_aspect;
    std::map<std::string, Matrix4> m_camera_spaces; // CoordinateSystem before WorldBegin
    std::set<std::string> m_warned;
    int m_depth = 0;
    // frames
    bool m_in_frame = false;
    bool m_frame_read = false;
    bool m_frames_seen = false;
    bool m_skipping = false;
    int m_skip_line = 0;
    std::shared_ptr<const std::string> m_skip_file;
    // motion blocks
    bool m_in_motion = false;
    bool m_motion_used = false;
    // lights and objects
    std::unordered_map<std::string, int> m_light_handles;
    std::unordered_map<std::string, std::vector<Primitive>> m_objects;
    std::vector<Primitive>* m_object = nullptr;
    std::string m_object_handle;
    // inline archives
    std::unordered_map<std::string, std::vector<Statement>> m_archives;
    bool m_recording = false;
    int m_record_depth = 0;
    std::string m_record_name;
    int m_record_line = 0;
    std::shared_ptr<const std::string> m_record_file;
    std::vector<Statement> m_record;
};

} // namespace
} // namespace rib

Scene read_rib(const std::string& path, const RibReadOptions& options) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw IoError(path, "read error");
    Scene scene = parse_rib(ss.str(), path, options);
    scene.sources.insert(scene.sources.begin(), path);
    return scene;
}

Scene parse_rib(const std::string& text, const std::string& path,
                const RibReadOptions& options) {
    rib::Reader reader(options);
    reader.read_text(text, path);
    return reader.finish(path);
}

} // namespace sss

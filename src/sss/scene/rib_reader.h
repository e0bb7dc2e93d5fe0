// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file rib_reader.h
/// The RIB interpreter: a Reader executes statements in order, keeps the RI
/// graphics state (transform, attributes, blocks) and fills a Scene. Its
/// member functions are defined per kind of request, one file each (named
/// below with each group).

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "ri_context.h"
#include "rib_lexer.h"
#include "rib_params.h"
#include "sss/scene/blobby.h"
#include "sss/scene/rib.h"
#include "sss/scene/scene.h"

namespace sss::rib {

/// The blocks that save and restore (part of) the graphics state.
enum class Block { Attribute, Transform, World, Frame, Object, Solid };

/// "AttributeBegin", "WorldBegin"...: the request that opens a block.
const char* block_begin_name(Block b);

/// The attribute half of the graphics state, with a cached immutable
/// snapshot so that primitives made under unchanged attributes share it.
struct AttributeState {
    Attributes attrs;
    std::shared_ptr<const Attributes> snapshot;
};

/// A moving current transformation (MotionBegin around transformations):
/// the CTM at each time. Empty: the CTM does not move.
struct CtmMotion {
    std::vector<double> times;
    std::vector<Matrix4> keys;
};

/// The graphics state saved by an open block, and where the block opened.
struct SavedState {
    Block block;
    Matrix4 ctm;
    AttributeState attributes; // unused for TransformBegin
    int line;
    std::shared_ptr<const std::string> file;
    CtmMotion ctm_motion;
};

/// The whole text of a file, inflated if it is gzip; throws IoError
/// "cannot open<context>: <reason>".
std::string slurp(const std::string& path, const std::string& context);
/// The whole of standard input, inflated if it is gzip.
std::string slurp_standard_input();

/// The identity of a file for the ReadArchive cycle check: its canonical path.
std::string file_key(const std::string& path);

class Reader {
public:
    explicit Reader(const RibReadOptions& options)
        : m_options(options), m_decls(predeclared()) {}

    /// Executes every statement of `text` (read from `path`).
    void read_text(std::string_view text, const std::string& path);
    /// The scene read, after the checks at the end of the file.
    Scene finish(const std::string& path);

    // --- rib_dynamic_load.cpp: what the Ri C binding's calls reach -------------

    /// Carries out a statement an Ri call made.
    void ri_execute(const Statement& s) { execute(s); }
    /// What a parameter name is declared as (Declare or the predeclared
    /// names); nullptr when it is not.
    const Decl* declared(const std::string& name) const;
    /// The step of the current u basis (v: of the v basis).
    int basis_step(bool v) const;
    /// RiProcedural with a subdivide function of the DSO's own: run at once,
    /// in a copy of the graphics state, asked for the detail of its bound;
    /// then its free function (always, if there is one).
    void ri_procedural(const Statement& s, void* data, const double bound[6],
                       void (*subdivide)(void*, float), void (*free_data)(void*));

private:
    using Handler = void (Reader::*)(const Statement&);
    using HandlerTable = std::unordered_map<std::string_view, Handler>;

    // --- rib.cpp: dispatch and warnings ---------------------------------------

    /// Runs the statement's handler, or warns about a request it skips.
    void execute(const Statement& s);
    /// True when `s` is taken before its handler: recorded into an inline
    /// archive, skipped with a frame not read, or a later motion sample.
    bool diverted(const Statement& s);
    /// Request name -> handler.
    static const HandlerTable& handlers();
    /// Adds the warning "file:line: what"; `kind` groups it with others for
    /// the count (Warnings), else its text does.
    void warn(const Statement& s, const std::string& what, std::string_view kind = {});
    void warn_once(const std::string& key, const Statement& s, const std::string& what,
                   std::string_view kind = {});
    /// A request that is not carried out: a RibError "<what> (reading
    /// leniently: <lenient>, with a warning)", or when reading leniently
    /// that warning once per key ("<what>, <lenient>").
    void not_implemented(const std::string& key, const Statement& s,
                         const std::string& what, const std::string& lenient);

    // --- rib_params.cpp: parameter lists --------------------------------------

    /// The "name" value pairs from argument i on. `single`: every parameter
    /// must hold exactly one element (shader calls, options); otherwise any
    /// whole number of elements (primitives, checked against the topology).
    /// `shader`: a shader call's parameters, where an undeclared name is
    /// kept (Param::declared false) for the shader's declaration to type.
    ParamList take_params(const Statement& s, std::size_t i, bool single,
                          bool shader = false);

    // --- rib_archives.cpp: files, frames and archives -------------------------

    void run_text(std::string_view text, std::shared_ptr<const std::string> path);
    void run_file(const Statement& from, const std::string& path);
    /// Option "searchpath": each kind's folders, "&" expanded.
    void set_search_paths(const Statement& s, const ParamList& params);
    /// An archive's file: absolute as it is, else found along the archive
    /// (or procedural) search path, else relative to the folder of the file
    /// that names it; an error naming the search path when none exists.
    std::string resolve_path(const Statement& s, const std::string& name,
                             const char* kind = "archive");
    /// One more level of archives is within Limit::ArchiveDepth.
    void check_archive_depth(const Statement& from, const std::string& name);
    void read_archive(const Statement& s, const std::string& name);
    /// Stores an inline archive and how many statements reading it replays.
    void define_archive(const std::string& name, std::vector<Statement> body);
    /// The mesh of an OBJ file, as a primitive under the current state.
    void add_obj(const std::string& text, const std::string& path);
    void do_frame_begin(const Statement& s);
    void do_frame_end(const Statement& s);
    void do_archive_begin(const Statement& s);
    void do_archive_end(const Statement& s);
    void do_read_archive(const Statement& s);
    void do_procedural(const Statement& s);
    /// Procedural "RunProgram": runs the program and reads the RIB it answers.
    void run_program(const Statement& s, const std::string& command,
                     const std::string& data, const std::vector<double>& bound);
    /// Procedural "DynamicLoad": loads the DSO (once per read), converts its
    /// parameter string and runs its Subdivide, whose Ri calls are carried
    /// out as they come (rib_dynamic_load.cpp).
    void dynamic_load(const Statement& s, const std::string& dso, const std::string& data,
                      const std::vector<double>& bound);
    /// The raster area a bound (current object space) covers: the detail
    /// a procedural is asked for.
    double raster_area(const std::vector<double>& bound) const;

    // --- rib_state.cpp: graphics state, blocks and transforms -----------------

    Attributes& attrs_mut();
    std::shared_ptr<const Attributes> snapshot();
    void push(const Statement& s, Block block);
    SavedState pop(const Statement& s, Block block);
    void restore_all(SavedState& saved);
    /// CTM = CTM * m: the new transform applies to points first.
    void concat(const Matrix4& m);
    /// True when the current space is left-handed (camera space is).
    bool current_left_handed() const;
    void do_world_begin(const Statement& s);
    void do_world_end(const Statement& s);
    void do_attribute_begin(const Statement& s);
    void do_attribute_end(const Statement& s);
    void do_transform_begin(const Statement& s);
    void do_transform_end(const Statement& s);
    void do_solid_begin(const Statement& s);
    void do_solid_end(const Statement& s);
    void do_object_begin(const Statement& s);
    void do_object_end(const Statement& s);
    void do_object_instance(const Statement& s);
    void do_identity(const Statement& s);
    void do_transform(const Statement& s);
    void do_concat_transform(const Statement& s);
    void do_translate(const Statement& s);
    void do_rotate(const Statement& s);
    void do_scale(const Statement& s);
    void do_skew(const Statement& s);
    void do_perspective(const Statement& s);
    void do_coordinate_system(const Statement& s);
    void do_coord_sys_transform(const Statement& s);

    /// Sets the CTM; it no longer moves.
    void set_ctm(const Matrix4& m) {
        m_ctm = m;
        m_ctm_motion = {};
    }
    void restore_ctm(const SavedState& saved) {
        m_ctm = saved.ctm;
        m_ctm_motion = saved.ctm_motion;
    }

    // --- rib_motion.cpp: motion blocks and the shutter --------------------------

    void do_shutter(const Statement& s);
    void do_motion_begin(const Statement& s);
    void do_motion_end(const Statement& s);
    /// A request inside a motion block, before its handler: true when it
    /// is not executed (a later sample of a request that cannot move).
    bool motion_statement(const Statement& s);
    /// The same request after its handler ran.
    void after_motion_statement(const Statement& s);
    /// The transform (and transform motion) of a primitive made now:
    /// CTM x object_to_ctm, or the CTM's motion composed with the
    /// primitive's own (ObjectInstance of a moving object).
    void place(Primitive& p, const Matrix4& object_to_ctm) const;

    // --- rib_options.cpp: options, camera and declarations --------------------

    /// Options are frozen inside the world block: such requests only warn.
    bool option_allowed(const Statement& s);
    void do_format(const Statement& s);
    void do_frame_aspect(const Statement& s);
    void do_screen_window(const Statement& s);
    void do_crop_window(const Statement& s);
    void do_projection(const Statement& s);
    void do_clipping(const Statement& s);
    void do_pixel_samples(const Statement& s);
    void do_display(const Statement& s);
    void do_display_channel(const Statement& s);
    void do_hider(const Statement& s);
    void do_option(const Statement& s);
    void do_color_samples(const Statement& s);
    void do_declare(const Statement& s);
    void do_depth_of_field(const Statement& s);
    void do_pixel_filter(const Statement& s);
    void do_exposure(const Statement& s);
    void do_quantize(const Statement& s);
    void do_imager(const Statement& s);

    // --- rib_attributes.cpp: attributes, shaders and lights -------------------

    /// A shader call with its space; before WorldBegin the space is camera-relative
    /// and is converted at WorldBegin.
    ShaderRef make_shader(const Statement& s, const std::string& name, ParamList params);
    void set_light(int index, bool on);
    void do_attribute(const Statement& s);
    void do_color(const Statement& s);
    void do_opacity(const Statement& s);
    void do_sides(const Statement& s);
    void do_orientation(const Statement& s);
    void do_reverse_orientation(const Statement& s);
    void do_shading_rate(const Statement& s);
    void do_shading_interpolation(const Statement& s);
    void do_surface(const Statement& s);
    void do_coshader(const Statement& s);
    void do_displacement(const Statement& s);
    /// Atmosphere, Interior and Exterior: a volume shader of the attributes.
    void do_volume_shader(const Statement& s);
    void do_light_source(const Statement& s);
    void do_illuminate(const Statement& s);
    void do_basis(const Statement& s);

    // --- rib_geometry.cpp: primitives ------------------------------------------

    /// Stores a primitive under the current transform and attributes (or in
    /// the object being defined).
    void add_primitive(const Statement& s, Primitive p, const Matrix4& object_to_ctm,
                       const std::string& source);
    void add_primitive(const Statement& s, Primitive p);
    /// Keeps a placed primitive (in the object being defined, or the scene).
    void store_primitive(Primitive p);
    /// Makes "P" the position parameter (from Pw or, for patches, Pz) and
    /// checks it holds `n_points` points.
    void resolve_positions(const Statement& s, ParamList& params, std::size_t n_points,
                           int grid_nu = 0, int grid_nv = 0, bool uwrap = false,
                           bool vwrap = false);
    void do_polygon(const Statement& s);
    void do_general_polygon(const Statement& s);
    void do_points_polygons(const Statement& s);
    void do_points_general_polygons(const Statement& s);
    void do_subdivision_mesh(const Statement& s);
    /// HierarchicalSubdivisionMesh's tags (3 argument counts each, string
    /// arguments) as SubdivisionMesh's; its edits are not implemented.
    void hierarchical_tags(const Statement& s, Primitive& p,
                           const std::vector<std::string>& string_args);
    /// Keeps the tags the dicer carries out or that change nothing it
    /// computes; any other is not implemented (read leniently: left out).
    void check_subdivision_tags(const Statement& s, Primitive& p);
    void do_quadric(const Statement& s);
    void do_patch(const Statement& s);
    void do_patch_mesh(const Statement& s);
    void do_geometry(const Statement& s);
    void do_points(const Statement& s);
    void do_curves(const Statement& s);
    void do_nupatch(const Statement& s);
    void do_blobby(const Statement& s);
    /// Blobby field plugins (1004) are not implemented: an error, or when
    /// reading leniently a warning and each made the constant field 0 (p's
    /// code rewritten).
    void lenient_blobby_fields(const Statement& s, Primitive& p,
                               const BlobbyProgram& program);
    void do_make_texture(const Statement& s);
    void do_make_shadow(const Statement& s);
    void do_make_cube_face_environment(const Statement& s);
    /// Files a Make request with the frame it belongs to (MakeRequest).
    void add_make(MakeRequest m);
    void do_trim_curve(const Statement& s);

    // --- state -----------------------------------------------------------------

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
    int m_depth = 0;          // archives being read (files and inline archives)
    uint64_t m_max_depth = 0; // limit(Limit::ArchiveDepth), once read
    /// Files being read through ReadArchive: (file_key, path as named).
    std::vector<std::pair<std::string, std::string>> m_reading;
    uint64_t m_replayed = 0; // statements replayed from inline archives
    uint64_t m_next_replay_check = 1'000'000;
    // frames
    bool m_in_frame = false;
    bool m_frame_read = false;
    bool m_frames_seen = false;
    bool m_skipping = false;
    /// Between the FrameEnd of the frame read and the next FrameBegin:
    /// Make requests there run after the frame.
    bool m_after_read_frame = false;
    /// Make requests outside frames before any frame was read: the frame
    /// that follows them takes them (or, without frames, the scene).
    std::vector<MakeRequest> m_pending_makes;
    int m_skip_line = 0;
    std::shared_ptr<const std::string> m_skip_file;
    // motion blocks
    enum class MotionKind { Transform, Geometry, Other };
    CtmMotion m_ctm_motion;
    bool m_in_motion = false;
    std::vector<double> m_motion_times;
    std::size_t m_motion_count = 0; // requests of the block so far
    std::string m_motion_request;   // its first request
    MotionKind m_motion_kind = MotionKind::Other;
    Matrix4 m_motion_base{1.0}; // the CTM at MotionBegin
    CtmMotion m_motion_base_motion;
    std::vector<Matrix4> m_motion_ctms;                 // per time: the CTM made
    std::vector<std::vector<Primitive>> m_motion_prims; // per time: the primitives made
    bool m_motion_capture = false;
    // lights and objects
    std::unordered_map<std::string, int> m_light_handles;
    std::unordered_map<std::string, std::vector<Primitive>> m_objects;
    // Memory of the primitives ObjectInstance and inline archives copied,
    // checked against the budget every kMemoryCheckStep bytes.
    static constexpr uint64_t kMemoryCheckStep = 64u << 20;
    uint64_t m_copied_bytes = 0;
    uint64_t m_copied_primitives = 0;
    uint64_t m_next_memory_check = kMemoryCheckStep;
    std::vector<Primitive>* m_object = nullptr;
    std::string m_object_handle;
    // inline archives
    /// Shared: a replay keeps its body while the archive is redefined.
    struct InlineArchive {
        std::shared_ptr<const std::vector<Statement>> body;
        /// Statements a ReadArchive of it replays, the inline archives it
        /// reads included (as defined when it was; saturated).
        uint64_t replays = 0;
    };
    std::unordered_map<std::string, InlineArchive> m_archives;
    bool m_recording = false;
    int m_record_depth = 0;
    std::string m_record_name;
    int m_record_line = 0;
    std::shared_ptr<const std::string> m_record_file;
    std::vector<Statement> m_record;
    // DynamicLoad: the DSOs loaded (by file key; closed with the reader) and
    // the Ri calls' context.
    std::map<std::string, std::shared_ptr<void>> m_dsos;
    std::unique_ptr<RiContext> m_ri;
};

} // namespace sss::rib

// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the data structures of the execution
// engine (engine.h) shared by its implementation files.
//
//  - BoundProgram: a Program's ops, each bound at ShaderInstance
//    construction to a function chosen by op name and argument types
//    (engine_bind.cpp, and the register_* tables of the engine_*.cpp files).
//  - Frame: one shader's storage over a batch (SoA per symbol: a uniform
//    symbol holds one value, a varying one a value per point, values stored
//    point after point), its running mask and per-point stop codes
//    (break / continue / return), engine.cpp.
//  - ShadingContext::Impl: one thread's state: the string table, the frames
//    of the surface and of each light, the light caches.
//
// Values: floats; a string is an index into the context's string table
// (stored as a float); a matrix is 16 floats in RenderMan's row-major order,
// which is glm's column-major order of our column-vector matrices (scene.h):
// the RSL product A*B is glm B*A.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "sss/rsl/program.h"
#include "sss/shading/engine.h"

namespace sss::detail {

/// The global variables the engine binds by name.
enum Global : int {
    G_P,
    G_N,
    G_Ng,
    G_I,
    G_E,
    G_dPdu,
    G_dPdv,
    G_Cs,
    G_Os,
    G_u,
    G_v,
    G_du,
    G_dv,
    G_s,
    G_t,
    G_Ci,
    G_Oi,
    G_L,
    G_Cl,
    G_Ol,
    G_Ps,
    G_ncomps,
    G_time,
    G_dtime,
    G_dPdtime,
    G_alpha,
    G_count
};
/// RSL name of a global.
const char* global_name(int g);

struct Frame;
struct BoundOp;
struct Slot;
using OpFn = void (*)(Frame&, const BoundOp&);

/// The kinds of the control-flow ops: set by bind_program, run by Frame::run.
enum Control : int {
    C_None = 0,
    C_If,
    C_Loop,
    C_Break,
    C_Continue,
    C_Block,
    C_Return,
    C_Illuminance,
    C_Illuminate,
    C_Solar,
    C_Gather
};

/// One op bound to its implementation, with what the binder chose.
struct BoundOp {
    OpFn fn = nullptr;
    const Op* op = nullptr;             ///< in the Program (kept alive by BoundProgram)
    int index = 0;                      ///< op index
    int ia = 0, ib = 0, ic = 0, id = 0; ///< variant data of the binder
};

/// A Program with every op bound.
struct BoundProgram {
    std::shared_ptr<const Program> program;
    std::vector<BoundOp> ops;
    int globals[G_count];        ///< symbol index of each global, or -1
    bool has_illuminate = false; ///< a light with illuminate or solar
    std::vector<int> params;     ///< parameter symbols, in declaration order

    /// "file:line" of op `index` (or the program's source path).
    std::string where(int index) const;
    /// "shader 'name' (file:line)" for messages about op `index`.
    std::string describe(int index) const;
};

/// Binds and validates; throws ValueError.
std::shared_ptr<const BoundProgram> bind_program(std::shared_ptr<const Program> program);

/// What a binder sees of an op.
struct BindInfo {
    const Program& program;
    const Op& op;
    int nargs() const { return static_cast<int>(op.args.size()); }
    const Symbol& sym(int k) const { return program.symbols[op.args[k]]; }
    ShadingType type(int k) const { return sym(k).type.type; }
    bool is_array(int k) const { return sym(k).type.is_array(); }
    int floats(int k) const { return sym(k).type.floats(); }
    bool varying(int k) const { return sym(k).varying; }
    bool is(int k, ShadingType t) const { return !is_array(k) && type(k) == t; }
    bool is_float(int k) const { return is(k, ShadingType::Float); }
    bool is_string(int k) const { return is(k, ShadingType::String); }
    bool is_color(int k) const { return is(k, ShadingType::Color); }
    bool is_matrix(int k) const { return is(k, ShadingType::Matrix); }
    bool is_ptype(int k) const { return !is_array(k) && is_point_like(type(k)); }
    bool is_triple_(int k) const { return !is_array(k) && is_triple(type(k)); }
    /// A scalar float or a triple (1 or 3 floats, not an array).
    bool is_f_or_triple(int k) const { return is_float(k) || is_triple_(k); }
    bool writes(int k) const { return (op.writes >> k) & 1u; }
};
/// Chooses the implementation: returns false (with `why` when the reason is
/// more than "no overload") if the op's arguments fit none.
using Binder = bool (*)(const BindInfo&, BoundOp&, std::string& why);
using BinderTable = std::unordered_map<std::string, Binder>;

void register_core_ops(BinderTable& t); // engine_ops.cpp
void register_math(BinderTable& t);     // engine_math.cpp
void register_geometry(BinderTable& t); // engine_geometry.cpp
void register_lighting(BinderTable& t); // engine_lighting.cpp
void register_texture(BinderTable& t);  // engine_texture.cpp
void register_raytrace(BinderTable& t); // engine_raytrace.cpp
void register_arrays(BinderTable& t);   // engine_arrays.cpp
void register_coshader(BinderTable& t); // engine_coshader.cpp
/// aref and aassign of a resizable array (engine_arrays.cpp): b.ia = the
/// floats per element; the length is the array's at run time.
void op_aref_resizable(Frame& f, const BoundOp& b);
void op_aassign_resizable(Frame& f, const BoundOp& b);
/// Empties the resizable arrays of a frame (a new batch).
void reset_resizable(Frame& f);
/// Sets the length of the resizable array in slot s (ef floats per element;
/// first elements kept, new ones 0); errors name op b of frame f and `what`.
void resize_array(Frame& f, const BoundOp& b, Slot& s, int ef, double length,
                  const char* what);
/// The current length of the resizable array in slot s.
int resizable_length(const Frame& f, const Slot& s);
/// environment("raytrace", ...) (engine_raytrace.cpp; engine_texture.cpp
/// routes the name "raytrace" to it).
void environment_raytrace(Frame& f, const BoundOp& b);
/// shadow(map[ch], P, options) on a depth map (engine_texture.cpp): the
/// non-"raytrace", non-empty names of op_shadow (engine_raytrace.cpp).
void shadow_map_lookup(Frame& f, const BoundOp& b);

/// One symbol's storage in a frame.
struct Slot {
    float* p = nullptr;
    int nf = 0;     ///< floats per value (elements included)
    int stride = 0; ///< nf when varying (a resizable array's capacity), 0 when uniform
    bool varying = false;
    int resizable = -1; ///< a resizable array: its index in Frame::resizable
    float* at(std::size_t i) const { return p + i * static_cast<std::size_t>(stride); }
};

/// The storage of a resizable array (engine_arrays.cpp): `length` elements
/// per value, in blocks of `capacity` elements (a varying array's values are
/// Slot::stride = capacity * element floats apart). The length is one for
/// the whole batch.
struct ResizableArray {
    std::vector<float> data;
    int length = 0;
    int capacity = 0;
};

/// The storage of a resizable array may use at most this many floats over
/// the batch (1 GiB).
constexpr std::size_t kMaxResizableFloats = std::size_t(1) << 28;

/// Per-point stop codes (why a point stopped running): 0 runs; otherwise the
/// low two bits give the kind and the rest the depth of the construct.
enum StopKind : uint32_t { StopReturn = 1, StopBreak = 2, StopContinue = 3 };
/// Depth 0 of StopReturn = the shader's own return.

/// One shader's execution over a batch.
struct Frame {
    ShadingContext::Impl* ctx = nullptr;
    const ShaderInstance* instance = nullptr;
    const BoundProgram* bound = nullptr;
    const Program* program = nullptr;
    std::size_t n = 0;
    bool is_light = false;
    /// What the shader runs as: its kind, or for a class one of its
    /// pipelines (a class's displacement method at displacement time).
    ShaderKind kind = ShaderKind::Surface;

    std::vector<float> arena;
    std::vector<Slot> slots;
    std::vector<ResizableArray> resizable; ///< Slot::resizable indexes it

    // Running mask.
    std::vector<uint8_t> mask;
    std::size_t active = 0;
    std::vector<uint32_t> stop;
    int loop_depth = 0;                         ///< enclosing loops (illuminance is none)
    int block_depth = 0;                        ///< enclosing blocks
    std::deque<std::vector<uint8_t>> mask_pool; ///< stable references
    int mask_depth = 0;
    std::vector<uint32_t> calls; ///< per op: how many times it ran (random)

    // Spaces of this frame.
    glm::dmat4 shader_to_current{1.0};

    // Light frames: the illuminate/solar state.
    std::vector<uint8_t> lit;
    std::vector<glm::vec3> light_L;  ///< L as illuminate / solar set it
    std::vector<glm::vec3> light_Ps; ///< the surface points being lit
    /// The cone the surface asked about (illuminance's axis and angle, or N
    /// and PI/2 for diffuse()...): illuminate/solar skip points whose light
    /// falls outside it, since the surface would not use them (and their
    /// shadow rays are the bulk of the work). Null axis: every direction.
    const float* request_axis = nullptr;
    int request_axis_stride = 0;
    float request_angle = 4.0f;
    bool in_illuminate = false;
    bool solar = false;

    // Surface frames: the light of the running illuminance iteration.
    int current_light = -1;

    Slot& slot(const BoundOp& b, int k) { return slots[b.op->args[k]]; }
    float* ptr(const BoundOp& b, int k, std::size_t i) { return slot(b, k).at(i); }
    /// The string value of (uniform) argument k at point i.
    const std::string& str(const BoundOp& b, int k, std::size_t i = 0);
    /// Index of the first running point, or n.
    std::size_t first_active() const;
    void recount();
    bool all_on() const { return active == n; }
    /// Runs fn(i) for every running point when `varying`, else once for the
    /// first running point (uniform results: written if any point runs).
    template <class F>
    void each(bool varying, F&& fn) {
        if (active == 0) return;
        if (!varying) {
            fn(first_active());
            return;
        }
        if (active == n) {
            for (std::size_t i = 0; i < n; ++i) fn(i);
        } else {
            for (std::size_t i = 0; i < n; ++i)
                if (mask[i]) fn(i);
        }
    }
    /// Runs ops [begin, end) under the running mask.
    void run(int begin, int end);
    std::vector<uint8_t>& push_mask();
    /// mask = entry && not stopped (after a construct's body), and recount.
    void restore_mask(const std::vector<uint8_t>& entry);
    void pop_mask() { --mask_depth; }
    /// Whether op `b`'s results vary (any written argument, or the result).
    bool writes_varying(const BoundOp& b) const;

    std::string where(const BoundOp& b) const { return bound->where(b.index); }
    [[noreturn]] void fail(const BoundOp& b, const std::string& what) const;
    /// The string table index of `s`, a string op b made: fails when s is
    /// longer than the batch's string limit (SHADER_STRING_LENGTH), checks
    /// the memory budget as the table grows.
    float intern(const BoundOp& b, const std::string& s);
    /// Fails unless a string of `length` bytes fits the string limit.
    void check_string_length(const BoundOp& b, uint64_t length) const;
    /// Consults the memory budget for `bytes` more that op b allocates.
    void check_memory_for(const BoundOp& b, uint64_t bytes,
                          const std::string& what) const;
    /// A warning given once per job.
    void warn_once(const BoundOp& b, const std::string& what) const;
};

/// The matrix from the named space to "current". An unknown name acts, as
/// in PRMan, as "current", with a warning naming the call (once per call).
glm::dmat4 named_space_to_current(Frame& f, const BoundOp& b, const std::string& space);

/// Cached results of one light for a batch.
struct LightState {
    const ShaderInstance* instance = nullptr;
    std::unique_ptr<Frame> frame;
    bool valid = false;
    std::vector<uint8_t> computed;
    std::vector<glm::vec3> Ps, L, Cl, Ol;
    /// The surface N the cache was computed for (the light's N global).
    std::vector<glm::vec3> N;
    std::vector<uint8_t> lit;
    /// The request cone the cache was computed for (see Frame::request_axis).
    std::vector<glm::vec3> request_axis;
    float request_angle = 4.0f;
    bool request_all = true;
    bool ambient = false;
    bool nondiffuse = false, nonspecular = false;
    std::vector<std::string> categories;
    bool described = false;
};

/// A shader object a shader holds a handle to (RSL 2.0 `shader` values): a
/// co-shader of the batch (`Shader` in the RIB) or one of its lights. The
/// handle value k names ShadingContext::Impl::objects[k - 1]; 0 is null.
struct ShaderObject {
    const ShaderInstance* instance = nullptr;
    int light = -1; ///< index into the batch's lights, or -1 for a co-shader
    /// A co-shader's storage over the batch, set up (parameters, member
    /// variables, construct() and begin()) when a method or getvar first
    /// needs it, and kept for the batch: member variables keep their values
    /// from one call to the next.
    std::unique_ptr<Frame> frame;
    bool busy = false; ///< running one of its methods
};

/// A "send:light:NAME" option of a running illuminance: light shaders run
/// with their parameter NAME set to `value` (a slot of the surface frame).
struct LightSend {
    std::string name;
    const Slot* value = nullptr;
    ShadingType type = ShadingType::Float;
};

/// Copies the parameter (or output parameter) `name` of frame `from` into
/// argument k of op b at the running points of f, when `from` has one of a
/// fitting type (point, vector and normal fit each other; no arrays): the
/// message-passing functions and illuminance's "light:NAME" (engine_lighting.cpp).
/// The element index of array access at point i (the index rounded down),
/// checked against the array's length: an error naming the shader's line.
inline int array_element(Frame& f, const BoundOp& b, const Slot& idx, std::size_t i,
                         int length) {
    const float v = *idx.at(i);
    const float fl = std::floor(v);
    if (!(fl >= 0.0f) || fl >= static_cast<float>(length))
        f.fail(b, "array index " + std::to_string(v) + " out of range [0, " +
                      std::to_string(length) + ")");
    return static_cast<int>(fl);
}

bool copy_parameter(Frame& f, const BoundOp& b, int k, const Frame& from,
                    const std::string& name);

/// Whether a shader of categories `shader` (its `__category`, split) is
/// selected by the category expression `cat` (comma-separated names, each
/// required, any of them; a leading '-' excludes): illuminance, getlights,
/// getshaders (engine_lighting.cpp).
bool category_matches(const std::string& cat, const std::vector<std::string>& shader);

} // namespace sss::detail

namespace sss {

struct ShadingResources::Impl {
    Impl();
    ~Impl();
    mutable std::mutex warned_mutex;
    mutable std::set<std::string> warned;
    /// True the first time `text` is seen.
    bool first_time(const std::string& text) const;

    // The job's bake3d budget (every thread's batches): points and bytes
    // handed over so far, and the files named.
    std::mutex bake3d_mutex;
    uint64_t bake3d_points = 0;
    uint64_t bake3d_bytes = 0;
    uint64_t bake3d_checked_bytes = 0; ///< bytes at the last memory check
    std::set<std::string> bake3d_files;
};

namespace detail {
/// The memory budget (check_memory) is consulted each time the shader
/// allocations of a batch or a job grow by this much.
constexpr uint64_t kShaderMemoryStep = uint64_t(64) << 20;
} // namespace detail

struct ShadingContext::Impl {
    Impl(const ShadingResources& r, ShadingServices& s) : resources(r), services(s) {}
    const ShadingResources& resources;
    ShadingServices& services;

    // String table: index 0 is "".
    std::vector<std::string> strings;
    std::unordered_map<std::string, int> string_index;
    float intern(const std::string& s);
    void reset_strings();
    /// Bytes of the batch's string table, and at its last memory check.
    uint64_t string_bytes = 0, string_checked_bytes = 0;

    // The batch's budgets (docs/limits.md), read at each execute.
    /// Ops and loop iterations run in this batch (lights and co-shaders
    /// included) and the most allowed: Frame::run counts them.
    uint64_t ops = 0, ops_limit = 0;
    uint64_t string_limit = 0; ///< bytes of one string
    uint64_t array_limit = 0;  ///< elements of one resizable array

    ShadingBatch* batch = nullptr;
    LightList lights;
    CoshaderList coshaders;
    /// The shader objects handed out in this execute (engine_coshader.cpp);
    /// a deque: a method running may hand out more while its own is in use.
    std::deque<detail::ShaderObject> objects;
    detail::Frame main;
    std::vector<detail::LightState> light_states;
    /// The running illuminance's "send:light:" options (light() applies them).
    std::vector<detail::LightSend> light_sends;
    int depth = 0; ///< nested executions (lights inside a surface)
    /// Storage of parameters a varying primitive variable made varying.
    std::vector<std::vector<float>> extra_storage;

    // Spaces (per batch).
    glm::dmat4 world_to_camera{1.0}, camera_to_world{1.0};
    glm::dmat4 object_to_current{1.0};

    // Results of the last execute.
    /// Keeps the last program alive for output() after its ShaderInstance
    /// is gone (main.program points into it).
    std::shared_ptr<const Program> last_program;
    std::size_t nonfinite = 0;
    /// Shadow and occlusion rays traced, over every execute (never reset).
    mutable uint64_t rays = 0;
    std::string last_shader, last_where;

    /// Prepares `frame` for `instance` over n points (storage, constants,
    /// globals from `batch` for surfaces; lights leave globals to the caller
    /// then call init_params).
    void setup_frame(detail::Frame& frame, const ShaderInstance& instance, std::size_t n);
    void load_surface_globals(detail::Frame& frame);
    void init_params(detail::Frame& frame, bool primvars);
    /// Runs the body over the running mask already set: a classic shader's
    /// body, or a class's member initialisers and the methods of its
    /// pipeline for frame.kind.
    void run_body(detail::Frame& frame);

    /// The light results for point positions P (stride 0 or 3) under `mask`
    /// (null: all points): runs the light if the cache does not cover them.
    /// Light `index`'s description (ambient, categories, flags), filled once.
    detail::LightState& describe_light(int index);
    /// Light `index` evaluated for the points of `mask` at surface P, for a
    /// surface that uses only light arriving within `angle` of `axis` (per
    /// point, stride floats apart; null axis: from everywhere). Cached.
    detail::LightState& light(int index, const float* P, int P_stride,
                              const std::vector<uint8_t>& mask, std::size_t active,
                              const float* axis = nullptr, int axis_stride = 0,
                              float angle = 4.0f);
    /// Space name -> matrix to the current space (points), false if unknown.
    bool space_to_current(const std::string& space, const detail::Frame& f,
                          glm::dmat4& m) const;
};

} // namespace sss

namespace sss::detail {

inline const std::string& Frame::str(const BoundOp& b, int k, std::size_t i) {
    const float v = *ptr(b, k, i);
    const std::size_t idx = v >= 0.0f ? static_cast<std::size_t>(v) : 0u;
    return idx < ctx->strings.size() ? ctx->strings[idx] : ctx->strings[0];
}

// --- small vector helpers over float storage ----------------------------
inline glm::vec3 ld3(const float* p) {
    return glm::vec3(p[0], p[1], p[2]);
}
inline void st3(float* p, const glm::vec3& v) {
    p[0] = v.x;
    p[1] = v.y;
    p[2] = v.z;
}
inline glm::dmat4 ldm(const float* p) {
    glm::dmat4 m;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m[c][r] = p[c * 4 + r];
    return m;
}
inline void stm(float* p, const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) p[c * 4 + r] = static_cast<float>(m[c][r]);
}
/// Points through a projective matrix (divided by w when w != 1).
glm::vec3 xform_point(const glm::dmat4& m, const glm::vec3& p);
glm::vec3 xform_vector(const glm::dmat4& m, const glm::vec3& v);
/// Normals: the inverse transpose of m's 3x3 part.
glm::vec3 xform_normal(const glm::dmat4& m, const glm::vec3& n);
/// Converts a value of type t (point/vector/normal) by m (space -> current).
glm::vec3 xform_typed(ShadingType t, const glm::dmat4& m, const glm::vec3& v);

/// Derivative of argument k of `b` along u (dir 0) or v (dir 1), in units of
/// the parameter (divided by du / dv), for `comps` floats per point, into out
/// (n * comps floats). `name` is the symbol's name (Points layout).
void derivative(Frame& f, const Slot& x, int comps, int dir, const std::string& name,
                float* out);

/// A token-value option list starting at argument `first`: calls
/// fn(name, slot k) for each pair.
template <class F>
void for_options(Frame& f, const BoundOp& b, int first, F&& fn) {
    const int n = static_cast<int>(b.op->args.size());
    for (int k = first; k + 1 < n; k += 2) fn(f.str(b, k), k + 1);
}

/// Hash for per-point random numbers.
uint64_t point_hash(uint64_t seed, std::size_t point, int op, uint32_t call);

} // namespace sss::detail

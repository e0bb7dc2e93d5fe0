// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file engine.h
/// Module shading: the engine that runs compiled shaders (module rsl) over
/// batches of shading points, its ops and the shading language's function
/// library (noise, strings, colour spaces). The engine reaches the renderer
/// only through ShadingServices (below): the scene, rays, textures
/// (TextureServices, texture_services.h) and bake3d's records. The
/// renderers' side, the scene's shaders bound for a job, the texture
/// library and bake3d's files, is module binding.
/// May use: rsl, light, scene and util.
///
/// The shading engine: runs compiled shaders (program.h) SIMD-style over a
/// batch of shading points (a diced grid in ptbake, a batch of ray hits in
/// render) with a running mask for varying control flow, as REYES renderers
/// run shaders on grids. Shared by ptbake and render.
///
/// Spaces: "current" is camera space (RenderMan's convention, shading.md
/// section 4): every point, vector and normal of a batch is in camera space,
/// and the eye E is the origin. Named spaces: "current"/"camera", "world",
/// "object" (the batch's primitive; world without one), "shader" (the
/// instance's), "screen", "raster", "NDC" (from the scene's camera) and the
/// scene's CoordinateSystem names; an unknown name is a ShaderRuntimeError.
///
/// What the engine implements (details in src/sss/shading/engine*.cpp):
///  - every op of program.h and every overload of builtins.cpp (a program
///    using anything else is refused when its ShaderInstance is built);
///  - structured control flow under a running mask (if, loops, break and
///    continue n, returns from inlined functions and from the shader), with
///    uniform stores written when any point runs;
///  - lights run lazily per batch (illuminate/solar/ambient lights,
///    categories, __nondiffuse/__nonspecular);
///  - the ray-tracing shadeops (engine_raytrace.cpp, docs/shading.md "Ray
///    tracing"): gather, trace(), environment("raytrace"), occlusion() and
///    indirectdiffuse() through ShadingServices::trace; shadow("raytrace")
///    and transmission() through ShadingServices::transmit. Every ray carries
///    depth = ShadingBatch::ray.depth + 1;
///  - texture/environment/textureinfo/texture3d and depth-map shadow()
///    through ShadingServices::textures(), bake3d records handed to
///    ShadingServices::bake3d;
///  - attribute/option/rendererinfo/rayinfo queries.
///  - message passing: lightsource() inside illuminance (and its
///    "light:NAME" options), surface() in light shaders;
///  - resizable arrays (engine_arrays.cpp);
///  - RSL 2.0 class shaders: the member initialisers and the methods of the
///    pipeline of the kind the shader runs as (execute_as), and co-shaders:
///    `shader` handles, method calls, getvar (engine_coshader.cpp).
/// Not supported (they run and return 0, warned once where it matters):
/// displacement() and atmosphere() message passing,
/// gather's "primitive:" outputs (a compile error).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "sss/light/ray_tracer.h"
#include "sss/rsl/program.h"
#include "sss/scene/scene.h"
#include "sss/shading/texture_services.h"
#include "sss/util/error.h"

namespace sss {

namespace detail {
struct BoundProgram; // engine_internal.h: a Program's ops bound to implementations
}

/// A shader failed at run time in a way it cannot recover from (array
/// index out of range, a light shader that does not exist...). The message
/// names the shader's file:line.
class ShaderRuntimeError : public ValueError {
public:
    using ValueError::ValueError;
};

/// One parameter value given to a shader (a RIB Surface/LightSource call's
/// "name" value pair, or a primitive variable of the same name).
struct ShaderArgument {
    std::string name;
    TypeSpec type;                    ///< as declared in the RIB
    bool varying = false;             ///< one value per point of the batch
    std::vector<float> numbers;       ///< floats, in the RIB's order
    std::vector<std::string> strings; ///< strings
};

/// A compiled shader bound to the parameter values of one call, with the
/// "shader" space (the CTM at the call).
///
/// Construction also binds every op of the program to its implementation
/// (by op name and the types and storage of its arguments) and validates the
/// program (symbol indices, control-flow ranges, constants): a program using
/// a function or an overload the engine does not implement is refused here
/// with a ValueError naming the function and the shader's file:line.
class ShaderInstance {
public:
    /// Binds `params` to the program's parameters. Throws ValueError naming
    /// `where` for a parameter of the wrong type or size; parameters the
    /// shader does not declare are reported through `warnings` (PRMan warns
    /// and ignores them).
    ///
    /// A RIB value fits a parameter when the types agree (point, vector and
    /// normal are interchangeable; "float" numbers fit any type when their
    /// count is right; "integer" is a float) and it has as many elements as
    /// the parameter (1 for a non-array). Points, vectors and normals are
    /// kept in shader space and converted to the current (camera) space when
    /// the shader runs (points affinely, vectors without translation,
    /// normals by the inverse transpose); colours are taken as they are.
    ShaderInstance(std::shared_ptr<const Program> program, const ParamList& params,
                   const Matrix4& shader_to_world, std::string where,
                   std::vector<std::string>* warnings = nullptr);

    const Program& program() const { return *m_program; }
    const std::shared_ptr<const Program>& program_ptr() const { return m_program; }
    const Matrix4& shader_to_world() const { return m_shader_to_world; }
    const std::string& where() const { return m_where; }
    /// The bound values (uniform, in the RIB's space: points in shader space).
    const std::vector<ShaderArgument>& arguments() const { return m_arguments; }
    /// The bound value of the program's symbol `symbol` (a parameter), or
    /// null when the call gives none: names are matched once, at binding.
    const ShaderArgument* argument_of(int symbol) const {
        const int a = symbol >= 0 && std::size_t(symbol) < m_argument_of.size()
                          ? m_argument_of[std::size_t(symbol)]
                          : -1;
        return a < 0 ? nullptr : &m_arguments[std::size_t(a)];
    }
    /// A uniform parameter's value as bound or defaulted, when it is a
    /// constant (for the renderer: light categories, file names...).
    std::optional<std::string> string_parameter(const std::string& name) const;
    std::optional<float> float_parameter(const std::string& name) const;
    /// The program's ops bound to implementations (engine internal).
    const detail::BoundProgram& bound() const { return *m_bound; }
    /// The RIB handle of a co-shader (`Shader "name" "handle"`) or a light
    /// (`LightSource "name" "handle"`): what getshader() and getlight() look
    /// for. Empty for other shaders.
    const std::string& handle() const { return m_handle; }
    void set_handle(std::string handle) { m_handle = std::move(handle); }

private:
    std::shared_ptr<const Program> m_program;
    std::shared_ptr<const detail::BoundProgram> m_bound;
    Matrix4 m_shader_to_world{1.0};
    std::string m_where;
    std::string m_handle;
    std::vector<ShaderArgument> m_arguments;
    std::vector<int> m_argument_of; ///< per symbol: its index in m_arguments, or -1
};

/// What kind of ray a shader traces: the `Attribute "visibility"` name that
/// decides which objects it sees, and the `Attribute "trace"` depth limit
/// that applies (maxdiffusedepth, maxspeculardepth).
///  - Camera: primary rays (render only).
///  - Diffuse: occlusion(), indirectdiffuse(), gather(... "distribution"
///    "cosine"), gather("environment", ...).
///  - Specular: trace(), environment("raytrace", ...), gather() with the
///    default "uniform" distribution.
///  - Transmission: shadow("raytrace", ...), transmission().
enum class RayKind : uint8_t { Camera, Diffuse, Specular, Transmission };
/// "camera", "diffuse", "specular", "transmission" (rayinfo("type")).
const char* ray_kind_name(RayKind kind);

/// How the point being shaded was reached: set by the renderer on every
/// batch (camera hits and ptbake grids: depth 0, kind Camera, label "").
struct RayContext {
    int depth = 0;                  ///< rayinfo("depth")
    RayKind kind = RayKind::Camera; ///< rayinfo("type")
    std::string label;              ///< rayinfo("label"): the label of the ray that hit
};

/// How the points of a batch are related, for derivatives (Du, Dv, area,
/// calculatenormal, texture filter widths).
enum class BatchLayout {
    /// nu x nv points of a grid, u fastest: centred differences inside,
    /// second-order one-sided differences at the edges.
    Grid,
    /// Groups of three points: a hit, then the same surface at (u + du, v)
    /// and at (u, v + dv) (from the ray differentials); forward differences.
    /// The results of the two helper points are not used.
    Triplets,
    /// Unrelated points: derivatives come from dPdu*du and dPdv*dv only
    /// (Du(P) = dPdu, Dv(P) = dPdv, Du(u) = Dv(v) = 1; Du and Dv of anything
    /// else are 0).
    Points
};

/// The points to shade and the global variables, in camera space.
///
/// Derivatives (Du, Dv, Deriv, area, calculatenormal, filterstep, implicit
/// texture filter widths) difference their argument over the whole batch,
/// whatever the running mask: the values of points masked off where the
/// argument was computed are whatever those points hold (the compiler
/// hoists such arguments out of varying conditions when it can).
struct ShadingBatch {
    std::size_t size = 0;
    BatchLayout layout = BatchLayout::Points;
    int nu = 0, nv = 0; ///< Grid: size == nu * nv

    // One entry per point (empty vectors take the documented defaults).
    std::vector<glm::vec3> P, N, Ng, I, dPdu, dPdv;
    std::vector<glm::vec3> Cs, Os; ///< default: the attributes' Color / Opacity
    std::vector<float> u, v, du, dv, s, t;
    /// area(P, "dicing"): the micropolygon's area when the dicer knows it.
    std::vector<float> dicing_area;
    /// bake3d's point radius when the call gives no "radius" (world units);
    /// empty: sqrt(area / pi) of the micropolygon (dicing_area when given,
    /// else area(P)).
    std::vector<float> radius;
    /// Motion blur: the time each point's rays are traced at (0 = shutter
    /// open, 1 = close; ShadowRay::time). Empty: 0.
    std::vector<float> ray_time;
    float time = 0.0f;
    /// How the points were reached (rayinfo; depth limits of their rays).
    RayContext ray;
    /// Seed of random() (and of the sample patterns of the ray-tracing
    /// shadeops: gather, trace, shadow, transmission, occlusion,
    /// indirectdiffuse): point i of the batch draws from
    /// hash(seed, i, the call, the how-many-th call of it), so results depend
    /// on the batch's seed and point order only, never on the thread count.
    /// Renderers set it from the grid or the batch index.
    uint64_t seed = 0;
    /// Rays start this far (world units) off the surface, as the C++ lights'
    /// ray_offset: shadow/transmission rays along the batch's N (or Ng)
    /// turned towards the ray, occlusion/indirectdiffuse rays along their N
    /// argument, gather/trace rays along the ray; a call's "bias" overrides it.
    float ray_offset = 0.0f;

    /// Rays leaving these points ignore hits on the batch's own primitive
    /// closer than this (world units): render shades points on the smooth
    /// surface the vertex normals describe, up to this far above the flat
    /// triangles that rays hit, and a ray into the object would find its
    /// own triangle first.
    float self_distance = 0.0f;
    /// The primitive being shaded (object space, attributes, RIB location).
    const Primitive* primitive = nullptr;
    /// Whether dPdu x dPdv already points along the oriented surface normal
    /// (ray hits, whose u and v are screen steps chosen that way): then
    /// calculatenormal does not apply RenderMan's parametric rule (flipped
    /// for a mirroring transform or Orientation "inside") a second time.
    bool oriented_derivatives = false;
    /// Primitive variables bound to shader parameters of the same name
    /// (type checked as RIB values; uniform or one value per point). Points,
    /// vectors and normals are in object space (the primitive's, world space
    /// without a primitive) and converted to the current space.
    std::vector<ShaderArgument> primvars;

    /// Outputs: Ci and Oi after a surface, volume or imager shader, P and N
    /// after a displacement shader (written back into P and N). Volume and
    /// imager shaders also read them: they start from the Ci and Oi given
    /// here (0 and Os when empty), as the surface (or the pixel) left them.
    std::vector<glm::vec3> Ci, Oi;
    /// Imager shaders: the pixels' alpha, read and written (1 when empty).
    /// Left alone by the other kinds.
    std::vector<float> alpha;
};

/// Rays a shader asks the renderer to trace and, for the ones that hit,
/// shade with the hit object's own surface shader (ShadingServices::trace).
/// Everything is in world space except the returned shader values, which
/// are in the current (camera) space like every shading value.
/// Which faces of one-sided (`Sides 1`) surfaces rays hit (the ray-tracing
/// shadeops' "hitsides"; PRMan's default is both; two-sided surfaces are
/// always hit).
enum class HitSides { Both, Front, Back };

struct RayQuery {
    // --- request
    RayKind kind = RayKind::Specular;
    std::string label; ///< the rays' label (gather "label"), rayinfo at the hits
    int depth = 1;     ///< depth of these rays: the shading point's depth + 1
    std::vector<ShadowRay> rays; ///< origins already offset; unit directions
    /// Angle (radians) between neighbouring rays of one shading point: the
    /// hit's footprint (filter widths, dPdu/dPdv) is length * spread wide.
    float spread = 0.0f;
    /// Variables of the hit shader to return: a global ("Ci", "Oi", "P",
    /// "N", "Cs", "s"...) or an output parameter of the surface shader, and
    /// the floats per ray each takes (1, 3 or 16; matching the caller's
    /// variable). Empty: the hits are found but nothing is shaded.
    std::vector<std::string> outputs;
    std::vector<int> output_floats;
    /// The primitive whose shader traces the rays (its `Attribute "trace"`
    /// depth limits apply); the engine sets it from ShadingBatch::primitive.
    const Primitive* origin = nullptr;
    /// Whether the caller reads `length`: a query with no outputs that does
    /// not may be answered with Embree's any-hit test (streams), its hits'
    /// lengths left at infinity.
    bool need_length = true;
    /// Hits on `origin` closer than this are ignored (ShadingBatch::self_distance).
    float self_distance = 0.0f;
    HitSides hitsides = HitSides::Both;
    /// Seed of the hit shaders' random numbers (ray r's batch point draws
    /// from hash(seed, r)): results never depend on the thread count.
    uint64_t seed = 0;

    // --- results (ShadingServices::trace fills every vector)
    std::vector<uint8_t> hit;  ///< per ray
    std::vector<float> length; ///< distance to the hit; infinity for misses
    /// Per output: rays.size() * output_floats[k] floats; 0 for misses and
    /// for hits whose shader has no such variable.
    std::vector<std::vector<float>> values;
};

/// Values a bake3d call hands to the pipeline: world-space points, and for
/// each channel its floats per point.
struct Bake3dRecord {
    std::string file;
    std::vector<std::string> channels; ///< channel names, as written
    std::vector<int> channel_floats;   ///< floats per point of each channel
    std::vector<glm::vec3> P, N;       ///< world space
    std::vector<float> radius;
    /// The micropolygon's area per point (ShadingBatch::dicing_area, else
    /// area(P); 0 when the call gave "radius" and the batch no area): the
    /// `_area` a baker writes when the shader bakes none.
    std::vector<float> area;
    std::vector<float> values; ///< per point: all channels' floats in order
};

/// What the renderer provides to shaders. Every function may be called from
/// many threads at once.
class ShadingServices {
public:
    virtual ~ShadingServices() = default;
    /// The scene (coordinate systems, camera, options, attributes).
    virtual const Scene& scene() const = 0;
    /// Ray tracer of the objects visible to transmission rays (shadow
    /// "raytrace", transmission()), or null: then nothing is occluded.
    virtual const RayTracer* occluders() const { return nullptr; }
    /// Traces `query.rays` against the objects visible to `query.kind` and
    /// shades the hits (ray tracing shadeops). The default sees nothing:
    /// every ray misses. Rays deeper than the scene's limits (`Option
    /// "trace" "maxdepth"`, `Attribute "trace" "maxdiffusedepth" /
    /// "maxspeculardepth"` of the shading point) miss without being traced.
    virtual void trace(RayQuery& query) {
        query.hit.assign(query.rays.size(), 0);
        query.length.assign(query.rays.size(), std::numeric_limits<float>::infinity());
        query.values.resize(query.outputs.size());
        for (std::size_t k = 0; k < query.outputs.size(); ++k)
            query.values[k].assign(query.rays.size() * query.output_floats[k], 0.0f);
    }
    /// Transmission along segments (shadow("raytrace"), transmission()):
    /// out[r] = the colour that gets through ray r (1 = nothing in the
    /// way), from the opacity of what the rays cross as `Attribute "shade"
    /// "transmissionhitmode"` says ("primitive": Os; "shader": the hit
    /// shader's Oi). The default: all-or-nothing through occluders().
    virtual void transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                          int depth);
    /// The texture lookups of shaders (texture, environment, textureinfo,
    /// texture3d, shadow on depth maps), or null: then every lookup fails as an
    /// unreadable file would ("no texture services", reported once, results 0).
    virtual TextureServices* textures() { return nullptr; }
    /// Receives what bake3d writes (ptbake collects it; render too).
    virtual void bake3d(Bake3dRecord&& record) { (void)record; }
    /// printf output (one message per call).
    virtual void message(const std::string& text) = 0;
    /// A run-time warning of a shader ("file:line: unknown texture option
    /// ..."). The engine gives each text once per ShadingResources.
    /// By default: message("warning: " + text).
    virtual void warning(const std::string& text) { message("warning: " + text); }
    /// Frame number for patterns in file names (texture3d, bake3d).
    virtual std::optional<int> frame() const { return std::nullopt; }
};

/// What the shading contexts of one job share: the run-time warnings given
/// so far (each text once per job). Thread-safe.
class ShadingResources {
public:
    ShadingResources();
    ~ShadingResources();
    ShadingResources(const ShadingResources&) = delete;
    ShadingResources& operator=(const ShadingResources&) = delete;

    struct Impl;
    Impl& impl() const { return *m_impl; }

private:
    std::unique_ptr<Impl> m_impl;
};

/// The lights a surface sees: light shader instances (LightSource and
/// AreaLightSource calls that are on for the primitive).
using LightList = std::span<const ShaderInstance* const>;
/// The co-shaders a shader may reach by handle (getshader, getshaders): the
/// `Shader "name" "handle"` calls in effect for the primitive (RSL 2.0),
/// each with its handle (ShaderInstance::handle).
using CoshaderList = std::span<const ShaderInstance* const>;

/// One thread's shading state (scratch memory, light caches). Create one
/// per thread; reuse it for every batch.
class ShadingContext {
public:
    ShadingContext(const ShadingResources& resources, ShadingServices& services);
    ~ShadingContext();
    ShadingContext(const ShadingContext&) = delete;
    ShadingContext& operator=(const ShadingContext&) = delete;

    /// Runs `shader` over every point of `batch`. Surface shaders leave Ci
    /// and Oi in the batch; displacement shaders leave the new P and N in
    /// batch.P and batch.N; volume shaders change the batch's Ci and Oi;
    /// imager shaders its Ci, Oi and alpha. `lights` are run lazily by illuminance loops,
    /// ambient(), diffuse()... and cached for the batch. Throws
    /// ShaderRuntimeError for errors a shader cannot recover from, including
    /// a loop that runs more than kMaxLoopIterations times in one batch
    /// ("loop does not end") and a batch over one of the shading budgets
    /// (sss/util/limits.h: SHADER_OPERATIONS, SHADER_STRING_LENGTH,
    /// SHADER_ARRAY_LENGTH, and per job BAKE3D_POINTS, BAKE3D_FILES, read at
    /// each execute). Throws OutOfMemoryError when the shader's strings,
    /// arrays or bake3d points would pass the job's memory budget.
    ///
    /// Before the body: Ci = 0, Oi = Os (volume and imager shaders: the
    /// batch's Ci and Oi); uninitialised locals are 0 (strings
    /// ""). After it, non-finite values of Ci, Oi, P, N and the output
    /// parameters are replaced by 0; nonfinite_points() counts the points.
    ///
    /// `coshaders` are what the shader's getshader() and getshaders() find
    /// (RSL 2.0 co-shaders; getlight() and getlights() find `lights`): their
    /// frames are set up when first called and kept for the batch.
    void execute(const ShaderInstance& shader, ShadingBatch& batch, LightList lights = {},
                 CoshaderList coshaders = {});
    /// execute() running `shader` as a shader of kind `kind`: a class shader
    /// (RSL 2.0) with displacement and surface methods runs as a
    /// displacement shader on the dicer's grids and as a surface at shading.
    /// Throws ValueError when the shader cannot run as `kind`
    /// (Program::runs_as).
    void execute_as(ShaderKind kind, const ShaderInstance& shader, ShadingBatch& batch,
                    LightList lights = {}, CoshaderList coshaders = {});

    /// Points of the last execute() whose results held NaN or infinity (and
    /// were written as 0).
    /// Rays this context has handed to ShadingServices::trace and transmit
    /// (all batches).
    uint64_t rays_traced() const;
    std::size_t nonfinite_points() const;
    /// "N points of shader X at file:line gave NaN or infinity; written as 0"
    /// for the last execute(), or "" when there were none.
    std::string nonfinite_message() const;

    /// Iterations of one loop (or illuminance loop) in one batch after which
    /// the engine gives up: a guard against shaders that never end.
    static constexpr long kMaxLoopIterations = 10'000'000;

    /// After execute: the values of the shader's symbol `name` (an output
    /// parameter or global, for AOVs) at every point, as floats
    /// (type.floats() per point). False when the shader has no such symbol.
    /// Valid until the next execute(), even when the ShaderInstance is gone.
    bool output(const std::string& name, TypeSpec& type,
                std::vector<float>& values) const;

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss

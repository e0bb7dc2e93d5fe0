#pragma once
/// \file engine.h
/// The shading engine: runs compiled shaders (program.h) SIMD-style over a
/// batch of shading points (a diced grid in ptbake, a batch of ray hits in
/// render) with a running mask for varying control flow, as REYES renderers
/// run shaders on grids. Shared by ptbake and render.
///
/// Spaces: "current" is camera space (RenderMan's convention, shading.md
/// section 4): every point, vector and normal of a batch is in camera space,
/// and the eye E is the origin.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "sss/scene/scene.h"
#include "sss/shading/program.h"
#include "sss/util/error.h"

namespace sss {

class RayTracer; // sss/light/ray_tracer.h

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
class ShaderInstance {
public:
    /// Binds `params` to the program's parameters. Throws ValueError naming
    /// `where` for a parameter of the wrong type or size; parameters the
    /// shader does not declare are reported through `warnings` (PRMan warns
    /// and ignores them).
    ShaderInstance(std::shared_ptr<const Program> program, const ParamList& params,
                   const Matrix4& shader_to_world, std::string where,
                   std::vector<std::string>* warnings = nullptr);

    const Program& program() const { return *m_program; }
    const std::shared_ptr<const Program>& program_ptr() const { return m_program; }
    const Matrix4& shader_to_world() const { return m_shader_to_world; }
    const std::string& where() const { return m_where; }
    /// The bound values (uniform, in the RIB's space: points in shader space).
    const std::vector<ShaderArgument>& arguments() const { return m_arguments; }
    /// A uniform parameter's value as bound or defaulted, when it is a
    /// constant (for the renderer: light categories, file names...).
    std::optional<std::string> string_parameter(const std::string& name) const;
    std::optional<float> float_parameter(const std::string& name) const;

private:
    std::shared_ptr<const Program> m_program;
    Matrix4 m_shader_to_world{1.0};
    std::string m_where;
    std::vector<ShaderArgument> m_arguments;
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
    /// (Du of anything but P, s, t, u, v is 0).
    Points
};

/// The points to shade and the global variables, in camera space.
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
    float time = 0.0f;

    /// The primitive being shaded (object space, attributes, RIB location).
    const Primitive* primitive = nullptr;
    /// Primitive variables bound to shader parameters of the same name.
    std::vector<ShaderArgument> primvars;

    /// Outputs: Ci and Oi after a surface shader, P and N after a
    /// displacement shader (written back into P and N).
    std::vector<glm::vec3> Ci, Oi;
};

/// Values a bake3d call hands to the pipeline: world-space points, and for
/// each channel its floats per point.
struct Bake3dRecord {
    std::string file;
    std::vector<std::string> channels; ///< channel names, as written
    std::vector<int> channel_floats;   ///< floats per point of each channel
    std::vector<glm::vec3> P, N;       ///< world space
    std::vector<float> radius;
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
    /// Receives what bake3d writes (ptbake collects it; render too).
    virtual void bake3d(Bake3dRecord&& record) { (void)record; }
    /// printf output (one message per call).
    virtual void message(const std::string& text) = 0;
    /// Frame number for patterns in file names (texture3d, bake3d).
    virtual std::optional<int> frame() const { return std::nullopt; }
};

/// Shared read-only resources of a job: the OpenImageIO texture system,
/// opened brick maps and point clouds. Thread-safe.
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
    /// batch.P and batch.N. `lights` are run lazily by illuminance loops,
    /// ambient(), diffuse()... and cached for the batch. Throws
    /// ShaderRuntimeError for errors a shader cannot recover from.
    void execute(const ShaderInstance& shader, ShadingBatch& batch,
                 LightList lights = {});

    /// After execute: the values of the shader's symbol `name` (an output
    /// parameter or global, for AOVs) at every point, as floats
    /// (type.floats() per point). False when the shader has no such symbol.
    bool output(const std::string& name, TypeSpec& type,
                std::vector<float>& values) const;

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss

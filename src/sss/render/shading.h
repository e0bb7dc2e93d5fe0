#pragma once
// Internal to the renderer (render.cpp, shaders.cpp): the built-in surface
// shaders, what they are given at a shading point and what they return. The
// shaders and their formulas are documented in docs/render.md.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_lookup.h"
#include "sss/light/lights.h"
#include "sss/light/ray_tracer.h"
#include "sss/scene/scene.h"

namespace sss::detail {

/// Where a shader reads its subsurface diffusion: a brick map (.bkm) or a
/// point cloud (.ptc, .ply), opened once per file and channel and shared by
/// every shader naming it. Lookups are thread-safe.
class DiffusionSource {
public:
    /// Opens `path` and finds `channel` (a color, or a float used as grey).
    /// Errors name `where` (the shader's RIB location) and the file.
    DiffusionSource(const std::string& path, const std::string& channel,
                    const std::string& where);
    ~DiffusionSource();
    DiffusionSource(const DiffusionSource&) = delete;
    DiffusionSource& operator=(const DiffusionSource&) = delete;

    /// The channel at world point p for a surface of normal n, texture3d-style
    /// (brick maps blend the levels nearest to `radius`; point clouds always
    /// average their nearest points). False, with `out` zero, where there is
    /// no data.
    bool lookup(const glm::vec3& p, const glm::vec3& n, float radius,
                glm::vec3& out) const;
    const std::string& path() const { return m_path; }
    bool is_brick_map() const { return m_map != nullptr; }

private:
    std::string m_path;
    std::unique_ptr<BrickMap> m_map;
    std::unique_ptr<PointCloud> m_cloud;
    std::unique_ptr<PointCloudLookup> m_cloud_lookup;
    int m_offset = 0;     ///< first float of the channel in a lookup's result
    int m_components = 3; ///< 1 (float channel) or 3
};

/// The built-in surface shaders.
enum class ShaderKind { Default, Constant, Matte, Plastic, ReadSsdiffusion, Skin };

/// One Surface call resolved: its kind and parameters (defaults filled in).
struct SurfaceShader {
    ShaderKind kind = ShaderKind::Default;
    std::string where; ///< "scene.rib:12: Surface \"plastic\"", for messages
    double ka = 1.0, kd = 1.0, ks = 0.5, roughness = 0.1;
    glm::dvec3 specular_color{1.0};
    double ks_facing = 0.0, ks_glancing = 0.0;        ///< skin
    double sss_weight = 1.0;                          ///< skin
    glm::dvec3 sss_color{1.0};                        ///< skin
    int occlusion_samples = 0;                        ///< 0: no ambient occlusion
    double occlusion_maxdist = 0.0;                   ///< 0: unlimited
    double filter_scale = 1.0;                        ///< brick-map filter radius scale
    std::shared_ptr<const DiffusionSource> diffusion; ///< read_ssdiffusion, skin
};

/// The shaders of a scene: one per distinct Surface call, and for every
/// primitive the index of its shader.
struct ShaderSet {
    std::vector<SurfaceShader> shaders;
    std::vector<int> of_primitive;
    /// Diffusion files opened, by path (for reports).
    std::vector<std::string> files;
};

/// Resolves every primitive's Surface (frame patterns in file names expanded
/// with `frame`); unknown shaders warn once per name and render with
/// defaultsurface. Opens every diffusion file. Throws ValueError / Error
/// naming the shader's RIB location.
ShaderSet resolve_surface_shaders(const Scene& scene, std::optional<int> frame,
                                  std::vector<std::string>& warnings);

/// The diffusion files (brick maps, point clouds) the scene's shaders read,
/// frame patterns expanded, each once, without opening them.
std::vector<std::string> diffusion_files(const Scene& scene, std::optional<int> frame);

/// What a shader sees at a shading point (world space, unit vectors).
struct ShadingPoint {
    glm::dvec3 p{0.0};  ///< position (on the smooth surface)
    glm::dvec3 n{0.0};  ///< shading normal with the surface's orientation (lookups)
    glm::dvec3 nf{0.0}; ///< shading normal faced towards the viewer (lighting)
    glm::dvec3 v{0.0};  ///< towards the viewer (-I)
    glm::dvec3 cs{1.0}; ///< surface colour
    double filter_radius = 0.0; ///< brick-map lookup radius (pixel footprint)
    double ray_offset = 0.0;    ///< shadow and occlusion ray origin offset along nf
    uint64_t seed = 0;          ///< sample-pattern seed (deterministic per sample)
};

/// The lights and occluders a shader can query.
struct ShadingEnv {
    const std::vector<Light>* lights = nullptr;
    const std::vector<int>* active = nullptr; ///< lights on for the primitive
    const RayTracer* occluders = nullptr;     ///< shadow / occlusion geometry, or null
    std::vector<LightSample>* scratch = nullptr;
};

/// A shader's result, split into the AOVs. Beauty = ambient + diffuse +
/// specular + sss + emission.
struct ShadeResult {
    glm::dvec3 ambient{0.0};
    glm::dvec3 diffuse{0.0};
    glm::dvec3 specular{0.0};
    glm::dvec3 sss{0.0};
    glm::dvec3 emission{0.0}; ///< constant: beauty only
    double occlusion = 1.0;   ///< unoccluded fraction the shader used (1: none computed)
    uint64_t rays = 0;        ///< shadow and occlusion rays traced
};

/// Runs a shader at a shading point.
void shade(const SurfaceShader& shader, const ShadingPoint& sp, const ShadingEnv& env,
           ShadeResult& out);

} // namespace sss::detail

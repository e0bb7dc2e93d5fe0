// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the render module: the job shared by render.cpp (tiles,
// pixels, render_image, render_scene), render_setup.cpp (the phases
// before the tiles: camera, shaders and AOVs, surfaces, dicing, ray tracers)
// and render_volumes.cpp (the Atmosphere and Imager shaders).

#include "sss/render/render.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "sss/bake/bake.h"
#include "sss/binding/bake3d_file.h"
#include "sss/binding/displacement.h"
#include "sss/binding/scene_rays.h"
#include "sss/binding/scene_shaders.h"
#include "sss/dice/dice.h"
#include "sss/light/ray_tracer.h"
#include "sss/render/camera_sampling.h"
#include "sss/shading/engine.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/hash.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/math.h"
#include "sss/util/progress.h"
#include "sss/util/version.h"

namespace sss::render_detail {

/// Pixels per tile side: the unit of parallel work and of filter splatting.
constexpr int kTile = 16;
/// Render dicing: triangles about this many raster pixels across, whatever
/// the ShadingRate (shading is per pixel sample, not per micropolygon).
/// Smooth shading comes from the vertex normals, so the triangles only need
/// to get the silhouette right: their chords are within a few hundredths of
/// a pixel of a curved surface whose radius is 100 pixels or more.
constexpr double kEdgePixels = 4.0;
/// Surfaces composited along one camera ray, and hits examined in all
/// (hidden back faces and fully transparent surfaces included).
constexpr int kMaxLayers = 8;
constexpr int kMaxHits = 32;
/// A ray stops once less than this fraction of light gets through.
constexpr double kOpaque = 1e-4;
/// Pixels a sample may reach on each side of its own (PixelFilter widths
/// of at most 16 pixels).
constexpr int kMaxReach = 8;

/// Whether `Attribute "visibility" name` leaves the primitive visible.
inline bool visible_to(const Primitive& prim, const char* name) {
    return attributes_of(prim).visible_to(name);
}

/// Camera rays from raster positions, as the ray tracer takes them.
class CameraRays {
public:
    /// Checks the camera (check_camera: errors name its RIB statements).
    explicit CameraRays(const Camera& cam) : m_projection((check_camera(cam), cam)) {}

    /// The ray through raster point (x, y) (pixels, y down), clipped to
    /// [hither, yon] along the camera's z (CameraProjection::ray); *units is
    /// the ray length per unit of camera z (the depth of a hit at t is t /
    /// *units). Intervals beyond float range become infinite; a ray that is
    /// not valid (a projective camera transform can make one between valid
    /// corners) is passed on: the ray tracer counts it as a miss.
    ShadowRay ray(double x, double y, const glm::dvec2& lens, double* units) const {
        const CameraProjection::Ray r = m_projection.ray(x, y, lens);
        *units = r.units;
        ShadowRay out;
        out.origin = to_float(r.origin);
        out.direction = to_float(r.direction);
        out.tnear = to_float(r.tnear);
        out.tfar = to_float(r.tfar);
        return out;
    }

private:
    /// Converts with overflow to infinity (a plain conversion of a double
    /// beyond float range is undefined behaviour).
    static float to_float(double v) {
        constexpr double kMax = std::numeric_limits<float>::max();
        if (v > kMax) return std::numeric_limits<float>::infinity();
        if (v < -kMax) return -std::numeric_limits<float>::infinity();
        return static_cast<float>(v);
    }
    static glm::vec3 to_float(const glm::dvec3& v) {
        return {to_float(v.x), to_float(v.y), to_float(v.z)};
    }

    CameraProjection m_projection;
};

/// A primitive as the renderer uses it.
struct Surface {
    DicedSurface diced;
    /// Cs per triangle when the primitive has varying colours (the colour of
    /// the micropolygon nearest to the triangle's centre); empty otherwise.
    std::vector<glm::vec3> triangle_colors;
    bool camera = true;  ///< seen by camera rays
    bool shadows = true; ///< casts shadows and occludes
    /// Seen by the shaders' secondary rays (trace, gather, occlusion...).
    bool secondary = false;
};

/// An AOV of the image: an output variable of the surface shaders.
struct Aov {
    std::string variable;  ///< the shaders' output variable ("_diffuse", "Csss")
    std::string layer;     ///< image layer ("diffuse") or channel name
    int floats = 3;        ///< 1 (float) or 3 (colour, point, vector, normal)
    bool as_rgb = false;   ///< a float written as layer.R/G/B (occlusion)
    float fallback = 0.0f; ///< value where a shader has no such variable
    int offset = 0;        ///< first value in a sample
};

/// Writes shader printf output, one message at a time.
class RenderServices final : public SceneServices {
public:
    using SceneServices::SceneServices;
    const RayTracer* occluders() const override { return m_occluders; }
    void set_occluders(const RayTracer* tracer) { m_occluders = tracer; }
    /// bake3d at the camera's hits bakes nothing: a bake RIB's clouds come
    /// from its bake pass (BakeJob), one point per micropolygon of the whole
    /// surface, not one per camera sample.
    void bake3d(Bake3dRecord&& record) override { (void)record; }

private:
    const RayTracer* m_occluders = nullptr;
};

/// Everything the pixel loop reads (immutable once built).
struct Renderer {
    explicit Renderer(const SceneShaders& bound) : shaders(bound) {}
    const Scene* scene = nullptr;
    Camera camera;
    std::optional<CameraRays> rays;
    int nx = 1, ny = 1;                ///< pixel samples
    std::optional<PixelFilter> filter; ///< the PixelFilter
    int reach_x = 1, reach_y = 1;      ///< pixels a sample reaches on each side
    /// The filter's weights can sum to about zero over a pixel (negative
    /// lobes, or narrower than a pixel): such pixels take the value of their
    /// own sample nearest to their centre.
    bool nearest_fallback = false;
    const SceneShaders& shaders; ///< the job's, bound once (RenderJob)
    std::unique_ptr<ShadingResources> resources;
    std::unique_ptr<TextureLibrary> textures; ///< before services, which use it
    std::unique_ptr<RenderServices> services;
    std::vector<Aov> aovs;
    std::vector<char> derivatives; ///< per primitive: its shader differentiates
    /// Per primitive: its shader reads u, v, s, t, du or dv (or looks up a
    /// texture): it is diced with DicedSurface::vertex_uvst, which the hits
    /// interpolate.
    std::vector<char> parametric;
    int values = 4;                         ///< per sample: RGBA, then the AOVs
    std::vector<Surface> surfaces;          ///< by primitive
    std::vector<uint32_t> camera_primitive; ///< camera mesh -> primitive
    std::unique_ptr<RayTracer> camera_tracer;
    std::unique_ptr<RayTracer> shadow_tracer; ///< only when it differs from the camera's
    const RayTracer* occluders = nullptr;
    /// Whether some shader traces secondary rays, and the scene they see.
    bool any_rays = false;
    std::unique_ptr<SceneRays> scene_rays;
    double extent = 0.0;
    /// Pixel size per unit of depth (perspective; hits lie beyond hither), or
    /// the pixel size (orthographic): Camera::pixel_size_at without its tan().
    double pixel_per_depth = 0.0;
    glm::dmat3 normal_to_camera{1.0}; ///< inverse transpose of world->camera
    glm::dvec3 camera_x{1, 0, 0}, camera_y{0, 1, 0}; ///< camera axes in world space
    /// Motion blur: camera samples spread over the shutter (Camera::motion_blur).
    bool motion_blur = false;
    /// A moving camera: its world-to-camera at each motion sample (empty
    /// when it does not move), and the shutter's open and close times.
    std::vector<double> camera_times;
    std::vector<glm::dmat4> world_to_camera_keys;
    double shutter_open = 0.0, shutter_close = 0.0;
    /// A frame with a depth-map display ("zfile", "shadow"): the depth is
    /// the nearest surface at least `zthreshold` opaque in every channel
    /// (PRMan's Option "limits" "zthreshold"), semi-transparent ones are
    /// seen through; otherwise the nearest surface.
    bool opaque_depth = false;
    glm::dvec3 zthreshold{0.996};
    std::atomic<uint64_t> surface_samples{0}; ///< camera samples that met a surface
    std::atomic<uint64_t> camera_rays{0};
    std::atomic<uint64_t> shadow_rays{0};
    std::atomic<uint64_t> bad_samples{0};
    std::atomic<uint64_t> nan_points{0};
    /// Shading at the ShadingRate (shade_pass_cached) rather than at every
    /// camera sample; the camera's world-to-NDC for its lattice points.
    bool shading_cache = false;
    glm::dmat4 world_to_ndc{1.0};
    /// Per primitive: ShadingInterpolation "smooth" (else "constant").
    std::vector<char> smooth_shading;
    std::atomic<uint64_t> shading_points{0}; ///< points the surface shaders ran at
};

/// One camera sample of a tile, while its ray goes through the layers.
struct CameraSample {
    ShadowRay ray;
    double units = 1.0;
    uint64_t key = 0;
    double sx = 0.0, sy = 0.0;
    glm::dvec3 trans{1.0};
    int layers = 0;
    int hits = 0;
    bool active = true;
    float depth = std::numeric_limits<float>::infinity();
};

/// A surface a camera ray hit, to be shaded.
struct SurfaceHit {
    uint32_t sample = 0;
    uint32_t primitive = 0;
    glm::dvec3 p, n, ng; ///< world: point on the smooth surface, normals (oriented)
    glm::dvec3 dir;      ///< the ray's direction
    glm::dvec3 cs, os;
    glm::dvec3 dpdx, dpdy; ///< one pixel's footprint on the tangent plane
    double radius = 0.0;   ///< texture3d filter radius
    float depth = 0.0f;
    uint32_t triangle = 0;      ///< the triangle hit, and the barycentrics of
    float b1 = 0.0f, b2 = 0.0f; ///< its vertices 1 and 2 at the hit
    uint64_t seed = 0;
    double lift = 0.0; ///< distance of p above the flat triangle
    float time = 0.0f; ///< the ray's time (0 = shutter open, 1 = close)
};

/// Shading points already shaded in a tile (render_shading.cpp): the values
/// of each lattice point (primitive, triangle, point of its lattice), so that
/// every later sample that hits it takes them.
struct ShadingCache {
    /// A lattice point of a primitive: `tag` says which kind (its top two
    /// bits) and a, b where: a cell of triangle a, b its (i, j, upper); a
    /// mesh vertex a (a corner, shared by the triangles around it); the
    /// point of edge (a, b), a < b, at the fraction the tag's low bits hold
    /// (shared by the edge's two triangles when both cut it there); a point
    /// inside triangle a, b its (i, j).
    struct Key {
        uint32_t prim = 0, tag = 0, a = 0, b = 0;
        bool operator==(const Key&) const = default;
    };
    struct KeyHash {
        std::size_t operator()(const Key& k) const {
            return std::size_t(
                detail::splitmix64((uint64_t(k.prim) << 32 | k.tag) ^
                                   detail::splitmix64(uint64_t(k.a) << 32 | k.b)));
        }
    };
    /// A lattice point the camera cannot see (off its projection, or facing
    /// away on a one-sided surface).
    static constexpr uint32_t kUnseen = UINT32_MAX;
    std::unordered_map<Key, uint32_t, KeyHash> slot;
    std::vector<float> values; ///< per slot: Ci, Oi, then the AOVs' floats
    /// Cells per edge of each triangle met (primitive << 32 | triangle).
    std::unordered_map<uint64_t, int> lattice;
};

/// Finds what each active sample's ray hits next; samples whose ray leaves
/// the scene (or runs out of layers) become inactive. Hits that are not
/// shaded (slivers, one-sided back faces, transparent surfaces) only move
/// the ray on.
void trace_pass(const Renderer& job, std::vector<CameraSample>& samples,
                std::vector<SurfaceHit>& hits, uint64_t& camera_count);

/// Shades every hit of one pass on its own, primitive by primitive in
/// batches, and composites each into its sample (front to back).
void shade_pass(Renderer& job, ShadingContext& context, std::vector<SurfaceHit>& hits,
                std::vector<CameraSample>& samples, std::vector<float>& values);

/// shade_pass() at the ShadingRate: each hit takes the values of its
/// triangle's lattice cell (ShadingInterpolation "constant") or of the cell's
/// corners blended at the hit ("smooth"), shading the points the tile's cache
/// lacks. Deterministic: a point's values depend only on the point.
void shade_pass_cached(Renderer& job, ShadingContext& context,
                       std::vector<SurfaceHit>& hits, std::vector<CameraSample>& samples,
                       std::vector<float>& values, ShadingCache& cache);

/// The times a moving primitive is diced at: evenly over the shutter with
/// motion blur (a step at each of its motion samples when they fall on an
/// even spacing, else four steps per sample interval, at most 33), the
/// shutter's open time alone without. Empty when it does not move.
std::vector<double> dice_times(const Camera& camera, const Primitive& prim);

/// Moves a camera ray made by the camera as it is at the shutter's open time
/// to the camera as it is at `time` (a moving camera), and stamps the time.
void move_camera_ray(const Renderer& job, double time, ShadowRay& ray);
/// The depth rule of the frame (Renderer::opaque_depth, zthreshold): opaque
/// surfaces only when a Display is a depth map.
void setup_depth(Renderer& job, const Scene& scene);

/// The camera with the image size overrides, the pixel samples, the camera
/// rays and the pixel size per unit of depth; ValueError (UsageError for a
/// half-given override) on values that cannot render.
void setup_camera(Renderer& job, const Scene& scene, const RenderJobOptions& options);

/// The image's AOVs: every name a Display mode or a DisplayChannel asks for
/// that is an output variable of a surface shader (its own name and declared
/// type), else a built-in layer (ambient, diffuse, specular, sss, occlusion:
/// the standard shaders' _ambient...). A Display mode naming neither is a
/// ValueError naming the Display; a DisplayChannel naming neither only
/// declares a channel (bake3d's).
std::vector<Aov> plan_aovs(const Scene& scene, const SceneShaders& shaders);

/// Shaders, lights, AOVs and shading resources (textures, brick maps and
/// point clouds are opened on first use); true when some light or shader
/// traces shadow or occlusion rays.
bool resolve_shading(Renderer& job, const Scene& scene, std::optional<int> frame,
                     RenderReport& report);

/// What is diced: everything the camera sees, and everything that casts
/// shadows when some light or shader traces them. Returns those primitives;
/// *separate_shadows tells whether shadows see other surfaces than the camera.
std::vector<std::size_t> plan_surfaces(Renderer& job, bool any_shadows,
                                       bool* separate_shadows);

/// Dices the primitives `to_dice` into triangles of about kEdgePixels, with
/// unit vertex normals and per-triangle colours.
void dice_surfaces(Renderer& job, const std::vector<std::size_t>& to_dice,
                   bool separate_shadows, RenderReport& report);

/// The ray tracers: one when the camera and shadows see the same surfaces,
/// else one each; and the scene extent.
void build_tracers(Renderer& job, const std::vector<std::size_t>& to_dice,
                   bool any_shadows, bool separate_shadows, RenderReport& report);

/// Runs a primitive's Atmosphere shader on the camera hits its surface
/// shader just shaded: point k * stride of `surface` is hit k (stride 3 for
/// triplets); P, I, N and the surface's Ci and Oi go in, and the shader's Ci
/// and Oi replace the surface's (render_volumes.cpp).
void run_atmosphere(Renderer& job, ShadingContext& context, const ShaderInstance& shader,
                    ShadingBatch& surface, std::size_t stride, LightList lights);

/// Runs the scene's Imager shader (if any) on every pixel of the filtered
/// image, before the Displays' exposure and quantisation: Ci = R G B, Oi =
/// alpha = A, P = the pixel's centre in raster space; R G B = Ci and A =
/// alpha afterwards. The AOVs and Z are not touched.
void run_imager(Renderer& job, Image& image);

} // namespace sss::render_detail

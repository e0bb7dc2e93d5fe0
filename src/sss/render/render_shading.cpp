// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file render_shading.cpp
/// The camera samples' surfaces: tracing each live sample to its next
/// surface, shading the hits in batches per primitive and compositing them
/// front to back. Two ways to shade (docs/render.md, "Shading rate"):
/// every hit on its own (-pixelshading 1), or, by default, at points of the
/// surface fixed by the ShadingRate, whatever the pixel samples: each diced
/// triangle is split into a lattice of cells about ShadingRate pixels in
/// area, a cell (ShadingInterpolation "constant") or its corners ("smooth")
/// is shaded once per tile, and every sample that hits it takes that colour
/// (or the corners' colours blended at the hit).

#include "render_internal.h"

#include <numeric>

namespace sss::render_detail {

namespace {

/// A hit on triangle `triangle` of primitive `prim_index` at barycentrics
/// (b1, b2), seen along `dir` at distance t (`units` per unit of depth) at
/// `time`: h's point, normals, colours, pixel footprint and depth. False when
/// the hit is not shaded (a degenerate sliver, a one-sided back face, a fully
/// transparent surface).
bool fill_hit(const Renderer& job, uint32_t prim_index, uint32_t triangle, double b1,
              double b2, glm::dvec3 ng, const glm::dvec3& dir, double t, double units,
              float time, SurfaceHit& h, bool full = true, bool lattice = false) {
    const Surface& surf = job.surfaces[prim_index];
    const Primitive& prim = job.scene->primitives[prim_index];
    const Attributes& attr = attributes_of(prim);
    const DicedSurface& d = surf.diced;
    const uint32_t* tri = &d.triangles[3 * std::size_t(triangle)];
    // A moving surface as it is at the ray's time.
    const glm::dvec3 v0(d.vertex_at(tri[0], time)), v1(d.vertex_at(tri[1], time)),
        v2(d.vertex_at(tri[2], time));
    const glm::dvec3 n0(d.normal_at(tri[0], time)), n1(d.normal_at(tri[1], time)),
        n2(d.normal_at(tri[2], time));
    const double b0 = 1.0 - b1 - b2;
    const glm::dvec3 p = b0 * v0 + b1 * v1 + b2 * v2;

    const double ng_len = glm::length(ng);
    if (!(ng_len > 0.0) || !std::isfinite(ng_len)) return false; // degenerate sliver
    ng /= ng_len;
    glm::dvec3 n = b0 * n0 + b1 * n1 + b2 * n2;
    const double n_len = glm::length(n);
    n = (n_len > 0.0 && std::isfinite(n_len)) ? n / n_len : ng;
    // The vertex normals carry the orientation (Orientation, ReverseOrientation).
    if (glm::dot(ng, n) < 0.0) ng = -ng;
    const bool back = glm::dot(ng, dir) > 0.0;
    if (back && attr.sides == 1) return false; // one-sided: back faces are not seen

    const glm::dvec3 os = glm::clamp(attr.opacity, 0.0, 1.0);
    if (os == glm::dvec3(0.0)) return false;

    h.primitive = prim_index;
    h.triangle = triangle;
    h.b1 = static_cast<float>(b1);
    h.b2 = static_cast<float>(b2);
    h.time = time;
    h.depth = static_cast<float>(t / units);
    // Shading at the ShadingRate needs no more of a camera sample's hit.
    if (!full) return true;
    // The point on the smooth surface the vertex normals describe
    // (Hanika 2021): the barycentric blend of p projected onto each
    // vertex's tangent plane. Shadow and occlusion rays start there,
    // clear of the flat triangles' own shadows near the terminator; it
    // is used only on the side it bulges to, and never farther than the
    // triangle's size.
    const glm::dvec3 ngf = back ? -ng : ng;
    glm::dvec3 smooth = b0 * (p - glm::dot(p - v0, n0) * n0) +
                        b1 * (p - glm::dot(p - v1, n1) * n1) +
                        b2 * (p - glm::dot(p - v2, n2) * n2);
    const double lift = glm::dot(smooth - p, ngf);
    const double size =
        std::max({glm::length(v1 - v0), glm::length(v2 - v1), glm::length(v0 - v2)});
    if (!(lift > 0.0) || !(glm::length(smooth - p) < 0.5 * size)) smooth = p;
    h.lift = glm::length(smooth - p);
    h.p = smooth;
    h.n = n;
    h.ng = ng;
    h.dir = dir;
    h.cs = surf.triangle_colors.empty() ? attr.color
                                        : glm::dvec3(surf.triangle_colors[triangle]);
    h.os = os;
    const double depth = t / units;
    const double pixel =
        job.camera.perspective ? job.pixel_per_depth * depth : job.pixel_per_depth;
    h.radius = 0.5 * std::sqrt(std::max(attr.shading_rate, 0.0)) * pixel;
    // The pixel's footprint: the camera's x and y steps of one pixel,
    // projected along the ray onto the tangent plane (capped at grazing
    // angles). A lattice point of a triangle whose vertex normals lie almost
    // in its plane (a patch collapsed to a pole or a crease) takes the plane
    // of its shading normal: the triangle's would make calculatenormal()
    // turn away from N there.
    const glm::dvec3 plane = lattice && std::abs(glm::dot(n, ng)) < 0.5 ? n : ng;
    const double cosine = glm::dot(dir, plane);
    const auto project = [&](const glm::dvec3& step) {
        glm::dvec3 v = step;
        if (std::abs(cosine) > 1e-6) v -= dir * (glm::dot(step, plane) / cosine);
        const double cap = 8.0 * pixel;
        const double len = glm::length(v);
        return len > cap ? v * (cap / len) : v;
    };
    h.dpdx = project(job.camera_x * pixel);
    h.dpdy = project(job.camera_y * pixel);
    // The hit's u and v directions are screen steps, not the surface's
    // parameters: v steps the way that makes dPdu x dPdv point along the
    // oriented normal, as the parametric derivatives do, so that
    // calculatenormal(P) (and of a displaced P) faces like N.
    if (glm::dot(glm::cross(h.dpdx, h.dpdy), plane) < 0.0) h.dpdy = -h.dpdy;
    return true;
}

/// (u, v, s, t) at a hit, linear over its triangle (DicedSurface::
/// vertex_uvst), and at its two neighbours (the hit moved by dpdx and dpdy,
/// in the triangle's plane): the barycentric blend, then its gradient.
std::array<glm::dvec4, 3> hit_uvst(const DicedSurface& d, const SurfaceHit& h) {
    const uint32_t* tri = &d.triangles[3 * std::size_t(h.triangle)];
    const glm::dvec4 a0(d.vertex_uvst[tri[0]]), a1(d.vertex_uvst[tri[1]]),
        a2(d.vertex_uvst[tri[2]]);
    const double b1 = h.b1, b2 = h.b2;
    const glm::dvec4 at = (1.0 - b1 - b2) * a0 + b1 * a1 + b2 * a2;
    std::array<glm::dvec4, 3> out{at, at, at};
    const glm::dvec3 v0(d.vertices[tri[0]]);
    const glm::dvec3 e1 = glm::dvec3(d.vertices[tri[1]]) - v0;
    const glm::dvec3 e2 = glm::dvec3(d.vertices[tri[2]]) - v0;
    const glm::dvec3 cross = glm::cross(e1, e2);
    const double cross2 = glm::dot(cross, cross);
    if (!(cross2 > 0.0) || !std::isfinite(cross2)) return out;
    // Gradients of the barycentrics b1 and b2 in the triangle's plane.
    const glm::dvec3 g1 = glm::cross(e2, cross) / cross2;
    const glm::dvec3 g2 = glm::cross(cross, e1) / cross2;
    const auto change = [&](const glm::dvec3& step) {
        return (a1 - a0) * glm::dot(g1, step) + (a2 - a0) * glm::dot(g2, step);
    };
    out[1] += change(h.dpdx);
    out[2] += change(h.dpdy);
    return out;
}

/// The AOVs the shader just run has (values[a], has[a]), as each AOV's
/// floats: a float replicated into a colour layer, a colour's mean into a
/// float one (shaders may declare one output variable with either type).
void shader_aovs(ShadingContext& context, const std::vector<Aov>& aovs,
                 std::vector<std::vector<float>>& aov_values, std::vector<char>& has) {
    for (std::size_t a = 0; a < aovs.size(); ++a) {
        TypeSpec type;
        std::vector<float>& values = aov_values[a];
        if (!context.output(aovs[a].variable, type, values) || type.is_array() ||
            type.type == ShadingType::String)
            continue;
        const int floats = shading_type_floats(type.type);
        const int want = aovs[a].floats;
        if (floats == want) {
            has[a] = 1;
        } else if (floats == 1 && want == 3) {
            std::vector<float> wide(values.size() * 3);
            for (std::size_t i = 0; i < values.size(); ++i)
                wide[3 * i] = wide[3 * i + 1] = wide[3 * i + 2] = values[i];
            values.swap(wide);
            has[a] = 1;
        } else if (floats == 3 && want == 1) {
            std::vector<float> mean(values.size() / 3);
            for (std::size_t i = 0; i < mean.size(); ++i)
                mean[i] = (values[3 * i] + values[3 * i + 1] + values[3 * i + 2]) / 3.0f;
            values.swap(mean);
            has[a] = 1;
        }
    }
}

/// A batch of m hit points of `prim` (triplets: each hit with its two
/// neighbours), every per-point array sized.
void start_batch(const Renderer& job, const Primitive& prim, std::size_t m, bool triplets,
                 bool parametric, ShadingBatch& batch) {
    batch = ShadingBatch{};
    batch.size = m;
    batch.layout = triplets ? BatchLayout::Triplets : BatchLayout::Points;
    batch.oriented_derivatives = true;
    batch.primitive = &prim;
    batch.time = static_cast<float>(job.shutter_open);
    for (auto* v : {&batch.P, &batch.N, &batch.Ng, &batch.I, &batch.dPdu, &batch.dPdv,
                    &batch.Cs, &batch.Os})
        v->resize(m);
    // At hits the batch's u and v directions are one pixel step along the
    // camera's x and y (dPdu, dPdv are those steps' footprints), so du = dv
    // = 1 pixel: Du(x) is x's change per pixel.
    batch.du.assign(m, 1.0f);
    batch.dv.assign(m, 1.0f);
    if (parametric)
        for (auto* v : {&batch.u, &batch.v, &batch.s, &batch.t}) v->resize(m);
    batch.dicing_area.resize(m);
    batch.radius.resize(m);
    if (job.motion_blur) batch.ray_time.resize(m);
}

/// Floats of one shaded point: Ci, Oi (as the shader left them), then each
/// AOV's floats (its fallback where the shader has no such variable).
int point_floats(const Renderer& job) {
    int n = 6;
    for (const Aov& aov : job.aovs) n += aov.floats;
    return n;
}

/// Shades hits [begin, end) of one primitive, seen from origins[k] (world),
/// in one batch: their point_floats() values go to out (one run per hit).
void shade_batch(Renderer& job, ShadingContext& context, const SurfaceHit* hits,
                 const glm::dvec3* origins, std::size_t n, float* out) {
    const uint32_t prim_index = hits[0].primitive;
    const Primitive& prim = job.scene->primitives[prim_index];
    const ShaderInstance& shader = *job.shaders.surface_of[prim_index];
    const glm::dmat4& to_camera = job.camera.world_to_camera;
    // A shader that differentiates gets each hit with two neighbours, one
    // pixel step along the camera's x and y on the tangent plane (ray
    // differentials), and forward differences between them.
    const bool triplets = job.derivatives[prim_index] != 0;
    const std::size_t r = triplets ? 3 : 1;
    const std::size_t m = n * r;
    const DicedSurface& diced = job.surfaces[prim_index].diced;
    const bool parametric = !diced.vertex_uvst.empty();
    ShadingBatch batch;
    start_batch(job, prim, m, triplets, parametric, batch);
    // Point i of the batch draws its samples from hash(seed, i): the first
    // hit's key fixes them for the batch (tiles are split into batches the
    // same way for any thread count).
    batch.seed = hits[0].seed;
    batch.ray_offset = trace_bias(prim).value_or(static_cast<float>(1e-5 * job.extent));
    double lift = 0.0;
    for (std::size_t k = 0; k < n; ++k) lift = std::max(lift, hits[k].lift);
    // Rays into the object start above its flat triangles: twice the
    // largest lift clears them (glancing rays travel farther).
    batch.self_distance = static_cast<float>(4.0 * lift + 1e-5 * job.extent);
    for (std::size_t k = 0; k < n; ++k) {
        const SurfaceHit& h = hits[k];
        const glm::dvec3 pc = glm::dvec3(to_camera * glm::dvec4(h.p, 1.0));
        const glm::dvec3 oc = glm::dvec3(to_camera * glm::dvec4(origins[k], 1.0));
        const glm::vec3 du_c(glm::dmat3(to_camera) * h.dpdx);
        const glm::vec3 dv_c(glm::dmat3(to_camera) * h.dpdy);
        const glm::vec3 n_c(glm::normalize(job.normal_to_camera * h.n));
        const glm::vec3 ng_c(glm::normalize(job.normal_to_camera * h.ng));
        const float area = glm::length(glm::cross(du_c, dv_c));
        std::array<glm::dvec4, 3> uvst{}; // at the hit and its neighbours
        if (parametric) uvst = hit_uvst(diced, h);
        for (std::size_t q = 0; q < r; ++q) {
            const std::size_t i = k * r + q;
            const glm::vec3 offset = q == 1 ? du_c : q == 2 ? dv_c : glm::vec3(0.0f);
            batch.P[i] = glm::vec3(pc) + offset;
            batch.I[i] = glm::vec3(pc - oc) + offset;
            batch.N[i] = n_c;
            batch.Ng[i] = ng_c;
            batch.dPdu[i] = du_c;
            batch.dPdv[i] = dv_c;
            batch.Cs[i] = glm::vec3(h.cs);
            batch.Os[i] = glm::vec3(h.os);
            batch.dicing_area[i] = area;
            batch.radius[i] = static_cast<float>(h.radius);
            if (job.motion_blur) batch.ray_time[i] = h.time;
            if (parametric) {
                batch.u[i] = static_cast<float>(uvst[q].x);
                batch.v[i] = static_cast<float>(uvst[q].y);
                batch.s[i] = static_cast<float>(uvst[q].z);
                batch.t[i] = static_cast<float>(uvst[q].w);
            }
        }
    }
    const auto& lights = job.shaders.lights_of[prim_index];
    const auto& coshaders = job.shaders.coshaders_of[prim_index];
    context.execute(shader, batch, LightList(lights.data(), lights.size()),
                    CoshaderList(coshaders.data(), coshaders.size()));
    job.nan_points += context.nonfinite_points();

    std::vector<std::vector<float>> aov_values(job.aovs.size());
    std::vector<char> has(job.aovs.size(), 0);
    shader_aovs(context, job.aovs, aov_values, has);
    // The atmosphere between the eye and the hit, after the surface (and
    // after its AOVs were read: they are the surface's).
    if (const ShaderInstance* atmosphere = job.shaders.atmosphere_of[prim_index])
        run_atmosphere(job, context, *atmosphere, batch, r,
                       LightList(lights.data(), lights.size()));
    const std::size_t floats = std::size_t(point_floats(job));
    for (std::size_t k = 0; k < n; ++k) {
        float* o = out + k * floats;
        for (int c = 0; c < 3; ++c) {
            o[c] = batch.Ci[k * r][c];
            o[3 + c] = batch.Oi[k * r][c];
        }
        o += 6;
        for (std::size_t a = 0; a < job.aovs.size(); ++a) {
            const Aov& aov = job.aovs[a];
            for (int c = 0; c < aov.floats; ++c)
                o[c] = has[a] ? aov_values[a][k * r * std::size_t(aov.floats) + c]
                              : aov.fallback;
            o += aov.floats;
        }
    }
}

/// Composites a shaded point's values (point_floats()) into its sample,
/// behind what the sample holds (front to back).
void composite(const Renderer& job, CameraSample& cs, float* v, float depth,
               const float* point) {
    const glm::dvec3 ci(point[0], point[1], point[2]);
    const glm::dvec3 oi = glm::clamp(glm::dvec3(point[3], point[4], point[5]), 0.0, 1.0);
    if (job.opaque_depth ? std::isinf(cs.depth) && oi.x >= job.zthreshold.x &&
                               oi.y >= job.zthreshold.y && oi.z >= job.zthreshold.z
                         : cs.layers == 0)
        cs.depth = depth;
    const glm::dvec3 w = cs.trans;
    for (int c = 0; c < 3; ++c) v[c] += static_cast<float>(w[c] * ci[c]);
    const double coverage = (w.x * oi.x + w.y * oi.y + w.z * oi.z) / 3.0;
    const float* x = point + 6;
    for (const Aov& aov : job.aovs) {
        float* dst = v + aov.offset;
        if (aov.floats == 3) {
            for (int c = 0; c < 3; ++c)
                dst[c] += static_cast<float>(w[c] * static_cast<double>(x[c]));
        } else {
            const float add = static_cast<float>(coverage * static_cast<double>(x[0]));
            dst[0] += add;
            if (aov.as_rgb) dst[1] += add, dst[2] += add;
        }
        x += aov.floats;
    }
    cs.trans *= 1.0 - oi;
    ++cs.layers;
    if (std::max({cs.trans.x, cs.trans.y, cs.trans.z}) < kOpaque) cs.active = false;
}

/// The batches of hits sorted by primitive: [begin, end) of one primitive,
/// at most kBatch long.
constexpr std::size_t kBatch = 256;
template <class Each>
void for_batches(const std::vector<SurfaceHit>& hits, Each&& each) {
    std::size_t begin = 0;
    while (begin < hits.size()) {
        std::size_t end = begin;
        while (end < hits.size() && end - begin < kBatch &&
               hits[end].primitive == hits[begin].primitive)
            ++end;
        each(begin, end);
        begin = end;
    }
}

} // namespace

void trace_pass(const Renderer& job, std::vector<CameraSample>& samples,
                std::vector<SurfaceHit>& hits, uint64_t& camera_count) {
    hits.clear();
    // Continuing past a hit: far enough to leave its triangle behind, near
    // enough not to skip a surface behind it.
    const float skip_base = static_cast<float>(1e-6 * job.extent);
    for (std::size_t s = 0; s < samples.size(); ++s) {
        CameraSample& cs = samples[s];
        if (!cs.active) continue;
        ShadowRay& ray = cs.ray;
        if (!(ray.tnear <= ray.tfar) || cs.hits >= kMaxHits || cs.layers >= kMaxLayers) {
            cs.active = false;
            continue;
        }
        const RayHit hit = job.camera_tracer->intersect(ray);
        ++camera_count;
        ++cs.hits;
        if (!hit.hit) {
            cs.active = false;
            continue;
        }
        ray.tnear = hit.t + skip_base + 1e-6f * hit.t;
        SurfaceHit h;
        if (!fill_hit(job, job.camera_primitive[hit.mesh], hit.triangle, hit.u, hit.v,
                      glm::dvec3(hit.geometric_normal), glm::dvec3(ray.direction), hit.t,
                      cs.units, ray.time, h, !job.shading_cache))
            continue;
        h.sample = static_cast<uint32_t>(s);
        h.seed = detail::splitmix64(cs.key ^
                                    (0xA5A5A5A5ull + static_cast<uint64_t>(cs.layers)));
        hits.push_back(h);
    }
}

void shade_pass(Renderer& job, ShadingContext& context, std::vector<SurfaceHit>& hits,
                std::vector<CameraSample>& samples, std::vector<float>& values) {
    std::stable_sort(hits.begin(), hits.end(),
                     [](const SurfaceHit& a, const SurfaceHit& b) {
                         return a.primitive < b.primitive;
                     });
    const std::size_t floats = std::size_t(point_floats(job));
    std::vector<float> shaded;
    std::vector<glm::dvec3> origins;
    for_batches(hits, [&](std::size_t begin, std::size_t end) {
        const std::size_t n = end - begin;
        origins.resize(n);
        for (std::size_t k = 0; k < n; ++k)
            origins[k] = glm::dvec3(samples[hits[begin + k].sample].ray.origin);
        shaded.resize(n * floats);
        shade_batch(job, context, &hits[begin], origins.data(), n, shaded.data());
        for (std::size_t k = 0; k < n; ++k) {
            const SurfaceHit& h = hits[begin + k];
            composite(job, samples[h.sample], &values[std::size_t(h.sample) * job.values],
                      h.depth, &shaded[k * floats]);
        }
    });
}

namespace {

/// Cells per edge of triangle `triangle` of primitive `prim` (k: k^2 cells):
/// cells of about ShadingRate square pixels (a micropolygon's area) by the
/// triangle's area on the screen (the surface at shutter open), at least 1
/// and at most kMaxLattice. A triangle partly behind the eye is measured in
/// the world at its centroid's depth.
constexpr int kMaxLattice = 64;
int lattice_size(const Renderer& job, uint32_t prim, uint32_t triangle) {
    const DicedSurface& d = job.surfaces[prim].diced;
    const uint32_t* tri = &d.triangles[3 * std::size_t(triangle)];
    const glm::dvec3 v[3] = {glm::dvec3(d.vertices[tri[0]]),
                             glm::dvec3(d.vertices[tri[1]]),
                             glm::dvec3(d.vertices[tri[2]])};
    double area = 0.0; // square pixels
    glm::dvec2 r[3];
    bool projected = true;
    for (int i = 0; i < 3; ++i) {
        const glm::dvec4 ndc = job.world_to_ndc * glm::dvec4(v[i], 1.0);
        if (!(ndc.w > 0.0)) {
            projected = false;
            break;
        }
        r[i] =
            glm::dvec2(ndc.x / ndc.w * job.camera.xres, ndc.y / ndc.w * job.camera.yres);
    }
    if (projected) {
        const glm::dvec2 a = r[1] - r[0], b = r[2] - r[0];
        area = 0.5 * std::abs(a.x * b.y - a.y * b.x);
    } else {
        const glm::dvec3 c = (v[0] + v[1] + v[2]) / 3.0;
        const double depth = (job.camera.world_to_camera * glm::dvec4(c, 1.0)).z;
        const double pixel = job.camera.perspective
                                 ? job.pixel_per_depth * std::max(depth, 1e-12)
                                 : job.pixel_per_depth;
        area = 0.5 * glm::length(glm::cross(v[1] - v[0], v[2] - v[0])) / (pixel * pixel);
    }
    const double rate =
        std::max(attributes_of(job.scene->primitives[prim]).shading_rate, 1e-6);
    const double k = std::ceil(std::sqrt(area / rate) - 1e-9);
    return std::isfinite(k) ? int(std::clamp(k, 1.0, double(kMaxLattice))) : 1;
}

/// The shading point (barycentrics b1, b2) of triangle `triangle` seen from
/// the camera as at shutter open through its pinhole (the lens's centre):
/// its hit, and the eye it is seen from. False where fill_hit() would not
/// shade it, or off the camera's projection.
bool lattice_hit(const Renderer& job, uint32_t prim, uint32_t triangle, double b1,
                 double b2, SurfaceHit& h, glm::dvec3& origin) {
    const DicedSurface& d = job.surfaces[prim].diced;
    const uint32_t* tri = &d.triangles[3 * std::size_t(triangle)];
    const glm::dvec3 v0(d.vertices[tri[0]]), v1(d.vertices[tri[1]]),
        v2(d.vertices[tri[2]]);
    const glm::dvec3 p = (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2;
    const glm::dvec4 ndc = job.world_to_ndc * glm::dvec4(p, 1.0);
    if (!(ndc.w > 0.0)) return false;
    const double x = ndc.x / ndc.w * job.camera.xres, y = ndc.y / ndc.w * job.camera.yres;
    if (!std::isfinite(x) || !std::isfinite(y)) return false;
    double units = 1.0;
    const ShadowRay ray = job.rays->ray(x, y, glm::dvec2(0.0), &units);
    origin = glm::dvec3(ray.origin);
    const glm::dvec3 dir = glm::normalize(p - origin);
    if (!std::isfinite(dir.x)) return false;
    const double t = glm::dot(p - origin, glm::dvec3(ray.direction));
    return fill_hit(job, prim, triangle, b1, b2, glm::cross(v1 - v0, v2 - v0), dir,
                    std::max(t, 0.0), units, 0.0f, h, true, true);
}

/// The key of lattice point (i, j) (barycentrics i / k, j / k) of triangle
/// `triangle` (vertices tri): a corner is its mesh vertex and a point on an
/// edge is keyed by the edge and its fraction in lowest terms from the
/// edge's lower vertex, so that the triangles around them share them.
ShadingCache::Key lattice_key(uint32_t prim, uint32_t triangle, const uint32_t* tri,
                              int i, int j, int k) {
    const int b0 = k - i - j; // the weight of vertex 0, in k-ths
    if (i == k) return {prim, 1u << 30, tri[1], 0};
    if (j == k) return {prim, 1u << 30, tri[2], 0};
    if (b0 == k) return {prim, 1u << 30, tri[0], 0};
    // On an edge: the fraction n / k of the way from vertex `from` to `to`.
    uint32_t from = 0, to = 0;
    int n = 0;
    if (j == 0)
        from = tri[0], to = tri[1], n = i;
    else if (i == 0)
        from = tri[0], to = tri[2], n = j;
    else if (b0 == 0)
        from = tri[1], to = tri[2], n = j;
    else
        return {prim, 3u << 30, triangle, uint32_t(i) << 16 | uint32_t(j)};
    int den = k;
    if (from > to) std::swap(from, to), n = den - n;
    const int g = std::gcd(n, den);
    n /= g, den /= g;
    return {prim, 2u << 30 | uint32_t(n) << 15 | uint32_t(den), from, to};
}

/// A sample's hit as up to three cached points and their weights; count 0:
/// the hit is shaded on its own (its lattice point could not be).
struct CachedRef {
    uint32_t slot[3] = {0, 0, 0};
    float weight[3] = {0, 0, 0};
    int count = 0;
};

/// The points a pass must shade: new lattice points, and hits whose own
/// lattice point is not seen; each with its eye and its slot in the cache.
struct Pending {
    std::vector<SurfaceHit> hits;
    std::vector<glm::dvec3> origins;
    std::vector<uint32_t> slots;
};

/// A new slot at the end of the cache's values.
uint32_t new_slot(ShadingCache& cache, std::size_t floats) {
    const auto slot = uint32_t(cache.values.size() / floats);
    cache.values.resize(cache.values.size() + floats, 0.0f);
    return slot;
}

/// The slot of lattice point `key` at barycentrics (b1, b2) of triangle
/// `tri`, queued in `pending` when new; false where it cannot be seen.
bool lattice_slot(const Renderer& job, ShadingCache& cache, std::size_t floats,
                  const ShadingCache::Key& key, uint32_t tri, double b1, double b2,
                  Pending& pending, uint32_t& slot) {
    if (auto it = cache.slot.find(key); it != cache.slot.end()) {
        slot = it->second;
        return slot != ShadingCache::kUnseen;
    }
    SurfaceHit h;
    glm::dvec3 origin;
    if (!lattice_hit(job, key.prim, tri, b1, b2, h, origin)) {
        cache.slot.emplace(key, ShadingCache::kUnseen);
        return false;
    }
    slot = new_slot(cache, floats);
    cache.slot.emplace(key, slot);
    h.seed = ShadingCache::KeyHash()(key) ^ 0x5EED5EEDull;
    pending.hits.push_back(h);
    pending.origins.push_back(origin);
    pending.slots.push_back(slot);
    return true;
}

/// The lattice points of hit h and their weights (count 0: one of them is not
/// seen, and the hit must be shaded on its own).
CachedRef lattice_ref(const Renderer& job, ShadingCache& cache, std::size_t floats,
                      const SurfaceHit& h, Pending& pending) {
    const uint64_t tri_key = uint64_t(h.primitive) << 32 | h.triangle;
    auto [kit, fresh] = cache.lattice.try_emplace(tri_key, 0);
    if (fresh) kit->second = lattice_size(job, h.primitive, h.triangle);
    const int k = kit->second;
    // (Barycentrics from the tracer; a non-finite one would make no cell.)
    const auto unit = [](float b) {
        return std::isfinite(b) ? std::clamp(double(b), 0.0, 1.0) : 0.0;
    };
    const double x = unit(h.b1) * k, y = unit(h.b2) * k;
    int ci = std::min(int(x), k - 1), cj = std::min(int(y), k - 1);
    if (ci + cj > k - 1) ci = k - 1 - cj; // on the far edge
    const double fx = x - ci, fy = y - cj;
    const bool upper = fx + fy > 1.0;
    CachedRef ref;
    if (!job.smooth_shading[h.primitive]) {
        // The cell's centroid.
        const double o = upper ? 2.0 / 3.0 : 1.0 / 3.0;
        const ShadingCache::Key key{h.primitive, 0, h.triangle,
                                    (uint32_t(ci) << 16 | uint32_t(cj)) << 1 |
                                        (upper ? 1u : 0u)};
        ref.weight[0] = 1.0f;
        ref.count = lattice_slot(job, cache, floats, key, h.triangle, (ci + o) / k,
                                 (cj + o) / k, pending, ref.slot[0])
                        ? 1
                        : 0;
        return ref;
    }
    // The cell's corners, blended linearly at the hit.
    int vi[3], vj[3];
    double w[3];
    if (!upper) {
        vi[0] = ci, vj[0] = cj, w[0] = 1.0 - fx - fy;
        vi[1] = ci + 1, vj[1] = cj, w[1] = fx;
        vi[2] = ci, vj[2] = cj + 1, w[2] = fy;
    } else {
        vi[0] = ci + 1, vj[0] = cj + 1, w[0] = fx + fy - 1.0;
        vi[1] = ci, vj[1] = cj + 1, w[1] = 1.0 - fx;
        vi[2] = ci + 1, vj[2] = cj, w[2] = 1.0 - fy;
    }
    const uint32_t* tri =
        &job.surfaces[h.primitive].diced.triangles[3 * std::size_t(h.triangle)];
    for (int c = 0; c < 3; ++c) {
        const ShadingCache::Key key =
            lattice_key(h.primitive, h.triangle, tri, vi[c], vj[c], k);
        if (!lattice_slot(job, cache, floats, key, h.triangle, double(vi[c]) / k,
                          double(vj[c]) / k, pending, ref.slot[c]))
            return CachedRef{};
        ref.weight[c] = static_cast<float>(w[c]);
    }
    ref.count = 3;
    return ref;
}

/// Queues hit h of `cs` to be shaded on its own, in a slot of its own.
uint32_t queue_hit(const Renderer& job, ShadingCache& cache, std::size_t floats,
                   const SurfaceHit& h, const CameraSample& cs, Pending& pending) {
    // Completed first: trace_pass kept only where it is (it accepted the hit
    // with the tracer's normal, which can only differ from this one in sign).
    SurfaceHit full = h;
    const DicedSurface& d = job.surfaces[h.primitive].diced;
    const uint32_t* tri = &d.triangles[3 * std::size_t(h.triangle)];
    const glm::dvec3 v0(d.vertex_at(tri[0], h.time)), v1(d.vertex_at(tri[1], h.time)),
        v2(d.vertex_at(tri[2], h.time));
    fill_hit(job, h.primitive, h.triangle, h.b1, h.b2, glm::cross(v1 - v0, v2 - v0),
             glm::dvec3(cs.ray.direction), double(h.depth) * cs.units, cs.units, h.time,
             full);
    full.sample = h.sample;
    full.seed = h.seed;
    const uint32_t slot = new_slot(cache, floats);
    pending.hits.push_back(full);
    pending.origins.push_back(glm::dvec3(cs.ray.origin));
    pending.slots.push_back(slot);
    return slot;
}

} // namespace

void shade_pass_cached(Renderer& job, ShadingContext& context,
                       std::vector<SurfaceHit>& hits, std::vector<CameraSample>& samples,
                       std::vector<float>& values, ShadingCache& cache) {
    const std::size_t floats = std::size_t(point_floats(job));
    std::vector<CachedRef> refs(hits.size());
    Pending pending;
    for (std::size_t i = 0; i < hits.size(); ++i) {
        refs[i] = lattice_ref(job, cache, floats, hits[i], pending);
        if (refs[i].count == 0)
            refs[i].slot[0] =
                queue_hit(job, cache, floats, hits[i], samples[hits[i].sample], pending);
    }
    // Shade the new points, by primitive in batches.
    const std::size_t n_new = pending.hits.size();
    std::vector<uint32_t> order(n_new);
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return pending.hits[a].primitive < pending.hits[b].primitive;
    });
    std::vector<SurfaceHit> sorted(n_new);
    std::vector<glm::dvec3> origins(n_new);
    for (std::size_t i = 0; i < n_new; ++i) {
        sorted[i] = pending.hits[order[i]];
        origins[i] = pending.origins[order[i]];
    }
    std::vector<float> shaded;
    for_batches(sorted, [&](std::size_t begin, std::size_t end) {
        const std::size_t n = end - begin;
        shaded.resize(n * floats);
        shade_batch(job, context, &sorted[begin], &origins[begin], n, shaded.data());
        for (std::size_t k = 0; k < n; ++k)
            std::copy_n(
                &shaded[k * floats], floats,
                &cache.values[std::size_t(pending.slots[order[begin + k]]) * floats]);
    });
    job.shading_points += n_new;
    // Each sample takes its points' values.
    std::vector<float> point(floats);
    for (std::size_t i = 0; i < hits.size(); ++i) {
        const SurfaceHit& h = hits[i];
        const CachedRef& ref = refs[i];
        if (ref.count <= 1) {
            std::copy_n(&cache.values[std::size_t(ref.slot[0]) * floats], floats,
                        point.data());
        } else {
            std::fill(point.begin(), point.end(), 0.0f);
            for (int c = 0; c < ref.count; ++c) {
                const float* src = &cache.values[std::size_t(ref.slot[c]) * floats];
                for (std::size_t f = 0; f < floats; ++f)
                    point[f] += ref.weight[c] * src[f];
            }
        }
        composite(job, samples[h.sample], &values[std::size_t(h.sample) * job.values],
                  h.depth, point.data());
    }
}

} // namespace sss::render_detail

/// \file shaders.cpp
/// The renderer's built-in surface shaders (docs/render.md, "Shaders"):
/// defaultsurface, constant, matte, plastic, read_ssdiffusion and skin, with
/// RenderMan's ambient(), diffuse() and specular() over the lights of
/// lights.h, ray-traced ambient occlusion, and the _ssdiffusion lookups in
/// brick maps or point clouds.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "shading.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/hash.h"
#include "sss/util/math.h"

namespace sss::detail {

namespace {

/// Occlusion rays per shading point are capped: more only costs time.
constexpr int kMaxOcclusionSamples = 1024;
/// Lookups return at most this many floats (the .bkm format's own limit).
constexpr int kMaxLookupFloats = 1024;

bool ends_with_nocase(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    for (std::size_t i = 0; i < suffix.size(); ++i) {
        const char a = s[s.size() - suffix.size() + i];
        const char b = suffix[i];
        if (std::tolower(static_cast<unsigned char>(a)) != b) return false;
    }
    return true;
}

std::optional<ShaderKind> shader_kind(const std::string& name) {
    if (name == "constant") return ShaderKind::Constant;
    if (name == "matte") return ShaderKind::Matte;
    if (name == "plastic") return ShaderKind::Plastic;
    if (name == "read_ssdiffusion") return ShaderKind::ReadSsdiffusion;
    if (name == "skin") return ShaderKind::Skin;
    if (name == "defaultsurface") return ShaderKind::Default;
    return std::nullopt;
}

double finite_float(const ParamList& params, const char* name, double fallback) {
    const double v = params.get_float(name, fallback);
    if (!std::isfinite(v))
        throw ValueError(std::string("\"") + name + "\" is not finite");
    return v;
}

double non_negative(const ParamList& params, const char* name, double fallback) {
    const double v = finite_float(params, name, fallback);
    if (v < 0.0)
        throw ValueError(std::string("\"") + name + "\" must not be negative, got " +
                         std::to_string(v));
    return v;
}

glm::dvec3 finite_color(const ParamList& params, const char* name,
                        const glm::dvec3& fallback) {
    const glm::dvec3 v = params.get_vec3(name, fallback);
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw ValueError(std::string("\"") + name + "\" is not finite");
    return v;
}

/// Ka and Kd, with the shader's defaults.
void read_ka_kd(const ParamList& p, double ka, double kd, SurfaceShader& s) {
    s.ka = finite_float(p, "Ka", ka);
    s.kd = finite_float(p, "Kd", kd);
}

/// The highlight's roughness (shader's default) and specularcolor (white).
void read_highlight(const ParamList& p, double roughness, SurfaceShader& s) {
    s.roughness = finite_float(p, "roughness", roughness);
    s.specular_color = finite_color(p, "specularcolor", glm::dvec3(1.0));
}

/// Fills a shader's parameters from its Surface call (defaults as documented).
void read_parameters(const ShaderRef& ref, SurfaceShader& s) {
    const ParamList& p = ref.params;
    switch (s.kind) {
    case ShaderKind::Default:
        read_ka_kd(p, 0.2, 0.8, s);
        break;
    case ShaderKind::Constant:
        break;
    case ShaderKind::Matte:
        read_ka_kd(p, 1.0, 1.0, s);
        break;
    case ShaderKind::Plastic:
        read_ka_kd(p, 1.0, 0.5, s);
        s.ks = finite_float(p, "Ks", 0.5);
        read_highlight(p, 0.1, s);
        break;
    case ShaderKind::ReadSsdiffusion:
        read_ka_kd(p, 0.0, 0.0, s);
        break;
    case ShaderKind::Skin:
        read_ka_kd(p, 0.0, 0.3, s);
        s.ks_facing = finite_float(p, "Ksfacing", 0.05);
        s.ks_glancing = finite_float(p, "Ksglancing", 0.3);
        read_highlight(p, 0.2, s);
        s.sss_weight = finite_float(p, "sss_weight", finite_float(p, "Ksss", 1.0));
        s.sss_color = finite_color(p, "sss_color", glm::dvec3(1.0));
        break;
    }
    if (s.kind == ShaderKind::Plastic || s.kind == ShaderKind::Skin) {
        if (!(s.roughness > 0.0))
            throw ValueError("\"roughness\" must be > 0, got " +
                             std::to_string(s.roughness));
    }
    if (s.kind != ShaderKind::Constant && s.kind != ShaderKind::Default) {
        const double samples = non_negative(p, "occlusion_samples", 0.0);
        if (samples > kMaxOcclusionSamples || samples != std::floor(samples))
            throw ValueError("\"occlusion_samples\" must be a whole number in [0, " +
                             std::to_string(kMaxOcclusionSamples) + "], got " +
                             std::to_string(samples));
        s.occlusion_samples = static_cast<int>(samples);
        s.occlusion_maxdist = non_negative(p, "occlusion_maxdist", 0.0);
    }
    if (s.kind == ShaderKind::ReadSsdiffusion || s.kind == ShaderKind::Skin)
        s.filter_scale = non_negative(p, "filterscale", 1.0);
}

/// Fraction of `count` cosine-distributed rays about nf that escape within
/// maxdist. The directions are stratified (equal-weight rings, golden-angle
/// turns) and rotated and jittered by the seed.
double ambient_occlusion(const ShadingPoint& sp, const RayTracer& tracer, int count,
                         double maxdist) {
    // Tangent frame around nf (Duff et al. 2017).
    const glm::dvec3& w = sp.nf;
    const double sign = std::copysign(1.0, w.z);
    const double a = -1.0 / (sign + w.z);
    const double b = w.x * w.y * a;
    const glm::dvec3 t1(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x);
    const glm::dvec3 t2(b, sign + w.y * w.y * a, -w.y);

    const uint64_t h = splitmix64(sp.seed ^ 0x6f63636c75646521ull);
    const double rotation = unit_double(h);
    const glm::vec3 origin(sp.p + sp.nf * sp.ray_offset);
    const float tfar = maxdist > 0.0 ? static_cast<float>(maxdist)
                                     : std::numeric_limits<float>::infinity();
    constexpr int kBlock = 64;
    ShadowRay rays[kBlock];
    uint8_t hits[kBlock];
    int open = 0;
    for (int begin = 0; begin < count; begin += kBlock) {
        const int m = std::min(kBlock, count - begin);
        for (int i = 0; i < m; ++i) {
            const int k = begin + i;
            // Cosine-weighted: the squared radius on the unit disk is uniform.
            const double r2 =
                (k + unit_double(splitmix64(h + 1 + static_cast<uint64_t>(k)))) / count;
            double turn = rotation + k * 0.6180339887498949;
            turn -= std::floor(turn);
            const double phi = 2.0 * kPi * turn;
            const double r = std::sqrt(r2);
            const double z = std::sqrt(std::max(0.0, 1.0 - r2));
            const glm::dvec3 d = r * std::cos(phi) * t1 + r * std::sin(phi) * t2 + z * w;
            rays[i].origin = origin;
            rays[i].direction = glm::vec3(glm::normalize(d));
            rays[i].tnear = 0.0f;
            rays[i].tfar = tfar;
        }
        tracer.occluded(rays, static_cast<std::size_t>(m), hits);
        for (int i = 0; i < m; ++i) open += hits[i] ? 0 : 1;
    }
    return static_cast<double>(open) / count;
}

/// Shadow rays light_samples() traced for one returned (non-ambient) light.
uint64_t shadow_ray_count(const Light& l, const RayTracer* tracer) {
    if (!l.shadows || !tracer) return 0;
    return (l.samples > 1 && l.size > 0.0) ? static_cast<uint64_t>(l.samples) : 1u;
}

} // namespace

// ---------------------------------------------------------------------------
// Diffusion sources

DiffusionSource::DiffusionSource(const std::string& path, const std::string& channel,
                                 const std::string& where)
    : m_path(path) {
    const bool cloud = ends_with_nocase(path, ".ptc") || ends_with_nocase(path, ".ply");
    try {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path, ec))
            throw IoError(path, std::filesystem::exists(path, ec)
                                    ? "not a regular file"
                                    : "no such file or directory");
        if (cloud) {
            m_cloud = std::make_unique<PointCloud>(read_point_cloud(path));
            const Channel* c = m_cloud->find_channel(channel);
            if (!c) throw ValueError("has no channel '" + channel + "'");
            if (c->type != ChannelType::Float && c->type != ChannelType::Color)
                throw ValueError("channel '" + channel + "' is a " +
                                 channel_type_name(c->type) + ", not a color or float");
            m_components = c->components();
            m_offset = 0;
            m_cloud_lookup =
                std::make_unique<PointCloudLookup>(*m_cloud, std::vector{channel});
        } else {
            m_map = std::make_unique<BrickMap>(path);
            const BrickMapInfo& info = m_map->info();
            if (info.data_size > kMaxLookupFloats)
                throw ValueError("has " + std::to_string(info.data_size) +
                                 " floats per sample, more than the renderer reads");
            const int index = m_map->channel_index(channel);
            if (index < 0) {
                std::string names;
                for (const auto& [name, type] : info.channels)
                    names += (names.empty() ? "" : ", ") + name;
                throw ValueError("has no channel '" + channel + "' (it has: " + names +
                                 ")");
            }
            m_offset = m_map->channel_offset(channel);
            m_components = channel_type_size(info.channels[index].second);
        }
    } catch (const Error& e) {
        const std::string what = e.what();
        // Library messages already start with the file name.
        const std::string text = what.rfind(path, 0) == 0 ? what : path + ": " + what;
        throw Error(where + ": " + text);
    }
}

DiffusionSource::~DiffusionSource() = default;

bool DiffusionSource::lookup(const glm::vec3& p, const glm::vec3& n, float radius,
                             glm::vec3& out) const {
    float buf[kMaxLookupFloats];
    bool found = false;
    if (m_map) {
        found = m_map->lookup(p, n, radius, buf);
    } else {
        // Point clouds: a fixed radius may hold no point at all, so always the
        // nearest points (radius 0).
        found = m_cloud_lookup->lookup(p, n, 0.0f, buf);
    }
    if (!found) {
        out = glm::vec3(0.0f);
        return false;
    }
    if (m_components == 1)
        out = glm::vec3(buf[m_offset]);
    else
        out = glm::vec3(buf[m_offset], buf[m_offset + 1], buf[m_offset + 2]);
    return true;
}

// ---------------------------------------------------------------------------
// Resolving the scene's shaders

namespace {

/// A diffusion shader's "filename" with frame patterns expanded ("" if none).
std::string diffusion_file(const ShaderRef& ref, const std::string& where,
                           std::optional<int> frame) {
    std::string file;
    try {
        file = ref.params.get_string("filename", "");
    } catch (const ValueError& e) {
        throw ValueError(where + ": " + e.what());
    }
    return file.empty() ? file : expand_frame_pattern(file, frame, where + " filename");
}

} // namespace

std::vector<std::string> diffusion_files(const Scene& scene, std::optional<int> frame) {
    std::vector<std::string> files;
    for (const Primitive& prim : scene.primitives) {
        if (!prim.attributes || !prim.attributes->surface) continue;
        const ShaderRef& ref = *prim.attributes->surface;
        const std::optional<ShaderKind> kind = shader_kind(ref.name);
        if (kind != ShaderKind::ReadSsdiffusion && kind != ShaderKind::Skin) continue;
        const std::string where = (ref.source.empty() ? "" : ref.source + ": ") +
                                  "Surface \"" + ref.name + "\"";
        std::string file = diffusion_file(ref, where, frame);
        if (!file.empty() && std::find(files.begin(), files.end(), file) == files.end())
            files.push_back(std::move(file));
    }
    return files;
}

ShaderSet resolve_surface_shaders(const Scene& scene, std::optional<int> frame,
                                  std::vector<std::string>& warnings) {
    ShaderSet set;
    set.of_primitive.assign(scene.primitives.size(), -1);
    std::map<const ShaderRef*, int> by_ref;
    std::map<std::pair<std::string, std::string>, std::shared_ptr<const DiffusionSource>>
        sources;
    std::set<std::string> warned;
    int default_index = -1;

    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const Primitive& prim = scene.primitives[i];
        const ShaderRef* ref = prim.attributes && prim.attributes->surface
                                   ? &*prim.attributes->surface
                                   : nullptr;
        std::optional<ShaderKind> kind =
            ref ? shader_kind(ref->name) : ShaderKind::Default;
        if (ref && !kind) {
            if (warned.insert(ref->name).second)
                warnings.push_back((ref->source.empty() ? "" : ref->source + ": ") +
                                   "surface shader '" + ref->name +
                                   "' is not built in (constant, matte, plastic, "
                                   "read_ssdiffusion, skin); rendered with "
                                   "defaultsurface");
            ref = nullptr;
        }
        if (!ref) {
            if (default_index < 0) {
                default_index = static_cast<int>(set.shaders.size());
                SurfaceShader s;
                s.kind = ShaderKind::Default;
                s.where = "defaultsurface";
                s.ka = 0.2;
                s.kd = 0.8;
                set.shaders.push_back(std::move(s));
            }
            set.of_primitive[i] = default_index;
            continue;
        }
        auto found = by_ref.find(ref);
        if (found != by_ref.end()) {
            set.of_primitive[i] = found->second;
            continue;
        }

        SurfaceShader s;
        s.kind = *kind;
        s.where = (ref->source.empty() ? "" : ref->source + ": ") + "Surface \"" +
                  ref->name + "\"";
        try {
            read_parameters(*ref, s);
        } catch (const ValueError& e) {
            throw ValueError(s.where + ": " + e.what());
        }
        if (s.kind == ShaderKind::ReadSsdiffusion || s.kind == ShaderKind::Skin) {
            std::string channel;
            try {
                channel = ref->params.get_string("channel", "_ssdiffusion");
            } catch (const ValueError& e) {
                throw ValueError(s.where + ": " + e.what());
            }
            const std::string file = diffusion_file(*ref, s.where, frame);
            if (file.empty() && s.kind == ShaderKind::ReadSsdiffusion)
                throw ValueError(s.where +
                                 " has no \"filename\" (a .bkm brick map or a .ptc "
                                 "point cloud with " +
                                 channel + ")");
            if (!file.empty()) {
                auto key = std::make_pair(file, channel);
                auto it = sources.find(key);
                if (it == sources.end()) {
                    it = sources
                             .emplace(key, std::make_shared<const DiffusionSource>(
                                               file, channel, s.where))
                             .first;
                    if (std::find(set.files.begin(), set.files.end(), file) ==
                        set.files.end())
                        set.files.push_back(file);
                }
                s.diffusion = it->second;
            }
        }
        const int index = static_cast<int>(set.shaders.size());
        set.shaders.push_back(std::move(s));
        by_ref.emplace(ref, index);
        set.of_primitive[i] = index;
    }
    return set;
}

// ---------------------------------------------------------------------------
// Shading

void shade(const SurfaceShader& shader, const ShadingPoint& sp, const ShadingEnv& env,
           ShadeResult& out) {
    out = ShadeResult{};
    const glm::dvec3& cs = sp.cs;
    if (shader.kind == ShaderKind::Constant) {
        out.emission = cs;
        return;
    }
    if (shader.kind == ShaderKind::Default) {
        // RenderMan's defaultsurface: a headlight, no light sources.
        out.diffuse = cs * (shader.ka + shader.kd * std::abs(glm::dot(sp.n, sp.v)));
        return;
    }

    // ambient(), diffuse(Nf) and specular(Nf, V, roughness) in one illuminance loop.
    const bool wants_specular =
        shader.kind == ShaderKind::Plastic || shader.kind == ShaderKind::Skin;
    glm::dvec3 ambient(0.0), diffuse(0.0), specular(0.0);
    std::vector<LightSample>& lights = *env.scratch;
    light_samples(*env.lights, *env.active, sp.p, sp.nf, env.occluders, sp.seed,
                  sp.ray_offset, lights);
    const double exponent = wants_specular ? 1.0 / shader.roughness : 0.0;
    for (const LightSample& l : lights) {
        if (l.ambient) {
            ambient += l.color;
            continue;
        }
        out.rays += shadow_ray_count((*env.lights)[l.light], env.occluders);
        diffuse += l.color * glm::dot(sp.nf, l.direction);
        if (wants_specular) {
            const glm::dvec3 h = l.direction + sp.v;
            const double len = glm::length(h);
            if (len > 0.0) {
                const double c = glm::dot(sp.nf, h) / len;
                if (c > 0.0) specular += l.color * std::pow(c, exponent);
            }
        }
    }

    double occlusion = 1.0;
    if (shader.occlusion_samples > 0 && env.occluders) {
        occlusion = ambient_occlusion(sp, *env.occluders, shader.occlusion_samples,
                                      shader.occlusion_maxdist);
        out.rays += static_cast<uint64_t>(shader.occlusion_samples);
    }
    out.occlusion = occlusion;

    glm::dvec3 ssd(0.0);
    if (shader.diffusion) {
        glm::vec3 value;
        shader.diffusion->lookup(
            glm::vec3(sp.p), glm::vec3(sp.n),
            static_cast<float>(sp.filter_radius * shader.filter_scale), value);
        // Blockers bake negative light: where they outweigh the light that
        // diffuses past them the result is no light, not negative light.
        ssd = glm::max(glm::dvec3(value), glm::dvec3(0.0));
    }

    switch (shader.kind) {
    case ShaderKind::Matte:
        out.ambient = cs * (shader.ka * occlusion) * ambient;
        out.diffuse = cs * shader.kd * diffuse;
        break;
    case ShaderKind::Plastic:
        out.ambient = cs * (shader.ka * occlusion) * ambient;
        out.diffuse = cs * shader.kd * diffuse;
        out.specular = shader.specular_color * shader.ks * specular;
        break;
    case ShaderKind::ReadSsdiffusion:
        out.ambient = cs * (shader.ka * occlusion) * ambient;
        out.diffuse = cs * shader.kd * diffuse;
        out.sss = cs * ssd;
        break;
    case ShaderKind::Skin: {
        const double facing = std::max(0.0, glm::dot(sp.nf, sp.v));
        const double ks =
            shader.ks_glancing + (shader.ks_facing - shader.ks_glancing) * facing;
        out.ambient = cs * (shader.ka * occlusion) * ambient;
        out.diffuse = cs * (shader.kd * occlusion) * diffuse;
        out.specular = shader.specular_color * ks * specular;
        out.sss = shader.sss_weight * shader.sss_color * ssd;
        break;
    }
    case ShaderKind::Constant:
    case ShaderKind::Default:
        break;
    }
}

} // namespace sss::detail

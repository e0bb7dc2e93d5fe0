// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file scene_shaders.cpp
/// Binding a scene's Surface, Displacement, LightSource, Atmosphere,
/// Interior, Exterior and Imager calls to compiled shaders (scene_shaders.h).

#include "sss/binding/scene_shaders.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <system_error>

#include "sss/binding/texture_library.h"
#include "sss/rsl/builtins.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/messages.h"

namespace sss {

namespace {

/// The call's parameters with frame patterns in strings expanded; strings
/// that are not valid patterns ("50%") stay as they are.
ParamList expand_strings(const ParamList& params, std::optional<int> frame,
                         const std::string& where) {
    ParamList out = params;
    for (Param& p : out.items) {
        if (p.type != ParamType::String) continue;
        for (std::string& s : p.strings) {
            if (s.find_first_of("%#$") == std::string::npos) continue;
            try {
                s = expand_frame_pattern(s, frame, where + " " + sss::quoted(p.name));
            } catch (const MissingFrameError&) {
                throw;
            } catch (const Error&) {
                // Not a frame pattern: left alone.
            }
        }
    }
    return out;
}

/// A name with the extension of a file shaders read (maps, clouds, images).
bool looks_like_file(const std::string& v) {
    static const char* const extensions[] = {".bkm",  ".ptc", ".ply", ".tx",
                                             ".tex",  ".exr", ".png", ".tif",
                                             ".tiff", ".jpg", ".hdr", ".slo"};
    std::string ext = std::filesystem::path(v).extension().string();
    for (char& c : ext)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (const char* e : extensions)
        if (ext == e) return true;
    return false;
}

std::string call_where(const ShaderRef& ref, const char* request) {
    return (ref.source.empty() ? std::string() : ref.source + ": ") + request + " " +
           sss::quoted(ref.name);
}

} // namespace

bool program_uses(const Program& program, std::string_view op) {
    return std::any_of(program.ops.begin(), program.ops.end(),
                       [&](const Op& o) { return o.name == op; });
}

bool program_reads_parametric(const Program& program) {
    static const char* const names[] = {"u", "v", "s", "t", "du", "dv", "dPdu", "dPdv"};
    for (const Symbol& sym : program.symbols)
        if (sym.kind == SymbolKind::Global &&
            std::find_if(std::begin(names), std::end(names),
                         [&](const char* n) { return sym.name == n; }) != std::end(names))
            return true;
    return program_uses(program, "texture");
}

bool program_uses_derivatives(const Program& program) {
    for (const Op& o : program.ops) {
        // area(P, "dicing") is the micropolygon's own area: no neighbours.
        if (o.name == "area" && o.args.size() == 3) {
            const Symbol& space = program.symbols[static_cast<std::size_t>(o.args[2])];
            if (space.kind == SymbolKind::Const && space.strings.size() == 1 &&
                space.strings[0] == "dicing")
                continue;
        }
        for (const detail::BuiltinSignature& sig : detail::builtin_signatures())
            if (sig.derivatives && o.name == sig.name) return true;
    }
    return false;
}

bool SceneShaders::uses(std::string_view op) const {
    for (const auto* list : {&surfaces, &displacements, &volumes, &lights, &coshaders})
        for (const auto& s : *list)
            if (program_uses(s->program(), op)) return true;
    return imager && program_uses(imager->program(), op);
}

std::optional<std::string> unlit_scene_warning(const Scene& scene,
                                               const SceneShaders& shaders) {
    if (!scene.lights.empty()) return std::nullopt;
    std::vector<std::string> names;
    for (const auto& s : shaders.surfaces) {
        const Program& p = s->program();
        bool reads = false;
        for (const char* op :
             {"ambient", "diffuse", "specular", "phong", "specularbrdf", "illuminance"})
            reads = reads || program_uses(p, op);
        if (reads && std::find(names.begin(), names.end(), p.name) == names.end())
            names.push_back(p.name);
    }
    if (names.empty()) return std::nullopt;
    std::string list;
    for (std::size_t i = 0; i < names.size() && i < 4; ++i)
        list += (i ? ", " : "") + names[i];
    if (names.size() > 4) list += ", ...";
    return (scene.path.empty() ? std::string("the scene") : scene.path) +
           ": no light sources: the surfaces shaded by " + list +
           " gather light from none and are black but for what they emit";
}

std::vector<std::string> shader_search_path(const Scene& scene) {
    return resolve_shader_search_path(search_path(scene, "shader"));
}

void run_make_requests(const Scene& scene, bool after_frame) {
    std::optional<TextureLibrary> maker;
    for (const MakeRequest& m : scene.makes) {
        if (m.after_frame != after_frame) continue;
        if (!maker) maker.emplace();
        const std::string where = m.source + ": " + m.kind;
        if (m.kind == "MakeShadow") {
            maker->make_shadow(m.input, m.output, where);
        } else if (m.kind == "MakeCubeFaceEnvironment") {
            std::array<std::string, 6> faces;
            for (std::size_t k = 0; k < faces.size() && k < m.faces.size(); ++k)
                faces[k] = m.faces[k];
            maker->make_cube_environment(faces, m.output, m.fov, m.filter, where);
        } else {
            TextureLibrary::Make t;
            t.latlong = m.kind == "MakeLatLongEnvironment";
            t.input = m.input;
            t.output = m.output;
            t.swrap = m.swrap;
            t.twrap = m.twrap;
            t.filter = m.filter;
            maker->make_texture(t, where);
        }
    }
}

SceneShaders bind_scene_shaders(const Scene& scene, std::optional<int> frame,
                                bool image) {
    // The textures the RIB makes come before any shader looks one up.
    run_make_requests(scene, false);
    SceneShaders out;
    out.library = std::make_unique<ShaderLibrary>(shader_search_path(scene));
    ShaderLibrary& library = *out.library;

    for (const LightInstance& light : scene.lights) {
        const std::string where =
            call_where(light.shader, light.area ? "AreaLightSource" : "LightSource");
        auto program = library.load(light.shader.name, ShaderKind::Light, where);
        out.lights.push_back(std::make_unique<ShaderInstance>(
            program, expand_strings(light.shader.params, frame, where),
            light.shader.shader_to_world, where, &out.warnings));
        out.lights.back()->set_handle(light.handle); // getlight("handle")
    }

    if (image && scene.options.imager) {
        const ShaderRef& ref = *scene.options.imager;
        const std::string where = call_where(ref, "Imager");
        auto program = library.load(ref.name, ShaderKind::Imager, where);
        out.imager = std::make_unique<ShaderInstance>(
            program, expand_strings(ref.params, frame, where), ref.shader_to_world, where,
            &out.warnings);
    }

    std::map<const ShaderRef*, const ShaderInstance*> by_ref;
    std::map<const ShaderRef*, const ShaderInstance*> volume_by_ref;
    // One instance per Atmosphere, Interior or Exterior call.
    const auto volume = [&](const std::optional<ShaderRef>& ref,
                            const char* request) -> const ShaderInstance* {
        if (!ref) return nullptr;
        if (auto it = volume_by_ref.find(&*ref); it != volume_by_ref.end())
            return it->second;
        const std::string where = call_where(*ref, request);
        auto program = library.load(ref->name, ShaderKind::Volume, where);
        out.volumes.push_back(std::make_unique<ShaderInstance>(
            program, expand_strings(ref->params, frame, where), ref->shader_to_world,
            where, &out.warnings));
        volume_by_ref.emplace(&*ref, out.volumes.back().get());
        return out.volumes.back().get();
    };
    out.atmosphere_of.resize(scene.primitives.size(), nullptr);
    out.interior_of.resize(scene.primitives.size(), nullptr);
    out.exterior_of.resize(scene.primitives.size(), nullptr);
    std::map<const ShaderRef*, const ShaderInstance*> displacement_by_ref;
    std::set<const ShaderInstance*> overridden; // class displacements warned about
    std::map<const Attributes*, std::size_t> lights_by_attributes;
    const ShaderInstance* fallback = nullptr;
    out.surface_of.resize(scene.primitives.size(), nullptr);
    out.displacement_of.resize(scene.primitives.size(), nullptr);
    out.lights_of.resize(scene.primitives.size());
    out.coshaders_of.resize(scene.primitives.size());
    std::map<const ShaderRef*, const ShaderInstance*> coshader_by_ref;
    const auto coshader = [&](const CoshaderRef& c) -> const ShaderInstance* {
        if (auto it = coshader_by_ref.find(&c.shader); it != coshader_by_ref.end())
            return it->second;
        const std::string where = call_where(c.shader, "Shader");
        auto program = library.load_any(c.shader.name, where);
        out.coshaders.push_back(std::make_unique<ShaderInstance>(
            program, expand_strings(c.shader.params, frame, where),
            c.shader.shader_to_world, where, &out.warnings));
        out.coshaders.back()->set_handle(c.handle);
        coshader_by_ref.emplace(&c.shader, out.coshaders.back().get());
        return out.coshaders.back().get();
    };
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const Primitive& prim = scene.primitives[i];
        const Attributes& attr = attributes_of(prim);
        const ShaderRef* ref = attr.surface ? &*attr.surface : nullptr;
        if (!ref) {
            if (!fallback) {
                const std::string where = "defaultsurface";
                auto program = library.load("defaultsurface", ShaderKind::Surface, where);
                out.surfaces.push_back(std::make_unique<ShaderInstance>(
                    program, ParamList{}, Matrix4(1.0), where, &out.warnings));
                fallback = out.surfaces.back().get();
            }
            out.surface_of[i] = fallback;
        } else if (auto it = by_ref.find(ref); it != by_ref.end()) {
            out.surface_of[i] = it->second;
        } else {
            const std::string where = call_where(*ref, "Surface");
            auto program = library.load(ref->name, ShaderKind::Surface, where);
            out.surfaces.push_back(std::make_unique<ShaderInstance>(
                program, expand_strings(ref->params, frame, where), ref->shader_to_world,
                where, &out.warnings));
            out.surface_of[i] = out.surfaces.back().get();
            by_ref.emplace(ref, out.surface_of[i]);
        }
        const ShaderInstance* surface = out.surface_of[i];
        const bool displaces = surface->program().is_class() &&
                               surface->program().runs_as(ShaderKind::Displacement);
        if (displaces && !attr.displacement) {
            // An RSL 2.0 class with a displacement method displaces the
            // surfaces it shades (PRMan runs it at displacement time).
            out.displacement_of[i] = surface;
        } else if (attr.displacement) {
            if (displaces && overridden.insert(surface).second)
                out.warnings.push_back(
                    surface->where() + ": the displacement method of '" +
                    surface->program().name +
                    "' is not run: the primitive's Displacement " +
                    sss::quoted(attr.displacement->name) + " displaces it");
            const ShaderRef* d = &*attr.displacement;
            if (auto it = displacement_by_ref.find(d); it != displacement_by_ref.end()) {
                out.displacement_of[i] = it->second;
            } else {
                const std::string where = call_where(*d, "Displacement");
                auto program = library.load(d->name, ShaderKind::Displacement, where);
                out.displacements.push_back(std::make_unique<ShaderInstance>(
                    program, expand_strings(d->params, frame, where), d->shader_to_world,
                    where, &out.warnings));
                out.displacement_of[i] = out.displacements.back().get();
                displacement_by_ref.emplace(d, out.displacement_of[i]);
            }
        }
        if (image) out.atmosphere_of[i] = volume(attr.atmosphere, "Atmosphere");
        out.interior_of[i] = volume(attr.interior, "Interior");
        out.exterior_of[i] = volume(attr.exterior, "Exterior");
        if (out.interior_of[i] || out.exterior_of[i]) out.any_interior_exterior = true;
        for (int l : attr.lights_on)
            if (l >= 0 && static_cast<std::size_t>(l) < out.lights.size())
                out.lights_of[i].push_back(out.lights[static_cast<std::size_t>(l)].get());
        for (const CoshaderRef& c : attr.coshaders)
            out.coshaders_of[i].push_back(coshader(c));
    }
    return out;
}

void record_shader_inputs(JobFiles& files, const SceneShaders& shaders) {
    const auto add = [&](const ShaderInstance& s) {
        const bool bakes = program_uses(s.program(), "bake3d");
        for (const ShaderArgument& a : s.arguments()) {
            if (bakes && a.name == "filename") continue;
            for (const std::string& v : a.strings) {
                std::error_code ec;
                if (v.empty() || !std::filesystem::is_regular_file(v, ec)) continue;
                files.input(
                    v,
                    "parameter " + sss::quoted(a.name) + " " + sss::quoted(v) + " of " +
                        (s.where().empty() ? sss::quoted(s.program().name) : s.where()));
            }
        }
    };
    for (const auto* list : {&shaders.surfaces, &shaders.displacements, &shaders.volumes,
                             &shaders.lights, &shaders.coshaders})
        for (const auto& s : *list) add(*s);
    if (shaders.imager) add(*shaders.imager);
    if (shaders.library)
        for (const std::string& f : shaders.library->files())
            files.input(f, "the shader file \"" + f + "\"");
}

std::vector<std::string> shader_input_files(const SceneShaders& shaders) {
    std::vector<std::string> files;
    const auto add = [&](const ShaderInstance& s) {
        for (const ShaderArgument& a : s.arguments())
            for (const std::string& v : a.strings) {
                std::error_code ec;
                if (v.empty()) continue;
                if (!std::filesystem::is_regular_file(v, ec) && !looks_like_file(v))
                    continue;
                if (std::find(files.begin(), files.end(), v) == files.end())
                    files.push_back(v);
            }
    };
    for (const auto* list : {&shaders.surfaces, &shaders.displacements, &shaders.volumes,
                             &shaders.lights, &shaders.coshaders})
        for (const auto& s : *list) add(*s);
    if (shaders.imager) add(*shaders.imager);
    if (shaders.library)
        for (const std::string& f : shaders.library->files())
            if (std::find(files.begin(), files.end(), f) == files.end())
                files.push_back(f);
    return files;
}

} // namespace sss

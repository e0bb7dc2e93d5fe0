// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Helpers of the shading engine tests: a ShadingServices that records what
// shaders send, RSL compiled from text, and batches of points.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/light/ray_tracer.h"
#include "sss/rsl/compiler.h"
#include "sss/scene/scene.h"
#include "sss/shading/engine.h"

namespace sss::test {

/// Records messages, warnings and bake3d records; textures through
/// `texture_services` (none by default: every lookup fails).
class RecordingServices : public ShadingServices {
public:
    Scene scene_;
    const RayTracer* tracer = nullptr;
    std::vector<std::string> messages;
    std::vector<std::string> warnings;
    std::vector<Bake3dRecord> bakes;
    TextureServices* texture_services = nullptr;

    const Scene& scene() const override { return scene_; }
    const RayTracer* occluders() const override { return tracer; }
    TextureServices* textures() override { return texture_services; }
    void bake3d(Bake3dRecord&& record) override { bakes.push_back(std::move(record)); }
    void message(const std::string& text) override { messages.push_back(text); }
    void warning(const std::string& text) override { warnings.push_back(text); }
};

/// The only shader of `source`, compiled (the test fails on errors).
inline std::shared_ptr<const Program> compile_shader(const std::string& source) {
    try {
        CompileResult r = compile_text(source, "test.sl");
        if (r.shaders.size() != 1) {
            ADD_FAILURE() << "expected one shader, got " << r.shaders.size();
            return std::make_shared<Program>();
        }
        return std::make_shared<Program>(std::move(r.shaders[0]));
    } catch (const ShaderCompileError& e) {
        std::string all;
        for (const Diagnostic& d : e.diagnostics()) all += d.format() + "\n";
        ADD_FAILURE() << "compile failed:\n" << all << "\nsource:\n" << source;
        return std::make_shared<Program>();
    }
}

/// A grid batch of nu x nv points on the plane z = 1 (camera space): u, v at
/// cell centres, s = u, t = v, N = Ng = (0, 0, -1) facing the eye.
inline ShadingBatch plane_grid(int nu, int nv) {
    ShadingBatch b;
    b.layout = BatchLayout::Grid;
    b.nu = nu;
    b.nv = nv;
    b.size = static_cast<std::size_t>(nu) * nv;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const float u = (i + 0.5f) / nu, v = (j + 0.5f) / nv;
            b.u.push_back(u);
            b.v.push_back(v);
            b.du.push_back(1.0f / nu);
            b.dv.push_back(1.0f / nv);
            b.P.push_back(glm::vec3(u - 0.5f, v - 0.5f, 1.0f));
            b.N.push_back(glm::vec3(0, 0, -1));
            b.Ng.push_back(glm::vec3(0, 0, -1));
            b.dPdu.push_back(glm::vec3(1, 0, 0));
            b.dPdv.push_back(glm::vec3(0, 1, 0));
        }
    b.s = b.u;
    b.t = b.v;
    b.I = b.P;
    return b;
}

/// One shading context with its services.
struct Engine {
    RecordingServices services;
    ShadingResources resources;
    ShadingContext context{resources, services};

    ShaderInstance instance(const std::string& source, const ParamList& params = {},
                            const Matrix4& shader_to_world = Matrix4(1.0)) {
        return ShaderInstance(compile_shader(source), params, shader_to_world,
                              "test.rib:1");
    }

    /// Runs a surface shader and returns the output parameter `name`.
    std::vector<float> run(const std::string& source, ShadingBatch& batch,
                           const std::string& name = "r", LightList lights = {}) {
        ShaderInstance inst = instance(source);
        context.execute(inst, batch, lights);
        TypeSpec type;
        std::vector<float> values;
        EXPECT_TRUE(context.output(name, type, values)) << name;
        return values;
    }
};

inline Param float_param(const std::string& name, double v) {
    Param p;
    p.name = name;
    p.type = ParamType::Float;
    p.numbers = {v};
    return p;
}

inline Param point_param(const std::string& name, const glm::dvec3& v,
                         ParamType type = ParamType::Point) {
    Param p;
    p.name = name;
    p.type = type;
    p.numbers = {v.x, v.y, v.z};
    return p;
}

inline Param string_param(const std::string& name, const std::string& v) {
    Param p;
    p.name = name;
    p.type = ParamType::String;
    p.strings = {v};
    return p;
}

/// environment(map, dir) through the shading engine for each direction,
/// point lookups ("width" 0; world = camera space here). No warnings.
inline std::vector<glm::vec3> environment_lookups(TextureServices& textures,
                                                  const std::string& map,
                                                  const std::vector<glm::vec3>& dirs) {
    Engine e;
    e.services.texture_services = &textures;
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = dirs.size();
    for (const glm::vec3& d : dirs) {
        b.P.push_back(glm::vec3(0.0f));
        b.N.push_back(d);
    }
    b.Ng = b.N;
    b.I = b.N;
    ParamList p;
    p.set(string_param("map", map));
    ShaderInstance inst = e.instance(R"(
surface t(string map = "";) {
    Ci = color environment(map, vector N, "width", 0);
    Oi = 1;
}
)",
                                     p);
    e.context.execute(inst, b);
    EXPECT_TRUE(e.services.warnings.empty());
    return b.Ci;
}

} // namespace sss::test

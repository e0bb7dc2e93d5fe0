/// \file corpus_test.cpp
/// The RSL acceptance corpus (tests/shading/corpus/*.sl, docs/shading.md
/// "Test corpus"): every construct and built-in of the language, each
/// checked by the shader itself against a value computed by hand or in
/// closed form. Each corpus shader declares `output varying float
/// check_<name>` parameters (corpus.h): 0 passes; anything else (the error,
/// or -1 when the shader never wrote it) fails, and this file reports the
/// file, the check and the first failing point. Some checks need the whole
/// batch (area summed over a sphere): those shaders write `value_<name>`
/// outputs that the C++ test aggregates.
///
/// Also here: the coverage test (every built-in of builtins.cpp is called by
/// some corpus file), the table of shaders that must not compile (message
/// and file:line:column), and run-time failures (division by zero, NaN,
/// array index out of range).
///
/// Suite names start with "RslCorpus".

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <OpenImageIO/imagebuf.h>

#include "engine_test_util.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/rsl/builtins.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

constexpr double kPi = std::numbers::pi;

/// The corpus folder (tests/shading/corpus).
std::filesystem::path corpus_dir() {
    return std::filesystem::path(SSS_TEST_DATA_DIR).parent_path() / "shading" / "corpus";
}

PreprocessOptions corpus_options() {
    PreprocessOptions o;
    o.include_dirs = {corpus_dir().string(), (corpus_dir() / "include").string()};
    o.defines = {{"CORPUS_LEVEL", "3"}}; // preprocessor.sl checks it
    return o;
}

/// Every shader of a corpus file, compiled from disk (the test fails on errors).
std::vector<std::shared_ptr<const Program>> compile_corpus(const std::string& file) {
    std::vector<std::shared_ptr<const Program>> out;
    try {
        CompileResult r = compile_file((corpus_dir() / file).string(), corpus_options());
        for (const Diagnostic& w : r.warnings)
            ADD_FAILURE() << file << ": " << w.format();
        for (Program& p : r.shaders)
            out.push_back(std::make_shared<Program>(std::move(p)));
    } catch (const ShaderCompileError& e) {
        std::string all;
        for (const Diagnostic& d : e.diagnostics()) all += d.format() + "\n";
        ADD_FAILURE() << file << " does not compile:\n" << all;
    } catch (const std::exception& e) {
        ADD_FAILURE() << file << ": " << e.what();
    }
    return out;
}

/// Asserts every check_* output of the last execute() is 0 at every point;
/// returns the number of checks.
int expect_checks(const ShadingContext& ctx, const Program& prog, const std::string& what,
                  std::size_t points, bool allow_nonfinite = false) {
    int checks = 0;
    for (int index : prog.parameters()) {
        const std::string& name = prog.symbols[index].name;
        if (name.rfind("check_", 0) != 0) continue;
        ++checks;
        TypeSpec type;
        std::vector<float> values;
        if (!ctx.output(name, type, values)) {
            ADD_FAILURE() << what << ": no output " << name;
            continue;
        }
        std::size_t bad = 0, first = 0;
        for (std::size_t i = 0; i < values.size(); ++i) {
            if (values[i] != 0.0f && bad++ == 0) first = i;
        }
        EXPECT_EQ(values.size() == 1 ? points : values.size(), points)
            << what << " " << name;
        EXPECT_EQ(bad, 0u) << what << ": " << name.substr(6) << " fails at " << bad
                           << " of " << values.size() << " points (first: point " << first
                           << ", value " << values[first]
                           << (values[first] == -1.0f ? ": never written" : "") << ")";
    }
    EXPECT_GT(checks, 0) << what << " has no checks";
    if (!allow_nonfinite) {
        EXPECT_EQ(ctx.nonfinite_points(), 0u) << what << ": " << ctx.nonfinite_message();
    }
    return checks;
}

/// One float output per point.
std::vector<float> output_of(const ShadingContext& ctx, const std::string& name) {
    TypeSpec type;
    std::vector<float> values;
    EXPECT_TRUE(ctx.output(name, type, values)) << name;
    return values;
}

/// A sphere of radius r as a grid at cell centres (u around z, v pole to
/// pole), with exact N, dPdu, dPdv, s = u, t = v.
ShadingBatch sphere_grid(int nu, int nv, double r) {
    ShadingBatch b;
    b.layout = BatchLayout::Grid;
    b.nu = nu;
    b.nv = nv;
    b.size = static_cast<std::size_t>(nu) * nv;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const double u = (i + 0.5) / nu, v = (j + 0.5) / nv;
            const double th = 2 * kPi * u, ph = -kPi / 2 + kPi * v;
            const glm::dvec3 n(std::cos(ph) * std::cos(th), std::cos(ph) * std::sin(th),
                               std::sin(ph));
            b.P.push_back(glm::vec3(r * n));
            b.N.push_back(glm::vec3(n));
            b.dPdu.push_back(glm::vec3(2 * kPi * r * std::cos(ph) *
                                       glm::dvec3(-std::sin(th), std::cos(th), 0)));
            b.dPdv.push_back(
                glm::vec3(kPi * r *
                          glm::dvec3(-std::sin(ph) * std::cos(th),
                                     -std::sin(ph) * std::sin(th), std::cos(ph))));
            b.u.push_back(static_cast<float>(u));
            b.v.push_back(static_cast<float>(v));
            b.du.push_back(1.0f / nu);
            b.dv.push_back(1.0f / nv);
        }
    b.Ng = b.N;
    b.s = b.u;
    b.t = b.v;
    b.I = b.P;
    return b;
}

/// Runs shader `name` of `file` (by default the file's first surface shader)
/// over `batch` and checks it.
int run_corpus(const std::string& file, ShadingBatch& batch, const ParamList& params = {},
               Engine* engine = nullptr, LightList lights = {},
               const std::string& name = "",
               const Matrix4& shader_to_world = Matrix4(1.0)) {
    Engine local;
    Engine& e = engine ? *engine : local;
    std::shared_ptr<const Program> prog;
    for (auto& p : compile_corpus(file))
        if (!prog && (name.empty() ? p->kind == ShaderKind::Surface : p->name == name))
            prog = p;
    if (!prog) {
        ADD_FAILURE() << file << ": no shader " << name;
        return 0;
    }
    const std::string what = file + (name.empty() ? "" : " (" + name + ")");
    try {
        ShaderInstance inst(prog, params, shader_to_world, file);
        e.context.execute(inst, batch, lights);
    } catch (const std::exception& ex) {
        ADD_FAILURE() << what << ": " << ex.what();
        return 0;
    }
    return expect_checks(e.context, *prog, what, batch.size);
}
int run_corpus(const std::string& file, ShadingBatch&& batch,
               const ParamList& params = {}, Engine* engine = nullptr,
               LightList lights = {}, const std::string& name = "") {
    return run_corpus(file, batch, params, engine, lights, name);
}

TEST(RslCorpus, OperatorsAndTypes) {
    run_corpus("operators_and_types.sl", plane_grid(8, 4));
}

TEST(RslCorpus, ControlFlow) {
    run_corpus("control_flow.sl", plane_grid(8, 4));
}

TEST(RslCorpus, Functions) {
    run_corpus("functions.sl", plane_grid(8, 2));
}

TEST(RslCorpus, Math) {
    run_corpus("math.sl", plane_grid(8, 2));
}

TEST(RslCorpus, Noise) {
    run_corpus("noise.sl", plane_grid(16, 8));
}

TEST(RslCorpus, Geometry) {
    Engine e;
    e.services.scene_.options.camera.near_clip = 1;
    e.services.scene_.options.camera.far_clip = 11;
    run_corpus("geometry.sl", plane_grid(4, 2), {}, &e);
}

TEST(RslCorpus, Derivatives) {
    run_corpus("derivatives.sl", plane_grid(16, 8), {}, nullptr, {}, "derivatives");
}

TEST(RslCorpus, AreaSummedOverASphereIs4PiR2) {
    Engine e;
    const double r = 1.5;
    ShadingBatch b = sphere_grid(128, 128, r);
    run_corpus("derivatives.sl", b, {}, &e, {}, "sphere_area");
    double total = 0.0;
    for (float a : output_of(e.context, "value_area")) total += a;
    EXPECT_NEAR(total / (4 * kPi * r * r), 1.0, 1e-3);
}

TEST(RslCorpus, CalculatenormalOfADisplacedSphere) {
    Engine e;
    ShadingBatch b = sphere_grid(96, 96, 1.5);
    const std::vector<glm::vec3> before = b.P;
    run_corpus("derivatives.sl", b, {}, &e, {}, "bumpy");
    // The displacement's P and N are written back into the batch.
    EXPECT_NE(b.P[100], before[100]);
    EXPECT_NEAR(glm::length(b.N[100]), 1.0f, 1e-5f);
}

TEST(RslCorpus, Spaces) {
    Engine e;
    Camera& cam = e.services.scene_.options.camera;
    cam.world_to_camera = glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 5));
    cam.perspective = true;
    cam.fov = 90;
    cam.xres = 200;
    cam.yres = 100;
    // Screen-space z is f/(f-n) - f n / ((f-n) z): finite clipping planes
    // keep it well conditioned in float for the round trips.
    cam.near_clip = 0.5;
    cam.far_clip = 100;
    e.services.scene_.coordinate_systems["lamp"] = glm::rotate(
        glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 1)), kPi / 2, glm::dvec3(0, 0, 1));
    Primitive prim;
    prim.object_to_world = glm::scale(glm::translate(Matrix4(1.0), glm::dvec3(0, 3, 0)),
                                      glm::dvec3(2, 1, 1));
    ShadingBatch b = plane_grid(4, 2);
    b.primitive = &prim;
    run_corpus("spaces.sl", b, {}, &e, {}, "",
               glm::translate(Matrix4(1.0), glm::dvec3(1, 0, 0)));
}

TEST(RslCorpus, Color) {
    run_corpus("color.sl", plane_grid(4, 2));
}

TEST(RslCorpus, Matrix) {
    run_corpus("matrix.sl", plane_grid(4, 2));
}

TEST(RslCorpus, Strings) {
    Engine e;
    run_corpus("strings.sl", plane_grid(2, 1), {}, &e);
    // A varying printf prints once per running point.
    EXPECT_EQ(e.services.messages,
              (std::vector<std::string>{"skin 0.25\n", "skin 0.75\n"}));
}

TEST(RslCorpus, Lighting) {
    Engine e;
    const auto shaders = compile_corpus("lighting.sl");
    auto light = [&](const std::string& name, ParamList params) {
        for (auto& p : shaders)
            if (p->name == name) return ShaderInstance(p, params, Matrix4(1.0), name);
        ADD_FAILURE() << "no light " << name;
        return ShaderInstance(std::make_shared<Program>(), {}, Matrix4(1.0), name);
    };
    std::vector<ShaderInstance> lights;
    lights.push_back(light("keylight", [] {
        ParamList p;
        p.set(float_param("intensity", 2));
        return p;
    }()));
    lights.push_back(light("filllight", [] {
        ParamList p;
        p.set(float_param("intensity", 0.5));
        return p;
    }()));
    lights.push_back(light("amblight", [] {
        ParamList p;
        p.set(float_param("intensity", 0.25));
        return p;
    }()));
    lights.push_back(light("spotlight", {}));
    lights.push_back(light("skylight", [] {
        ParamList p;
        p.set(float_param("intensity", 0.1));
        return p;
    }()));
    std::vector<const ShaderInstance*> list;
    for (const ShaderInstance& l : lights) list.push_back(&l);
    run_corpus("lighting.sl", plane_grid(8, 8), {}, &e, list);
    // The unsupported calls warned (trace() and indirectdiffuse() no longer do).
    std::string all;
    for (const std::string& w : e.services.warnings) all += w + "\n";
    for (const char* name : {"depth-map shadows"})
        EXPECT_NE(all.find(name), std::string::npos) << name << " in:\n" << all;
    for (const char* name : {"trace()", "indirectdiffuse()"})
        EXPECT_EQ(all.find(name), std::string::npos) << name << " in:\n" << all;
}

/// Writes a float image of `channels` channels with value(x, y, c).
template <class F>
std::string write_image(const std::string& path, int w, int h, int channels, F value) {
    OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, channels, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float v[4];
            for (int c = 0; c < channels; ++c) v[c] = value(x, y, c);
            buf.setpixel(x, y, v, channels);
        }
    EXPECT_TRUE(buf.write(path)) << buf.geterror();
    return path;
}

TEST(RslCorpus, Textures) {
    TempDir dir;
    const std::string map =
        write_image(dir.file("map.exr"), 4, 2, 3, [](int x, int y, int c) {
            return c == 0 ? (x + 0.5f) / 4 : c == 1 ? (y + 0.5f) / 2 : 0.25f + 0.1f * x;
        });
    const std::string env = write_image(dir.file("env.exr"), 8, 4, 3,
                                        [](int, int, int c) { return 0.2f * (c + 1); });
    Engine e;
    ParamList params;
    params.set(string_param("map", map));
    params.set(string_param("env", env));
    run_corpus("textures.sl", plane_grid(4, 2), params, &e);
    EXPECT_TRUE(e.services.warnings.empty()) << e.services.warnings[0];
}

TEST(RslCorpus, Bake3dAndTexture3d) {
    TempDir dir;
    // A 1 x 1 square on world z = 0, normals -z (towards the camera below).
    PointCloud cloud;
    const int n = 32;
    cloud.resize(std::size_t(n) * n);
    // Every channel first: adding one may move the others.
    cloud.add_channel("v", ChannelType::Float);
    cloud.add_channel("c", ChannelType::Color);
    cloud.add_channel("x", ChannelType::Float);
    Channel& v = *cloud.find_channel("v");
    Channel& c = *cloud.find_channel("c");
    Channel& x = *cloud.find_channel("x");
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::size_t k = std::size_t(j) * n + i;
            cloud.positions[k] = {(i + 0.5f) / n - 0.5f, (j + 0.5f) / n - 0.5f, 0.0f};
            cloud.normals[k] = {0.0f, 0.0f, -1.0f};
            cloud.radii[k] = 0.5f / n;
            v.data[k] = 0.25f;
            c.data[3 * k] = 0.1f;
            c.data[3 * k + 1] = 0.2f;
            c.data[3 * k + 2] = 0.3f;
            x.data[k] = cloud.positions[k].x;
        }
    const std::string ptc = dir.file("square.ptc"), bkm = dir.file("square.bkm");
    write_point_cloud(cloud, ptc);
    build_brick_map({cloud}, BrickMapBuildOptions{}, bkm);

    Engine e;
    e.services.scene_.options.camera.world_to_camera =
        glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 1));
    ShadingBatch b = plane_grid(6, 6);
    b.Cs.assign(b.size, glm::vec3(0.5f, 0.25f, 1.0f));
    ParamList params;
    params.set(string_param("cloud", ptc));
    params.set(string_param("bkm", bkm));
    params.set(string_param("out", "baked.ptc"));
    run_corpus("bake3d_texture3d.sl", b, params, &e);
    // What bake3d sent: world-space points on z = 0, the channels per point.
    ASSERT_EQ(e.services.bakes.size(), 1u);
    const Bake3dRecord& rec = e.services.bakes[0];
    EXPECT_EQ(rec.file, "baked.ptc");
    EXPECT_EQ(rec.channels, (std::vector<std::string>{"a", "col"}));
    EXPECT_EQ(rec.channel_floats, (std::vector<int>{1, 3}));
    ASSERT_EQ(rec.P.size(), b.size);
    ASSERT_EQ(rec.values.size(), 4 * b.size);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_NEAR(rec.P[i].x, b.P[i].x, 1e-6);
        EXPECT_NEAR(rec.P[i].z, 0.0f, 1e-6);
        EXPECT_NEAR(rec.N[i].z, -1.0f, 1e-6);
        EXPECT_EQ(rec.radius[i], 0.05f);
        EXPECT_NEAR(rec.values[4 * i], b.u[i], 1e-6);
        EXPECT_NEAR(rec.values[4 * i + 1], 0.5f, 1e-6);
        EXPECT_NEAR(rec.values[4 * i + 3], 1.0f, 1e-6);
    }
}

TEST(RslCorpus, Queries) {
    Engine e;
    Camera& cam = e.services.scene_.options.camera;
    cam.xres = 320;
    cam.yres = 240;
    cam.near_clip = 0.5;
    cam.far_clip = 100;
    e.services.scene_.options.hider = "raytrace";
    e.services.scene_.options.groups["render"].set(float_param("bucket", 16));
    auto attr = std::make_shared<Attributes>();
    attr->groups["identifier"].set(string_param("name", "ball"));
    attr->groups["user"].set(float_param("k", 4));
    attr->shading_rate = 2;
    attr->color = {1, 0.5, 0.25};
    Primitive prim;
    prim.attributes = attr;
    ShadingBatch b = plane_grid(2, 1);
    b.primitive = &prim;
    run_corpus("queries.sl", b, {}, &e);
}

TEST(RslCorpus, Raytrace) {
    run_corpus("raytrace.sl", plane_grid(4, 2));
}

TEST(RslCorpus, Preprocessor) {
    run_corpus("preprocessor.sl", plane_grid(4, 1));
}

// --- coverage ----------------------------------------------------------------------

/// Built-ins no corpus file needs to call. Empty: the functions this release
/// does not support (trace, indirectdiffuse, surface/displacement/
/// lightsource message passing, depth-map shadow) are called anyway and
/// their documented result (0, the variable untouched) is checked
/// (lighting.sl, queries.sl). Add a name here only with a comment saying
/// where its documented behaviour is tested instead.
const std::set<std::string> kNotInCorpus = {};

TEST(RslCorpus, EveryBuiltinIsExercised) {
    // Every corpus file, compiled: the ops of its shaders name the built-ins
    // it really calls (a name in a comment or a string does not count).
    std::set<std::string> called;
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(corpus_dir())) {
        if (entry.path().extension() != ".sl") continue;
        ++files;
        for (const auto& prog : compile_corpus(entry.path().filename().string()))
            for (const Op& op : prog->ops) called.insert(op.name);
    }
    EXPECT_GE(files, 16);
    std::set<std::string> missing;
    for (const detail::BuiltinSignature& sig : detail::builtin_signatures())
        if (!called.count(sig.name) && !kNotInCorpus.count(sig.name))
            missing.insert(sig.name);
    std::string list;
    for (const std::string& name : missing) list += " " + name;
    EXPECT_TRUE(missing.empty())
        << "built-ins no file of " << corpus_dir().string() << " calls:" << list;
    for (const std::string& name : kNotInCorpus)
        EXPECT_TRUE(detail::is_builtin(name))
            << name << " in the allow-list is no built-in";
}

// --- bad shaders --------------------------------------------------------------------

/// A shader that must not compile: the first error's message (a part of it)
/// and where it points.
struct BadShader {
    const char* what;
    const char* source;
    const char* message;
    int line, column;
};

const BadShader kBadShaders[] = {
    {"missing semicolon", "surface t() {\n    float x = 1\n    float y = 2;\n}\n",
     "expected ';' after the declaration, got 'float'", 3, 5},
    {"missing brace", "surface t() {\n    if (u > 0) {\n        Ci = 1;\n}\n",
     "missing '}' at the end of the file", 5, 1},
    {"incomplete expression", "surface t() {\n    float x = 1 / ;\n}\n",
     "unexpected ';' in an expression", 2, 19},
    {"unterminated string", "surface t() {\n    string s = \"abc;\n}\n",
     "unterminated string", 2, 16},
    {"triple to float", "surface t() {\n    float x = color(1, 2, 3);\n}\n",
     "cannot convert color to float", 2, 15},
    {"point to colour", "surface t() {\n    color c = point(1, 2, 3);\n}\n",
     "cannot convert point to color (points and colors do not mix)", 2, 15},
    {"colour plus point", "surface t() {\n    Ci = Cs + P;\n}\n",
     "operator '+' cannot combine color and point", 2, 13},
    {"point dot colour", "surface t() {\n    float x = P . Cs;\n}\n",
     "operator '.' cannot combine point and color", 2, 17},
    {"string arithmetic", "surface t() {\n    float x = \"a\" + 1;\n}\n",
     "operator '+' cannot combine string and float", 2, 19},
    {"unknown function", "surface t() {\n    float x = frobnicate(1);\n}\n",
     "unknown function 'frobnicate'", 2, 15},
    {"unknown variable", "surface t() {\n    Ci = nosuchvar;\n}\n",
     "unknown variable 'nosuchvar'", 2, 10},
    {"too many arguments", "surface t() {\n    float x = sin(1, 2);\n}\n",
     "no version of 'sin' takes (float, float)", 2, 15},
    {"too few arguments", "surface t() {\n    float x = sin();\n}\n",
     "no version of 'sin' takes ()", 2, 15},
    {"wrong argument type", "surface t() {\n    float x = sin(\"a\");\n}\n",
     "no version of 'sin' takes (string)", 2, 15},
    {"recursion",
     "float f(float x) {\n    return f(x) + 1;\n}\nsurface t() {\n    Ci = f(u);\n}\n",
     "recursive call of 'f' (RSL functions cannot recurse)", 2, 12},
    {"varying to uniform", "surface t() {\n    uniform float k = u;\n}\n",
     "cannot assign a varying value to uniform 'k'", 2, 23},
    {"read-only parameter", "surface t(float Kd = 1;) {\n    Kd = 2;\n}\n",
     "cannot assign to shader parameter 'Kd': it is read-only", 2, 5},
    {"read-only global", "surface t() {\n    u = 2;\n}\n",
     "cannot assign to global variable 'u': it is read-only in a surface shader", 2, 5},
    {"read-only global as an output argument",
     "surface t() {\n    float kr, kt;\n    fresnel(I, N, 1.5, u, kt);\n}\n",
     "cannot assign to global variable 'u'", 3, 24},
    {"read-only function parameter",
     "float f(float x) {\n    x = 1;\n    return x;\n}\nsurface t() {\n    Ci = "
     "f(u);\n}\n",
     "cannot assign to function parameter 'x'", 2, 5},
    {"constant to an output parameter",
     "void g(output float a) { a = 1; }\nsurface t() {\n    g(3);\n}\n",
     "argument 1 of 'g' must be a variable (the parameter is output)", 3, 7},
    {"L outside illuminance", "surface t() {\n    L = vector(1, 0, 0);\n}\n",
     "'L' exists only inside an illuminance statement", 2, 5},
    {"whole-array assignment",
     "surface t() {\n    float a[2] = {1, 2}, b[2] = {3, 4};\n    a = b;\n}\n",
     "cannot assign a whole array ('a')", 3, 5},
    {"array initialiser size", "surface t() {\n    float a[3] = {1, 2};\n}\n",
     "'a' has 3 elements but 2 values are given", 2, 11},
    {"redeclaration", "surface t() {\n    float x = 1;\n    float x = 2;\n}\n",
     "'x' is already declared in this scope", 3, 11},
    {"break outside a loop", "surface t() {\n    break;\n}\n", "break outside a loop", 2,
     5},
    {"gather output not a variable",
     "surface t() {\n    gather(\"\", P, N, 1, 4, \"surface:Ci\", Ci + 1) { Ci = 1; "
     "}\n}\n",
     "the value of gather output \"surface:Ci\" must be a variable", 2, 45},
    {"gather argument count", "surface t() {\n    gather(\"\", P, N, 1) { Ci = 1; }\n}\n",
     "gather takes (category, P, dir, angle, samples", 2, 5},
    {"gather primitive output",
     "surface t() {\n    color c;\n    gather(\"\", P, N, 1, 4, \"primitive:Cs\", c) Ci "
     "= c;\n}\n",
     "primitive variables of the hit are not supported", 3, 44},
};

TEST(RslCorpusErrors, BadShadersGiveClearMessages) {
    for (const BadShader& bad : kBadShaders) {
        SCOPED_TRACE(bad.what);
        try {
            compile_text(bad.source, "bad.sl");
            ADD_FAILURE() << "compiled:\n" << bad.source;
        } catch (const ShaderCompileError& e) {
            ASSERT_FALSE(e.diagnostics().empty());
            const Diagnostic& d = e.diagnostics()[0];
            EXPECT_EQ(d.severity, Diagnostic::Severity::Error);
            EXPECT_NE(d.message.find(bad.message), std::string::npos) << d.format();
            EXPECT_EQ(d.file, "bad.sl");
            EXPECT_EQ(d.line, bad.line) << d.format();
            EXPECT_EQ(d.column, bad.column) << d.format();
            // what() is the first error on one line, "file:line:column: ...".
            const std::string where = "bad.sl:" + std::to_string(bad.line) + ":" +
                                      std::to_string(bad.column) + ":";
            EXPECT_EQ(std::string(e.what()).rfind(where, 0), 0u) << e.what();
        }
    }
}

TEST(RslCorpusErrors, PreprocessorErrorsNameTheLine) {
    const struct {
        const char* source;
        const char* message;
        int line;
    } cases[] = {
        {"#include \"nosuchheader.h\"\nsurface t() {}\n", "cannot find include file", 1},
        {"\n#error stop here\nsurface t() {}\n", "stop here", 2},
        {"#if 1\nsurface t() {}\n", "unterminated #if", 1},
    };
    for (const auto& c : cases) {
        try {
            compile_text(c.source, "bad.sl", corpus_options());
            ADD_FAILURE() << "compiled:\n" << c.source;
        } catch (const PreprocessError& e) {
            EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
                << e.what();
            EXPECT_EQ(e.file(), "bad.sl");
            EXPECT_EQ(e.line(), c.line) << e.what();
        }
    }
}

/// Runs `source` over a 4 x 1 plane grid and returns the ShaderRuntimeError's
/// message ("" when it ran).
std::string runtime_error(const std::string& source) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    ShaderInstance inst(
        std::make_shared<Program>(compile_text(source, "bad.sl").shaders.at(0)), {},
        Matrix4(1.0), "scene.rib:7");
    try {
        e.context.execute(inst, b);
    } catch (const ShaderRuntimeError& err) {
        return err.what();
    }
    return "";
}

TEST(RslCorpusRuntime, ErrorsNameTheRibCallAndTheShaderLine) {
    const struct {
        const char* source;
        const char* message;
        int line;
    } cases[] = {
        {"surface t() {\n    float a[3] = {1, 2, 3};\n    Ci = a[u * 4];\n}\n",
         "array index 3.500000 out of range [0, 3)", 3},
        {"surface t() {\n    float a[3] = {1, 2, 3};\n    Ci = a[-0.5];\n}\n",
         "array index -0.500000 out of range [0, 3)", 3},
        {"surface t() {\n    float a[3] = {1, 2, 3};\n    a[3] = 1;\n}\n",
         "array index 3.000000 out of range [0, 3)", 3},
        {"surface t() {\n    Ci = comp(Cs, 3);\n}\n",
         "component index 3.000000 out of range", 2},
        {"surface t() {\n    matrix m = 1;\n    Ci = comp(m, 4, 0);\n}\n",
         "component index 4.000000 out of range [0, 4)", 3},
        {"surface t() {\n    Ci = color \"nosuchspace\" (1, 2, 3);\n}\n",
         "unknown colour space \"nosuchspace\"", 2},
        {"surface t() {\n    Ci = xcomp(transform(\"nowhere\", P));\n}\n",
         "unknown coordinate system \"nowhere\"", 2},
        {"surface t() {\n    Ci = texture(\"nosuch.tx\");\n}\n", "nosuch.tx", 2},
        {"surface t() {\n    float x;\n    Oi = texture3d(\"nosuch.ptc\", P, N, \"v\", "
         "x);\n}\n",
         "nosuch.ptc", 3},
        {"surface t() {\n    Ci = spline(\"nosuchbasis\", u, 0, 1, 2, 3);\n}\n",
         "unknown basis \"nosuchbasis\"", 2},
        {"surface t() {\n    printf(\"%d %d\\n\", 1);\n}\n", "format \"%d %d", 2},
    };
    for (const auto& c : cases) {
        const std::string what = runtime_error(c.source);
        EXPECT_NE(what.find(c.message), std::string::npos) << c.source << "\n-> " << what;
        // The RIB call, then the shader's file:line.
        const std::string where = "scene.rib:7: bad.sl:" + std::to_string(c.line) + ":";
        EXPECT_EQ(what.rfind(where, 0), 0u) << what;
    }
}

// Documented (engine.h, docs/shading.md): division by zero and NaN are IEEE
// inside a shader; results that are not finite are written as 0 and counted.
TEST(RslCorpusRuntime, DivisionByZeroAndNaNGiveFiniteResults) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    ShaderInstance inst(std::make_shared<Program>(compile_text(R"(
surface t(output varying float inf = 1; output varying float nan = 1;
          output varying color c = 1; output varying float fine = 0;
          output varying float guarded = 0;) {
    inf = 1 / (u - u);
    nan = sqrt(-u) + log(0) * 0;
    c = color(acos(2), 0 / (u - u), pow(0, -1));
    Ci = Cs / 0;
    Oi = 1;
    fine = u;
    /* a shader can test for NaN: it is not equal to itself */
    float x = 0 / (u - u);
    guarded = x != x ? 7 : x;
}
)",
                                                               "bad.sl")
                                                      .shaders.at(0)),
                        {}, Matrix4(1.0), "scene.rib:3");
    e.context.execute(inst, b);
    EXPECT_EQ(e.context.nonfinite_points(), 4u);
    EXPECT_NE(e.context.nonfinite_message().find("4 points"), std::string::npos)
        << e.context.nonfinite_message();
    for (const char* name : {"inf", "nan", "c"})
        for (float v : output_of(e.context, name)) EXPECT_EQ(v, 0.0f) << name;
    const std::vector<float> fine = output_of(e.context, "fine");
    const std::vector<float> guarded = output_of(e.context, "guarded");
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(b.Ci[i], glm::vec3(0.0f));
        EXPECT_EQ(b.Oi[i], glm::vec3(1.0f));
        EXPECT_FLOAT_EQ(fine[i], b.u[i]);
        EXPECT_EQ(guarded[i], 7.0f);
    }
}

// --- bugs the corpus found (each fixed in src/sss/shading/) ----------------------

// ShadingContext::output() read the program through a raw pointer: after the
// ShaderInstance (the only owner of its Program) was destroyed it read freed
// memory. The context now keeps the last program alive.
TEST(RslCorpusFixes, OutputsOutliveTheShaderInstance) {
    Engine e;
    ShadingBatch b = plane_grid(3, 1);
    {
        ShaderInstance inst = e.instance(R"(
surface t(output varying float r = 0;) { r = u * 2; }
)");
        e.context.execute(inst, b);
    }
    const std::vector<float> r = output_of(e.context, "r");
    ASSERT_EQ(r.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(r[i], 2 * b.u[i]);
}

} // namespace

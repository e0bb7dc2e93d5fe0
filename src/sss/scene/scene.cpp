// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file scene.cpp
/// The scene layer basics: typed parameter access, the RI spline bases and
/// the camera's screen-window arithmetic.

#include "sss/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "sss/util/error.h"
#include "sss/util/math.h"
#include "sss/util/name_table.h"

namespace sss {

int param_type_components(ParamType type) {
    switch (type) {
    case ParamType::Float:
    case ParamType::Integer:
    case ParamType::String:
        return 1;
    case ParamType::Color:
    case ParamType::Point:
    case ParamType::Vector:
    case ParamType::Normal:
        return 3;
    case ParamType::HPoint:
        return 4;
    case ParamType::Matrix:
        return 16;
    }
    return 1;
}

namespace {

// The RIB spellings. "int" is an alias the RIB reader accepts in declarations.
// clang-format off
constexpr NameTable<ParamClass, 6> kParamClassNames({{
    {ParamClass::Constant, "constant"}, {ParamClass::Uniform, "uniform"},
    {ParamClass::Varying, "varying"}, {ParamClass::Vertex, "vertex"},
    {ParamClass::FaceVarying, "facevarying"}, {ParamClass::FaceVertex, "facevertex"},
}});

constexpr NameTable<ParamType, 10> kParamTypeNames({{
    {ParamType::Float, "float"}, {ParamType::Integer, "integer"},
    {ParamType::String, "string"}, {ParamType::Color, "color"},
    {ParamType::Point, "point"}, {ParamType::Vector, "vector"},
    {ParamType::Normal, "normal"}, {ParamType::HPoint, "hpoint"},
    {ParamType::Matrix, "matrix"}, {ParamType::Integer, "int"},
}});

constexpr NameTable<PrimitiveKind, 19> kPrimitiveKindNames({{
    {PrimitiveKind::Polygon, "Polygon"},
    {PrimitiveKind::GeneralPolygon, "GeneralPolygon"},
    {PrimitiveKind::PointsPolygons, "PointsPolygons"},
    {PrimitiveKind::PointsGeneralPolygons, "PointsGeneralPolygons"},
    {PrimitiveKind::SubdivisionMesh, "SubdivisionMesh"},
    {PrimitiveKind::Sphere, "Sphere"}, {PrimitiveKind::Cylinder, "Cylinder"},
    {PrimitiveKind::Cone, "Cone"}, {PrimitiveKind::Disk, "Disk"},
    {PrimitiveKind::Torus, "Torus"}, {PrimitiveKind::Hyperboloid, "Hyperboloid"},
    {PrimitiveKind::Paraboloid, "Paraboloid"}, {PrimitiveKind::Patch, "Patch"},
    {PrimitiveKind::PatchMesh, "PatchMesh"}, {PrimitiveKind::Teapot, "Teapot"},
    {PrimitiveKind::Points, "Points"}, {PrimitiveKind::Curves, "Curves"},
    {PrimitiveKind::NuPatch, "NuPatch"}, {PrimitiveKind::Blobby, "Blobby"},
}});
// clang-format on

} // namespace

const char* param_class_name(ParamClass c) {
    return kParamClassNames.name(c);
}

std::optional<ParamClass> parse_param_class(std::string_view name) {
    return kParamClassNames.parse(name);
}

const char* param_type_name(ParamType type) {
    return kParamTypeNames.name(type);
}

std::optional<ParamType> parse_param_type(std::string_view name) {
    return kParamTypeNames.parse(name);
}

int Param::element_size() const {
    return param_type_components(type) * std::max(array_size, 1);
}

std::size_t Param::element_count() const {
    if (type == ParamType::String)
        return strings.size() / static_cast<std::size_t>(std::max(array_size, 1));
    return numbers.size() / static_cast<std::size_t>(element_size());
}

const Param* ParamList::find(std::string_view name) const {
    for (const Param& p : items)
        if (p.name == name) return &p;
    return nullptr;
}

namespace {

std::string parameter(std::string_view name) {
    return "parameter " + sss::quoted(name);
}

/// The parameter's numbers, checked to be numeric and at least `needed`.
const std::vector<double>& numbers_of(const Param& p, std::size_t needed,
                                      const char* wanted) {
    if (p.type == ParamType::String)
        throw ValueError(parameter(p.name) + ": expected " + wanted + ", got a string");
    if (p.numbers.size() < needed)
        throw ValueError(parameter(p.name) + ": expected " + wanted + ", got " +
                         std::to_string(p.numbers.size()) + " numbers");
    return p.numbers;
}

} // namespace

double ParamList::get_float(std::string_view name, double fallback) const {
    const Param* p = find(name);
    if (!p) return fallback;
    if (p->type != ParamType::Float && p->type != ParamType::Integer)
        throw ValueError(parameter(name) + ": expected a float, got a " +
                         param_type_name(p->type));
    return numbers_of(*p, 1, "a float")[0];
}

int ParamList::get_int(std::string_view name, int fallback) const {
    const Param* p = find(name);
    if (!p) return fallback;
    if (p->type != ParamType::Float && p->type != ParamType::Integer)
        throw ValueError(parameter(name) + ": expected an integer, got a " +
                         param_type_name(p->type));
    double v = numbers_of(*p, 1, "an integer")[0];
    // A float parameter used as a count must still hold a whole number.
    if (v != std::floor(v) || std::abs(v) > 2147483647.0)
        throw ValueError(parameter(name) + ": expected an integer, got " +
                         std::to_string(v));
    return static_cast<int>(v);
}

std::string ParamList::get_string(std::string_view name,
                                  const std::string& fallback) const {
    const Param* p = find(name);
    if (!p) return fallback;
    if (p->type != ParamType::String)
        throw ValueError(parameter(name) + ": expected a string, got a " +
                         param_type_name(p->type));
    if (p->strings.empty())
        throw ValueError(parameter(name) + ": expected a string, got none");
    return p->strings[0];
}

glm::dvec3 ParamList::get_vec3(std::string_view name, const glm::dvec3& fallback) const {
    const Param* p = find(name);
    if (!p) return fallback;
    switch (p->type) {
    case ParamType::Color:
    case ParamType::Point:
    case ParamType::Vector:
    case ParamType::Normal:
    case ParamType::Float:
        break;
    default:
        throw ValueError(parameter(name) + ": expected 3 numbers, got a " +
                         param_type_name(p->type));
    }
    const auto& n = numbers_of(*p, 3, "3 numbers");
    return {n[0], n[1], n[2]};
}

void ParamList::set(Param p) {
    for (Param& q : items) {
        if (q.name == p.name) {
            q = std::move(p);
            return;
        }
    }
    items.push_back(std::move(p));
}

namespace {

/// A basis given as RenderMan writes it (row-major rows of the row-vector
/// matrix), loaded the way scene.h documents: numbers k go to m[k/4][k%4].
Matrix4 basis_matrix(const double (&b)[16], double scale) {
    Matrix4 m(1.0);
    for (int k = 0; k < 16; ++k) m[k / 4][k % 4] = b[k] * scale;
    return m;
}

} // namespace

std::optional<Basis> named_basis(std::string_view name) {
    // The matrices of the RI specification (section "Basis").
    static const double bezier[16] = {-1, 3, -3, 1, 3, -6, 3, 0, -3, 3, 0, 0, 1, 0, 0, 0};
    static const double bspline[16] = {-1, 3, -3, 1, 3, -6, 3, 0,
                                       -3, 0, 3,  0, 1, 4,  1, 0};
    static const double catmull_rom[16] = {-1, 3, -3, 1, 2, -5, 4, -1,
                                           -1, 0, 1,  0, 0, 2,  0, 0};
    static const double hermite[16] = {2, 1, -2, 1, -3, -2, 3, -1,
                                       0, 1, 0,  0, 1,  0,  0, 0};
    static const double power[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

    Basis b;
    if (name == "bezier") {
        b = {basis_matrix(bezier, 1.0), 3, "bezier"};
    } else if (name == "b-spline" || name == "bspline") {
        b = {basis_matrix(bspline, 1.0 / 6.0), 1, "b-spline"};
    } else if (name == "catmull-rom" || name == "catmullrom") {
        b = {basis_matrix(catmull_rom, 0.5), 1, "catmull-rom"};
    } else if (name == "hermite") {
        b = {basis_matrix(hermite, 1.0), 2, "hermite"};
    } else if (name == "power") {
        b = {basis_matrix(power, 1.0), 4, "power"};
    } else {
        return std::nullopt;
    }
    return b;
}

std::string Attributes::name() const {
    auto it = groups.find("identifier");
    if (it == groups.end()) return "";
    const Param* p = it->second.find("name");
    if (!p || p->type != ParamType::String || p->strings.empty()) return "";
    return p->strings[0];
}

const Attributes& attributes_of(const Primitive& prim) {
    static const Attributes defaults;
    return prim.attributes ? *prim.attributes : defaults;
}

std::size_t ClassCounts::of(ParamClass c) const {
    switch (c) {
    case ParamClass::Constant:
        return 1;
    case ParamClass::Uniform:
        return uniform;
    case ParamClass::Varying:
        return varying;
    case ParamClass::Vertex:
        return vertex;
    case ParamClass::FaceVarying:
        return facevarying;
    case ParamClass::FaceVertex:
        return facevertex;
    }
    return 1;
}

const char* primitive_kind_name(PrimitiveKind kind) {
    return kPrimitiveKindNames.name(kind);
}

std::array<double, 4> Camera::resolved_screen_window() const {
    if (screen_window) return *screen_window;
    // RI default: the shorter image side spans [-1, 1].
    double a = static_cast<double>(xres) * pixel_aspect / static_cast<double>(yres);
    if (a >= 1.0) return {-a, a, -1.0, 1.0};
    return {-1.0, 1.0, -1.0 / a, 1.0 / a};
}

double Camera::pixel_size_at(double distance) const {
    auto sw = resolved_screen_window();
    double width = sw[1] - sw[0];
    if (!perspective) return width / static_cast<double>(xres);
    double half_angle = fov * kPi / 360.0;
    return width * std::max(distance, near_clip) * std::tan(half_angle) /
           static_cast<double>(xres);
}

bool Attributes::visible_to(const char* kind) const {
    auto it = groups.find("visibility");
    if (it == groups.end()) return true;
    const Param* p = it->second.find(kind);
    // PRMan 12's "trace" stands for both kinds of traced rays when the
    // newer names are not given.
    if (!p &&
        (std::string_view(kind) == "diffuse" || std::string_view(kind) == "specular"))
        p = it->second.find("trace");
    if (!p) return true;
    if (p->type == ParamType::String)
        return p->strings.empty() ||
               (p->strings[0] != "transparent" && p->strings[0] != "0");
    return p->numbers.empty() || p->numbers[0] != 0.0;
}

std::vector<std::string> default_search_path(const std::string& rib_path,
                                             const std::string& kind) {
    std::vector<std::string> out = {"."};
    const std::string dir = std::filesystem::path(rib_path).parent_path().string();
    if (!dir.empty() && dir != ".") out.push_back(dir);
    if (kind == "shader") out.push_back("@");
    return out;
}

std::vector<std::string> search_path(const Scene& scene, const std::string& kind) {
    if (auto it = scene.options.search_paths.find(kind);
        it != scene.options.search_paths.end())
        return it->second;
    return default_search_path(scene.path, kind);
}

std::optional<std::string> find_on_search_path(const std::vector<std::string>& path,
                                               const std::string& name) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (name.empty()) return std::nullopt;
    if (fs::path(name).is_absolute())
        return fs::exists(name, ec) ? std::optional<std::string>(name) : std::nullopt;
    for (const std::string& dir : path) {
        if (dir == "@" || dir.empty()) continue;
        const std::string candidate =
            dir == "." ? name : (fs::path(dir) / name).lexically_normal().string();
        if (fs::exists(candidate, ec)) return candidate;
    }
    return std::nullopt;
}

std::string search_path_text(const std::vector<std::string>& path) {
    std::string text;
    for (const std::string& dir : path) text += (text.empty() ? "" : ":") + dir;
    return text;
}

Matrix4 Camera::world_to_ndc() const {
    const auto sw = resolved_screen_window();
    Matrix4 proj(1.0);
    if (perspective) {
        const double c = 1.0 / std::tan(fov * kPi / 360.0);
        const double n = near_clip, f = far_clip;
        proj = Matrix4(0.0);
        proj[0][0] = c;
        proj[1][1] = c;
        proj[2][2] = f / (f - n);
        proj[3][2] = -f * n / (f - n);
        proj[2][3] = 1.0;
    }
    Matrix4 screen_to_ndc(1.0);
    screen_to_ndc[0][0] = 1.0 / (sw[1] - sw[0]);
    screen_to_ndc[3][0] = -sw[0] / (sw[1] - sw[0]);
    screen_to_ndc[1][1] = -1.0 / (sw[3] - sw[2]);
    screen_to_ndc[3][1] = sw[3] / (sw[3] - sw[2]);
    return screen_to_ndc * proj * world_to_camera;
}

} // namespace sss

namespace sss {

namespace {

/// The samples around `time`: indices a <= b and the weight of b.
void bracket(const std::vector<double>& times, double time, std::size_t& a,
             std::size_t& b, double& w) {
    a = b = 0;
    w = 0.0;
    if (times.empty() || !(time > times.front())) return;
    if (!(time < times.back())) {
        a = b = times.size() - 1;
        return;
    }
    b = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), time) -
                                 times.begin());
    a = b - 1;
    const double span = times[b] - times[a];
    w = span > 0.0 ? (time - times[a]) / span : 0.0;
}

} // namespace

std::vector<double> PrimitiveMotion::times() const {
    std::vector<double> out = transform_times;
    out.insert(out.end(), shape_times.begin(), shape_times.end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

Matrix4 matrix_at(const std::vector<double>& times, const std::vector<Matrix4>& keys,
                  double time) {
    std::size_t a = 0, b = 0;
    double w = 0.0;
    bracket(times, time, a, b, w);
    if (keys.empty()) return Matrix4(1.0);
    if (a == b || w == 0.0) return keys[a];
    return keys[a] * (1.0 - w) + keys[b] * w;
}

Primitive primitive_at(const Primitive& prim, double time) {
    Primitive out = prim;
    out.motion.reset();
    if (!prim.motion) return out;
    const PrimitiveMotion& m = *prim.motion;
    if (!m.transform_times.empty())
        out.object_to_world = matrix_at(m.transform_times, m.transforms, time);
    if (m.shape_times.empty()) return out;
    std::size_t a = 0, b = 0;
    double w = 0.0;
    bracket(m.shape_times, time, a, b, w);
    out.args = m.shape_args[a];
    out.params = m.shape_params[a];
    if (a == b || w == 0.0) return out;
    const std::vector<double>& args_b = m.shape_args[b];
    if (args_b.size() == out.args.size())
        for (std::size_t i = 0; i < out.args.size(); ++i)
            out.args[i] += w * (args_b[i] - out.args[i]);
    for (Param& p : out.params.items) {
        const Param* q = m.shape_params[b].find(p.name);
        if (!q || p.type == ParamType::String || q->numbers.size() != p.numbers.size())
            continue;
        for (std::size_t i = 0; i < p.numbers.size(); ++i)
            p.numbers[i] += w * (q->numbers[i] - p.numbers[i]);
    }
    return out;
}

} // namespace sss

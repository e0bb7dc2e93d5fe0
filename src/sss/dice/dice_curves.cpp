// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_curves.cpp
/// Points and Curves, as RenderMan draws them: a point is a round disk of
/// its width and a curve a flat ribbon of its width, both facing the camera
/// unless "N" gives their normal. Each becomes a polygon mesh in object
/// space (disks as area-preserving regular polygons, ribbons as quads along
/// the curve at the dicing rate) that the polygon dicer turns into
/// micropolygons, so that displacement, Cs and the texture coordinates
/// work as on any mesh.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "dice_common.h"
#include "mesh_common.h"
#include "sss/util/math.h"

namespace sss::detail {

namespace {

using glm::dvec3;
using glm::dvec4;

/// Where the viewer is, in the primitive's object space: disks and ribbons
/// turn towards it. Without a camera, RenderMan's default one (at the
/// origin of world space, looking down +z).
struct Viewer {
    bool perspective = true;
    dvec3 eye{0.0};    ///< perspective: the eye
    dvec3 toward{0.0}; ///< orthographic: the direction to the viewer

    Viewer(const Primitive& prim, const DiceControl& control) {
        static const Camera default_camera;
        const Camera& cam = control.camera ? *control.camera : default_camera;
        const Matrix4 camera_to_object =
            glm::inverse(prim.object_to_world) * glm::inverse(cam.world_to_camera);
        perspective = cam.perspective || !control.camera;
        const dvec4 e = camera_to_object * dvec4(0.0, 0.0, 0.0, 1.0);
        eye = dvec3(e) / e.w;
        toward = safe_normalize(dvec3(camera_to_object * dvec4(0.0, 0.0, -1.0, 0.0)),
                                dvec3(0.0, 0.0, -1.0));
    }

    /// The direction from p to the viewer (not normalised).
    dvec3 at(const dvec3& p) const { return perspective ? eye - p : toward; }

    static dvec3 safe_normalize(const dvec3& v, const dvec3& fallback) {
        const double len = glm::length(v);
        return len > 0.0 && std::isfinite(len) ? v / len : fallback;
    }
};

/// Any unit vector perpendicular to unit n.
dvec3 perpendicular(const dvec3& n) {
    const dvec3 helper =
        std::abs(n.x) < 0.9 ? dvec3(1.0, 0.0, 0.0) : dvec3(0.0, 1.0, 0.0);
    return glm::normalize(glm::cross(n, helper));
}

/// One numeric primitive variable carried onto the mesh as a vertex-class
/// parameter (Cs, s, t, st): its values per element, by storage class.
struct Channel {
    const Param* param = nullptr;
    std::size_t width = 0; ///< numbers per element
    std::vector<double> out;

    const double* element(std::size_t k) const { return &param->numbers[width * k]; }
};

/// The mesh the points or curves become, in object space.
struct Mesh {
    std::vector<dvec3> P, N;
    std::vector<int> nverts, verts;
    std::vector<Channel> channels;
    /// Curves without texture coordinates: s across the ribbon, t along the
    /// curve, per vertex (empty otherwise).
    std::vector<double> s, t;

    /// Appends a vertex with its position, normal and the channel values
    /// `blend` writes (blend(channel, destination)).
    template <class Blend>
    void vertex(const dvec3& p, const dvec3& n, const Blend& blend) {
        P.push_back(p);
        N.push_back(n);
        for (Channel& c : channels) {
            const std::size_t at = c.out.size();
            c.out.resize(at + c.width);
            blend(c, &c.out[at]);
        }
    }

    /// The PointsPolygons primitive of the mesh, with prim's transform,
    /// attributes and source.
    Primitive primitive(const Primitive& prim) const {
        Primitive m;
        m.kind = PrimitiveKind::PointsPolygons;
        m.nverts = nverts;
        m.verts = verts;
        m.object_to_world = prim.object_to_world;
        m.attributes = prim.attributes;
        m.source = prim.source;
        m.params.set(vec3_param("P", ParamType::Point, P));
        m.params.set(vec3_param("N", ParamType::Normal, N));
        for (const Channel& c : channels) {
            Param q = *c.param;
            q.storage = ParamClass::Vertex;
            q.numbers = c.out;
            m.params.set(std::move(q));
        }
        if (!s.empty()) {
            m.params.set(float_param("s", s));
            m.params.set(float_param("t", t));
        }
        return m;
    }

    static Param float_param(const char* name, const std::vector<double>& v) {
        Param q;
        q.name = name;
        q.type = ParamType::Float;
        q.storage = ParamClass::Vertex;
        q.numbers = v;
        return q;
    }

    static Param vec3_param(const char* name, ParamType type,
                            const std::vector<dvec3>& v) {
        Param q;
        q.name = name;
        q.type = type;
        q.storage = ParamClass::Vertex;
        q.numbers.reserve(3 * v.size());
        for (const dvec3& x : v) q.numbers.insert(q.numbers.end(), {x.x, x.y, x.z});
        return q;
    }
};

/// The channels a primitive carries to its mesh.
std::vector<Channel> channels_of(const Primitive& prim) {
    std::vector<Channel> out;
    for (const char* name : {"Cs", "s", "t", "st"}) {
        const Param* q = prim.params.find(name);
        if (!q || q->type == ParamType::String) continue;
        Channel c;
        c.param = q;
        c.width = static_cast<std::size_t>(q->element_size());
        out.push_back(c);
    }
    return out;
}

/// A float primitive variable read by storage class (width, N).
struct Scalar {
    const Param* param = nullptr;
    double fallback = 1.0;
    double at(std::size_t uniform, std::size_t varying) const {
        if (!param) return fallback;
        switch (param->storage) {
        case ParamClass::Constant:
            return param->numbers[0];
        case ParamClass::Uniform:
            return param->numbers[uniform];
        default:
            return param->numbers[varying];
        }
    }
};

/// The width of a point or curve: "width", else "constantwidth", else 1.
Scalar width_of(const Primitive& prim) {
    Scalar w;
    if (const Param* q = prim.params.find("width"); q && q->type == ParamType::Float) {
        w.param = q;
    } else if (const Param* c = prim.params.find("constantwidth");
               c && c->type == ParamType::Float && !c->numbers.empty()) {
        w.fallback = c->numbers[0];
    }
    return w;
}

/// A unit user normal "N" of element k (by class), if given.
struct NormalVar {
    const Param* param = nullptr;
    explicit NormalVar(const Primitive& prim) : param(prim.params.find("N")) {
        if (param && param->element_size() != 3)
            fail(prim, "\"N\" must have 3 numbers per value");
    }
    dvec3 at(std::size_t k) const {
        const double* v = &param->numbers[3 * k];
        return dvec3(v[0], v[1], v[2]);
    }
};

void check_width(const Primitive& prim, double w) {
    if (!(w >= 0.0) || !std::isfinite(w))
        fail(prim, "width must be a finite number >= 0, not " + std::to_string(w));
}

void check_faces(const Primitive& prim, const DiceControl& control, double faces) {
    if (faces > static_cast<double>(control.max_micropolygons))
        too_many_micropolygons(prim, control, faces);
}

// --- Points -----------------------------------------------------------------

/// A disk of radius r about c, facing n, `cells` micropolygons across,
/// with the values of point `element`: a regular polygon of the disk's
/// area, and for larger disks rings of quads around a small central polygon
/// (sides and rings of about four micropolygons, which the polygon dicer
/// dices further: one big polygon would be cut into many small triangles).
void disk(Mesh& mesh, const dvec3& c, const dvec3& n, double r, double cells,
          std::size_t element) {
    const int sides = std::clamp(static_cast<int>(std::ceil(kPi * cells / 4.0)), 8, 64);
    const int rings = std::clamp(static_cast<int>(std::ceil(cells / 8.0)), 1, 16);
    const double step = 2.0 * kPi / sides;
    const double outer = r * std::sqrt(step / std::sin(step)); // area-preserving
    const dvec3 a = perpendicular(n);
    const dvec3 b = glm::cross(n, a);
    const auto first = static_cast<int>(mesh.P.size());
    for (int ring = 1; ring <= rings; ++ring) {
        const double radius = outer * ring / rings;
        for (int k = 0; k < sides; ++k) {
            const dvec3 p =
                c + radius * (std::cos(k * step) * a + std::sin(k * step) * b);
            mesh.vertex(p, n, [&](const Channel& ch, double* out) {
                const bool single = ch.param->storage == ParamClass::Constant ||
                                    ch.param->storage == ParamClass::Uniform;
                const double* v = ch.element(single ? 0 : element);
                std::copy(v, v + ch.width, out);
            });
        }
    }
    for (int k = 0; k < sides; ++k) mesh.verts.push_back(first + k);
    mesh.nverts.push_back(sides);
    for (int ring = 1; ring < rings; ++ring) {
        const int in = first + (ring - 1) * sides;
        const int out = in + sides;
        for (int k = 0; k < sides; ++k) {
            const int next = (k + 1) % sides;
            mesh.verts.insert(mesh.verts.end(), {in + k, out + k, out + next, in + next});
            mesh.nverts.push_back(4);
        }
    }
}

Mesh points_mesh(const Primitive& prim, const DiceControl& control) {
    const std::vector<dvec3> pts = read_positions(prim);
    const Viewer viewer(prim, control);
    const Scalar width = width_of(prim);
    const NormalVar user_n(prim);
    const double rate = attributes_of(prim).shading_rate;
    Mesh mesh;
    mesh.channels = channels_of(prim);
    check_faces(prim, control, static_cast<double>(pts.size()));
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double w = width.at(0, i);
        check_width(prim, w);
        if (w == 0.0) continue;
        const dvec3 n =
            user_n.param
                ? Viewer::safe_normalize(
                      user_n.at(user_n.param->storage == ParamClass::Constant ||
                                        user_n.param->storage == ParamClass::Uniform
                                    ? 0
                                    : i),
                      dvec3(0.0, 0.0, 1.0))
                : Viewer::safe_normalize(viewer.at(pts[i]), dvec3(0.0, 0.0, -1.0));
        const dvec3 world = dvec3(prim.object_to_world * dvec4(pts[i], 1.0));
        const double edge = control.edge_length_at(world, rate);
        const double across =
            w * glm::length(dvec3(prim.object_to_world * dvec4(perpendicular(n), 0.0)));
        disk(mesh, pts[i], n, 0.5 * w, control.note(across / edge, prim), i);
    }
    return mesh;
}

// --- Curves -----------------------------------------------------------------

/// One curve's indices: its first vertex and varying value, its vertices,
/// segments and varying values, and its number.
struct CurveIndex {
    std::size_t curve = 0;
    std::size_t first_vertex = 0, first_varying = 0;
    int vertices = 0, segments = 0, varying = 0;
};

/// Where a sample of a curve takes its values: the control vertices and
/// weights (vertex class), the varying values and weight (varying class).
struct CurveSample {
    std::array<std::size_t, 4> vertex{};
    dvec4 w{0.0}, dw{0.0};
    int order = 4;
    std::size_t varying0 = 0, varying1 = 0;
    double t = 0.0; ///< between varying0 and varying1
};

class CurveMesher {
public:
    CurveMesher(const Primitive& prim, const DiceControl& control)
        : m_prim(prim), m_control(control), m_viewer(prim, control),
          m_points(read_positions(prim)), m_width(width_of(prim)), m_user_n(prim) {
        m_cubic = prim.type == "cubic";
        const Attributes& attr = attributes_of(prim);
        m_basis = resolve_basis(attr.v_basis);
        m_step = m_cubic ? attr.v_basis.step : 1;
        m_rate = attr.shading_rate;
        m_mesh.channels = channels_of(prim);
        m_default_st =
            !prim.params.has("s") && !prim.params.has("t") && !prim.params.has("st");
    }

    Mesh run() {
        CurveIndex c;
        double quads = 0.0;
        for (std::size_t k = 0; k < m_prim.nverts.size(); ++k) {
            c.curve = k;
            c.vertices = m_prim.nverts[k];
            c.segments = m_cubic ? (m_prim.vwrap ? c.vertices / m_step
                                                 : (c.vertices - 4) / m_step + 1)
                                 : (m_prim.vwrap ? c.vertices : c.vertices - 1);
            c.varying = m_prim.vwrap ? c.segments : c.segments + 1;
            quads += curve(c);
            check_faces(m_prim, m_control, quads);
            c.first_vertex += static_cast<std::size_t>(c.vertices);
            c.first_varying += static_cast<std::size_t>(c.varying);
        }
        return std::move(m_mesh);
    }

private:
    /// The sample at parameter x in [0, 1] of segment `seg` of curve c.
    CurveSample sample(const CurveIndex& c, int seg, double x) const {
        CurveSample s;
        const auto wrap = [&](int k) {
            return c.first_vertex + static_cast<std::size_t>(k % c.vertices);
        };
        if (m_cubic) {
            const int first = seg * m_step;
            for (int k = 0; k < 4; ++k) s.vertex[k] = wrap(first + k);
            s.w = m_basis * dvec4(x * x * x, x * x, x, 1.0);
            s.dw = m_basis * dvec4(3.0 * x * x, 2.0 * x, 1.0, 0.0);
        } else {
            s.order = 2;
            s.vertex[0] = wrap(seg);
            s.vertex[1] = wrap(seg + 1);
            s.w = dvec4(1.0 - x, x, 0.0, 0.0);
            s.dw = dvec4(-1.0, 1.0, 0.0, 0.0);
        }
        s.varying0 = c.first_varying + static_cast<std::size_t>(seg % c.varying);
        s.varying1 = c.first_varying + static_cast<std::size_t>((seg + 1) % c.varying);
        s.t = x;
        return s;
    }

    /// Blends n-number elements of `data` at a sample, by storage class.
    void blend(const Param& q, std::size_t n, const CurveSample& s, std::size_t curve,
               double* out) const {
        const double* d = q.numbers.data();
        switch (q.storage) {
        case ParamClass::Constant:
            std::copy(d, d + n, out);
            return;
        case ParamClass::Uniform:
            std::copy(d + n * curve, d + n * (curve + 1), out);
            return;
        case ParamClass::Vertex:
            for (std::size_t c = 0; c < n; ++c) {
                double v = 0.0;
                for (int k = 0; k < s.order; ++k) v += s.w[k] * d[n * s.vertex[k] + c];
                out[c] = v;
            }
            return;
        default: // varying, facevarying, facevertex: along the segment
            for (std::size_t c = 0; c < n; ++c)
                out[c] =
                    (1.0 - s.t) * d[n * s.varying0 + c] + s.t * d[n * s.varying1 + c];
            return;
        }
    }

    dvec3 position(const CurveSample& s, const dvec4& w) const {
        dvec3 p(0.0);
        for (int k = 0; k < s.order; ++k) p += w[k] * m_points[s.vertex[k]];
        return p;
    }

    /// Quads along curve c; returns how many.
    double curve(const CurveIndex& c) {
        const double total = static_cast<double>(c.segments);
        double quads = 0.0;
        for (int seg = 0; seg < c.segments; ++seg) {
            const int n = samples(c, seg);
            for (int k = 0; k <= n; ++k) {
                const double x = static_cast<double>(k) / n;
                ribbon_vertices(c, sample(c, seg, x), (seg + x) / total);
                if (k == 0) continue;
                const auto v = static_cast<int>(m_mesh.P.size());
                m_mesh.nverts.push_back(4);
                m_mesh.verts.insert(m_mesh.verts.end(), {v - 4, v - 3, v - 1, v - 2});
                quads += 1.0;
            }
            // The next segment starts afresh (its first sample repeats this end).
        }
        return quads;
    }

    /// Quads for one segment: one per four micropolygon edges along it
    /// (the polygon dicer dices them further), at least four per cubic.
    int samples(const CurveIndex& c, int seg) const {
        constexpr int kProbe = 8;
        double length = 0.0;
        dvec3 previous(0.0);
        for (int k = 0; k <= kProbe; ++k) {
            const CurveSample s = sample(c, seg, static_cast<double>(k) / kProbe);
            const dvec3 world =
                dvec3(m_prim.object_to_world * dvec4(position(s, s.w), 1.0));
            check_world_point(m_prim, world);
            if (k > 0) length += glm::length(world - previous);
            previous = world;
        }
        const CurveSample mid = sample(c, seg, 0.5);
        const dvec3 world =
            dvec3(m_prim.object_to_world * dvec4(position(mid, mid.w), 1.0));
        const double edge = m_control.edge_length_at(world, m_rate);
        const double n = m_control.note(std::ceil(length / (4.0 * edge)), m_prim);
        return static_cast<int>(std::clamp(n, m_cubic ? 4.0 : 1.0, 4096.0));
    }

    /// The two vertices across the ribbon at a sample; v is the curve's
    /// parameter there (0 at its start, 1 at its end).
    void ribbon_vertices(const CurveIndex& c, const CurveSample& s, double v) {
        const dvec3 p = position(s, s.w);
        dvec3 tangent = position(s, s.dw);
        if (!(glm::length(tangent) > 0.0)) tangent = dvec3(0.0, 0.0, 1.0);
        tangent = glm::normalize(tangent);
        double w = m_width.fallback;
        if (m_width.param) blend(*m_width.param, 1, s, c.curve, &w);
        check_width(m_prim, w);
        dvec3 facing;
        if (m_user_n.param) {
            blend(*m_user_n.param, 3, s, c.curve, &facing.x);
        } else {
            facing = m_viewer.at(p);
        }
        dvec3 side = glm::cross(tangent, facing);
        side = glm::length(side) > 0.0 ? glm::normalize(side) : perpendicular(tangent);
        dvec3 n = glm::normalize(glm::cross(side, tangent));
        if (glm::dot(n, facing) < 0.0) n = -n;
        for (int edge = 0; edge < 2; ++edge) {
            const double u = edge;
            m_mesh.vertex(p + (u - 0.5) * w * side, n,
                          [&](const Channel& ch, double* out) {
                              blend(*ch.param, ch.width, s, c.curve, out);
                          });
            if (m_default_st) {
                m_mesh.s.push_back(u);
                m_mesh.t.push_back(v);
            }
        }
    }

    const Primitive& m_prim;
    const DiceControl& m_control;
    const Viewer m_viewer;
    const std::vector<dvec3> m_points;
    const Scalar m_width;
    const NormalVar m_user_n;
    bool m_cubic = false;
    glm::dmat4 m_basis{1.0};
    int m_step = 1;
    double m_rate = 1.0;
    bool m_default_st = false;
    Mesh m_mesh;
};

} // namespace

DicedSurface dice_points(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate) {
    const Mesh mesh = points_mesh(prim, control);
    if (mesh.nverts.empty()) return {};
    return dice_polygons(mesh.primitive(prim), control, estimate);
}

DicedSurface dice_curves(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate) {
    const Mesh mesh = CurveMesher(prim, control).run();
    if (mesh.nverts.empty()) return {};
    return dice_polygons(mesh.primitive(prim), control, estimate);
}

} // namespace sss::detail

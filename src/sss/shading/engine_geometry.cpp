// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_geometry.cpp
/// Geometric built-ins (RISpec 15.2-15.4): components, length, normalize
/// (0 stays 0), distance, ptlined, rotate, faceforward (Nref defaults to Ng),
/// reflect, refract (0 on total internal reflection), fresnel, the
/// transform family, depth, derivatives (Du, Dv, Deriv per BatchLayout),
/// area, calculatenormal, comp/setcomp, ctransform and the matrix functions.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "engine_internal.h"
#include "rsl_math.h"

namespace sss::detail {

glm::dmat4 named_space_to_current(Frame& f, const BoundOp& b, const std::string& space) {
    glm::dmat4 m(1.0);
    if (f.ctx->space_to_current(space, f, m)) return m;
    f.warn_once(b, "unknown coordinate system \"" + space +
                       "\": taken as \"current\", as PRMan does");
    return glm::dmat4(1.0);
}

// --- derivatives --------------------------------------------------------------

void derivative(Frame& f, const Slot& x, int comps, int dir, const std::string& name,
                float* out) {
    const std::size_t n = f.n;
    std::fill(out, out + n * comps, 0.0f);
    const ShadingBatch* batch = f.ctx->batch;
    if (!batch || n == 0) return;
    const std::vector<float>& dparam = dir == 0 ? batch->du : batch->dv;
    auto spacing = [&](std::size_t i) { return dparam.size() > i ? dparam[i] : 0.0f; };
    auto divide = [&](std::size_t i, float diff) {
        const float d = spacing(i);
        return d != 0.0f ? diff / d : 0.0f;
    };
    switch (batch->layout) {
    case BatchLayout::Points: {
        if (name == "P") {
            const std::vector<glm::vec3>& t = dir == 0 ? batch->dPdu : batch->dPdv;
            if (comps == 3 && t.size() >= n)
                for (std::size_t i = 0; i < n; ++i) st3(out + i * 3, t[i]);
        } else if ((dir == 0 && name == "u") || (dir == 1 && name == "v")) {
            if (comps == 1)
                for (std::size_t i = 0; i < n; ++i) out[i] = 1.0f;
        }
        return;
    }
    case BatchLayout::Triplets: {
        if (!x.varying) return;
        for (std::size_t j = 0; j + 2 < n; j += 3) {
            const float* a = x.at(j);
            const float* c = x.at(j + 1 + dir);
            for (int k = 0; k < comps; ++k) {
                const float d = divide(j, c[k] - a[k]);
                out[j * comps + k] = d;
                out[(j + 1) * comps + k] = d;
                out[(j + 2) * comps + k] = d;
            }
        }
        return;
    }
    case BatchLayout::Grid: {
        if (!x.varying) return;
        const std::size_t nu = static_cast<std::size_t>(batch->nu);
        const std::size_t nv = static_cast<std::size_t>(batch->nv);
        const std::size_t len = dir == 0 ? nu : nv;   // points along the direction
        const std::size_t lines = dir == 0 ? nv : nu; // lines of them
        const std::size_t step = dir == 0 ? 1 : nu;
        for (std::size_t l = 0; l < lines; ++l) {
            const std::size_t base = dir == 0 ? l * nu : l;
            for (std::size_t c = 0; c < len; ++c) {
                const std::size_t i = base + c * step;
                for (int k = 0; k < comps; ++k) {
                    auto X = [&](std::size_t cc) { return x.at(base + cc * step)[k]; };
                    float diff = 0.0f;
                    if (len == 2)
                        diff = X(1) - X(0);
                    else if (len >= 3) {
                        if (c == 0)
                            diff = -1.5f * X(0) + 2.0f * X(1) - 0.5f * X(2);
                        else if (c == len - 1)
                            diff =
                                1.5f * X(len - 1) - 2.0f * X(len - 2) + 0.5f * X(len - 3);
                        else
                            diff = 0.5f * (X(c + 1) - X(c - 1));
                    }
                    out[i * comps + k] = divide(i, diff);
                }
            }
        }
        return;
    }
    }
}

namespace {

const std::string& arg_name(const Frame& f, const BoundOp& b, int k) {
    return f.program->symbols[b.op->args[k]].name;
}

/// Du / Dv of argument 1 into d.
template <int Dir>
void op_D(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    const int nc = x.nf;
    std::vector<float> tmp(f.n * nc);
    derivative(f, x, nc, Dir, arg_name(f, b, 1), tmp.data());
    f.each(d.varying, [&](std::size_t i) {
        std::memcpy(d.at(i), tmp.data() + i * nc, sizeof(float) * nc);
    });
}

bool bind_D(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_f_or_triple(1) || in.is_array(0) ||
        in.floats(0) != in.floats(1))
        return false;
    b.fn = in.op.name == "Du" ? op_D<0> : op_D<1>;
    return true;
}

void op_Deriv(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& num = f.slot(b, 1);
    Slot& den = f.slot(b, 2);
    const int nc = num.nf;
    const std::size_t n = f.n;
    std::vector<float> nu(n * nc), nv(n * nc), du(n), dv(n);
    derivative(f, num, nc, 0, arg_name(f, b, 1), nu.data());
    derivative(f, num, nc, 1, arg_name(f, b, 1), nv.data());
    derivative(f, den, 1, 0, arg_name(f, b, 2), du.data());
    derivative(f, den, 1, 1, arg_name(f, b, 2), dv.data());
    f.each(d.varying, [&](std::size_t i) {
        float* o = d.at(i);
        const bool use_u = std::fabs(du[i]) >= std::fabs(dv[i]);
        const float dd = use_u ? du[i] : dv[i];
        for (int k = 0; k < nc; ++k) {
            const float nn = use_u ? nu[i * nc + k] : nv[i * nc + k];
            o[k] = dd != 0.0f ? nn / dd : 0.0f;
        }
    });
}

bool bind_Deriv(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_f_or_triple(1) || !in.is_float(2) ||
        in.floats(0) != in.floats(1) || in.is_array(0))
        return false;
    b.fn = op_Deriv;
    return true;
}

/// The differences of P along u and v (Du(P) du, Dv(P) dv).
void p_differences(Frame& f, const Slot& p, const std::string& name,
                   std::vector<glm::vec3>& eu, std::vector<glm::vec3>& ev) {
    const std::size_t n = f.n;
    eu.resize(n);
    ev.resize(n);
    derivative(f, p, 3, 0, name, &eu[0].x);
    derivative(f, p, 3, 1, name, &ev[0].x);
    const ShadingBatch* batch = f.ctx->batch;
    for (std::size_t i = 0; i < n; ++i) {
        eu[i] *= batch && batch->du.size() > i ? batch->du[i] : 0.0f;
        ev[i] *= batch && batch->dv.size() > i ? batch->dv[i] : 0.0f;
    }
}

void op_area(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& p = f.slot(b, 1);
    const ShadingBatch* batch = f.ctx->batch;
    if (b.ia) { // area(P, "dicing")
        const std::string& kind = f.str(b, 2, f.first_active());
        if (kind == "dicing" && batch && batch->dicing_area.size() >= f.n) {
            f.each(d.varying, [&](std::size_t i) { *d.at(i) = batch->dicing_area[i]; });
            return;
        }
    }
    std::vector<glm::vec3> eu, ev;
    p_differences(f, p, arg_name(f, b, 1), eu, ev);
    f.each(d.varying,
           [&](std::size_t i) { *d.at(i) = glm::length(glm::cross(eu[i], ev[i])); });
}

bool bind_area(const BindInfo& in, BoundOp& b, std::string&) {
    if (!(in.nargs() == 2 || (in.nargs() == 3 && in.is_string(2))) || !in.is_float(0) ||
        !in.is_ptype(1))
        return false;
    b.ia = in.nargs() == 3 ? 1 : 0;
    b.fn = op_area;
    return true;
}

void op_calculatenormal(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& p = f.slot(b, 1);
    const std::size_t n = f.n;
    std::vector<float> du(n * 3), dv(n * 3);
    derivative(f, p, 3, 0, arg_name(f, b, 1), du.data());
    derivative(f, p, 3, 1, arg_name(f, b, 1), dv.data());
    // RenderMan's rule (as the dicer's normals): dPdu x dPdv, flipped when
    // the object-to-current transform mirrors or the orientation is inside.
    const ShadingBatch* batch = f.ctx->batch;
    const bool inside =
        batch && batch->primitive && attributes_of(*batch->primitive).orientation_inside;
    const bool mirror = glm::determinant(glm::dmat3(f.ctx->object_to_current)) < 0.0;
    const bool oriented = batch && batch->oriented_derivatives;
    const float sign = (!oriented && mirror != inside) ? -1.0f : 1.0f;
    f.each(d.varying, [&](std::size_t i) {
        glm::vec3 c = glm::cross(ld3(&du[i * 3]), ld3(&dv[i * 3])) * sign;
        const float len = glm::length(c);
        st3(d.at(i), len > 0.0f ? c / len : glm::vec3(0.0f));
    });
}

bool bind_calculatenormal(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_ptype(0) || !in.is_ptype(1)) return false;
    b.fn = op_calculatenormal;
    return true;
}

// --- components -----------------------------------------------------------------

void op_xcomp(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    const int c = b.ia;
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = x.at(i)[c]; });
}

bool bind_xcomp(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_float(0) || !in.is_triple_(1)) return false;
    b.ia = in.op.name[0] - 'x';
    b.fn = op_xcomp;
    return true;
}

void op_setxcomp(Frame& f, const BoundOp& b) {
    Slot& x = f.slot(b, 0);
    Slot& v = f.slot(b, 1);
    const int c = b.ia;
    f.each(x.varying, [&](std::size_t i) { x.at(i)[c] = *v.at(i); });
}

bool bind_setxcomp(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_triple_(0) || !in.is_float(1)) return false;
    b.ia = in.op.name[3] - 'x';
    b.fn = op_setxcomp;
    return true;
}

int comp_index(Frame& f, const BoundOp& b, float v, int count) {
    const float fl = std::floor(v);
    if (!(fl >= 0.0f) || fl >= static_cast<float>(count))
        f.fail(b, "component index " + std::to_string(v) + " out of range [0, " +
                      std::to_string(count) + ")");
    return static_cast<int>(fl);
}

void op_comp(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    const bool matrix = b.ia != 0;
    f.each(d.varying, [&](std::size_t i) {
        int k;
        if (matrix)
            k = comp_index(f, b, *f.ptr(b, 2, i), 4) * 4 +
                comp_index(f, b, *f.ptr(b, 3, i), 4);
        else
            k = comp_index(f, b, *f.ptr(b, 2, i), 3);
        *d.at(i) = x.at(i)[k];
    });
}

bool bind_comp(const BindInfo& in, BoundOp& b, std::string&) {
    if (!in.is_float(0)) return false;
    if (in.nargs() == 3 && in.is_triple_(1) && in.is_float(2)) {
        b.ia = 0;
    } else if (in.nargs() == 4 && in.is_matrix(1) && in.is_float(2) && in.is_float(3)) {
        b.ia = 1;
    } else {
        return false;
    }
    b.fn = op_comp;
    return true;
}

void op_setcomp(Frame& f, const BoundOp& b) {
    Slot& x = f.slot(b, 0);
    const bool matrix = b.ia != 0;
    f.each(x.varying, [&](std::size_t i) {
        int k;
        float v;
        if (matrix) {
            k = comp_index(f, b, *f.ptr(b, 1, i), 4) * 4 +
                comp_index(f, b, *f.ptr(b, 2, i), 4);
            v = *f.ptr(b, 3, i);
        } else {
            k = comp_index(f, b, *f.ptr(b, 1, i), 3);
            v = *f.ptr(b, 2, i);
        }
        x.at(i)[k] = v;
    });
}

bool bind_setcomp(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() == 3 && in.is_triple_(0) && in.is_float(1) && in.is_float(2)) {
        b.ia = 0;
    } else if (in.nargs() == 4 && in.is_matrix(0) && in.is_float(1) && in.is_float(2) &&
               in.is_float(3)) {
        b.ia = 1;
    } else {
        return false;
    }
    b.fn = op_setcomp;
    return true;
}

// --- vectors ------------------------------------------------------------------

void op_length(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = glm::length(ld3(x.at(i))); });
}

void op_normalize(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    f.each(d.varying, [&](std::size_t i) {
        const glm::vec3 v = ld3(x.at(i));
        const float len = glm::length(v);
        st3(d.at(i), len > 0.0f ? v / len : glm::vec3(0.0f));
    });
}

void op_distance(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        *d.at(i) = glm::distance(ld3(f.ptr(b, 1, i)), ld3(f.ptr(b, 2, i)));
    });
}

/// ptlined(P0, P1, Q): distance from Q to the segment P0-P1.
void op_ptlined(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const glm::vec3 p0 = ld3(f.ptr(b, 1, i)), p1 = ld3(f.ptr(b, 2, i)),
                        q = ld3(f.ptr(b, 3, i));
        const glm::vec3 s = p1 - p0;
        const float l2 = glm::dot(s, s);
        float t = l2 > 0.0f ? glm::dot(q - p0, s) / l2 : 0.0f;
        t = std::clamp(t, 0.0f, 1.0f);
        *d.at(i) = glm::distance(q, p0 + t * s);
    });
}

/// rotate(Q, angle, P0, P1): Q rotated by angle (radians) about the axis
/// through P0 and P1.
void op_rotate_point(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const glm::dvec3 q(ld3(f.ptr(b, 1, i)));
        const double angle = *f.ptr(b, 2, i);
        const glm::dvec3 p0(ld3(f.ptr(b, 3, i))), p1(ld3(f.ptr(b, 4, i)));
        const glm::dvec3 axis = p1 - p0;
        const double len = glm::length(axis);
        if (!(len > 0.0)) {
            st3(d.at(i), glm::vec3(q));
            return;
        }
        const glm::dvec3 k = axis / len;
        const glm::dvec3 v = q - p0;
        const double c = std::cos(angle), s = std::sin(angle);
        const glm::dvec3 r =
            v * c + glm::cross(k, v) * s + k * glm::dot(k, v) * (1.0 - c);
        st3(d.at(i), glm::vec3(p0 + r));
    });
}

void op_faceforward(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const bool has_ref = b.ia != 0;
    const int g_ng = f.bound->globals[G_Ng];
    const ShadingBatch* batch = f.ctx->batch;
    f.each(d.varying, [&](std::size_t i) {
        const glm::vec3 n = ld3(f.ptr(b, 1, i));
        const glm::vec3 I = ld3(f.ptr(b, 2, i));
        glm::vec3 ref;
        if (has_ref)
            ref = ld3(f.ptr(b, 3, i));
        else if (g_ng >= 0)
            ref = ld3(f.slots[g_ng].at(i));
        else if (batch && batch->Ng.size() > i)
            ref = batch->Ng[i];
        else if (batch && batch->N.size() > i)
            ref = batch->N[i];
        else
            ref = n;
        st3(d.at(i), glm::dot(I, ref) > 0.0f ? -n : n);
    });
}

void op_reflect(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const glm::vec3 I = ld3(f.ptr(b, 1, i)), n = ld3(f.ptr(b, 2, i));
        st3(d.at(i), I - 2.0f * glm::dot(I, n) * n);
    });
}

glm::vec3 refract_dir(const glm::vec3& I, const glm::vec3& n, float eta) {
    const float c = glm::dot(I, n);
    const float k = 1.0f - eta * eta * (1.0f - c * c);
    if (k < 0.0f) return glm::vec3(0.0f);
    return eta * I - (eta * c + std::sqrt(k)) * n;
}

void op_refract(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        st3(d.at(i),
            refract_dir(ld3(f.ptr(b, 1, i)), ld3(f.ptr(b, 2, i)), *f.ptr(b, 3, i)));
    });
}

/// fresnel(I, N, eta, Kr, Kt [, R, T]): unpolarised dielectric reflectance
/// for the relative index eta (as refract's: incident over transmitted);
/// total internal reflection gives Kr = 1, Kt = 0.
void op_fresnel(Frame& f, const BoundOp& b) {
    const bool rt = b.ia != 0;
    f.each(f.writes_varying(b), [&](std::size_t i) {
        const glm::vec3 I = ld3(f.ptr(b, 0, i)), n = ld3(f.ptr(b, 1, i));
        const float eta = *f.ptr(b, 2, i);
        const float c = std::fabs(glm::dot(I, n));
        const float k = 1.0f - eta * eta * (1.0f - c * c);
        float kr = 1.0f;
        if (k >= 0.0f) {
            const float ct = std::sqrt(k);
            const float rs = (eta * c - ct) / (eta * c + ct);
            const float rp = (c - eta * ct) / (c + eta * ct);
            kr = 0.5f * (rs * rs + rp * rp);
        }
        *f.ptr(b, 3, i) = kr;
        *f.ptr(b, 4, i) = 1.0f - kr;
        if (rt) {
            st3(f.ptr(b, 5, i), I - 2.0f * glm::dot(I, n) * n);
            st3(f.ptr(b, 6, i), refract_dir(I, n, eta));
        }
    });
}

bool bind_fresnel(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if ((n != 5 && n != 7) || !in.is_ptype(0) || !in.is_ptype(1) || !in.is_float(2) ||
        !in.is_float(3) || !in.is_float(4))
        return false;
    if (n == 7 && (!in.is_ptype(5) || !in.is_ptype(6))) return false;
    b.ia = n == 7;
    b.fn = op_fresnel;
    return true;
}

// --- transforms -------------------------------------------------------------

/// The matrix (glm, column vectors) that a transform call applies, for point i.
struct XformSpec {
    int from = -1;   // arg index of the "from" space string, or -1 (current)
    int to = -1;     // arg index of the "to" space string, or -1
    int matrix = -1; // arg index of the matrix, or -1
    int value = 0;   // arg index of the value
};

template <int Kind> // 0 point, 1 vector, 2 normal
void op_transform(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    XformSpec s;
    s.from = b.ia;
    s.to = b.ib;
    s.matrix = b.ic;
    s.value = b.id;
    auto matrix_at = [&](std::size_t i) {
        glm::dmat4 m(1.0);
        if (s.from >= 0) m = named_space_to_current(f, b, f.str(b, s.from, i));
        if (s.to >= 0)
            m = glm::inverse(named_space_to_current(f, b, f.str(b, s.to, i))) * m;
        if (s.matrix >= 0) m = ldm(f.ptr(b, s.matrix, i)) * m;
        return m;
    };
    const bool uniform_m = (s.from < 0 || !f.slot(b, s.from).varying) &&
                           (s.to < 0 || !f.slot(b, s.to).varying) &&
                           (s.matrix < 0 || !f.slot(b, s.matrix).varying);
    glm::dmat4 um(1.0), unorm(1.0);
    if (uniform_m && f.active > 0) {
        um = matrix_at(f.first_active());
        if (Kind == 2) unorm = glm::transpose(glm::inverse(um));
    }
    f.each(d.varying, [&](std::size_t i) {
        const glm::dmat4 m = uniform_m ? um : matrix_at(i);
        const glm::vec3 v = ld3(f.ptr(b, s.value, i));
        glm::vec3 r;
        if (Kind == 0)
            r = xform_point(m, v);
        else if (Kind == 1)
            r = xform_vector(m, v);
        else
            r = glm::vec3((uniform_m ? glm::dmat3(unorm)
                                     : glm::transpose(glm::inverse(glm::dmat3(m)))) *
                          glm::dvec3(v));
        st3(d.at(i), r);
    });
}

template <int Kind>
bool bind_transform(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 3 || n > 4 || !in.is_ptype(0) || !in.is_ptype(n - 1)) return false;
    b.ia = b.ib = b.ic = -1;
    b.id = n - 1;
    if (n == 3) {
        if (in.is_string(1))
            b.ib = 1; // (to, v)
        else if (in.is_matrix(1))
            b.ic = 1; // (m, v)
        else
            return false;
    } else {
        if (!in.is_string(1)) return false;
        b.ia = 1;
        if (in.is_string(2))
            b.ib = 2; // (from, to, v)
        else if (in.is_matrix(2))
            b.ic = 2; // (from, m, v)
        else
            return false;
    }
    b.fn = op_transform<Kind>;
    return true;
}

void op_depth(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const Camera& cam = f.ctx->services.scene().options.camera;
    const double near = cam.near_clip, far = cam.far_clip;
    f.each(d.varying, [&](std::size_t i) {
        *d.at(i) = static_cast<float>((f.ptr(b, 1, i)[2] - near) / (far - near));
    });
}

void op_ctransform(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const bool two = b.ia != 0;
    f.each(d.varying, [&](std::size_t i) {
        glm::vec3 c = ld3(f.ptr(b, two ? 3 : 2, i));
        if (two) {
            const std::string& from = f.str(b, 1, i);
            glm::vec3 rgb;
            if (!rsl_color_to_rgb(from, c, rgb))
                f.fail(b, "unknown colour space \"" + from + "\"");
            c = rgb;
        }
        const std::string& to = f.str(b, two ? 2 : 1, i);
        glm::vec3 out;
        if (!rsl_rgb_to_color(to, c, out))
            f.fail(b, "unknown colour space \"" + to + "\"");
        st3(d.at(i), out);
    });
}

bool bind_ctransform(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (!in.is_color(0) || !in.is_color(n - 1)) return false;
    if (n == 3 && in.is_string(1))
        b.ia = 0;
    else if (n == 4 && in.is_string(1) && in.is_string(2))
        b.ia = 1;
    else
        return false;
    b.fn = op_ctransform;
    return true;
}

// --- matrices -----------------------------------------------------------------

void op_determinant(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        *d.at(i) = static_cast<float>(glm::determinant(ldm(f.ptr(b, 1, i))));
    });
}

/// translate / rotate / scale (m, ...): m with the transform appended as
/// RiTranslate... append to the CTM (applied to points first).
template <int Kind> // 0 translate, 1 rotate, 2 scale
void op_matrix_xform(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const glm::dmat4 m = ldm(f.ptr(b, 1, i));
        glm::dmat4 t(1.0);
        if (Kind == 0) {
            t = glm::translate(glm::dmat4(1.0), glm::dvec3(ld3(f.ptr(b, 2, i))));
        } else if (Kind == 1) {
            const glm::dvec3 axis(ld3(f.ptr(b, 3, i)));
            if (glm::length(axis) > 0.0)
                t = glm::rotate(glm::dmat4(1.0), static_cast<double>(*f.ptr(b, 2, i)),
                                glm::normalize(axis));
        } else {
            t = glm::scale(glm::dmat4(1.0), glm::dvec3(ld3(f.ptr(b, 2, i))));
        }
        stm(d.at(i), m * t);
    });
}

#define SSS_SIMPLE_BINDER(name, cond, fnp)                                               \
    bool name(const BindInfo& in, BoundOp& b, std::string&) {                            \
        if (!(cond)) return false;                                                       \
        b.fn = fnp;                                                                      \
        return true;                                                                     \
    }
SSS_SIMPLE_BINDER(bind_length, in.nargs() == 2 && in.is_float(0) && in.is_triple_(1),
                  op_length)
SSS_SIMPLE_BINDER(bind_normalize, in.nargs() == 2 && in.is_ptype(0) && in.is_ptype(1),
                  op_normalize)
SSS_SIMPLE_BINDER(bind_distance,
                  in.nargs() == 3 && in.is_float(0) && in.is_ptype(1) && in.is_ptype(2),
                  op_distance)
SSS_SIMPLE_BINDER(bind_ptlined,
                  in.nargs() == 4 && in.is_float(0) && in.is_ptype(1) && in.is_ptype(2) &&
                      in.is_ptype(3),
                  op_ptlined)
SSS_SIMPLE_BINDER(bind_reflect,
                  in.nargs() == 3 && in.is_ptype(0) && in.is_ptype(1) && in.is_ptype(2),
                  op_reflect)
SSS_SIMPLE_BINDER(bind_refract,
                  in.nargs() == 4 && in.is_ptype(0) && in.is_ptype(1) && in.is_ptype(2) &&
                      in.is_float(3),
                  op_refract)
SSS_SIMPLE_BINDER(bind_depth, in.nargs() == 2 && in.is_float(0) && in.is_ptype(1),
                  op_depth)
SSS_SIMPLE_BINDER(bind_determinant, in.nargs() == 2 && in.is_float(0) && in.is_matrix(1),
                  op_determinant)
SSS_SIMPLE_BINDER(bind_translate,
                  in.nargs() == 3 && in.is_matrix(0) && in.is_matrix(1) && in.is_ptype(2),
                  op_matrix_xform<0>)
SSS_SIMPLE_BINDER(bind_scale,
                  in.nargs() == 3 && in.is_matrix(0) && in.is_matrix(1) && in.is_ptype(2),
                  op_matrix_xform<2>)
#undef SSS_SIMPLE_BINDER

bool bind_rotate(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() == 4 && in.is_matrix(0) && in.is_matrix(1) && in.is_float(2) &&
        in.is_ptype(3)) {
        b.fn = op_matrix_xform<1>;
        return true;
    }
    if (in.nargs() == 5 && in.is_ptype(0) && in.is_ptype(1) && in.is_float(2) &&
        in.is_ptype(3) && in.is_ptype(4)) {
        b.fn = op_rotate_point;
        return true;
    }
    return false;
}

bool bind_faceforward(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if ((n != 3 && n != 4) || !in.is_ptype(0) || !in.is_ptype(1) || !in.is_ptype(2))
        return false;
    if (n == 4 && !in.is_ptype(3)) return false;
    b.ia = n == 4;
    b.fn = op_faceforward;
    return true;
}

} // namespace

void register_geometry(BinderTable& t) {
    t["Du"] = bind_D;
    t["Dv"] = bind_D;
    t["Deriv"] = bind_Deriv;
    t["area"] = bind_area;
    t["calculatenormal"] = bind_calculatenormal;
    t["xcomp"] = bind_xcomp;
    t["ycomp"] = bind_xcomp;
    t["zcomp"] = bind_xcomp;
    t["setxcomp"] = bind_setxcomp;
    t["setycomp"] = bind_setxcomp;
    t["setzcomp"] = bind_setxcomp;
    t["comp"] = bind_comp;
    t["setcomp"] = bind_setcomp;
    t["length"] = bind_length;
    t["normalize"] = bind_normalize;
    t["distance"] = bind_distance;
    t["ptlined"] = bind_ptlined;
    t["rotate"] = bind_rotate;
    t["faceforward"] = bind_faceforward;
    t["reflect"] = bind_reflect;
    t["refract"] = bind_refract;
    t["fresnel"] = bind_fresnel;
    t["transform"] = bind_transform<0>;
    t["vtransform"] = bind_transform<1>;
    t["ntransform"] = bind_transform<2>;
    t["depth"] = bind_depth;
    t["ctransform"] = bind_ctransform;
    t["determinant"] = bind_determinant;
    t["translate"] = bind_translate;
    t["scale"] = bind_scale;
}

} // namespace sss::detail

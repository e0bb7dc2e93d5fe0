// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_ops.cpp
/// The operators of program.h: assign, arithmetic (component by component, a
/// float operand replicated; matrix products and A/B = A * inverse(B)),
/// dot, cross, comparisons, logic, array elements, construct and cast with
/// spaces.

#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "engine_internal.h"
#include "rsl_math.h"

namespace sss::detail {

namespace {

// --- assign ---------------------------------------------------------------

void op_copy(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& s = f.slot(b, 1);
    const std::size_t bytes = sizeof(float) * static_cast<std::size_t>(d.nf);
    if (d.nf == 1) {
        f.each(d.varying, [&](std::size_t i) { *d.at(i) = *s.at(i); });
        return;
    }
    f.each(d.varying, [&](std::size_t i) { std::memmove(d.at(i), s.at(i), bytes); });
}

void op_splat(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& s = f.slot(b, 1);
    const int nf = d.nf;
    f.each(d.varying, [&](std::size_t i) {
        const float v = *s.at(i);
        float* o = d.at(i);
        for (int k = 0; k < nf; ++k) o[k] = v;
    });
}

void op_float_to_matrix(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& s = f.slot(b, 1);
    f.each(d.varying, [&](std::size_t i) {
        const float v = *s.at(i);
        float* o = d.at(i);
        for (int k = 0; k < 16; ++k) o[k] = (k % 5 == 0) ? v : 0.0f;
    });
}

bool bind_assign(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2) return false;
    const Symbol& d = in.sym(0);
    const Symbol& s = in.sym(1);
    const bool dstr = d.type.type == ShadingType::String;
    const bool sstr = s.type.type == ShadingType::String;
    if (dstr != sstr) return false;
    if (d.type.floats() == s.type.floats() &&
        (d.type.type == s.type.type || d.type.is_array() == s.type.is_array())) {
        if (!d.type.is_array() && d.type.type != s.type.type) {
            // Different types of one size: triples among themselves.
            if (!(is_triple(d.type.type) && is_triple(s.type.type))) return false;
        }
        b.fn = op_copy;
        return true;
    }
    if (in.is_float(1) && in.is_triple_(0)) {
        b.fn = op_splat;
        return true;
    }
    if (in.is_float(1) && in.is_matrix(0)) {
        b.fn = op_float_to_matrix;
        return true;
    }
    return false;
}

// --- arithmetic -----------------------------------------------------------

struct Add {
    float operator()(float a, float b) const { return a + b; }
};
struct Sub {
    float operator()(float a, float b) const { return a - b; }
};
struct Mul {
    float operator()(float a, float b) const { return a * b; }
};
struct Div {
    float operator()(float a, float b) const { return a / b; }
};

template <class F>
void op_bin(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    const int nd = d.nf;
    const F fn;
    if (nd == 1) {
        f.each(d.varying, [&](std::size_t i) { *d.at(i) = fn(*x.at(i), *y.at(i)); });
        return;
    }
    const int ax = x.nf == 1 ? 0 : 1;
    const int ay = y.nf == 1 ? 0 : 1;
    f.each(d.varying, [&](std::size_t i) {
        float* o = d.at(i);
        const float* p = x.at(i);
        const float* q = y.at(i);
        float r[16];
        for (int k = 0; k < nd; ++k) r[k] = fn(p[k * ax], q[k * ay]);
        std::memcpy(o, r, sizeof(float) * nd);
    });
}

void op_neg(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    const int nd = d.nf;
    f.each(d.varying, [&](std::size_t i) {
        float* o = d.at(i);
        const float* p = x.at(i);
        for (int k = 0; k < nd; ++k) o[k] = -p[k];
    });
}

void op_matmul(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    f.each(d.varying, [&](std::size_t i) {
        // RSL (row vectors) A*B is glm B*A.
        stm(d.at(i), ldm(y.at(i)) * ldm(x.at(i)));
    });
}

void op_matdiv(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    f.each(d.varying, [&](std::size_t i) {
        // A * inverse(B) in RSL order.
        stm(d.at(i), glm::inverse(ldm(y.at(i))) * ldm(x.at(i)));
    });
}

bool numeric(const BindInfo& in, int k) {
    return !in.is_array(k) && in.type(k) != ShadingType::String &&
           in.type(k) != ShadingType::Void;
}

template <class F>
bool bind_arith(const BindInfo& in, BoundOp& b, bool matrix_special, OpFn matrix_fn) {
    if (in.nargs() != 3 || !numeric(in, 0) || !numeric(in, 1) || !numeric(in, 2))
        return false;
    const int nd = in.floats(0), na = in.floats(1), nb = in.floats(2);
    if (matrix_special && in.is_matrix(1) && in.is_matrix(2)) {
        if (!in.is_matrix(0)) return false;
        b.fn = matrix_fn;
        return true;
    }
    if ((na != 1 && na != nd) || (nb != 1 && nb != nd)) return false;
    if (nd == 16 && na == 16 && nb == 16 && matrix_special) return false;
    b.fn = op_bin<F>;
    return true;
}

bool bind_add(const BindInfo& in, BoundOp& b, std::string&) {
    return bind_arith<Add>(in, b, false, nullptr);
}
bool bind_sub(const BindInfo& in, BoundOp& b, std::string&) {
    return bind_arith<Sub>(in, b, false, nullptr);
}
bool bind_mul(const BindInfo& in, BoundOp& b, std::string&) {
    return bind_arith<Mul>(in, b, true, op_matmul);
}
bool bind_div(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() == 3 && in.is_matrix(2) && !in.is_matrix(1)) return false;
    return bind_arith<Div>(in, b, true, op_matdiv);
}
bool bind_neg(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !numeric(in, 0) || in.floats(0) != in.floats(1)) return false;
    b.fn = op_neg;
    return true;
}

void op_dot(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    f.each(d.varying, [&](std::size_t i) {
        const float* p = x.at(i);
        const float* q = y.at(i);
        *d.at(i) = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    });
}

void op_cross(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    f.each(d.varying,
           [&](std::size_t i) { st3(d.at(i), glm::cross(ld3(x.at(i)), ld3(y.at(i)))); });
}

bool bind_dot(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || !in.is_triple_(1) || !in.is_triple_(2))
        return false;
    b.fn = op_dot;
    return true;
}
bool bind_cross(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_triple_(0) || !in.is_triple_(1) || !in.is_triple_(2))
        return false;
    b.fn = op_cross;
    return true;
}

// --- comparisons and logic --------------------------------------------------

template <bool Equal>
void op_eq(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    const int n = std::max(x.nf, y.nf);
    const int ax = x.nf == 1 ? 0 : 1;
    const int ay = y.nf == 1 ? 0 : 1;
    f.each(d.varying, [&](std::size_t i) {
        const float* p = x.at(i);
        const float* q = y.at(i);
        bool eq = true;
        for (int k = 0; k < n; ++k) eq = eq && p[k * ax] == q[k * ay];
        *d.at(i) = (eq == Equal) ? 1.0f : 0.0f;
    });
}

struct Lt {
    bool operator()(float a, float b) const { return a < b; }
};
struct Le {
    bool operator()(float a, float b) const { return a <= b; }
};
struct Gt {
    bool operator()(float a, float b) const { return a > b; }
};
struct Ge {
    bool operator()(float a, float b) const { return a >= b; }
};
struct And {
    bool operator()(float a, float b) const { return a != 0.0f && b != 0.0f; }
};
struct Or {
    bool operator()(float a, float b) const { return a != 0.0f || b != 0.0f; }
};

template <class F>
void op_rel(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    Slot& y = f.slot(b, 2);
    const F fn;
    f.each(d.varying,
           [&](std::size_t i) { *d.at(i) = fn(*x.at(i), *y.at(i)) ? 1.0f : 0.0f; });
}

void op_not(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& x = f.slot(b, 1);
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = *x.at(i) == 0.0f ? 1.0f : 0.0f; });
}

bool bind_eq(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || in.is_array(1) || in.is_array(2))
        return false;
    const bool s1 = in.is_string(1), s2 = in.is_string(2);
    if (s1 != s2) return false;
    const int na = in.floats(1), nb = in.floats(2);
    if (na != nb && na != 1 && nb != 1) return false;
    b.fn = in.op.name == "eq" ? op_eq<true> : op_eq<false>;
    return true;
}

template <class F>
bool bind_rel(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || !in.is_float(1) || !in.is_float(2))
        return false;
    b.fn = op_rel<F>;
    return true;
}

bool bind_not(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_float(0) || !in.is_float(1)) return false;
    b.fn = op_not;
    return true;
}

// --- arrays ---------------------------------------------------------------

void op_aref(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& a = f.slot(b, 1);
    Slot& idx = f.slot(b, 2);
    const int ne = b.ia, length = b.ib;
    f.each(d.varying, [&](std::size_t i) {
        const int e = array_element(f, b, idx, i, length);
        std::memmove(d.at(i), a.at(i) + e * ne, sizeof(float) * ne);
    });
}

void op_aassign(Frame& f, const BoundOp& b) {
    Slot& a = f.slot(b, 0);
    Slot& idx = f.slot(b, 1);
    Slot& s = f.slot(b, 2);
    const int ne = b.ia, length = b.ib;
    const bool splat = s.nf == 1 && ne != 1;
    f.each(a.varying, [&](std::size_t i) {
        const int e = array_element(f, b, idx, i, length);
        float* o = a.at(i) + e * ne;
        if (splat) {
            for (int k = 0; k < ne; ++k) o[k] = *s.at(i);
        } else {
            std::memmove(o, s.at(i), sizeof(float) * ne);
        }
    });
}

bool bind_aref(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_array(1) || !in.is_float(2) || in.is_array(0))
        return false;
    const int ne = shading_type_floats(in.type(1));
    if (in.floats(0) != ne) return false;
    b.ia = ne;
    b.ib = in.sym(1).type.array;
    b.fn = in.sym(1).type.is_resizable() ? op_aref_resizable : op_aref;
    return true;
}

bool bind_aassign(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_array(0) || !in.is_float(1) || in.is_array(2))
        return false;
    const int ne = shading_type_floats(in.type(0));
    if (in.floats(2) != ne && !(in.is_float(2) && in.type(0) != ShadingType::String))
        return false;
    if ((in.type(0) == ShadingType::String) != in.is_string(2)) return false;
    b.ia = ne;
    b.ib = in.sym(0).type.array;
    b.fn = in.sym(0).type.is_resizable() ? op_aassign_resizable : op_aassign;
    return true;
}

// --- construct and cast ---------------------------------------------------

/// Converts a triple of type t given in `space` to the current space (or a
/// colour space to rgb). Throws for an unknown space.
struct SpaceConv {
    bool identity = true;
    bool color = false;
    std::string name;
    glm::dmat4 m{1.0};
};

SpaceConv space_conv(Frame& f, const BoundOp& b, ShadingType t,
                     const std::string& space) {
    SpaceConv c;
    c.name = space;
    if (t == ShadingType::Color) {
        if (space == "rgb" || space == "RGB" || space.empty()) return c;
        glm::vec3 dummy;
        if (!rsl_color_to_rgb(space, glm::vec3(0.0f), dummy))
            f.fail(b, "unknown colour space \"" + space + "\"");
        c.identity = false;
        c.color = true;
        return c;
    }
    if (space.empty() || space == "current") return c;
    c.m = named_space_to_current(f, b, space);
    c.identity = false;
    return c;
}

inline glm::vec3 apply(const SpaceConv& c, ShadingType t, const glm::vec3& v) {
    if (c.identity) return v;
    if (c.color) {
        glm::vec3 rgb(0.0f);
        rsl_color_to_rgb(c.name, v, rgb);
        return rgb;
    }
    return xform_typed(t, c.m, v);
}

/// construct d [space] x y z
void op_construct3(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const int first = b.ia; // 1 without a space, 2 with
    Slot& x = f.slot(b, first);
    Slot& y = f.slot(b, first + 1);
    Slot& z = f.slot(b, first + 2);
    const ShadingType t = static_cast<ShadingType>(b.ib);
    const Slot* sp = first == 2 ? &f.slot(b, 1) : nullptr;
    if (sp && sp->varying) {
        f.each(d.varying, [&](std::size_t i) {
            const SpaceConv c = space_conv(f, b, t, f.str(b, 1, i));
            st3(d.at(i), apply(c, t, glm::vec3(*x.at(i), *y.at(i), *z.at(i))));
        });
        return;
    }
    const SpaceConv c = sp ? space_conv(f, b, t, f.str(b, 1)) : SpaceConv{};
    f.each(d.varying, [&](std::size_t i) {
        st3(d.at(i), apply(c, t, glm::vec3(*x.at(i), *y.at(i), *z.at(i))));
    });
}

/// A matrix given in `space`: current -> space prepended (RSL order), i.e.
/// glm M * inverse(space_to_current).
glm::dmat4 matrix_in_space(Frame& f, const BoundOp& b, const std::string& space,
                           const glm::dmat4& m) {
    if (space.empty() || space == "current") return m;
    const glm::dmat4 to = named_space_to_current(f, b, space);
    return m * glm::inverse(to);
}

/// construct d [space] m00..m33 | construct d space f | construct d f
void op_construct_matrix(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const int first = b.ia;
    const bool scalar = b.ib != 0;
    const bool has_space = first == 2;
    std::string space = has_space ? f.str(b, 1, f.first_active()) : std::string();
    f.each(d.varying, [&](std::size_t i) {
        glm::dmat4 m(0.0);
        if (scalar) {
            m = glm::dmat4(static_cast<double>(*f.ptr(b, first, i)));
        } else {
            float v[16];
            for (int k = 0; k < 16; ++k) v[k] = *f.ptr(b, first + k, i);
            m = ldm(v);
        }
        if (has_space) {
            if (f.slot(b, 1).varying) space = f.str(b, 1, i);
            m = matrix_in_space(f, b, space, m);
        }
        stm(d.at(i), m);
    });
}

bool bind_construct(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 2 || in.is_array(0)) return false;
    const bool space = in.is_string(1);
    const int first = space ? 2 : 1;
    for (int k = first; k < n; ++k)
        if (!in.is_float(k)) return false;
    const int values = n - first;
    if (in.is_triple_(0)) {
        if (values != 3) return false;
        b.ia = first;
        b.ib = static_cast<int>(in.type(0));
        b.fn = op_construct3;
        return true;
    }
    if (in.is_matrix(0)) {
        if (values != 16 && values != 1) return false;
        b.ia = first;
        b.ib = values == 1 ? 1 : 0;
        b.fn = op_construct_matrix;
        return true;
    }
    return false;
}

/// cast d space s
void op_cast3(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& s = f.slot(b, 2);
    const ShadingType t = static_cast<ShadingType>(b.ib);
    const bool single = s.nf == 1;
    auto value = [&](std::size_t i) {
        return single ? glm::vec3(*s.at(i)) : ld3(s.at(i));
    };
    if (f.slot(b, 1).varying) {
        f.each(d.varying, [&](std::size_t i) {
            st3(d.at(i), apply(space_conv(f, b, t, f.str(b, 1, i)), t, value(i)));
        });
        return;
    }
    const SpaceConv c = space_conv(f, b, t, f.str(b, 1, f.first_active()));
    f.each(d.varying, [&](std::size_t i) { st3(d.at(i), apply(c, t, value(i))); });
}

void op_cast_matrix(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& s = f.slot(b, 2);
    const bool single = s.nf == 1;
    f.each(d.varying, [&](std::size_t i) {
        const glm::dmat4 m =
            single ? glm::dmat4(static_cast<double>(*s.at(i))) : ldm(s.at(i));
        stm(d.at(i), matrix_in_space(f, b, f.str(b, 1, i), m));
    });
}

bool bind_cast(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_string(1) || in.is_array(0) || in.is_array(2))
        return false;
    if (in.is_triple_(0) && (in.is_triple_(2) || in.is_float(2))) {
        b.ib = static_cast<int>(in.type(0));
        b.fn = op_cast3;
        return true;
    }
    if (in.is_matrix(0) && (in.is_matrix(2) || in.is_float(2))) {
        b.fn = op_cast_matrix;
        return true;
    }
    return false;
}

} // namespace

void register_core_ops(BinderTable& t) {
    t["assign"] = bind_assign;
    t["neg"] = bind_neg;
    t["add"] = bind_add;
    t["sub"] = bind_sub;
    t["mul"] = bind_mul;
    t["div"] = bind_div;
    t["dot"] = bind_dot;
    t["cross"] = bind_cross;
    t["eq"] = bind_eq;
    t["ne"] = bind_eq;
    t["lt"] = bind_rel<Lt>;
    t["le"] = bind_rel<Le>;
    t["gt"] = bind_rel<Gt>;
    t["ge"] = bind_rel<Ge>;
    t["and"] = bind_rel<And>;
    t["or"] = bind_rel<Or>;
    t["not"] = bind_not;
    t["aref"] = bind_aref;
    t["aassign"] = bind_aassign;
    t["construct"] = bind_construct;
    t["cast"] = bind_cast;
}

} // namespace sss::detail

// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_math.cpp
/// Math built-ins (RISpec 15.1): component-by-component functions of floats
/// and triples, min/max/clamp/mix/step/smoothstep/filterstep, spline,
/// random, the noise family (rsl_math.h), and the string functions concat,
/// format, printf and match.
///
/// random() is deterministic: point i draws hash(batch seed, i, op, call
/// count of that op in the batch) (ShadingBatch::seed), whatever the threads.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "engine_internal.h"
#include "rsl_math.h"
#include "sss/util/hash.h"

namespace sss::detail {

namespace {

constexpr float kPiF = 3.14159265358979323846f;

// --- component by component -------------------------------------------------

/// Runs F::eval(values, count) per component: d = F(args...), each argument a
/// float (replicated) or of d's size.
template <class F>
void op_elem(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const int na = static_cast<int>(b.op->args.size()) - 1;
    const int nd = d.nf;
    Slot* s[64];
    int step[64];
    for (int j = 0; j < na; ++j) {
        s[j] = &f.slot(b, j + 1);
        step[j] = s[j]->nf == 1 ? 0 : 1;
    }
    float v[64] = {};
    f.each(d.varying, [&](std::size_t i) {
        const float* p[64];
        for (int j = 0; j < na; ++j) p[j] = s[j]->at(i);
        float r[16];
        for (int k = 0; k < nd; ++k) {
            for (int j = 0; j < na; ++j) v[j] = p[j][k * step[j]];
            r[k] = F::eval(v, na);
        }
        std::memcpy(d.at(i), r, sizeof(float) * nd);
    });
}

/// Arity: the exact argument count, or -2 for "one or more".
template <class F, int Arity>
bool bind_elem(const BindInfo& in, BoundOp& b, std::string&) {
    const int na = in.nargs() - 1;
    if (Arity >= 0 ? na != Arity : na < 1) return false;
    if (in.is_array(0) || !(in.is_float(0) || in.is_triple_(0))) return false;
    const int nd = in.floats(0);
    for (int k = 1; k <= na; ++k) {
        if (in.is_array(k) || in.is_string(k) || in.is_matrix(k)) return false;
        if (in.floats(k) != 1 && in.floats(k) != nd) return false;
    }
    b.fn = op_elem<F>;
    return true;
}

#define SSS_UNARY(Name, expr)                                                            \
    struct Name {                                                                        \
        static float eval(const float* v, int) {                                         \
            const float x = v[0];                                                        \
            return (expr);                                                               \
        }                                                                                \
    };
SSS_UNARY(FRadians, x* kPiF / 180.0f)
SSS_UNARY(FDegrees, x * 180.0f / kPiF)
SSS_UNARY(FSin, std::sin(x))
SSS_UNARY(FCos, std::cos(x))
SSS_UNARY(FTan, std::tan(x))
SSS_UNARY(FAsin, std::asin(x))
SSS_UNARY(FAcos, std::acos(x))
SSS_UNARY(FAtan, std::atan(x))
SSS_UNARY(FExp, std::exp(x))
SSS_UNARY(FSqrt, std::sqrt(x))
SSS_UNARY(FInvSqrt, 1.0f / std::sqrt(x))
SSS_UNARY(FLog, std::log(x))
SSS_UNARY(FAbs, std::fabs(x))
SSS_UNARY(FSign, x > 0.0f ? 1.0f : (x < 0.0f ? -1.0f : 0.0f))
SSS_UNARY(FFloor, std::floor(x))
SSS_UNARY(FCeil, std::ceil(x))
SSS_UNARY(FRound, std::round(x))
SSS_UNARY(FErf, std::erf(x))
SSS_UNARY(FErfc, std::erfc(x))
#undef SSS_UNARY

struct FAtan2 {
    static float eval(const float* v, int) { return std::atan2(v[0], v[1]); }
};
struct FPow {
    static float eval(const float* v, int) { return std::pow(v[0], v[1]); }
};
struct FLogBase {
    static float eval(const float* v, int) { return std::log(v[0]) / std::log(v[1]); }
};
struct FMod {
    static float eval(const float* v, int) {
        return v[0] - v[1] * std::floor(v[0] / v[1]);
    }
};
struct FMin {
    static float eval(const float* v, int n) {
        float r = v[0];
        for (int j = 1; j < n; ++j) r = std::min(r, v[j]);
        return r;
    }
};
struct FMax {
    static float eval(const float* v, int n) {
        float r = v[0];
        for (int j = 1; j < n; ++j) r = std::max(r, v[j]);
        return r;
    }
};
struct FClamp {
    // min tested first (as Aqsis does): when min > max a value below min is
    // min, so the published volume shaders' loops that clamp their step to
    // [min, what remains] reach their end.
    static float eval(const float* v, int) {
        return v[0] < v[1] ? v[1] : (v[0] > v[2] ? v[2] : v[0]);
    }
};
struct FMix {
    static float eval(const float* v, int) { return v[0] * (1.0f - v[2]) + v[1] * v[2]; }
};
struct FStep {
    static float eval(const float* v, int) { return v[1] < v[0] ? 0.0f : 1.0f; }
};
struct FSmoothstep {
    static float eval(const float* v, int) {
        const float e0 = v[0], e1 = v[1], x = v[2];
        if (x < e0) return 0.0f;
        if (x >= e1) return 1.0f;
        const float t = (x - e0) / (e1 - e0);
        return t * t * (3.0f - 2.0f * t);
    }
};

// --- filterstep -------------------------------------------------------------

/// filterstep(edge, s1 [, s2], "width" w): the step box-filtered over
/// [s1, s2], or over s1 -+ half the point's width |Du(s1) du| + |Dv(s1) dv|.
void op_filterstep(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& edge = f.slot(b, 1);
    Slot& s1 = f.slot(b, 2);
    const bool two = b.ia != 0;
    float wscale = 1.0f;
    for_options(f, b, two ? 4 : 3, [&](const std::string& name, int k) {
        if (name == "width" && f.slot(b, k).nf == 1)
            wscale = *f.ptr(b, k, f.first_active());
    });
    std::vector<float> width;
    if (!two) {
        const std::size_t n = f.n;
        std::vector<float> du(n), dv(n);
        const std::string& name = f.program->symbols[b.op->args[2]].name;
        derivative(f, s1, 1, 0, name, du.data());
        derivative(f, s1, 1, 1, name, dv.data());
        const int* g = f.bound->globals;
        width.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const float gdu = g[G_du] >= 0 ? *f.slots[g[G_du]].at(i) : 0.0f;
            const float gdv = g[G_dv] >= 0 ? *f.slots[g[G_dv]].at(i) : 0.0f;
            const float fdu =
                f.ctx->batch && f.ctx->batch->du.size() > i ? f.ctx->batch->du[i] : gdu;
            const float fdv =
                f.ctx->batch && f.ctx->batch->dv.size() > i ? f.ctx->batch->dv[i] : gdv;
            width[i] = (std::fabs(du[i] * fdu) + std::fabs(dv[i] * fdv)) * wscale;
        }
    }
    f.each(d.varying, [&](std::size_t i) {
        const float e = *edge.at(i);
        float lo, hi;
        if (two) {
            lo = std::min(*s1.at(i), *f.ptr(b, 3, i));
            hi = std::max(*s1.at(i), *f.ptr(b, 3, i));
        } else {
            const float c = *s1.at(i);
            lo = c - 0.5f * width[i];
            hi = c + 0.5f * width[i];
        }
        float r;
        if (!(hi > lo))
            r = lo < e ? 0.0f : 1.0f;
        else
            r = std::clamp((hi - e) / (hi - lo), 0.0f, 1.0f);
        *d.at(i) = r;
    });
}

bool bind_filterstep(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 3 || !in.is_float(0) || !in.is_float(1) || !in.is_float(2)) return false;
    const bool two = n >= 4 && in.is_float(3) && (n - 4) % 2 == 0;
    const int opts = two ? 4 : 3;
    if ((n - opts) % 2 != 0) return false;
    for (int k = opts; k < n; k += 2)
        if (!in.is_string(k)) return false;
    b.ia = two ? 1 : 0;
    b.fn = op_filterstep;
    return true;
}

// --- spline -----------------------------------------------------------------

void op_spline(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const bool basis = b.ia != 0;
    const bool array = b.ib != 0;
    const int tk = basis ? 2 : 1;
    const int nc = d.nf;
    const int nargs = static_cast<int>(b.op->args.size());
    std::vector<float> values;
    const std::string bname = basis ? f.str(b, 1, f.first_active()) : "catmull-rom";
    f.each(d.varying, [&](std::size_t i) {
        int count;
        const float* vals;
        if (array) {
            Slot& a = f.slot(b, tk + 1);
            count = a.nf / nc;
            vals = a.at(i);
        } else {
            count = nargs - tk - 1;
            values.resize(static_cast<std::size_t>(count) * nc);
            for (int j = 0; j < count; ++j)
                std::memcpy(values.data() + j * nc, f.ptr(b, tk + 1 + j, i),
                            sizeof(float) * nc);
            vals = values.data();
        }
        if (!rsl_spline(bname, *f.ptr(b, tk, i), vals, count, nc, d.at(i)))
            f.fail(b, "spline: unknown basis \"" + bname + "\" or too few values (" +
                          std::to_string(count) + ")");
    });
}

bool bind_spline(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 2 || in.is_array(0) || !(in.is_float(0) || in.is_triple_(0))) return false;
    const bool basis = in.is_string(1);
    const int tk = basis ? 2 : 1;
    if (tk >= n || !in.is_float(tk)) return false;
    const int nc = in.floats(0);
    if (n == tk + 2 && in.is_array(tk + 1)) {
        if (shading_type_floats(in.type(tk + 1)) != nc) return false;
        b.ib = 1;
    } else {
        for (int k = tk + 1; k < n; ++k)
            if (in.is_array(k) || in.floats(k) != nc || in.is_string(k)) return false;
        b.ib = 0;
    }
    b.ia = basis ? 1 : 0;
    b.fn = op_spline;
    return true;
}

// --- random -----------------------------------------------------------------

void op_random(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const uint64_t seed = f.ctx->batch ? f.ctx->batch->seed : 0;
    const uint32_t call = f.calls[b.index]++;
    const int nf = d.nf;
    f.each(d.varying, [&](std::size_t i) {
        uint64_t h = point_hash(seed, d.varying ? i : 0, b.index, call);
        float* o = d.at(i);
        for (int k = 0; k < nf; ++k) {
            o[k] = static_cast<float>(unit_double(h));
            h = splitmix64(h);
        }
    });
}

bool bind_random(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 1 || !(in.is_float(0) || in.is_triple_(0))) return false;
    b.fn = op_random;
    return true;
}

// --- noise ------------------------------------------------------------------

enum NoiseKind { NoiseNoise, NoisePeriodic, NoiseCell };
enum NoiseArgs { A_f, A_ff, A_p, A_pf };

template <int Kind>
void op_noise(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const bool vec = d.nf == 3;
    const int pattern = b.ia;
    f.each(d.varying, [&](std::size_t i) {
        auto F = [&](int k) { return *f.ptr(b, k, i); };
        auto P = [&](int k) { return ld3(f.ptr(b, k, i)); };
        float r = 0.0f;
        glm::vec3 v(0.0f);
        if constexpr (Kind == NoiseNoise) {
            switch (pattern) {
            case A_f:
                vec ? (void)(v = rsl_vnoise(F(1))) : (void)(r = rsl_noise(F(1)));
                break;
            case A_ff:
                vec ? (void)(v = rsl_vnoise(F(1), F(2)))
                    : (void)(r = rsl_noise(F(1), F(2)));
                break;
            case A_p:
                vec ? (void)(v = rsl_vnoise(P(1))) : (void)(r = rsl_noise(P(1)));
                break;
            default:
                vec ? (void)(v = rsl_vnoise(P(1), F(2)))
                    : (void)(r = rsl_noise(P(1), F(2)));
            }
        } else if constexpr (Kind == NoiseCell) {
            switch (pattern) {
            case A_f:
                vec ? (void)(v = rsl_vcellnoise(F(1))) : (void)(r = rsl_cellnoise(F(1)));
                break;
            case A_ff:
                vec ? (void)(v = rsl_vcellnoise(F(1), F(2)))
                    : (void)(r = rsl_cellnoise(F(1), F(2)));
                break;
            case A_p:
                vec ? (void)(v = rsl_vcellnoise(P(1))) : (void)(r = rsl_cellnoise(P(1)));
                break;
            default:
                vec ? (void)(v = rsl_vcellnoise(P(1), F(2)))
                    : (void)(r = rsl_cellnoise(P(1), F(2)));
            }
        } else {
            switch (pattern) {
            case A_f: // (x, px)
                vec ? (void)(v = rsl_vpnoise(F(1), F(2)))
                    : (void)(r = rsl_pnoise(F(1), F(2)));
                break;
            case A_ff: // (x, y, px, py)
                vec ? (void)(v = rsl_vpnoise(F(1), F(2), F(3), F(4)))
                    : (void)(r = rsl_pnoise(F(1), F(2), F(3), F(4)));
                break;
            case A_p: // (p, period)
                vec ? (void)(v = rsl_vpnoise(P(1), P(2)))
                    : (void)(r = rsl_pnoise(P(1), P(2)));
                break;
            default: // (p, t, pp, pt)
                vec ? (void)(v = rsl_vpnoise(P(1), F(2), P(3), F(4)))
                    : (void)(r = rsl_pnoise(P(1), F(2), P(3), F(4)));
            }
        }
        if (vec)
            st3(d.at(i), v);
        else
            *d.at(i) = r;
    });
}

template <int Kind>
bool bind_noise(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 2 || !(in.is_float(0) || in.is_triple_(0))) return false;
    int pattern = -1;
    if (Kind != NoisePeriodic) {
        if (n == 2 && in.is_float(1))
            pattern = A_f;
        else if (n == 3 && in.is_float(1) && in.is_float(2))
            pattern = A_ff;
        else if (n == 2 && in.is_ptype(1))
            pattern = A_p;
        else if (n == 3 && in.is_ptype(1) && in.is_float(2))
            pattern = A_pf;
    } else {
        if (n == 3 && in.is_float(1) && in.is_float(2))
            pattern = A_f;
        else if (n == 5 && in.is_float(1) && in.is_float(2) && in.is_float(3) &&
                 in.is_float(4))
            pattern = A_ff;
        else if (n == 3 && in.is_ptype(1) && in.is_ptype(2))
            pattern = A_p;
        else if (n == 5 && in.is_ptype(1) && in.is_float(2) && in.is_ptype(3) &&
                 in.is_float(4))
            pattern = A_pf;
    }
    if (pattern < 0) return false;
    b.ia = pattern;
    b.fn = op_noise<Kind>;
    return true;
}

// --- strings ----------------------------------------------------------------

bool any_varying(Frame& f, const BoundOp& b, int first) {
    for (std::size_t k = first; k < b.op->args.size(); ++k)
        if (f.slots[b.op->args[k]].varying) return true;
    return false;
}

std::string format_at(Frame& f, const BoundOp& b, int pattern, std::size_t i) {
    const int n = static_cast<int>(b.op->args.size());
    std::vector<RslFormatArg> args;
    std::vector<const std::string*> keep;
    args.reserve(n);
    for (int k = pattern + 1; k < n; ++k) {
        const Symbol& sym = f.program->symbols[b.op->args[k]];
        RslFormatArg a;
        a.type = sym.type.type;
        a.numbers = f.ptr(b, k, i);
        if (a.type == ShadingType::String) a.string = &f.str(b, k, i);
        args.push_back(a);
    }
    try {
        return rsl_format(f.str(b, pattern, i), args);
    } catch (const ValueError& e) {
        f.fail(b, e.what());
    }
}

void op_format(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying,
           [&](std::size_t i) { *d.at(i) = f.intern(b, format_at(f, b, 1, i)); });
}

void op_printf(Frame& f, const BoundOp& b) {
    const bool varying = any_varying(f, b, 0);
    f.each(varying,
           [&](std::size_t i) { f.ctx->services.message(format_at(f, b, 0, i)); });
}

bool bind_format(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 2 || !in.is_string(0) || !in.is_string(1)) return false;
    for (int k = 2; k < in.nargs(); ++k)
        if (in.is_array(k)) return false;
    b.fn = op_format;
    return true;
}

bool bind_printf(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 1 || !in.is_string(0)) return false;
    for (int k = 1; k < in.nargs(); ++k)
        if (in.is_array(k)) return false;
    b.fn = op_printf;
    return true;
}

void op_concat(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const int n = static_cast<int>(b.op->args.size());
    f.each(d.varying, [&](std::size_t i) {
        // Measured first: a doubling string stops before it is built.
        uint64_t length = 0;
        for (int k = 1; k < n; ++k) length += f.str(b, k, i).size();
        f.check_string_length(b, length);
        std::string s;
        s.reserve(length);
        for (int k = 1; k < n; ++k) s += f.str(b, k, i);
        *d.at(i) = f.intern(b, s);
    });
}

bool bind_concat(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 2) return false;
    for (int k = 0; k < in.nargs(); ++k)
        if (!in.is_string(k)) return false;
    b.fn = op_concat;
    return true;
}

void op_match(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        try {
            *d.at(i) = rsl_match(f.str(b, 1, i), f.str(b, 2, i)) ? 1.0f : 0.0f;
        } catch (const ValueError& e) {
            f.fail(b, e.what());
        }
    });
}

bool bind_match(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || !in.is_string(1) || !in.is_string(2))
        return false;
    b.fn = op_match;
    return true;
}

bool bind_atan(const BindInfo& in, BoundOp& b, std::string& why) {
    if (in.nargs() == 2) return bind_elem<FAtan, 1>(in, b, why);
    return bind_elem<FAtan2, 2>(in, b, why);
}
bool bind_log(const BindInfo& in, BoundOp& b, std::string& why) {
    if (in.nargs() == 2) return bind_elem<FLog, 1>(in, b, why);
    return bind_elem<FLogBase, 2>(in, b, why);
}

} // namespace

void register_math(BinderTable& t) {
    t["radians"] = bind_elem<FRadians, 1>;
    t["degrees"] = bind_elem<FDegrees, 1>;
    t["sin"] = bind_elem<FSin, 1>;
    t["cos"] = bind_elem<FCos, 1>;
    t["tan"] = bind_elem<FTan, 1>;
    t["asin"] = bind_elem<FAsin, 1>;
    t["acos"] = bind_elem<FAcos, 1>;
    t["atan"] = bind_atan;
    t["pow"] = bind_elem<FPow, 2>;
    t["exp"] = bind_elem<FExp, 1>;
    t["sqrt"] = bind_elem<FSqrt, 1>;
    t["inversesqrt"] = bind_elem<FInvSqrt, 1>;
    t["log"] = bind_log;
    t["mod"] = bind_elem<FMod, 2>;
    t["abs"] = bind_elem<FAbs, 1>;
    t["sign"] = bind_elem<FSign, 1>;
    t["floor"] = bind_elem<FFloor, 1>;
    t["ceil"] = bind_elem<FCeil, 1>;
    t["round"] = bind_elem<FRound, 1>;
    t["min"] = bind_elem<FMin, -2>;
    t["max"] = bind_elem<FMax, -2>;
    t["clamp"] = bind_elem<FClamp, 3>;
    t["mix"] = bind_elem<FMix, 3>;
    t["step"] = bind_elem<FStep, 2>;
    t["smoothstep"] = bind_elem<FSmoothstep, 3>;
    t["erf"] = bind_elem<FErf, 1>;
    t["erfc"] = bind_elem<FErfc, 1>;
    t["filterstep"] = bind_filterstep;
    t["spline"] = bind_spline;
    t["random"] = bind_random;
    t["noise"] = bind_noise<NoiseNoise>;
    t["pnoise"] = bind_noise<NoisePeriodic>;
    t["cellnoise"] = bind_noise<NoiseCell>;
    t["concat"] = bind_concat;
    t["format"] = bind_format;
    t["printf"] = bind_printf;
    t["match"] = bind_match;
}

} // namespace sss::detail

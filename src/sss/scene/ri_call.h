// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file ri_call.h
/// One Ri call of the C binding as the RIB statement it stands for: its
/// positional arguments, its parameter list sized from the declarations and
/// the primitive's topology, and the guard that carries it out (or keeps its
/// error for when the DSO returns).

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "ri_context.h"
#include "rib_lexer.h"
#include "sss/scene/ri.h"

namespace sss::rib {

/// Elements per storage class of one primitive (RISpec's table of counts);
/// constant is always 1.
struct ClassCounts {
    std::size_t uniform = 1;
    std::size_t varying = 1;
    std::size_t vertex = 1;
    std::size_t facevarying = 1;
    /// Points and Curves: the predeclared (uniform) "width" is RI's varying
    /// width, as the reader reads it there.
    bool varying_width = false;
};

/// A statement being made from a call's arguments.
class RiCall {
public:
    RiCall(RiContext& context, const char* request);

    RiCall& number(double v);
    RiCall& string(const char* v, const char* what);
    RiCall& floats(const RtFloat* v, std::size_t n, const char* what);
    RiCall& ints(const RtInt* v, std::size_t n, const char* what);
    RiCall& strings(RtToken const* v, std::size_t n, const char* what);
    /// The token/value pairs, each value's length from its declaration.
    RiCall& params(RtInt n, RtToken const tokens[], RtPointer const values[],
                   const ClassCounts& counts);

    RiContext& context() { return m_context; }
    const Statement& statement() const { return m_statement; }
    [[noreturn]] void fail(const std::string& what) const;

private:
    RiContext& m_context;
    Statement m_statement;
};

/// Runs `make` on a new call of `request` and carries the statement out,
/// inside the context of this thread's procedural. Nothing after an error:
/// the first one is kept for when the DSO returns.
void ri_guarded(const char* request, const std::function<void(RiCall&)>& make);

/// The same, for a call that does more than one statement (RiProcedural).
void ri_guarded_raw(const char* request, const std::function<void(RiCall&)>& act);

/// Token/value pairs of a variadic call, up to RI_NULL.
struct RiParamVector {
    std::vector<RtToken> tokens;
    std::vector<RtPointer> values;
    RtInt count() const { return static_cast<RtInt>(tokens.size()); }
};

/// Strings kept for the DSO (handles, declared names): valid for the read.
const char* ri_keep(RiContext& context, std::string text);

/// Keeps the geometry calls (ri_geometry.cpp) in every program that has
/// the rest of the binding.
void ri_geometry_anchor();

} // namespace sss::rib

/// Collects a variadic call's pairs after the argument `last`.
#define SSS_RI_VARARGS(pv, last)                                                         \
    ::sss::rib::RiParamVector pv;                                                        \
    do {                                                                                 \
        va_list ap_;                                                                     \
        va_start(ap_, last);                                                             \
        for (;;) {                                                                       \
            RtToken token_ = va_arg(ap_, RtToken);                                       \
            if (!token_ || pv.tokens.size() >= 100000) break;                            \
            pv.tokens.push_back(token_);                                                 \
            pv.values.push_back(va_arg(ap_, RtPointer));                                 \
        }                                                                                \
        va_end(ap_);                                                                     \
    } while (0)

// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_arrays.cpp
/// Resizable arrays (PRMan 13.5's dynamic arrays, `float a[]`): their
/// storage, element access, and arraylength, resize, push, pop, reserve.
///
/// A resizable array keeps its values apart from the frame's arena
/// (ResizableArray, engine_internal.h): `length` elements per value in blocks
/// of `capacity` elements, so that a varying array grows without moving its
/// values for every push (the capacity doubles). The length is one for the
/// whole batch, as PRMan requires: resize, push and pop change it for every
/// point, whichever points run; new elements are 0 (""), and push writes its
/// value at the running points. Programs without resizable arrays never run
/// any of this: fixed arrays keep their own aref/aassign (engine_ops.cpp).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "engine_internal.h"
#include "sss/util/limits.h"

namespace sss::detail {

namespace {

std::string count_text(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.0f", v);
    return buf;
}

/// The most elements a resizable array may have (SHADER_ARRAY_LENGTH, kept
/// within an int).
long max_length(const Frame& f) {
    return static_cast<long>(std::min<uint64_t>(f.ctx->array_limit, 1u << 30));
}

/// Makes room for `capacity` elements per value (keeping the values).
/// Fails when the storage would pass kMaxResizableFloats.
void set_capacity(Frame& f, const BoundOp& b, Slot& s, int ef, int capacity) {
    ResizableArray& r = f.resizable[static_cast<std::size_t>(s.resizable)];
    if (capacity <= r.capacity) return;
    const std::size_t reps = s.varying ? f.n : 1;
    const std::size_t floats = reps * static_cast<std::size_t>(capacity) * ef;
    if (floats > kMaxResizableFloats)
        f.fail(b, "a resizable array of " + std::to_string(capacity) + " elements of " +
                      std::to_string(ef) + " floats over " + std::to_string(reps) +
                      " points needs more than " + std::to_string(kMaxResizableFloats) +
                      " floats (1 GiB)");
    // Large storage is counted against the job's memory budget.
    const uint64_t bytes = uint64_t(floats) * sizeof(float);
    if (bytes >= kShaderMemoryStep / 4)
        f.check_memory_for(b, bytes,
                           "a resizable array of " + std::to_string(capacity) +
                               " elements over " + std::to_string(reps) + " points");
    std::vector<float> data(floats, 0.0f);
    const std::size_t keep = static_cast<std::size_t>(r.length) * ef;
    if (keep > 0)
        for (std::size_t i = 0; i < reps; ++i)
            std::memcpy(data.data() + i * capacity * ef,
                        r.data.data() + i * static_cast<std::size_t>(r.capacity) * ef,
                        sizeof(float) * keep);
    r.data.swap(data);
    r.capacity = capacity;
    s.p = r.data.data();
    s.stride = s.varying ? capacity * ef : 0;
}

/// Sets the length of the resizable array in slot s (ef floats per element):
/// the first elements are kept, new ones are 0.
void set_length(Frame& f, const BoundOp& b, Slot& s, int ef, double want,
                const char* what) {
    if (!(want >= 0.0))
        f.fail(b, std::string(what) + ": a negative array length (" + count_text(want) +
                      ")");
    const long most = max_length(f);
    if (want > static_cast<double>(most))
        f.fail(b, std::string(what) + ": an array of " + count_text(want) + " elements " +
                      limit_exceeded(Limit::ShaderArrayLength));
    const int length = static_cast<int>(want);
    ResizableArray& r = f.resizable[static_cast<std::size_t>(s.resizable)];
    if (length > r.capacity) {
        // Doubling, within both limits (the length itself is checked first).
        const std::size_t reps = s.varying ? f.n : 1;
        const std::size_t per = reps * static_cast<std::size_t>(ef);
        long cap = std::max<long>({length, 2L * r.capacity, 4L});
        cap = std::min<long>(cap, most);
        if (static_cast<std::size_t>(cap) * per > kMaxResizableFloats)
            cap = std::max<long>(length, static_cast<long>(kMaxResizableFloats / per));
        set_capacity(f, b, s, ef, static_cast<int>(cap));
    }
    if (length > r.length) {
        const std::size_t reps = s.varying ? f.n : 1;
        for (std::size_t i = 0; i < reps; ++i) {
            float* p = s.p + i * static_cast<std::size_t>(s.stride);
            std::fill(p + static_cast<std::size_t>(r.length) * ef,
                      p + static_cast<std::size_t>(length) * ef, 0.0f);
        }
    }
    r.length = length;
    s.nf = length * ef;
}

int length_of(const Frame& f, const Slot& s) {
    return f.resizable[static_cast<std::size_t>(s.resizable)].length;
}

void op_arraylength(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const Slot& a = f.slot(b, 1);
    const float n = static_cast<float>(a.resizable >= 0 ? length_of(f, a) : b.ib);
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = n; });
}

void op_resize(Frame& f, const BoundOp& b) {
    const float n = *f.slot(b, 1).p;
    set_length(f, b, f.slot(b, 0), b.ia, std::floor(static_cast<double>(n)), "resize");
}

void op_reserve(Frame& f, const BoundOp& b) {
    // A hint: clamped to the limits, never an error.
    Slot& a = f.slot(b, 0);
    const double n = std::floor(static_cast<double>(*f.slot(b, 1).p));
    const std::size_t per = (a.varying ? f.n : 1) * static_cast<std::size_t>(b.ia);
    const double most =
        std::min<double>(double(max_length(f)), double(kMaxResizableFloats / per));
    if (n > 0.0) set_capacity(f, b, a, b.ia, static_cast<int>(std::min(n, most)));
}

void op_push(Frame& f, const BoundOp& b) {
    Slot& a = f.slot(b, 0);
    const Slot& v = f.slot(b, 1);
    const int ef = b.ia;
    const int at = length_of(f, a);
    set_length(f, b, a, ef, static_cast<double>(at) + 1.0, "push");
    const bool splat = v.nf == 1 && ef != 1;
    f.each(a.varying, [&](std::size_t i) {
        float* o = a.at(i) + static_cast<std::size_t>(at) * ef;
        if (splat)
            std::fill(o, o + ef, *v.at(i));
        else
            std::memcpy(o, v.at(i), sizeof(float) * ef);
    });
}

void op_pop(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& a = f.slot(b, 1);
    const int ef = b.ia;
    const int length = length_of(f, a);
    if (length == 0) f.fail(b, "pop: the array is empty");
    f.each(d.varying, [&](std::size_t i) {
        std::memcpy(d.at(i), a.at(i) + static_cast<std::size_t>(length - 1) * ef,
                    sizeof(float) * ef);
    });
    set_length(f, b, a, ef, length - 1.0, "pop");
}

bool is_resizable(const BindInfo& in, int k) {
    return in.sym(k).type.is_resizable();
}

/// The floats per element of a resizable array argument k.
int element_floats(const BindInfo& in, int k) {
    return shading_type_floats(in.type(k));
}

/// An element value for array argument k: of its type (or a float for a
/// triple or matrix).
bool fits_element(const BindInfo& in, int array, int value) {
    if (in.is_array(value)) return false;
    if ((in.type(array) == ShadingType::String) != in.is_string(value)) return false;
    return in.floats(value) == element_floats(in, array) ||
           (in.is_float(value) && in.type(array) != ShadingType::String);
}

bool bind_arraylength(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_float(0) || !in.is_array(1)) return false;
    b.ib = in.sym(1).type.array;
    b.fn = op_arraylength;
    return true;
}

bool bind_resize(const BindInfo& in, BoundOp& b, std::string& why) {
    if (in.nargs() != 2 || !is_resizable(in, 0) || !in.is_float(1)) return false;
    if (in.varying(1)) {
        why = "the length must be uniform";
        return false;
    }
    b.ia = element_floats(in, 0);
    b.fn = in.op.name == "resize" ? op_resize : op_reserve;
    return true;
}

bool bind_push(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !is_resizable(in, 0) || !fits_element(in, 0, 1)) return false;
    b.ia = element_floats(in, 0);
    b.fn = op_push;
    return true;
}

bool bind_pop(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !is_resizable(in, 1) || in.is_array(0) ||
        in.type(0) != in.type(1))
        return false;
    b.ia = element_floats(in, 1);
    b.fn = op_pop;
    return true;
}

} // namespace

void op_aref_resizable(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    Slot& a = f.slot(b, 1);
    Slot& idx = f.slot(b, 2);
    const int ne = b.ia, length = length_of(f, a);
    f.each(d.varying, [&](std::size_t i) {
        const int e = array_element(f, b, idx, i, length);
        std::memmove(d.at(i), a.at(i) + e * ne, sizeof(float) * ne);
    });
}

void op_aassign_resizable(Frame& f, const BoundOp& b) {
    Slot& a = f.slot(b, 0);
    Slot& idx = f.slot(b, 1);
    Slot& s = f.slot(b, 2);
    const int ne = b.ia, length = length_of(f, a);
    const bool splat = s.nf == 1 && ne != 1;
    f.each(a.varying, [&](std::size_t i) {
        const int e = array_element(f, b, idx, i, length);
        float* o = a.at(i) + e * ne;
        if (splat)
            std::fill(o, o + ne, *s.at(i));
        else
            std::memmove(o, s.at(i), sizeof(float) * ne);
    });
}

void resize_array(Frame& f, const BoundOp& b, Slot& s, int ef, double length,
                  const char* what) {
    set_length(f, b, s, ef, length, what);
}

int resizable_length(const Frame& f, const Slot& s) {
    return length_of(f, s);
}

void reset_resizable(Frame& f) {
    for (ResizableArray& r : f.resizable) {
        r.data.clear();
        r.length = 0;
        r.capacity = 0;
    }
}

void register_arrays(BinderTable& t) {
    t["arraylength"] = bind_arraylength;
    t["resize"] = bind_resize;
    t["reserve"] = bind_resize;
    t["push"] = bind_push;
    t["pop"] = bind_pop;
}

} // namespace sss::detail

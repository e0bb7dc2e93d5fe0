// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file ri_api.cpp
/// The Ri C binding for DynamicLoad procedurals: each call made into the
/// statement its RIB request is and carried out by the reader at once
/// (ri_context.h). Here: the context, the calls' arguments and parameter
/// lists, tokens, bases, filters, and the requests other than geometry
/// (ri_geometry.cpp).

#include <atomic>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "ri_call.h"
#include "rib_args.h"
#include "rib_params.h"
#include "rib_reader.h"
#include "sss/scene/rib.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace sss::rib {

namespace {

thread_local RiContext* t_context = nullptr;

// Calls from a thread without a procedural: nobody to report them to but
// the procedural that made the thread, which checks this count.
std::atomic<unsigned> g_stray_calls{0};

} // namespace

RiScope::RiScope(RiContext* context) : m_previous(t_context) {
    t_context = context;
    ri_geometry_anchor();
}

RiScope::~RiScope() {
    t_context = m_previous;
}

RiContext* current_ri_context() {
    return t_context;
}

unsigned ri_stray_calls() {
    return g_stray_calls.load();
}

RiCall::RiCall(RiContext& context, const char* request) : m_context(context) {
    m_statement.name = request;
    m_statement.file = context.file;
    m_statement.line = ++context.calls;
}

void RiCall::fail(const std::string& what) const {
    rib::fail(m_statement, what);
}

RiCall& RiCall::number(double v) {
    if (!std::isfinite(v)) fail("an argument is not a finite number");
    Value value;
    value.number = v;
    m_statement.args.push_back(std::move(value));
    return *this;
}

RiCall& RiCall::string(const char* v, const char* what) {
    if (!v) fail(std::string("no ") + what + " (a null pointer)");
    Value value;
    value.kind = Value::Kind::String;
    value.string = v;
    m_statement.args.push_back(std::move(value));
    return *this;
}

namespace {

// The memory an argument array will take, checked before it is copied: a
// count read from the DSO's arrays may be anything.
void check_count(const RiCall& call, std::size_t n, std::size_t bytes_each,
                 const char* what) {
    if (n > (std::size_t(1) << 40) / bytes_each)
        call.fail(std::string(what) + ": " + std::to_string(n) + " values is too many");
    // Small arrays are most calls: only a big one is worth reading the
    // process's memory use for.
    if (uint64_t(n) * bytes_each >= (uint64_t(1) << 20))
        check_memory(uint64_t(n) * bytes_each,
                     where(call.statement()) + ": " + call.statement().name + " " + what,
                     "");
}

} // namespace

RiCall& RiCall::floats(const RtFloat* v, std::size_t n, const char* what) {
    if (n > 0 && !v) fail(std::string("no ") + what + " (a null pointer)");
    check_count(*this, n, sizeof(double), what);
    Value value;
    value.kind = Value::Kind::Array;
    value.numbers.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v[i]))
            fail(std::string(what) + "[" + std::to_string(i) +
                 "] is not a finite number");
        value.numbers.push_back(v[i]);
    }
    m_statement.args.push_back(std::move(value));
    return *this;
}

RiCall& RiCall::ints(const RtInt* v, std::size_t n, const char* what) {
    if (n > 0 && !v) fail(std::string("no ") + what + " (a null pointer)");
    check_count(*this, n, sizeof(double), what);
    Value value;
    value.kind = Value::Kind::Array;
    value.numbers.assign(v, v + n);
    m_statement.args.push_back(std::move(value));
    return *this;
}

RiCall& RiCall::strings(RtToken const* v, std::size_t n, const char* what) {
    if (n > 0 && !v) fail(std::string("no ") + what + " (a null pointer)");
    check_count(*this, n, sizeof(std::string), what);
    Value value;
    value.kind = Value::Kind::Array;
    value.string_array = true;
    for (std::size_t i = 0; i < n; ++i) {
        if (!v[i])
            fail(std::string(what) + "[" + std::to_string(i) + "] is a null pointer");
        value.strings.emplace_back(v[i]);
    }
    m_statement.args.push_back(std::move(value));
    return *this;
}

RiCall& RiCall::params(RtInt n, RtToken const tokens[], RtPointer const values[],
                       const ClassCounts& counts) {
    if (n < 0) fail("a negative number of parameters");
    if (n > 0 && (!tokens || !values)) fail("no parameter list (a null pointer)");
    for (RtInt k = 0; k < n; ++k) {
        if (!tokens[k]) fail("parameter " + std::to_string(k) + " has no name");
        const std::string spelled = tokens[k];
        Decl decl;
        if (spelled.find_first_of(" \t\n") != std::string::npos) {
            std::string name;
            const std::string error = parse_decl(spelled, true, decl, &name);
            if (!error.empty()) fail(error);
        } else if (const Decl* d = m_context.reader->declared(spelled)) {
            decl = *d;
            if (spelled == "width" && counts.varying_width &&
                decl.storage == ParamClass::Uniform)
                decl.storage = ParamClass::Varying;
        } else {
            fail("parameter " + sss::quoted(spelled) +
                 " is not declared (RiDeclare it, or declare it inline: "
                 "\"uniform float " +
                 truncated(spelled, kMaxEcho) + "\")");
        }
        if (!values[k]) fail("parameter " + sss::quoted(spelled) + " has no value");
        std::size_t elements = 1;
        switch (decl.storage) {
        case ParamClass::Constant:
            elements = 1;
            break;
        case ParamClass::Uniform:
            elements = counts.uniform;
            break;
        case ParamClass::Varying:
            elements = counts.varying;
            break;
        case ParamClass::Vertex:
            elements = counts.vertex;
            break;
        case ParamClass::FaceVarying:
        case ParamClass::FaceVertex:
            elements = counts.facevarying;
            break;
        }
        const std::size_t per_element =
            std::size_t(decl.array_size) *
            (decl.type == ParamType::String ? 1 : param_type_components(decl.type));
        const std::size_t total = elements * per_element;
        string(spelled.c_str(), "parameter name");
        if (decl.type == ParamType::String)
            strings(static_cast<RtToken const*>(values[k]), total, spelled.c_str());
        else if (decl.type == ParamType::Integer)
            ints(static_cast<const RtInt*>(values[k]), total, spelled.c_str());
        else
            floats(static_cast<const RtFloat*>(values[k]), total, spelled.c_str());
    }
    return *this;
}

namespace {

// The context a call may go into, or nullptr when it must do nothing.
RiContext* usable_context(const char* request) {
    RiContext* context = t_context;
    if (!context) {
        ++g_stray_calls;
        return nullptr;
    }
    if (context->error) return nullptr;
    if (!context->subdividing) {
        context->error = std::make_exception_ptr(
            RibError(*context->file, context->calls + 1, request,
                     "Ri calls are made in Subdivide, not in ConvertParameters or Free"));
        return nullptr;
    }
    return context;
}

} // namespace

void ri_guarded(const char* request, const std::function<void(RiCall&)>& make) {
    RiContext* context = usable_context(request);
    if (!context) return;
    try {
        RiCall call(*context, request);
        make(call);
        context->reader->ri_execute(call.statement());
    } catch (...) {
        if (!context->error) context->error = std::current_exception();
    }
}

void ri_guarded_raw(const char* request, const std::function<void(RiCall&)>& act) {
    RiContext* context = usable_context(request);
    if (!context) return;
    try {
        RiCall call(*context, request);
        act(call);
    } catch (...) {
        if (!context->error) context->error = std::current_exception();
    }
}

const char* ri_keep(RiContext& context, std::string text) {
    context.kept.push_back(std::move(text));
    return context.kept.back().c_str();
}

} // namespace sss::rib

using sss::rib::ClassCounts;
using sss::rib::ri_guarded;
using sss::rib::RiCall;

namespace {

constexpr ClassCounts kSingle{};

// The variadic call forwarded to its V form.
#define SSS_RI_FORWARD(last, call)                                                       \
    SSS_RI_VARARGS(pv, last);                                                            \
    call

// A shader-like request: name, then one value per parameter.
void named_request(const char* request, RtToken name, RtInt n, RtToken tokens[],
                   RtPointer values[]) {
    ri_guarded(request, [&](RiCall& c) {
        c.string(name, "name").params(n, tokens, values, kSingle);
    });
}

// "dynamicload:3": a handle no RIB file is likely to use.
const char* new_handle(sss::rib::RiContext& context, const char* kind) {
    const char* handle =
        sss::rib::ri_keep(context, std::string("dynamicload:") + kind + ":" +
                                       std::to_string(context.next_handle++));
    context.handles.insert(handle);
    return handle;
}

} // namespace

extern "C" {

// --- tokens ------------------------------------------------------------------

#define SSS_RI_TOKEN(var, text) RtToken var = const_cast<char*>(text)
SSS_RI_TOKEN(RI_FRAMEBUFFER, "framebuffer");
SSS_RI_TOKEN(RI_FILE, "file");
SSS_RI_TOKEN(RI_RGB, "rgb");
SSS_RI_TOKEN(RI_RGBA, "rgba");
SSS_RI_TOKEN(RI_RGBZ, "rgbz");
SSS_RI_TOKEN(RI_RGBAZ, "rgbaz");
SSS_RI_TOKEN(RI_A, "a");
SSS_RI_TOKEN(RI_Z, "z");
SSS_RI_TOKEN(RI_AZ, "az");
SSS_RI_TOKEN(RI_PERSPECTIVE, "perspective");
SSS_RI_TOKEN(RI_ORTHOGRAPHIC, "orthographic");
SSS_RI_TOKEN(RI_HIDDEN, "hidden");
SSS_RI_TOKEN(RI_PAINT, "paint");
SSS_RI_TOKEN(RI_CONSTANT, "constant");
SSS_RI_TOKEN(RI_SMOOTH, "smooth");
SSS_RI_TOKEN(RI_FLATNESS, "flatness");
SSS_RI_TOKEN(RI_FOV, "fov");
SSS_RI_TOKEN(RI_AMBIENTLIGHT, "ambientlight");
SSS_RI_TOKEN(RI_POINTLIGHT, "pointlight");
SSS_RI_TOKEN(RI_DISTANTLIGHT, "distantlight");
SSS_RI_TOKEN(RI_SPOTLIGHT, "spotlight");
SSS_RI_TOKEN(RI_INTENSITY, "intensity");
SSS_RI_TOKEN(RI_LIGHTCOLOR, "lightcolor");
SSS_RI_TOKEN(RI_FROM, "from");
SSS_RI_TOKEN(RI_TO, "to");
SSS_RI_TOKEN(RI_CONEANGLE, "coneangle");
SSS_RI_TOKEN(RI_CONEDELTAANGLE, "conedeltaangle");
SSS_RI_TOKEN(RI_BEAMDISTRIBUTION, "beamdistribution");
SSS_RI_TOKEN(RI_MATTE, "matte");
SSS_RI_TOKEN(RI_METAL, "metal");
SSS_RI_TOKEN(RI_SHINYMETAL, "shinymetal");
SSS_RI_TOKEN(RI_PLASTIC, "plastic");
SSS_RI_TOKEN(RI_PAINTEDPLASTIC, "paintedplastic");
SSS_RI_TOKEN(RI_KA, "Ka");
SSS_RI_TOKEN(RI_KD, "Kd");
SSS_RI_TOKEN(RI_KS, "Ks");
SSS_RI_TOKEN(RI_ROUGHNESS, "roughness");
SSS_RI_TOKEN(RI_KR, "Kr");
SSS_RI_TOKEN(RI_TEXTURENAME, "texturename");
SSS_RI_TOKEN(RI_SPECULARCOLOR, "specularcolor");
SSS_RI_TOKEN(RI_DEPTHCUE, "depthcue");
SSS_RI_TOKEN(RI_FOG, "fog");
SSS_RI_TOKEN(RI_BUMPY, "bumpy");
SSS_RI_TOKEN(RI_MINDISTANCE, "mindistance");
SSS_RI_TOKEN(RI_MAXDISTANCE, "maxdistance");
SSS_RI_TOKEN(RI_BACKGROUND, "background");
SSS_RI_TOKEN(RI_DISTANCE, "distance");
SSS_RI_TOKEN(RI_AMPLITUDE, "amplitude");
SSS_RI_TOKEN(RI_INSIDE, "inside");
SSS_RI_TOKEN(RI_OUTSIDE, "outside");
SSS_RI_TOKEN(RI_LH, "lh");
SSS_RI_TOKEN(RI_RH, "rh");
SSS_RI_TOKEN(RI_P, "P");
SSS_RI_TOKEN(RI_PZ, "Pz");
SSS_RI_TOKEN(RI_PW, "Pw");
SSS_RI_TOKEN(RI_N, "N");
SSS_RI_TOKEN(RI_NP, "Np");
SSS_RI_TOKEN(RI_CS, "Cs");
SSS_RI_TOKEN(RI_OS, "Os");
SSS_RI_TOKEN(RI_S, "s");
SSS_RI_TOKEN(RI_T, "t");
SSS_RI_TOKEN(RI_ST, "st");
SSS_RI_TOKEN(RI_WIDTH, "width");
SSS_RI_TOKEN(RI_CONSTANTWIDTH, "constantwidth");
SSS_RI_TOKEN(RI_BILINEAR, "bilinear");
SSS_RI_TOKEN(RI_BICUBIC, "bicubic");
SSS_RI_TOKEN(RI_LINEAR, "linear");
SSS_RI_TOKEN(RI_CUBIC, "cubic");
SSS_RI_TOKEN(RI_PRIMITIVE, "primitive");
SSS_RI_TOKEN(RI_INTERSECTION, "intersection");
SSS_RI_TOKEN(RI_UNION, "union");
SSS_RI_TOKEN(RI_DIFFERENCE, "difference");
SSS_RI_TOKEN(RI_PERIODIC, "periodic");
SSS_RI_TOKEN(RI_NONPERIODIC, "nonperiodic");
SSS_RI_TOKEN(RI_CLAMP, "clamp");
SSS_RI_TOKEN(RI_BLACK, "black");
SSS_RI_TOKEN(RI_IGNORE, "ignore");
SSS_RI_TOKEN(RI_PRINT, "print");
SSS_RI_TOKEN(RI_ABORT, "abort");
SSS_RI_TOKEN(RI_HANDLER, "handler");
SSS_RI_TOKEN(RI_ORIGIN, "origin");
SSS_RI_TOKEN(RI_IDENTIFIER, "identifier");
SSS_RI_TOKEN(RI_NAME, "name");
SSS_RI_TOKEN(RI_COMMENT, "comment");
SSS_RI_TOKEN(RI_STRUCTURE, "structure");
SSS_RI_TOKEN(RI_VERBATIM, "verbatim");
SSS_RI_TOKEN(RI_SHADOWNAME, "shadowname");
#undef SSS_RI_TOKEN

// --- bases and filters ----------------------------------------------------------

RtBasis RiBezierBasis = {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}};
RtBasis RiBSplineBasis = {{-1.0f / 6, 3.0f / 6, -3.0f / 6, 1.0f / 6},
                          {3.0f / 6, -6.0f / 6, 3.0f / 6, 0},
                          {-3.0f / 6, 0, 3.0f / 6, 0},
                          {1.0f / 6, 4.0f / 6, 1.0f / 6, 0}};
RtBasis RiCatmullRomBasis = {
    {-0.5f, 1.5f, -1.5f, 0.5f}, {1, -2.5f, 2, -0.5f}, {-0.5f, 0, 0.5f, 0}, {0, 1, 0, 0}};
RtBasis RiHermiteBasis = {{2, 1, -2, 1}, {-3, -2, 3, -1}, {0, 1, 0, 0}, {1, 0, 0, 0}};
RtBasis RiPowerBasis = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};

RtFloat RiBoxFilter(RtFloat, RtFloat, RtFloat, RtFloat) {
    return 1.0f;
}

RtFloat RiTriangleFilter(RtFloat x, RtFloat y, RtFloat xwidth, RtFloat ywidth) {
    const float hx = xwidth * 0.5f, hy = ywidth * 0.5f;
    return std::max(0.0f, (hx - std::fabs(x)) / hx) *
           std::max(0.0f, (hy - std::fabs(y)) / hy);
}

RtFloat RiGaussianFilter(RtFloat x, RtFloat y, RtFloat xwidth, RtFloat ywidth) {
    x *= 2.0f / xwidth;
    y *= 2.0f / ywidth;
    return std::exp(-2.0f * (x * x + y * y));
}

RtFloat RiCatmullRomFilter(RtFloat x, RtFloat y, RtFloat, RtFloat) {
    const float r2 = x * x + y * y, r = std::sqrt(r2);
    if (r >= 2.0f) return 0.0f;
    if (r < 1.0f) return 3.0f * r * r2 - 5.0f * r2 + 2.0f;
    return -r * r2 + 5.0f * r2 - 8.0f * r + 4.0f;
}

RtFloat RiSincFilter(RtFloat x, RtFloat y, RtFloat, RtFloat) {
    const float pi = 3.14159265f;
    const float sx = x == 0.0f ? 1.0f : std::sin(pi * x) / (pi * x);
    const float sy = y == 0.0f ? 1.0f : std::sin(pi * y) / (pi * y);
    return sx * sy;
}

// The reader reports every error itself (the read stops with one ERROR
// line, whatever handler is set): the handlers only print when called.
RtVoid RiErrorIgnore(RtInt, RtInt, char*) {}
RtVoid RiErrorPrint(RtInt code, RtInt severity, char* message) {
    std::fprintf(stderr, "Ri error %d (severity %d): %s\n", code, severity,
                 message ? message : "");
}
RtVoid RiErrorAbort(RtInt code, RtInt severity, char* message) {
    RiErrorPrint(code, severity, message);
}
RtVoid RiErrorHandler(RtErrorHandler) {}

// --- declarations and options ------------------------------------------------

RtToken RiDeclare(char* name, char* declaration) {
    sss::rib::RiContext* context = sss::rib::current_ri_context();
    if (!name) return nullptr;
    ri_guarded("Declare", [&](RiCall& c) {
        c.string(name, "name").string(declaration ? declaration : "", "declaration");
    });
    return context ? const_cast<char*>(sss::rib::ri_keep(*context, name)) : name;
}

RtVoid RiFormat(RtInt xres, RtInt yres, RtFloat aspect) {
    ri_guarded("Format", [&](RiCall& c) { c.number(xres).number(yres).number(aspect); });
}
RtVoid RiFrameAspectRatio(RtFloat aspect) {
    ri_guarded("FrameAspectRatio", [&](RiCall& c) { c.number(aspect); });
}
RtVoid RiScreenWindow(RtFloat l, RtFloat r, RtFloat b, RtFloat t) {
    ri_guarded("ScreenWindow",
               [&](RiCall& c) { c.number(l).number(r).number(b).number(t); });
}
RtVoid RiCropWindow(RtFloat x0, RtFloat x1, RtFloat y0, RtFloat y1) {
    ri_guarded("CropWindow",
               [&](RiCall& c) { c.number(x0).number(x1).number(y0).number(y1); });
}
RtVoid RiProjectionV(RtToken name, RtInt n, RtToken tokens[], RtPointer values[]) {
    named_request("Projection", name, n, tokens, values);
}
RtVoid RiProjection(RtToken name, ...) {
    SSS_RI_FORWARD(name,
                   RiProjectionV(name, pv.count(), pv.tokens.data(), pv.values.data()));
}
RtVoid RiClipping(RtFloat hither, RtFloat yon) {
    ri_guarded("Clipping", [&](RiCall& c) { c.number(hither).number(yon); });
}
RtVoid RiDepthOfField(RtFloat fstop, RtFloat focallength, RtFloat focaldistance) {
    ri_guarded("DepthOfField", [&](RiCall& c) {
        c.number(fstop).number(focallength).number(focaldistance);
    });
}
RtVoid RiShutter(RtFloat opentime, RtFloat closetime) {
    ri_guarded("Shutter", [&](RiCall& c) { c.number(opentime).number(closetime); });
}
RtVoid RiPixelSamples(RtFloat xs, RtFloat ys) {
    ri_guarded("PixelSamples", [&](RiCall& c) { c.number(xs).number(ys); });
}
RtVoid RiExposure(RtFloat gain, RtFloat gamma) {
    ri_guarded("Exposure", [&](RiCall& c) { c.number(gain).number(gamma); });
}
RtVoid RiDisplayV(char* name, RtToken type, RtToken mode, RtInt n, RtToken tokens[],
                  RtPointer values[]) {
    ri_guarded("Display", [&](RiCall& c) {
        c.string(name, "name").string(type, "type").string(mode, "mode");
        c.params(n, tokens, values, kSingle);
    });
}
RtVoid RiDisplay(char* name, RtToken type, RtToken mode, ...) {
    SSS_RI_FORWARD(mode, RiDisplayV(name, type, mode, pv.count(), pv.tokens.data(),
                                    pv.values.data()));
}
RtVoid RiHiderV(RtToken type, RtInt n, RtToken tokens[], RtPointer values[]) {
    named_request("Hider", type, n, tokens, values);
}
RtVoid RiHider(RtToken type, ...) {
    SSS_RI_FORWARD(type, RiHiderV(type, pv.count(), pv.tokens.data(), pv.values.data()));
}
RtVoid RiOptionV(RtToken name, RtInt n, RtToken tokens[], RtPointer values[]) {
    named_request("Option", name, n, tokens, values);
}
RtVoid RiOption(RtToken name, ...) {
    SSS_RI_FORWARD(name, RiOptionV(name, pv.count(), pv.tokens.data(), pv.values.data()));
}

// --- blocks ---------------------------------------------------------------------

#define SSS_RI_PLAIN(fn, request)                                                        \
    RtVoid fn(void) {                                                                    \
        ri_guarded(request, [](RiCall&) {});                                             \
    }
SSS_RI_PLAIN(RiFrameEnd, "FrameEnd")
SSS_RI_PLAIN(RiWorldBegin, "WorldBegin")
SSS_RI_PLAIN(RiWorldEnd, "WorldEnd")
SSS_RI_PLAIN(RiAttributeBegin, "AttributeBegin")
SSS_RI_PLAIN(RiAttributeEnd, "AttributeEnd")
SSS_RI_PLAIN(RiTransformBegin, "TransformBegin")
SSS_RI_PLAIN(RiTransformEnd, "TransformEnd")
SSS_RI_PLAIN(RiSolidEnd, "SolidEnd")
SSS_RI_PLAIN(RiObjectEnd, "ObjectEnd")
SSS_RI_PLAIN(RiMotionEnd, "MotionEnd")
SSS_RI_PLAIN(RiIdentity, "Identity")
SSS_RI_PLAIN(RiReverseOrientation, "ReverseOrientation")
#undef SSS_RI_PLAIN

RtVoid RiFrameBegin(RtInt frame) {
    ri_guarded("FrameBegin", [&](RiCall& c) { c.number(frame); });
}
RtVoid RiSolidBegin(RtToken operation) {
    ri_guarded("SolidBegin", [&](RiCall& c) { c.string(operation, "operation"); });
}
RtObjectHandle RiObjectBegin(void) {
    const char* handle = nullptr;
    ri_guarded("ObjectBegin", [&](RiCall& c) {
        handle = new_handle(c.context(), "object");
        c.string(handle, "handle");
    });
    return const_cast<char*>(handle);
}
RtVoid RiObjectInstance(RtObjectHandle handle) {
    ri_guarded("ObjectInstance", [&](RiCall& c) {
        if (!c.context().owns(handle)) c.fail("not a handle RiObjectBegin returned");
        c.string(static_cast<const char*>(handle), "handle");
    });
}
RtVoid RiMotionBeginV(RtInt n, RtFloat times[]) {
    ri_guarded("MotionBegin", [&](RiCall& c) {
        if (n < 0) c.fail("a negative number of times");
        c.floats(times, std::size_t(n), "times");
    });
}
RtVoid RiMotionBegin(RtInt n, ...) {
    std::vector<RtFloat> times;
    va_list ap;
    va_start(ap, n);
    for (RtInt i = 0; i < n && i < 1000; ++i) times.push_back(float(va_arg(ap, double)));
    va_end(ap);
    RiMotionBeginV(RtInt(times.size()), times.data());
}

// --- attributes -------------------------------------------------------------------

RtVoid RiColor(RtColor color) {
    ri_guarded("Color", [&](RiCall& c) { c.floats(color, 3, "color"); });
}
RtVoid RiOpacity(RtColor color) {
    ri_guarded("Opacity", [&](RiCall& c) { c.floats(color, 3, "opacity"); });
}

#define SSS_RI_SHADER(fn, request)                                                       \
    RtVoid fn##V(RtToken name, RtInt n, RtToken tokens[], RtPointer values[]) {          \
        named_request(request, name, n, tokens, values);                                 \
    }                                                                                    \
    RtVoid fn(RtToken name, ...) {                                                       \
        SSS_RI_FORWARD(name,                                                             \
                       fn##V(name, pv.count(), pv.tokens.data(), pv.values.data()));     \
    }
SSS_RI_SHADER(RiSurface, "Surface")
SSS_RI_SHADER(RiDisplacement, "Displacement")
SSS_RI_SHADER(RiAtmosphere, "Atmosphere")
SSS_RI_SHADER(RiInterior, "Interior")
SSS_RI_SHADER(RiExterior, "Exterior")
SSS_RI_SHADER(RiAttribute, "Attribute")
SSS_RI_SHADER(RiGeometry, "Geometry")
#undef SSS_RI_SHADER

RtVoid RiShaderV(RtToken name, RtToken handle, RtInt n, RtToken tokens[],
                 RtPointer values[]) {
    ri_guarded("Shader", [&](RiCall& c) {
        c.string(name, "name")
            .string(handle, "handle")
            .params(n, tokens, values, kSingle);
    });
}
RtVoid RiShader(RtToken name, RtToken handle, ...) {
    SSS_RI_FORWARD(
        handle, RiShaderV(name, handle, pv.count(), pv.tokens.data(), pv.values.data()));
}

namespace {

RtLightHandle light(const char* request, RtToken name, RtInt n, RtToken tokens[],
                    RtPointer values[]) {
    const char* handle = nullptr;
    ri_guarded(request, [&](RiCall& c) {
        handle = new_handle(c.context(), "light");
        c.string(name, "name")
            .string(handle, "handle")
            .params(n, tokens, values, kSingle);
    });
    return const_cast<char*>(handle);
}

} // namespace

RtLightHandle RiLightSourceV(RtToken name, RtInt n, RtToken tokens[],
                             RtPointer values[]) {
    return light("LightSource", name, n, tokens, values);
}
RtLightHandle RiLightSource(RtToken name, ...) {
    SSS_RI_VARARGS(pv, name);
    return RiLightSourceV(name, pv.count(), pv.tokens.data(), pv.values.data());
}
RtLightHandle RiAreaLightSourceV(RtToken name, RtInt n, RtToken tokens[],
                                 RtPointer values[]) {
    return light("AreaLightSource", name, n, tokens, values);
}
RtLightHandle RiAreaLightSource(RtToken name, ...) {
    SSS_RI_VARARGS(pv, name);
    return RiAreaLightSourceV(name, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiIlluminate(RtLightHandle light, RtBoolean onoff) {
    ri_guarded("Illuminate", [&](RiCall& c) {
        if (!c.context().owns(light)) c.fail("not a handle RiLightSource returned");
        c.string(static_cast<const char*>(light), "light").number(onoff ? 1 : 0);
    });
}
RtVoid RiShadingRate(RtFloat size) {
    ri_guarded("ShadingRate", [&](RiCall& c) { c.number(size); });
}
RtVoid RiShadingInterpolation(RtToken type) {
    ri_guarded("ShadingInterpolation", [&](RiCall& c) { c.string(type, "type"); });
}
RtVoid RiMatte(RtBoolean onoff) {
    ri_guarded("Matte", [&](RiCall& c) { c.number(onoff ? 1 : 0); });
}
RtVoid RiSides(RtInt sides) {
    ri_guarded("Sides", [&](RiCall& c) { c.number(sides); });
}
RtVoid RiOrientation(RtToken orientation) {
    ri_guarded("Orientation", [&](RiCall& c) { c.string(orientation, "orientation"); });
}

namespace {

// A standard basis by its name (as RIB spells it), another as its matrix.
void basis_argument(RiCall& c, RtBasis basis) {
    struct Named {
        RtBasis* basis;
        const char* name;
    };
    const Named named[] = {{&RiBezierBasis, "bezier"},
                           {&RiBSplineBasis, "b-spline"},
                           {&RiCatmullRomBasis, "catmull-rom"},
                           {&RiHermiteBasis, "hermite"},
                           {&RiPowerBasis, "power"}};
    for (const Named& n : named)
        if (basis == *n.basis) {
            c.string(n.name, "basis");
            return;
        }
    c.floats(basis ? &basis[0][0] : nullptr, 16, "basis");
}

} // namespace

RtVoid RiBasis(RtBasis ubasis, RtInt ustep, RtBasis vbasis, RtInt vstep) {
    ri_guarded("Basis", [&](RiCall& c) {
        basis_argument(c, ubasis);
        c.number(ustep);
        basis_argument(c, vbasis);
        c.number(vstep);
    });
}

// --- transformations --------------------------------------------------------------

RtVoid RiTransform(RtMatrix m) {
    ri_guarded("Transform",
               [&](RiCall& c) { c.floats(m ? &m[0][0] : nullptr, 16, "matrix"); });
}
RtVoid RiConcatTransform(RtMatrix m) {
    ri_guarded("ConcatTransform",
               [&](RiCall& c) { c.floats(m ? &m[0][0] : nullptr, 16, "matrix"); });
}
RtVoid RiPerspective(RtFloat fov) {
    ri_guarded("Perspective", [&](RiCall& c) { c.number(fov); });
}
RtVoid RiTranslate(RtFloat dx, RtFloat dy, RtFloat dz) {
    ri_guarded("Translate", [&](RiCall& c) { c.number(dx).number(dy).number(dz); });
}
RtVoid RiRotate(RtFloat angle, RtFloat dx, RtFloat dy, RtFloat dz) {
    ri_guarded("Rotate",
               [&](RiCall& c) { c.number(angle).number(dx).number(dy).number(dz); });
}
RtVoid RiScale(RtFloat sx, RtFloat sy, RtFloat sz) {
    ri_guarded("Scale", [&](RiCall& c) { c.number(sx).number(sy).number(sz); });
}
RtVoid RiSkew(RtFloat angle, RtFloat dx1, RtFloat dy1, RtFloat dz1, RtFloat dx2,
              RtFloat dy2, RtFloat dz2) {
    ri_guarded("Skew", [&](RiCall& c) {
        c.number(angle)
            .number(dx1)
            .number(dy1)
            .number(dz1)
            .number(dx2)
            .number(dy2)
            .number(dz2);
    });
}
RtVoid RiCoordinateSystem(RtToken space) {
    ri_guarded("CoordinateSystem", [&](RiCall& c) { c.string(space, "space"); });
}
RtVoid RiCoordSysTransform(RtToken space) {
    ri_guarded("CoordSysTransform", [&](RiCall& c) { c.string(space, "space"); });
}

// --- archives and records -------------------------------------------------------------

RtVoid RiReadArchiveV(RtToken name, RtArchiveCallback, RtInt n, RtToken tokens[],
                      RtPointer values[]) {
    named_request("ReadArchive", name, n, tokens, values);
}
RtVoid RiReadArchive(RtToken name, RtArchiveCallback callback, ...) {
    SSS_RI_FORWARD(callback, RiReadArchiveV(name, callback, pv.count(), pv.tokens.data(),
                                            pv.values.data()));
}

// Comments, structure and verbatim records only matter to a RIB being
// written; a renderer, which this is, passes over them.
RtVoid RiArchiveRecord(RtToken, char*, ...) {}

// --- texture files ----------------------------------------------------------------

namespace {

void filter_argument(RiCall& c, RtFilterFunc filter) {
    if (filter == RiBoxFilter)
        c.string("box", "filter");
    else if (filter == RiTriangleFilter)
        c.string("triangle", "filter");
    else if (filter == RiCatmullRomFilter)
        c.string("catmull-rom", "filter");
    else if (filter == RiSincFilter)
        c.string("sinc", "filter");
    else if (filter == RiGaussianFilter)
        c.string("gaussian", "filter");
    else
        c.fail("a filter function of the DSO's own (only the standard Ri filters are "
               "known by name)");
}

} // namespace

RtVoid RiMakeTextureV(char* picture, char* texture, RtToken swrap, RtToken twrap,
                      RtFilterFunc filter, RtFloat swidth, RtFloat twidth, RtInt n,
                      RtToken tokens[], RtPointer values[]) {
    ri_guarded("MakeTexture", [&](RiCall& c) {
        c.string(picture, "picture name").string(texture, "texture name");
        c.string(swrap, "swrap").string(twrap, "twrap");
        filter_argument(c, filter);
        c.number(swidth).number(twidth).params(n, tokens, values, kSingle);
    });
}
RtVoid RiMakeTexture(char* picture, char* texture, RtToken swrap, RtToken twrap,
                     RtFilterFunc filter, RtFloat swidth, RtFloat twidth, ...) {
    SSS_RI_FORWARD(twidth,
                   RiMakeTextureV(picture, texture, swrap, twrap, filter, swidth, twidth,
                                  pv.count(), pv.tokens.data(), pv.values.data()));
}
RtVoid RiMakeShadowV(char* picture, char* texture, RtInt n, RtToken tokens[],
                     RtPointer values[]) {
    ri_guarded("MakeShadow", [&](RiCall& c) {
        c.string(picture, "picture name").string(texture, "texture name");
        c.params(n, tokens, values, kSingle);
    });
}
RtVoid RiMakeShadow(char* picture, char* texture, ...) {
    SSS_RI_FORWARD(texture, RiMakeShadowV(picture, texture, pv.count(), pv.tokens.data(),
                                          pv.values.data()));
}

} // extern "C"

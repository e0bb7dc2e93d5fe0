// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_dynamic_load.cpp
/// Procedural "DynamicLoad" (RiProcedural's third protocol): the DSO is
/// loaded once per read, its ConvertParameters turns the data string into
/// its own data, its Subdivide makes geometry through the Ri C binding (each
/// call carried out as it comes, ri_api.cpp) and its Free releases the data.

#include <dlfcn.h>

#include <filesystem>

#include "rib_args.h"
#include "rib_reader.h"
#include "sss/scene/ri.h"
#include "sss/util/messages.h"

namespace sss::rib {

namespace fs = std::filesystem;

namespace {

using ConvertFunc = RtPointer (*)(RtString);
using SubdivideFunc = RtVoid (*)(RtPointer, RtFloat);
using FreeFunc = RtVoid (*)(RtPointer);

void* symbol(const Statement& s, void* handle, const char* name,
             const std::string& path) {
    dlerror();
    void* f = dlsym(handle, name);
    if (!f)
        fail(s, sss::quoted(path) + " does not export " + name +
                    " (a DynamicLoad DSO exports ConvertParameters, Subdivide and Free "
                    "with C linkage)");
    return f;
}

// Runs a DSO function inside the context; the first error an Ri call met
// there is thrown when it returns.
template <class F>
void in_context(RiContext& context, bool subdividing, F&& f) {
    const bool was = context.subdividing;
    const unsigned stray = ri_stray_calls();
    context.subdividing = subdividing;
    {
        RiScope scope(&context);
        f();
    }
    context.subdividing = was;
    if (context.error) {
        std::exception_ptr e = context.error;
        context.error = nullptr;
        std::rethrow_exception(e);
    }
    if (ri_stray_calls() != stray)
        throw RibError(*context.file, context.calls, "DynamicLoad",
                       "Ri calls from a thread of the DSO's own (Ri calls are made in "
                       "Subdivide's thread)");
}

} // namespace

const Decl* Reader::declared(const std::string& name) const {
    auto it = m_decls.find(name);
    return it == m_decls.end() ? nullptr : &it->second;
}

int Reader::basis_step(bool v) const {
    return v ? m_attr.attrs.v_basis.step : m_attr.attrs.u_basis.step;
}

void Reader::dynamic_load(const Statement& s, const std::string& dso,
                          const std::string& data, const std::vector<double>& bound) {
    // Along the procedural search path, as PRMan finds it; "name" may leave
    // out the ".so".
    std::string path;
    try {
        path = resolve_path(s, dso, "procedural");
    } catch (const IoError&) {
        if (fs::path(dso).extension() == ".so") throw;
        path = resolve_path(s, dso + ".so", "procedural");
    }
    check_archive_depth(s, path);
    const std::string key = file_key(path);
    auto loaded = m_dsos.find(key);
    if (loaded == m_dsos.end()) {
        // RTLD_LOCAL: two DSOs may both define Subdivide.
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* why = dlerror();
            fail(s, "cannot load " + sss::quoted(path) + ": " +
                        (why ? why : "unknown error") +
                        (why && std::string(why).find("undefined symbol: Ri") !=
                                     std::string::npos
                             ? " (this program does not provide the Ri C binding)"
                             : ""));
        }
        loaded =
            m_dsos
                .emplace(key, std::shared_ptr<void>(handle, [](void* h) { dlclose(h); }))
                .first;
        m_scene.sources.push_back(path);
        m_scene.source_uses.push_back("Procedural \"DynamicLoad\" at " + where(s));
    }
    void* handle = loaded->second.get();
    auto convert =
        reinterpret_cast<ConvertFunc>(symbol(s, handle, "ConvertParameters", path));
    auto subdivide =
        reinterpret_cast<SubdivideFunc>(symbol(s, handle, "Subdivide", path));
    auto free_data = reinterpret_cast<FreeFunc>(symbol(s, handle, "Free", path));

    if (!m_ri) m_ri = std::make_unique<RiContext>();
    RiContext& context = *m_ri;
    context.reader = this;
    // Nested loads (a DSO's RiProcedural of another) keep their own label.
    const std::shared_ptr<const std::string> outer_file = context.file;
    const int outer_calls = context.calls;
    context.file = std::make_shared<const std::string>(
        fs::path(path).filename().string() + " (DynamicLoad at " + where(s) + ")");
    context.calls = 0;

    std::vector<char> text(data.begin(), data.end());
    text.push_back('\0');
    RtPointer converted = nullptr;
    // Free runs whatever happened after ConvertParameters; the first error is
    // the one reported.
    auto release = [&] {
        try {
            in_context(context, false, [&] { free_data(converted); });
        } catch (...) {
        }
    };
    try {
        in_context(context, false, [&] { converted = convert(text.data()); });
    } catch (...) {
        release();
        throw;
    }
    const std::size_t depth = m_stack.size();
    push(s, Block::Attribute);
    ++m_depth;
    try {
        in_context(context, true, [&] {
            subdivide(converted, static_cast<RtFloat>(raster_area(bound)));
        });
    } catch (...) {
        release();
        throw;
    }
    --m_depth;
    in_context(context, false, [&] { free_data(converted); });
    if (m_stack.size() != depth + 1)
        fail(s, sss::quoted(path) + "'s Subdivide left " +
                    std::to_string(m_stack.size() - depth - 1) + " block(s) open");
    SavedState saved = pop(s, Block::Attribute);
    restore_all(saved);
    context.file = outer_file;
    context.calls = outer_calls;
}

void Reader::ri_procedural(const Statement& s, void* data, const double bound[6],
                           void (*subdivide)(void*, float), void (*free_data)(void*)) {
    struct Release {
        void (*f)(void*);
        void* data;
        ~Release() {
            if (f) f(data);
        }
    } release{free_data, data};
    check_archive_depth(s, "a procedural's own subdivide function");
    const std::vector<double> b(bound, bound + 6);
    for (double v : b)
        if (!std::isfinite(v)) fail(s, "the bound is not finite");
    const std::size_t depth = m_stack.size();
    push(s, Block::Attribute);
    ++m_depth;
    subdivide(data, static_cast<float>(raster_area(b)));
    --m_depth;
    // An error of the procedural's own calls is the first kept: the blocks
    // it leaves open then are not another one.
    if (m_ri && m_ri->error) return;
    if (m_stack.size() != depth + 1)
        fail(s, "a procedural's subdivide function left " +
                    std::to_string(m_stack.size() - depth - 1) + " block(s) open");
    SavedState saved = pop(s, Block::Attribute);
    restore_all(saved);
}

} // namespace sss::rib

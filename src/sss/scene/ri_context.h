// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file ri_context.h
/// Where the Ri C binding's calls go: the reader running a DynamicLoad
/// procedural. A call becomes the statement its RIB request would be and is
/// carried out at once; an error is kept (a C caller cannot be unwound
/// through) and thrown when the DSO's function returns.

#include <deque>
#include <exception>
#include <memory>
#include <set>
#include <string>

namespace sss::rib {

class Reader;
struct Statement;

/// The reader's side of the Ri calls, alive for the whole read (the handles
/// and names the calls return point into it).
struct RiContext {
    Reader* reader = nullptr;
    /// "dso.so (DynamicLoad at scene.rib:12)": the file of the statements
    /// made, their line the number of the Ri call.
    std::shared_ptr<const std::string> file;
    int calls = 0;
    /// The first error of the procedural running; later calls do nothing.
    std::exception_ptr error;
    /// Strings handed back to the DSO (declared names, handles).
    std::deque<std::string> kept;
    int next_handle = 1;
    /// The light and object handles given out (a DSO's pointer is checked
    /// against them before it is read).
    std::set<const void*> handles;
    bool owns(const void* handle) const { return handles.count(handle) > 0; }
    /// Inside a DSO's Subdivide (or a procedural it made): Ri calls are
    /// carried out. Outside (ConvertParameters, Free): they are errors.
    bool subdividing = false;
};

/// Makes `context` receive this thread's Ri calls while alive (the previous
/// one again after, for procedurals that run inside others).
class RiScope {
public:
    explicit RiScope(RiContext* context);
    ~RiScope();
    RiScope(const RiScope&) = delete;
    RiScope& operator=(const RiScope&) = delete;

private:
    RiContext* m_previous;
};

/// The context of this thread's Ri calls; nullptr outside any procedural.
RiContext* current_ri_context();

/// Ri calls so far made from threads without a procedural (a DSO's own
/// threads): the procedural that started them fails when this grows.
unsigned ri_stray_calls();

} // namespace sss::rib

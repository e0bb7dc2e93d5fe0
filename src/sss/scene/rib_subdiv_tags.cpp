// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_subdiv_tags.cpp
/// The tags of SubdivisionMesh and HierarchicalSubdivisionMesh (PRMan's
/// list): the ones the dicer carries out, the ones that change nothing it
/// computes, and the ones that are not implemented (an error, or read
/// leniently a warning and the tag left out).

#include "rib_reader.h"

#include <algorithm>
#include <string_view>

#include "rib_args.h"

namespace sss::rib {

namespace {

/// Carried out by the subdivision dicer (subdivision.cpp).
bool dicer_tag(std::string_view tag) {
    return tag == "interpolateboundary" || tag == "crease" || tag == "corner" ||
           tag == "hole";
}

/// Face-varying values are interpolated bilinearly over each face whatever
/// these say, so they change nothing computed here.
bool facevarying_tag(std::string_view tag) {
    return tag == "facevaryinginterpolateboundary" ||
           tag == "facevaryingpropagatecorners";
}

/// The tags a mesh keeps, with their arguments (SubdivisionMesh's layout:
/// two argument counts per tag).
struct KeptTags {
    std::vector<std::string> tags;
    std::vector<int> nargs, ints;
    std::vector<double> floats;

    /// Keeps tag t of p, whose ti integers start at ni and tf floats at nf.
    void keep(const Primitive& p, std::size_t t, std::size_t ni, std::size_t ti,
              std::size_t nf, std::size_t tf) {
        tags.push_back(p.tags[t]);
        nargs.push_back(static_cast<int>(ti));
        nargs.push_back(static_cast<int>(tf));
        const auto ib = p.tag_intargs.begin() + static_cast<long>(ni);
        ints.insert(ints.end(), ib, ib + static_cast<long>(ti));
        const auto fb = p.tag_floatargs.begin() + static_cast<long>(nf);
        floats.insert(floats.end(), fb, fb + static_cast<long>(tf));
    }
    /// Makes them p's tags.
    void apply(Primitive& p) {
        p.tags = std::move(tags);
        p.tag_nargs = std::move(nargs);
        p.tag_intargs = std::move(ints);
        p.tag_floatargs = std::move(floats);
    }
};

} // namespace

void Reader::hierarchical_tags(const Statement& s, Primitive& p,
                               const std::vector<std::string>& string_args) {
    if (p.tag_nargs.size() != 3 * p.tags.size())
        fail(s, "nargs must have 3 numbers per tag: " + std::to_string(p.tags.size()) +
                    " tags, " + std::to_string(p.tag_nargs.size()) + " numbers");
    // Hierarchical edits need the refined mesh's addressing: not implemented.
    KeptTags kept;
    std::size_t ni = 0, nf = 0, ns = 0;
    for (std::size_t t = 0; t < p.tags.size(); ++t) {
        const int ti = p.tag_nargs[3 * t], tf = p.tag_nargs[3 * t + 1],
                  ts = p.tag_nargs[3 * t + 2];
        if (ni + ti > p.tag_intargs.size() || nf + tf > p.tag_floatargs.size() ||
            ns + ts > string_args.size())
            fail(s, "tag \"" + p.tags[t] + "\" needs more arguments than given");
        const std::string& tag = p.tags[t];
        const bool edit = tag == "vertexedit" || tag == "edgeedit" || tag == "faceedit";
        if (tag == "creasemethod") {
            // Sharpness is spread as RenderMan's "normal" method does; Chaikin's
            // smoothing of varying crease sharpness is not implemented.
            const std::string method = ts > 0 ? string_args[ns] : "normal";
            if (method != "normal")
                not_implemented("subdivision creasemethod " + method, s,
                                "creasemethod \"" + method + "\" is not supported",
                                "\"normal\" is used");
        } else if (edit) {
            not_implemented("subdivision tag " + tag, s,
                            "hierarchical edits (\"" + tag + "\") are not supported",
                            "the tag is left out");
        } else {
            kept.keep(p, t, ni, static_cast<std::size_t>(ti), nf,
                      static_cast<std::size_t>(tf));
        }
        ni += static_cast<std::size_t>(ti);
        nf += static_cast<std::size_t>(tf);
        ns += static_cast<std::size_t>(ts);
    }
    if (ni != p.tag_intargs.size() || nf != p.tag_floatargs.size() ||
        ns != string_args.size())
        fail(s, "tag argument counts do not match intargs/floatargs/stringargs");
    kept.apply(p);
}

void Reader::check_subdivision_tags(const Statement& s, Primitive& p) {
    if (p.tag_nargs.size() != 2 * p.tags.size()) return; // the caller's error
    KeptTags kept;
    std::size_t ni = 0, nf = 0;
    for (std::size_t t = 0; t < p.tags.size(); ++t) {
        const int ti = std::max(p.tag_nargs[2 * t], 0),
                  tf = std::max(p.tag_nargs[2 * t + 1], 0);
        if (ni + ti > p.tag_intargs.size() || nf + tf > p.tag_floatargs.size())
            return; // the caller's error
        const std::string& tag = p.tags[t];
        const bool keep = dicer_tag(tag) || facevarying_tag(tag);
        if (!keep)
            not_implemented("subdivision tag " + tag, s,
                            "subdivision tag \"" + tag + "\" is not supported",
                            "the tag is left out");
        if (keep)
            kept.keep(p, t, ni, static_cast<std::size_t>(ti), nf,
                      static_cast<std::size_t>(tf));
        ni += static_cast<std::size_t>(ti);
        nf += static_cast<std::size_t>(tf);
    }
    if (ni != p.tag_intargs.size() || nf != p.tag_floatargs.size()) return;
    kept.apply(p);
}

} // namespace sss::rib

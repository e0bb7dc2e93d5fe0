// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file rib.h
/// Reader for ASCII RenderMan RIB files into the scene layer (scene.h).

#include <optional>
#include <string>

#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace sss {

/// A RIB file that cannot be understood: names the file, the line and the
/// statement ("scene.rib:12: Sphere: expected 4 numbers, got 3").
class RibError : public FormatError {
public:
    RibError(const std::string& path, int line, const std::string& statement,
             const std::string& what)
        : FormatError(Composed{}, compose(path, line, statement, what), path),
          m_line(line), m_statement(statement) {}
    int line() const { return m_line; }
    const std::string& statement() const { return m_statement; }

private:
    static std::string compose(const std::string& path, int line,
                               const std::string& statement, const std::string& what) {
        // Appended piece by piece: GCC 12 at -O3 warns (-Wrestrict, a false
        // positive) on ":" + std::to_string(line) inlined here.
        std::string out = path;
        if (line > 0) {
            out += ':';
            out += std::to_string(line);
        }
        out += ": ";
        if (!statement.empty()) {
            out += statement;
            out += ": ";
        }
        out += what;
        return out;
    }

    int m_line;
    std::string m_statement;
};

/// How to read a RIB.
struct RibReadOptions {
    /// With several FrameBegin blocks: the one to read. nullopt = the first.
    /// A requested frame that a file with FrameBegin blocks does not contain is
    /// an error; a file without FrameBegin is the same scene for every frame.
    std::optional<int> frame;
    /// What to do with a request RenderMan has that is not carried out here
    /// (CSG, motion blur, Blobby ground planes, ...): false (the
    /// default) throws RibError, so that a farm never renders an incomplete
    /// frame; true skips it with one warning per kind, as the tools'
    /// -lenient option asks.
    bool lenient = false;
};

/// The path that names standard input for read_rib.
inline constexpr const char* kRibStandardInput = "-";

/// Reads a RIB file, plain or gzip-compressed (ReadArchive paths are
/// relative to the including file; a ReadArchive of a ".obj" file brings in
/// a Wavefront OBJ mesh as PointsPolygons). The path "-" reads standard
/// input: messages name it "<stdin>", the scene has no path (relative names
/// are relative to the working folder) and no source file. Throws IoError /
/// RibError.
Scene read_rib(const std::string& path, const RibReadOptions& options = {});
/// Same, from text in memory; `path` names it in messages and is the base for
/// relative ReadArchive paths.
Scene parse_rib(const std::string& text, const std::string& path,
                const RibReadOptions& options = {});

} // namespace sss

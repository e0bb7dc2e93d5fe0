// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file obj_import.h
/// Wavefront OBJ import: the mesh of an OBJ file (met through ReadArchive)
/// as one PointsPolygons primitive.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sss/scene/scene.h"

namespace sss::detail {

/// An OBJ file's faces as one primitive, in the file's object space.
struct ObjMesh {
    /// PointsPolygons with "P" (vertex; vertices after the last one a face
    /// uses are dropped) and, when every face corner names a normal, "N"
    /// (facevarying). No transform, attributes or source yet.
    Primitive primitive;
    int first_face_line = 0; ///< the line of the first face ("f")
};

/// Reads OBJ text (v, vn, vt and f; g, o, s, usemtl, mtllib and l carry
/// nothing for us). `path` names the file in messages. Each other statement
/// adds one warning "path:line: ..." to `warnings`; a file without faces adds
/// "path: no faces, nothing imported" and gives nullopt. Throws RibError
/// (path, line, keyword) for a malformed line or an index out of range, and
/// LimitError "path:line: f: ..." when a face, or the face corners of the
/// mesh so far, exceed Limit::PrimitiveVertices.
std::optional<ObjMesh> import_obj(std::string_view text, const std::string& path,
                                  std::vector<std::string>& warnings);

} // namespace sss::detail

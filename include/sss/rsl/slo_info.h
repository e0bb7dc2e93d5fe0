// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file slo_info.h
/// What `sloinfo` prints about a compiled shader (.slo): its type and name,
/// then each parameter's storage class, type, array length, whether it is
/// an output, and its default value. As text laid out like PRMan's sloinfo,
/// or as JSON for pipeline tools.

#include <string>

#include "sss/rsl/program.h"

namespace sss {

/// PRMan's layout:
///
///     surface "plastic"
///         "Ks" "parameter uniform float"
///             Default value: 0.5
///
/// Colours print as "rgb" [r g b], points, vectors, normals and matrices as
/// "current" [...], strings quoted, arrays as {a, b, ...}. A default the
/// shader computes when it runs (an expression that is not a constant, such
/// as a point in "shader" space) prints as <computed when the shader runs>.
std::string describe_shader(const Program& program);

/// The same as one JSON object: {"file", "type", "name", "parameters": [{"name",
/// "storage", "type", "array", "output", "default"}]}, "default" being a list
/// of numbers or of strings, or null when it is computed when the shader runs.
/// A class shader (RSL 2.0) also has "methods": the names of its public
/// methods (the pipeline methods among them).
std::string describe_shader_json(const Program& program, const std::string& file);

} // namespace sss

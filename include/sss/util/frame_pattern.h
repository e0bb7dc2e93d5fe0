// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file frame_pattern.h
/// Frame-number patterns in file names, shared by every tool's path
/// arguments and by file names inside scenes (docs/cli-conventions.md):
///   %d, %04d     printf style (%0Nd pads to N digits)
///   ####         one digit per '#' (Nuke, USD, Deadline); a lone '#' is
///                ambiguous across tools (1 or 4 digits) and rejected
///   $F, $F4      Houdini style ($F4 pads to 4 digits); ${F} and ${F4} too
/// Negative frames keep their sign in front of the padded digits.

#include <optional>
#include <string>

#include "sss/util/error.h"

namespace sss {

/// A frame pattern in a file name with no frame number to expand it with. A
/// UsageError (the caller must say which frame); the command-line layer adds
/// how to give it.
class MissingFrameError : public UsageError {
public:
    using UsageError::UsageError;
};

/// True if path contains a frame pattern (a lone '#' counts, so that it can
/// be reported).
bool has_frame_pattern(const std::string& path);

/// Expands every frame pattern of path with frame. A path without pattern is
/// returned unchanged. Throws MissingFrameError for a pattern without a
/// frame number ("<what>: 'x.####.ptc' has a frame pattern"), UsageError for a
/// lone '#' and for a malformed %-sequence.
std::string expand_frame_pattern(const std::string& path, std::optional<int> frame,
                                 const std::string& what = "path");

} // namespace sss

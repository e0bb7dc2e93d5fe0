// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file json.h
/// JSON string quoting, shared by the tools that write JSON (sloinfo -json,
/// ptview -serve).

#include <string>
#include <string_view>

namespace sss {

/// `text` as a JSON string literal, quotes included: `"` and `\` escaped,
/// control characters (below 0x20) as `\u00XX`, every other byte as it is
/// (so UTF-8 passes through).
std::string json_quote(std::string_view text);

} // namespace sss

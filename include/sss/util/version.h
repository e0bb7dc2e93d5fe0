// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file version.h
/// The project's version.

namespace sss {

/// Project version string ("0.1.0").
const char* version_string();

} // namespace sss

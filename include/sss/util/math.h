// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file math.h
/// Numeric constants shared by the stages.

#include <numbers>

namespace sss {

/// pi in double precision (std::numbers::pi).
inline constexpr double kPi = std::numbers::pi;

} // namespace sss

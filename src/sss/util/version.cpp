// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file version.cpp
/// The project version, from the build (CMakeLists.txt).

#include "sss/util/version.h"

#ifndef SSS_VERSION_STRING
#error "SSS_VERSION_STRING must be defined by the build (see CMakeLists.txt)"
#endif

namespace sss {

const char* version_string() {
    return SSS_VERSION_STRING;
}

} // namespace sss

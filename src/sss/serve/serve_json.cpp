// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file serve_json.cpp
/// The JSON writer of the page's answers and the program search.

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <sys/stat.h>
#include <unistd.h>

#include "serve_internal.h"
#include "sss/util/json.h"

namespace sss {

void JsonWriter::value_start() {
    if (m_after_key) {
        m_after_key = false;
        return;
    }
    if (!m_first.empty()) {
        if (!m_first.back()) m_text += ',';
        m_first.back() = false;
    }
}

JsonWriter& JsonWriter::begin_object() {
    value_start();
    m_text += '{';
    m_first.push_back(true);
    return *this;
}

JsonWriter& JsonWriter::end_object() {
    m_text += '}';
    m_first.pop_back();
    return *this;
}

JsonWriter& JsonWriter::begin_array() {
    value_start();
    m_text += '[';
    m_first.push_back(true);
    return *this;
}

JsonWriter& JsonWriter::end_array() {
    m_text += ']';
    m_first.pop_back();
    return *this;
}

JsonWriter& JsonWriter::key(const std::string& name) {
    value_start();
    m_text += json_quote(name);
    m_text += ':';
    m_after_key = true;
    return *this;
}

JsonWriter& JsonWriter::string(const std::string& value) {
    value_start();
    m_text += json_quote(value);
    return *this;
}

JsonWriter& JsonWriter::number(double value) {
    value_start();
    if (!std::isfinite(value)) {
        m_text += "null";
        return *this;
    }
    // The shortest of %.15g and %.17g that reads back exactly.
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.15g", value);
    if (std::strtod(buf, nullptr) != value)
        std::snprintf(buf, sizeof buf, "%.17g", value);
    m_text += buf;
    return *this;
}

JsonWriter& JsonWriter::boolean(bool value) {
    value_start();
    m_text += value ? "true" : "false";
    return *this;
}

JsonWriter& JsonWriter::null() {
    value_start();
    m_text += "null";
    return *this;
}

JsonWriter& JsonWriter::numbers(const double* values, std::size_t n) {
    begin_array();
    for (std::size_t i = 0; i < n; ++i) number(values[i]);
    return end_array();
}

JsonWriter& JsonWriter::numbers(const float* values, std::size_t n) {
    begin_array();
    for (std::size_t i = 0; i < n; ++i) {
        // A float's shortest exact text: %.9g always reads back to it.
        value_start();
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.9g", double(values[i]));
        m_text += std::isfinite(values[i]) ? buf : "null";
    }
    return end_array();
}

JsonWriter& JsonWriter::strings(const std::vector<std::string>& values) {
    begin_array();
    for (const std::string& v : values) string(v);
    return end_array();
}

std::string find_program(const std::string& program) {
    const auto executable = [](const std::string& path) {
        struct stat st {};
        return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
               ::access(path.c_str(), X_OK) == 0;
    };
    if (program.empty()) return "";
    if (program.find('/') != std::string::npos) return executable(program) ? program : "";
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/bin:/bin";
    std::size_t start = 0;
    while (start <= dirs.size()) {
        std::size_t end = dirs.find(':', start);
        if (end == std::string::npos) end = dirs.size();
        const std::string dir = end > start ? dirs.substr(start, end - start) : ".";
        const std::string candidate = dir + "/" + program;
        if (executable(candidate)) return candidate;
        start = end + 1;
    }
    return "";
}

} // namespace sss

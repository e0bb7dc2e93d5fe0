// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file serve_internal.h
/// What the serve module's sources share: a JSON writer for the page's
/// answers and the program search of the turntable's encoder.

#include <cstddef>
#include <string>
#include <vector>

namespace sss {

/// Writes JSON text: objects, arrays, strings (escaped), numbers (shortest
/// text that reads back to the same double; floats as floats), booleans.
/// The caller nests the calls correctly; commas are placed here.
class JsonWriter {
public:
    JsonWriter& begin_object();
    JsonWriter& end_object();
    JsonWriter& begin_array();
    JsonWriter& end_array();
    JsonWriter& key(const std::string& name);
    JsonWriter& string(const std::string& value);
    JsonWriter& number(double value);
    JsonWriter& boolean(bool value);
    JsonWriter& null();
    /// An array of numbers.
    JsonWriter& numbers(const double* values, std::size_t n);
    JsonWriter& numbers(const float* values, std::size_t n);
    JsonWriter& strings(const std::vector<std::string>& values);
    const std::string& text() const { return m_text; }

private:
    void value_start();
    std::string m_text;
    std::vector<bool> m_first; ///< per open level: nothing written in it yet
    bool m_after_key = false;
};

/// The path of `program` (a name searched on PATH, or a path with a '/')
/// when it is an executable file, else "".
std::string find_program(const std::string& program);

} // namespace sss

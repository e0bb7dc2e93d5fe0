// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file rib_lexer.h
/// The RIB tokenizer: statements (a request name and its arguments) read from
/// ASCII RIB text, and the text helpers the reader and the OBJ import share.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

// The reader's internals live in sss::rib, not sss::detail, so that their
// short names (Value, Statement, Reader...) cannot meet another module's.
namespace sss::rib {

/// One argument of a statement: a number, a string or a bracketed array.
struct Value {
    enum class Kind { Number, String, Array };
    Kind kind = Kind::Number;
    double number = 0.0;
    std::string string;
    std::vector<double> numbers;      // Array of numbers
    std::vector<std::string> strings; // Array of strings
    bool string_array = false;        // an empty array is neither

    bool is_number() const { return kind == Kind::Number; }
    bool is_string() const { return kind == Kind::String; }
    bool is_array() const { return kind == Kind::Array; }
};

/// A request and its arguments, with where it was read.
struct Statement {
    std::string name;
    std::vector<Value> args;
    int line = 0;
    std::shared_ptr<const std::string> file;
};

/// "a number", "a string" or "an array", for messages.
const char* describe(const Value& v);

/// White space as the RIB (and OBJ) tokenizers see it.
bool is_space(char c);

/// `s` in lower case (ASCII).
std::string lower(std::string_view s);

/// Parses a whole token as a finite number; sets `error` otherwise.
bool parse_number(std::string_view text, double& out, std::string& error);

/// Splits ASCII RIB text into statements. Strings longer than
/// limit(Limit::StringLength) and words or numbers longer than
/// limit(Limit::TokenLength) are LimitErrors; an argument list or array
/// whose memory exceeds what the process may use is an OutOfMemoryError.
class Lexer {
public:
    /// Throws RibError for gzip-compressed text; skips a UTF-8 byte order mark.
    Lexer(std::string_view text, std::shared_ptr<const std::string> path);

    /// Reads the next statement; false at the end of the text.
    bool next(Statement& st);

private:
    enum class Tok { End, Word, Number, String, Open, Close };
    struct Token {
        Tok kind = Tok::End;
        int line = 0;
        double number = 0.0;
        std::string text;
    };

    [[noreturn]] void fail(int line, const std::string& statement,
                           const std::string& what);
    /// "file:line: Statement" for limit errors.
    std::string where(int line) const;
    /// A token of `length` bytes starting on `line`: within TokenLength.
    /// `word`: a word (maybe the next request), else a number of this one.
    void check_token(std::size_t length, int line, bool word) const;
    /// `count` elements of `element_bytes` each, about to grow: checked
    /// against the memory budget at each doubling from 65536 elements.
    void check_growth(std::size_t count, std::size_t element_bytes, int line,
                      const char* what) const;
    static std::string tok_name(const Token& t);
    void read_array(const Statement& st, int open_line, Value& v);
    Token take();
    Token scan();
    std::string scan_string();

    std::string_view m_text;
    std::shared_ptr<const std::string> m_path;
    std::size_t m_pos = 0;
    int m_line = 1;
    Token m_peek;
    bool m_has_peek = false;
    std::string m_statement; // the statement being read, for messages
    uint64_t m_max_string = 0;
    uint64_t m_max_token = 0;
};

} // namespace sss::rib

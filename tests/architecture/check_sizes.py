#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Size limits on the C++ sources: no file over 1200 lines, no function over 150.

Usage: check_sizes.py SOURCE_DIR

Scans SOURCE_DIR/{src,include,python} for *.cpp, *.h and *.inl. Prints one
`file:line: name N lines` per offender and exits 1 if there is any.

Functions are found with a heuristic that relies on the project's clang-format
style rather than a C++ parser: comments and literals are blanked out, braces
are counted, and a brace block opened at namespace or class scope is a function
definition unless its statement starts a namespace/class/struct/enum/union or
extern block, or is an initializer (an `=` outside parentheses, which also
covers a lambda stored in a variable). A function's length runs from the first
line of its signature (template line included) to its closing brace.
"""

import os
import re
import sys

MAX_FILE_LINES = 1200
MAX_FUNCTION_LINES = 150
ROOTS = ("src", "include", "python")
SUFFIXES = (".cpp", ".h", ".inl")

CONTAINER = re.compile(r"^(?:(?:inline|export)\s+)?(namespace|class|struct|union|enum|extern)\b")
ACCESS = re.compile(r"^\s*(?:public|private|protected)\s*:(?!:)")
# A constructor's initializer list whose next member is initialized with braces.
MEMBER_INIT = re.compile(r"\)\s*(?:noexcept\s*)?:(?!:)[^;]*[\w>]\s*$")
RAW_STRING = re.compile(r'R"([^()\\\s]{0,16})\(')


def blank_comments_and_literals(text):
    """Returns text with comments and string/char literals replaced by spaces.

    Newlines are kept so that line numbers stay valid.
    """
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "/" and text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif c == "/" and text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and RAW_STRING.match(text, i) and (i == 0 or not (
                text[i - 1].isalnum() or text[i - 1] == "_")):
            m = RAW_STRING.match(text, i)
            end = ")" + m.group(1) + '"'
            j = text.find(end, m.end())
            j = n if j < 0 else j + len(end)
            out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and \
                    text[i + 1].isalnum() and not text[i - 1].isalpha():
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * max(0, j - i - 2) + (c if j - i >= 2 else ""))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def blank_preprocessor(text):
    """Blanks preprocessor lines (with their continuations)."""
    lines = text.split("\n")
    continued = False
    for k, line in enumerate(lines):
        if continued or line.lstrip().startswith("#"):
            continued = line.rstrip().endswith("\\")
            lines[k] = ""
    return "\n".join(lines)


def has_top_level_assignment(statement):
    depth = 0
    s = re.sub(r"\boperator\s*[^\s(]*", "operator", statement)
    for k, c in enumerate(s):
        if c in "([<":
            depth += 1 if c != "<" else 0
        elif c in ")]":
            depth -= 1
        elif c == "=" and depth == 0:
            prev = s[k - 1] if k > 0 else ""
            nxt = s[k + 1] if k + 1 < len(s) else ""
            if prev not in "=!<>" and nxt != "=":
                return True
    return False


def function_name(statement):
    depth = 0
    head = []
    for c in statement:
        if c == "(" and depth == 0:
            break
        depth += c == "<"
        depth -= c == ">"
        head.append(c)
    words = re.findall(r"[~A-Za-z_][\w:~]*(?:\s*operator\s*\S+)?", "".join(head))
    return words[-1] if words else "?"


def classify(statement):
    """'container', 'function' or 'other' for the statement opening a block."""
    s = statement.strip()
    s = re.sub(r"^template\s*<.*?>\s*(?=[A-Za-z_])", "", s, flags=re.S)
    s = re.sub(r"^(\[\[.*?\]\]\s*)+", "", s, flags=re.S)
    if CONTAINER.match(s):
        if not re.match(r"^(?:enum|struct|class|union)\b[^(]*\)", s):
            return "container"
    if has_top_level_assignment(s):
        return "other"
    if "(" in s:
        return "function"
    return "other"


def long_functions(text):
    """Yields (line, name, length) for the functions longer than the limit."""
    code = blank_preprocessor(blank_comments_and_literals(text))
    # Each entry: (kind, start line, name); kinds: container, function, inner,
    # meminit (a braced member initializer) and other.
    stack = []
    statement = []
    statement_line = None
    line = 1
    for c in code:
        in_function = any(kind in ("function", "inner") for kind, _, _ in stack)
        if c == "\n":
            line += 1
            if not in_function:
                statement.append(c)
            continue
        if in_function:
            if c == "{":
                stack.append(("inner", line, None))
            elif c == "}":
                kind, start, name = stack.pop()
                length = line - start + 1
                if kind == "function" and length > MAX_FUNCTION_LINES:
                    yield start, name, length
            continue
        if c == "{" and stack and stack[-1][0] == "meminit":
            stack.append(("meminit", line, None))
        elif c == "{" and MEMBER_INIT.search("".join(statement)):
            # A braced member initializer in a constructor's list: the
            # statement goes on to the constructor's body.
            stack.append(("meminit", line, None))
        elif c == "{":
            text_so_far = "".join(statement)
            kind = classify(text_so_far)
            start = statement_line if statement_line is not None else line
            name = function_name(text_so_far) if kind == "function" else None
            stack.append((kind, start, name))
            statement, statement_line = [], None
        elif c == "}" and stack and stack[-1][0] == "meminit":
            stack.pop()
            statement.append(c)
        elif c in ";}":
            if c == "}" and stack:
                stack.pop()
            statement, statement_line = [], None
        elif c == ":" and ACCESS.match("".join(statement) + c):
            statement, statement_line = [], None
        else:
            if statement_line is None and not c.isspace():
                statement_line = line
            statement.append(c)


def check_file(path, rel):
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
    problems = []
    lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
    if lines > MAX_FILE_LINES:
        problems.append(f"{rel}:1: file {lines} lines (limit {MAX_FILE_LINES})")
    for start, name, length in long_functions(text):
        problems.append(
            f"{rel}:{start}: {name} {length} lines (limit {MAX_FUNCTION_LINES})")
    return problems


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return 2
    root = argv[1]
    problems = []
    scanned = 0
    for sub in ROOTS:
        top = os.path.join(root, sub)
        for dirpath, dirnames, filenames in os.walk(top):
            dirnames.sort()
            for name in sorted(filenames):
                if name.endswith(SUFFIXES):
                    path = os.path.join(dirpath, name)
                    scanned += 1
                    problems += check_file(path, os.path.relpath(path, root))
    if scanned == 0:
        print(f"check_sizes: no sources under {root}", file=sys.stderr)
        return 2
    for p in problems:
        print(p)
    if problems:
        print(f"check_sizes: {len(problems)} over the limits in {scanned} files",
              file=sys.stderr)
        return 1
    print(f"check_sizes: {scanned} files within the limits")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

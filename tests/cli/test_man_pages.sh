#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# The hand-written man pages (man/*.1) against the tools: one page per
# installed tool and no other; every option a tool's --help lists (sss-farm:
# its commands' too) appears in its page; every page has the sections a user
# looks for and renders without a warning, as groff (-ww) and lintian's
# check (man --warnings) see it. tests/cli/test_man_examples.sh runs the
# pages' EXAMPLES.
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
pages="$root/man"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_man_pages.XXXXXX")"
trap 'rm -rf "$work"' EXIT
command -v groff >/dev/null || { echo "FAIL: groff is needed (scripts/install-deps)" >&2; exit 1; }
command -v man >/dev/null || { echo "FAIL: man (man-db) is needed (scripts/install-deps)" >&2; exit 1; }

# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# The tools cmake/install.cmake installs, and sss-farm.
read -ra tools <<<"$(sed -n '/^set(SSS_TOOLS/,/)/p' "$root/cmake/install.cmake" |
    sed 's/^set(SSS_TOOLS//; s/)//' | tr '\n' ' ')"
tools+=(sss-farm)
((${#tools[@]} >= 13)) || fail "cannot read the tools from cmake/install.cmake: ${tools[*]}"
for t in "${tools[@]}"; do
    [[ -f "$pages/$t.1" ]] || fail "no man page man/$t.1"
done
for page in "$pages"/*.1; do
    name="$(basename "$page" .1)"
    [[ " ${tools[*]} " == *" $name "* ]] || fail "man/$name.1 is not the page of an installed tool"
done

for t in "${tools[@]}"; do
    page="$pages/$t.1"
    [[ -f "$page" ]] || continue
    # Sections, in the order of man-pages(7).
    sections="$(grep '^\.SH ' "$page" | sed 's/^\.SH //; s/"//g' | tr '\n' '|')"
    want='NAME|SYNOPSIS|DESCRIPTION|'
    [[ "$sections" == "$want"* ]] || fail "$t.1: sections $sections do not start with $want"
    for s in OPTIONS EXAMPLES ENVIRONMENT 'EXIT STATUS' 'SEE ALSO'; do
        [[ "|$sections" == *"|$s|"* ]] || fail "$t.1: no section $s"
    done
    # No warning from groff, nor from man as lintian runs it.
    warnings="$(groff -man -Tutf8 -ww -z "$page" 2>&1)"
    [[ -z "$warnings" ]] || fail "$t.1: groff warns: $warnings"
    warnings="$(LC_ALL=C.UTF-8 MANROFFSEQ='' MANWIDTH=80 man --warnings -E UTF-8 -l -Tutf8 -Z "$page" 2>&1 >/dev/null)"
    [[ -z "$warnings" ]] || fail "$t.1: man --warnings: $warnings"
    # NAME is what whatis and apropos read: "tool \- what it does".
    grep -A1 '^\.SH NAME' "$page" | tail -1 | grep -q "^${t//-/\\\\-} \\\\- [a-z]" ||
        fail "$t.1: the NAME line is not '$t \\- description'"

    # The options --help lists, rendered page against help text.
    if [[ "$t" == sss-farm ]]; then
        for c in "" submit task status; do "$bin/sss-farm" $c --help; done >"$work/$t.help"
    else
        "$bin/$t" --help >"$work/$t.help"
    fi
    groff -man -Tutf8 -P-cbou "$page" 2>/dev/null >"$work/$t.txt"
    missing="$(python3 - "$work/$t.help" "$work/$t.txt" <<'PY'
import re, sys
help_text = open(sys.argv[1]).read()
page = " ".join(open(sys.argv[2], encoding="utf-8").read().split())
# As sss::usage_options (src/sss/cli/args.cpp): one or two dashes and a
# letter, at a line's start or after a space, '(', '[' or ','.
options = re.findall(r"(?:^|(?<=[\s(\[,]))(--?[A-Za-z][A-Za-z0-9_]*(?:-[A-Za-z0-9_]+)*)",
                     help_text, re.M)
assert len(options) >= 3, "no options found in --help"
missing = sorted({o for o in options
                  if not re.search(r"(?<![A-Za-z0-9_-])" + re.escape(o) + r"(?![A-Za-z0-9_])", page)})
print(" ".join(missing))
PY
)" || { fail "$t: cannot compare --help with the page"; continue; }
    [[ -z "$missing" ]] || fail "$t.1 lacks options its --help lists: $missing"
done

finish_checks "man page"
echo "all man page checks passed (${#tools[@]} pages)"

# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Check helpers for CLI tests that run every check and report all failures
# (sourced after lib.sh). Call finish_checks NAME at the end.

failures=0

# fail MESSAGE: records a failed check.
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

# no_warnings STDERR: no warning or error line in a tool's stderr (the
# sanitizer build adds its own summaries there, e.g. of suppressed leaks in
# OpenImageIO, so an empty stderr is too much to ask).
no_warnings() { ! grep -qE "WARNING|ERROR" <<<"$1"; }

# render_clean ARGS...: runs render (needs $bin); fails unless it exits 0
# without a warning.
render_clean() {
    run "$bin/render" "$@"
    [[ "$rc" == 0 ]] && no_warnings "$err" || fail "render $*: exit $rc, stderr: $err"
}

# expect_rc CODE LABEL: checks the last run's exit status.
expect_rc() {
    if [[ "$rc" != "$1" ]]; then
        fail "$2: expected exit $1, got $rc"$'\n'"  stdout: ${out:0:400}"$'\n'"  stderr: $err"
        return 1
    fi
}

# points FILE: the point count ptinfo reports ("" if unreadable). Needs $ptinfo.
points() {
    "$ptinfo" "$1" 2>/dev/null | sed -n 's/^points: *//p'
}

# has_channel FILE "color _ssdiffusion"
has_channel() {
    "$ptinfo" "$1" 2>/dev/null | grep -Eq "^ *$2\$"
}

# mtime_of FILE: modification time at full resolution ("none" if missing).
mtime_of() { stat -c %y "$1" 2>/dev/null || echo none; }

# finish_checks NAME: exits 1 if any check failed.
finish_checks() {
    if ((failures > 0)); then
        echo "$failures check(s) failed" >&2
        exit 1
    fi
    echo "all $1 CLI checks passed"
}

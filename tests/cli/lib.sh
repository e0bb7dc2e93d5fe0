# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Shared helpers for the CLI tests (sourced; needs $work, a scratch folder).

# Runs a command, storing its exit status in $rc, stdout in $out, stderr in $err.
run() {
    set +e
    "$@" >"$work/stdout" 2>"$work/stderr"
    rc=$?
    set -e
    out="$(cat "$work/stdout")"
    err="$(cat "$work/stderr")"
}

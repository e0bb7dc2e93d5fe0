#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of inputs that are not regular files and files that are not
# scenes (issue 15, first part): every tool refuses a directory, a FIFO and a
# character device as an input with one ERROR line that says what it is,
# within seconds (a FIFO used to block the readers forever), and writes
# nothing; render and ptbake refuse a RIB without WorldBegin (an archive, or
# not RIB at all) and render warns about a world without geometry.
# Needs SSS_BIN_DIR (the folder with the executables).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_special.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

mkdir folder.rib folder.ptc folder.bkm folder.sl folder.exr
mkfifo fifo.rib fifo.ptc fifo.bkm fifo.sl fifo.exr

# refused LABEL TOOL WHAT ARGS...: exit 1 within 60 s (a tool that blocks on a
# FIFO would wait forever; a refusal takes well under a second), one "TOOL ERROR:" first
# line saying WHAT, and no new files in the folder.
refused() {
    local label="$1" tool="$2" what="$3"
    shift 3
    local before after
    before="$(ls -A | grep -v "^std\(out\|err\)$")"
    run timeout 60 "$bin/$tool" "$@"
    after="$(ls -A | grep -v "^std\(out\|err\)$")"
    if [[ "$rc" == 124 ]]; then
        fail "$label: $tool blocked (killed after 60 s)"
        return
    fi
    expect_rc 1 "$label" || return 0
    local first
    first="$(head -n 1 <<<"$err")"
    [[ "$first" == "$tool ERROR: "*"$what"* ]] || fail "$label: expected '$what': $err"
    [[ "$before" == "$after" ]] || fail "$label: files appeared: $(diff <(echo "$before") <(echo "$after") | tr '\n' ' ')"
}

for kind in folder fifo; do
    what="is a directory"
    [[ $kind == fifo ]] && what="is a FIFO"
    refused "render $kind" render "$what" $kind.rib
    refused "ptbake $kind" ptbake "$what" $kind.rib
    refused "ptfilter $kind" ptfilter "$what" -ssdiffusion -material marble $kind.ptc out.ptc
    refused "ptinfo $kind" ptinfo "$what" $kind.ptc
    refused "brickmake $kind" brickmake "$what" $kind.ptc out.bkm
    refused "brickinfo $kind" brickinfo "$what" $kind.bkm
    refused "ptview $kind" ptview "$what" $kind.ptc out.png
    refused "shader $kind" shader "$what" $kind.sl
    refused "envdome $kind" envdome "$what" $kind.exr out.rib
done
refused "render /dev/null" render "is a character device" /dev/null
refused "ptinfo /dev/zero" ptinfo "is a character device" /dev/zero
[[ ! -e folder.exr/../folder.rib.exr && ! -e folder.exr.exr ]] || fail "render wrote an image for a folder"

# Not scenes.
printf 'Format 8 8 1\nProjection "perspective"\n' >noworld.rib
refused "render without WorldBegin" render "no WorldBegin" noworld.rib
refused "ptbake without WorldBegin" ptbake "no WorldBegin" noworld.rib
printf 'Format 8 8 1\nDisplay "empty.exr" "openexr" "rgba"\nWorldBegin\nWorldEnd\n' >empty.rib
run "$bin/render" empty.rib
if expect_rc 0 "render, a world without geometry"; then
    [[ "$err" == *"no geometry"* ]] || fail "an empty world should warn: $err"
    [[ -s empty.exr ]] || fail "an empty world still renders its (empty) image"
fi

finish_checks "special inputs"

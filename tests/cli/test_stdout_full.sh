#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of the standard-output policy (docs/cli-conventions.md, "Standard
# output"): a write error on stdout is a failure, exit 1 with
# "<tool> ERROR: cannot write to standard output: <reason>", for every tool
# and for --help/--version too; a job whose stdout failed before its outputs
# were committed changes nothing (previous outputs byte-identical, no
# temporaries left); a job that prints nothing does not care where stdout goes.
# Uses /dev/full (every write fails with ENOSPC) and a closed stdout.
# Needs SSS_BIN_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_stdout.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
[[ -w /dev/full ]] || { echo "SKIP: no /dev/full"; exit 0; }

# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# full LABEL TOOL ARGS...: runs TOOL with stdout on /dev/full; expects exit 1
# and the stdout error as the first (and only) ERROR line.
full() {
    local label="$1" tool="$2"
    shift 2
    set +e
    timeout 60 "$bin/$tool" "$@" >/dev/full 2>stderr
    rc=$?
    set -e
    err="$(cat stderr)"
    if [[ "$rc" != 1 ]]; then
        fail "$label: expected exit 1, got $rc: $err"
        return 0
    fi
    [[ "$(head -n 1 stderr)" == "$tool ERROR: cannot write to standard output: No space left on device" ]] ||
        fail "$label: $err"
    [[ "$(grep -c "ERROR" stderr)" == 1 ]] || fail "$label: not one ERROR line: $err"
}

# unchanged LABEL FILE: FILE is still byte-identical to old.ref and no
# temporary is left.
unchanged() {
    cmp -s "$2" old.ref || fail "$1: $2 was changed"
    local tmp
    tmp="$(find . -name '.*.tmp' | head -n 1)"
    [[ -z "$tmp" ]] || fail "$1: temporary left: $tmp"
}

# --- --help and --version ------------------------------------------------------
for tool in render ptbake ptfilter ptinfo ptsynth brickmake brickinfo ptview shader envdome; do
    full "$tool --help" "$tool" --help
    full "$tool --version" "$tool" --version
    "$bin/$tool" --help >/dev/null || fail "$tool --help fails on a working stdout"
done

# --- inputs --------------------------------------------------------------------
"$bin/ptsynth" -n 400 in.ptc >/dev/null
"$bin/brickmake" in.ptc in.bkm
cat >scene.rib <<'EOF'
Format 16 16 1
Projection "perspective" "fov" 40
Display "image.exr" "openexr" "rgba"
Translate 0 0 5
WorldBegin
LightSource "distantlight" 1
Surface "matte"
Sphere 1 -1 1 360
WorldEnd
EOF
cat >bake.rib <<'EOF'
Format 16 16 1
Projection "perspective" "fov" 40
Translate 0 0 5
WorldBegin
LightSource "distantlight" 1
Surface "bake_radiance_t" "string filename" "baked.ptc"
Sphere 1 -1 1 360
WorldEnd
EOF
printf 'surface flat() { Ci = 1; }\n' >flat.sl

# --- jobs that print before committing: nothing changes --------------------------
echo "previous output" >old.ref
for f in out.ptc filtered.ptc image.exr baked.ptc out.bkm flat.slo sky.exr view.png; do cp old.ref $f; done
full "ptsynth" ptsynth -n 100 out.ptc
unchanged "ptsynth" out.ptc
full "ptfilter -progress 1" ptfilter -ssdiffusion -progress 1 in.ptc filtered.ptc
unchanged "ptfilter -progress 1" filtered.ptc
full "render -progress 1" render -progress 1 scene.rib
unchanged "render -progress 1" image.exr
full "ptbake -progress 1" ptbake -progress 1 bake.rib
unchanged "ptbake -progress 1" baked.ptc
full "brickmake -progress 1" brickmake -progress 1 in.ptc out.bkm
unchanged "brickmake -progress 1" out.bkm
full "shader" shader flat.sl
unchanged "shader" flat.slo
full "envdome -progress 1" envdome -sky 8 4 -progress 1 sky.exr
unchanged "envdome -progress 1" sky.exr
full "ptview" ptview -res 16 16 in.ptc view.png
unchanged "ptview" view.png

# --- tools that only print ---------------------------------------------------------
full "ptinfo" ptinfo in.ptc
full "brickinfo" brickinfo in.bkm
# -newer 1 with nothing to do prints one line.
"$bin/ptfilter" -ssdiffusion in.ptc up.ptc
full "ptfilter -newer 1, nothing to do" ptfilter -ssdiffusion -newer 1 in.ptc up.ptc

# --- a job that prints nothing does not fail ----------------------------------------
set +e
"$bin/ptfilter" -ssdiffusion in.ptc quiet.ptc >/dev/full 2>stderr
rc=$?
"$bin/render" scene.rib >&- 2>>stderr
rc2=$?
set -e
[[ "$rc" == 0 && -s quiet.ptc ]] || fail "a quiet ptfilter failed on /dev/full: $(cat stderr)"
[[ "$rc2" == 0 ]] && ! cmp -s image.exr old.ref || fail "a quiet render failed with stdout closed: $(cat stderr)"

# A closed stdout is an error for a tool that prints.
set +e
"$bin/ptinfo" in.ptc >&- 2>stderr
rc=$?
set -e
[[ "$rc" == 1 && "$(head -n 1 stderr)" == "ptinfo ERROR: cannot write to standard output: Bad file descriptor" ]] ||
    fail "ptinfo with stdout closed: exit $rc: $(cat stderr)"

finish_checks "stdout"

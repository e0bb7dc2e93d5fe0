#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# What the tools say when a command line or an input is wrong
# (docs/cli-conventions.md, "Messages"): an unknown option gets the closest
# option the tool's --help lists ("did you mean -material?"), an unknown
# material the closest preset, and nothing is guessed when nothing is close
# (all exit 2); a missing input is "<file>: cannot open: No such file or
# directory" in every tool (exit 1).
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_feedback.XXXXXX")"
trap 'rm -rf "$work"' EXIT
# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"
cd "$work"

# says RC LINE TOOL ARGS...: TOOL ARGS exits RC and the first line of its
# stderr is LINE exactly.
says() {
    local want_rc="$1" want="$2" tool="$3"
    shift 3
    run "$bin/$tool" "$@"
    local first
    first="$(head -n 1 <<<"$err")"
    [[ "$rc" == "$want_rc" ]] || fail "$tool $*: exit $rc, not $want_rc ($err)"
    [[ "$first" == "$want" ]] || fail "$tool $*: said '$first', not '$want'"
}

"$bin/ptsynth" -n 500 in.ptc >/dev/null

# --- did you mean --------------------------------------------------------
says 2 "ptfilter ERROR: unknown option -materail; did you mean -material?" \
    ptfilter -ssdiffusion -materail skin1 in.ptc out.ptc
says 2 "ptfilter ERROR: unknown option -maxsolidagle; did you mean -maxsolidangle?" \
    ptfilter -ssdiffusion -maxsolidagle 0.5 in.ptc out.ptc
says 2 "ptfilter ERROR: option -material: unknown material 'skin11'; did you mean 'skin1'?" \
    ptfilter -ssdiffusion -material skin11 in.ptc out.ptc
says 2 "ptbake ERROR: option -material: unknown material 'Marble'; did you mean 'marble'?" \
    ptbake -material Marble scene.rib
says 2 "ssprofile ERROR: option -material: unknown material 'wholmilk'; did you mean 'wholemilk'?" \
    ssprofile -material wholmilk
says 2 "brickmake ERROR: unknown option -maxerrror; did you mean -maxerror?" \
    brickmake -maxerrror 0.01 in.ptc out.bkm
says 2 "ptbake ERROR: unknown option -spaceing; did you mean -spacing?" ptbake -spaceing 1 s.rib
says 2 "render ERROR: unknown option -sampels; did you mean -samples?" render -sampels 2 s.rib
says 2 "ptview ERROR: unknown option -exposre; did you mean -exposure?" \
    ptview -exposre 1 in.ptc out.png
says 2 "brickinfo ERROR: unknown option -picutre; did you mean -picture?" \
    brickinfo -picutre x.png m.bkm
says 2 "ptinfo ERROR: unknown option -stat; did you mean -stats?" ptinfo -stat 0 in.ptc
says 2 "ptsynth ERROR: unknown option -jiter; did you mean -jitter?" ptsynth -jiter 0.5 o.ptc
says 2 "sloinfo ERROR: unknown option -jsno; did you mean -json?" sloinfo -jsno 1 x.slo
says 2 "envdome ERROR: unknown option -intesity; did you mean -intensity?" \
    envdome -intesity 2 p.exr o.rib
says 2 "ssprofile ERROR: unknown option -photon; did you mean -photons?" ssprofile -photon 10
says 2 "shader ERROR: unknown option -nsod; did you mean -nosd?" shader -nsod x.sl
says 2 "ptfilter ERROR: unknown option -threds; did you mean -threads?" \
    ptfilter -ssdiffusion --threds 2 in.ptc out.ptc
# Nothing close: nothing guessed (and the material list instead).
says 2 "ptfilter ERROR: unknown option -bogus" ptfilter -ssdiffusion -bogus in.ptc out.ptc
says 2 "ptfilter ERROR: unknown option -x" ptfilter -ssdiffusion -x in.ptc out.ptc
says 2 "ptfilter ERROR: option -material: unknown material 'granite' (known: apple, chicken1, chicken2, cream, ketchup, marble, potato, skimmilk, skin1, skin2, spectralon, wholemilk)" \
    ptfilter -ssdiffusion -material granite in.ptc out.ptc
[[ ! -e out.ptc && ! -e out.bkm ]] || fail "a refused command line wrote an output"

# --- missing inputs -------------------------------------------------------
enoent="cannot open: No such file or directory"
says 1 "ptfilter ERROR: nope.ptc: $enoent" ptfilter -ssdiffusion nope.ptc out.ptc
says 1 "ptfilter ERROR: nope.ptc: $enoent" ptfilter -ssdiffusion -blocker nope.ptc in.ptc out.ptc
says 1 "ptfilter ERROR: nope.ptpart: $enoent" ptfilter -merge nope.ptpart out.ptc
says 1 "brickmake ERROR: nope.ptc: $enoent" brickmake nope.ptc out.bkm
says 1 "brickinfo ERROR: nope.bkm: $enoent" brickinfo nope.bkm
says 1 "ptinfo ERROR: nope.ptc: $enoent" ptinfo nope.ptc
says 1 "ptview ERROR: nope.ptc: $enoent" ptview nope.ptc out.png
says 1 "render ERROR: nope.rib: $enoent" render nope.rib
says 1 "ptbake ERROR: nope.rib: $enoent" ptbake nope.rib
says 1 "sloinfo ERROR: nope.slo: $enoent" sloinfo nope.slo
says 1 "envdome ERROR: nope.exr: $enoent" envdome nope.exr out.rib
[[ ! -e out.ptc && ! -e out.bkm && ! -e out.png && ! -e out.rib ]] ||
    fail "a job with a missing input wrote an output"
# A missing archive says where it was looked for.
printf 'WorldBegin\nReadArchive "gone.rib"\nWorldEnd\n' >archive.rib
run "$bin/render" archive.rib
[[ "$rc" == 1 && "$err" == "render ERROR: gone.rib: $enoent (not found along the archive search path"* ]] ||
    fail "missing archive: exit $rc: $err"
finish_checks "feedback"

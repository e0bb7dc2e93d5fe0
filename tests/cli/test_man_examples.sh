#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Every command line in the EXAMPLES of the man pages (man/*.1) runs and
# exits 0: the pages are run in pipeline order (ptsynth, ptbake, ptfilter,
# brickmake, ... ssprofile) in a copy of the bundled teapot scene, where each
# page's examples use what the earlier ones made, and a copy of the orbit
# scene for the blocks marked `.\" sandbox: orbit` (frame sequences). A block
# marked `.\" not run: <why>` is skipped (sss-farm's need a Slurm cluster);
# /usr/share/sss stands for the build's shaders.
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
bin="$(cd "$bin" && pwd)"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_man_examples.XXXXXX")"
trap 'rm -rf "$work"' EXIT

# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

mkdir -p "$work/teapot" "$work/orbit" "$work/share/sss/shaders"
cp "$root/scenes/teapot/bake.rib" "$root/scenes/teapot/teapot.rib" "$work/teapot/"
cp "$root/scenes/orbit/bake.rib" "$root/scenes/orbit/orbit.rib" "$work/orbit/"
# /usr/share/sss/shaders of an install: the compiled shaders, headers and sources.
ln -s "$bin/../shaders/"*.slo "$bin/../shaders/"*.h "$root/shaders/"*.sl "$work/share/sss/shaders/"
export PATH="$bin:$PATH"

# blocks PAGE: each EXAMPLES block as "SANDBOX|RUN|text with \n escaped", one a line.
blocks() {
    python3 - "$1" <<'PY'
import re, sys
sandbox, run, block, out = "teapot", True, None, []
for line in open(sys.argv[1], encoding="utf-8").read().splitlines():
    if line.startswith('.\\" sandbox:'):
        sandbox = line.split(":", 1)[1].strip()
    elif line.startswith('.\\" not run:'):
        run = False
    elif line == ".EX":
        block = []
    elif line == ".EE":
        text = "\n".join(block)
        for troff, shell in (("\\-", "-"), ("\\e", "\\"), ("\\&", ""), ("\\(aq", "'")):
            text = text.replace(troff, shell)
        if "\\" in text.replace("\\\n", ""):
            sys.exit("an escape the test does not know in: " + text)
        out.append("%s|%d|%s" % (sandbox, run, text.replace("\n", "\\n")))
        sandbox, run, block = "teapot", True, None
    elif block is not None:
        block.append(line)
print("\n".join(out))
PY
}

total=0
for t in ptsynth ptbake ptfilter brickmake brickinfo ptinfo ptview render shader sloinfo envdome \
    ssprofile sss-farm; do
    page="$root/man/$t.1"
    ran=0
    while IFS='|' read -r sandbox run text; do
        [[ -n "$sandbox" ]] || continue
        ((run)) || continue
        text="${text//\\n/$'\n'}"
        text="${text//\/usr\/share\/sss\//$work/share/sss/}"
        if ! (cd "$work/$sandbox" && bash -e -o pipefail -c "$text") >"$work/out" 2>&1; then
            fail "$t.1: this example failed in $sandbox/:"$'\n'"$text"$'\n'"--- its output:"$'\n'"$(tail -n 20 "$work/out")"
        fi
        ran=$((ran + 1))
    done < <(blocks "$page")
    [[ "$t" == sss-farm ]] || ((ran > 0)) || fail "$t.1: no example was run"
    total=$((total + ran))
done

finish_checks "man page example"
echo "all $total man page examples ran"

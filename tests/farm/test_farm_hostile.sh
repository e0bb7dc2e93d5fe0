#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# sss-farm against hostile input (any user, seconds, stub tools only): many
# malformed specs (wrong types, huge numbers, deep nesting, non-UTF-8, NULs,
# missing keys, names through '..'), specs that are FIFOs or links out of the
# work folder, huge frame ranges and part counts, and file names with spaces,
# quotes, $(...) and newlines carried through submit's --wrap and task's
# command untouched. Every failure must be one `sss-farm ERROR:` line with
# exit 1 or 2, never a traceback, a hang or a write outside the work folder.
#
# usage: tests/farm/test_farm_hostile.sh      env: SSS_BIN_DIR (default build/bin)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="$(realpath -m "${SSS_BIN_DIR:-$root/build/bin}")"
farm="$bin/sss-farm"
[[ -x "$farm" ]] || { echo "test_farm_hostile ERROR: no $farm (build first: scripts/build)" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# shellcheck source=tests/cli/lib.sh
source "$root/tests/cli/lib.sh"
# shellcheck source=tests/cli/checks.sh
source "$root/tests/cli/checks.sh"
cd "$work"

# one_error CODE LABEL: the last run failed with exit CODE and exactly one
# line on stderr, sss-farm's ERROR (plus the usage hint for exit 2).
one_error() {
    expect_rc "$1" "$2" || return 0
    local errors
    errors="$(grep -c '' "$work/stderr" || true)"
    grep -q 'Traceback' "$work/stderr" && { fail "$2: a traceback: $(head -c 300 "$work/stderr")"; return 0; }
    [[ "$(head -n1 "$work/stderr")" == "sss-farm ERROR: "* ]] || fail "$2: stderr: $(head -c 300 "$work/stderr")"
    [[ "$errors" == $(($1 == 2 ? 2 : 1)) ]] || fail "$2: $errors lines on stderr: $(head -c 300 "$work/stderr")"
}

# --- stub tools and Slurm -------------------------------------------------------
# Each stub tool writes its arguments, one per line (NUL-separated), to args.<tool>.
mkdir tools stubs
for t in ptbake ptfilter brickmake render ptinfo; do
    printf '#!/usr/bin/env bash\nprintf "%%s\\0" "$@" >"%s/args.%s"\n' "$work" "$t" >"tools/$t"
done
# sbatch runs the array's first task at once: --wrap through sh, in --chdir;
# it keeps its --output.
cat >stubs/sbatch <<'EOF'
#!/usr/bin/env bash
for a in "$@"; do
    case "$a" in
        --output=*) printf '%s\n' "${a#--output=}" >>"$STUB_DIR/outputs.log" ;;
        --wrap=*) wrap="${a#--wrap=}" ;;
        --chdir=*) chdir="${a#--chdir=}" ;;
        --array=*) task="${a#--array=}"; task="${task%%[-,]*}" ;;
    esac
done
(cd "$chdir" && SLURM_ARRAY_TASK_ID="$task" sh -c "$wrap") >>"$STUB_DIR/tasks.log" 2>&1
echo 7
EOF
printf '#!/bin/sh\nexit 0\n' >stubs/squeue
printf '#!/bin/sh\nexit 0\n' >stubs/scontrol
printf '#!/bin/sh\nexit 0\n' >stubs/scancel
chmod +x tools/* stubs/*
export STUB_DIR="$work/stubs" SSS_BIN_DIR="$work/tools"
export PATH="$work/stubs:$PATH"

# --- names with spaces, quotes, $(...) and newlines: passed on as they are ---------
odd=$'odd dir \'q\' "dq" $(touch PWNED1) `touch PWNED2`\nline2'
mkdir "$odd"
rib=$'sc ene \'1\' "2" $(touch PWNED3) ;touch PWNED4\nx.####.rib'
args="$(python3 -c 'import shlex, sys; print(shlex.join(["-o", sys.argv[1] + ".exr", sys.argv[1]]))' "$rib")"
run "$farm" submit --frames 3 --workdir "$odd" --name odd --render "$args"
expect_rc 0 "submit with odd names"
python3 - "$work/args.render" "$rib" <<'EOF' || fail "render's arguments: $(tr '\0' ' ' <"$work/args.render" 2>&1)"
import sys
got = open(sys.argv[1], "rb").read().decode().split("\0")[:-1]
sys.exit(got != ["-frame", "3", "-newer", "1", "-threads", "0", "-o", sys.argv[2] + ".exr", sys.argv[2]])
EOF
python3 -c 'import json,sys; sys.exit(json.load(open(sys.argv[1]))["state"] != "done")' "$odd/.sss-farm/status/odd.render.3" ||
    fail "odd names: status file: $(cat stubs/tasks.log)"
grep -qF -- "+ $work/tools/render -frame 3 " "$odd/logs/odd-render.0003.log" || fail "odd names: no frame log"
found="$(find "$work" "$HOME" -maxdepth 3 -name 'PWNED*' 2>/dev/null | head -n3 || true)"
[[ -z "$found" ]] || fail "a file name ran code: $found"

# --- a % in the work folder: sbatch's log name keeps it (%% in its pattern) ------
pct="$work/100%j done"
mkdir "$pct"
: >stubs/outputs.log
run "$farm" submit --frames 3 --workdir "$pct" --name pct --render a.rib
expect_rc 0 "submit from a folder with a %"
grep -qxF "$work/100%%j done/logs/pct-render.slurm.log" stubs/outputs.log ||
    fail "the log pattern of a folder with a %: $(cat stubs/outputs.log)"

# --- huge ranges and counts: refused before anything is allocated ----------------------
for frames in 1-1000000000 "1-$(printf '9%.0s' {1..5000})" 0-4000001 "1,2,x" "" "5-"; do
    run timeout 20 "$farm" submit --frames "$frames" --render a.rib --dry-run
    one_error 2 "--frames ${frames:0:30}"
done
run timeout 20 "$farm" submit --frames 1 --filter "a.ptc b.ptc" --splitpoints 1 --parts 99999999 --dry-run
one_error 2 "--parts 99999999"
run timeout 20 "$farm" submit --frames 1 --render a.rib --splitpoints "$(printf '9%.0s' {1..5000})" --parts 2 --dry-run
one_error 2 "5000-digit --splitpoints"
run "$farm" submit --frames 1 --render a.rib --name "../up" --dry-run
one_error 2 "--name through .."

# --- frame patterns: at most 16 digits, as the tools (a wider one is a plain name) ------
mkdir wide
h17="#################"
touch "wide/o.$h17.bkm" wide/p.0000000000000001.bkm
run "$farm" submit --frames 1 --workdir wide --name p --brick "in.ptc o.$h17.bkm" --render "-o p.################.bkm r.rib"
expect_rc 0 "submit with wide patterns"
run "$farm" status "$work/wide/.sss-farm/p.json"
expect_rc 0 "status with wide patterns"
[[ "$(grep -c 'outputs exist: 1$' stdout)" == 2 ]] || fail "wide patterns: status: $out"

# --- a good spec to spoil ---------------------------------------------------------------
mkdir w
run "$farm" submit --frames 1-2 --workdir w --name s --filter "-ssdiffusion in.####.ptc out.####.ptc" \
    --brick "out.####.ptc out.####.bkm" --splitpoints 5 --parts 2
expect_rc 0 "submit"
spec="$work/w/.sss-farm/s.json"
cp "$spec" good.json
run "$farm" task "$spec" brick --frame 1
expect_rc 0 "task of the good spec"
run timeout 20 "$farm" task "$spec" brick --frame "$(printf '9%.0s' {1..5000})"
one_error 2 "5000-digit --frame"
SLURM_ARRAY_TASK_ID="$(printf '9%.0s' {1..5000})" run timeout 20 "$farm" task "$spec" brick
one_error 2 "5000-digit SLURM_ARRAY_TASK_ID"
run "$farm" task "$spec" filter --frame 1 --part 99999999
one_error 2 "--part 99999999"

# Hostile specs, generated: each replaces the spec, then task and status must
# fail with one line (exit 1) within seconds.
mkdir hostile
python3 - good.json hostile <<'EOF'
import copy, json, os, sys
good = json.load(open(sys.argv[1]))
out = sys.argv[2]
cases = {}
def spoil(name, f):
    s = copy.deepcopy(good)
    f(s)
    cases[name] = json.dumps(s).encode()
def put(key, value):
    return lambda s: s.__setitem__(key, value)
def stage(key, value):
    return lambda s: s["stages"][1].__setitem__(key, value)
def delete(key):
    return lambda s: s.pop(key)
for key in ("format", "name", "workdir", "bin_dir", "frames", "stages"):
    spoil("missing-" + key, delete(key))
for key, value in (("name", 5), ("name", "../../escape"), ("name", "a/b"), ("name", "x" * 5000),
                   ("name", ".."), ("name", "a\u0000b"), ("workdir", ["/"]), ("workdir", "relative"),
                   ("workdir", "/tmp/\u0000x"), ("bin_dir", None), ("frames", 12), ("frames", "1-" + "9" * 5000),
                   ("frames", "1-1000000000"), ("frames", "-5"), ("frames", "a-b"), ("split", [1, 2]),
                   ("split", {"points": "5", "parts": 2}), ("split", {"points": 5, "parts": 99999999}),
                   ("split", {"points": 5, "parts": True}), ("split", {"points": -1, "parts": 2}),
                   ("split", {"points": 10 ** 30, "parts": 2}), ("stages", {}), ("stages", []),
                   ("retries", -1), ("retries", "2"), ("retries", 10 ** 6), ("retries", None),
                   ("format", "sss-farm 1"), ("format", "sss-farm 3"),
                   ("submissions", [{"jobs": {}, "frames": "a-b"}]),
                   ("submissions", [{"jobs": {}, "frames": "1", "skipped": "1-" + "9" * 50}]),
                   ("stages", [None]), ("stages", [1] * 5), ("submissions", "x"), ("submissions", [None]),
                   ("submissions", [{"jobs": [1]}]), ("submissions", [{"jobs": {"a": 5}}])):
    spoil("bad-%s-%d" % (key, len(cases)), put(key, value))
for key, value in (("stage", "../../x"), ("stage", "brick/../../x"), ("stage", 7), ("stage", "filter"),
                   ("stage", "nope"), ("tool", "/bin/sh"), ("tool", "../../../bin/sh"), ("tool", "render"),
                   ("args", []), ("args", "out.ptc out.bkm"), ("args", [1, 2]), ("args", ["a\u0000b", "c"]),
                   ("args", ["x" * 100000]), ("args", [None]), ("cpus", "2"), ("cpus", 0), ("cpus", 10 ** 100),
                   ("mem", -1), ("mem", 1.5)):
    spoil("bad-stage-%s-%d" % (key, len(cases)), stage(key, value))
spoil("stage-not-object", lambda s: s["stages"].__setitem__(1, "brick"))
cases["not-json"] = b"{"
cases["empty"] = b""
cases["list"] = b"[]"
cases["string"] = b'"sss-farm 1"'
cases["deep"] = b"[" * 100000 + b"]" * 100000
cases["deep-object"] = b'{"a":' * 50000 + b"1" + b"}" * 50000
cases["non-utf8"] = json.dumps(good).encode().replace(b'"brick"', b'"br\xffick"', 1)
cases["nul-byte"] = json.dumps(good).encode().replace(b'"brick"', b'"br\x00ick"', 1)
cases["nan"] = json.dumps(good).encode().replace(b'"points": 5', b'"points": NaN', 1)
cases["infinity"] = json.dumps(good).encode().replace(b'"points": 5', b'"points": Infinity', 1)
cases["huge-int"] = json.dumps(good).encode().replace(b'"points": 5', b'"points": ' + b"9" * 5000, 1)
cases["huge-float"] = json.dumps(good).encode().replace(b'"points": 5', b'"points": 1e999', 1)
cases["big-file"] = b" " * (17 << 20)
for name, data in cases.items():
    with open(os.path.join(out, name + ".json"), "wb") as f:
        f.write(data)
print(len(cases))
EOF
count=0
for h in hostile/*.json; do
    count=$((count + 1))
    cp "$h" "$spec"
    for cmd in "task $spec brick --frame 1" "status $spec"; do
        # shellcheck disable=SC2086
        run timeout 20 "$farm" $cmd
        one_error 1 "$(basename "$h"): ${cmd%% *}"
    done
done
((count >= 60)) || fail "only $count hostile specs"
[[ ! -e "$work/escape" && ! -e "$work/x" ]] || fail "a hostile spec wrote outside the work folder"

# --- specs and status files out of place -----------------------------------------------
cp good.json "$spec"
mkfifo "$work/fifo.json"
run timeout 20 "$farm" status "$work/fifo.json"
one_error 1 "a FIFO spec"
run timeout 20 "$farm" task "$work/fifo.json" brick --frame 1
one_error 1 "a FIFO spec (task)"
cp good.json elsewhere.json
run "$farm" task "$work/elsewhere.json" brick --frame 1
one_error 1 "a spec outside its work folder"
ln -s "$work/elsewhere.json" w/.sss-farm/link.json
run "$farm" status "$work/w/.sss-farm/link.json"
one_error 1 "a spec linked from elsewhere"
mv w/.sss-farm/status w/status.real
mkdir outside
ln -s "$work/outside" w/.sss-farm/status
run "$farm" task "$spec" brick --frame 2
one_error 1 "a status folder linked out of the work folder"
[[ -z "$(ls outside)" ]] || fail "task wrote into a linked status folder: $(ls outside)"
rm w/.sss-farm/status
mv w/status.real w/.sss-farm/status
mkfifo w/.sss-farm/status/s.brick.2
run timeout 20 "$farm" status "$spec"
one_error 1 "a FIFO status file"

finish_checks sss-farm-hostile

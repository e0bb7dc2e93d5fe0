#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# sloinfo on shaders compiled by `shader`: the type and name, each
# parameter's storage class, type, array length, output flag and default in
# PRMan's layout and as JSON; a computed default; several files; what is
# refused (a file that is not a .slo, a missing file, a bad option). Needs
# SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

cat >params.sl <<'SL'
surface params(float Ks = 0.5; varying float height = 0; color tint = color(1, 0.5, 0.25);
               string map = "wood.tx"; float weights[3] = {1, 2, 3};
               point from = point "shader" (0, 0, 1);
               output varying color aov = 0;) {
    Ci = tint * Ks + aov;
}
SL
cat >spot.sl <<'SL'
light spot(float intensity = 1;) {
    illuminate(P) { Cl = intensity; }
}
SL
"$bin/shader" -q params.sl spot.sl
"$bin/sloinfo" params.slo >out.txt
expect() { grep -Fqx -- "$1" out.txt || { cat out.txt >&2; fail "no line '$1'"; }; }
expect 'surface "params"'
expect '    "Ks" "parameter uniform float"'
expect '		Default value: 0.5'
expect '    "height" "parameter varying float"'
expect '    "tint" "parameter uniform color"'
expect '		Default value: "rgb" [1 0.5 0.25]'
expect '    "map" "parameter uniform string"'
expect '		Default value: "wood.tx"'
expect '    "weights" "parameter uniform float[3]"'
expect '		Default value: {1, 2, 3}'
expect '    "from" "parameter uniform point"'
expect '		Default value: <computed when the shader runs>'
expect '    "aov" "output parameter varying color"'
[[ "$(grep -c 'Default value' out.txt)" == 7 ]] || fail "not one default per parameter"

# JSON, one object per file, read back by Python's parser.
"$bin/sloinfo" -json 1 params.slo spot.slo >out.json
[[ "$(wc -l <out.json)" == 2 ]] || fail "-json: not one line per file"
python3 - out.json <<'PY' || fail "-json: unexpected content"
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
p, s = lines
assert (p["type"], p["name"], p["file"]) == ("surface", "params", "params.slo"), p
by = {q["name"]: q for q in p["parameters"]}
assert list(by) == ["Ks", "height", "tint", "map", "weights", "from", "aov"], list(by)
assert by["Ks"] == {"name": "Ks", "storage": "uniform", "type": "float", "array": 0,
                    "output": False, "default": [0.5]}, by["Ks"]
assert by["weights"]["array"] == 3 and by["weights"]["default"] == [1, 2, 3]
assert by["map"]["default"] == ["wood.tx"]
assert by["from"]["default"] is None
assert by["aov"]["output"] is True and by["aov"]["storage"] == "varying"
assert (s["type"], s["name"]) == ("light", "spot") and s["parameters"][0]["default"] == [1]
PY

# Refused: not a .slo (exit 1, an ERROR line naming it), missing, bad option.
echo "not a shader" >bad.slo
rc=0
"$bin/sloinfo" bad.slo >/dev/null 2>err.txt || rc=$?
[[ "$rc" == 1 ]] || fail "a corrupt .slo: exit $rc, expected 1"
grep -q '^sloinfo ERROR: .*bad.slo' err.txt || fail "a corrupt .slo: $(cat err.txt)"
rc=0
"$bin/sloinfo" nosuch.slo >/dev/null 2>err.txt || rc=$?
[[ "$rc" == 1 ]] || fail "a missing .slo: exit $rc, expected 1"
rc=0
"$bin/sloinfo" -json 2 params.slo >/dev/null 2>err.txt || rc=$?
[[ "$rc" == 2 ]] || fail "-json 2: exit $rc, expected 2"
rc=0
"$bin/sloinfo" >/dev/null 2>err.txt || rc=$?
[[ "$rc" == 2 ]] || fail "no file: exit $rc, expected 2"
"$bin/sloinfo" --help | grep -q -- '-json 0|1' || fail "--help does not name -json"
echo "test_sloinfo: ok"

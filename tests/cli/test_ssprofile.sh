#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# ssprofile: the profiles against the Monte-Carlo walk (numbers that fail when
# a profile or the walk goes wrong), its outputs, the table writer, bad
# options. Needs SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
ssprofile="$bin/ssprofile"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

# status <out> <err> cmd...: runs cmd, prints its exit status.
status() {
    local out="$1" err="$2"
    shift 2
    local rc=0
    "$@" >"$out" 2>"$err" || rc=$?
    echo "$rc"
}

"$ssprofile" --help >"$tmp/help.txt"
grep -q -- '-maketable' "$tmp/help.txt" || fail "--help does not name -maketable"

# --- marble against the walk --------------------------------------------------
# The classic dipole misses the single-scattering peak (24 % L1w for marble);
# photon beam diffusion is within a few per cent; the walk's noise is printed.
"$ssprofile" -material marble -profile classic,pbd,mc -photons 60000 -threads 2 \
    -csv "$tmp/m.csv" -svg "$tmp/m.svg" -tsv "$tmp/m.tsv" >"$tmp/marble.txt"
[[ "$(grep -c '^channel ' "$tmp/marble.txt")" == 3 ]] || fail "three channels expected"
# tsv columns: channel alpha eta walk_rd walk_rd_error walk_single profile l1w ...
awk -F'\t' 'NR > 1 && $7 == "classic" && !($8 > 0.18 && $8 < 0.32) { bad = 1 }
            NR > 1 && $7 == "pbd" && !($8 < 0.10) { bad = 1 }
            NR > 1 && $7 == "mc" && !($8 < 0.08) { bad = 1 }
            NR > 1 && !($4 > 0.7 && $4 < 0.9) { bad = 1 }
            END { exit bad }' "$tmp/m.tsv" || { cat "$tmp/m.tsv" >&2; fail "marble L1w out of range"; }
[[ "$(wc -l <"$tmp/m.tsv")" == 10 ]] || fail "tsv: header and 9 rows expected"
head -c 4 "$tmp/m.svg" | grep -q '<svg' || fail "svg is not an SVG picture"
[[ "$(grep -c '<polyline' "$tmp/m.svg")" == 12 ]] || fail "svg: walk and 3 profiles x 3 channels"
head -1 "$tmp/m.csv" | grep -q '^channel,alpha,eta,r0,r1,walk_single' || fail "csv header"
[[ "$(wc -l <"$tmp/m.csv")" == 601 ]] || fail "csv: 200 annuli x 3 channels"

# The same seed gives the same walk whatever the thread count.
"$ssprofile" -material ketchup -profile classic -photons 20000 -threads 1 -tsv "$tmp/k1.tsv" >/dev/null
"$ssprofile" -material ketchup -profile classic -photons 20000 -threads 2 -tsv "$tmp/k2.tsv" >/dev/null
cmp -s "$tmp/k1.tsv" "$tmp/k2.tsv" || fail "the walk depends on the thread count"
"$ssprofile" -material ketchup -profile classic -photons 20000 -seed 9 -tsv "$tmp/k3.tsv" >/dev/null
! cmp -s "$tmp/k1.tsv" "$tmp/k3.tsv" || fail "another seed gave the same walk"

# --- the table writer -----------------------------------------------------------
"$ssprofile" -maketable "$tmp/t.tbl" -photons 3000 >"$tmp/t.txt"
grep -q '^eta 1 1.1 1.2 1.3 1.4 1.5 1.6$' "$tmp/t.tbl" || fail "table: eta nodes"
[[ "$(grep -c '^ratio ' "$tmp/t.tbl")" == 140 ]] || fail "table: 7 x 20 ratio rows"
if grep -Eqi 'nan|inf' "$tmp/t.tbl"; then fail "table: non-finite values"; fi

# --- in a scene's geometry ------------------------------------------------------
# A 2 mm skin1 ball lit from one side, with a bone inside: the walk's cloud has
# ptfilter's channel, the light that reaches the bone is absorbed, and
# ptfilter's point model loses light in so small an object (issue 32's case).
cat >"$tmp/ball.rib" <<'RIB'
ShadingRate 400
WorldBegin
LightSource "distantlight" 1 "intensity" [1] "from" [0 0 1] "to" [0 0 0]
Attribute "identifier" "name" ["ball"]
Surface "bake_radiance_t" "string filename" ["ball.ptc"]
Sphere 2 -2 2 360
AttributeBegin
Attribute "identifier" "name" ["bone"]
Surface "constant"
Sphere 0.8 -0.8 0.8 360
AttributeEnd
WorldEnd
RIB
(cd "$tmp" && "$bin/ptbake" ball.rib >/dev/null)
"$bin/ptfilter" -ssdiffusion -material skin1 "$tmp/ball.ptc" "$tmp/pf.ptc"
"$ssprofile" -scene "$tmp/ball.rib" -material skin1 -photons 20000 -blocker bone \
    "$tmp/ball.ptc" "$tmp/truth.ptc" -compare "$tmp/pf.ptc" >"$tmp/scene.txt"
"$bin/ptinfo" "$tmp/truth.ptc" >"$tmp/truth.txt"
grep -q 'color _ssdiffusion$' "$tmp/truth.txt" || fail "-scene: no _ssdiffusion"
grep -q 'color _ssdiffusion_error$' "$tmp/truth.txt" || fail "-scene: no _ssdiffusion_error"
grep -Eq '^ssprofile: r: flux in [0-9.]+; out 0\.[0-9]+ \+- 0\.[0-9]+, blocked 0\.[0-9]*[1-9]' \
    "$tmp/scene.txt" || { cat "$tmp/scene.txt" >&2; fail "-scene: no light blocked by the bone"; }
# (measured x0.38 of the walk's total at 200000 paths)
grep -Eq 'pf.ptc r: flux-weighted L1 [0-9.]+% \(walk noise [0-9.]+%\), total x0\.[0-6]' "$tmp/scene.txt" ||
    { cat "$tmp/scene.txt" >&2; fail "-scene: ptfilter should lose light in a 2 mm ball"; }
rc="$(status "$tmp/o" "$tmp/e" "$ssprofile" -scene "$tmp/ball.rib" -blocker nosuch -photons 1000 \
    "$tmp/ball.ptc" "$tmp/x.ptc")"
[[ "$rc" == 1 ]] || fail "unknown blocker: exit $rc, expected 1"
grep -q "no object named 'nosuch'" "$tmp/e" || fail "unknown blocker: message"
[[ ! -e "$tmp/x.ptc" ]] || fail "unknown blocker: an output was written"
rc="$(status "$tmp/o" "$tmp/e" "$ssprofile" -scene "$tmp/ball.rib" "$tmp/ball.ptc")"
[[ "$rc" == 2 ]] || fail "-scene with one cloud: exit $rc, expected 2"

# --- bad input --------------------------------------------------------------------
for args in "-profile nosuch" "-photons 0" "-photons -5" "-seed x" "-material nosuch" \
    "-maketable $tmp/x.tbl -svg $tmp/x.svg" "stray" "-blocker bone" "-albedo fromfile"; do
    # shellcheck disable=SC2086 # a list of words
    rc="$(status "$tmp/o" "$tmp/e" "$ssprofile" $args)"
    [[ "$rc" == 2 ]] || fail "'$args': exit $rc, expected 2"
    grep -q '^ssprofile ERROR: ' "$tmp/e" || fail "'$args': no ERROR line"
done
rc="$(status "$tmp/o" "$tmp/e" "$ssprofile" -ior 2.0 -profile mc -photons 1000)"
[[ "$rc" == 1 ]] || fail "ior 2 with mc: exit $rc, expected 1"
grep -q "outside the Monte-Carlo table's range" "$tmp/e" || fail "ior 2 with mc: message"
rc="$(status "$tmp/o" "$tmp/e" "$ssprofile" -scattering 0 1 1 -absorption 1 1 1 -photons 1000)"
[[ "$rc" == 1 ]] || fail "no scattering: exit $rc, expected 1"
rc="$(status "$tmp/o" "$tmp/e" "$ssprofile" -photons 1000 -csv "$tmp/no/such/dir.csv")"
[[ "$rc" == 1 ]] || fail "unwritable csv: exit $rc, expected 1"
echo "test_ssprofile: ok"

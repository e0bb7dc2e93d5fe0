#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# A Blobby's repelling ground plane (opcode 1003) through ptbake and render:
# a depth map of a wall at z = 5 (a zfile render), a blob whose surface
# reaches z = 5.15 on its own stays in front of the wall with the repeller
# added (its operands in PRMan's order or in RISpec's), renders cleanly, and
# a missing depth map is one ERROR line naming it. Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_blobby_ground.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"
ptinfo="$bin/ptinfo"
# zmax FILE: the largest z of a cloud's bounding box.
zmax() { "$ptinfo" "$1" 2>/dev/null | sed -n 's/^bbox: .* max [^ ]* [^ ]* \([^ ]*\)$/\1/p'; }
below() { python3 -c "import sys; sys.exit(0 if float('${1:-nan}') < $2 else 1)"; }

view() {
    printf 'Format 64 64 1\nProjection "orthographic"\nScreenWindow -2 2 -2 2\n'
}

# --- the depth map: a wall at z = 5 seen from the origin ----------------------
{
    view
    printf 'Display "wall.z" "zfile" "z"\nWorldBegin\n'
    printf '  Polygon "P" [-3 -3 5  3 -3 5  3 3 5  -3 3 5]\nWorldEnd\n'
} >wall.rib
render_clean wall.rib
[[ -s wall.z ]] || fail "no wall.z"

# blob NAME CODE FLOATS STRINGS: a baking scene of one Blobby.
blob() {
    {
        view
        printf 'WorldBegin\n  Attribute "cull" "hidden" 0 "backfacing" 0\n'
        printf '  Surface "bake_constant" "string filename" "%s.ptc"\n' "$1"
        printf '  Blobby %s %s %s %s\nWorldEnd\n' "$2" "$3" "$4" "$5"
    } >"$1.rib"
}
ball='1 0 0 0 0 1 0 0 0 0 1 0 0 0 4.7 1'
# A = 0.6 (the field ends 0.6 before the wall), B = 0.02, C = 0.2, D = 0.1.
shape='0.6 0.02 0.2 0.1'
blob alone 1 '[1001 0]' "[$ball]" '[]'
blob note 2 '[1001 0 1003 0 16 0 2 0 1]' "[$ball $shape]" '["wall.z"]'
blob rispec 2 '[1001 0 1003 16 0 0 2 0 1]' "[$ball $shape]" '["wall.z"]'
for name in alone note rispec; do
    run "$bin/ptbake" "$name.rib"
    [[ "$rc" == 0 ]] && no_warnings "$err" || fail "ptbake $name: exit $rc, stderr: $err"
done
# Alone, the blob (field radius 1, surface where (1 - r^2)^3 = 0.5: r = 0.454)
# reaches through the wall; repelled, it stops in front of it.
z_alone="$(zmax alone.ptc)" z_note="$(zmax note.ptc)" z_rispec="$(zmax rispec.ptc)"
below 5.1 "$z_alone" || fail "the blob alone reaches z = $z_alone, not past 5.1"
below "$z_note" 4.99 || fail "the repelled blob reaches z = $z_note, not in front of 5"
below "$z_note" 4.8 && fail "the repelled blob ends at z = $z_note: pushed back too far"
[[ "$z_note" == "$z_rispec" ]] || fail "the operand orders differ: $z_note and $z_rispec"

# --- render: the repelled blob is a clean, non-empty image --------------------
sed 's/^  Surface .*/  LightSource "ambientlight" 1\n  Surface "matte"/' note.rib >note_render.rib
render_clean -o note.exr note_render.rib
a="$(oiiotool note.exr --ch A --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p')"
below 0.01 "${a:-0}" || fail "note.exr is empty (alpha $a)"

# --- a depth map that does not exist ------------------------------------------
blob missing 2 '[1001 0 1003 0 16 0 2 0 1]' "[$ball $shape]" '["nosuch.z"]'
run "$bin/ptbake" missing.rib
expect_rc 1 "missing depth map" &&
    { [[ "$(grep -c ERROR <<<"$err")" == 1 && "$err" == *nosuch.z* ]] || fail "missing: $err"; }

finish_checks "blobby ground plane"

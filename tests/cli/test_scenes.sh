#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# End-to-end test of the bundled scenes: every scenes/*/run script in quick mode
# (SSS_QUICK=1) into a scratch folder, ptbake -> ptfilter -> brickmake -> render
# as a user types them. Checks that the images exist and are readable, and that
# their numbers make sense, each against a threshold:
#   teapot   sss brighter than no sss on the key light's shadowed side, about
#            equal where the key light falls; beauty = sum of the AOVs
#   thinbox  the blocker's ring darker the stronger the blocker; nothing of it
#            without sss
#   bone     the bone baked as a blocker cloud (-blocker) darkens the skin
#            above it; without the blocker the lit face is even
#   skin     the thin rim lit from behind is red (R > G, B) and much brighter
#            than the thick middle with sss, not without
#   varying  the colour varies with the per-point albedo (fromfile) with sss,
#            not in the plain matte
#   orbit    frames 1-2 as per-frame jobs with frame patterns; the orbiting
#            light moves; one frame run alone gives the same brick map
#   absorption  light gathered through the teapot: the thin spout and handle
#            glow far more than the thick body, reddest (least absorbed)
#   gibake   indirectdiffuse in the bake: the crystal much brighter than with
#            direct light only, and redder on the side facing the red wall
#   domelight  the envdome dome lights skin1 (red diffusion), envlight lights
#            the same ear about as brightly
#   appnote  the application note's workflow baked with render -p:2: the
#            clouds are ptbake's, the bake passes write no image; the three
#            material forms agree; the varying teapot's colour varies; the
#            blocker's ring is darker than the slab around it; the
#            absorption-only pass: thin parts glow, the body stays dark
#   skinstudy  seven AOVs of a user shader, each in a file of its own with the
#            declared channels and equal to its layer of the beauty's EXR; the
#            bumped diffuse (calculatenormal) as bright as a matte's; one
#            warning for vtransform("", ...)
#   calcite  the 8-bit and 16-bit TIFFs of the AOVs _occlusion and _sss hold
#            the EXR's values within their quantization; _occlusion comes from
#            occlusion(), not the 1.0 of a shader without it
# Usage: test_scenes.sh [PART...]: the scenes above (by name) and "guard" (an
# output folder inside scenes/ is refused); all of them without arguments.
# Needs SSS_BIN_DIR (the folder with ptbake, ptfilter, brickmake and render) and
# oiiotool. Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
for tool in ptbake ptfilter brickmake render; do
    [[ -x "$bin/$tool" ]] || { echo "FAIL: missing executable $bin/$tool" >&2; exit 1; }
done
command -v oiiotool >/dev/null 2>&1 ||
    { echo "FAIL: oiiotool not found (openimageio-tools, scripts/install-deps)" >&2; exit 1; }
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
scenes="$(cd "$here/../../scenes" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_scenes.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

ptinfo="$bin/ptinfo" # for points() (checks.sh) and cloud_stats
# shellcheck source=SCRIPTDIR/lib.sh
source "$here/lib.sh"
# shellcheck source=SCRIPTDIR/checks.sh
source "$here/checks.sh"

# size FILE: "WIDTH HEIGHT" ("" if oiiotool cannot read it).
size() {
    oiiotool --info "$1" 2>/dev/null | sed -n 's/^.*: *\([0-9][0-9]*\) x *\([0-9][0-9]*\), .*$/\1 \2/p'
}
# channels FILE: the channel list, comma separated.
channels() {
    oiiotool --info -v "$1" 2>/dev/null | sed -n 's/^ *channel list: //p' | tr -d ' '
}
# stat FILE CHANNELS WHAT X0 Y0 X1 Y1: oiiotool's statistic WHAT (Avg, Min, Max,
# StdDev) of each channel (one number per channel) over the box [X0, X1) x [Y0, Y1),
# given in fractions of the image size. A channel list "A/B" is the ratio A / B.
stat() {
    local file="$1" chans="$2" what="$3" w h
    read -r w h <<<"$(size "$file")"
    [[ -n "${h:-}" ]] || { echo "unreadable"; return; }
    local box
    box="$(awk -v w="$w" -v h="$h" -v x0="$4" -v y0="$5" -v x1="$6" -v y1="$7" 'BEGIN {
        a = int(x0 * w); b = int(y0 * h); c = int(x1 * w); d = int(y1 * h)
        if (c <= a) c = a + 1; if (d <= b) d = b + 1
        printf "%dx%d+%d+%d", c - a, d - b, a, b }')"
    local image=("$file" --ch "$chans")
    [[ "$chans" == */* ]] && image=("$file" --ch "${chans%/*}" "$file" --ch "${chans#*/}" --div)
    oiiotool "${image[@]}" --cut "$box" --printstats 2>/dev/null |
        sed -n "s/^ *Stats $what: *//p" | sed 's/ *(float)//' | head -n 1
}
mean() { stat "$1" "$2" Avg "${@:3}"; }
# is EXPRESSION VAR=VALUE...: an awk condition on numbers; false if a value is
# not a number (an unreadable image).
is() {
    local cond="$1" args=() kv
    shift
    for kv in "$@"; do
        [[ "${kv#*=}" =~ ^-?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?$ ]] || return 1
        args+=(-v "$kv")
    done
    awk "${args[@]}" "BEGIN { exit !($cond) }"
}
# format FILE: the pixel type oiiotool reports (uint8, uint16, half, float...).
format() {
    oiiotool --info "$1" 2>/dev/null | sed -n 's/^.* channel, \([a-z0-9]*\) .*$/\1/p'
}
# maxdiff A.. -- B..: the largest absolute difference, over the pixels and
# channels, between two oiiotool images given as argument lists (e.g.
# "x.tif" and "x.exr --ch _sss.R,_sss.G,_sss.B").
maxdiff() {
    local first=()
    while [[ "$1" != -- ]]; do first+=("$1"); shift; done
    shift
    oiiotool "${first[@]}" "$@" --sub --abs --printstats 2>/dev/null |
        sed -n 's/^ *Stats Max: *//p' | sed 's/ *(float)//' | tr ' ' '\n' |
        awk 'NF { if ($1 > m) m = $1; n++ } END { if (n) printf "%.6g\n", m }'
}
# cloud_stats FILE CHANNEL: ptinfo's min, mean and max of each component of a
# colour channel, "rmin rmean rmax gmin gmean gmax bmin bmean bmax".
cloud_stats() {
    "$ptinfo" "$1" 2>/dev/null | awk -v ch="$2" '
        $1 == "color" && $2 == ch { on = 1; next }
        on && $1 ~ /^[rgb]:$/ { printf "%s %s %s ", $3, $5, $7; if ($1 == "b:") exit; next }
        { on = 0 }'
}
# image_ok FILE W H LABEL: exists, readable, of that size.
image_ok() {
    if [[ ! -s "$1" ]]; then
        fail "$4: $1 missing"
        return 1
    fi
    local s
    s="$(size "$1")"
    [[ "$s" == "$2 $3" ]] || { fail "$4: $1 is '${s:-unreadable}', expected $2 x $3"; return 1; }
}
# exr_ok FILE W H LABEL: image_ok, with the beauty and every AOV layer.
exr_ok() {
    image_ok "$@" || return 1
    local c
    c="$(channels "$1")"
    local want
    for want in R G B A ambient.R diffuse.R specular.R sss.R sss.G sss.B occlusion.R; do
        [[ ",$c," == *",$want,"* ]] || fail "$4: $1 lacks channel $want (has $c)"
    done
}

export SSS_QUICK=1
start_marker="$work/start"
touch "$start_marker"
declare -A seconds

# run_scene NAME [ARGS...]: runs scenes/NAME/run into $work/NAME.
run_scene() {
    local name="$1" t0 t1
    shift
    t0="$(date +%s.%N)"
    run "$scenes/$name/run" "$work/$name" "$@"
    t1="$(date +%s.%N)"
    seconds[$name]="$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')"
    expect_rc 0 "scenes/$name/run" || return 1
    [[ "$out" == *"images in $work/$name"* || "$out" == *" in $work/$name"* ]] ||
        fail "$name: the run script does not say where its images are: ${out: -300}"
}

# ---------------------------------------------------------------------------
# Teapot: 160 x 120 in quick mode.
scene_teapot() {
    run_scene teapot || return 0
    d=teapot
    exr_ok $d/teapot.exr 160 120 teapot
    exr_ok $d/teapot_nosss.exr 160 120 teapot
    image_ok $d/teapot_compare.png 320 120 "teapot compare"
    [[ -s $d/teapot_clouds.png ]] || fail "teapot: no ptview picture of the clouds"
    [[ -s $d/teapot.ptc && -s $d/teapot_ssd.ptc && -s $d/teapot_ssd.bkm ]] ||
        fail "teapot: the intermediate files are missing: $(ls $d)"
    # The right of the body, just past the key light's terminator.
    s="$(mean $d/teapot.exr R 0.625 0.42 0.69 0.67)"
    n="$(mean $d/teapot_nosss.exr R 0.625 0.42 0.69 0.67)"
    is "s > 1.25 * n && n > 0" s="$s" n="$n" ||
        fail "teapot shadowed side: with sss $s should be well above without $n"
    # The left of the body, in the key light: the two agree (energy is kept).
    s="$(mean $d/teapot.exr R 0.25 0.42 0.375 0.67)"
    n="$(mean $d/teapot_nosss.exr R 0.25 0.42 0.375 0.67)"
    is "s > 0.8 * n && s < 1.25 * n && n > 0.3" s="$s" n="$n" ||
        fail "teapot lit side: with sss $s, without $n should be about equal"
    # The sky is empty and transparent; the table is opaque.
    a="$(stat $d/teapot.exr A Max 0 0 1 0.1)"
    is "a == 0" a="$a" || fail "teapot: alpha of the empty top rows is $a, not 0"
    a="$(stat $d/teapot.exr A Min 0 0.9 1 1)"
    is "a == 1" a="$a" || fail "teapot: alpha of the table is $a, not 1"
    # The beauty is the sum of the AOV layers; the no-sss image has no sss.
    sum="$(oiiotool $d/teapot.exr --ch ambient.R $d/teapot.exr --ch diffuse.R --add \
        $d/teapot.exr --ch specular.R --add $d/teapot.exr --ch sss.R --add \
        --printstats 2>/dev/null | sed -n 's/^ *Stats Avg: *\([^ ]*\).*/\1/p')"
    r="$(mean $d/teapot.exr R 0 0 1 1)"
    is "r > 0.1 && sum > 0.99 * r && sum < 1.01 * r" r="$r" sum="$sum" ||
        fail "teapot: beauty mean $r is not the sum of the AOVs $sum"
    z="$(stat $d/teapot_nosss.exr sss.R Max 0 0 1 1)"
    is "z == 0" z="$z" || fail "teapot: the no-sss image has sss.R up to $z"
    z="$(mean $d/teapot.exr sss.R 0.3 0.3 0.7 0.8)"
    is "z > 0.1" z="$z" || fail "teapot: the sss layer is dark ($z) over the teapot"
}

# ---------------------------------------------------------------------------
# Thin box: 128 x 128, three blocker strengths.
scene_thinbox() {
    run_scene thinbox || return 0
    d=thinbox
    for b in 0.25 0.5 1; do
        exr_ok $d/blocker_$b/thinbox.exr 128 128 "thinbox $b"
        grep -q "Color \[-$b -$b -$b\]" $d/blocker_$b/bake.rib || fail "thinbox: blocker_$b/bake.rib has no Color -$b"
    done
    exr_ok $d/thinbox_nosss.exr 128 128 "thinbox no sss"
    image_ok $d/thinbox_compare.png 512 128 "thinbox compare"
    # The ring's left arc (behind the blocker) and a patch to the left of it.
    ring() { mean "$1" R 0.31 0.44 0.37 0.56; }
    away() { mean "$1" R 0.16 0.44 0.22 0.56; }
    r25="$(ring $d/blocker_0.25/thinbox.exr)"
    r50="$(ring $d/blocker_0.5/thinbox.exr)"
    r100="$(ring $d/blocker_1/thinbox.exr)"
    is "r25 > r50 + 0.005 && r50 > r100 + 0.005" r25="$r25" r50="$r50" r100="$r100" ||
        fail "thinbox: the ring should darken with the blocker: -0.25 $r25, -0.5 $r50, -1 $r100"
    a25="$(away $d/blocker_0.25/thinbox.exr)"
    a100="$(away $d/blocker_1/thinbox.exr)"
    is "a25 > 0.05 && r25 < 0.95 * a25" a25="$a25" r25="$r25" ||
        fail "thinbox -0.25: ring $r25 should be darker than beside it $a25"
    is "a100 > 0.7 * a25 && a100 <= a25 * 1.01" a25="$a25" a100="$a100" ||
        fail "thinbox: away from the ring the strengths should roughly agree: $a25, $a100"
    n="$(away $d/thinbox_nosss.exr)"
    nr="$(ring $d/thinbox_nosss.exr)"
    # Without sss the underside has the ambient light only (0.03), and no ring.
    is "n < 0.04 && a25 > n + 0.04 && nr < 1.1 * n + 0.001 && nr > 0.9 * n - 0.001" a25="$a25" n="$n" nr="$nr" ||
        fail "thinbox: without sss the underside should be dark and even ($n, ring $nr; with sss $a25)"
}

# ---------------------------------------------------------------------------
# Bone: 128 x 128, the block with and without the bone as a blocker.
scene_bone() {
    run_scene bone || return 0
    d=bone
    exr_ok $d/bone.exr 128 128 "bone"
    exr_ok $d/bone_noblocker.exr 128 128 "bone without the blocker"
    exr_ok $d/bone_nosss.exr 128 128 "bone no sss"
    image_ok $d/bone_compare.png 384 128 "bone compare"
    # A strip of the lit face above the bone, and one nearer the back edge.
    above() { mean "$1" R 0.35 0.47 0.65 0.53; }
    beside() { mean "$1" R 0.35 0.30 0.65 0.36; }
    b="$(above $d/bone.exr)" bb="$(beside $d/bone.exr)"
    n="$(above $d/bone_noblocker.exr)" nb="$(beside $d/bone_noblocker.exr)"
    # (measured: 0.29 above against 0.43 beside; without the blocker 0.46 and 0.44)
    is "bb > 0.2 && b < 0.8 * bb" b="$b" bb="$bb" ||
        fail "bone: the skin above the bone ($b) should be darker than beside it ($bb)"
    is "n > 0.9 * nb && n < 1.15 * nb" n="$n" nb="$nb" ||
        fail "bone: without the blocker the lit face should be even ($n above, $nb beside)"
}

# ---------------------------------------------------------------------------
# Skin: 120 x 150.
scene_skin() {
    run_scene skin || return 0
    d=skin
    exr_ok $d/skin.exr 120 150 skin
    exr_ok $d/skin_nosss.exr 120 150 skin
    image_ok $d/skin_compare.png 240 150 "skin compare"
    # The thin rim on the right, lit from behind, and the thick middle.
    read -r tr tg tb <<<"$(mean $d/skin.exr R,G,B 0.59 0.3 0.66 0.7)"
    read -r mr _ _ <<<"$(mean $d/skin.exr R,G,B 0.33 0.4 0.5 0.6)"
    nt="$(mean $d/skin_nosss.exr R 0.59 0.3 0.66 0.7)"
    nm="$(mean $d/skin_nosss.exr R 0.33 0.4 0.5 0.6)"
    is "tr > 1.5 * tg && tr > 3 * tb" tr="$tr" tg="$tg" tb="$tb" ||
        fail "skin: the thin rim should be red with sss: R $tr G $tg B $tb"
    is "tr > 3 * nt" tr="$tr" nt="$nt" || fail "skin: the thin rim with sss ($tr) should be far brighter than without ($nt)"
    is "tr > 1.5 * mr && nt < 1.2 * nm" tr="$tr" mr="$mr" nt="$nt" nm="$nm" ||
        fail "skin: with sss the thin rim ($tr) should outshine the thick middle ($mr); without, not ($nt, $nm)"
    o="$(stat $d/skin.exr occlusion.R Min 0.3 0.3 0.6 0.7) $(stat $d/skin.exr occlusion.R Max 0.3 0.3 0.6 0.7)"
    is "lo >= 0 && hi <= 1 && hi > 0.5" lo="${o% *}" hi="${o#* }" || fail "skin: occlusion range $o"
}

# ---------------------------------------------------------------------------
# Varying albedo: 160 x 120.
scene_varying() {
    run_scene varying || return 0
    d=varying
    exr_ok $d/varying.exr 160 120 varying
    exr_ok $d/varying_nosss.exr 160 120 varying
    image_ok $d/varying_compare.png 320 120 "varying compare"
    # G / R over the lit front: it follows the per-point albedo with sss and
    # is the constant colour's ratio in the matte.
    vs="$(stat $d/varying.exr G/R StdDev 0.45 0.3 0.6 0.6)"
    vn="$(stat $d/varying_nosss.exr G/R StdDev 0.45 0.3 0.6 0.6)"
    is "vs > 0.03 && vn < 0.01" vs="$vs" vn="$vn" ||
        fail "varying: G/R should vary with sss (stddev $vs) and not in the matte ($vn)"
    read -r r g b <<<"$(mean $d/varying.exr R,G,B 0.45 0.3 0.6 0.6)"
    is "r > g && g > b && b > 0.02" r="$r" g="$g" b="$b" || fail "varying: not skin-like reds: $r $g $b"
}

# ---------------------------------------------------------------------------
# Orbit: frames 1-2, each a separate job with patterns in every file name.
scene_orbit() {
    run_scene orbit || return 0
    d=orbit
    for f in 0001 0002; do
        for file in orbit.$f.ptc orbit_ssd.$f.ptc orbit_ssd.$f.bkm; do
            [[ -s $d/$file ]] || fail "orbit: $file missing"
        done
        exr_ok $d/orbit.$f.exr 160 120 "orbit frame $f"
        exr_ok $d/orbit_nosss.$f.exr 160 120 "orbit frame $f"
    done
    image_ok $d/orbit_compare.png 320 240 "orbit compare"
    # shellcheck disable=SC2016 # a literal $F
    leftover="$(find $d -name '*0003*' -o -name '*0004*' -o -name '*#*' -o -name '*%*' -o -name '*$F*')"
    [[ -z "$leftover" ]] || fail "orbit: unexpected files $leftover"
    [[ "$out" == *"render -frame 2 "*"orbit.rib"* ]] || fail "orbit: no 'render -frame 2 ... orbit.rib' step"
    # The key light is front left in frame 1, front right in frame 2.
    l1="$(mean $d/orbit.0001.exr R 0.3 0.45 0.45 0.7)"
    r1="$(mean $d/orbit.0001.exr R 0.55 0.45 0.7 0.7)"
    l2="$(mean $d/orbit.0002.exr R 0.3 0.45 0.45 0.7)"
    r2="$(mean $d/orbit.0002.exr R 0.55 0.45 0.7 0.7)"
    is "l1 > 2 * r1 && r2 > 2 * l2" l1="$l1" r1="$r1" l2="$l2" r2="$r2" ||
        fail "orbit: the light should move from left (frame 1: $l1 | $r1) to right (frame 2: $l2 | $r2)"
    # A farm task: frame 2 alone, in a fresh folder, gives the same brick map.
    run "$scenes/orbit/run" "$work/orbit_farm" 2 2
    if expect_rc 0 "orbit frame 2 alone"; then
        cmp -s $d/orbit_ssd.0002.bkm orbit_farm/orbit_ssd.0002.bkm ||
            fail "orbit: frame 2 alone gives a different brick map"
        [[ ! -e orbit_farm/orbit.0001.ptc ]] || fail "orbit: frame 2 alone also made frame 1"
        image_ok orbit_farm/orbit_compare_2-2.png 160 240 "orbit frame 2 alone, its sheet"
    fi
}

# thin_parts_glow IMAGE LAYER LABEL: the absorption-only teapot (160 x 120,
# the light through it in LAYER): the thin spout and handle glow far more than
# the thick body, and red, the least absorbed, gets through best.
thin_parts_glow() {
    local img="$1" l="$2" label="$3" sr sg sb hr br
    read -r sr sg sb <<<"$(mean "$img" "$l.R,$l.G,$l.B" 0.72 0.38 0.81 0.5)"
    read -r hr _ _ <<<"$(mean "$img" "$l.R,$l.G,$l.B" 0.16 0.42 0.31 0.58)"
    read -r br _ _ <<<"$(mean "$img" "$l.R,$l.G,$l.B" 0.47 0.54 0.59 0.66)"
    is "sr > 3 * br && hr > 1.5 * br && br > 0" sr="$sr" hr="$hr" br="$br" ||
        fail "$label: spout ($sr) and handle ($hr) should glow far more than the body ($br)"
    is "sr > sg && sg > sb" sr="$sr" sg="$sg" sb="$sb" ||
        fail "$label: red should get through best: $sr $sg $sb"
}

# ---------------------------------------------------------------------------
# Absorption-only teapot: 160 x 120; the light gathered through it is "sss".
scene_absorption() {
    run_scene absorption || return 0
    d=absorption
    exr_ok $d/absorption.exr 160 120 absorption
    thin_parts_glow $d/absorption.exr sss absorption
}

# ---------------------------------------------------------------------------
# GI bake: 100 x 100, with and without indirectdiffuse.
scene_gibake() {
    run_scene gibake || return 0
    d=gibake
    exr_ok $d/gibake.exr 100 100 gibake
    exr_ok $d/gibake_direct.exr 100 100 gibake
    image_ok $d/gibake_compare.png 200 100 "gibake compare"
    read -r gr gg _ <<<"$(mean $d/gibake.exr R,G,B 0.4 0.45 0.48 0.55)"
    read -r dr dg _ <<<"$(mean $d/gibake_direct.exr R,G,B 0.4 0.45 0.48 0.55)"
    is "gr > 1.5 * dr && gg > 1.5 * dg" gr="$gr" gg="$gg" dr="$dr" dg="$dg" ||
        fail "gibake: bounced light should brighten the crystal: GI $gr $gg, direct $dr $dg"
    is "gr / gg > 1.05 * dr / dg" gr="$gr" gg="$gg" dr="$dr" dg="$dg" ||
        fail "gibake: the side facing the red wall should turn red with GI: $gr/$gg vs $dr/$dg"
}

# ---------------------------------------------------------------------------
# Dome light: 120 x 150, the dome with sss and envlight without.
scene_domelight() {
    run_scene domelight || return 0
    d=domelight
    exr_ok $d/domelight.exr 120 150 domelight
    exr_ok $d/domelight_envlight.exr 120 150 domelight
    image_ok $d/domelight_compare.png 240 150 "domelight compare"
    [[ -s $d/sky.exr && -s $d/dome.rib ]] || fail "domelight: no probe or dome: $(ls $d)"
    n="$(grep -c '^ *LightSource "distantlight_rts"' $d/dome.rib || true)"
    [[ "$n" == 64 ]] || fail "domelight: dome.rib has $n shadowed lights, not 64"
    read -r sr sg sb <<<"$(mean $d/domelight.exr sss.R,sss.G,sss.B 0.33 0.3 0.66 0.7)"
    is "sr > 0.05 && sr > sg && sg > sb" sr="$sr" sg="$sg" sb="$sb" ||
        fail "domelight: skin1 diffusion under the dome should be red: $sr $sg $sb"
    read -r ar _ _ <<<"$(mean $d/domelight.exr R,G,B 0.33 0.3 0.66 0.7)"
    read -r er _ _ <<<"$(mean $d/domelight_envlight.exr R,G,B 0.33 0.3 0.66 0.7)"
    is "er > ar / 3 && er < 3 * ar" er="$er" ar="$ar" ||
        fail "domelight: envlight ($er) and the dome ($ar) should light the ear alike"
}

# ---------------------------------------------------------------------------
# The application note's workflow: bakes by render -p:2, 160 x 120 renders
# (the slab 128 x 128).
scene_appnote() {
    run_scene appnote || return 0
    d=appnote
    # The bake passes: render -p:2 writes the clouds ptbake writes from the
    # same RIBs (the quick run's copies), and no image (Display "null").
    local rib cloud n1 n2 m1 m2 file
    for rib in teapot:direct_rad_t varying:varying_rad_t blocker:blocker_rad_t; do
        cloud=${rib#*:}
        rib=${rib%:*}_bake.rib
        run bash -c "cd $d && '$bin/ptbake' -p:2 -o '$work/ptbake_$cloud.ptc' $rib"
        expect_rc 0 "appnote: ptbake $rib" || continue
        n1="$(points "$d/$cloud.ptc")"
        n2="$(points "ptbake_$cloud.ptc")"
        is "n1 == n2 && n1 > 10000" n1="$n1" n2="$n2" ||
            fail "appnote: render -p:2 $rib baked $n1 points, ptbake $n2"
        read -r _ m1 _ <<<"$(cloud_stats "$d/$cloud.ptc" _radiance_t)"
        read -r _ m2 _ <<<"$(cloud_stats "ptbake_$cloud.ptc" _radiance_t)"
        is "m1 == m2 && m1 != 0" m1="$m1" m2="$m2" ||
            fail "appnote: $rib: mean _radiance_t $m1 from render, $m2 from ptbake"
        for file in "$d/$cloud"*; do
            [[ "$file" == "$d/$cloud.ptc" || "$file" == "$d/$cloud.bkm" ]] ||
                fail "appnote: the null display of $rib wrote $file"
        done
    done
    # The three forms of marble: -scattering/-absorption are the table's own
    # numbers (the same cloud, byte for byte); -albedo/-diffusemeanfreepath
    # are rounded to 3 digits (min, mean and max within 0.5 %).
    cmp -s $d/ssdiffusion.ptc $d/ssdiffusion_coeffs.ptc ||
        fail "appnote: -scattering/-absorption of marble gives another cloud than -material marble"
    local marble rounded
    read -r -a marble <<<"$(cloud_stats $d/ssdiffusion.ptc _ssdiffusion)"
    read -r -a rounded <<<"$(cloud_stats $d/ssdiffusion_albedo.ptc _ssdiffusion)"
    if ((${#marble[@]} != 9 || ${#rounded[@]} != 9)); then
        fail "appnote: no _ssdiffusion statistics: '${marble[*]}' '${rounded[*]}'"
    else
        for i in 0 1 2 3 4 5 6 7 8; do
            is "x > 0 && y > 0.995 * x && y < 1.005 * x" x="${marble[$i]}" y="${rounded[$i]}" ||
                fail "appnote: -albedo/-diffusemeanfreepath differs from -material marble: ${rounded[*]} vs ${marble[*]}"
        done
    fi
    # Marble teapot: the beauty and the shader's AOVs, by their own names.
    image_ok $d/teapot_render.exr 160 120 "appnote teapot"
    c="$(channels $d/teapot_render.exr)"
    for want in R G B A _ambient.R _diffuse.R _sss.R _ssdiffusion.B; do
        [[ ",$c," == *",$want,"* ]] || fail "appnote: teapot_render.exr lacks $want (has $c)"
    done
    [[ ",$c," != *",specular.R,"* && ",$c," != *",occlusion.R,"* ]] ||
        fail "appnote: teapot_render.exr has layers nobody asked for: $c"
    image_ok $d/teapot_sss.tif 160 120 "appnote teapot sss"
    [[ "$(format $d/teapot_sss.tif)" == uint8 ]] || fail "appnote: teapot_sss.tif is $(format $d/teapot_sss.tif), not 8-bit"
    sum="$(oiiotool $d/teapot_render.exr --ch _ambient.R $d/teapot_render.exr --ch _diffuse.R --add \
        $d/teapot_render.exr --ch _sss.R --add --printstats 2>/dev/null | sed -n 's/^ *Stats Avg: *\([^ ]*\).*/\1/p')"
    r="$(mean $d/teapot_render.exr R 0 0 1 1)"
    is "r > 0.1 && sum > 0.99 * r && sum < 1.01 * r" r="$r" sum="$sum" ||
        fail "appnote: teapot beauty mean $r is not the sum of _ambient, _diffuse, _sss ($sum)"
    z="$(mean $d/teapot_render.exr _sss.R 0.3 0.3 0.7 0.8)"
    is "z > 0.1" z="$z" || fail "appnote: the _sss layer is dark ($z) over the teapot"
    # Varying teapot: G / R over the body follows the per-point albedo; the
    # marble teapot's hardly varies.
    image_ok $d/varying_render.exr 160 120 "appnote varying"
    vs="$(stat $d/varying_render.exr G/R StdDev 0.4 0.45 0.6 0.7)"
    vm="$(stat $d/teapot_render.exr G/R StdDev 0.4 0.45 0.6 0.7)"
    is "vs > 0.025 && vs > 2 * vm" vs="$vs" vm="$vm" ||
        fail "appnote: the varying teapot's G/R should vary (stddev $vs) more than marble's ($vm)"
    # Blocker: lit from below, seen from above. The ring's left arc, the slab
    # outside it and inside it.
    image_ok $d/blocker_render.exr 128 128 "appnote blocker"
    ring="$(mean $d/blocker_render.exr _sss.R 0.31 0.5 0.36 0.6)"
    outside="$(mean $d/blocker_render.exr _sss.R 0.16 0.5 0.22 0.6)"
    inside="$(mean $d/blocker_render.exr _sss.R 0.47 0.5 0.53 0.56)"
    is "outside > 0.3 && ring < 0.9 * outside && ring < 0.95 * inside" ring="$ring" outside="$outside" inside="$inside" ||
        fail "appnote: the blocker's ring ($ring) should be darker than the slab outside ($outside) and inside it ($inside)"
    # Absorption only (the note's one-sided teapot): spout and handle glow,
    # the thick body stays dark, red gets through best, and the rays into the
    # body find where they leave it.
    image_ok $d/noscatter.exr 160 120 "appnote noscatter"
    thin_parts_glow $d/noscatter.exr _sss "appnote noscatter"
    m="$(mean $d/noscatter.exr _missed 0.47 0.54 0.59 0.66)"
    is "m < 0.05" m="$m" || fail "appnote noscatter: $m of the rays into the body find no exit"
}

# ---------------------------------------------------------------------------
# Skin study: 120 x 150; seven AOVs of skin_pass.sl.
scene_skinstudy() {
    run_scene skinstudy || return 0
    d=skinstudy
    log="$out$err"
    image_ok $d/skin_render.exr 120 150 skinstudy || return 0
    [[ -s $d/textures/skin_bump.tif && -s $d/ear_rad_t.ptc && -s $d/ear_ssd.bkm ]] ||
        fail "skinstudy: the bump map or the intermediate files are missing: $(ls $d)"
    for file in "$d"/skin_bake*; do
        [[ "$file" == "$d/skin_bake.rib" ]] || fail "skinstudy: the null display of skin_bake.rib wrote $file"
    done
    # Each AOV: its own file, with the channels its declaration gives (a
    # colour R, G, B; a float one channel), equal to its layer of the beauty.
    c="$(channels $d/skin_render.exr)"
    local aov file want layer diff
    for aov in ambient:color diffuse:color specular:color sss:color albedo:color occlusion:float bump:float; do
        file=$d/skin_${aov%:*}.exr
        image_ok "$file" 120 150 "skinstudy ${aov%:*}" || continue
        if [[ ${aov#*:} == color ]]; then
            want="R,G,B" layer="_${aov%:*}.R,_${aov%:*}.G,_${aov%:*}.B"
        else
            want="_${aov%:*}" layer="_${aov%:*}"
        fi
        [[ "$(channels "$file")" == "$want" ]] || fail "skinstudy: $file has channels $(channels "$file"), not $want"
        [[ ",$c," == *",${layer%%,*},"* ]] || fail "skinstudy: skin_render.exr lacks ${layer%%,*} (has $c)"
        diff="$(maxdiff "$file" -- $d/skin_render.exr --ch "$layer")"
        is "diff == 0" diff="$diff" || fail "skinstudy: $file differs from its layer of skin_render.exr by $diff"
    done
    # The bump map was read and moves the specular highlights.
    bs="$(stat $d/skin_render.exr _bump StdDev 0.35 0.3 0.55 0.65)"
    is "bs > 0.03" bs="$bs" || fail "skinstudy: the _bump AOV hardly varies ($bs): was the map found?"
    # The bumped normal (calculatenormal of the moved P) faces out: the
    # diffuse is as bright as a matte's with the same Kd (facing in, it would
    # be black: the lights are outside).
    awk '/^ *Display "\+/ { next }
         /^ *Display "skin_render.exr"/ { print "Display \"skin_matte.exr\" \"openexr\" \"rgba,_diffuse\""; next }
         /Surface "skin_pass"/ { print "    Surface \"matte\" \"Ka\" [1] \"Kd\" [0.1]"; skip = 1; next }
         skip && /^ *"/ { next }
         { skip = 0; print }' $d/skin_render.rib >$d/skin_matte.rib
    run bash -c "cd $d && '$bin/render' -p:2 -res 120 150 -samples 1 skin_matte.rib"
    if expect_rc 0 "skinstudy: the matte copy"; then
        db="$(mean $d/skin_render.exr _diffuse.R 0.35 0.3 0.55 0.65)"
        dm="$(mean $d/skin_matte.exr _diffuse.R 0.35 0.3 0.55 0.65)"
        is "dm > 0.01 && db > 0.85 * dm && db < 1.15 * dm" db="$db" dm="$dm" ||
            fail "skinstudy: the bumped diffuse ($db) should be about the matte's ($dm)"
    fi
    read -r sr sg sb <<<"$(mean $d/skin_render.exr _sss.R,_sss.G,_sss.B 0.35 0.3 0.55 0.65)"
    is "sr > 0.1 && sr > sg && sg > sb" sr="$sr" sg="$sg" sb="$sb" ||
        fail "skinstudy: the skin1 diffusion should be bright and red: $sr $sg $sb"
    # dispSPACE "": one warning for its vtransform call.
    n="$(grep -c 'unknown coordinate system ""' <<<"$log" || true)"
    [[ "$n" == 1 ]] || fail "skinstudy: $n warnings about the space \"\", not 1: ${log: -600}"
}

# ---------------------------------------------------------------------------
# Calcite: 120 x 150; _occlusion and _sss as 8-bit and 16-bit TIFFs.
scene_calcite() {
    run_scene calcite || return 0
    d=calcite
    image_ok $d/calcite.exr 120 150 calcite || return 0
    c="$(channels $d/calcite.exr)"
    [[ "$c" == "R,G,B,A,_occlusion.R,_occlusion.G,_occlusion.B,_sss.R,_sss.G,_sss.B" ]] ||
        fail "calcite: calcite.exr has channels $c"
    [[ -s $d/calcite_rad_t.ptc && -s $d/calcite_ssd.bkm ]] || fail "calcite: the intermediate files are missing: $(ls $d)"
    for file in "$d"/calcite_bake*; do
        [[ ! -e "$file" ]] || fail "calcite: the null display of crystal_bake.rib wrote $file"
    done
    image_ok $d/calcite_occlusion.tif 120 150 "calcite occlusion"
    image_ok $d/calcite_sss.tif 120 150 "calcite sss"
    f8="$(format $d/calcite_occlusion.tif)" f16="$(format $d/calcite_sss.tif)"
    [[ "$f8" == uint8 && "$f16" == uint16 ]] ||
        fail "calcite: the TIFFs are $f8 and $f16, not uint8 and uint16"
    [[ "$(channels $d/calcite_occlusion.tif)" == R,G,B ]] ||
        fail "calcite: calcite_occlusion.tif has channels $(channels $d/calcite_occlusion.tif)"
    # Quantization: 8 bits within one step (rounding and a dither of half a
    # step) plus the EXR's half floats; 16 bits within the half floats'
    # rounding, far below an 8-bit step.
    e8="$(maxdiff $d/calcite_occlusion.tif -- $d/calcite.exr --ch _occlusion.R,_occlusion.G,_occlusion.B)"
    is "e8 < 1.02 / 255 + 0.0005" e8="$e8" ||
        fail "calcite: calcite_occlusion.tif differs from the EXR's _occlusion by $e8 (more than an 8-bit step)"
    e16="$(maxdiff $d/calcite_sss.tif -- $d/calcite.exr --ch _sss.R,_sss.G,_sss.B --clamp:min=0:max=1)"
    is "e16 < 0.0005" e16="$e16" ||
        fail "calcite: calcite_sss.tif differs from the EXR's _sss (clamped to 1) by $e16"
    # _occlusion on the big crystal comes from occlusion(): open (about 1) at
    # the top, darker down by the rock; not the 1 of a shader without it.
    otop="$(mean $d/calcite.exr _occlusion.R 0.3 0.36 0.4 0.42)"
    olow="$(mean $d/calcite.exr _occlusion.R 0.35 0.62 0.48 0.68)"
    omin="$(stat $d/calcite.exr _occlusion.R Min 0.32 0.42 0.43 0.64)"
    omax="$(stat $d/calcite.exr _occlusion.R Max 0 0 1 1)"
    is "otop > 0.9 && olow < 0.8 && omin > 0.3 && omin < 0.75 && omax <= 1" otop="$otop" olow="$olow" omin="$omin" omax="$omax" ||
        fail "calcite: _occlusion of the big crystal: top $otop, by the rock $olow, min $omin (inside it), max $omax"
    # The diffusion lights the crystals.
    s="$(mean $d/calcite.exr _sss.R 0.32 0.4 0.48 0.65)"
    is "s > 0.1" s="$s" || fail "calcite: the crystals' _sss is dark ($s)"
}

# ---------------------------------------------------------------------------
# An output folder inside scenes/ is refused, and nothing is created there.
scene_guard() {
    run "$scenes/teapot/run" "$scenes/teapot/out"
    if expect_rc 1 "output folder inside scenes/"; then
        [[ "$err" == *"ERROR"*"inside scenes/"* ]] || fail "an output folder inside scenes/: $err"
    fi
    [[ ! -e "$scenes/teapot/out" ]] || { fail "scenes/teapot/out was created"; rm -rf "$scenes/teapot/out"; }
}

# The parts to run: the arguments (CTest runs one per test, cli.test_scenes.<part>,
# tests/CMakeLists.txt), or all of them.
all_parts=(teapot thinbox bone skin varying orbit absorption gibake domelight appnote skinstudy calcite guard)
parts=("$@")
((${#parts[@]})) || parts=("${all_parts[@]}")
for part in "${parts[@]}"; do
    if ! declare -F "scene_$part" >/dev/null; then
        echo "usage: test_scenes.sh [PART...]; parts: ${all_parts[*]}" >&2
        exit 2
    fi
    "scene_$part"
done
# The run scripts wrote nothing into scenes/.
new="$(find "$scenes" -newer "$start_marker" -print | head -n 5)"
[[ -z "$new" ]] || fail "the run scripts wrote into scenes/: $new"

times=""
for part in "${!seconds[@]}"; do
    times+=" $part ${seconds[$part]}"
done
echo "quick-mode run times (s):${times:- none}"
finish_checks "scenes (${parts[*]})"

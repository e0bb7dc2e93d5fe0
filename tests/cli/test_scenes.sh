#!/usr/bin/env bash
# End-to-end test of the bundled scenes: every scenes/*/run script in quick mode
# (SSS_QUICK=1) into a scratch folder, ptbake -> ptfilter -> brickmake -> render
# as a user types them. Checks that the images exist and are readable, and that
# their numbers make sense, each against a threshold:
#   teapot   sss brighter than no sss on the key light's shadowed side, about
#            equal where the key light falls; beauty = sum of the AOVs
#   thinbox  the blocker's ring darker the stronger the blocker; nothing of it
#            without sss
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

# ---------------------------------------------------------------------------
# Absorption-only teapot: 160 x 120; the light gathered through it is "sss".
scene_absorption() {
    run_scene absorption || return 0
    d=absorption
    exr_ok $d/absorption.exr 160 120 absorption
    read -r sr sg sb <<<"$(mean $d/absorption.exr sss.R,sss.G,sss.B 0.72 0.38 0.81 0.5)"
    read -r hr _ _ <<<"$(mean $d/absorption.exr sss.R,sss.G,sss.B 0.16 0.42 0.31 0.58)"
    read -r br _ _ <<<"$(mean $d/absorption.exr sss.R,sss.G,sss.B 0.47 0.54 0.59 0.66)"
    is "sr > 3 * br && hr > 1.5 * br && br > 0" sr="$sr" hr="$hr" br="$br" ||
        fail "absorption: spout ($sr) and handle ($hr) should glow far more than the body ($br)"
    is "sr > sg && sg > sb" sr="$sr" sg="$sg" sb="$sb" ||
        fail "absorption: red should get through best: $sr $sg $sb"
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
all_parts=(teapot thinbox skin varying orbit absorption gibake domelight guard)
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

#!/usr/bin/env bash
# The RIB that users' scenes bring: gzip-compressed scenes and archives, a
# scene on standard input, and the RISpec requests render and ptbake carry
# out (each renders a non-empty image with exit 0 and no warning), or refuse
# by default when still not implemented (-lenient: a warning). Needs
# SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_rib_requests.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"

failures=0
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

# The mean of an image's alpha: the share of the frame something covers.
coverage() {
    oiiotool "$1" --ch A --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p'
}
# Fails unless the image's alpha coverage lies in [lo, hi].
expect_coverage() {
    local c
    c="$(coverage "$1")"
    python3 -c "import sys; c = float('$c' or 'nan'); sys.exit(0 if $2 <= c <= $3 else 1)" ||
        fail "$1: coverage $c not in [$2, $3]"
}
# Runs render on a scene; fails unless it exits 0 with nothing on stderr.
render_clean() {
    run "$bin/render" "$@"
    [[ "$rc" == 0 && -z "$err" ]] || fail "render $*: exit $rc, stderr: $err"
}

header() {
    cat <<'RIB'
Format 64 48 1
PixelSamples 2 2
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0] "intensity" 1
  Surface "matte"
RIB
}

# --- gzip and standard input --------------------------------------------------
{
    header
    echo '  ReadArchive "ball.rib.gz"'
    echo 'WorldEnd'
} >scene.rib
echo 'Sphere 1 -1 1 360' | gzip >ball.rib.gz
gzip -c scene.rib >scene.rib.gz
render_clean -o plain.exr scene.rib
expect_coverage plain.exr 0.15 0.18
render_clean -o gz.exr scene.rib.gz
render_clean -o stdin.exr - <scene.rib
render_clean -o stdin_gz.exr - <scene.rib.gz
for f in gz stdin stdin_gz; do
    oiiotool plain.exr "$f.exr" --fail 0 --diff >/dev/null 2>&1 || fail "$f.exr differs from plain.exr"
done
# Without -o, a scene from standard input renders to render.exr.
render_clean - <scene.rib
[[ -f render.exr ]] || fail "render - wrote no render.exr"
# A truncated gzip stream is an error naming standard input.
head -c 40 scene.rib.gz >cut.rib.gz
run "$bin/render" -o cut.exr - <cut.rib.gz
[[ "$rc" == 1 && "$err" == *"render ERROR: <stdin>"*"truncated"* ]] ||
    fail "truncated gzip on stdin: exit $rc, stderr: $err"
[[ ! -e cut.exr ]] || fail "a failed render left cut.exr"
# ptbake reads standard input too, and -newer never skips it.
cat >bake.rib <<'RIB'
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0] "intensity" 1
  Surface "bake_radiance_t" "string filename" ["ball.ptc"]
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$bin/ptbake" -spacing 0.1 -newer 1 - <bake.rib
[[ "$rc" == 0 && -s ball.ptc ]] || fail "ptbake - : exit $rc, stderr: $err"
touch -d '2 hours ago' bake.rib
run "$bin/ptbake" -spacing 0.1 -newer 1 - <bake.rib
[[ "$rc" == 0 && "$out" != *"nothing to do"* ]] || fail "ptbake -newer 1 - skipped: $out"

((failures == 0)) || { echo "$failures check(s) failed" >&2; exit 1; }
echo "rib requests: all checks passed"

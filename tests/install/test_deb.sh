#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# The Debian packages as a farm node gets them (docs/install.md): cpack makes
# sss, libsss<major.minor>, sss-dev and (with the Python module) python3-sss
# from the build tree; lintian reports no error on any of them; their
# dependencies must be Debian packages this machine has; they are
# unpacked into a temporary root (dpkg -x: the machine's own /usr is not
# touched) and the bundled teapot scene runs its whole pipeline (ptbake ->
# ptfilter -> brickmake -> ptview -> render) with the installed tools, shaders
# and scene only; the unpacked Python module reads the filtered cloud.
#
#   test_deb.sh BUILD_DIR
set -euo pipefail

build="$(cd "${1:?usage: test_deb.sh BUILD_DIR}" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() {
    echo "FAIL: $*" >&2
    exit 1
}

(cd "$build" && cpack -B "$tmp/packages" >"$tmp/cpack.log" 2>&1) ||
    { cat "$tmp/cpack.log" >&2; fail "cpack"; }
version="$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$build/CMakeCache.txt")"
deb="$tmp/packages/sss_${version}_amd64.deb"
dev="$tmp/packages/sss-dev_${version}_amd64.deb"
[[ -f "$deb" && -f "$dev" ]] || { ls "$tmp/packages" >&2; fail "cpack made no sss/sss-dev $version"; }
libname="libsss${version%.*}"
lib="$tmp/packages/${libname}_${version}_amd64.deb"
[[ -f "$lib" ]] || { ls "$tmp/packages" >&2; fail "cpack made no $libname"; }
grep -q "/libsss\\.so\\.${version%.*} -> " <<<"$(dpkg-deb -c "$lib")" ||
    fail "$libname lacks libsss.so.${version%.*}"
grep -q "^ _ZN3sss11ssdiffusion.*@SSS_${version%.*} $version\$" <<<"$(dpkg-deb -I "$lib" symbols)" ||
    fail "$libname's symbols file lacks sss::ssdiffusion"
grep -q "^libsss ${version%.*} $libname" <<<"$(dpkg-deb -I "$lib" shlibs)" ||
    fail "$libname has no shlibs entry: $(dpkg-deb -I "$lib" shlibs)"
[[ "$(dpkg-deb -f "$dev" Depends)" == *"$libname (= $version)"* ]] || fail "sss-dev must depend on $libname"

# lintian: no error on any package (warnings are reported, not fatal).
if command -v lintian >/dev/null; then
    for p in "$tmp/packages/"*.deb; do
        lintian --tag-display-limit 0 "$p" >"$tmp/lintian.txt" 2>&1 || true
        if grep -q '^E: ' "$tmp/lintian.txt"; then
            cat "$tmp/lintian.txt" >&2
            fail "lintian reports errors on $(basename "$p")"
        fi
        grep '^W: ' "$tmp/lintian.txt" >&2 || true
    done
else
    fail "lintian is not installed (scripts/install-deps installs it)"
fi
py=""
if grep -q '^SSS_BUILD_PYTHON:BOOL=ON$' "$build/CMakeCache.txt"; then
    py="$tmp/packages/python3-sss_${version}_amd64.deb"
    [[ -f "$py" ]] || { ls "$tmp/packages" >&2; fail "cpack made no python3-sss $version"; }
fi

# Dependencies: the libraries the tools load (found by dpkg-shlibdeps), each
# a package this machine has installed at a version that satisfies it.
depends="$(dpkg-deb -f "$deb" Depends)"
for needed in libembree3-3 libopenimageio2.4 libtbb12 libstdc++6 python3; do # not $lib: unpacked below
    [[ ",$depends," == *" $needed"[\ ,]* || ",$depends," == *",$needed"[\ ,]* ]] ||
        fail "sss's Depends lacks $needed: $depends"
done
check_depends() { # check_depends "a (>= 1), b, ..."
    local item name op ver have
    IFS=',' read -ra items <<<"$1"
    for item in "${items[@]}"; do
        item="${item# }"
        name="${item%% *}"
        have="$(dpkg-query -W -f='${Version}' "$name" 2>/dev/null)" ||
            fail "dependency $name is not installed here"
        if [[ "$item" == *"("* ]]; then
            op="$(sed 's/.*(\([<>=]*\) .*/\1/' <<<"$item")"
            ver="$(sed 's/.*([<>=]* \(.*\))/\1/' <<<"$item")"
            dpkg --compare-versions "$have" "$op" "$ver" || fail "$name $have does not satisfy $item"
        fi
    done
}
check_depends "$depends"
check_depends "$(dpkg-deb -f "$dev" Depends | sed "s/$libname (= $version), //")"
if [[ -n "$py" ]]; then
    pydeps="$(dpkg-deb -f "$py" Depends)"
    [[ "$pydeps" == *"sss (= $version)"* && "$pydeps" == *python3-numpy* ]] ||
        fail "python3-sss's Depends: $pydeps"
    check_depends "$(sed "s/sss (= $version), //" <<<"$pydeps")"
fi
dpkg-deb -c "$deb" >"$tmp/deb.txt"
dpkg-deb -c "$dev" >"$tmp/dev.txt"
grep -q '\./usr/share/man/man1/ptfilter\.1\.gz' "$tmp/deb.txt" || fail "no man page in $deb"
grep -q '\./usr/share/sss/shaders/bake_radiance_t\.slo' "$tmp/deb.txt" || fail "no shaders in $deb"
grep -q '\./usr/.*/cmake/sss/sssConfig\.cmake' "$tmp/dev.txt" || fail "no CMake package in $dev"

root="$tmp/root"
dpkg -x "$deb" "$root"
dpkg -x "$dev" "$root"
dpkg -x "$lib" "$root"
[[ -z "$py" ]] || dpkg -x "$py" "$root"

# sss-farm from the unpacked package finds its modules (usr/share/sss/farm).
[[ "$("$root/usr/bin/sss-farm" --version)" == "sss-farm (sss) "* ]] ||
    fail "the unpacked sss-farm: $("$root/usr/bin/sss-farm" --version 2>&1)"

# The teapot pipeline (quick version) from the installed tree alone: the
# installed scene finds the installed tools by itself, and writes under the
# current folder.
unset SSS_SHADER_DIR SSS_PLUGIN_DIR SSS_BIN_DIR BUILD_DIR
mkdir "$tmp/work"
(cd "$tmp/work" && PATH="/usr/bin:/bin" SSS_QUICK=1 "$root/usr/share/sss/scenes/teapot/run") \
    >"$tmp/run.log" 2>&1 || { cat "$tmp/run.log" >&2; fail "the teapot pipeline with the installed tools"; }
mv "$tmp/work/out/scenes/teapot" "$tmp/out"
grep -q "^+ ptbake " "$tmp/run.log" || fail "the scene printed no commands"
for f in teapot.ptc teapot_ssd.ptc teapot_ssd.bkm teapot_clouds.png teapot.exr; do
    [[ -s "$tmp/out/$f" ]] || fail "the pipeline wrote no $f"
done
# The picture is lit and has subsurface scattering in it (its sss AOV).
mean="$(oiiotool --stats "$tmp/out/teapot.exr" 2>/dev/null | sed -n 's/^ *Stats Avg: //p' | head -1)"
awk -v m="${mean%% *}" 'BEGIN { exit !(m > 0.01) }' || fail "teapot.exr is dark (mean '$mean')"
# Debian's python3 with the unpacked module (and no build tree on its path).
if [[ -n "$py" ]]; then
    points="$("$root/usr/bin/ptinfo" "$tmp/out/teapot_ssd.ptc" | sed -n 's/^points: *//p')"
    got="$(cd "$tmp" && PYTHONPATH="$root/usr/lib/python3/dist-packages" /usr/bin/python3 -c "
import sss, sys
assert sss.__file__.startswith('$root/'), sss.__file__
c = sss.read_cloud('$tmp/out/teapot_ssd.ptc')
print(len(c['_ssdiffusion']))")" || fail "the unpacked Python module"
    [[ "$got" == "$points" ]] || fail "the Python module read $got points, ptinfo says $points"
fi
echo "deb: sss, sss-dev${py:+ and python3-sss} $version packaged; dependencies installed here; teapot pipeline ran from the unpacked packages"

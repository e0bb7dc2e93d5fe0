#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# `cmake --install` of the build tree, moved after installing (the tree is
# relocatable), used as a studio would (docs/install.md):
#   - the installed tools run with nothing of the build tree: ptbake finds the
#     standard shaders beside itself, ptfilter filters, man pages are there;
#   - sss-farm finds its package (share/sss/farm), also through a link, and
#     writes no __pycache__;
#   - the library is in the multiarch folder; libsss.so has a soname and
#     exports only the public API, under a symbol version; the command line's
#     headers are not installed; the .slo files do not name the build folder;
#   - a C++ program outside the tree (tests/install/consumer) links the
#     installed shared library through find_package(sss), and the diffusion's
#     archives through find_package(sss COMPONENTS diffusion), each without
#     Embree, OpenImageIO or OpenEXR being looked up, and filters a cloud,
#     byte for byte as the installed ptfilter does;
#   - the same program built with pkg-config's flags (sss, sss-static) does
#     the same.
#
#   test_install.sh BUILD_DIR
set -euo pipefail

build="$(cd "${1:?usage: test_install.sh BUILD_DIR}" && pwd)"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() {
    echo "FAIL: $*" >&2
    exit 1
}

cmake --install "$build" --prefix "$tmp/first" >"$tmp/install.log" ||
    { cat "$tmp/install.log" >&2; fail "cmake --install"; }
mv "$tmp/first" "$tmp/moved" # relocated: nothing may point at the first place
prefix="$tmp/moved"
libdir="$(cd "$prefix" && dirname "$(find . -name sss.pc -path '*/pkgconfig/*' | head -1)")"
libdir="${libdir%/pkgconfig}"
[[ "$libdir" == ./lib/*-linux-gnu ]] || fail "libraries in $libdir, not the multiarch folder"
[[ -f "$prefix/$libdir/libsss_util.a" ]] || fail "no libsss_util.a in $prefix/$libdir"
[[ -d "$prefix/include/sss/diffusion" ]] || fail "no headers in $prefix/include/sss"
[[ ! -e "$prefix/include/sss/cli" ]] || fail "the command line's headers are not public API"
soname="$(readelf -d "$prefix/$libdir/libsss.so" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')"
[[ "$soname" == libsss.so.* && -f "$prefix/$libdir/$soname" ]] || fail "libsss.so: soname '$soname'"
# Only the public API is exported, under one version.
exported="$(nm -D --defined-only -C "$prefix/$libdir/libsss.so")"
grep -q ' sss::ssdiffusion(' <<<"$exported" || fail "libsss.so does not export sss::ssdiffusion"
versions="$(nm -D --defined-only "$prefix/$libdir/libsss.so")"
grep -q '@@SSS_' <<<"$versions" || fail "libsss.so's symbols have no version"
if grep -E ' [TW] std::' <<<"$exported" >/dev/null; then fail "libsss.so exports std:: instances"; fi
if grep -lq "$build" "$prefix/share/sss/shaders/"*.slo; then
    fail "installed .slo files name the build folder"
fi
grep -q '^source "bake_radiance_t.sl"' "$prefix/share/sss/shaders/bake_radiance_t.slo" ||
    fail "bake_radiance_t.slo does not name its source by its own name"

# The tools, with an environment that names nothing of the build tree.
export -n SSS_SHADER_DIR SSS_PLUGIN_DIR 2>/dev/null || true
unset SSS_SHADER_DIR SSS_PLUGIN_DIR
bin="$prefix/bin"
for tool in ptbake ptfilter brickmake brickinfo render ptinfo ptsynth ptview shader sloinfo envdome ssprofile sss-farm; do
    [[ -x "$bin/$tool" ]] || fail "$tool not installed"
    "$bin/$tool" --version >/dev/null || fail "$tool --version"
    page="$prefix/share/man/man1/$tool.1.gz"
    text="$(gzip -dc "$page")" || fail "no gzipped man page $page"
    grep -q '^\.TH' <<<"$text" || fail "man page $page has no .TH"
    grep -q '^\.SH EXAMPLES' <<<"$text" || fail "man page $page lacks EXAMPLES"
done
# sss-farm's package (share/sss/farm/sss_farm) is found from the moved tree
# and through a link from elsewhere, leaves no __pycache__, and its absence is
# one error line.
farm_pkg="$prefix/share/sss/farm/sss_farm"
[[ -f "$farm_pkg/cli.py" ]] || fail "sss-farm's package is not in $farm_pkg"
ln -s "$bin/sss-farm" "$tmp/linked-sss-farm"
# (Without PYTHONDONTWRITEBYTECODE, which a developer's shell may set: sss-farm must not need it.)
[[ "$(env -u PYTHONDONTWRITEBYTECODE "$tmp/linked-sss-farm" --version)" == "sss-farm (sss) "* ]] ||
    fail "sss-farm through a link"
env -u PYTHONDONTWRITEBYTECODE "$bin/sss-farm" submit --help >/dev/null || fail "sss-farm submit --help"
[[ -z "$(find "$prefix/share/sss/farm" -name __pycache__ -o -name '*.pyc')" ]] ||
    fail "sss-farm wrote byte-compiled caches: $(find "$prefix/share/sss/farm" -name '*.pyc')"
mv "$farm_pkg" "$tmp/farm_pkg"
if "$bin/sss-farm" --version >/dev/null 2>"$tmp/farm.err"; then fail "sss-farm ran without its package"; fi
grep -qF "sss-farm ERROR: its Python package sss_farm is not in $(realpath "$prefix")/share/sss/farm " \
    "$tmp/farm.err" ||
    fail "sss-farm without its package: $(cat "$tmp/farm.err")"
mv "$tmp/farm_pkg" "$farm_pkg"
cd "$tmp"
printf 'WorldBegin\nSurface "bake_radiance_t" "string filename" ["sphere.ptc"]\nSphere 1 -1 1 360\nWorldEnd\n' >bake.rib
"$bin/ptbake" bake.rib >/dev/null 2>ptbake.err || { cat ptbake.err >&2; fail "installed ptbake"; }
[[ "$("$bin/ptinfo" sphere.ptc | sed -n 's/^points: *//p')" -gt 100 ]] || fail "ptbake baked nothing"

# The standard shaders are found beside the tools, not in the build tree.
"$bin/ptsynth" -n 20000 -light 1 1 1 cloud.ptc >/dev/null
"$bin/ptfilter" -ssdiffusion -material skin1 -unitlength 0.1 cloud.ptc tool.ptc

# find_package(sss) from a project outside the tree.
# The shared library: needs only glm and oneTBB to be found, not Embree,
# OpenImageIO or OpenEXR (whose configs print Debian's Imath warning).
no_heavy=(--no-warn-unused-cli -DCMAKE_DISABLE_FIND_PACKAGE_embree=ON -DCMAKE_DISABLE_FIND_PACKAGE_OpenImageIO=ON
    -DCMAKE_DISABLE_FIND_PACKAGE_OpenEXR=ON)
cmake -S "$here/consumer" -B consumer -DCMAKE_PREFIX_PATH="$prefix" "${no_heavy[@]}" \
    -DCMAKE_BUILD_TYPE=Release >consumer.log 2>&1 || { cat consumer.log >&2; fail "configuring the consumer"; }
if grep -qi "imath\|warning" consumer.log; then cat consumer.log >&2; fail "find_package(sss) warned"; fi
cmake --build consumer >>consumer.log 2>&1 || { cat consumer.log >&2; fail "building the consumer"; }
readelf -d consumer/filter | grep -q "NEEDED.*\[$soname\]" || fail "the consumer does not use $soname"
consumer/filter cloud.ptc cmake.ptc skin1 0.1
cmp tool.ptc cmake.ptc || fail "find_package(sss) program: output differs from ptfilter's"
# One module's archives, as a component: the same packages stay unneeded.
cmake -S "$here/consumer" -B static -DCMAKE_PREFIX_PATH="$prefix" "${no_heavy[@]}" \
    -DSSS_STATIC_COMPONENTS=ON -DCMAKE_BUILD_TYPE=Release >static.log 2>&1 ||
    { cat static.log >&2; fail "configuring the consumer of COMPONENTS diffusion"; }
cmake --build static >>static.log 2>&1 || { cat static.log >&2; fail "building it"; }
if readelf -d static/filter | grep -q "NEEDED.*libsss"; then fail "COMPONENTS diffusion linked libsss.so"; fi
static/filter cloud.ptc static.ptc skin1 0.1
cmp tool.ptc static.ptc || fail "COMPONENTS diffusion program: output differs from ptfilter's"

# pkg-config: sss (the shared library) and sss-static (the archives).
pc="$prefix/$libdir/pkgconfig"
flags="$(PKG_CONFIG_PATH="$pc" pkg-config --cflags --libs sss)" || fail "pkg-config sss"
# shellcheck disable=SC2086
g++ -O2 "$here/consumer/filter.cpp" -o filter_pc $flags -Wl,-rpath,"$prefix/$libdir" ||
    fail "building with pkg-config's flags"
./filter_pc cloud.ptc pc.ptc skin1 0.1
cmp tool.ptc pc.ptc || fail "pkg-config program: output differs from ptfilter's"
flags="$(PKG_CONFIG_PATH="$pc" pkg-config --cflags --libs sss-static)" || fail "pkg-config sss-static"
# shellcheck disable=SC2086
g++ -O2 "$here/consumer/filter.cpp" -o filter_static $flags || fail "building with sss-static's flags"
./filter_static cloud.ptc static_pc.ptc skin1 0.1
cmp tool.ptc static_pc.ptc || fail "sss-static program: output differs from ptfilter's"
./filter_pc missing.ptc x.ptc skin1 0.1 2>err.txt && fail "a missing input must fail"
grep -q "filter ERROR: .*missing.ptc" err.txt || fail "no library error: $(cat err.txt)"
echo "install: relocated tree, tools, shaders, man pages, libsss.so, find_package(sss) with components, and pkg-config (sss, sss-static) all work"

#!/usr/bin/env bash
# `cmake --install` of the build tree, moved after installing (the tree is
# relocatable), used as a studio would (docs/install.md):
#   - the installed tools run with nothing of the build tree: ptbake finds the
#     standard shaders beside itself, ptfilter filters, man pages are there;
#   - a C++ program outside the tree (tests/install/consumer) links the
#     installed library through find_package(sss) and filters a cloud, byte
#     for byte as the installed ptfilter does;
#   - the same program built with pkg-config's flags does the same.
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
[[ -f "$prefix/$libdir/libsss_util.a" ]] || fail "no libsss_util.a in $prefix/$libdir"
[[ -d "$prefix/include/sss/diffusion" ]] || fail "no headers in $prefix/include/sss"

# The tools, with an environment that names nothing of the build tree.
export -n SSS_SHADER_DIR SSS_PLUGIN_DIR 2>/dev/null || true
unset SSS_SHADER_DIR SSS_PLUGIN_DIR
bin="$prefix/bin"
for tool in ptbake ptfilter brickmake brickinfo render ptinfo ptsynth ptview shader sloinfo envdome ssprofile sss-farm; do
    [[ -x "$bin/$tool" ]] || fail "$tool not installed"
    "$bin/$tool" --version >/dev/null || fail "$tool --version"
    page="$prefix/share/man/man1/$tool.1"
    grep -q '^\.TH' "$page" || fail "no man page $page"
    grep -qF -- '\fB\-' "$page" || fail "man page $page lacks the options"
done
cd "$tmp"
printf 'WorldBegin\nSurface "bake_radiance_t" "string filename" ["sphere.ptc"]\nSphere 1 -1 1 360\nWorldEnd\n' >bake.rib
"$bin/ptbake" bake.rib >/dev/null 2>ptbake.err || { cat ptbake.err >&2; fail "installed ptbake"; }
[[ "$("$bin/ptinfo" sphere.ptc | sed -n 's/^points: *//p')" -gt 100 ]] || fail "ptbake baked nothing"

# The standard shaders are found beside the tools, not in the build tree.
"$bin/ptsynth" -n 20000 -light 1 1 1 cloud.ptc >/dev/null
"$bin/ptfilter" -ssdiffusion -material skin1 -unitlength 0.1 cloud.ptc tool.ptc

# find_package(sss) from a project outside the tree.
cmake -S "$here/consumer" -B consumer -DCMAKE_PREFIX_PATH="$prefix" \
    -DCMAKE_BUILD_TYPE=Release >consumer.log 2>&1 || { cat consumer.log >&2; fail "configuring the consumer"; }
cmake --build consumer >>consumer.log 2>&1 || { cat consumer.log >&2; fail "building the consumer"; }
consumer/filter cloud.ptc cmake.ptc skin1 0.1
cmp tool.ptc cmake.ptc || fail "find_package(sss) program: output differs from ptfilter's"

# pkg-config.
flags="$(PKG_CONFIG_PATH="$prefix/$libdir/pkgconfig" pkg-config --cflags --libs sss)" ||
    fail "pkg-config sss"
# shellcheck disable=SC2086
g++ -O2 "$here/consumer/filter.cpp" -o filter_pc $flags || fail "building with pkg-config's flags"
./filter_pc cloud.ptc pc.ptc skin1 0.1
cmp tool.ptc pc.ptc || fail "pkg-config program: output differs from ptfilter's"
./filter_pc missing.ptc x.ptc skin1 0.1 2>err.txt && fail "a missing input must fail"
grep -q "filter ERROR: .*missing.ptc" err.txt || fail "no library error: $(cat err.txt)"
echo "install: relocated tree, tools, shaders, man pages, find_package(sss) and pkg-config all work"

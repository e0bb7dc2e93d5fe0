# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash disable=SC2034
# Shared by the scenes' run scripts (sourced, after `set -euo pipefail`).
#
#   scene_setup NAME [OUTPUT_DIR]
#
# sets `here` (the scene's folder), `root` (the repository), `out` (the output
# folder: OUTPUT_DIR, or out/scenes/NAME; created; never inside scenes/) and
# `quick` (1 when SSS_QUICK=1), puts the tools' folder first in PATH (SSS_BIN_DIR,
# default build/bin, or $BUILD_DIR/bin; in an install, the install's bin
# folder, else the tools on PATH) so that the commands in the run scripts
# read exactly as a user types them, and changes to `out`.
# See docs/scenes.md.

die() {
    echo "${scene_name:-scene} ERROR: $*" >&2
    exit 1
}

scene_setup() {
    scene_name="$1"
    here="$(cd "$(dirname "${BASH_SOURCE[1]}")" && pwd)"
    root="$(cd "$here/../.." && pwd)"
    local build="${BUILD_DIR:-build}"
    [[ "$build" == /* ]] || build="$root/$build"
    local bin="${SSS_BIN_DIR:-}" installed=0
    if [[ -z "$bin" ]]; then
        # A source tree's build, else an install's bin folder (the scenes are
        # in <prefix>/share/sss/scenes), else the tools on PATH.
        if [[ -d "$build/bin" ]]; then
            bin="$build/bin"
        elif [[ -x "$root/../../bin/ptfilter" ]]; then
            bin="$root/../../bin"
            installed=1
        elif command -v ptfilter >/dev/null 2>&1; then
            bin="$(dirname "$(command -v ptfilter)")"
            installed=1
        else
            die "no tools: build first (scripts/build), or set SSS_BIN_DIR"
        fi
    fi
    [[ -d "$bin" ]] || die "no tools folder $bin (build first: scripts/build, or set SSS_BIN_DIR)"
    bin="$(cd "$bin" && pwd)"
    local tool
    for tool in ptbake ptfilter brickmake render ptview; do
        [[ -x "$bin/$tool" ]] || die "missing $bin/$tool (build first: scripts/build)"
    done
    command -v oiiotool >/dev/null 2>&1 ||
        die "oiiotool not found (Debian: openimageio-tools; scripts/install-deps installs it)"
    export PATH="$bin:$PATH"

    # Installed, the scenes' folder is not writable: the outputs go to the
    # current folder's out/scenes/NAME.
    local default_out="$root/out/scenes/$scene_name"
    [[ "$installed" == 0 && -w "$root" ]] || default_out="$PWD/out/scenes/$scene_name"
    out="$(realpath -m -- "${2:-$default_out}")"
    case "$out/" in
    "$root/scenes/"*) die "the output folder $out is inside scenes/; give another one" ;;
    esac
    mkdir -p "$out"

    quick=0 # used by the run scripts
    [[ "${SSS_QUICK:-0}" == 0 ]] || quick=1
    cd "$out" || exit 1
}

# step COMMAND...: prints the command (words that need it quoted), then runs it.
step() {
    local word line="+"
    for word in "$@"; do
        if [[ "$word" =~ ^[A-Za-z0-9_./%#=:,+-]+$ ]]; then line+=" $word"; else line+=" '$word'"; fi
    done
    echo "$line"
    "$@"
}

# compare OUT.png COLSxROWS IMAGE.exr...: the images' beauty (R, G, B) in a
# grid, row by row, as an 8-bit sRGB PNG.
compare() {
    local png="$1" layout="$2"
    shift 2
    local args=() image
    for image in "$@"; do
        # shellcheck disable=SC2054 # R,G,B is one argument
        args+=("$image" --ch R,G,B)
    done
    step oiiotool "${args[@]}" --mosaic "$layout" --colorconvert linear sRGB -d uint8 -o "$png"
}

# no_sss IN.rib OUT.rib 'Surface ...': IN.rib with the line that calls the
# subsurface shader ("read_ssdiffusion" or "skin") replaced by the given one,
# indented the same. Prints the sed command it runs.
no_sss() {
    local replacement="${3//\\/\\\\}"
    replacement="${replacement//&/\\&}"
    replacement="${replacement//#/\\#}"
    local expr="s#^( *)Surface \"(read_ssdiffusion|skin)\".*#\\1$replacement#"
    echo "+ sed -E '$expr' $1 > $2"
    sed -E "$expr" "$1" >"$2"
    grep -qF -- "$3" "$2" || die "$1 has no read_ssdiffusion or skin Surface line to replace"
}

#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Scene-scale invariance: the same small scene at scales s = 1e-6 ... 1e6
# (geometry, camera and lights all scaled by s; ptfilter's -unitlength, scene
# units per mm, times s) runs through the whole chain ptbake -> ptfilter
# -ssdiffusion -> brickmake -> render and must give what s = 1 gives:
#   - every tool succeeds, quietly, and every output is finite;
#   - the baked clouds (ShadingRate dicing, -spacing L*s, -spacing mfp) and the
#     _ssdiffusion cloud have the same points, with positions s x those of
#     s = 1 (float precision), radii s x, areas s^2 x, the same normals, and
#     the same irradiance and _ssdiffusion values;
#   - the images (beauty and AOVs, float EXR) are the same pixel for pixel.
# The scene: a sphere (curved receiver), a thin torus partly in the sphere's
# shadow, and a plate receiving both shadows, all marble; an ambient light, a
# shadowed distant light and a shadowed point light whose intensity is scaled
# by s^2 (irradiance falls off as 1/d^2); ambient occlusion with its maxdist
# scaled by s (a length in world units).
# Needs SSS_BIN_DIR (ptbake, ptfilter, brickmake, render), oiiotool and
# python3. SSS_SCALES overrides the list (the first is the reference);
# SSS_KEEP=1 keeps the scratch folder. Every check runs; failures are listed
# and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
for tool in ptbake ptfilter brickmake render; do
    [[ -x "$bin/$tool" ]] || { echo "FAIL: missing executable $bin/$tool" >&2; exit 1; }
done
command -v oiiotool >/dev/null 2>&1 ||
    { echo "FAIL: oiiotool not found (openimageio-tools, scripts/install-deps)" >&2; exit 1; }
command -v python3 >/dev/null 2>&1 || { echo "FAIL: python3 not found" >&2; exit 1; }
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_scale.XXXXXX")"
if [[ -n "${SSS_KEEP:-}" ]]; then echo "scratch folder: $work"; else trap 'rm -rf "$work"' EXIT; fi
cd "$work"

# shellcheck source=SCRIPTDIR/lib.sh
source "$here/lib.sh"
# shellcheck source=SCRIPTDIR/checks.sh
source "$here/checks.sh"

# Memory guard (each scale needs < 100 MB); CTest's TIMEOUT guards the time.
# (No ulimit -v under the sanitizers: ASan's shadow memory needs terabytes of
# address space.)
[[ -n "${SSS_SANITIZED:-}" ]] || ulimit -v 4000000 2>/dev/null || true

# shellcheck disable=SC2206
scales=(${SSS_SCALES:-1 1e-6 1e-4 1e-2 1e2 1e4 1e6}) # the first is the reference
unitlength=0.1                                      # at s = 1 the scene is in cm

# scene S MODE: the scene at scale S; MODE bake or render.
scene() {
    awk -v s="$1" -v mode="$2" 'BEGIN {
        f = "%.9g"
        print "##RenderMan RIB"
        print "Format 96 72 1"
        print "PixelSamples 2 2"
        print "Projection \"perspective\" \"fov\" 40"
        print "ShadingRate 2"
        if (mode == "bake") {
            print "DisplayChannel \"color _radiance_t\""
            print "DisplayChannel \"float _area\""
        } else {
            print "Display \"img.exr\" \"openexr\" \"rgba\" \"string type\" [\"float\"]"
        }
        printf "Translate 0 0 " f "\n", 6 * s
        print "Rotate -25 1 0 0"
        print "WorldBegin"
        printf "  Scale " f " " f " " f "\n", s, s, s
        print "  LightSource \"ambientlight\" 1 \"intensity\" [0.05]"
        print "  LightSource \"distantlight\" 2 \"from\" [-2 3 -1] \"to\" [0 0 0] \"intensity\" [0.8]"
        print "      \"string shadowname\" [\"raytrace\"]"
        printf "  LightSource \"pointlight\" 3 \"from\" [1.5 2.5 2] \"intensity\" [" f "]\n", 6 * s * s
        print "      \"string shadowname\" [\"raytrace\"]"
        if (mode == "bake")
            surf = "Surface \"bake_radiance_t\" \"string filename\" [\"bake.ptc\"]" \
                   " \"string displaychannels\" [\"_area,_radiance_t\"]"
        else
            surf = sprintf("Surface \"read_ssdiffusion\" \"string filename\" [\"ssd.bkm\"]" \
                           " \"float Ka\" [1] \"float Kd\" [0.1]" \
                           " \"float occlusion_samples\" [4] \"float occlusion_maxdist\" [" f "]", 1.5 * s)
        print "  AttributeBegin"
        print "    " surf
        print "    Sphere 1 -1 1 360"
        print "  AttributeEnd"
        print "  AttributeBegin"
        print "    " surf
        print "    Translate 1.6 -0.55 0.2"
        print "    Rotate 70 1 0 0"
        print "    Torus 0.4 0.1 0 360 360"
        print "  AttributeEnd"
        print "  AttributeBegin"
        print "    " surf
        print "    Polygon \"P\" [-3 -1 -2.5  -3 -1 2.5  3 -1 2.5  3 -1 -2.5]"
        print "  AttributeEnd"
        print "WorldEnd"
    }'
}

# quiet LABEL: the last run succeeded and printed nothing (no warning at any scale).
quiet() {
    expect_rc 0 "$1" || return 1
    [[ -z "$out$err" ]] || fail "$1 printed: $out $err"
    return 0
}

# The chain, for every scale, in folder s_<scale>.
for s in "${scales[@]}"; do
    mkdir -p "s_$s"
    cd "s_$s"
    scene "$s" bake >bake.rib
    scene "$s" render >render.rib
    u="$(awk -v s="$s" -v u="$unitlength" 'BEGIN { printf "%.9g", u * s }')"
    spacing="$(awk -v s="$s" 'BEGIN { printf "%.9g", 0.07 * s }')"
    run "$bin/ptbake" -o bake.ply bake.rib
    quiet "s=$s: ptbake" || { cd ..; continue; }
    run "$bin/ptbake" -spacing "$spacing" -o spacing.ply bake.rib
    quiet "s=$s: ptbake -spacing $spacing" || true
    # A material whose mean free path (1/1.01 mm) gives about as many points as
    # the ShadingRate.
    run "$bin/ptbake" -spacing mfp -scattering 1 1 1 -absorption 0.01 0.01 0.01 \
        -unitlength "$u" -o mfp.ply bake.rib
    quiet "s=$s: ptbake -spacing mfp -unitlength $u" || true
    run "$bin/ptfilter" -ssdiffusion -material marble -unitlength "$u" bake.ply ssd.ply
    quiet "s=$s: ptfilter -unitlength $u" || { cd ..; continue; }
    run "$bin/brickmake" ssd.ply ssd.bkm
    quiet "s=$s: brickmake" || { cd ..; continue; }
    run "$bin/render" render.rib
    quiet "s=$s: render" || { cd ..; continue; }
    oiiotool --dumpdata img.exr >img.txt 2>&1 || fail "s=$s: oiiotool cannot read img.exr"
    cd ..
done

# compare.py REF_DIR DIR S: compares the clouds and the image of DIR (scale
# S) with those of REF_DIR (s = 1); prints the measured differences and exits
# 1 with the reasons when a tolerance is exceeded.
cat >compare.py <<'PYTHON'
import math, struct, sys

ref_dir, dir_, s = sys.argv[1], sys.argv[2], float(sys.argv[3])
problems = []

# Geometry: positions s x those of s = 1 within float rounding (1e-6 of the
# scene size; measured <= 5e-8), radii s x and areas s^2 x within 1e-5
# relative (measured <= 1e-7), the same normals (measured identical).
POS_TOL, SIZE_TOL, NORMAL_TOL = 1e-6, 1e-5, 1e-5

# Values, relative to the channel's mean |value| at s = 1. The chain does the
# same computation at every scale up to rounding, except where a decision
# sits on its boundary: a camera ray at a silhouette, or a shadow ray at an
# occluder's edge, can flip between hit and miss under a rounding change (the
# same happens between two s = 1 scenes a rounding apart), and then its pixel
# or point changes by up to a light's share; ptfilter's choice of how a source
# node enters a receiver group (shared local expansion, per-receiver
# expansion, monopole) can flip too, and changes the points near it by at most
# that node's error bound, a fraction of the tolerance (the default's RMS error
# against the exact sum is ~5e-4). So an item (point or pixel) whose values
# are off by more than `tight` is an outlier; outliers are allowed up to a
# fraction of the items, and the RMS over all values is bounded.
#   values           tight  outliers  rms   measured, 1e-6..1e6
#   _radiance_t      1e-5   0.1 %     1e-4  max 2e-7, no outlier
#   _ssdiffusion     1e-3   1 %       1e-3  max 2.6e-4, rms 8e-6 (one node's
#                    flipped choice, the same at every scale; 3e-6 before
#                    the receiver groups, issue 17)
#   image, 19 ch.    5e-4   0.2 %     1e-2  max 1.9e-4 (the ssd flip), rms 5e-6,
#                    but for one flipped camera sample at a silhouette at some
#                    scales (it makes 4 outlier pixels off by up to 0.5, rms 5e-3)
LIMITS = {"_radiance_t": (1e-5, 0.001, 1e-4), "_ssdiffusion": (1e-3, 0.01, 1e-3),
          "image": (5e-4, 0.002, 1e-2)}

def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    names, codes, count = [], "<", 0
    for line in data[:end].decode().splitlines():
        w = line.split()
        if w[0] == "element" and w[1] == "vertex":
            count = int(w[2])
        elif w[0] == "property":
            # floats, and the uchar display colour
            if w[1] not in ("float", "uchar"):
                raise ValueError(f"property {w[2]} is {w[1]}, not float or uchar")
            names.append(w[2])
            codes += "f" if w[1] == "float" else "B"
    k = len(names)
    flat = [v for i in range(count)
            for v in struct.unpack_from(codes, data, end + i * struct.calcsize(codes))]
    return count, {n: flat[i::k] for i, n in enumerate(names)}

def finite(values):
    return all(math.isfinite(v) for v in values)

def compare_values(label, kind, rows0, rows1):
    """rows: one list of values per item (point or pixel)."""
    tight, fraction, rms_tol = LIMITS[kind]
    nch = len(rows0[0])
    means = [sum(abs(r[c]) for r in rows0) / len(rows0) or 1.0 for c in range(nch)]
    worst, sq, outliers = 0.0, 0.0, 0
    for r0, r1 in zip(rows0, rows1):
        d = [abs(r1[c] - r0[c]) / means[c] for c in range(nch)]
        worst = max(worst, max(d))
        sq += sum(x * x for x in d)
        outliers += max(d) > tight
    rms = math.sqrt(sq / (nch * len(rows0)))
    if outliers > fraction * len(rows0) or rms > rms_tol:
        problems.append(f"{label}: {outliers} of {len(rows0)} items off by more than "
                        f"{tight:g} of the channel mean ({fraction:.1%} allowed), "
                        f"max {worst:.3g}, rms {rms:.3g} ({rms_tol:g} allowed)")
    return f"{kind} max {worst:.2g} rms {rms:.2g} ({outliers} outliers)"

def compare_cloud(name, channel):
    try:
        n0, c0 = read_ply(f"{ref_dir}/{name}")
        n1, c1 = read_ply(f"{dir_}/{name}")
    except (OSError, ValueError) as e:
        problems.append(f"{name}: {e}")
        return ""
    if n1 != n0 or n0 == 0:
        problems.append(f"{name}: {n1} points, {n0} at the reference scale")
        return ""
    if sorted(c0) != sorted(c1):
        problems.append(f"{name}: channels {sorted(c1)}, {sorted(c0)} at the reference")
        return ""
    for k, v in c1.items():
        if not finite(v):
            problems.append(f"{name}: non-finite {k}")
    size = max(max(c0[a]) - min(c0[a]) for a in "xyz")
    pos = max(abs(c1[a][i] - s * c0[a][i]) for a in "xyz" for i in range(n0)) / (s * size)
    nrm = max(abs(c1[a][i] - c0[a][i]) for a in ("nx", "ny", "nz") for i in range(n0))
    rad = max(abs(c1["radius"][i] - s * c0["radius"][i]) / (s * c0["radius"][i])
              for i in range(n0) if c0["radius"][i] > 0)
    line = (f"{name}: {n0} points, position {pos:.2g} of the size, normal {nrm:.2g}, "
            f"radius {rad:.2g}")
    if pos > POS_TOL:
        problems.append(f"{name}: positions off by {pos:.3g} of the scene size")
    if nrm > NORMAL_TOL:
        problems.append(f"{name}: normals off by {nrm:.3g}")
    if rad > SIZE_TOL:
        problems.append(f"{name}: radii off by {rad:.3g} (relative)")
    if "_area" in c0:
        a = max(abs(c1["_area"][i] - s**2 * c0["_area"][i]) / (s**2 * c0["_area"][i])
                for i in range(n0) if c0["_area"][i] > 0)
        line += f", area {a:.2g}"
        if a > SIZE_TOL:
            problems.append(f"{name}: areas off by {a:.3g} (relative)")
    keys = [f"{channel}_{c}" for c in "rgb"]
    rows0 = list(zip(*(c0[k] for k in keys)))
    rows1 = list(zip(*(c1[k] for k in keys)))
    return line + ", " + compare_values(f"{name} {channel}", channel, rows0, rows1)

def read_image(path):
    with open(path) as f:
        return [[float(v) for v in line.split(":", 1)[1].split()]
                for line in f if "Pixel (" in line]

def compare_image():
    p0, p1 = read_image(f"{ref_dir}/img.txt"), read_image(f"{dir_}/img.txt")
    if not p0 or len(p1) != len(p0) or len(p1[0]) != len(p0[0]):
        problems.append(f"image: {len(p1)} pixels, {len(p0)} at the reference (or unreadable)")
        return ""
    if not all(finite(p) for p in p1):
        problems.append("image: non-finite pixels")
    return (f"image: {len(p0)} pixels x {len(p0[0])} channels, " +
            compare_values("image", "image", p0, p1))

print(f"s={sys.argv[3]}:")
for line in (compare_cloud("bake.ply", "_radiance_t"),
             compare_cloud("spacing.ply", "_radiance_t"),
             compare_cloud("mfp.ply", "_radiance_t"),
             compare_cloud("ssd.ply", "_ssdiffusion"),
             compare_image()):
    if line:
        print("  " + line)
for p in problems:
    print("  PROBLEM " + p)
sys.exit(1 if problems else 0)
PYTHON

ref="${scales[0]}"
if [[ -s "s_$ref/img.txt" ]]; then
    # The reference itself: finite pixels, and a picture (the sphere lit).
    python3 - "s_$ref/img.txt" <<'PYTHON' || fail "the s=$ref image is not finite or is black"
import math, sys
vals = [float(v) for line in open(sys.argv[1]) if "Pixel (" in line
        for v in line.split(":", 1)[1].split()]
sys.exit(0 if vals and all(math.isfinite(v) for v in vals) and max(vals) > 0.1 else 1)
PYTHON
    for s in "${scales[@]:1}"; do
        [[ -s "s_$s/img.txt" ]] || continue # its failure is already recorded
        run python3 compare.py "s_$ref" "s_$s" "$s"
        echo "$out"
        [[ "$rc" == 0 ]] || fail "s=$s differs from s=$ref (see above)${err:+: $err}"
    done
else
    fail "no reference image at s = $ref"
fi

finish_checks scale

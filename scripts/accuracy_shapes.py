# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The diffusion on real shapes against the light (scripts/accuracy-report --shapes).

Every case is a scene: a RIB is written, baked with ptbake, filtered with ptfilter
(the surface profiles alone and with -volume 1 / -blocker) and walked with the
project's Monte-Carlo in the same geometry (ssprofile -scene). The report,
docs/accuracy-shapes.md, and its data, docs/accuracy/shapes/*.tsv, are written
from the results; the commands are in the report.
"""
import csv
import datetime
import os
import re
import statistics
import subprocess
import sys
import time

# Jensen et al. 2001 (the material table of src/sss/diffusion/material.cpp).
MATERIALS = {
    "skin1": ((0.74, 0.88, 1.01), (0.032, 0.17, 0.48), 1.3),
    "marble": ((2.19, 2.62, 3.00), (0.0021, 0.0041, 0.0071), 1.5),
}
CHANNELS = "rgb"

# What ptfilter is asked, per method: the surface profiles alone (classic is
# PRMan's and the default) and with the volume.
METHODS = {
    "classic": [],
    "pbd": ["-profile", "pbd"],
    "classic+volume": ["-volume", "1"],
    "pbd+volume": ["-profile", "pbd", "-volume", "1"],
    "mc+volume": ["-profile", "mc", "-volume", "1"],
}


def told(extra, incidence):
    """The volume methods are told how the light entered (-incidence): the
    irradiance in the cloud does not say, and it decides how deep the light
    first scatters. The surface profiles have no such option."""
    volume = "-volume" in extra or "-blocker" in extra
    return extra + ["-incidence", incidence] if volume and incidence != "normal" else extra


def mfp(material, c):
    ss, sa, _ = MATERIALS[material]
    return 1.0 / (ss[c] + sa[c])


def dmfp(material, c):
    ss, sa, _ = MATERIALS[material]
    return 1.0 / (3.0 * sa[c] * (ss[c] + sa[c])) ** 0.5


class Runner:
    def __init__(self, bin_dir, work, photons):
        self.bin = bin_dir
        self.work = work
        self.photons = photons
        os.makedirs(work, exist_ok=True)

    def run(self, tool, args, cwd=None):
        cmd = [os.path.join(self.bin, tool)] + [str(a) for a in args]
        print("+ " + " ".join(cmd), file=sys.stderr, flush=True)
        t = time.perf_counter()
        out = subprocess.run(cmd, check=True, text=True, stdout=subprocess.PIPE,
                             cwd=cwd or self.work).stdout
        return out, time.perf_counter() - t

    def bake(self, name, rib_text, spacing):
        rib = os.path.join(self.work, name + ".rib")
        with open(rib, "w") as f:
            f.write(rib_text)
        args = ["-spacing", spacing] if spacing else []
        self.run("ptbake", args + [name + ".rib"])
        return rib

    def filter(self, material, cloud, out, extra):
        self.run("ptfilter", ["-ssdiffusion", "-material", material, "-threads", 2] + extra +
                 [cloud, out])
        return out

    def walk(self, rib, material, cloud, compare, regions, blockers=(), incidence="diffuse",
             photons=None):
        args = ["-scene", rib, "-material", material, "-photons", photons or self.photons,
                "-scattered", 1, "-incidence", incidence, "-seed", 1001]
        for b in blockers:
            args += ["-blocker", b]
        for c in compare:
            args += ["-compare", c]
        for name, box in regions.items():
            args += ["-region", name] + list(box)
        text, seconds = self.run("ssprofile", args + [cloud, "truth_" + os.path.basename(cloud)])
        return parse_walk(text), seconds


def parse_walk(text):
    """The walk's totals, each compared cloud's total and L1, and the regions."""
    r = {"out": {}, "blocked": {}, "compare": {}, "regions": {}}
    for line in text.splitlines():
        m = re.match(r"ssprofile: ([rgb]): flux in \S+; out ([0-9.]+) \+- [0-9.]+, blocked "
                     r"([0-9.]+)", line)
        if m:
            r["out"][m.group(1)] = float(m.group(2))
            r["blocked"][m.group(1)] = float(m.group(3))
            continue
        m = re.match(r"ssprofile: (\S+) ([rgb]): flux-weighted L1 ([0-9.]+)% \(walk noise "
                     r"([0-9.]+)%\), total x([0-9.]+)", line)
        if m:
            r["compare"].setdefault(os.path.basename(m.group(1)), {})[m.group(2)] = (
                float(m.group(3)) / 100, float(m.group(5)), float(m.group(4)) / 100)
            continue
        m = re.match(r"ssprofile: region (\S+): \d+ points, walk (\S+) (\S+) (\S+)", line)
        if m:
            r["regions"].setdefault(m.group(1), {})["walk"] = [float(m.group(i))
                                                              for i in (2, 3, 4)]
            continue
        m = re.match(r"ssprofile: region (\S+): (\S+) (\S+) (\S+) (\S+), x", line)
        if m:
            r["regions"].setdefault(m.group(1), {})[os.path.basename(m.group(2))] = [
                float(m.group(i)) for i in (3, 4, 5)]
    return r


def ratio(a, b):
    return a / b if b > 0 else float("nan")


def box_rib(cloud, w, d, h, light_from="0 0 1"):
    """A w x d x h box, its top face at z = 0, lit from above."""
    x0, x1, y0, y1, z0, z1 = -w / 2, w / 2, -d / 2, d / 2, -h, 0
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1),
         (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (0, 4, 7, 3)]
    polys = "\n".join('Polygon "P" [%s]' % " ".join("%g %g %g" % v[i] for i in f) for f in faces)
    return f"""Attribute "dice" "rasterorient" 0
WorldBegin
Attribute "cull" "hidden" 0 "backfacing" 0
LightSource "distantlight" 1 "intensity" [1] "from" [{light_from}] "to" [0 0 0]
AttributeBegin
Attribute "identifier" "name" ["medium"]
Surface "bake_radiance_t" "string filename" ["{cloud}"]
{polys}
AttributeEnd
"""


def slabs(r, quick):
    rows = []
    thick = [1, 2, 5]
    for material in ("skin1", "marble"):
        for d in thick:
            name = f"slab_{material}_{d}mm"
            rib = r.bake(name, box_rib(name + ".ptc", 40, 40, d) + "WorldEnd\n",
                         0.5 if quick else 0.25)
            regions = {"R": (-5, -5, -0.01, 5, 5, 0.01), "T": (-5, -5, -d - 0.01, 5, 5, -d + 0.01)}
            for incidence in ("normal", "diffuse"):
                outs = {}
                for method, extra in METHODS.items():
                    args = told(extra, incidence)
                    out = f"{name}_{method}" + ("" if args == extra else "_" + incidence)
                    outs[method] = (out + ".ptc" if incidence != "normal" and args == extra
                                    else r.filter(material, name + ".ptc", out + ".ptc", args))
                w, _ = r.walk(rib, material, name + ".ptc", list(outs.values()), regions,
                              incidence=incidence)
                for method, out in outs.items():
                    for c, ch in enumerate(CHANNELS):
                        reg = w["regions"]
                        rows.append({
                            "material": material, "d_mm": d, "incidence": incidence,
                            "channel": ch, "d_over_l": round(d / mfp(material, c), 2),
                            "method": method,
                            "R": ratio(reg["R"][out][c], reg["R"]["walk"][c]),
                            "T": ratio(reg["T"][out][c], reg["T"]["walk"][c]),
                            "out_per_in": w["compare"][out][ch][1] * w["out"][ch],
                            "walk_out_per_in": w["out"][ch],
                        })
    return rows


def spheres(r, quick):
    rows = []
    for material in ("skin1", "marble"):
        for radius in (2, 5, 20):
            name = f"sphere_{material}_{radius}mm"
            rib = r.bake(name, f"""Attribute "dice" "rasterorient" 0
WorldBegin
Attribute "cull" "hidden" 0 "backfacing" 0
LightSource "distantlight" 1 "intensity" [1] "from" [0 0 1] "to" [0 0 0]
Attribute "identifier" "name" ["medium"]
Surface "bake_radiance_t" "string filename" ["{name}.ptc"]
Sphere {radius} -{radius} {radius} 360
WorldEnd
""", radius / (8 if quick else 12))
            outs, times = {}, {}
            for method, extra in METHODS.items():
                t = time.perf_counter()
                outs[method] = r.filter(material, name + ".ptc", f"{name}_{method}.ptc",
                                        told(extra, "diffuse"))
                times[method] = time.perf_counter() - t
            # Per point the walk is noisy on a sphere's dark side: skin1's walks
            # are cheap and get 4x the paths; marble's 20 mm ball is slow (long
            # paths, little absorption) and gets a quarter.
            photons = (4 * r.photons if material == "skin1"
                       else r.photons if radius < 20 else max(r.photons // 4, 50000))
            w, _ = r.walk(rib, material, name + ".ptc", list(outs.values()), {}, photons=photons)
            for method, out in outs.items():
                for c, ch in enumerate(CHANNELS):
                    l1, total, noise = w["compare"][out][ch]
                    rows.append({"material": material, "radius_mm": radius, "channel": ch,
                                 "radius_over_dmfp": round(radius / dmfp(material, c), 2),
                                 "method": method, "flux": total, "l1w": l1, "noise": noise,
                                 "seconds": round(times[method], 3)})
    return rows


BONE = """AttributeBegin
Attribute "identifier" "name" ["bone"]
Surface "bake_constant" "string filename" ["{cloud}"]
Translate 0 0 -4
Rotate 90 0 1 0
Cylinder 2.5 -12 12 360
Translate 0 0 12
Disk 0 2.5 360
Translate 0 0 -24
Disk 0 2.5 -360
AttributeEnd
"""


def bone_box(r, quick):
    rows = []
    regions = {f"top{o:g}": (-5, o - 0.5, -0.01, 5, o + 0.5, 0.01) for o in (0.0, 2.5, 5.0)}
    regions["bottom"] = (-5, -1, -10.01, 5, 1, -9.99)
    for material in ("skin1", "marble"):
        name = f"bonebox_{material}"
        rib = r.bake(name, box_rib(name + ".ptc", 30, 30, 10) +
                     BONE.format(cloud=name + "_bone.ptc") + "WorldEnd\n", 0.5 if quick else 0.3)
        with_bone = {
            "classic": [],
            "pbd+volume+blocker": ["-profile", "pbd", "-blocker", name + "_bone.ptc"],
            "mc+volume+blocker": ["-profile", "mc", "-blocker", name + "_bone.ptc"],
            "classic+volume+blocker": ["-blocker", name + "_bone.ptc"],
        }
        outs = {m: r.filter(material, name + ".ptc", f"{name}_{m}.ptc", told(e, "diffuse"))
                for m, e in with_bone.items()}
        w, _ = r.walk(rib, material, name + ".ptc", list(outs.values()), regions,
                      blockers=["bone"])
        # The same box without the bone (its geometry left out, not only its
        # absorption), for how much the bone darkens it.
        free_rib = os.path.join(r.work, name + "_free.rib")
        with open(free_rib, "w") as f:
            f.write(box_rib(name + ".ptc", 30, 30, 10) + "WorldEnd\n")
        free, _ = r.walk(free_rib, material, name + ".ptc", [], regions)
        for method, out in outs.items():
            for c, ch in enumerate(CHANNELS):
                row = {"material": material, "channel": ch, "method": method}
                for reg in regions:
                    row[reg] = ratio(w["regions"][reg][out][c], w["regions"][reg]["walk"][c])
                    row["bone_darkens_" + reg] = ratio(w["regions"][reg]["walk"][c],
                                                       free["regions"][reg]["walk"][c])
                rows.append(row)
    return rows


def thin_box(r, root, quick):
    """The thin box scene (scenes/thinbox) with its torus baked as a blocker
    cloud of its own, against the old negative-light fake."""
    with open(os.path.join(root, "scenes", "thinbox", "bake.rib")) as f:
        fake = f.read()
    real = fake.replace("Color [-1 -1 -1]", "").replace(
        'Surface "bake_constant" "string filename" ["thinbox.ptc"]',
        'Surface "bake_constant" "string filename" ["torus.ptc"]')
    fake = fake.replace('["thinbox.ptc"]', '["fake.ptc"]')
    spacing = 0.3 if quick else None
    r.bake("thinbox_fake", fake, spacing)
    rib = r.bake("thinbox", real, spacing)
    methods = {"classic (no blocker)": ("thinbox.ptc", []),
               "classic, negative-light torus": ("fake.ptc", []),
               "classic+volume+blocker": ("thinbox.ptc", ["-blocker", "torus.ptc"]),
               "pbd+volume+blocker": ("thinbox.ptc", ["-profile", "pbd", "-blocker",
                                                      "torus.ptc"]),
               "mc+volume+blocker": ("thinbox.ptc", ["-profile", "mc", "-blocker",
                                                    "torus.ptc"])}
    outs = {}
    for i, (m, (cloud, extra)) in enumerate(methods.items()):
        outs[m] = r.filter("skin1", cloud, f"thinbox_{i}.ptc", told(extra, "diffuse"))
    # The fake's cloud holds the torus's points too: it is compared on the
    # regions only.
    regions = {"top": (-3, 1.99, -3, 3, 2.01, 3), "under_centre": (-2, -2.01, -2, 2, -1.99, 2),
               "under_ring": (5.2, -2.01, -0.8, 6.8, -1.99, 0.8)}
    w, _ = r.walk(rib, "skin1", "thinbox.ptc", list(outs.values()), regions,
                  blockers=["blocker"])
    rows = []
    for m, out in outs.items():
        for c, ch in enumerate(CHANNELS):
            row = {"method": m, "channel": ch}
            for reg in regions:
                row[reg] = ratio(w["regions"][reg][out][c], w["regions"][reg]["walk"][c])
            rows.append(row)
    return rows


def cost(r, quick):
    """Wall time of ptfilter with and without the volume (median of three)."""
    rows = []
    n = 100000 if quick else 1000000
    r.run("ptsynth", ["-n", n, "-size", 50, "-light", 1, 1, 1, "bench_sphere.ptc"])
    cases = [("sphere r 50 mm, %d points, marble" % n, "marble", "bench_sphere.ptc",
              ["-volume", "1"]),
             ("thin box (scenes/thinbox), skin1", "skin1", "thinbox.ptc",
              ["-blocker", "torus.ptc"])]
    for label, material, cloud, extra in cases:
        t = {}
        for name, args in (("classic", []), ("volume", extra)):
            times = []
            for _ in range(3):
                _, s = r.run("ptfilter", ["-ssdiffusion", "-material", material, "-threads", 2]
                             + args + [cloud, "cost.ptc"])
                times.append(s)
            t[name] = statistics.median(times)
        rows.append({"case": label, "classic_s": round(t["classic"], 3),
                     "volume_s": round(t["volume"], 3),
                     "ratio": round(t["volume"] / t["classic"], 2),
                     "command": "ptfilter -ssdiffusion -material %s -threads 2 %s %s out.ptc" %
                                (material, " ".join(extra), cloud)})
    return rows


def write_tsv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), delimiter="\t")
        w.writeheader()
        for row in rows:
            w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in row.items()})


def read_tsv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f, delimiter="\t"))


def run_cases(bin_dir, root, data_dir, work, photons, quick):
    r = Runner(bin_dir, work, photons)
    os.makedirs(data_dir, exist_ok=True)
    write_tsv(os.path.join(data_dir, "slabs.tsv"), slabs(r, quick))
    write_tsv(os.path.join(data_dir, "spheres.tsv"), spheres(r, quick))
    write_tsv(os.path.join(data_dir, "bone.tsv"), bone_box(r, quick))
    write_tsv(os.path.join(data_dir, "thinbox.tsv"), thin_box(r, root, quick))
    write_tsv(os.path.join(data_dir, "cost.tsv"), cost(r, quick))


def run_cost(bin_dir, data_dir, work, quick):
    """Only the cost again (the walks' data are kept)."""
    write_tsv(os.path.join(data_dir, "cost.tsv"), cost(Runner(bin_dir, work, 0), quick))


def pct(x):
    return f"{100 * (float(x) - 1):+.0f} %"


def f2(x):
    return f"{float(x):.2f}"


def by_case(rows, keys):
    """(the case's key values, {method: row}) per case, in the rows' order."""
    cases = {}
    for r in rows:
        cases.setdefault(tuple(r[k] for k in keys), {})[r["method"]] = r
    return cases.items()


def write_report(path, data_dir, photons, commit):
    slab = read_tsv(os.path.join(data_dir, "slabs.tsv"))
    sph = read_tsv(os.path.join(data_dir, "spheres.tsv"))
    bone = read_tsv(os.path.join(data_dir, "bone.tsv"))
    thin = read_tsv(os.path.join(data_dir, "thinbox.tsv"))
    cost_rows = read_tsv(os.path.join(data_dir, "cost.tsv"))
    out = []
    w = out.append
    w("# Accuracy on real shapes: the diffusion against the light\n")
    w(f"Generated by `scripts/accuracy-report --shapes` (commit {commit}, "
      f"{datetime.date.today().isoformat()}, {photons} Monte-Carlo paths per channel and "
      "walk, seed 1001). Do not edit by hand.\n")
    w("""Every case is a scene: the script writes its RIB, bakes it with `ptbake`, filters the
cloud with `ptfilter` and walks the light through the same geometry with `ssprofile -scene`
(the reduced isotropic medium of the material's coefficients, exact Fresnel boundary; see
[accuracy.md](accuracy.md)). The walk counts only light that scattered at least once
(`-scattered 1`): light that crosses a thin part without a collision depends on the real phase
function, which Jensen's data do not give, and no diffusion model describes it. Figures are
`ptfilter` / walk; `out/in` is the light a result gives off per unit of light that entered.

Methods: `classic` and `pbd` are the surface profiles alone (classic is PRMan's and the
default); `+volume` adds `-volume 1` (docs/volume.md); `+blocker` gives the bone's own baked
cloud as `-blocker`.
""")
    # Summary against the acceptance.
    w("## Summary\n")
    w("The worst case of each measure against the walk, with `-volume 1` (and `-blocker` for "
      "the bone) and the two most accurate profiles.\n")
    worst = lambda rows, k: max((abs(float(r[k]) - 1) for r in rows), default=float("nan"))
    w("| case | measure | pbd+volume | mc+volume | goal |")
    w("|---|---|---|---|---|")
    cols = {}
    for p in ("pbd", "mc"):
        sel = [r for r in slab if r["method"] == p + "+volume"]
        thick = [r for r in sel if float(r["d_over_l"]) >= 2]
        mid = [r for r in sel if 1 <= float(r["d_over_l"]) < 2]
        ss = [r for r in sph if r["method"] == p + "+volume"]
        big = [r for r in ss if float(r["radius_over_dmfp"]) >= 1]
        small = [r for r in ss if float(r["radius_over_dmfp"]) < 1]
        bb = [r for r in bone if r["method"] == p + "+volume+blocker"]
        cols[p] = [
            f"{100 * worst(thick, 'R'):.0f} %, {100 * worst(thick, 'T'):.0f} %",
            f"{100 * worst(mid, 'R'):.0f} %, {100 * worst(mid, 'T'):.0f} %",
            f"{max((float(r['out_per_in']) for r in sel), default=float('nan')):.3f}",
            f"{100 * worst(big, 'flux'):.0f} %",
            f"{100 * worst(small, 'flux'):.0f} %",
            f"{100 * max((float(r['l1w']) for r in ss), default=float('nan')):.0f} % "
            f"(noise {100 * max((float(r['noise']) for r in ss), default=float('nan')):.0f} %)",
            f"{100 * max((abs(float(r[k]) - 1) for r in bb for k in ('top0', 'top2.5', 'top5')), default=float('nan')):.0f} %",
        ]
    labels = [("slabs, d >= 2 l", "abs(R - 1), abs(T - 1)", "10 %"),
              ("slabs, l <= d < 2 l", "abs(R - 1), abs(T - 1)", "25 %"),
              ("slabs", "light out per light in", "<= 1"),
              ("spheres, radius >= dmfp", "abs(flux - 1)", "10 %"),
              ("spheres, radius < dmfp", "abs(flux - 1)", "20 %"),
              ("spheres", "flux-weighted L1", "15 %"),
              ("bone box", "lit face at 0, 2.5, 5 mm from above the bone", "10 %")]
    for i, (case, measure, goal) in enumerate(labels):
        w(f"| {case} | {measure} | {cols['pbd'][i]} | {cols['mc'][i]} | {goal} |")
    w("")
    w("## Cost\n")
    w("Wall time of the whole `ptfilter` run (read, diffusion, write), 2 threads, the median "
      "of three.\n")
    w("| case | classic s | with the volume s | ratio | command |")
    w("|---|---|---|---|---|")
    for r in cost_rows:
        w(f"| {r['case']} | {r['classic_s']} | {r['volume_s']} | x{r['ratio']} | "
          f"`{r['command']}` |")
    w("")
    w("## Slabs\n")
    w("40 x 40 mm slabs lit on the top face by a distant light (`ptbake -spacing 0.25`); R and T "
      "are the mean exitance over the middle 10 x 10 mm of the lit and of the back face. "
      "ptfilter gets the same cloud for either incidence (the irradiance does not say where the "
      "light came from); the walk lets it in straight (normal) or diffuse, and the `+volume` "
      "methods are told which with `-incidence` (the surface profiles have no such option).\n")
    methods = list(dict.fromkeys(r["method"] for r in slab))
    w("| material | d | incidence | channel | d / l | " +
      " | ".join(f"{m} R / T / out/in" for m in methods) + " |")
    w("|---|---|---|---|---|" + "---|" * len(methods))
    for k, by in by_case(slab, ("material", "d_mm", "incidence", "channel", "d_over_l")):
        cells = [f"{pct(by[m]['R'])} / {pct(by[m]['T'])} / {f2(by[m]['out_per_in'])}"
                 for m in methods]
        w(f"| {k[0]} | {k[1]} mm | {k[2]} | {k[3]} | {k[4]} | " + " | ".join(cells) + " |")
    w("")
    w("## Spheres\n")
    w("Spheres lit from one side by a distant light; `flux` is the light the result gives off "
      "over the walk's, `L1w` the flux-weighted L1 error per point, which includes the walk's "
      "own noise per point (`noise`: what a perfect result would score); `s` is ptfilter's "
      "wall time.\n")
    methods = list(dict.fromkeys(r["method"] for r in sph))
    w("| material | radius | channel | radius / dmfp | noise | " +
      " | ".join(f"{m} flux / L1w / s" for m in methods) + " |")
    w("|---|---|---|---|---|" + "---|" * len(methods))
    for k, by in by_case(sph, ("material", "radius_mm", "channel", "radius_over_dmfp")):
        cells = [f"x{float(by[m]['flux']):.2f} / {100 * float(by[m]['l1w']):.0f} % / "
                 f"{by[m]['seconds']}" for m in methods]
        noise = by[methods[0]]["noise"]
        w(f"| {k[0]} | {k[1]} mm | {k[2]} | {k[3]} | {100 * float(noise):.0f} % | " +
          " | ".join(cells) + " |")
    w("")
    w("## A bone under the skin\n")
    w("A 30 x 30 x 10 mm box lit on top with an absorbing cylinder inside (radius 2.5 mm, axis "
      "4 mm under the lit face, 24 mm long), baked with its own cloud (`bake_constant`). Figures "
      "are ptfilter / walk over strips of the lit face at 0, 2.5 and 5 mm from above the bone's "
      "axis and over the middle of the far face; `bone` is how much the bone darkens each strip "
      "in the walk (with / without it).\n")
    w("| material | channel | method | top 0 | top 2.5 | top 5 | far face | bone: top 0 / far |")
    w("|---|---|---|---|---|---|---|---|")
    for r in bone:
        w(f"| {r['material']} | {r['channel']} | {r['method']} | {pct(r['top0'])} | "
          f"{pct(r['top2.5'])} | {pct(r['top5'])} | {pct(r['bottom'])} | "
          f"x{float(r['bone_darkens_top0']):.2f} / x{float(r['bone_darkens_bottom']):.2f} |")
    w("")
    w("## The thin box with its torus\n")
    w("`scenes/thinbox` (4 mm of skin1, a torus in its middle plane), baked at the scene's own "
      "resolution, against the walk with the torus absorbing. The negative-light fake bakes the "
      "torus into the box's cloud with `Color [-1 -1 -1]`; the real blocker bakes it into a "
      "cloud of its own, given to `-blocker`. Regions: the middle of the lit top, the middle of "
      "the underside and the underside below the torus's ring.\n")
    w("| method | channel | top | under the middle | under the ring |")
    w("|---|---|---|---|---|")
    for r in thin:
        w(f"| {r['method']} | {r['channel']} | {pct(r['top'])} | {pct(r['under_centre'])} | "
          f"{pct(r['under_ring'])} |")
    w("")
    with open(path, "w") as f:
        f.write("\n".join(out))

#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The live diffusion of ptview -serve: how long from a moved control to the
new picture, at 200k and 1M points (docs/ptview.md, "Latency").

    bench/ptview_serve_bench.py [--bin build/bin] [--points 200000,1000000]
                                [--repeat 5] [--work out/ptview-serve-bench]

For each size: a ptsynth sphere (baked: _area, _radiance_t), ptview -serve
on it, and headless Chromium (tests/browser/webdriver.py, SwiftShader's
WebGL2 on the CPU) on the page with two 512 x 512 tiles (the bake and its
live diffusion). Then `repeat` times each:
  - preview: the mean free path slider moved ('input' event): the diffusion
    of the subsample (every k-th point, about 50000) and its picture;
  - whole: the slider let go ('change' event): the whole cloud.
The page measures each from the event to the picture drawn and waited for
(sssView.latencies: the server's diffusion time, the answer's arrival, the
drawing). Also the server alone: POST /api/diffuse from Python, no browser.
Prints one table; medians and maxima in milliseconds.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "browser"))
from webdriver import Browser  # noqa: E402


def serve(bin_dir, cloud, work):
    p = subprocess.Popen([os.path.join(bin_dir, "ptview"), "-serve", "-port", "0", cloud],
                         cwd=work, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    url = re.search(r" at (http://[^#\s]+)", p.stdout.readline()).group(1)
    return p, url


def server_only(url, preview, repeat):
    """Round trips of POST /api/diffuse: (the diffusion, the whole request) in ms."""
    inner, outer = [], []
    for k in range(repeat):
        body = f"-material\nmarble\n-albedo\n0.8\n0.7\n0.6\n-diffusemeanfreepath\n{4 + k}\n3\n2".encode()
        t = time.perf_counter()
        with urllib.request.urlopen(urllib.request.Request(
                f"{url}api/diffuse?cloud=0&preview={int(preview)}", data=body), timeout=120) as r:
            data = r.read()
        outer.append(1000 * (time.perf_counter() - t))
        n = int.from_bytes(data[:4], "little")
        inner.append(1000 * json.loads(data[4:4 + n])["seconds"])
    return inner, outer


def in_browser(url, repeat):
    with Browser(1400, 900) as b:
        b.get(url + "#res=512x512")
        b.wait("return window.sssView && sssView.ready && sssView.busy == 0 && "
               "sssView.shownLiveSeq == sssView.liveSeq", 300, "the page")
        b.run("sssView.profile = true")
        b.run("sssView.render()")
        draw = b.run("return sssView.phases")
        results = {"preview": [], "whole": []}
        for k in range(repeat):
            for kind, event in (("preview", "input"), ("whole", "change")):
                value = (-1) ** k * (0.3 + 0.2 * k) + (0.05 if kind == "whole" else 0)
                n = b.run("return sssView.latencies.length")
                b.run(f"const s=document.getElementById('mfp-scale'); s.value={value};"
                      f"s.dispatchEvent(new Event('{event}'))")
                b.wait("return sssView.busy == 0 && sssView.shownLiveSeq == sssView.liveSeq && "
                       f"sssView.latencies.length > {n}", 300, kind)
                results[kind].append(b.run("return sssView.latencies[sssView.latencies.length - 1]"))
        max_point = b.run("const gl=document.getElementById('canvas').getContext('webgl2');"
                          "return gl.getParameter(gl.ALIASED_POINT_SIZE_RANGE)[1]")
    return draw, results, max_point


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--points", default="200000,1000000")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--work", default=os.path.join(ROOT, "out", "ptview-serve-bench"))
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    med = lambda xs: statistics.median(xs)  # noqa: E731
    rows = []
    for n in (int(x) for x in args.points.split(",")):
        cloud = f"sphere{n}.ptc"
        subprocess.run([os.path.join(args.bin, "ptsynth"), "-shape", "sphere", "-n", str(n),
                        "-size", "50", "-light", "1", "1", "1", cloud], cwd=args.work, check=True,
                       stdout=subprocess.DEVNULL)
        p, url = serve(args.bin, cloud, args.work)
        try:
            for preview in (True, False):
                inner, outer = server_only(url, preview, args.repeat)
                rows.append((n, "preview" if preview else "whole", "server", med(inner), max(inner),
                             med(outer), max(outer)))
            draw, results, max_point = in_browser(url, args.repeat)
            for kind in ("preview", "whole"):
                lat = results[kind]
                rows.append((n, kind, f"page ({lat[0]['points']} points)", med([x["server"] for x in lat]),
                             max(x["server"] for x in lat), med([x["ms"] for x in lat]),
                             max(x["ms"] for x in lat)))
            print(f"{n} points: both tiles drawn in {draw['total']:.0f} ms (splats {draw['splat']:.0f} ms, "
                  f"auto exposure {draw['exposure']:.0f} ms); largest point sprite {max_point} pixels",
                  flush=True)
        finally:
            p.terminate()
            p.wait(10)
    print(f"\n{'points':>8} {'update':>8} {'measured':>22} {'diffusion ms':>14} {'latency ms':>14}")
    print(f"{'':>8} {'':>8} {'':>22} {'median  max':>14} {'median  max':>14}")
    for n, kind, where, dm, dx, lm, lx in rows:
        print(f"{n:>8} {kind:>8} {where:>22} {dm:>7.0f} {dx:>5.0f} {lm:>8.0f} {lx:>5.0f}")


if __name__ == "__main__":
    main()

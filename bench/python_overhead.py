#!/usr/bin/python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""What the sss Python module costs over the C++ it calls (docs/python.md).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py \
        --bin build/bin [--points 1000000] [--runs 5] [--threads 1]

Measures, each the median of --runs runs on a ptsynth sphere:
  1. file to file: the ptfilter executable against sss.ptfilter() (the same
     library call, sss::SsDiffusionFiles), wall and CPU time; the outputs must
     be byte-identical;
  2. in memory: sss.ssdiffusion(cloud) against the library's own time of the
     ssdiffusion() call inside it (report["seconds"]): the difference is the
     conversion of the arrays to and from the C++ cloud;
  3. read_cloud() and write_cloud() of the input;
  4. fixed costs per call: ssdiffusion() of a 10-point cloud and
     BrickMap.lookup() of 1 point, against 1M lookups per point;
  5. `import sss` in a fresh interpreter, against `import numpy`.
"""

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import sss


def median_time(fn, runs):
    """(median wall seconds, median CPU seconds of this process) of fn()."""
    walls, cpus = [], []
    for _ in range(runs):
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        t0 = time.perf_counter()
        fn()
        walls.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        cpus.append(r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def median_process(cmd, runs):
    """(median wall, median user + sys CPU) of a child process."""
    walls, cpus = [], []
    for _ in range(runs):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        walls.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.environ.get("SSS_BIN_DIR", "build/bin"))
    ap.add_argument("--points", type=int, default=1000000)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="sss_pybench_")
    src = os.path.join(tmp, "in.ptc")
    subprocess.run([os.path.join(args.bin, "ptsynth"), "-n", str(args.points), "-light",
                    "1", "1", "1", src], check=True, stdout=subprocess.DEVNULL)
    n = sss.read_cloud(src).size
    print(f"sss {sss.__version__}, Python {sys.version.split()[0]}, numpy {np.__version__}; "
          f"{n} points, threads {args.threads}, median of {args.runs} runs")

    # 1. File to file.
    exe_out, py_out = os.path.join(tmp, "exe.ptc"), os.path.join(tmp, "py.ptc")
    exe = median_process([os.path.join(args.bin, "ptfilter"), "-ssdiffusion", "-threads",
                          str(args.threads), src, exe_out], args.runs)
    py = median_time(lambda: sss.ptfilter(src, py_out, threads=args.threads), args.runs)
    with open(exe_out, "rb") as a, open(py_out, "rb") as b:
        same = a.read() == b.read()
    print(f"file to file   ptfilter executable  wall {exe[0]:.3f} s  cpu {exe[1]:.3f} s")
    print(f"               sss.ptfilter()       wall {py[0]:.3f} s  cpu {py[1]:.3f} s  "
          f"({100 * (py[0] / exe[0] - 1):+.1f} % wall; outputs identical: {same})")

    # 2. In memory.
    cloud = sss.read_cloud(src)
    inner = []

    def in_memory():
        out = sss.ssdiffusion(cloud, threads=args.threads)
        inner.append(out.report["seconds"])

    total = median_time(in_memory, args.runs)[0]
    lib = statistics.median(inner)
    print(f"in memory      sss.ssdiffusion()    wall {total:.3f} s, of which the library "
          f"call {lib:.3f} s: module {1e3 * (total - lib):.1f} ms "
          f"({1e9 * (total - lib) / n:.1f} ns per point)")

    # 3. Reading and writing.
    rd = median_time(lambda: sss.read_cloud(src), args.runs)[0]
    wr = median_time(lambda: sss.write_cloud(os.path.join(tmp, "w.ptc"), cloud),
                     args.runs)[0]
    print(f"clouds         read_cloud() {rd:.3f} s ({rd / n * 1e9:.1f} ns per point), "
          f"write_cloud() {wr:.3f} s")

    # 4. Fixed costs per call.
    tiny = {k: v[:10] for k, v in cloud.items()}
    tiny = sss.Cloud(tiny, cloud.types)
    inner.clear()
    per_call = median_time(lambda: [in_memory_tiny(tiny, inner) for _ in range(100)],
                           args.runs)[0] / 100
    lib_tiny = statistics.median(inner)
    print(f"per call       ssdiffusion() of 10 points {1e6 * per_call:.0f} us, of which "
          f"the library call {1e6 * lib_tiny:.0f} us")
    bkm = os.path.join(tmp, "out.bkm")
    sss.make_brickmap(exe_out, bkm, maxerror=0.002)
    m = sss.BrickMap(bkm)
    one_p, one_n = cloud["P"][:1].copy(), cloud["N"][:1].copy()
    m.lookup(cloud["P"], "_ssdiffusion", normals=cloud["N"], threads=args.threads)  # cache
    one = median_time(lambda: [m.lookup(one_p, "_ssdiffusion", normals=one_n,
                                        threads=args.threads) for _ in range(1000)],
                      args.runs)[0] / 1000
    many = median_time(lambda: m.lookup(cloud["P"], "_ssdiffusion", normals=cloud["N"],
                                        threads=args.threads), args.runs)[0]
    print(f"lookups        1 point per call {1e6 * one:.1f} us; {n} points in one call "
          f"{many:.3f} s ({1e9 * many / n:.0f} ns per point)")

    # 5. Import.
    def fresh(module):
        return median_process([sys.executable, "-c", f"import {module}"], args.runs)[0]

    print(f"import         python -c 'import sss' {fresh('sss'):.3f} s, "
          f"'import numpy' {fresh('numpy'):.3f} s, 'pass' {fresh('os'):.3f} s")


def in_memory_tiny(tiny, inner):
    inner.append(sss.ssdiffusion(tiny, threads=1).report["seconds"])


if __name__ == "__main__":
    main()

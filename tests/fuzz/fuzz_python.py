#!/usr/bin/env python3
"""Fuzzing the sss Python module (docs/fuzzing.md, docs/python.md).

An input's bytes choose a sequence of up to 12 calls of the module (read and
write clouds, the diffusion, ptfilter, brick maps and their lookups, frame
patterns, the extension's functions directly) with hostile arguments: NaN
and infinities, huge and negative sizes, NUL bytes and long strings in
paths, wrong types, empty and misshapen arrays, the input's own bytes as a
cloud or brick map file. Each call must return or raise one of the module's
documented exceptions (sss.Error and its subclasses, which are also OSError,
ValueError or MemoryError) or the TypeError/ValueError of a wrong argument
type; anything else (SystemError, another exception, a crash, a hang) is a
finding.

    fuzz_python.py one FILE               run one input in this process
    fuzz_python.py replay PATH...         each file (folders: every file below
                                          them; "open-*" skipped) in a child
                                          process with a 10 s timeout
    fuzz_python.py fuzz SECONDS FINDINGS CORPUS...
                                          random and mutated inputs, each in a
                                          child process; a crash, a finding or
                                          a hang keeps the input in FINDINGS

The module is found on PYTHONPATH (the build's python/ folder). Every file a
call names is relative to a scratch folder, the children's working folder;
no name has a '/', so nothing outside it is read or written.
"""

import hashlib
import os
import random
import subprocess
import sys
import tempfile
import time
import traceback

TIMEOUT = 10
MAX_CALLS = 12
NAN = float("nan")
INF = float("inf")


class Choices:
    """Reads choices from the input's bytes; 0 once they are used up."""

    def __init__(self, data):
        self.data = data
        self.pos = 0

    def byte(self):
        if self.pos >= len(self.data):
            return 0
        self.pos += 1
        return self.data[self.pos - 1]

    def pick(self, seq):
        return seq[self.byte() % len(seq)]

    def rest(self):
        return self.data[self.pos:]

    def exhausted(self):
        return self.pos >= len(self.data)


def hostile_number(c):
    return c.pick([0, 1, -1, 0.5, NAN, INF, -INF, 1e308, -1e-308, 2**31, 2**63, -(2**64),
                   10**30, 1e-45, 3, 64, "1", None, [1, 2], True])


def hostile_name(c, ext):
    return c.pick(["a" + ext, "b" + ext, "missing" + ext, "", "a\0b" + ext, "x" * 5000 + ext,
                   "junk" + ext, "f.%04d" + ext, "f.####" + ext, "$F4" + ext, " " + ext,
                   "\udcff" + ext, b"bytes" + ext.encode(), 7, None, "a" + ext + "\n",
                   "..", "."])


def make_cloud(c, np, sss):
    n = c.pick([0, 1, 3, 16, 100])
    rng = np.random.default_rng(c.byte())
    cloud = sss.Cloud()
    shape = c.pick(["ok", "ok", "ok", "nan", "flat", "wide", "nopoints", "object", "int",
                    "mismatch", "matrix", "big"])
    p = rng.normal(size=(n, 3)).astype(np.float32)
    if shape == "nopoints":
        return {"radius": np.zeros(n)}
    if shape == "flat":
        p = p.reshape(-1)
    if shape == "wide":
        p = rng.normal(size=(n, 5))
    if shape == "object":
        p = np.array([["a", "b", "c"]] * n, dtype=object)
    if shape == "int":
        p = (p * 10).astype(np.int64)
    cloud["P"] = p
    cloud["N"] = rng.normal(size=(n, 3)).astype(np.float32)
    cloud["radius"] = np.abs(rng.normal(size=n)).astype(np.float32) * 0.1
    cloud["_area"] = np.full(n, 0.01, dtype=np.float32)
    cloud["_radiance_t"] = np.abs(rng.normal(size=(n, 3))).astype(np.float32)
    cloud.types = {"_area": "float", "_radiance_t": "color"}
    if shape == "nan" and n:
        cloud["_area"][0] = NAN
    if shape == "mismatch":
        cloud["_area"] = np.zeros(n + 1)
    if shape == "matrix":
        cloud["m"] = np.zeros((n, 4, 4))
        cloud.types["m"] = c.pick(["matrix", "float", "bogus", "color"])
    if shape == "big":
        cloud["_wide"] = np.zeros((n, 1000), dtype=np.float32)
    return cloud


def options(c):
    keys = ["material", "unitlength", "scattering", "absorption", "albedo",
            "diffusemeanfreepath", "ior", "maxsolidangle", "profile", "criterion", "isa",
            "exact", "areachannel", "radiancechannel", "keepchannels", "threads",
            "maxerror", "maxdepth", "radiusscale", "channels", "frame", "compress",
            "ptcversion", "bogus", "blocker", "volume", "incidence"]
    out = {}
    for _ in range(c.byte() % 4):
        key = c.pick(keys)
        out[key] = c.pick([hostile_number(c), "skin1", "marble", "fromfile", "nope", "",
                           (1, 2, 3), (NAN, 1, 1), [0.5] * 3, ["_area", ""], "a\0b",
                           "x" * 3000, 1, 0.1, 2, 15, 21, -1])
    # Keep the work small: no run over a second or two.
    if out.get("maxsolidangle") is None:
        out["maxsolidangle"] = 2.0
    out.setdefault("threads", 1)
    return out


def progress(c):
    kind = c.pick([None, None, "raise", "bad", "ok"])
    if kind == "raise":
        def cb(done, total):
            raise KeyError("from the callback")
        return cb
    if kind == "bad":
        return 42
    if kind == "ok":
        return lambda done, total: None
    return None


def private_call(c, np, ext_mod):
    """One call of the extension module with arguments the wrapper never passes."""
    c.pick([
        lambda: ext_mod.read_cloud(c.pick([None, 5, "", "a\0b"])),
        lambda: ext_mod.write_cloud("d.ptc", c.pick([{}, {"P": None}, {"P": "x"}, []]),
                                    {}, {}, 0, False),
        lambda: ext_mod.write_cloud("d.ptc", {"P": np.zeros((2, 3))},
                                    c.pick([{"P": 5}, {"P": "matrix"}, None]),
                                    c.pick([{}, {"format": np.zeros(1)},
                                            {"world_to_eye": np.zeros(3)},
                                            {"format": "x"}]),
                                    c.pick([0, 2**40]), c.pick([True, None])),
        lambda: ext_mod.ssdiffusion(c.pick([[], {}, None, ["x.ptc"]]),
                                    c.pick([[], ["-unitlength"], [None], "abc"]), None),
        lambda: ext_mod.make_brickmap(c.pick([[], [{}], [None]]), "e.bkm",
                                      c.pick([[], ["-maxdepth", "99"]]), None),
        lambda: ext_mod.BrickMap(c.pick(["", "junk.bkm", None]), c.pick([0, -1])),
    ])()


def call(c, np, sss, state):
    """One call chosen by the input. Exceptions propagate to the verdict."""
    op = c.byte() % 12
    ext = c.pick([".ptc", ".ply", ".bkm", ".ptc.gz", ""])
    if op == 0:
        sss.read_cloud(c.pick(state["files"] + [hostile_name(c, ext)]))
    elif op == 1:
        cloud = make_cloud(c, np, sss)
        name = c.pick(["a.ptc", "b.ply", "c.ptc", hostile_name(c, ext)])
        sss.write_cloud(name, cloud, types=c.pick([None, {}, {"_area": "color"},
                                                   {"P": "float"}, {"x": 1}, "bad"]),
                        ptcversion=c.pick([0, 1, 2, 3, -1, 2**40, NAN]),
                        compress=c.pick([False, True]))
        if isinstance(name, str) and os.path.exists(name):
            state["files"].append(name)
    elif op == 2:
        source = c.pick([make_cloud(c, np, sss)] + state["files"] + [hostile_name(c, ext)])
        sss.ssdiffusion(source, progress=progress(c), **options(c))
    elif op == 3:
        sss.ptfilter(c.pick(state["files"] + [[], hostile_name(c, ext)]),
                     c.pick(["out.ptc", hostile_name(c, ext)]), progress=progress(c),
                     **options(c))
    elif op == 4:
        source = c.pick([make_cloud(c, np, sss), [], [make_cloud(c, np, sss)] * 2]
                        + state["files"] + [hostile_name(c, ext)])
        out = c.pick(["m.bkm", hostile_name(c, ".bkm")])
        sss.make_brickmap(source, out, progress=progress(c), **options(c))
        if isinstance(out, str) and os.path.exists(out):
            state["maps"].append(out)
    elif op in (5, 6):
        name = c.pick(state["maps"] + ["junk.bkm", hostile_name(c, ".bkm")])
        bkm = sss.BrickMap(name, c.pick([256 << 20, 0, 1, -1, 2**64, 2**70, NAN, "x"]))
        repr(bkm)
        n = c.pick([0, 1, 7, 2000])
        points = c.pick([np.zeros((n, 3)), np.full((n, 3), NAN), np.ones((n, 2)),
                         np.zeros(n), [[0, 0, 0]], "points", np.full((n, 3), 1e38)])
        normals = c.pick([None, np.ones((n, 3)), np.zeros((n + 1, 3)), np.full((n, 3), INF)])
        radius = c.pick([0.0, NAN, -1.0, np.zeros(n), np.zeros(n + 3), 1e30, "r"])
        bkm.lookup(points, c.pick([None, "_ssdiffusion", "_radiance_t", "", "a\0b", 5]),
                   normals=normals, filterradius=radius,
                   threads=c.pick([0, 1, -1, 2**31, 10**20]),
                   return_found=c.pick([False, True]))
        if op == 6:
            bkm.verify()
            bkm.info  # noqa: B018 (the property's conversion is what is tested)
    elif op == 7:
        path = c.pick(["f.%04d.ptc", "f.####.ptc", "f.$F4.ptc", "f.${F}.ptc", "#", "",
                       "x" * 5000 + "%d", "%99999999d", "%-5d", "a\0%d", 5])
        sss.has_frame_pattern(path)
        sss.expand_frame_pattern(path, frame=hostile_number(c),
                                 what=c.pick(["path", "", "a\0b", None, 3]))
    elif op == 8:
        # The input's remaining bytes as a file, then read as what its name says.
        name = "junk" + c.pick([".ptc", ".ply", ".bkm"])
        with open(name, "wb") as f:
            f.write(c.rest()[:65536])
        if name.endswith(".bkm"):
            sss.BrickMap(name).verify()
        else:
            sss.read_cloud(name)
    elif op == 9:
        # The extension directly: what the wrapper would not pass. pybind11
        # reports an argument it cannot convert inside a container as a
        # RuntimeError ("Unable to cast"): the private API's, tolerated here.
        ext_mod = sss._sss
        try:
            private_call(c, np, ext_mod)
        except RuntimeError as e:
            if "Unable to cast" not in str(e):
                raise
    elif op == 10:
        cloud = make_cloud(c, np, sss)
        if isinstance(cloud, sss.Cloud):
            repr(cloud)
            cloud.channels  # noqa: B018
        sss.Cloud(c.pick([(), [("P", 1)], "PN", None]), types=c.pick([None, {"a": 1}]),
                  world_to_eye=c.pick([None, np.zeros(16), np.zeros(3), "m"]),
                  format=c.pick([None, (1, 2), "fmt", 5]))
    else:
        sss.isa_names()
        sss.ssdiffusion(make_cloud(c, np, sss), isa=c.pick(sss.isa_names() + ["x", ""]),
                        threads=1, maxsolidangle=2.0, keepchannels=c.pick([True, False]))


def run_one(data):
    """Runs the calls of one input; exits 3 after printing a finding."""
    import numpy as np  # after the child's limits are set
    import sss
    import warnings

    warnings.simplefilter("ignore")
    allowed = (sss.Error, TypeError, ValueError, OSError, MemoryError)
    c = Choices(data)
    state = {"files": [], "maps": []}
    for _ in range(MAX_CALLS):
        if c.exhausted():
            break
        try:
            call(c, np, sss, state)
        except SystemError:
            traceback.print_exc()
            print("FUZZ FINDING: SystemError", file=sys.stderr)
            sys.exit(3)
        except KeyError as e:
            # Only the progress callback's own KeyError is expected.
            if "from the callback" not in str(e):
                traceback.print_exc()
                print("FUZZ FINDING: KeyError", file=sys.stderr)
                sys.exit(3)
        except allowed:
            pass
        except Exception:  # noqa: BLE001 (any other exception is the finding)
            traceback.print_exc()
            print("FUZZ FINDING: an exception the module does not document",
                  file=sys.stderr)
            sys.exit(3)


def child(path, scratch):
    """Runs one input in a child process; (verdict, stderr) with verdict None when fine."""
    # Absolute: the child's working folder is the scratch folder.
    path_list = os.environ.get("PYTHONPATH", "").split(os.pathsep)
    env = dict(os.environ, SSS_MEMORY_LIMIT="1G", OMP_NUM_THREADS="1",
               PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.pathsep.join(os.path.abspath(p) for p in path_list if p))
    try:
        r = subprocess.run([sys.executable, os.path.abspath(__file__), "one",
                            os.path.abspath(path)], cwd=scratch, env=env,
                           capture_output=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return "timeout", ""
    for f in os.listdir(scratch):
        os.remove(os.path.join(scratch, f))
    if r.returncode == 0:
        return None, ""
    return ("crash" if r.returncode < 0 or r.returncode not in (1, 3) else "finding",
            r.stderr.decode(errors="replace")[-4000:])


def files_below(paths):
    out = []
    for p in paths:
        if os.path.isdir(p):
            for root, _, names in os.walk(p):
                out += [os.path.join(root, n) for n in names]
        elif os.path.isfile(p):
            out.append(p)
    return sorted(out)


def replay(paths):
    files = files_below(paths)
    ran = 0
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="sss_fuzz_python_") as scratch:
        for f in files:
            if os.path.basename(f).startswith("open-"):
                print(f"replay: skipped (open finding): {f}", file=sys.stderr)
                continue
            print(f"replay: {f}", file=sys.stderr, flush=True)
            verdict, err = child(f, scratch)
            if verdict:
                print(err, file=sys.stderr)
                print(f"replay: {verdict} on {f}", file=sys.stderr)
                return 1
            ran += 1
    print(f"replay: {ran} inputs in {time.monotonic() - start:.2f} s")
    if ran == 0:
        print("replay: no input found", file=sys.stderr)
        return 1
    return 0


def mutate(data, rng):
    data = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        kind = rng.randrange(4)
        if kind == 0 or not data:
            data.insert(rng.randrange(len(data) + 1), rng.randrange(256))
        elif kind == 1:
            data[rng.randrange(len(data))] = rng.randrange(256)
        elif kind == 2:
            del data[rng.randrange(len(data))]
        else:
            i = rng.randrange(len(data))
            data[i:i] = data[i:i + rng.randint(1, 8)]
    return bytes(data[:4096])


def fuzz(seconds, findings, corpus):
    os.makedirs(findings, exist_ok=True)
    seeds = [open(f, "rb").read() for f in files_below(corpus)] or [b""]
    rng = random.Random()
    runs = found = 0
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="sss_fuzz_python_") as scratch:
        while time.monotonic() - start < seconds:
            if rng.randrange(4) == 0:
                data = bytes(rng.randrange(256) for _ in range(rng.randint(1, 200)))
            else:
                data = mutate(rng.choice(seeds), rng)
            path = os.path.join(scratch, "..", os.path.basename(scratch) + ".input")
            with open(path, "wb") as f:
                f.write(data)
            verdict, err = child(path, scratch)
            runs += 1
            if verdict:
                found += 1
                name = f"{verdict}-{hashlib.sha1(data).hexdigest()}"
                with open(os.path.join(findings, name), "wb") as f:
                    f.write(data)
                print(err, file=sys.stderr)
                print(f"Test unit written to {os.path.join(findings, name)}",
                      file=sys.stderr, flush=True)
            os.remove(path)
    elapsed = time.monotonic() - start
    print(f"Done {runs} runs in {int(elapsed)} second(s)")
    print(f"stat::number_of_executed_units: {runs}")
    print(f"stat::average_exec_per_sec: {runs / max(elapsed, 1e-9):.1f}")
    return 1 if found else 0


def main(argv):
    if len(argv) == 3 and argv[1] == "one":
        with open(argv[2], "rb") as f:
            run_one(f.read())
        return 0
    if len(argv) >= 3 and argv[1] == "replay":
        return replay(argv[2:])
    if len(argv) >= 4 and argv[1] == "fuzz":
        return fuzz(float(argv[2]), argv[3], argv[4:])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))

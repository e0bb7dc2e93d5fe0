# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The sss package without numpy (CTest python.no_numpy and
python.second.no_numpy; docs/python.md): run by tests/python/run_interpreter.py
with -I -S, so that no site-packages (and so no numpy) is on the path, and
with SSS_MODULE_DIR at the package built for this interpreter.

Importing works, and so does everything that takes no arrays: the
file-to-file diffusion (byte for byte the ptfilter executable's), brick maps
made from files and their header, frame patterns, the errors. What takes or
gives arrays raises an ImportError that says numpy is needed and for which
interpreter. Plain asserts, no pytest (an interpreter without numpy may well
have no pytest either).
"""

import errno
import os
import pickle
import subprocess
import sys
import tempfile

sys.path.insert(0, os.environ["SSS_MODULE_DIR"])
BIN = os.environ["SSS_BIN_DIR"]

try:
    import numpy  # noqa: F401
    print("SKIPPED: numpy is importable without site-packages here")
    sys.exit(77)
except ImportError:
    pass

import sss  # noqa: E402

CHECKS = []


def check(f):
    CHECKS.append(f)
    return f


def run(tool, *args):
    subprocess.run([os.path.join(BIN, tool), *map(str, args)], check=True,
                   capture_output=True)


def raises(exc_type, f, *args, **kwargs):
    try:
        f(*args, **kwargs)
    except exc_type as e:
        return e
    raise AssertionError(f"{f.__name__} did not raise {exc_type.__name__}")


@check
def imports_without_numpy(tmp):
    assert "numpy" not in sys.modules
    public = {n for n in dir(sss) if not n.startswith("_")}
    assert {"read_cloud", "PointCloudLookup", "FileNotFoundError"} <= public, public
    assert not {"np", "os", "warnings", "numbers", "sys"} & set(dir(sss))
    assert sss.__version__


@check
def frame_patterns(tmp):
    assert sss.has_frame_pattern("a.####.ptc")
    assert sss.expand_frame_pattern("a.####.ptc", 7) == "a.0007.ptc"
    raises(sss.UsageError, sss.expand_frame_pattern, "a.####.ptc")


@check
def ptfilter_file_to_file(tmp):
    src = os.path.join(tmp, "sphere.ptc")
    run("ptsynth", "-n", 1500, "-light", 1, 1, 1, src)
    mine, theirs = os.path.join(tmp, "py.ptc"), os.path.join(tmp, "tool.ptc")
    report = sss.ptfilter([src], mine, material="skin1", unitlength=0.1, threads=1)
    run("ptfilter", "-ssdiffusion", "-material", "skin1", "-unitlength", 0.1,
        "-threads", 1, src, theirs)
    with open(mine, "rb") as a, open(theirs, "rb") as b:
        assert a.read() == b.read(), "sss.ptfilter() differs from the executable"
    assert report["octree_nodes"] > 0


@check
def brickmaps_from_files(tmp):
    src = os.path.join(tmp, "plane.ptc")
    run("ptsynth", "-shape", "plane", "-n", 800, "-light", 0, 0, 1, src)
    bkm = os.path.join(tmp, "plane.bkm")
    assert sss.make_brickmap(src, bkm, maxerror=0.01)["bricks"] > 0
    m = sss.BrickMap(bkm)
    assert [n for n, _ in m.channels] == [n for n, _ in m.info["channels"]]
    assert m.verify() > 0
    e = raises(ImportError, m.lookup, [0.0, 0.0, 0.0])
    assert "numpy" in str(e) and sys.executable in str(e), str(e)


@check
def arrays_need_numpy(tmp):
    e = raises(ImportError, sss.read_cloud, os.path.join(tmp, "sphere.ptc"))
    assert "numpy" in str(e) and sys.version.split()[0] in str(e), str(e)
    raises(ImportError, sss.write_cloud, os.path.join(tmp, "x.ptc"), {"P": [[0, 0, 0]]})
    raises(ImportError, sss.ssdiffusion, os.path.join(tmp, "sphere.ptc"))
    # Checks that need no arrays come first.
    raises(sss.ValueError, sss.write_cloud, os.path.join(tmp, "x.xyz"), {})


@check
def errors_are_the_builtins(tmp):
    missing = os.path.join(tmp, "missing.bkm")
    e = raises(FileNotFoundError, sss.BrickMap, missing)
    assert isinstance(e, sss.IoError) and isinstance(e, sss.FileNotFoundError)
    assert e.errno == errno.ENOENT and e.filename == missing and e.path == missing
    assert str(e).startswith(missing + ": "), str(e)
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is sss.FileNotFoundError and back.errno == e.errno
    assert str(back) == str(e) and back.filename == missing
    e = raises(OSError, sss.ptfilter, [tmp],
               os.path.join(tmp, "out.ptc"))
    assert isinstance(e, sss.IoError) and e.errno == errno.EISDIR, (e, e.errno)
    raises(sss.UsageError, sss.ptfilter, [missing], os.path.join(tmp, "o.ptc"),
           maxsolidangle="x")


def main():
    print(f"Python {sys.version.split()[0]} at {sys.executable}, "
          f"sss {sss.__version__} from {os.path.dirname(sss.__file__)}")
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for f in CHECKS:
            try:
                f(tmp)
                print(f"ok {f.__name__}")
            except Exception as e:  # report every check, then fail
                failed += 1
                print(f"FAILED {f.__name__}: {type(e).__name__}: {e}")
    print(f"{len(CHECKS) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Runs the Python tests under a given interpreter (python/CMakeLists.txt):

    run_interpreter.py --python EXE --module-dir DIR [--borrow-from MAIN] pytest FILE
    run_interpreter.py --python EXE --module-dir DIR script FILE
    run_interpreter.py --python EXE --module-dir DIR stubtest PACKAGE

DIR holds the sss package built for EXE. `pytest` runs FILE with pytest
under EXE; when EXE has no numpy or pytest of its own but the same ABI as
MAIN (another build of the same CPython version), it borrows MAIN's, placed
after its own site-packages. `script` runs FILE without any site-packages
(-I -S), so without numpy. `stubtest` runs mypy's stubtest on PACKAGE (its
typing stub against the module). Exits 77 (CTest's skip) with the reason when there
is no EXE or it lacks what the tests need.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

SKIP = 77

_PROBE = r"""
import json, sys, sysconfig
def where(name):
    try:
        module = __import__(name)
    except Exception:
        return None
    import os
    return os.path.dirname(os.path.dirname(os.path.abspath(module.__file__)))
print(json.dumps({"soabi": sysconfig.get_config_var("SOABI") or "",
                  "version": sys.version.split()[0],
                  "numpy": where("numpy"), "pytest": where("pytest")}))
"""


def probe(python):
    out = subprocess.run([python, "-c", _PROBE], capture_output=True, text=True,
                         env=clean_env(), check=True)
    return json.loads(out.stdout)


def clean_env():
    env = dict(os.environ)
    for key in ("PYTHONPATH", "PYTHONHOME"):
        env.pop(key, None)
    return env


def skip(reason):
    print(f"SKIPPED: {reason}")
    sys.exit(SKIP)


def stubtest(args, env):
    """mypy's stubtest on the package `args.file` (the stub against the module)."""
    found = subprocess.run([args.python, "-c", "import mypy.stubtest"], env=env,
                           capture_output=True)
    if found.returncode != 0:
        skip(f"{args.python} has no mypy (Debian: apt-get install python3-mypy)")
    env["PYTHONPATH"] = args.module_dir
    with tempfile.TemporaryDirectory() as cache:
        env["MYPY_CACHE_DIR"] = cache
        result = subprocess.run([args.python, "-m", "mypy.stubtest", args.file],
                                env=env, cwd=cache)
    sys.exit(result.returncode)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--python", default="")
    parser.add_argument("--module-dir", default="")
    parser.add_argument("--borrow-from", default="")
    parser.add_argument("mode", choices=["pytest", "script", "stubtest"])
    parser.add_argument("file")
    args = parser.parse_args()
    if not args.python:
        skip("no second CPython 3.9 or later on this machine (name one with "
             "cmake -DSSS_PYTHON_EXTRA=/path/to/python3)")
    env = clean_env()
    env["SSS_MODULE_DIR"] = args.module_dir
    if args.mode == "script":
        sys.exit(subprocess.run([args.python, "-I", "-S", args.file], env=env).returncode)
    if args.mode == "stubtest":
        return stubtest(args, env)

    info = probe(args.python)
    borrowed = []
    missing = [name for name in ("numpy", "pytest") if not info[name]]
    if missing and args.borrow_from:
        main_info = probe(args.borrow_from)
        if main_info["soabi"] == info["soabi"]:
            for name in missing:
                if main_info[name] and main_info[name] not in borrowed:
                    borrowed.append(main_info[name])
            missing = [name for name in missing if not main_info[name]]
    if missing:
        skip(f"{args.python} (Python {info['version']}) has no "
             f"{' or '.join(missing)}, and none of the same ABI can be borrowed "
             "(PyPI is not reachable here to install them); python.second.no_numpy "
             "still checks the module under it")
    print(f"{args.python} (Python {info['version']}), module from {args.module_dir}"
          + (f", borrowing {', '.join(borrowed)}" if borrowed else ""))
    # The module on PYTHONPATH (the tests' own subprocesses import it too);
    # what is borrowed after the interpreter's own site-packages.
    env["PYTHONPATH"] = args.module_dir
    code = ("import sys; sys.path.extend(sys.argv[1].split(':') if sys.argv[1] else []); "
            "import pytest; "
            "sys.exit(pytest.main(['-q', '-p', 'no:cacheprovider', sys.argv[2]]))")
    # Not in the build folder, whose python/sss is another interpreter's.
    result = subprocess.run([args.python, "-c", code, ":".join(borrowed), args.file],
                            env=env, cwd=os.path.dirname(os.path.abspath(args.file)))
    sys.exit(result.returncode)


if __name__ == "__main__":
    main()

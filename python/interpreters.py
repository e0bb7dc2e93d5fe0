# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""What the build needs to know of Python interpreters (python/CMakeLists.txt,
scripts/build-python, docs/python.md).

    interpreters.py probe PYTHON      what the module for PYTHON needs, as
                                      CMake "set(NAME value)" lines
    interpreters.py second MAIN       a CPython 3.9+ on this machine other
                                      than MAIN, for the second interpreter's
                                      tests (empty when there is none)

Runs under any Python 3; asks each interpreter about itself in a subprocess.
"""

import glob
import json
import os
import subprocess
import sys

# Run by the interpreter asked about: what building and installing its
# extension module takes.
_PROBE = r"""
import json, os, sys, sysconfig
def has(name):
    try:
        __import__(name)
        return True
    except Exception:
        return False
debian = os.path.join(sys.prefix, "lib", "python3", "dist-packages")
print(json.dumps({
    "implementation": sys.implementation.name,
    "version": "%d.%d.%d" % sys.version_info[:3],
    "include": sysconfig.get_paths()["include"],
    "ext_suffix": sysconfig.get_config_var("EXT_SUFFIX"),
    "soabi": sysconfig.get_config_var("SOABI") or "",
    "tag": "cp%d%d" % sys.version_info[:2],
    "platlib": sysconfig.get_path("platlib"),
    "prefix_platlib": sysconfig.get_path("platlib", "posix_prefix",
                                         vars={"base": "", "platbase": ""}).lstrip("/"),
    "debian": debian in sys.path and sys.prefix == "/usr",
    "numpy": has("numpy"),
    "pytest": has("pytest"),
    "executable": os.path.realpath(sys.executable),
}))
"""

MIN_VERSION = (3, 9)


def probe(python):
    """The interpreter's facts (a dict), or None when it does not run."""
    try:
        out = subprocess.run([python, "-c", _PROBE], capture_output=True, text=True,
                             timeout=60, env=_clean_env())
    except (OSError, subprocess.TimeoutExpired):
        return None
    if out.returncode != 0:
        return None
    try:
        return json.loads(out.stdout)
    except ValueError:
        return None


def _clean_env():
    env = dict(os.environ)
    for key in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP"):
        env.pop(key, None)
    return env


def usable(info):
    """Why the module cannot be built for the interpreter, or ''."""
    if info is None:
        return "it does not run"
    if info["implementation"] != "cpython":
        return f"it is {info['implementation']}, not CPython"
    version = tuple(int(v) for v in info["version"].split(".")[:2])
    if version < MIN_VERSION:
        return f"it is Python {info['version']} (3.9 or later needed)"
    if not os.path.isfile(os.path.join(info["include"], "Python.h")):
        return (f"its headers are missing ({info['include']}/Python.h; "
                "Debian: apt-get install python3-dev)")
    return ""


def cmd_probe(python):
    info = probe(python)
    why = usable(info)
    if why:
        print(f'set(SSS_PROBE_ERROR "{python}: {why}")')
        return 0
    for key, value in info.items():
        if isinstance(value, bool):
            value = "ON" if value else "OFF"
        print(f'set(SSS_PROBE_{key.upper()} "{value}")')
    print('set(SSS_PROBE_ERROR "")')
    return 0


def _candidates():
    """python3 executables on PATH and in pyenv's versions, in that order."""
    seen = []
    for folder in os.environ.get("PATH", "").split(os.pathsep):
        for name in ["python3"] + [f"python3.{m}" for m in range(9, 20)]:
            path = os.path.join(folder, name)
            if os.access(path, os.X_OK) and not os.path.isdir(path):
                seen.append(path)
    root = os.environ.get("PYENV_ROOT") or os.path.expanduser("~/.pyenv")
    seen += sorted(glob.glob(os.path.join(root, "versions", "*", "bin", "python3")))
    # pyenv's shims choose a version by the folder: ask for the real ones.
    return [p for p in seen if "/shims/" not in p]


def cmd_second(main):
    """Prints the best second interpreter: one that runs the tests (numpy and
    pytest of its own, or borrowed from MAIN, which needs the same ABI) before
    one that does not; nothing when there is none."""
    main_info = probe(main)
    if main_info is None:
        return 0
    best, best_rank, done = "", -1, {main_info["executable"]}
    for path in _candidates():
        real = os.path.realpath(path)
        if real in done:
            continue
        done.add(real)
        info = probe(path)
        if usable(info):
            continue
        if info["numpy"] and info["pytest"]:
            rank = 2
        elif info["soabi"] == main_info["soabi"] and main_info["numpy"]:
            rank = 1
        else:
            rank = 0
        if rank > best_rank:
            best, best_rank = path, rank
    print(best, end="")
    return 0


def main(argv):
    if len(argv) == 3 and argv[1] == "probe":
        return cmd_probe(argv[2])
    if len(argv) == 3 and argv[1] == "second":
        return cmd_second(argv[2])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))

# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Fixtures of the sss Python module's tests (docs/python.md, docs/testing.md).

CTest runs them with PYTHONPATH at the build's python/ folder (the built
module) and SSS_BIN_DIR at its bin/ folder (the tools they compare against).
"""

import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def bin_dir():
    path = os.environ.get("SSS_BIN_DIR")
    if not path:
        pytest.fail("SSS_BIN_DIR must point at the build's bin folder")
    return path


@pytest.fixture(scope="session")
def tool(bin_dir):
    """tool(name, *args) runs a built executable; returns CompletedProcess."""

    def run(name, *args, check=True):
        result = subprocess.run([os.path.join(bin_dir, name), *map(str, args)],
                                capture_output=True, text=True)
        if check and result.returncode != 0:
            raise AssertionError(f"{name} {args} exited {result.returncode}: "
                                 f"{result.stderr}")
        return result

    return run


@pytest.fixture(scope="session")
def sphere(tool, tmp_path_factory):
    """A lit ptsynth sphere of about 3000 points (P, N, radius, _area, _radiance_t)."""
    path = tmp_path_factory.mktemp("clouds") / "sphere.ptc"
    tool("ptsynth", "-n", 3000, "-size", 2, "-light", 1, 1, 1, "-ambient", 0.1, path)
    return str(path)

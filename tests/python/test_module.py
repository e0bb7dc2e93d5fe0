# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The module as a Python package (docs/python.md): a namespace of the API
only, a concise help(), exceptions that are the builtins a caller catches
(errno and filename set, picklable), unknown extensions refused, single
points taken where arrays of points are."""

import errno
import os
import pickle
import pydoc
import subprocess
import sys

import numpy as np
import pytest

import sss


def test_namespace_is_the_api():
    names = set(dir(sss))
    for leaked in ("np", "numpy", "os", "sys", "warnings", "numbers", "_sss", "_errors"):
        assert leaked not in names, leaked
    assert {n for n in names if not n.startswith("_")} == set(sss.__all__) - {
        "__version__"} | {"FileNotFoundError", "ValueError"}
    # from sss import * brings the API and keeps the builtins.
    scope = {}
    exec("from sss import *", scope)
    assert "ValueError" not in scope and "FileNotFoundError" not in scope
    assert scope["PointCloudLookup"] is sss.PointCloudLookup


def test_import_does_not_load_numpy():
    code = "import sys, sss; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_help_is_concise():
    text = pydoc.render_doc(sss, renderer=pydoc.plaintext)
    lines = text.splitlines()
    # 813 lines before the exceptions and Cloud stopped listing what every
    # exception and dict inherits.
    assert len(lines) < 450, len(lines)
    assert "inherited from" not in text
    assert "with_traceback" not in text
    for name in sss.__all__:
        if name != "__version__":
            assert name in text, name


def test_missing_file_is_a_file_not_found_error(tmp_path):
    missing = str(tmp_path / "missing.ptc")
    with pytest.raises(FileNotFoundError) as e:
        sss.read_cloud(missing)
    err = e.value
    assert isinstance(err, sss.IoError) and isinstance(err, sss.Error)
    assert type(err) is sss.FileNotFoundError
    assert err.errno == errno.ENOENT
    assert err.strerror == os.strerror(errno.ENOENT)
    assert err.filename == missing and err.path == missing
    assert str(err) == f"{missing}: cannot open: No such file or directory"
    assert err.args == (str(err),)


def test_other_io_errors_are_oserrors_with_errno(tmp_path):
    with pytest.raises(OSError) as e:
        sss.read_cloud(str(tmp_path))
    assert type(e.value) is sss.IoError and e.value.errno == errno.EISDIR
    with pytest.raises(sss.IoError) as e:
        sss.write_cloud(str(tmp_path / "no" / "such" / "x.ptc"), {"P": np.zeros((1, 3))})
    assert e.value.errno == errno.ENOENT
    assert isinstance(e.value, FileNotFoundError)


def test_errors_pickle_and_keep_their_attributes(tmp_path):
    with pytest.raises(sss.FileNotFoundError) as e:
        sss.BrickMap(str(tmp_path / "none.bkm"))
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is sss.FileNotFoundError
    assert (back.errno, back.filename, str(back)) == (e.value.errno, e.value.filename,
                                                      str(e.value))
    bad = tmp_path / "bad.ptc"
    bad.write_bytes(b"not a cloud at all, not even close")
    with pytest.raises(sss.FormatError) as e:
        sss.read_cloud(str(bad))
    back = pickle.loads(pickle.dumps(e.value))
    assert (back.path, back.point, str(back)) == (e.value.path, e.value.point,
                                                  str(e.value))
    assert isinstance(back, ValueError)


def test_bad_values_are_value_errors(sphere):
    with pytest.raises(ValueError):
        sss.ssdiffusion(sphere, unitlength=-1)
    with pytest.raises(ValueError):
        sss.write_cloud("x.ptc", {"P": np.zeros((2, 2))})


@pytest.mark.parametrize("name", ["x.xyz", "x", "x.ptc.tmp", "x.bkm", "x.PTCX"])
def test_unknown_extensions_are_refused(tmp_path, name):
    cloud = {"P": np.zeros((1, 3), np.float32)}
    with pytest.raises(sss.ValueError, match="unknown extension"):
        sss.write_cloud(str(tmp_path / name), cloud)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("name", ["x.ptc", "x.PLY", "x.Ptc"])
def test_known_extensions_in_any_case(tmp_path, name):
    sss.write_cloud(str(tmp_path / name), {"P": np.ones((2, 3), np.float32)})
    assert sss.read_cloud(str(tmp_path / name)).size == 2


@pytest.fixture(scope="module")
def brickmap(sphere, tmp_path_factory):
    path = tmp_path_factory.mktemp("bkm") / "sphere.bkm"
    sss.make_brickmap(sphere, str(path), maxerror=0.002)
    return sss.BrickMap(str(path))


def test_single_point_lookup(sphere, brickmap):
    cloud = sss.read_cloud(sphere)
    p, n = cloud["P"][7], cloud["N"][7]
    many = brickmap.lookup(cloud["P"][7:8], normals=cloud["N"][7:8])
    one = brickmap.lookup(p, normals=n)
    assert one.shape == (many.shape[1],)
    np.testing.assert_array_equal(one, many[0])
    values, found = brickmap.lookup(list(map(float, p)), normals=tuple(n),
                                    return_found=True)
    assert found is True
    np.testing.assert_array_equal(values, many[0])
    with pytest.raises(ValueError, match="3 numbers"):
        brickmap.lookup([1.0, 2.0])


def test_one_normal_for_every_point(sphere, brickmap):
    cloud = sss.read_cloud(sphere)
    n = np.array([0.0, 0.0, 1.0], np.float32)
    a = brickmap.lookup(cloud["P"][:50], normals=n)
    b = brickmap.lookup(cloud["P"][:50], normals=np.tile(n, (50, 1)))
    np.testing.assert_array_equal(a, b)


def test_brickmap_lookup_of_a_list_of_channels(sphere, brickmap):
    cloud = sss.read_cloud(sphere)
    pts, nrm = cloud["P"][:100], cloud["N"][:100]
    area = brickmap.lookup(pts, "_area", normals=nrm)
    radiance = brickmap.lookup(pts, "_radiance_t", normals=nrm)
    both = brickmap.lookup(pts, ["_radiance_t", "_area"], normals=nrm)
    np.testing.assert_array_equal(both, np.hstack([radiance, area]))
    with pytest.raises(sss.ValueError, match="no channel 'nope'"):
        brickmap.lookup(pts, ["_area", "nope"])

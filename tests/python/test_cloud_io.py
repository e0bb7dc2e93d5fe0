# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Reading and writing .ptc/.ply clouds as dicts of numpy arrays."""

import gzip
import os

import numpy as np
import pytest

import sss

TYPES = {"float": (), "color": (3,), "point": (3,), "vector": (3,), "normal": (3,),
         "matrix": (4, 4)}


def every_type_cloud(n=257, seed=3):
    rng = np.random.default_rng(seed)
    cloud = sss.Cloud()
    cloud["P"] = rng.normal(size=(n, 3)).astype(np.float32)
    # .ptc stores unit normals (16-bit codes, docs/file-formats.md): the
    # normals are ones the format holds exactly, taken from a first write.
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    normals[::7] = 0  # points without a normal
    cloud["N"] = normals
    cloud["radius"] = rng.uniform(0.01, 0.1, size=n).astype(np.float32)
    for name, shape in TYPES.items():
        cloud["my_" + name] = rng.normal(size=(n, *shape)).astype(np.float32)
        cloud.types["my_" + name] = name
    cloud.world_to_eye = np.arange(16, dtype=np.float32).reshape(4, 4)
    cloud.world_to_ndc = np.eye(4, dtype=np.float32) * 2
    cloud.format = (640.0, 480.0, 1.5)
    return cloud


def quantised_normals(cloud, tmp_path):
    sss.write_cloud(tmp_path / "normals.ptc", {"P": cloud["P"], "N": cloud["N"]})
    cloud["N"] = sss.read_cloud(tmp_path / "normals.ptc")["N"]
    (tmp_path / "normals.ptc").unlink()
    return cloud


def assert_same(a, b):
    assert list(a.keys()) == list(b.keys())
    for key in a:
        assert a[key].dtype == np.float32
        assert a[key].shape == b[key].shape, key
        assert np.array_equal(a[key], b[key]), key
    assert a.types == b.types


@pytest.mark.parametrize("name,options", [
    ("v0.ptc", {}),
    ("v1.ptc", {"ptcversion": 1}),
    ("v2.ptc", {"ptcversion": 2}),
    ("v0gz.ptc", {"compress": True}),
    ("v2gz.ptc", {"ptcversion": 2, "compress": True}),
    ("cloud.ply", {}),
])
def test_round_trip_every_channel_type(tmp_path, name, options):
    cloud = quantised_normals(every_type_cloud(), tmp_path)
    path = tmp_path / name
    sss.write_cloud(path, cloud, **options)
    back = sss.read_cloud(path)
    assert_same(back, cloud)
    assert back.types == {"my_" + t: t for t in TYPES}
    assert np.array_equal(back.world_to_eye, cloud.world_to_eye)
    assert np.array_equal(back.world_to_ndc, cloud.world_to_ndc)
    assert back.format == cloud.format
    if name.endswith(".ptc"):
        assert back.file_version == options.get("ptcversion", 0)
        assert back.compressed == options.get("compress", False)
        with open(path, "rb") as f:
            assert (f.read(2) == b"\x1f\x8b") == options.get("compress", False)


def test_matches_ptinfo(tool, sphere):
    cloud = sss.read_cloud(sphere)
    info = tool("ptinfo", sphere).stdout
    assert f"points: {cloud.size}" in info.splitlines()
    assert cloud.types == {"_area": "float", "_radiance_t": "color"}
    # ptsynth: the areas add up to the sphere's area (radius 2).
    assert cloud["_area"].sum(dtype=np.float64) == pytest.approx(4 * np.pi * 4, rel=1e-3)
    assert np.allclose(np.linalg.norm(cloud["P"], axis=1), 2.0, rtol=1e-5)


def test_read_is_zero_copy(sphere):
    cloud = sss.read_cloud(sphere)
    for key, array in cloud.items():
        # The array views memory the library read into, owned by a capsule.
        assert not array.flags["OWNDATA"], key
        assert type(array.base).__name__ == "PyCapsule", key
        assert array.flags["C_CONTIGUOUS"] and array.flags["WRITEABLE"]


def test_write_plain_dict_infers_types_and_converts(tmp_path):
    n = 10
    d = {"P": np.arange(3 * n, dtype=np.float64).reshape(n, 3),  # converted to float32
         "radius": np.full(n, 0.5),
         "a": np.ones(n), "c": np.ones((n, 3)), "m": np.ones((n, 16))}
    sss.write_cloud(tmp_path / "d.ptc", d)
    back = sss.read_cloud(tmp_path / "d.ptc")
    assert back.types == {"a": "float", "c": "color", "m": "matrix"}
    assert back["m"].shape == (n, 4, 4)
    assert np.array_equal(back["N"], np.zeros((n, 3), np.float32))
    assert np.array_equal(back["P"], d["P"].astype(np.float32))


def test_empty_cloud_round_trip(tmp_path):
    cloud = sss.Cloud({"P": np.zeros((0, 3), np.float32), "c": np.zeros((0, 3))},
                      types={"c": "normal"})
    sss.write_cloud(tmp_path / "e.ptc", cloud)
    back = sss.read_cloud(tmp_path / "e.ptc")
    assert back.size == 0 and back.types == {"c": "normal"}


def test_missing_file():
    with pytest.raises(sss.IoError) as e:
        sss.read_cloud("/nonexistent/cloud.ptc")
    assert isinstance(e.value, OSError) and isinstance(e.value, sss.Error)
    assert "/nonexistent/cloud.ptc" in str(e.value)
    assert e.value.path == "/nonexistent/cloud.ptc"


def test_truncated_file(tmp_path, sphere):
    data = open(sphere, "rb").read()
    bad = tmp_path / "truncated.ptc"
    bad.write_bytes(data[: len(data) * 2 // 3])
    with pytest.raises(sss.FormatError) as e:
        sss.read_cloud(bad)
    assert isinstance(e.value, ValueError)
    assert str(bad) in str(e.value) and e.value.path == str(bad)


def test_corrupt_file(tmp_path, sphere, tool):
    bad = tmp_path / "corrupt.ptc"
    bad.write_bytes(b"not a point cloud" + open(sphere, "rb").read()[17:])
    with pytest.raises(sss.FormatError) as e:
        sss.read_cloud(bad)
    # The message is the library's: the one ptinfo prints.
    result = tool("ptinfo", bad, check=False)
    assert result.returncode == 1
    assert str(e.value) in result.stderr


def test_nan_in_file_names_the_point(tmp_path, sphere):
    cloud = sss.read_cloud(sphere)
    # Write a valid file, then poke a NaN into the 5th point's radius bytes.
    path = tmp_path / "nan.ply"
    sss.write_cloud(path, cloud)
    data = bytearray(path.read_bytes())
    header_end = data.index(b"end_header\n") + len(b"end_header\n")
    record = 4 * (7 + 1 + 3)
    offset = header_end + 4 * record + 6 * 4
    data[offset:offset + 4] = np.float32(np.nan).tobytes()
    path.write_bytes(bytes(data))
    with pytest.raises(sss.FormatError) as e:
        sss.read_cloud(path)
    assert e.value.point == 4


def test_gzip_truncated(tmp_path, sphere):
    bad = tmp_path / "trunc_gz.ptc"
    bad.write_bytes(gzip.compress(open(sphere, "rb").read())[:5000])
    with pytest.raises(sss.FormatError):
        sss.read_cloud(bad)


def test_write_errors(tmp_path):
    n = 4
    ok = {"P": np.zeros((n, 3)), "radius": np.ones(n)}
    with pytest.raises(sss.ValueError, match="NaN|finite|nan"):
        sss.write_cloud(tmp_path / "nan.ptc", {**ok, "c": np.full(n, np.nan)})
    with pytest.raises(ValueError, match=r"cloud\['c'\]: expected 4 rows of 3 values"):
        sss.write_cloud(tmp_path / "shape.ptc", {**ok, "c": np.ones((n, 2))},
                        types={"c": "color"})
    with pytest.raises(sss.ValueError, match="unknown type 'colour'"):
        sss.write_cloud(tmp_path / "t.ptc", {**ok, "c": np.ones((n, 3))},
                        types={"c": "colour"})
    with pytest.raises(sss.ValueError, match="'P'"):
        sss.write_cloud(tmp_path / "p.ptc", {"radius": np.ones(n)})
    with pytest.raises(sss.IoError):
        sss.write_cloud("/nonexistent/dir/x.ptc", ok)
    # Nothing is left behind by the failed writes (atomic output).
    assert os.listdir(tmp_path) == []


def test_names_that_cannot_be_read_back_are_refused(tmp_path):
    n = 4
    cloud = {"P": np.zeros((n, 3), np.float32)}
    # A NUL would cut the path: "x\0y.ptc" must not write "x".
    for path in (str(tmp_path / "x\0y.ptc"), str(tmp_path / "x\0y.ply")):
        with pytest.raises(sss.ValueError, match="a file name cannot hold a NUL byte"):
            sss.write_cloud(path, cloud)
    assert os.listdir(tmp_path) == []
    with pytest.raises(sss.ValueError, match="NUL"):
        sss.read_cloud(str(tmp_path / "x\0y.ptc"))
    # The .ptc reader takes channel spec lines of at most 4095 bytes.
    for name, ok in (("c" * 4089, True), ("c" * 4090, False), ("c" * 5001, False)):
        path = tmp_path / "long.ptc"
        if ok:
            sss.write_cloud(path, {**cloud, name: np.ones(n, np.float32)})
            assert name in sss.read_cloud(path)
            continue
        with pytest.raises(sss.ValueError, match=r"is %d bytes long: a float channel's name may "
                                                 r"have at most 4089" % len(name)):
            sss.write_cloud(tmp_path / "bad.ptc", {**cloud, name: np.ones(n, np.float32)})
        assert not (tmp_path / "bad.ptc").exists()
    with pytest.raises(sss.ValueError, match="whitespace or control"):
        sss.write_cloud(tmp_path / "nul.ptc", {**cloud, "a\0b": np.ones(n, np.float32)})

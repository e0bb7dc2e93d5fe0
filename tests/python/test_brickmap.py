# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Brick maps from Python: building (brickmake) and texture3d lookups."""

import numpy as np
import pytest

import sss


@pytest.fixture(scope="module")
def diffused(tmp_path_factory, sphere):
    path = tmp_path_factory.mktemp("bkm") / "diffused.ptc"
    sss.ptfilter(sphere, path)
    return str(path)


@pytest.fixture(scope="module")
def maps(tmp_path_factory, tool, diffused):
    folder = tmp_path_factory.mktemp("maps")
    exe, py = folder / "exe.bkm", folder / "py.bkm"
    tool("brickmake", "-maxerror", 0.001, "-maxdepth", 8, diffused, exe)
    report = sss.make_brickmap(diffused, py, maxerror=0.001, maxdepth=8)
    return str(exe), str(py), report


def test_same_map_as_brickmake(maps, diffused, tool):
    exe, py, report = maps
    a, b = sss.BrickMap(exe), sss.BrickMap(py)
    assert report["points"] == sss.read_cloud(diffused).size
    assert report["bricks"] == a.info["total_bricks"] == b.info["total_bricks"]
    for key in ("channels", "total_samples", "cube_side", "max_depth", "bbox_min"):
        assert a.info[key] == b.info[key], key
    assert a.info["provenance"].startswith("brickmake")
    assert b.info["provenance"].startswith("sss.make_brickmap (Python)")
    assert "-maxerror 0.001" in b.info["provenance"]
    assert b.verify() == a.verify() > 0
    # brickinfo reads the module's map.
    assert "bricks" in tool("brickinfo", py).stdout


def test_lookup_many_points(maps, diffused):
    exe, py, _ = maps
    cloud = sss.read_cloud(diffused)
    bkm = sss.BrickMap(py)
    values, found = bkm.lookup(cloud["P"], "_ssdiffusion", normals=cloud["N"],
                               return_found=True)
    assert values.shape == (cloud.size, 3) and values.dtype == np.float32
    assert found.all()
    # Same lookups in the brickmake map, bit for bit.
    assert np.array_equal(values, sss.BrickMap(exe).lookup(cloud["P"], "_ssdiffusion",
                                                            normals=cloud["N"]))
    # The map reproduces the cloud's values (maxerror 0.001 plus interpolation).
    err = np.abs(values - cloud["_ssdiffusion"])
    assert np.sqrt(np.mean(err ** 2)) < 0.01 * np.abs(cloud["_ssdiffusion"]).max()
    # Every channel at once; a per-point filter radius; thread-count independence.
    all_channels = bkm.lookup(cloud["P"], normals=cloud["N"], threads=1)
    assert all_channels.shape == (cloud.size, bkm.info["data_size"])
    assert np.array_equal(all_channels[:, :3], values)
    radii = np.full(cloud.size, 0.2, np.float32)
    blurred_1 = bkm.lookup(cloud["P"], "_ssdiffusion", normals=cloud["N"],
                           filterradius=radii, threads=1)
    blurred_2 = bkm.lookup(cloud["P"], "_ssdiffusion", normals=cloud["N"],
                           filterradius=0.2, threads=2)
    assert np.array_equal(blurred_1, blurred_2)
    assert not np.array_equal(blurred_1, values)


def test_lookup_misses_and_errors(maps):
    bkm = sss.BrickMap(maps[1])
    far = np.array([[100.0, 100.0, 100.0]])
    values, found = bkm.lookup(far, "_ssdiffusion", normals=[[0, 0, 1]],
                               return_found=True)
    assert not found[0] and np.array_equal(values, np.zeros((1, 3), np.float32))
    with pytest.raises(sss.ValueError, match="no channel 'albedo'.*_ssdiffusion"):
        bkm.lookup(far, "albedo")
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        bkm.lookup(np.zeros((4, 2)), "_ssdiffusion")


def test_build_from_clouds_in_memory(tmp_path, diffused, maps):
    cloud = sss.read_cloud(diffused)
    sss.make_brickmap(cloud, tmp_path / "mem.bkm", maxerror=0.001, maxdepth=8,
                      channels=["_ssdiffusion"])
    mem = sss.BrickMap(tmp_path / "mem.bkm")
    assert mem.channels == [("_ssdiffusion", "color")]
    pts = cloud["P"][:100]
    assert np.array_equal(mem.lookup(pts, "_ssdiffusion", normals=cloud["N"][:100]),
                          sss.BrickMap(maps[1]).lookup(pts, "_ssdiffusion",
                                                       normals=cloud["N"][:100]))


def test_progress_and_bad_options(tmp_path, diffused):
    seen = []
    sss.make_brickmap(diffused, tmp_path / "p.bkm", progress=lambda d, t: seen.append(d / t))
    assert seen and seen[-1] == 1.0
    with pytest.raises(sss.UsageError, match="option -maxdepth"):
        sss.make_brickmap(diffused, tmp_path / "x.bkm", maxdepth=30)
    with pytest.raises(sss.UsageError, match="unknown keyword 'maxerr'"):
        sss.make_brickmap(diffused, tmp_path / "x.bkm", maxerr=0.1)
    with pytest.raises(sss.ValueError):
        sss.make_brickmap(diffused, tmp_path / "x.bkm", channels=["nothere"])
    assert not (tmp_path / "x.bkm").exists()


def test_callback_exception_cancels_the_build(tmp_path, diffused):
    def stop(done, total):
        if done * 2 >= total:
            raise RuntimeError("halfway")

    with pytest.raises(RuntimeError, match="halfway"):
        sss.make_brickmap(diffused, tmp_path / "c.bkm", maxerror=0.0001, progress=stop)
    assert not (tmp_path / "c.bkm").exists()
    # The next build works.
    sss.make_brickmap(diffused, tmp_path / "c.bkm")
    assert sss.BrickMap(tmp_path / "c.bkm").verify() > 0


def test_bad_brickmap_files(tmp_path, maps):
    with pytest.raises(sss.IoError):
        sss.BrickMap(tmp_path / "missing.bkm")
    data = open(maps[1], "rb").read()
    (tmp_path / "trunc.bkm").write_bytes(data[: len(data) // 2])
    with pytest.raises(sss.FormatError):
        sss.BrickMap(tmp_path / "trunc.bkm")
    corrupt = bytearray(data)
    corrupt[100] ^= 0xFF
    (tmp_path / "corrupt.bkm").write_bytes(bytes(corrupt))
    with pytest.raises(sss.FormatError):
        sss.BrickMap(tmp_path / "corrupt.bkm").verify()
    (tmp_path / "cloud.bkm").write_bytes(b"ptc not a bkm" * 10)
    with pytest.raises(sss.FormatError):
        sss.BrickMap(tmp_path / "cloud.bkm")

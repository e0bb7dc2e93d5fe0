# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""sss.PointCloudLookup, texture3d on a point cloud (docs/python.md): the
values and "found" flags of the renderer's own call
(sss::TextureLibrary::texture3d, run as tests/python/texture3d_reference.cpp)
bit for bit, near and far from the data, with and without normals and filter
radii; one point at a time; any thread count; from a file or a Cloud."""

import os
import subprocess
import threading
import time

import numpy as np
import pytest

import sss


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """reference(texture, P, N, radius, channels) -> (values, found) as the
    renderer's texture3d computes them."""
    folder = tmp_path_factory.mktemp("reference")
    program = os.path.join(os.environ["SSS_TEST_BIN_DIR"], "sss_texture3d_reference")

    def run(texture, P, N, radius, channels):
        # .ply keeps normals exactly (.ptc stores them as 16-bit codes).
        queries, out = str(folder / "queries.ply"), str(folder / "out.ply")
        sss.write_cloud(queries, {"P": P, "N": N, "radius": radius})
        subprocess.run([program, texture, queries, out, *channels], check=True,
                       capture_output=True, text=True)
        result = sss.read_cloud(out)
        names = [c for c in result.channels if c.startswith("_v")]
        values = np.stack([result[c] for c in names], axis=1)
        return values, result["_found"] == 1.0

    return run


@pytest.fixture(scope="module")
def queries(sphere):
    """Points on, near, inside and far from the sphere; the surface's normals,
    flipped ones and none; filter radii 0, small and large."""
    cloud = sss.read_cloud(sphere)
    rng = np.random.default_rng(5)
    n = 600
    pick = rng.integers(0, cloud.size, n)
    P = cloud["P"][pick] * rng.uniform(0.9, 1.1, (n, 1)).astype(np.float32)
    P[:40] *= 3.0  # far outside: misses
    P[40:60] = rng.uniform(-0.2, 0.2, (20, 3))  # deep inside the sphere
    N = cloud["N"][pick].copy()
    N[100:150] *= -1.0  # the other side: no agreeing normals
    N[150:220] = 0.0  # no normal: every side
    radius = np.zeros(n, np.float32)
    radius[300:400] = 0.05
    radius[400:450] = 5.0  # widens "near" to the far points too
    P[400:420] *= 1.5
    return P.astype(np.float32), N.astype(np.float32), radius


def test_matches_the_renderers_texture3d(sphere, reference, queries):
    P, N, radius = queries
    lookup = sss.PointCloudLookup(sphere)
    for channels in (["_radiance_t"], ["_area", "_radiance_t"]):
        want, want_found = reference(sphere, P, N, radius, channels)
        got, found = lookup.lookup(P, channels, normals=N, filterradius=radius,
                                   return_found=True)
        np.testing.assert_array_equal(found, want_found)
        np.testing.assert_array_equal(got[found], want[found])
        assert not got[~found].any(), "misses are 0"
    # The queries cover both cases.
    assert 0 < found.sum() < len(found)
    assert found[400:420].all() and not found[:40].any()


def test_every_channel_by_default_and_by_name(sphere):
    lookup = sss.PointCloudLookup(sphere)
    assert lookup.channels == [("_area", "float"), ("_radiance_t", "color")]
    assert lookup.size == sss.read_cloud(sphere).size
    cloud = sss.read_cloud(sphere)
    P, N = cloud["P"][:64], cloud["N"][:64]
    all_ = lookup.lookup(P, normals=N)
    assert all_.shape == (64, 4)
    np.testing.assert_array_equal(all_[:, :1], lookup.lookup(P, "_area", normals=N))
    np.testing.assert_array_equal(all_[:, 1:], lookup.lookup(P, "_radiance_t", normals=N))


def test_a_point_on_the_cloud_gives_nearly_its_value(sphere):
    cloud = sss.read_cloud(sphere)
    lookup = sss.PointCloudLookup(sphere)
    values, found = lookup.lookup(cloud["P"], "_radiance_t", normals=cloud["N"],
                                  return_found=True)
    assert found.all()
    # An average of the nearest points: close to the point's own value.
    error = np.abs(values - cloud["_radiance_t"]).mean()
    assert error < 0.05 * np.abs(cloud["_radiance_t"]).mean()


def test_single_point(sphere, queries):
    P, N, radius = queries
    lookup = sss.PointCloudLookup(sphere)
    many, found = lookup.lookup(P[:5], normals=N[:5], return_found=True)
    for i in range(5):
        one, hit = lookup.lookup(P[i].tolist(), normals=N[i], return_found=True)
        assert one.shape == (4,) and hit is bool(found[i])
        np.testing.assert_array_equal(one, many[i])


def test_thread_count_does_not_change_values(sphere, queries):
    P, N, radius = queries
    lookup = sss.PointCloudLookup(sphere)
    big = np.tile(P, (8, 1))
    big_n = np.tile(N, (8, 1))
    a = lookup.lookup(big, normals=big_n, threads=1)
    b = lookup.lookup(big, normals=big_n, threads=2)
    np.testing.assert_array_equal(a, b)


def test_from_a_cloud_as_from_its_file(sphere, queries):
    P, N, radius = queries
    from_file = sss.PointCloudLookup(sphere).lookup(P, normals=N, filterradius=radius)
    from_cloud = sss.PointCloudLookup(sss.read_cloud(sphere)).lookup(
        P, normals=N, filterradius=radius)
    np.testing.assert_array_equal(from_file, from_cloud)
    assert "sss.PointCloudLookup(a Cloud;" in repr(sss.PointCloudLookup(
        sss.read_cloud(sphere)))


def test_lookups_release_the_gil(sphere):
    lookup = sss.PointCloudLookup(sphere)
    P = np.random.default_rng(1).uniform(-1, 1, (400_000, 3)).astype(np.float32)
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    start = time.perf_counter()
    lookup.lookup(P, threads=1)
    end = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if start < x < end]
    assert end - start < 0.05 or len(during) >= 5, (end - start, len(during))


def test_errors(tmp_path, sphere):
    with pytest.raises(FileNotFoundError):
        sss.PointCloudLookup(str(tmp_path / "missing.ptc"))
    lookup = sss.PointCloudLookup(sphere)
    with pytest.raises(sss.ValueError, match="no channel '_nope'.*_area, _radiance_t"):
        lookup.lookup([[0, 0, 0]], "_nope")
    with pytest.raises(sss.ValueError, match=r"\(N, 3\)"):
        lookup.lookup(np.zeros((4, 2)))
    with pytest.raises(sss.ValueError, match="normals"):
        lookup.lookup(np.zeros((4, 3)), normals=np.zeros((3, 3)))

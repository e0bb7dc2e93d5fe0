# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""sss.ssdiffusion / sss.ptfilter against the ptfilter executable."""

import threading

import numpy as np
import pytest

import sss

# (keyword options, the same options as ptfilter words)
CASES = [
    ({}, []),
    ({"material": "skin1", "unitlength": 0.1, "maxsolidangle": 0.5},
     ["-material", "skin1", "-unitlength", "0.1", "-maxsolidangle", "0.5"]),
    ({"albedo": (0.8, 0.6, 0.4), "diffusemeanfreepath": (1.5, 0.7, 0.3), "ior": 1.4,
      "profile": "burley", "criterion": "bbox"},
     ["-albedo", "0.8", "0.6", "0.4", "-diffusemeanfreepath", "1.5", "0.7", "0.3",
      "-ior", "1.4", "-profile", "burley", "-criterion", "bbox"]),
    ({"scattering": [2.0, 2.5, 3.0], "absorption": np.array([0.01, 0.02, 0.03]),
      "profile": "better", "criterion": "centroid", "keepchannels": True, "isa": "x86-64"},
     ["-scattering", "2", "2.5", "3", "-absorption", "0.01", "0.02", "0.03",
      "-profile", "better", "-criterion", "centroid", "-keepchannels", "1",
      "-isa", "x86-64"]),
    ({"exact": True, "material": "ketchup", "unitlength": 0.3},
     ["-exact", "-material", "ketchup", "-unitlength", "0.3"]),
    ({"material": "skin1", "unitlength": 0.1, "profile": "pbd"},
     ["-material", "skin1", "-unitlength", "0.1", "-profile", "pbd"]),
    ({"albedo": (0.8, 0.6, 0.4), "diffusemeanfreepath": (1.5, 0.7, 0.3), "profile": "mc"},
     ["-albedo", "0.8", "0.6", "0.4", "-diffusemeanfreepath", "1.5", "0.7", "0.3",
      "-profile", "mc"]),
    ({"material": "skin1", "profile": "pbd", "volume": 1},
     ["-material", "skin1", "-profile", "pbd", "-volume", "1"]),
    ({"material": "skin1", "volume": 1, "incidence": "diffuse"},
     ["-material", "skin1", "-volume", "1", "-incidence", "diffuse"]),
]


def assert_clouds_identical(a, b):
    assert list(a.keys()) == list(b.keys())
    assert a.types == b.types
    for key in a:
        # Exactly, bit for bit (NaN never appears).
        assert a[key].tobytes() == b[key].tobytes(), key


@pytest.mark.parametrize("options,words", CASES)
def test_bit_identical_to_ptfilter(tmp_path, tool, sphere, options, words):
    out = tmp_path / "exe.ptc"
    tool("ptfilter", "-ssdiffusion", *words, sphere, out)
    expected = sss.read_cloud(out)
    # From a Cloud in memory, and from the file name.
    got = sss.ssdiffusion(sss.read_cloud(sphere), **options)
    assert_clouds_identical(got, expected)
    assert_clouds_identical(sss.ssdiffusion(sphere, threads=1, **options), expected)
    # ptfilter() writes the executable's file byte for byte.
    sss.ptfilter(sphere, tmp_path / "py.ptc", **options)
    assert (tmp_path / "py.ptc").read_bytes() == out.read_bytes()
    # The result is diffused light: positive, finite, not the input.
    d = got["_ssdiffusion"]
    assert np.isfinite(d).all() and d.max() > 0


def test_merged_inputs_and_write_options(tmp_path, tool, sphere):
    other = tmp_path / "plane.ptc"
    tool("ptsynth", "-shape", "plane", "-n", 500, "-size", 3, other)
    out = tmp_path / "exe.ptc"
    tool("ptfilter", "-ssdiffusion", "-compress", "1", "-ptcversion", "2", sphere, other,
         out)
    sss.ptfilter([sphere, other], tmp_path / "py.ptc", compress=True, ptcversion=2)
    assert (tmp_path / "py.ptc").read_bytes() == out.read_bytes()
    assert_clouds_identical(sss.ssdiffusion([sphere, str(other)]), sss.read_cloud(out))


def test_frame_pattern_in_ptfilter(tmp_path, sphere):
    import shutil
    shutil.copy(sphere, tmp_path / "in.0042.ptc")
    sss.ptfilter(str(tmp_path / "in.####.ptc"), str(tmp_path / "out.$F4.ptc"), frame=42)
    assert (tmp_path / "out.0042.ptc").exists()
    with pytest.raises(sss.UsageError, match="frame pattern"):
        sss.ptfilter(str(tmp_path / "in.####.ptc"), str(tmp_path / "o.ptc"))


def test_thread_count_does_not_change_result(sphere):
    one = sss.ssdiffusion(sphere, threads=1, maxsolidangle=0.3)
    two = sss.ssdiffusion(sphere, threads=2, maxsolidangle=0.3)
    assert_clouds_identical(one, two)


def test_progress_callback(sphere):
    seen = []
    sss.ssdiffusion(sphere, progress=lambda done, total: seen.append((done, total)))
    percents = [d * 100 // t for d, t in seen]
    assert len(seen) >= 2
    assert percents == sorted(percents) and len(set(percents)) == len(percents)
    assert percents[-1] == 100


def test_callback_exception_cancels(sphere, tmp_path):
    class Stop(Exception):
        pass

    calls = []

    def stop(done, total):
        calls.append(done)
        if done * 100 // total >= 10:
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        sss.ssdiffusion(sphere, progress=stop, maxsolidangle=0.1)
    # Cancelled at the first call past 10 %: no further calls.
    assert calls[-1] * 100 // 3000 < 100
    out = tmp_path / "cancelled.ptc"
    with pytest.raises(Stop):
        sss.ptfilter(sphere, out, progress=stop)
    assert not out.exists()
    # The module is usable afterwards.
    assert sss.ssdiffusion(sphere).size > 0


def test_gil_released_during_diffusion(tool, tmp_path):
    big = tmp_path / "big.ptc"
    tool("ptsynth", "-n", 100000, big)
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(1)
            stop.wait(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    try:
        sss.ssdiffusion(str(big), threads=1, maxsolidangle=0.3)
    finally:
        stop.set()
        t.join()
    # The other thread ran while the diffusion was computing.
    assert len(ticks) > 20


def ptfilter_error(tool, sphere, tmp_path, words):
    result = tool("ptfilter", "-ssdiffusion", *words, sphere, tmp_path / "o.ptc",
                  check=False)
    assert result.returncode in (1, 2)
    return result.stderr.splitlines()[0].removeprefix("ptfilter ERROR: ")


@pytest.mark.parametrize("options,words,error", [
    ({"material": "plastic"}, ["-material", "plastic"], sss.UsageError),
    ({"unitlength": -1.0}, ["-unitlength", "-1"], sss.UsageError),
    ({"maxsolidangle": float("nan")}, ["-maxsolidangle", "nan"], sss.UsageError),
    ({"profile": "gaussian"}, ["-profile", "gaussian"], sss.UsageError),
    ({"criterion": "fast"}, ["-criterion", "fast"], sss.UsageError),
    ({"isa": "neon"}, ["-isa", "neon"], sss.UsageError),
])
def test_bad_options_match_ptfilter(tool, sphere, tmp_path, options, words, error):
    with pytest.raises(error) as e:
        sss.ssdiffusion(sphere, **options)
    assert isinstance(e.value, ValueError) and isinstance(e.value, sss.Error)
    assert str(e.value) == ptfilter_error(tool, sphere, tmp_path, words)


def test_material_errors_in_keyword_words(tool, sphere, tmp_path):
    # ptfilter names its options ("-albedo"); the module the keywords.
    with pytest.raises(sss.ValueError) as e:
        sss.ssdiffusion(sphere, albedo=(1.5, 0.5, 0.5))
    assert str(e.value) == "impossible albedo value 1.500000"
    assert ptfilter_error(tool, sphere, tmp_path, ["-albedo", "1.5", "0.5", "0.5"]) == \
        "impossible -albedo value 1.500000"
    with pytest.raises(sss.UsageError, match="given both as scattering/absorption"):
        sss.ssdiffusion(sphere, albedo=(0.5, 0.5, 0.5), scattering=(1, 1, 1))


def test_unknown_keyword():
    with pytest.raises(sss.UsageError, match="unknown keyword 'maxsolidanlge'"):
        sss.ssdiffusion({"P": np.zeros((1, 3))}, maxsolidanlge=1)


def test_missing_channel_names_the_keyword(sphere):
    with pytest.raises(sss.ValueError) as e:
        sss.ssdiffusion(sphere, radiancechannel="_irradiance")
    assert "input has no channel '_irradiance' (set it with radiancechannel=" in str(e.value)
    assert "color _radiance_t" in str(e.value)
    cloud = sss.read_cloud(sphere)
    with pytest.raises(sss.ValueError, match="albedo='fromfile'"):
        sss.ssdiffusion(cloud, albedo="fromfile")


def test_bad_input_files(tmp_path, sphere):
    with pytest.raises(sss.IoError):
        sss.ssdiffusion(str(tmp_path / "missing.ptc"))
    bad = tmp_path / "bad.ptc"
    bad.write_bytes(open(sphere, "rb").read()[:1000])
    with pytest.raises(sss.FormatError):
        sss.ssdiffusion(str(bad))
    with pytest.raises(sss.FormatError):
        sss.ptfilter(str(bad), tmp_path / "o.ptc")
    assert not (tmp_path / "o.ptc").exists()


def test_negative_area_in_memory(sphere):
    cloud = sss.read_cloud(sphere)
    cloud["_area"][3] = -1.0
    with pytest.raises(sss.Error, match="cloud: "):
        sss.ssdiffusion(cloud)


@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_cancels(tool, tmp_path, threads):
    import os
    import signal
    import time

    big = tmp_path / "big.ptc"
    tool("ptsynth", "-n", 300000, big)
    cloud = sss.read_cloud(big)
    start = time.perf_counter()
    sss.ssdiffusion(cloud, threads=threads, maxsolidangle=0.1)
    whole = time.perf_counter() - start
    # The signal comes a third of the way through a run as long.
    timer = threading.Timer(whole / 3, os.kill, (os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sss.ssdiffusion(cloud, threads=threads, maxsolidangle=0.1)
    finally:
        timer.cancel()
        timer.join()
    interrupted = time.perf_counter() - start
    # The run stopped well before its end.
    assert whole > 0.1 and interrupted < 0.7 * whole


def test_volume_with_blockers_as_ptfilter(tmp_path, tool, sphere):
    # Two small balls inside the 2 mm sphere, given as a list: one -blocker each.
    blockers = []
    for i in range(2):
        path = tmp_path / f"bone{i}.ptc"
        tool("ptsynth", "-n", 500, "-size", 0.4, path)
        blockers.append(str(path))
    out = tmp_path / "exe.ptc"
    tool("ptfilter", "-ssdiffusion", "-material", "skin1", "-blocker", blockers[0],
         "-blocker", blockers[1], sphere, out)
    got = sss.ssdiffusion(sphere, material="skin1", blocker=blockers)
    assert_clouds_identical(got, sss.read_cloud(out))
    volume = got.report["volume"]
    assert volume["thin_points"] > 0 and volume["unknowns"] > 0
    assert all(b > 0 for b in volume["flux_blocked"])
    assert all(o <= i for o, i in zip(volume["flux_out"], volume["flux_in"]))
    assert all(0.2 <= lo <= hi <= 5 for lo, hi in
               zip(volume["transmission_min"], volume["transmission_max"]))


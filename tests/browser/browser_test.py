#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""ptview -serve in a real browser: Debian's headless Chromium driven through
chromedriver (tests/browser/webdriver.py). Run by
tests/cli/test_ptview_serve_browser.sh (CTest: cli.test_ptview_serve_browser).

    browser_test.py BIN_DIR WORK_DIR [SCREENSHOT_DIR]

Checks, on a 200k-point bake (ptsynth) and the quick teapot bake (ptbake,
with its camera) with its brick map:
  - the page loads without a console error and draws a non-blank picture;
  - dragging the mean free path slider changes the live diffusion's
    picture, within 0.5 s of the release (the whole cloud; and each preview
    on the subsample while dragging), measured in the page;
  - the command line the page shows reproduces the values it shows: Save
    writes them (their hash is the one the page computed of what it drew),
    and running the command writes the same file, byte for byte;
  - dragging on the picture orbits;
  - the page's picture of that state matches `ptview` of the same state (the
    batch command the page shows) within the tolerance of docs/ptview.md;
  - a turntable's frames are ptview's pictures of the orbit, and a video;
  - the bake camera's view, brick-map voxels, overlaid clouds, no console
    error; the server stopped by its PID.
SCREENSHOT_DIR: where the page's screenshots go (docs/images/ when the
documentation's are made again: scripts/ptview-pictures --serve).
"""
import atexit
import os
import re
import shlex
import signal
import statistics
import subprocess
import sys
import time
import base64

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from webdriver import Browser  # noqa: E402

# The page against ptview (docs/ptview.md, "Interactive view"): the mean
# absolute difference per channel, and the share of pixels more than 8/255
# apart (the rim of the silhouette, where single and double precision put a
# disc's edge on either side of a pixel centre).
MEAN_TOLERANCE = 1.0
FAR_TOLERANCE = 0.01
LATENCY_LIMIT_MS = 500.0
BACKGROUND = (63, 63, 63)  # ptview's background, linear 0.05, in sRGB

BIN, WORK = sys.argv[1], sys.argv[2]
SHOTS = sys.argv[3] if len(sys.argv) > 3 else os.path.join(WORK, "screenshots")
SANITIZED = os.environ.get("SSS_SANITIZED") == "1"
started = time.time()


def log(text):
    print(f"[{time.time() - started:5.1f} s] {text}", flush=True)


def fail(text):
    print(f"FAIL: {text}", file=sys.stderr, flush=True)
    sys.exit(1)


def tool(name, *args, cwd=None):
    r = subprocess.run([os.path.join(BIN, name), *args], cwd=cwd or WORK,
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        fail(f"{name} {' '.join(args)}: exit {r.returncode}: {r.stderr.strip()}")
    return r.stdout


RUNNING = []


@atexit.register
def stop_servers():
    """Servers a failed check left running."""
    for p in RUNNING:
        if p.poll() is None:
            p.kill()
            p.wait()


class Server:
    """ptview -serve on a free port, stopped by its PID."""

    def __init__(self, *args):
        self.out = open(os.path.join(WORK, f"serve{len(args)}.log"), "w+")
        self.process = subprocess.Popen([os.path.join(BIN, "ptview"), "-serve", "-port", "0", *args],
                                        cwd=WORK, stdout=subprocess.PIPE, stderr=self.out, text=True)
        RUNNING.append(self.process)
        line = self.process.stdout.readline()
        m = re.search(r" at (http://127\.0\.0\.1:\d+/)", line)
        if not m:
            self.stop()
            fail(f"ptview -serve printed no address: {line!r}; stderr: {open(self.out.name).read()}")
        self.url = m.group(1)
        log(f"ptview -serve {' '.join(args)}: {self.url} (pid {self.process.pid})")

    def stop(self):
        os.kill(self.process.pid, signal.SIGTERM)
        try:
            self.process.wait(10)
        except subprocess.TimeoutExpired:
            fail("ptview -serve did not stop on SIGTERM")
        if self.process.returncode not in (0, -signal.SIGTERM, 128 + signal.SIGTERM):
            fail(f"ptview -serve exited with {self.process.returncode}")


# Pictures are compared in the page: the browser decodes PNG files (without
# colour conversion) and reads its own canvas back, so that the test needs no
# image library. A picture is "canvas" or the base64 of a PNG file.
PIXELS_JS = """
window.sssPixels = async (picture) => {
  if (picture === 'canvas') {
    const c = document.getElementById('canvas'), gl = c.getContext('webgl2');
    const w = c.width, h = c.height, flipped = new Uint8Array(4 * w * h), data = new Uint8Array(4 * w * h);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, flipped);
    for (let y = 0; y < h; ++y) data.set(flipped.subarray(4 * w * (h - 1 - y), 4 * w * (h - y)), 4 * w * y);
    return { w, h, data };
  }
  const bytes = Uint8Array.from(atob(picture), (ch) => ch.charCodeAt(0));
  const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }),
                                         { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
  const c = new OffscreenCanvas(bitmap.width, bitmap.height), g = c.getContext('2d', { willReadFrequently: true });
  g.drawImage(bitmap, 0, 0);
  return { w: bitmap.width, h: bitmap.height, data: g.getImageData(0, 0, bitmap.width, bitmap.height).data };
};
"""


def picture(path=None):
    """A PNG file as compare() and coverage() take it; None: the canvas."""
    if path is None:
        return "canvas"
    with open(path, "rb") as f:
        return base64.b64encode(f.read()).decode()


def picture_size(browser, a=None):
    browser.run(PIXELS_JS)
    return browser.run_async("const p = await sssPixels(args[0]); return [p.w, p.h];", picture(a))


def compare(browser, a, b, region=None, threshold=8):
    """How two pictures of one size differ in a region (x, y, w, h): the mean
    absolute difference per channel (0..255), the largest, and the share of
    pixels with a channel more than `threshold` apart. a, b: picture()."""
    browser.run(PIXELS_JS)
    return browser.run_async("""
        const [a, b] = [await sssPixels(args[0]), await sssPixels(args[1])];
        if (a.w !== b.w || a.h !== b.h) throw new Error(`sizes differ: ${a.w}x${a.h}, ${b.w}x${b.h}`);
        const [x0, y0, w, h] = args[2] || [0, 0, a.w, a.h];
        let total = 0, largest = 0, far = 0;
        for (let y = y0; y < y0 + h; ++y)
          for (let x = x0; x < x0 + w; ++x) {
            let d = 0;
            for (let c = 0; c < 3; ++c) {
              const e = Math.abs(a.data[4 * (y * a.w + x) + c] - b.data[4 * (y * a.w + x) + c]);
              total += e / 3; d = Math.max(d, e);
            }
            largest = Math.max(largest, d); far += d > args[3];
          }
        return [total / (w * h), largest, far / (w * h)];""", a, b, region, threshold)


def coverage(browser, background, region=None):
    """The share of the canvas's pixels in a region not within 2 of a colour."""
    browser.run(PIXELS_JS)
    return browser.run_async("""
        const p = await sssPixels('canvas'), [x0, y0, w, h] = args[1] || [0, 0, p.w, p.h];
        let n = 0;
        for (let y = y0; y < y0 + h; ++y)
          for (let x = x0; x < x0 + w; ++x)
            n += [0, 1, 2].some((c) => Math.abs(p.data[4 * (y * p.w + x) + c] - args[0][c]) > 2);
        return n / (w * h);""", background, region)


def settle(browser, what, timeout=30):
    browser.wait("return window.sssView && sssView.ready && sssView.busy == 0 && "
                 "sssView.shownLiveSeq == sssView.liveSeq", timeout, what)


def check_console(browser, what):
    errors = browser.run("return sssView.errors")
    severe = [e for e in browser.console() if e.get("level") == "SEVERE"]
    if errors or severe:
        fail(f"{what}: console errors {severe} page errors {errors}")


def drag(browser, css, dx, dy, steps=6, start=(0, 0)):
    """A mouse drag on an element, from its centre (plus start), as a person
    does it: down, a few moves, up."""
    x, y = browser.run(
        f"const e=document.querySelector('{css}'); e.scrollIntoView({{block: 'center'}});"
        "const r=e.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]")
    moves = [{"type": "pointerMove", "origin": "viewport", "x": round(x + start[0]),
              "y": round(y + start[1]), "duration": 0},
             {"type": "pointerDown", "button": 0}]
    for k in range(1, steps + 1):
        moves += [{"type": "pointerMove", "origin": "viewport",
                   "x": round(x + start[0] + dx * k / steps),
                   "y": round(y + start[1] + dy * k / steps), "duration": 40}]
    moves.append({"type": "pointerUp", "button": 0})
    browser.actions(moves)


def compare_with_batch(browser, what):
    """The page's picture against the batch ptview command it shows."""
    batch = browser.run("return sssView.batchCommand")
    words = shlex.split(batch)
    if words[0] != "ptview" or words[-1] != "view.png":
        fail(f"no batch command: {batch}")
    tool("ptview", *words[1:])
    mean, largest, far = compare(browser, "canvas", picture(os.path.join(WORK, "view.png")))
    log(f"page ({what}) against '{batch}': mean difference {mean:.3f}/255, {far:.2%} of the "
        f"pixels more than 8/255 apart, largest {largest}")
    if mean > MEAN_TOLERANCE or far > FAR_TOLERANCE:
        fail(f"the page's picture differs from ptview's: mean {mean:.3f}, {far:.2%} far")
    return batch


def live_region(browser):
    """The live tile of a side-by-side sheet (x, y, w, h)."""
    return tuple(browser.run(
        "const l=[...document.querySelectorAll('.label')].findIndex(d=>d.textContent.includes('live'));"
        "const d=document.querySelectorAll('.label')[l];"
        "return [d.offsetLeft, d.offsetTop, 512, 512]"))


def main():
    os.makedirs(WORK, exist_ok=True)
    os.makedirs(SHOTS, exist_ok=True)
    tool("ptsynth", "-shape", "sphere", "-n", "200000", "-size", "50", "-light", "1", "1", "1",
         "bake.ptc")
    with open(os.path.join(WORK, "bake.rib"), "w") as f:
        f.write(open(os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "teapot",
                                  "bake.rib")).read())
    tool("ptbake", "-spacing", "0.06", "bake.rib")
    tool("ptfilter", "-ssdiffusion", "-material", "marble", "-unitlength", "0.1", "teapot.ptc",
         "teapot_ssd.ptc")
    tool("brickmake", "-maxerror", "0.002", "teapot_ssd.ptc", "teapot_ssd.bkm")
    log("clouds: bake.ptc (200000 points), teapot.ptc (its camera), teapot_ssd.bkm")

    server = Server("bake.ptc")
    with Browser(1400, 900) as browser:
        browser.get(server.url + "#res=512x512&az=30&el=20")
        settle(browser, "the first view and the first live diffusion", 90)
        check_console(browser, "first view")
        width, height = picture_size(browser)
        if (width, height) != (1026, 512):
            fail(f"the sheet is {width} x {height}, not 1026 x 512 (two 512 tiles)")
        lit = coverage(browser, BACKGROUND, (0, 0, 512, 512))
        if lit < 0.2:
            fail(f"the bake's tile is blank ({lit:.1%} of its pixels differ from the background)")
        log(f"page drawn without console errors; {lit:.0%} of the bake's tile covered")

        # The mean free path: the slider dragged (previews), then let go (the whole cloud).
        region = live_region(browser)
        browser.run("window.sssBefore = document.getElementById('canvas').toDataURL('image/png').split(',')[1]")
        n_before = len(browser.run("return sssView.latencies"))
        drag(browser, "#mfp-scale", 60, 0, steps=8)
        settle(browser, "the live diffusion after the drag")
        browser.run("window.sssAfter = document.getElementById('canvas').toDataURL('image/png').split(',')[1]")
        mean, largest, _ = compare(browser, browser.run("return sssBefore"), "canvas", region)
        if mean < 1.0:
            fail(f"the live tile did not change with the mean free path (mean difference {mean:.2f})")
        lat = browser.run("return sssView.latencies")[n_before:]
        whole = [x for x in lat if not x["preview"]]
        previews = [x for x in lat if x["preview"]]
        # (A preview still running at the release is cancelled: with the
        # sanitizers' slower diffusion, every one may be.)
        if not whole or (not previews and not SANITIZED):
            fail(f"the drag did not make previews and a whole update: {lat}")
        shown = (f"{len(previews)} previews of {previews[0]['points']} points, "
                 f"{max(x['ms'] for x in previews):.0f} ms at most" if previews else "no preview")
        log(f"mean free path dragged: picture changed (mean {mean:.1f}/255); {shown}; whole "
            f"cloud {whole[-1]['ms']:.0f} ms after the release (diffusion {whole[-1]['server']:.0f} ms)")
        # Three more releases, each a new mean free path, for the latency.
        for value in (0.5, -0.8, 1.7):
            browser.run(f"const s=document.getElementById('mfp-scale'); s.value={value};"
                        "s.dispatchEvent(new Event('change'))")
            settle(browser, "a whole update")
        lat = browser.run("return sssView.latencies")
        releases = [x["ms"] for x in lat[-3:]] + [whole[-1]["ms"]]
        median = statistics.median(releases)
        servers = ", ".join(f"{x['server']:.0f}" for x in lat[-3:])
        shown = ", ".join(f"{x:.0f}" for x in releases)
        log(f"live update of the whole 200k-point cloud: {shown} ms (median {median:.0f} ms; "
            f"diffusion {servers} ms)")
        if not SANITIZED:
            if median > LATENCY_LIMIT_MS:
                fail(f"the live update takes {median:.0f} ms (median), above {LATENCY_LIMIT_MS:.0f} ms")
            slow = [x["ms"] for x in previews if x["ms"] > LATENCY_LIMIT_MS]
            if len(slow) > len(previews) // 2:
                fail(f"previews took {slow} ms")

        # Save, then the command the page shows, run: the same file.
        browser.run("document.getElementById('save').click()")
        browser.wait("return sssView.saved", 30, "Save")
        saved = browser.run("return sssView.saved")
        shown = browser.run("return sssView.shownHash")
        if saved["hash"] != shown:
            fail(f"Save wrote values {saved['hash']}, the page drew {shown}")
        command = browser.run("return document.getElementById('command').textContent")
        words = shlex.split(command)
        if words[0] != "ptfilter" or words[-1] != "bake_ssd.ptc" or words[-2] != "bake.ptc":
            fail(f"unexpected command: {command}")
        subprocess.run([os.path.join(BIN, "ptfilter")] + words[1:-1] + ["command_ssd.ptc"],
                       cwd=WORK, check=True)
        if open(os.path.join(WORK, "bake_ssd.ptc"), "rb").read() != \
                open(os.path.join(WORK, "command_ssd.ptc"), "rb").read():
            fail(f"'{command}' does not reproduce the saved result")
        log(f"Save wrote the values drawn ({shown}); '{command}' writes the same bytes")
        # Those releases changed only the values: drawn from the points' pixels
        # (no point drawn again), which must still be ptview's picture.
        if not all(x.get("resolved") for x in lat[-3:]):
            fail(f"whole updates in an unchanged view drew the points again: {lat[-3:]}")
        compare_with_batch(browser, "the live tile's values set at its pixels")

        # Orbit by dragging the picture, then the page against ptview.
        az0 = browser.run("return location.hash")
        drag(browser, "#canvas", -120, 40, start=(-250, 0))
        settle(browser, "the orbit")
        browser.run("sssView.render()")
        if browser.run("return location.hash") == az0:
            fail("dragging the picture did not orbit")
        if compare(browser, browser.run("return sssAfter"), "canvas", (0, 0, 512, 512))[0] < 1.0:
            fail("the picture did not change when orbiting")
        batch = compare_with_batch(browser, "after the orbit")
        check_console(browser, "after the live diffusion, Save and the orbit")

        # A turntable: ptview's pictures of the orbit, and a video.
        browser.run("document.getElementById('tt-frames').value = 4;"
                    "document.getElementById('tt-name').value = 'spin';"
                    "document.getElementById('turntable-go').click()")
        browser.wait("return sssView.turntable", 60, "the turntable")
        tt = browser.run("return sssView.turntable")
        if len(tt["frames"]) != 4:
            fail(f"turntable: {tt}")
        m = re.search(r"-orbit (\S+) (\S+)", batch)
        az, el = float(m.group(1)), float(m.group(2))
        orbit_words = re.sub(r"-orbit \S+ \S+", f"-orbit {az + 90:g} {el:g}", batch)
        orbit_words = re.sub(r"-exposure \S+ ", "", orbit_words)
        orbit_words = shlex.split(orbit_words)[1:-1] + ["-exposure", f"{tt['exposure']!r}", "frame2.png"]
        tool("ptview", *orbit_words)
        mean, largest, _ = compare(browser, picture(os.path.join(WORK, "spin", "spin.0002.png")),
                                   picture(os.path.join(WORK, "frame2.png")))
        if largest > 0:
            fail(f"turntable frame 2 is not ptview -orbit {az + 90:g} {el:g}: largest difference {largest}")
        if tt["video"]:
            size = os.path.getsize(os.path.join(WORK, "spin", tt["video"]))
            if size < 1000:
                fail(f"the turntable's video is {size} bytes")
        log(f"turntable: {len(tt['frames'])} frames = ptview -orbit pictures; video: "
            f"{tt['video'] or tt['video_note']}")
    server.stop()

    # The teapot: its bake camera, its live diffusion, its brick map's voxels.
    server = Server("teapot.ptc", "teapot_ssd.bkm")
    with Browser(1280, 860) as browser:
        browser.get(server.url)
        settle(browser, "the teapot", 60)
        check_console(browser, "teapot")
        if browser.run("return document.getElementById('camera').value") != "file":
            fail("the teapot is not seen through its bake camera")
        if browser.run("return document.querySelectorAll('.label').length") != 3:
            fail("the teapot's bake, its live diffusion and the brick map are not three tiles")
        # The bake and its live diffusion (the brick map hidden), unit length 0.1.
        browser.run("document.querySelectorAll('#source-list input[type=checkbox]')[2].click()")
        browser.run("const s=document.getElementById('unitlength'); s.value=0.1;"
                    "s.dispatchEvent(new Event('change'))")
        settle(browser, "the teapot's diffusion")
        if "-unitlength 0.1 teapot.ptc" not in browser.run(
                "return document.getElementById('command').textContent"):
            fail("the unit length is not in the command line")
        browser.screenshot(os.path.join(SHOTS, "ptview-serve-teapot.png"))
        width, height = picture_size(browser)
        for x in (0, width // 2 + 1):
            if coverage(browser, BACKGROUND, (x, 0, width // 2 - 1, height)) < 0.1:
                fail(f"the teapot's tile at x {x} is blank")
        # The brick map's voxels at depth 3, alone, from an orbit.
        browser.run("const boxes=document.querySelectorAll('#source-list input[type=checkbox]');"
                    "boxes[0].click(); boxes[1].click(); boxes[2].click();"
                    "const d=document.querySelector('#source-list select:last-of-type');"
                    "const depths=document.querySelectorAll('#source-list select');"
                    "const depth=depths[depths.length - 1]; depth.value='3';"
                    "depth.dispatchEvent(new Event('change'));"
                    "const c=document.getElementById('camera'); c.value='orbit';"
                    "c.dispatchEvent(new Event('change'))")
        settle(browser, "the brick map's voxels")
        drag(browser, "#canvas", -60, 30)
        settle(browser, "the orbit")
        labels = browser.run("return [...document.querySelectorAll('.label')].map(l => l.textContent)")
        if labels != ["teapot_ssd.bkm depth 3 · _ssdiffusion"]:
            fail(f"the brick map's tile: {labels}")
        if coverage(browser, BACKGROUND) < 0.05:
            fail("the brick map's voxels are not drawn")
        browser.screenshot(os.path.join(SHOTS, "ptview-serve-brickmap.png"))
        # Overlaid: the bake and the voxels in one tile.
        browser.run("document.querySelectorAll('#source-list input[type=checkbox]')[0].click();"
                    "const l=document.getElementById('layout'); l.value='overlay';"
                    "l.dispatchEvent(new Event('change'))")
        settle(browser, "the overlay")
        if browser.run("return document.querySelectorAll('.label').length") != 1:
            fail("overlaid clouds are not in one tile")
        check_console(browser, "teapot views")
        log("teapot: bake camera, live diffusion (unit length 0.1), brick-map voxels, overlay")
    server.stop()
    log(f"screenshots in {SHOTS}; all checks passed")


if __name__ == "__main__":
    main()

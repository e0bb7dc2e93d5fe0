# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""A small W3C WebDriver client for Debian's chromium and chromedriver.

The browser tests (tests/browser/) and the latency benchmark
(bench/ptview_serve_bench.py) drive a headless Chromium through it, with the
standard library only: WebDriver is JSON over HTTP to chromedriver.
"""
import base64
import json
import os
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.error
import urllib.request


class WebDriverError(RuntimeError):
    pass


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def find_chromium():
    """(chromium, chromedriver) on this machine, or raises WebDriverError."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver") or (
        "/usr/bin/chromedriver" if os.path.exists("/usr/bin/chromedriver") else None)
    if not browser or not driver:
        raise WebDriverError("chromium and chromedriver are needed (Debian: apt-get install "
                             "chromium chromium-driver; scripts/install-deps installs them)")
    return browser, driver


class Browser:
    """A headless Chromium session. WebGL2 runs on SwiftShader (the CPU), as
    on a machine without a GPU."""

    def __init__(self, width=1280, height=800, timeout=60):
        browser, driver = find_chromium()
        self.profile = tempfile.mkdtemp(prefix="sss_chromium.")
        self.port = free_port()
        self.log = open(os.path.join(self.profile, "chromedriver.log"), "w")
        self.driver = subprocess.Popen([driver, f"--port={self.port}"], stdout=self.log,
                                       stderr=subprocess.STDOUT)
        self.base = f"http://127.0.0.1:{self.port}"
        self.timeout = timeout
        deadline = time.time() + 20
        while True:
            try:
                if self._call("GET", "/status")["value"].get("ready"):
                    break
            except (OSError, WebDriverError):
                pass
            if time.time() > deadline:
                self.close()
                raise WebDriverError("chromedriver did not start")
            time.sleep(0.1)
        args = ["--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--ignore-gpu-blocklist", f"--window-size={width},{height}",
                "--force-device-scale-factor=1", "--no-first-run",
                f"--user-data-dir={self.profile}/profile"]
        caps = {"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {"binary": browser, "args": args},
            "goog:loggingPrefs": {"browser": "ALL"}}}}
        try:
            self.session = self._call("POST", "/session", caps)["value"]["sessionId"]
        except Exception:
            self.close()
            raise

    def _call(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(self.base + path, data=data, method=method,
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as r:
                return json.loads(r.read() or b"{}")
        except urllib.error.HTTPError as e:
            text = e.read().decode(errors="replace")
            try:
                value = json.loads(text)["value"]
                text = f"{value.get('error')}: {value.get('message', '')[:2000]}"
            except (ValueError, KeyError, TypeError, AttributeError):
                pass
            raise WebDriverError(f"{method} {path}: {text}") from None

    def _session(self, method, path, body=None):
        return self._call(method, f"/session/{self.session}{path}", body)["value"]

    def get(self, url):
        self._session("POST", "/url", {"url": url})

    def run(self, script, *args):
        """Runs a function body in the page and returns its result."""
        return self._session("POST", "/execute/sync", {"script": script, "args": list(args)})

    def run_async(self, script, *args):
        """Runs an async function body (`await` allowed) and returns its result."""
        wrapped = ("const done = arguments[arguments.length - 1];"
                   f"(async (...args) => {{ {script} }})(...Array.from(arguments).slice(0, -1))"
                   ".then(done, (e) => done({error: String(e && e.stack || e)}));")
        value = self._session("POST", "/execute/async", {"script": wrapped, "args": list(args)})
        if isinstance(value, dict) and set(value) == {"error"}:
            raise WebDriverError(value["error"])
        return value

    def wait(self, script, timeout=30, what="the page"):
        """Waits until a script returns a true value; returns it."""
        deadline = time.time() + timeout
        while True:
            value = self.run(script)
            if value:
                return value
            if time.time() > deadline:
                raise WebDriverError(f"timed out waiting for {what} ({script})")
            time.sleep(0.05)

    def element(self, css):
        found = self._session("POST", "/element", {"using": "css selector", "value": css})
        return next(iter(found.values()))

    def actions(self, steps):
        """Pointer actions (W3C Actions): steps of pointerMove/Down/Up, pause."""
        self._session("POST", "/actions", {"actions": [{
            "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": steps}]})
        self._session("DELETE", "/actions")

    def screenshot(self, path):
        with open(path, "wb") as f:
            f.write(base64.b64decode(self._session("GET", "/screenshot")))

    def console(self):
        """The browser's console entries since the last call."""
        try:
            return self._session("POST", "/se/log", {"type": "browser"})
        except WebDriverError:
            return self._call("POST", f"/session/{self.session}/log",
                              {"type": "browser"})["value"]

    def close(self):
        try:
            if getattr(self, "session", None):
                self._call("DELETE", f"/session/{self.session}")
        except (OSError, WebDriverError):
            pass
        if self.driver.poll() is None:
            self.driver.terminate()
            try:
                self.driver.wait(10)
            except subprocess.TimeoutExpired:
                self.driver.kill()
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# ptview -serve without a browser: errors at start as the other tools give
# them (exit 1 for a bad file, 2 for a bad command line, nothing served),
# -check, the address printed for -port 0, a port in use, the page and the
# data over HTTP, 404s, refused hosts and origins, a few dozen malformed
# requests that leave the server answering, -bind's warning, Save's names,
# and the server stopped by its PID. The page in a real browser:
# test_ptview_serve_browser.sh.
# Needs SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
ptview="$bin/ptview"
tmp="$(mktemp -d)"
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    rm -rf "$tmp"
}
trap cleanup EXIT
cd "$tmp"

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

# expect_exit <code> <stderr pattern> cmd...
expect_exit() {
    local code="$1" pattern="$2" rc=0
    shift 2
    timeout 20 "$@" >out.txt 2>err.txt || rc=$?
    [ "$rc" = "$code" ] || { cat out.txt err.txt >&2; fail "'$*': exit $rc, expected $code"; }
    grep -q -- "$pattern" err.txt || { cat err.txt >&2; fail "'$*': no '$pattern' on stderr"; }
}

# start <log> args...: starts ptview -serve, sets $pid and $url (from its
# first line).
start() {
    local log="$1"
    shift
    : >"$log"
    "$ptview" -serve "$@" >>"$log" 2>"$log.err" &
    pid=$!
    pids+=("$pid")
    for _ in $(seq 100); do
        url="$(sed -n 's/^ptview: serving .* at \(http:[^# ]*\).*/\1/p' "$log")"
        [ -n "$url" ] && return 0
        kill -0 "$pid" 2>/dev/null || { cat "$log" "$log.err" >&2; fail "ptview -serve $* exited"; }
        sleep 0.05
    done
    fail "ptview -serve $* printed no address: $(cat "$log" "$log.err")"
}

# stop: SIGTERM to $pid; it must be gone within 10 s.
stop() {
    kill -TERM "$pid" || fail "ptview -serve (pid $pid) was gone before it was stopped"
    for _ in $(seq 200); do
        kill -0 "$pid" 2>/dev/null || { wait "$pid" 2>/dev/null || true; return 0; }
        sleep 0.05
    done
    fail "ptview -serve (pid $pid) did not stop on SIGTERM"
}

"$bin/ptsynth" -shape sphere -n 5000 -size 10 -light 1 1 1 bake.ptc >/dev/null
"$bin/ptsynth" -shape plane -n 400 plane.ptc >/dev/null
"$bin/ptfilter" -ssdiffusion plane.ptc plain.ptc # no _area: nothing to diffuse
printf 'pointcloud\n' >short.ptc
printf 'not a brick map\n' >bad.bkm

# --- errors at start: nothing is served ----------------------------------------
expect_exit 1 "^ptview ERROR: missing.ptc: cannot open: No such file or directory" "$ptview" -serve missing.ptc
expect_exit 1 "^ptview ERROR: short.ptc: " "$ptview" -serve bake.ptc short.ptc
expect_exit 1 "^ptview ERROR: bad.bkm: " "$ptview" -serve bad.bkm
expect_exit 2 "^ptview ERROR: no file to show" "$ptview" -serve
expect_exit 2 "^ptview ERROR: -o is for pictures; -serve shows the files in a browser" \
    "$ptview" -serve -o x.png bake.ptc
expect_exit 2 "^ptview ERROR: -columns is for pictures" "$ptview" -serve -columns 2 bake.ptc
expect_exit 2 "option -port: 70000 is out of range" "$ptview" -serve -port 70000 bake.ptc
expect_exit 2 "option -livepoints" "$ptview" -serve -livepoints 0 bake.ptc
expect_exit 2 "unknown option -sreve" "$ptview" -sreve bake.ptc
# -check reads nothing: a missing file is fine, a bad option is not.
"$ptview" -check -serve -port 8123 missing.ptc || fail "-check -serve missing.ptc: exit $?"
expect_exit 2 "option -bind" "$ptview" -check -serve -bind
# Batch ptview is as it was: one file and no output is still refused.
expect_exit 2 "no output picture given" "$ptview" bake.ptc

# --- a server: the address, the page, the data ---------------------------------
start serve.log -port 0 -orbit 200 35 -channel _radiance_t bake.ptc plain.ptc
grep -q "^ptview: serving 2 files at http://127.0.0.1:[0-9]*/#channel=_radiance_t&camera=orbit&az=200&el=35" serve.log ||
    fail "the first line: $(cat serve.log)"
port="${url##*:}"
port="${port%/}"
# A second server on the same port: exit 1, naming it.
expect_exit 1 "^ptview ERROR: 127.0.0.1:$port: cannot listen there" "$ptview" -serve -port "$port" bake.ptc

python3 - "$port" <<'EOF'
import json, socket, sys, urllib.request, urllib.error

port = int(sys.argv[1])
base = f"http://127.0.0.1:{port}"
failures = []

def check(cond, what):
    if not cond:
        failures.append(what)

def http(path, data=None, headers=None):
    req = urllib.request.Request(base + path, data=data, headers=headers or {},
                                 method="POST" if data is not None else "GET")
    try:
        with urllib.request.urlopen(req, timeout=20) as r:
            return r.status, r.headers, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read()

def raw(data, half_close=True):
    s = socket.create_connection(("127.0.0.1", port), timeout=20)
    s.sendall(data)
    if half_close:
        s.shutdown(socket.SHUT_WR)
    out = b""
    try:
        while chunk := s.recv(65536):
            out += chunk
    except (ConnectionResetError, socket.timeout):
        pass
    s.close()
    return out

status, headers, body = http("/")
check(status == 200 and b"viewer.js" in body, f"/: {status}")
check("script-src 'self'" in headers.get("Content-Security-Policy", ""), "no CSP on the page")
for asset in ("/viewer.js", "/viewer_gl.js", "/viewer.css"):
    check(http(asset)[0] == 200, asset)
status, _, body = http("/api/scene")
scene = json.loads(body)
check([i["label"] for i in scene["inputs"]] == ["bake.ptc", "plain.ptc"], f"scene: {scene['inputs']}")
check(scene["inputs"][0]["live"] and scene["inputs"][0]["points"] == 5000, "bake.ptc is baked")
check(any(m["name"] == "skin1" for m in scene["materials"]), "materials")
status, _, body = http("/api/data/c0/geometry")
n = int.from_bytes(body[:4], "little")
check(status == 200 and len(body) == ((4 + n + 3) // 4) * 4 + 7 * 5000 * 4, f"geometry: {len(body)} bytes")

# The live diffusion: ptfilter's parser, its messages, options refused.
status, _, body = http("/api/diffuse?cloud=0", b"-material\nskin1\n-unitlength\n0.1")
n = int.from_bytes(body[:4], "little")
meta = json.loads(body[4:4 + n])
check(status == 200 and meta["command"] ==
      "ptfilter -ssdiffusion -material skin1 -unitlength 0.1 bake.ptc bake_ssd.ptc", f"diffuse: {meta}")
for words, message in [(b"-material\nskin11", b"did you mean 'skin1'"),
                       (b"-albedo\n1.5\n0.5\n0.5", b"-albedo"),
                       (b"-blocker\n/etc/passwd", b"not one the live view offers"),
                       (b"-exact", b"not one the live view offers"),
                       (b"-keepchannels\n1", b"not one the live view offers"),
                       (b"stray", b"unexpected word")]:
    status, _, body = http("/api/diffuse?cloud=0", words)
    check(status == 400 and message in body, f"{words!r}: {status} {body!r}")
check(not scene["inputs"][1]["live"], "plain.ptc has no _area, yet a live diffusion")
check(http("/api/diffuse?cloud=1", b"")[0] == 404, "plain.ptc has no _area: no live diffusion")
check(http("/api/diffuse?cloud=99", b"")[0] == 404, "cloud 99")

# Save: plain names in the input's folder only.
status, _, body = http("/api/save?cloud=0&name=mine.ptc", b"-material\nskin1")
check(status == 200 and json.loads(body)["path"] == "mine.ptc", f"save: {status} {body!r}")
for name in ("../mine.ptc", "%2Ftmp%2Fx.ptc", "mine.txt", "bake.ptc", "mine.ptc", ".x.ptc"):
    status, _, body = http(f"/api/save?cloud=0&name={name}", b"-material\nskin1")
    check(status == 400, f"save as {name}: {status} {body!r}")

# Missing things: 404 with a short text.
for path in ("/x", "/api/data/c2/geometry", "/api/data/c0/channel/5", "/api/data/b0.1/geometry",
             "/api/data/..%2F..%2Fetc%2Fpasswd/geometry", "/etc/passwd", "/../../etc/passwd",
             "/api/data/c0/geometry/extra", "/viewer.js.map", "/index.html?x=../../etc/passwd/x"):
    status, _, body = http(path)
    check((status == 404 and len(body) < 300) or (path.startswith("/index") and status == 200),
          f"{path}: {status} {body[:100]!r}")

# Other web pages: a rebound host name, a cross-site POST.
check(http("/api/scene", headers={"Host": "evil.example"})[0] == 403, "Host evil.example")
check(http("/api/scene", headers={"Host": "localhost:1234"})[0] == 200, "Host localhost (a tunnel)")
check(http("/api/save?cloud=0&name=x.ptc&overwrite=1", b"",
           headers={"Origin": "http://evil.example"})[0] == 403, "Origin evil.example")

# Malformed requests: each answered with an error or dropped; none stops it.
junk = [b"", b"\r\n\r\n", b"GET\r\n\r\n", b"GET / HTTP/9.9\r\n\r\n", b"PUT / HTTP/1.1\r\n\r\n",
        b"GET /api/scene HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: -1\r\n\r\n",
        b"POST /api/diffuse?cloud=0 HTTP/1.1\r\nContent-Length: 99999999999999999999\r\n\r\nx",
        b"POST /api/diffuse?cloud=0 HTTP/1.1\r\nContent-Length: 50\r\n\r\nshort",
        b"POST /api/diffuse?cloud=0 HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n",
        b"GET /" + b"a" * 100000 + b" HTTP/1.1\r\n\r\n",
        b"GET / HTTP/1.1\r\n" + b"X: " + b"y" * 100000 + b"\r\n\r\n",
        b"GET /api/data/c0/channel/999999999999 HTTP/1.1\r\n\r\n",
        b"GET /api/data/c99999999999999/geometry HTTP/1.1\r\n\r\n",
        b"POST /api/turntable?frames=1e9&width=-1 HTTP/1.1\r\nContent-Length: 2\r\n\r\nc0",
        b"POST /api/diffuse?cloud=0 HTTP/1.1\r\nContent-Length: 9\r\n\r\n-material",
        b"POST /api/diffuse?cloud=0&preview=2 HTTP/1.1\r\nContent-Length: 0\r\n\r\n",
        b"POST /api/diffuse?cloud=0 HTTP/1.1\r\nContent-Length: 5\r\n\r\n\x00\x01\x02\x03\x04",
        bytes(range(256)) * 4, b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03"]
for j in junk:
    answer = raw(j)
    check(answer == b"" or (answer.startswith(b"HTTP/1.1 ") and answer[9:12] != b"500"),
          f"junk {j[:40]!r}: {answer[:60]!r}")
    check(http("/api/scene")[0] == 200, f"the server stopped answering after {j[:40]!r}")

if failures:
    print("FAIL: " + "\nFAIL: ".join(failures), file=sys.stderr)
    sys.exit(1)
EOF
[ -f mine.ptc ] || fail "Save wrote no mine.ptc"
"$bin/ptfilter" -ssdiffusion -material skin1 bake.ptc check.ptc
cmp -s mine.ptc check.ptc || fail "Save's mine.ptc is not what ptfilter -ssdiffusion -material skin1 writes"
stop
kill -0 "$pid" 2>/dev/null && fail "the server is still running"

# --- -savedir, -bind's warning ------------------------------------------------------
mkdir saved
start serve2.log -savedir saved -bind 0.0.0.0 bake.ptc
grep -q "ptview WARNING: -bind 0.0.0.0: whoever reaches this machine" serve2.log.err ||
    fail "no warning for -bind 0.0.0.0: $(cat serve2.log.err)"
python3 - "$url" <<'EOF'
import sys, urllib.request
req = urllib.request.Request(sys.argv[1] + "api/save?cloud=0&name=a.ptc", data=b"", method="POST")
urllib.request.urlopen(req, timeout=20).read()
EOF
[ -f saved/a.ptc ] || fail "-savedir saved: no saved/a.ptc"
stop
echo "test_ptview_serve: ok"

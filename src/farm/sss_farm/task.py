# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""task: what one array task runs: its frame, its log and status file, the
tool (or a split filter's part or merge), signals passed on, and a failed
attempt requeued."""

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time

from .common import PROG, Failure, Usage, one_line, quote_cmd, quoted, say, warn
from .frames import MAX_FRAME, MAX_PARTS, expand_frame, parse_frame_list
from .slurm import requeue_self
from .spec import check_in_workdir, check_spec_place, load_spec, log_path, stage_of, status_path, write_atomic
from .stages import filter_files, has_option, option_value, part_file, tool_command, tool_path, up_to_date


def count_points(spec, files):
    total = 0
    for f in files:
        r = subprocess.run([tool_path(spec, "ptinfo"), "-stats", "0", f], capture_output=True, text=True,
                           cwd=spec["workdir"])
        if r.returncode != 0:
            sys.stderr.write(r.stderr)
            raise Failure("cannot count the points of %s (ptinfo exit %d)" % (f, r.returncode))
        m = re.search(r"^\s*points:\s*(\d+)", r.stdout, re.M)
        if not m:
            raise Failure("ptinfo printed no 'points:' line for %s" % f)
        total += int(m.group(1))
    return total


_child = None
_cancelled = None  # the signal that stopped the task (scancel, a time limit)
CANCEL_CODES = (128 + signal.SIGTERM, 128 + signal.SIGINT)


def _forward(signum, frame):
    """SIGTERM/SIGINT (Slurm's time limit, scancel): passed on to the tool,
    which removes its temporaries and exits; the task then records it."""
    global _cancelled
    _cancelled = signum
    if _child is not None and _child.poll() is None:
        _child.send_signal(signum)
    else:
        raise SystemExit(128 + signum)


def run_logged(cmd, cwd):
    global _child
    say("+ " + quote_cmd(cmd))
    try:
        _child = subprocess.Popen(cmd, cwd=cwd)
    except OSError as e:
        raise Failure("cannot run %s: %s" % (cmd[0], e.strerror))
    code = _child.wait()
    _child = None
    return code if code >= 0 else 128 - code


def task_frame(spec, a):
    """(frame, submission number, array index) of a task: --frame F, or the
    frame at position SLURM_ARRAY_TASK_ID of its submission's frames."""
    subs = spec.get("submissions") or []
    number = a.submission if a.submission is not None else len(subs)
    if a.submission is not None and not 1 <= a.submission <= len(subs):
        raise Usage("--submission %d: %s has %d submissions" % (a.submission, spec["name"], len(subs)))
    if a.frame is not None:
        if not 0 <= a.frame <= MAX_FRAME:
            raise Usage("frame %d: frames go from 0 to %d" % (a.frame, MAX_FRAME))
        return a.frame, number, None
    index_text = os.environ.get("SLURM_ARRAY_TASK_ID")
    if not index_text:
        raise Usage("no frame: run as a Slurm array task (SLURM_ARRAY_TASK_ID) or give --frame N")
    if not re.fullmatch(r"\d{1,7}", index_text):
        raise Usage("SLURM_ARRAY_TASK_ID %s is not an array index" % quoted(index_text))
    if a.submission is None:
        raise Usage("an array task needs --submission N (a task of an older sss-farm: submit again)")
    frames = parse_frame_list(subs[number - 1]["frames"])
    index = int(index_text)
    if index >= len(frames):
        raise Usage("array index %d: submission %d of %s has %d frames" % (index, number, spec["name"], len(frames)))
    return frames[index], number, index


def redirect_output(path):
    """Standard output and error (the tools' too) appended to the frame's log."""
    sys.stdout.flush()
    sys.stderr.flush()
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    os.close(fd)


def record(path, state, code, attempt, number):
    """The task's status file: one JSON line `status` reads."""
    job = "%s_%s" % (os.environ.get("SLURM_ARRAY_JOB_ID"), os.environ.get("SLURM_ARRAY_TASK_ID"))
    write_atomic(path, json.dumps({
        "state": state, "exit": code, "attempt": attempt, "submission": number, "host": socket.gethostname(),
        "job": job if re.fullmatch(r"\d+_\d+", job) else "-",
        "time": time.strftime("%Y-%m-%dT%H:%M:%S%z")}) + "\n")


def cmd_task(a):
    spec = load_spec(a.spec)
    frame, number, index = task_frame(spec, a)
    check_spec_place(spec, a.spec)
    stage = a.stage
    s = stage_of(spec, stage)
    split = spec.get("split")
    name = stage if a.part is None else "%s-part%d" % (stage, a.part)
    if a.part is not None and (not 1 <= a.part <= MAX_PARTS or s["tool"] != "ptfilter" or not split or not 1 <= a.part <= split["parts"]):
        raise Usage("--part %d: only the filter stage of a split submission has parts (1 to N)" % a.part)
    for sig in (signal.SIGTERM, signal.SIGINT):
        if signal.getsignal(sig) != signal.SIG_IGN:
            signal.signal(sig, _forward)
    wd = spec["workdir"]
    try:
        os.chdir(wd)
    except OSError as e:
        raise Failure("%s: %s (is the work folder on a file system every node sees?)" % (wd, e.strerror))
    spath = status_path(spec, name, frame)
    os.makedirs(os.path.dirname(spath), exist_ok=True)
    check_in_workdir(spec, os.path.dirname(spath), "status folder")
    if index is not None:  # an array task: the frame's own log
        os.makedirs(os.path.join(wd, "logs"), exist_ok=True)
        redirect_output(log_path(spec, name, frame))
    restarts = os.environ.get("SLURM_RESTART_COUNT", "0") if index is not None else "0"
    attempt = 1 + (int(restarts) if re.fullmatch(r"\d{1,6}", restarts) else 0)
    retries = spec.get("retries", 0)
    tries = "" if index is None else " (attempt %d of %d)" % (attempt, retries + 1)
    say("== %s: %s %s frame %d%s on %s, job %s, %s%s" % (
        PROG, spec["name"], name, frame, "" if index is None else " (index %d)" % index,
        socket.gethostname(), os.environ.get("SLURM_JOB_ID", "-"), time.strftime("%Y-%m-%d %H:%M:%S"), tries))
    record(spath, "running", None, attempt, number)

    failure = None
    try:
        code = run_stage(spec, s, frame, a.part)
    except Failure as e:
        failure, code = one_line(e), 1
    except SystemExit as e:  # a signal between two tool runs
        code = e.code if isinstance(e.code, int) else 1
    if code == 0:
        record(spath, "done", 0, attempt, number)
        return 0
    what = "%s %s frame %d: %s" % (spec["name"], name, frame,
                                   failure or "%s exited with %d" % (s["tool"], code))
    if _cancelled is not None or code in CANCEL_CODES:
        record(spath, "cancelled", code, attempt, number)
        say("%s: %s (cancelled)" % (PROG, what))
        return code
    # A usage error fails the same way every time; anything else may pass on
    # another try (a file server's hiccup, a node's memory).
    if code != 2 and attempt <= retries and index is not None:
        record(spath, "retrying", code, attempt, number)
        if requeue_self():
            warn("%s%s: requeued, Slurm starts it again after its requeue delay" % (what, tries))
            return 0
    record(spath, "failed", code, attempt, number)
    sys.stdout.flush()
    print("%s ERROR: %s%s" % (PROG, what, tries), file=sys.stderr, flush=True)
    return code


def run_stage(spec, s, frame, part):
    wd = spec["workdir"]
    split = spec.get("split")
    if s["tool"] != "ptfilter" or not split:
        return run_logged(tool_command(spec, s, frame), wd)

    ins, out = filter_files(s["args"])
    n = split["parts"]
    in_files = [expand_frame(i, frame) for i in ins]
    out_file = expand_frame(out, frame)
    parts = [part_file(out, k, n) for k in range(1, n + 1)]
    newer = not has_option(s["args"], "newer") or option_value(s["args"], "newer") != "0"
    if newer and up_to_date([out_file], in_files):
        say("%s: %s is newer than its inputs; nothing to do" % (PROG, out_file))
        return 0
    points = count_points(spec, in_files)
    if points <= split["points"]:
        if part is not None:
            say("%s: frame %d: %d points <= %d: not split, the filter task runs ptfilter"
                % (PROG, frame, points, split["points"]))
            return 0
        say("%s: frame %d: %d points <= %d: not split" % (PROG, frame, points, split["points"]))
        return run_logged(tool_command(spec, s, frame), wd)

    if part is not None:
        say("%s: frame %d: %d points > %d: part %d of %d" % (PROG, frame, points, split["points"], part, n))
        cmd = tool_command(spec, s, frame, extra=["-part", "%d/%d" % (part, n)], output=parts[part - 1])
        return run_logged(cmd, wd)

    say("%s: frame %d: %d points > %d: merging %d parts" % (PROG, frame, points, split["points"], n))
    cmd = [tool_path(spec, "ptfilter"), "-merge", "-frame", str(frame), "-newer", "1" if newer else "0"]
    if has_option(s["args"], "progress"):
        cmd += ["-progress", option_value(s["args"], "progress") or "0"]
    code = run_logged(cmd + parts + [out], wd)
    if code == 0:
        for p in parts:
            try:
                os.remove(expand_frame(p, frame))
            except FileNotFoundError:
                pass
    return code

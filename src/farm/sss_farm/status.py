# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""status: what happened to every frame of the latest submission, from Slurm,
the tasks' status files and the outputs on disk; as text or JSON, with the
exit code."""

import json
import os
import re

from .common import PROG, STATUS_DONE, STATUS_FAILED, STATUS_RUNNING, Usage, quoted, say
from .frames import parse_frame_list, parse_frames, shown_frames
from .slurm import slurm_tasks
from .spec import (NAME_RE, check_in_workdir, check_spec_place, load_spec, log_path, no_constant,
                   part_stages, read_regular, spec_dir, spec_path, stage_of, status_path)
from .stages import stage_outputs


def read_status(spec, record_name, frame, number):
    """A task's status file as {state, exit, attempt}, or None when there is
    none or it belongs to another submission than `number`. The older form
    ("done", "failed N", "running HOST JOB") is read too."""
    path = status_path(spec, record_name, frame)
    if not os.path.lexists(path):
        return None
    text = read_regular(path, 4096, "status file").decode("utf-8", "replace").strip()
    try:
        st = json.loads(text, parse_constant=no_constant)
    except (ValueError, RecursionError):
        w = text.split()
        code = int(w[1]) if len(w) > 1 and re.fullmatch(r"\d{1,3}", w[1]) else None
        return {"state": w[0] if w else "?", "exit": 0 if w[:1] == ["done"] else code, "attempt": 1}
    if not isinstance(st, dict):
        return None
    if isinstance(st.get("submission"), int) and st["submission"] not in (number, 0):
        return None
    code = st.get("exit")
    attempt = st.get("attempt")
    return {"state": str(st.get("state", "?")),
            "exit": code if isinstance(code, int) and not isinstance(code, bool) else None,
            "attempt": attempt if isinstance(attempt, int) and not isinstance(attempt, bool) and attempt > 0 else 1}


PENDING_STATES = ("PENDING", "REQUEUED", "REQUEUE_HOLD", "REQUEUE_FED", "SUSPENDED", "RESV_DEL_HOLD")
RUNNING_STATES = ("RUNNING", "CONFIGURING", "COMPLETING", "STAGE_OUT", "SIGNALING", "RESIZING")
# What Slurm knows better than the task: it stopped the task for these.
SLURM_FAILURES = ("TIMEOUT", "OUT_OF_MEMORY", "NODE_FAIL", "BOOT_FAIL", "DEADLINE", "PREEMPTED")


def frame_state(slurm, status, upstream):
    """What happened to one task (a stage's frame): {state, reason,
    exit_code, attempts}, from Slurm's view of it (slurm), its status file
    (status) and the state of the stage it waited for (upstream)."""
    st = status or {}
    tried = st.get("attempt", 0) if status else 0
    code = st.get("exit")
    sl = slurm or {}
    sstate = sl.get("state", "")
    restarts = sl.get("restarts", 0)

    def result(state, reason=None, exit_code=code, attempts=tried):
        return {"state": state, "reason": reason, "exit_code": exit_code, "attempts": attempts}

    if sstate in PENDING_STATES:
        if restarts or st.get("state") == "retrying":
            return result("pending", "retry", attempts=max(restarts, tried))
        return result("pending", None, None, 0)
    if sstate in RUNNING_STATES:
        return result("running", None, None, max(restarts + 1, tried))
    slurm_code = code if code is not None else sl.get("exit")
    if sstate in SLURM_FAILURES:  # a time limit's SIGTERM looks like a cancel to the task
        return result("failed", sstate.lower(), slurm_code, max(tried, 1))
    if st.get("state") == "done":
        return result("done", exit_code=0)
    if st.get("state") == "failed":
        return result("failed")
    if st.get("state") == "cancelled" or (sstate == "CANCELLED" and "Dependency" not in sl.get("reason", "")):
        return result("cancelled", exit_code=slurm_code)
    if sstate == "CANCELLED":  # the task it waited for did not succeed
        return result("not_run", "cancelled" if upstream == "cancelled" else "failed", None, 0)
    if sstate == "FAILED":  # ended before it wrote its status file
        return result("failed", None, slurm_code, max(tried, 1))
    if st.get("state") in ("running", "retrying"):
        return result("lost")
    if sstate == "COMPLETED":
        return result("done", exit_code=0, attempts=max(tried, 1))
    return result("not_run", None, None, 0)


def state_label(fs, retries):
    """A frame_state as `status` prints it."""
    state, reason, code, attempts = fs["state"], fs["reason"], fs["exit_code"], fs["attempts"]
    if state == "pending" and reason == "retry":
        return "pending (attempt %d of %d)" % (attempts + 1, retries)
    if state == "done":
        return "up to date" if fs.get("skipped") else "done" if attempts <= 1 else "done (attempt %d)" % attempts
    if state == "failed":
        return "failed (%s)" % (reason or "exit %s" % ("?" if code is None else code))
    if state == "not_run" and reason:
        return "not run (an earlier stage %s)" % ("was cancelled" if reason == "cancelled" else "failed")
    if state == "not_run":
        return "not run"
    if state == "lost":
        return "lost (started, not finished, unknown to Slurm now)"
    return state


def status_report(spec):
    """Everything `status` says, as the --json object (docs/farm.md)."""
    frames = parse_frames(spec["frames"])
    subs = spec.get("submissions") or []
    latest = subs[-1] if subs else {"frames": "", "skipped": "", "jobs": {}}
    number = len(subs)
    queued = parse_frame_list(latest.get("frames", ""))
    index_of = {f: i for i, f in enumerate(queued)}
    skipped = set(parse_frame_list(latest.get("skipped", "")))
    jobs = latest["jobs"]
    tasks = slurm_tasks(jobs, len(queued))
    retries = spec.get("retries", 0)
    report = {"format": "sss-farm status 1", "name": spec["name"], "workdir": spec["workdir"],
              "spec": spec["path"], "frames": spec["frames"], "retries": retries, "submission": number,
              "submitted": latest.get("time"), "queued": latest.get("frames", ""),
              "skipped": latest.get("skipped", ""), "split": spec.get("split"), "stages": {}}
    order = []
    for s in spec["stages"]:
        if s["stage"] == "filter":
            order += part_stages(spec)
        order.append(s["stage"])
    upstream = {}  # frame -> the state of the stage the next one waits for
    for st in order:
        job = jobs.get(st)
        tool = "ptfilter" if st.startswith("filter-part") else stage_of(spec, st)["tool"]
        entry = {"tool": tool, "job": job, "frames": {}}
        for f in frames:
            i = index_of.get(f)
            if f in skipped:
                fs = {"state": "done", "reason": "up to date", "exit_code": None, "attempts": 0}
            elif i is None:
                fs = {"state": "not_run", "reason": None, "exit_code": None, "attempts": 0}
            else:
                fs = frame_state(tasks.get(job, {}).get(i), read_status(spec, st, f, number),
                                 upstream.get(f))
            fs = dict(fs, frame=f, index=i, skipped=f in skipped, log=log_path(spec, st, f))
            if not st.startswith("filter-part"):
                outs = stage_outputs(spec, st, f)
                fs["outputs"] = outs
                fs["outputs_exist"] = all(os.path.exists(x) for x in outs) if outs else None
            entry["frames"][str(f)] = fs
        report["stages"][st] = entry
        if not st.startswith("filter-part") and not stage_of(spec, st)["tool"] == "render":
            upstream = {f: entry["frames"][str(f)]["state"] for f in frames}
    states = [fs["state"] for e in report["stages"].values() for fs in e["frames"].values()]
    if any(x in ("pending", "running") for x in states):
        report["result"], report["exit"] = "running", STATUS_RUNNING
    elif any(x != "done" for x in states):
        report["result"], report["exit"] = "failed", STATUS_FAILED
    else:
        report["result"], report["exit"] = "done", STATUS_DONE
    return report


def cmd_status(a):
    if a.spec:
        path = a.spec
    elif a.name:
        if not re.fullmatch(NAME_RE, a.name):
            raise Usage("--name %s: use letters, digits, '_', '.' and '-'" % quoted(a.name))
        path = spec_path(os.path.realpath(a.workdir), a.name)
    else:
        raise Usage("status: give the spec (DIR/.sss-farm/NAME.json) or --workdir DIR --name NAME")
    spec = load_spec(path)
    check_spec_place(spec, path)
    check_in_workdir(spec, os.path.join(spec_dir(spec["workdir"]), "status"), "status folder")
    report = status_report(spec)
    if a.json:
        say(json.dumps(report, indent=1))
        return report["exit"]
    say("%s: %s, frames %s, in %s" % (PROG, spec["name"], spec["frames"], spec["workdir"]))
    if spec.get("split"):
        say("  split: frames with more than %d points are filtered in %d parts"
            % (spec["split"]["points"], spec["split"]["parts"]))
    if report["submission"]:
        say("  submitted %s (submission %d): queued %s; up to date, not queued: %s; retries %d" % (
            report["submitted"] or "?", report["submission"], report["queued"] or "-", report["skipped"] or "-",
            report["retries"]))
    else:
        say("  not submitted")
    width = max(len(x) for x in report["stages"])
    for st, entry in report["stages"].items():
        by = {}
        for fs in entry["frames"].values():
            by.setdefault(state_label(fs, report["retries"] + 1), []).append(fs["frame"])
        parts = ["%s %s" % (k, shown_frames(v)) for k, v in sorted(by.items(), key=lambda kv: min(kv[1]))]
        outs = ""
        if not st.startswith("filter-part"):
            known = [fs for fs in entry["frames"].values() if fs["outputs_exist"] is not None]
            have = [fs["frame"] for fs in known if fs["outputs_exist"]]
            outs = "; outputs exist: %s" % shown_frames(have) if known else "; outputs: unknown"
        say("  %-*s job %-8s %s%s" % (width, st, entry["job"] or "-", "; ".join(parts), outs))
    counts = {}
    for entry in report["stages"].values():
        for fs in entry["frames"].values():
            counts[fs["state"]] = counts.get(fs["state"], 0) + 1
    say("  %s (exit %d): %s" % (report["result"], report["exit"],
                                ", ".join("%d %s" % (n, k.replace("_", " ")) for k, n in sorted(counts.items()))))
    return report["exit"]

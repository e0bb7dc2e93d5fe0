# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The calls to Slurm: sbatch's array limit, what squeue, scontrol and sacct
say of a submission's jobs, and a task's requeue of itself. (sbatch and
scancel themselves are run by `submit`.)"""

import os
import re
import signal
import subprocess

from .common import warn


def sbatch_max_array_size():
    try:
        r = subprocess.run(["scontrol", "show", "config"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    m = re.search(r"^MaxArraySize\s*=\s*(\d+)", r.stdout, re.M)
    return int(m.group(1)) if m else None


def queued_jobs(jobs):
    """The job ids (of jobs: stage -> id) that squeue still lists."""
    ids = [j for j in jobs.values() if re.fullmatch(r"\d+", str(j))]
    if not ids:
        return []
    try:
        r = subprocess.run(["squeue", "-h", "-j", ",".join(ids), "-o", "%F"], capture_output=True, text=True,
                           timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return []
    return sorted(set(r.stdout.split()) & set(ids), key=int)


def slurm_exit(text):
    """Slurm's ExitCode "N:S" as a shell reports it: N, or 128 + S when a
    signal S ended the task; None when unknown."""
    m = re.fullmatch(r"(\d+):(\d+)", text or "")
    if not m:
        return None
    return 128 + int(m.group(2)) if int(m.group(2)) else int(m.group(1))


def slurm_tasks(jobs, count):
    """{array job id: {array index: {state, reason, exit, restarts}}} from
    scontrol (while Slurm remembers the job: MinJobAge), squeue, and sacct for
    what they no longer know of the `count` indices (when the cluster keeps
    accounting)."""
    ids = [j for j in jobs.values() if re.fullmatch(r"\d+", str(j))]
    found = {j: {} for j in ids}
    if not ids:
        return found

    def slurm(cmd):
        try:
            return subprocess.run(cmd, capture_output=True, text=True, errors="replace",
                                  timeout=60).stdout.splitlines()
        except (OSError, subprocess.TimeoutExpired):
            return []

    lines = slurm(["scontrol", "-o", "show", "job", ",".join(ids)])
    if not lines:  # an unknown id makes scontrol refuse the list: ask one by one
        for j in ids:
            lines += slurm(["scontrol", "-o", "show", "job", j])
    for line in lines:
        f = dict(re.findall(r"(\w+)=(\S*)", line))
        job, tasks = f.get("ArrayJobId"), f.get("ArrayTaskId")
        if job not in found or not tasks:
            continue
        restarts = int(f["Restarts"]) if re.fullmatch(r"\d{1,6}", f.get("Restarts", "")) else 0
        for task in expand_task_ids(tasks):
            found[job][task] = {"state": f.get("JobState", "?"), "reason": f.get("Reason", ""),
                                "exit": slurm_exit(f.get("ExitCode")), "restarts": restarts}
    for line in slurm(["squeue", "-h", "-r", "-j", ",".join(ids), "-o", "%F %K %T %r"]):
        w = line.split()
        if len(w) >= 3 and w[0] in found:
            for task in expand_task_ids(w[1]):
                old = found[w[0]].get(task, {})
                found[w[0]][task] = {"state": w[2], "reason": w[3] if len(w) > 3 else "", "exit": None,
                                     "restarts": old.get("restarts", 0)}
    if any(len(tasks) < count for tasks in found.values()):
        for line in slurm(["sacct", "-n", "-P", "-X", "-j", ",".join(ids), "--format=JobID,State,ExitCode"]):
            w = line.split("|")
            m = re.fullmatch(r"(\d+)_(\[?[\d,:-]+\]?)", w[0]) if len(w) >= 3 else None
            if not m or m.group(1) not in found:
                continue
            for task in expand_task_ids(m.group(2)):
                found[m.group(1)].setdefault(task, {"state": (w[1].split() or ["?"])[0], "reason": "",
                                                    "exit": slurm_exit(w[2]), "restarts": 0})
    return found


def expand_task_ids(text):
    out = []
    text = text.split("%")[0].strip("[]")
    for part in text.split(","):
        m = re.fullmatch(r"(\d+)(?:-(\d+))?(?::(\d+))?", part)
        if m:
            a = int(m.group(1))
            b = int(m.group(2) or a)
            out += list(range(a, min(b, a + 10 ** 7) + 1, int(m.group(3) or 1)))
    return out


def requeue_self():
    """Puts this array task back in Slurm's queue (scontrol requeue): Slurm
    stops it, keeps the tasks that wait for it waiting, and starts it again
    after its requeue delay with SLURM_RESTART_COUNT one more. False when
    Slurm refuses."""
    job, index = os.environ.get("SLURM_ARRAY_JOB_ID", ""), os.environ.get("SLURM_ARRAY_TASK_ID", "")
    if not (re.fullmatch(r"\d+", job) and re.fullmatch(r"\d+", index)):
        return False
    for sig in (signal.SIGTERM, signal.SIGINT):  # the requeue's own stop is not a cancel
        signal.signal(sig, signal.SIG_IGN)
    try:
        r = subprocess.run(["scontrol", "requeue", "%s_%s" % (job, index)], capture_output=True, text=True,
                           timeout=120)
    except (OSError, subprocess.TimeoutExpired) as e:
        warn("cannot requeue %s_%s: %s" % (job, index, e))
        return False
    if r.returncode != 0:
        warn("cannot requeue %s_%s: %s" % (job, index, (r.stderr or r.stdout).strip()))
        return False
    return True

# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""submit: the stages and resources from the command line, the tools' -check,
the frames that need work, and one sbatch array per stage."""

import os
import re
import shlex
import subprocess
import sys
import time

from .common import (DEFAULT_CPUS, DEFAULT_MAX_ARRAY_SIZE, DEFAULT_MEM_MB, MAX_RETRIES, PROG, SPEC_FORMAT,
                     STAGE_TOOLS, Failure, Usage, quote_cmd, quoted, say, warn)
from .frames import MAX_PARTS, compact, parse_frames, shown_frames
from .slurm import queued_jobs, sbatch_max_array_size
from .spec import (NAME_RE, latest_jobs, load_spec, part_stages, save_spec, spec_dir, spec_path,
                   stage_of)
from .stages import filter_files, frame_needs_work, has_option, part_file, tool_command


def stage_resource(values, stage, default, what):
    """-c 2 -c render=4: the value for a stage ('render2' falls back to 'render')."""
    result = default
    per_stage = {}
    for v in values or []:
        m = re.fullmatch(r"(?:([a-z0-9-]+)=)?(\d+)", v)
        if not m or int(m.group(2)) <= 0:
            raise Usage("%s '%s': give N or STAGE=N with N > 0" % (what, v))
        if m.group(1):
            if m.group(1) not in ("bake", "filter", "brick", "render", "part"):
                raise Usage("%s '%s': unknown stage '%s' (bake, filter, part, brick, render)"
                            % (what, v, m.group(1)))
            per_stage[m.group(1)] = int(m.group(2))
        else:
            result = int(m.group(2))
    base = re.sub(r"\d+$", "", stage)
    if stage.startswith("filter-part"):
        return per_stage.get("part", per_stage.get("filter", result))
    return per_stage.get(base, result)


def self_path():
    return os.path.realpath(sys.argv[0])


def default_bin_dir():
    env = os.environ.get("SSS_BIN_DIR")
    if env:
        return os.path.realpath(env)
    return os.path.dirname(self_path())


def build_stages(a):
    """The stages of a submission, from --bake ... --render, with their cores
    and memory; the split, from --splitpoints and --parts."""
    stages = []
    for stage in ("bake", "filter", "brick"):
        text = getattr(a, stage)
        if text is not None:
            stages.append({"stage": stage, "tool": STAGE_TOOLS[stage], "args": split_args(stage, text)})
    for i, text in enumerate(a.render or []):
        stages.append({"stage": "render" if i == 0 else "render%d" % (i + 1), "tool": "render",
                       "args": split_args("render", text)})
    if not stages:
        raise Usage("nothing to submit: give at least one of --bake, --filter, --brick, --render")

    split = None
    if a.splitpoints is not None or a.parts is not None:
        if a.splitpoints is None or a.parts is None:
            raise Usage("--splitpoints and --parts go together")
        if a.splitpoints < 0:
            raise Usage("--splitpoints %d: must be >= 0" % a.splitpoints)
        if not 2 <= a.parts <= MAX_PARTS:
            raise Usage("--parts %d: must be from 2 to %d" % (a.parts, MAX_PARTS))
        if "filter" not in [s["stage"] for s in stages]:
            raise Usage("--splitpoints/--parts split the filter stage: give --filter too")
        split = {"points": a.splitpoints, "parts": a.parts}
    for s in stages:
        if s["tool"] == "ptfilter":
            ins, out = filter_files(s["args"])
            if not ins:
                raise Usage("--filter: no input cloud (.ptc/.ply) before the output '%s'" % out)
            if split and not re.search(r"\.(ptc|ply)$", out or "", re.I):
                raise Usage("--filter: the output '%s' must end in .ptc or .ply" % out)
    for s in stages:
        s["cpus"] = stage_resource(a.cpus, s["stage"], DEFAULT_CPUS, "-c")
        s["mem"] = stage_resource(a.mem, s["stage"], DEFAULT_MEM_MB, "--mem")
    return stages, split


def check_arguments(spec, frames):
    """Runs every stage's tool with -check and the options a task adds, for the
    first and the last frame (and a part's command when the filter is split):
    the tool's own parser refuses what it would refuse on the farm. Usage with
    the tool's ERROR line when one refuses."""
    cwd = spec["workdir"] if os.path.isdir(spec["workdir"]) else None
    split = spec.get("split")
    for s in spec["stages"]:
        commands = []
        for frame in sorted({frames[0], frames[-1]}):
            commands.append((frame, tool_command(spec, s, frame)))
            if split and s["tool"] == "ptfilter":
                n = split["parts"]
                out = part_file(filter_files(s["args"])[1], 1, n)
                commands.append((frame, tool_command(spec, s, frame, ["-part", "1/%d" % n], out)))
        for frame, cmd in commands:
            cmd.insert(1, "-check")
            try:
                r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, errors="replace",
                                   stdin=subprocess.DEVNULL, timeout=120)
            except OSError as e:
                raise Failure("cannot run %s: %s" % (cmd[0], e.strerror))
            except subprocess.TimeoutExpired:
                raise Failure("%s -check did not answer in 120 s" % s["tool"])
            if r.returncode == 0:
                continue
            lines = [x for x in r.stderr.splitlines() if x.startswith(s["tool"] + " ERROR: ")]
            why = lines[0] if lines else "%s -check exited with %d: %s" % (
                s["tool"], r.returncode, r.stderr.strip()[-500:])
            base = re.sub(r"\d+$", "", s["stage"])
            where = "--" + base + ("" if base == s["stage"] else " (%s)" % s["stage"])
            message = "%s, frame %d: %s" % (where, frame, why)
            if r.returncode == 2:
                raise Usage(message, hint="%s: try '%s --help'" % (PROG, s["tool"]))
            raise Failure(message)


def plan_frames(spec, frames, force):
    """(queued, skipped): the frames that need work (frame_needs_work) and the
    ones whose outputs are all up to date; every frame is queued with force."""
    if force:
        return list(frames), []
    queued, skipped = [], []
    for f in frames:
        (queued if frame_needs_work(spec, f) else skipped).append(f)
    return queued, skipped


def previous_spec(path):
    """The spec a new submission of the same name replaces, or None; refuses
    while jobs of its latest submission are queued."""
    if not os.path.lexists(path):
        return None
    old = load_spec(path, older=True)
    queued = queued_jobs(latest_jobs(old))
    if queued:
        raise Failure("%s: jobs of the previous submission are still queued (%s): wait for them,"
                      " or cancel them (scancel %s)" % (old["name"], ", ".join(queued), " ".join(queued)))
    if old["format"] != SPEC_FORMAT:
        warn("%s: replacing a spec of an older sss-farm (its history is not kept)" % path)
        return None
    return old


def cmd_submit(a):
    frames = parse_frames(a.frames)
    workdir = os.path.realpath(a.workdir)
    name = a.name
    if not re.fullmatch(NAME_RE, name):
        raise Usage("--name %s: use letters, digits, '_', '.' and '-' (at most 100)" % quoted(name))
    if not 0 <= a.retries <= MAX_RETRIES:
        raise Usage("--retries %d: must be from 0 to %d" % (a.retries, MAX_RETRIES))
    bin_dir = default_bin_dir()
    stages, split = build_stages(a)

    tools = sorted({s["tool"] for s in stages} | ({"ptinfo"} if split else set()))
    missing = [t for t in tools if not os.access(os.path.join(bin_dir, t), os.X_OK)]
    if missing:
        raise Failure("no %s in %s (build first: scripts/build, or set SSS_BIN_DIR to the tools' folder)"
                      % (", ".join(missing), bin_dir))

    path = spec_path(workdir, name)
    spec = {"format": SPEC_FORMAT, "name": name, "workdir": workdir, "path": path,
            "bin_dir": bin_dir, "frames": compact(frames), "retries": a.retries, "split": split,
            "stages": stages, "submissions": []}
    check_arguments(spec, frames)

    queued, skipped = plan_frames(spec, frames, a.force)
    prefix = "# " if a.dry_run else ""  # a dry run prints a shell script
    if skipped:
        say("%s%s: %d of %d frames up to date (outputs newer than inputs), not queued: %s; --force queues them"
            % (prefix, PROG, len(skipped), len(frames), shown_frames(skipped)))
    max_array = None if a.dry_run else sbatch_max_array_size()
    limit = max_array or DEFAULT_MAX_ARRAY_SIZE
    if len(queued) > limit:
        raise Failure("%d frames to queue, more than Slurm's array limit MaxArraySize = %d%s (array indices go"
                      " from 0 to %d): submit fewer frames at a time, or raise MaxArraySize in slurm.conf"
                      % (len(queued), limit, "" if max_array else " (Slurm's default)", limit - 1))

    old = None if a.dry_run else previous_spec(path)
    if old is None and a.dry_run and os.path.isfile(path):
        try:
            old = load_spec(path)
        except Failure:
            old = None
    spec["submissions"] = old["submissions"] if old else []
    number = len(spec["submissions"]) + 1
    if not a.dry_run:
        os.makedirs(os.path.join(workdir, "logs"), exist_ok=True)
        os.makedirs(os.path.join(spec_dir(workdir), "status"), exist_ok=True)
        # Recorded before the first sbatch: a task that starts at once finds its frames.
        spec["submissions"].append({"time": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "frames": compact(queued),
                                    "skipped": compact(skipped), "jobs": {}})
        save_spec(spec, path)
    if not queued:
        say("%s%s: %s: every frame is up to date; nothing queued" % (prefix, PROG, name))
        return 0
    say("%s%s: %s: queuing %d frame%s (%s) as array %s" % (
        prefix, PROG, name, len(queued), "" if len(queued) == 1 else "s", shown_frames(queued),
        "index 0" if len(queued) == 1 else "indices 0-%d" % (len(queued) - 1)))
    submit_arrays(a, spec, number, queued)
    if not a.dry_run:
        say("%s: %s: status with: %s status %s" % (PROG, name, PROG, shlex.quote(path)))
    return 0


def submit_arrays(a, spec, number, queued):
    """One sbatch array per stage (and per part of a split filter), indices
    0..n-1 for the n queued frames, each chained to the stage before it."""
    workdir, name, path = spec["workdir"], spec["name"], spec["path"]
    me = self_path()
    array = "0-%d" % (len(queued) - 1) if len(queued) > 1 else "0"
    jobs = {}
    submitted = []

    def submit_one(stage, tool_stage, deps, part=None):
        s = stage_of(spec, tool_stage)
        cpus = stage_resource(a.cpus, stage, DEFAULT_CPUS, "-c")
        mem = stage_resource(a.mem, stage, DEFAULT_MEM_MB, "--mem")
        task = [me, "task", path, tool_stage, "--submission", str(number)] + (["--part", str(part)] if part else [])
        # The task writes its frame's log itself; Slurm's file keeps what comes
        # before (and slurmstepd's own lines). sbatch expands %: a % of DIR is %%.
        cmd = ["sbatch", "--parsable", "--job-name=sss-%s-%s" % (name, stage), "--array=" + array,
               "--chdir=" + workdir,
               "--output=%s/logs/%s-%s.slurm.log" % (workdir.replace("%", "%%"), name, stage),
               "--open-mode=append", "--requeue", "--cpus-per-task=%d" % cpus, "--mem=%d" % mem]
        if a.partition:
            cmd.append("--partition=" + a.partition)
        if deps:
            ids = [jobs.get(d, "<%s-jobid>" % d) for d in deps]
            cmd += ["--dependency=aftercorr:" + ":".join(ids), "--kill-on-invalid-dep=yes"]
        cmd += a.sbatch or []
        cmd.append("--wrap=exec " + quote_cmd(task))
        if a.dry_run:
            say(quote_cmd(cmd))
            jobs[stage] = "<%s-jobid>" % stage
            return
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        except OSError as e:
            raise Failure("cannot run sbatch: %s (is Slurm installed, and SLURM_CONF set?)" % e.strerror)
        except subprocess.TimeoutExpired:
            raise Failure("sbatch did not answer in 300 s")
        if r.returncode != 0 or not re.match(r"^\d+", r.stdout.strip()):
            raise Failure("sbatch for stage %s failed (exit %d): %s"
                          % (stage, r.returncode, (r.stderr or r.stdout).strip()))
        job = r.stdout.strip().split(";")[0]
        jobs[stage] = job
        submitted.append(job)
        spec["submissions"][-1]["jobs"][stage] = job
        save_spec(spec, path)
        say("%s: submitted %s as job %s (frames %s)" % (PROG, stage, job, shown_frames(queued)))

    try:
        previous = []  # the stage the next one waits for
        for s in spec["stages"]:
            st = s["stage"]
            if st == "filter" and spec.get("split"):
                parts = part_stages(spec)
                for k, ps in enumerate(parts, 1):
                    submit_one(ps, "filter", previous, part=k)
                submit_one("filter", "filter", parts)
                previous = ["filter"]
            elif s["tool"] == "render":
                submit_one(st, st, previous)  # every render waits for the last other stage
            else:
                submit_one(st, st, previous)
                previous = [st]
    except Failure as e:
        if submitted:  # no half chain: cancel what this submission queued
            subprocess.run(["scancel"] + submitted, capture_output=True)
            raise Failure("%s; cancelled the arrays this submission had queued (%s)" % (e, ", ".join(submitted)))
        raise


def split_args(stage, text):
    try:
        args = shlex.split(text)
    except ValueError as e:
        raise Usage("--%s '%s': %s" % (stage, text, e))
    if not args:
        raise Usage("--%s: empty argument string" % stage)
    for forbidden in ("frame", "check"):
        if has_option(args, forbidden):
            raise Usage("--%s: leave out -%s, sss-farm adds it" % (stage, forbidden))
    return args

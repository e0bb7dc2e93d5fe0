# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""What a stage reads and writes (for the split decision and for `status`),
and the tool's command a stage runs for a frame (for `task` and for the
-check at submission)."""

import os
import re

from .common import Failure
from .frames import expand_frame
from .spec import read_regular, stage_of


def filter_files(args):
    """ptfilter's file arguments: (inputs, output). The output is the last
    word; the inputs are the words before it ending in .ptc or .ply."""
    if not args:
        return [], None
    out = args[-1]
    ins = [a for a in args[:-1] if not a.startswith("-") and re.search(r"\.(ptc|ply)$", a, re.I)]
    return ins, out


def option_value(args, name):
    for i, a in enumerate(args[:-1]):
        if a.lstrip("-") == name and a.startswith("-"):
            return args[i + 1]
    return None


def has_option(args, name):
    return any(a.startswith("-") and a.lstrip("-") == name for a in args)


_rib_texts = {}  # path -> text: a RIB most frames share is read once per run


def rib_strings(path, pattern):
    if path not in _rib_texts:
        try:
            _rib_texts[path] = read_regular(path, 4 << 20, "RIB", cut=True).decode("utf-8", "replace")
        except Failure:
            _rib_texts[path] = ""
    return re.findall(pattern, _rib_texts[path])


def stage_outputs(spec, stage, frame):
    """The files a stage writes for a frame, as far as sss-farm can tell."""
    s = stage_of(spec, stage)
    args = s["args"]
    wd = spec["workdir"]
    tool = s["tool"]
    names = []
    if tool in ("ptfilter", "brickmake"):
        if args:
            names = [args[-1]]
    elif tool == "ptbake":
        o = option_value(args, "o")
        if o:
            names = [o]
        elif args:
            rib = expand_frame(args[-1], frame)
            names = rib_strings(os.path.join(wd, rib), r'"filename"\s*\[?\s*"([^"]+\.(?:ptc|ply))"')
            if not names:
                names = rib_strings(os.path.join(wd, rib), r'"([^"\s]+\.(?:ptc|ply))"')
    elif tool == "render":
        o = option_value(args, "o")
        if o:
            names = [o]
        elif args:
            rib = expand_frame(args[-1], frame)
            names = rib_strings(os.path.join(wd, rib), r'Display\s+"([^"]+)"')[:1]
    out = []
    for n in names:
        try:
            out.append(os.path.join(wd, expand_frame(n, frame)))
        except Failure:
            pass
    return out


def up_to_date(outputs, inputs):
    """-newer 1's rule: every output exists and is strictly newer than every input."""
    try:
        oldest_out = min(os.stat(o).st_mtime_ns for o in outputs)
        newest_in = max(os.stat(i).st_mtime_ns for i in inputs)
    except (OSError, ValueError):
        return False
    return oldest_out > newest_in


def stage_inputs(spec, stage, frame):
    """The files a stage reads for a frame that sss-farm can name: the clouds
    of ptfilter and brickmake (and -blocker's), the RIB of ptbake and render
    (not what the RIB reads: the tools' own -newer 1 sees those)."""
    s = stage_of(spec, stage)
    args = s["args"]
    if s["tool"] in ("ptfilter", "brickmake"):
        names = filter_files(args)[0]
    else:
        names = args[-1:]
    out = []
    for n in names:
        try:
            out.append(os.path.join(spec["workdir"], expand_frame(n, frame)))
        except Failure:
            pass
    return out


def frame_needs_work(spec, frame):
    """Whether a submission must queue the frame: some stage's outputs are
    unknown, missing, or not newer than its inputs and than the outputs of the
    stages before it (the rule of -newer 1 over the chain), or its arguments
    say -newer 0."""
    earlier = []  # the outputs of the stages before, for this frame
    for s in spec["stages"]:
        outputs = stage_outputs(spec, s["stage"], frame)
        if not outputs or option_value(s["args"], "newer") == "0":
            return True
        if not up_to_date(outputs, stage_inputs(spec, s["stage"], frame) + earlier):
            return True
        if s["tool"] != "render":  # every render reads what the stages before made
            earlier += outputs
    return False


def tool_path(spec, tool):
    return os.path.join(spec["bin_dir"], tool)


def added_options(args, frame, threads=True):
    extra = ["-frame", str(frame)]
    if not has_option(args, "newer"):
        extra += ["-newer", "1"]
    if threads and not has_option(args, "threads"):
        extra += ["-threads", os.environ.get("SLURM_CPUS_PER_TASK", "0")]
    return extra


def tool_command(spec, s, frame, extra=(), output=None):
    """The tool's command for a frame: the stage's arguments with -frame,
    -newer 1 and -threads added (and `extra`; `output` replaces the last word)."""
    args = list(s["args"])
    if output is not None:
        args[-1] = output
    cmd = [tool_path(spec, s["tool"])]
    # ptfilter's mode word stays first (ptfilter -ssdiffusion -frame 1 ...).
    if s["tool"] == "ptfilter" and args and args[0] in ("-ssdiffusion", "--ssdiffusion"):
        cmd.append(args.pop(0))
    elif s["tool"] == "ptfilter" and len(args) > 1 and args[0].lstrip("-") == "filter":
        cmd += args[:2]
        args = args[2:]
    return cmd + added_options(s["args"], frame) + list(extra) + args


def part_file(out_pattern, k, n):
    return "%s.part%dof%d.ptpart" % (out_pattern, k, n)

# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Frame numbers and patterns (the tools' rules, include/sss/util/frame_pattern.h):
--frames lists, their compact form, and frame patterns expanded."""

import re

from .common import Failure, Usage, one_line


_PATTERN = re.compile(r"%%|#+|%0?(\d*)d|\$\{F(\d*)\}|\$F(?!F)(\d*)")

# The widest frame pattern the tools expand (include/sss/util/frame_pattern.cpp):
# a wider one (%017d, $F17, 17 #s) is kept as it is written, not expanded.
MAX_PATTERN_WIDTH = 16
# The largest frame the tools' -frame takes (include/sss/cli/job.h); frames are
# not array task ids, so Slurm's MaxArraySize does not bound them.
MAX_FRAME = 1000000
# Each part is one more sbatch array; more than this would not fit Slurm's
# default MaxJobCount (10000) beside a few frames' worth of other jobs.
MAX_PARTS = 1000


def expand_frame(path, frame):
    """Expands %04d, %d, ####, $F4, ${F4} and %% as the tools do."""

    def repl(m):
        text = m.group(0)
        if text == "%%":
            return "%"
        if text.startswith("#"):
            if len(text) == 1:
                raise Failure("%s: a lone '#' is ambiguous (use #### or %%04d)" % one_line(path))
            width = len(text)
        elif text.startswith("%"):
            digits = m.group(1)
            if digits and not text.startswith("%0"):
                return text  # %4d is not a pattern for the tools either
            width = int(digits) if digits and len(digits) <= 3 else (0 if not digits else MAX_PATTERN_WIDTH + 1)
        else:
            digits = m.group(2) if m.group(2) is not None else m.group(3)
            width = int(digits) if digits and len(digits) <= 3 else (0 if not digits else MAX_PATTERN_WIDTH + 1)
        if width > MAX_PATTERN_WIDTH:
            return text
        return "%0*d" % (width, frame)

    return _PATTERN.sub(repl, path)


def parse_frames(text, error=None):
    """'1001-1100', '7', '1-9:2', '1,5,10-20:5' -> the sorted list of frames,
    each once. Refuses negatives and frames above MAX_FRAME before anything is
    expanded."""
    error = error or Usage
    shown = one_line(text)[:200]
    ranges = []
    for part in text.split(","):
        part = part.strip()
        m = re.fullmatch(r"(-?\d{1,12})(?:-(-?\d{1,12})(?::(-?\d{1,12}))?)?", part)
        if not m:
            raise error("--frames: '%s' is not a list of frames (A, A-B or A-B:STEP, separated by commas)"
                        % shown)
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) is not None else a
        step = int(m.group(3)) if m.group(3) is not None else 1
        if a < 0 or b < 0:
            raise error("--frames %s: frame numbers cannot be negative" % shown)
        if b < a:
            raise error("--frames %s: the range %d-%d is empty" % (shown, a, b))
        if step < 1:
            raise error("--frames %s: the step of %s must be 1 or more" % (shown, part))
        if b > MAX_FRAME:
            raise error("--frames %s: frame %d is above %d, the largest frame the tools take (-frame)"
                        % (shown, b, MAX_FRAME))
        ranges.append(range(a, b + 1, step))
    frames = set()
    for r in ranges:
        frames.update(r)
    return sorted(frames)


def parse_frame_list(text, error=None):
    """parse_frames, with "" for no frame (a submission that queued none)."""
    return parse_frames(text, error) if text else []


def compact(frames):
    """[1, 2, 3, 5] -> '1-3,5'; [1, 3, 5, 7] -> '1-7:2'; [] -> '' (the
    syntax of --frames, which parse_frames reads back)."""
    frames = sorted(set(frames))
    out = []
    i = 0
    while i < len(frames):
        j = i + 1
        if j < len(frames):
            step = frames[j] - frames[i]
            while j + 1 < len(frames) and frames[j + 1] - frames[j] == step:
                j += 1
            if step == 1 or j - i >= 2:  # a pair 3,7 stays a list
                out.append("%d-%d" % (frames[i], frames[j]) + ("" if step == 1 else ":%d" % step))
                i = j + 1
                continue
        out.append(str(frames[i]))
        i += 1
    return ",".join(out)


def shown_frames(frames):
    """compact(), '-' for none: for messages."""
    return compact(frames) or "-"

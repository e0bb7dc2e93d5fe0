# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The program's name and version, its defaults and limits, its two errors
(Failure: exit 1; Usage: exit 2) and the lines it prints."""

import shlex
import sys


PROG = "sss-farm"
VERSION = "0.2.0"

# The stages in chain order: name, tool.
STAGE_TOOLS = {"bake": "ptbake", "filter": "ptfilter", "brick": "brickmake", "render": "render"}
DEFAULT_CPUS = 2
DEFAULT_MEM_MB = 4096
DEFAULT_MAX_ARRAY_SIZE = 1001  # Slurm's default MaxArraySize
DEFAULT_RETRIES = 2  # requeues of a failed task: 3 attempts in all
MAX_RETRIES = 100
SPEC_FORMAT = "sss-farm 2"  # "sss-farm 1": array task id = frame (before 0.2)

# `status` exit codes (docs/farm.md): every frame done, some frame failed,
# cancelled or not run, or some frame still pending or running.
STATUS_DONE, STATUS_FAILED, STATUS_RUNNING = 0, 1, 3


class Failure(Exception):
    """A runtime failure: `sss-farm ERROR: <message>`, exit 1."""


class Usage(Exception):
    """A usage error: `sss-farm ERROR: <message>` and a hint, exit 2. `hint`
    replaces the usual "try 'sss-farm --help'" (a tool's refusal points at the
    tool's help)."""

    def __init__(self, message, hint=None):
        super().__init__(message)
        self.hint = hint


def one_line(text):
    text = str(text)
    out = []
    for ch in text:
        if ch == "\n":
            out.append("\\n")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append("\\x%02x" % ord(ch))
        else:
            out.append(ch)
    return "".join(out)[:4096]


def say(text):
    print(text, flush=True)


def warn(text):
    sys.stdout.flush()
    print("%s WARNING: %s" % (PROG, one_line(text)), file=sys.stderr, flush=True)


def quoted(text, limit=200):
    """`text` for a message: one line, quoted, cut after `limit` characters."""
    text = str(text)
    return '"%s%s"' % (one_line(text[:limit]), "..." if len(text) > limit else "")


def quote_cmd(words):
    return " ".join(shlex.quote(w) for w in words)

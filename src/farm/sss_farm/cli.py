# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The command line: the options of submit, task and status, their help (the
man page), and main(), which maps every error to one line and an exit code."""

import argparse
import os
import sys

from .common import (DEFAULT_CPUS, DEFAULT_MEM_MB, DEFAULT_RETRIES, PROG, STATUS_DONE, STATUS_FAILED,
                     STATUS_RUNNING, VERSION, Failure, Usage, one_line)
from .frames import MAX_FRAME
from .status import cmd_status
from .submit import cmd_submit
from .task import cmd_task


class Parser(argparse.ArgumentParser):
    """argparse with the project's error line: `sss-farm ERROR: ...`, exit 2."""

    def error(self, message):
        raise Usage(message)


SUBMIT_EPILOG = """\
Frames: any numbers from 0 to %(max)d, as a list of A, A-B and A-B:STEP
(1001-1100, 1-9:2, 1,5,10-20:5). Each stage is one Slurm job array whose
index is the frame's position in the list (0 .. n-1), so n must not exceed
MaxArraySize (scontrol show config; 1001 by default) whatever the numbers.

Before anything is queued, each stage's tool checks its arguments itself
(TOOL -check with the options a task adds): a refused argument fails the
submission with the tool's ERROR line, exit 2. Frames whose outputs all exist
and are newer than their inputs are not queued (--force queues them).

A task whose tool fails (any exit but 2, the usage error, and a cancel) is
requeued up to --retries times (scontrol requeue: another try after Slurm's
requeue delay, on any node); the stages after it wait for it.

exit status: 0 submitted (or nothing to do), 1 failure (sbatch refused, too
many frames, tools missing), 2 usage error (sss-farm's or a tool's -check).
""" % {"max": MAX_FRAME}

STATUS_EPILOG = """\
Per stage: the frames pending, running, done, failed (exit N, or timeout,
out_of_memory ... as Slurm says), cancelled, not run, or up to date (not
queued); and the frames whose outputs exist. --json prints the same as one
JSON object: per stage and frame, state, reason, exit_code, attempts, log.

exit status: %d every frame done (or up to date), %d some frame failed, was
cancelled or did not run (also: sss-farm's own errors), 2 usage error, %d some
frame still pending or running.
""" % (STATUS_DONE, STATUS_FAILED, STATUS_RUNNING)

TASK_EPILOG = """\
Run by each array task: the frame at position SLURM_ARRAY_TASK_ID of the
submission's frames (or --frame F, outside Slurm), with -frame F, -newer 1 and
-threads $SLURM_CPUS_PER_TASK added. An array task appends to its frame's log,
DIR/logs/NAME-STAGE.FFFF.log, and records DIR/.sss-farm/status/NAME.STAGE.F.

exit status: the tool's (1 failure, 2 usage error, 128+N killed by signal N);
0 when the task was requeued for another attempt.
"""

MAIN_EPILOG = """\
environment:
  SSS_BIN_DIR   the tools' folder (default: the folder of sss-farm), recorded
                at submission
  SLURM_CONF    the Slurm configuration sbatch, squeue and scontrol use
  SSS_ISA       exported at submission, the kernels' instruction set on every
                node (docs/farm.md)

See docs/farm.md.
"""


def sub_help(parser):
    """A sub-command's whole help, for the main --help (its man page)."""
    return parser.format_help().rstrip("\n") + "\n"


def main(argv):
    fmt = argparse.RawDescriptionHelpFormatter
    p = Parser(prog=PROG, formatter_class=fmt,
               description="Submits the sss chain (ptbake -> ptfilter -> brickmake -> render) over a list of\n"
                           "frames to Slurm, one job array per stage, retries failed tasks, and reports.")
    p.add_argument("--version", action="version", version="%s (sss) %s" % (PROG, VERSION))
    sub = p.add_subparsers(dest="command", metavar="{submit,task,status}", title="commands")

    s = sub.add_parser("submit", help="submit frames: one job array per stage", formatter_class=fmt,
                       description="Submits the frames of the chain to Slurm.", epilog=SUBMIT_EPILOG)
    s.add_argument("--frames", required=True, metavar="LIST",
                   help="the frames: A, A-B, A-B:STEP, separated by commas (1001-1100, 1-9:2)")
    s.add_argument("--workdir", default=".", help="where the tools run, logs/ and .sss-farm/ go (default .)")
    s.add_argument("--name", help="project name: job names sss-NAME-STAGE, spec DIR/.sss-farm/NAME.json"
                                  " (default: the work folder's name)")
    s.add_argument("--bake", metavar="ARGS", help="ptbake's arguments, e.g. \"-spacing 0.06 bake.rib\"")
    s.add_argument("--filter", metavar="ARGS", help="ptfilter's arguments (-ssdiffusion ... in.####.ptc out.####.ptc)")
    s.add_argument("--brick", metavar="ARGS", help="brickmake's arguments (in.####.ptc out.####.bkm)")
    s.add_argument("--render", metavar="ARGS", action="append",
                   help="render's arguments (repeatable: the stages render, render2, ...)")
    s.add_argument("-c", "--cpus", action="append", metavar="[STAGE=]N",
                   help="cores per task (default %d); STAGE=N for one stage (bake, filter, part, brick, render)"
                   % DEFAULT_CPUS)
    s.add_argument("--mem", action="append", metavar="[STAGE=]MB",
                   help="memory per task in MB (default %d); STAGE=MB for one stage" % DEFAULT_MEM_MB)
    s.add_argument("--partition", help="Slurm partition")
    s.add_argument("--sbatch", action="append", metavar="OPTION",
                   help="an extra sbatch option for every array, e.g. --sbatch=--time=2:00:00 (repeatable)")
    s.add_argument("--retries", type=int, default=DEFAULT_RETRIES, metavar="N",
                   help="requeue a failed task up to N times (default %d: %d attempts in all)"
                   % (DEFAULT_RETRIES, DEFAULT_RETRIES + 1))
    s.add_argument("--force", action="store_true",
                   help="queue every frame, also those whose outputs are up to date")
    s.add_argument("--splitpoints", type=int, metavar="P", help="split frames whose filter input has more than P points")
    s.add_argument("--parts", type=int, metavar="N", help="... into N parts, N tasks on N machines")
    s.add_argument("--dry-run", action="store_true",
                   help="check the arguments and print the sbatch commands; submit and write nothing")

    t = sub.add_parser("task", help="run one array task (what the jobs run)", formatter_class=fmt,
                       description="Runs one stage of one frame.", epilog=TASK_EPILOG)
    t.add_argument("spec", help="the spec, DIR/.sss-farm/NAME.json")
    t.add_argument("stage", help="bake, filter, brick, render, render2, ...")
    t.add_argument("--submission", type=int, metavar="N",
                   help="the submission whose frame list the array index counts in (submit passes it; default: the latest)")
    t.add_argument("--part", type=int, metavar="K", help="part K of a split filter stage")
    t.add_argument("--frame", type=int, metavar="F", help="the frame (default: from SLURM_ARRAY_TASK_ID)")

    st = sub.add_parser("status", help="report on the latest submission", formatter_class=fmt,
                        description="Reports on the latest submission of a spec.", epilog=STATUS_EPILOG)
    st.add_argument("spec", nargs="?", help="the spec, DIR/.sss-farm/NAME.json")
    st.add_argument("--workdir", default=".", help="with --name: the work folder (default .)")
    st.add_argument("--name", help="the spec DIR/.sss-farm/NAME.json")
    st.add_argument("--json", action="store_true", help="one JSON object (docs/farm.md)")
    for command, parser in (("submit", s), ("status", st), ("task", t)):
        parser._optionals.title = command + " options"  # their sections in the main help and man page
    p.epilog = "\n".join(sub_help(x) for x in (s, st, t)) + "\n" + MAIN_EPILOG

    # "--bake -spacing 0.06 bake.rib" style values start with a dash: bind
    # every value option to the next word (argparse would take it for an option).
    valued = {"--frames", "--workdir", "--name", "--bake", "--filter", "--brick", "--render", "--mem",
              "--partition", "--sbatch", "--splitpoints", "--parts", "-c", "--cpus", "--part", "--frame",
              "--retries", "--submission"}
    bound, i = [], 0
    while i < len(argv):
        if argv[i] in valued and i + 1 < len(argv):
            bound.append(argv[i] + "=" + argv[i + 1] if argv[i].startswith("--") else argv[i] + argv[i + 1])
            i += 2
        else:
            bound.append(argv[i])
            i += 1
    a = None
    try:
        a = p.parse_args(bound)
        if a.command == "submit":
            if a.name is None:
                a.name = os.path.basename(os.path.realpath(a.workdir)) or "sss"
            return cmd_submit(a)
        if a.command == "task":
            return cmd_task(a)
        if a.command == "status":
            return cmd_status(a)
        raise Usage("give a command: submit, task or status")
    except Usage as e:
        sys.stdout.flush()
        print("%s ERROR: %s" % (PROG, one_line(e)), file=sys.stderr)
        command = argv[0] + " " if argv and argv[0] in ("submit", "task", "status") else ""
        print(e.hint or "%s: try '%s %s--help'" % (PROG, PROG, command), file=sys.stderr)
        return 2
    except Failure as e:
        sys.stdout.flush()
        print("%s ERROR: %s" % (PROG, one_line(e)), file=sys.stderr)
        return 1
    except OSError as e:
        sys.stdout.flush()
        where = one_line(e.filename) + ": " if e.filename else ""
        print("%s ERROR: %s%s" % (PROG, where, one_line(e.strerror or e)), file=sys.stderr)
        return 1
    except MemoryError:
        sys.stdout.flush()
        print("%s ERROR: out of memory" % PROG, file=sys.stderr)
        return 1
    except Exception as e:  # never a traceback: one line a farm's log parser reads
        sys.stdout.flush()
        print("%s ERROR: internal error: %s: %s" % (PROG, type(e).__name__, one_line(e)[:1000]),
              file=sys.stderr)
        return 1

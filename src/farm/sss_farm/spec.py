# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The spec: DIR/.sss-farm/NAME.json (and the task status files and logs
beside it): its paths, reading it whole and checking it, writing it
atomically, its stages."""

import json
import os
import re
import stat

from .common import MAX_RETRIES, SPEC_FORMAT, STAGE_TOOLS, Failure, one_line, quoted
from .frames import MAX_PARTS, parse_frame_list, parse_frames


def spec_dir(workdir):
    return os.path.join(workdir, ".sss-farm")


def spec_path(workdir, name):
    return os.path.join(spec_dir(workdir), name + ".json")


def status_path(spec, stage, frame):
    return os.path.join(spec_dir(spec["workdir"]), "status", "%s.%s.%d" % (spec["name"], stage, frame))


def log_path(spec, record, frame):
    """A task's log: DIR/logs/NAME-STAGE.FFFF.log (the frame padded to 4)."""
    return os.path.join(spec["workdir"], "logs", "%s-%s.%04d.log" % (spec["name"], record, frame))


def write_atomic(path, text):
    # O_EXCL: a link planted at the temporary's name is not followed.
    tmp = "%s.%d.tmp" % (path, os.getpid())
    try:
        os.unlink(tmp)
    except FileNotFoundError:
        pass
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666)
    with os.fdopen(fd, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


MAX_SPEC_BYTES = 16 << 20


def read_regular(path, limit, what="file", cut=False):
    """The bytes of a regular file, at most `limit` (the first `limit` with
    `cut`, else a longer file is refused): a FIFO, device or folder is refused
    without waiting for a writer."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as e:
        raise Failure("%s: %s" % (one_line(path), e.strerror))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise Failure("%s: not a regular file (a %s cannot be a sss-farm %s)"
                          % (one_line(path), file_kind(st.st_mode), what))
        if st.st_size > limit and not cut:
            raise Failure("%s: %d bytes, more than a sss-farm %s may have (%d)"
                          % (one_line(path), st.st_size, what, limit))
        data = b""
        while len(data) <= limit:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            data += chunk
        if len(data) > limit:
            if cut:
                return data[:limit]
            raise Failure("%s: more than %d bytes" % (one_line(path), limit))
        return data
    except OSError as e:
        raise Failure("%s: %s" % (one_line(path), e.strerror))
    finally:
        os.close(fd)


def file_kind(mode):
    for test, kind in ((stat.S_ISDIR, "folder"), (stat.S_ISFIFO, "FIFO"), (stat.S_ISSOCK, "socket"),
                       (stat.S_ISCHR, "character device"), (stat.S_ISBLK, "block device")):
        if test(mode):
            return kind
    return "special file"


def no_constant(name):
    """json.loads' parse_constant: NaN and Infinity are not numbers in a spec
    or a status file."""
    raise ValueError("%s is not a number" % name)


def load_spec(path, older=False):
    """The spec at `path`, checked whole (validate_spec): every later step can
    trust its types and its names. `older`: a spec of an older sss-farm is
    returned too (submit replaces it), else refused."""
    shown = one_line(path)
    data = read_regular(path, MAX_SPEC_BYTES, "spec")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise Failure("%s: not a sss-farm spec (not UTF-8: byte %d)" % (shown, e.start))
    try:
        spec = json.loads(text, parse_constant=no_constant)
    except RecursionError:
        raise Failure("%s: not a sss-farm spec (nested too deeply)" % shown)
    except ValueError as e:
        raise Failure("%s: not a sss-farm spec (%s)" % (shown, one_line(e)[:200]))
    if not isinstance(spec, dict) or spec.get("format") not in (SPEC_FORMAT, "sss-farm 1"):
        raise Failure("%s: not a sss-farm spec" % shown)
    if spec["format"] != SPEC_FORMAT and not older:
        raise Failure("%s: a spec of an older sss-farm (array task id = frame): submit again to replace it"
                      % shown)
    validate_spec(spec, path)
    return spec


NAME_RE = r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}"
STAGE_RE = r"(bake|filter|brick|render)([2-9]|[1-9][0-9])?"
MAX_ARG_BYTES = 1 << 16
MAX_ARGS = 10000


def validate_spec(spec, path):
    """Refuses a spec sss-farm did not write: wrong types, names that would
    reach outside the work folder, NULs, numbers out of range."""
    shown = one_line(path)

    def bad(what):
        return Failure("%s: not a valid sss-farm spec: %s" % (shown, what))

    def text(value, what, limit=4096):
        if not isinstance(value, str):
            raise bad("%s is not a string" % what)
        if "\0" in value:
            raise bad("%s holds a NUL byte" % what)
        if len(value.encode("utf-8", "surrogatepass")) > limit:
            raise bad("%s is longer than %d bytes" % (what, limit))
        return value

    def integer(value, what, lo, hi):
        if not isinstance(value, int) or isinstance(value, bool) or not lo <= value <= hi:
            raise bad("%s is not an integer from %d to %d" % (what, lo, hi))
        return value

    if not re.fullmatch(NAME_RE, text(spec.get("name"), "'name'")):
        raise bad("'name' %s: use letters, digits, '_', '.' and '-'" % quoted(spec["name"]))
    if not os.path.isabs(text(spec.get("workdir"), "'workdir'")):
        raise bad("'workdir' %s is not an absolute path" % quoted(spec["workdir"]))
    text(spec.get("bin_dir"), "'bin_dir'")
    spec["path"] = path
    parse_frames(text(spec.get("frames"), "'frames'", 1 << 20), error=lambda m: bad("'frames': " + m))
    if spec["format"] == SPEC_FORMAT:
        integer(spec.get("retries"), "'retries'", 0, MAX_RETRIES)
    split = spec.get("split")
    if split is not None:
        if not isinstance(split, dict):
            raise bad("'split' is not an object")
        integer(split.get("points"), "'split' 'points'", 0, 1 << 62)
        integer(split.get("parts"), "'split' 'parts'", 2, MAX_PARTS)
    stages = spec.get("stages")
    if not isinstance(stages, list) or not 1 <= len(stages) <= 100:
        raise bad("'stages' is not a list of 1 to 100 stages")
    seen = set()
    for i, s in enumerate(stages):
        where = "stage %d" % (i + 1)
        if not isinstance(s, dict):
            raise bad("%s is not an object" % where)
        m = re.fullmatch(STAGE_RE, text(s.get("stage"), where + " 'stage'"))
        if not m or s["stage"] in seen:
            raise bad("%s: %s is not a stage name, or a repeated one" % (where, quoted(s["stage"])))
        seen.add(s["stage"])
        if s.get("tool") != STAGE_TOOLS[m.group(1)]:
            raise bad("%s: the tool of stage %s is %s" % (where, s["stage"], STAGE_TOOLS[m.group(1)]))
        args = s.get("args")
        if not isinstance(args, list) or not 1 <= len(args) <= MAX_ARGS:
            raise bad("%s 'args' is not a list of 1 to %d strings" % (where, MAX_ARGS))
        for j, arg in enumerate(args):
            text(arg, "%s argument %d" % (where, j + 1), MAX_ARG_BYTES)
        integer(s.get("cpus", 1), where + " 'cpus'", 1, 1 << 20)
        integer(s.get("mem", 1), where + " 'mem'", 1, 1 << 40)
    subs = spec.get("submissions", [])
    if not isinstance(subs, list):
        raise bad("'submissions' is not a list")
    for i, sub in enumerate(subs):
        if not isinstance(sub, dict) or not isinstance(sub.get("jobs"), dict):
            raise bad("submission %d has no 'jobs' object" % (i + 1))
        for st, job in sub["jobs"].items():
            text(st, "a job's stage", 200)
            text(job, "the job id of %s" % quoted(st), 200)
        text(sub.get("time", ""), "submission %d 'time'" % (i + 1), 200)
        for key in ("frames", "skipped"):
            what = "submission %d '%s'" % (i + 1, key)
            parse_frame_list(text(sub.get(key, ""), what, 1 << 20), error=lambda m: bad(what + ": " + m))


def check_in_workdir(spec, path, what):
    """Refuses `path` unless it is inside the spec's work folder once every
    symbolic link is resolved (a spec or status folder linked elsewhere)."""
    root = os.path.realpath(spec["workdir"])
    real = os.path.realpath(path)
    if os.path.commonpath([root, real]) != root:
        raise Failure("%s: the %s %s is outside the work folder %s (resolved: %s)"
                      % (spec["name"], what, quoted(path), quoted(spec["workdir"]), quoted(real)))


def check_spec_place(spec, path):
    """The spec must be the work folder's own DIR/.sss-farm/NAME.json."""
    expected = os.path.realpath(spec_path(spec["workdir"], spec["name"]))
    if os.path.realpath(path) != expected:
        raise Failure("%s: a spec of %s must be %s (its work folder's spec), not %s"
                      % (spec["name"], quoted(spec["workdir"]), quoted(expected), quoted(os.path.realpath(path))))
    check_in_workdir(spec, path, "spec")


def save_spec(spec, path):
    write_atomic(path, json.dumps(spec, indent=2) + "\n")


def stage_list(spec):
    return [s["stage"] for s in spec["stages"]]


def stage_of(spec, stage):
    for s in spec["stages"]:
        if s["stage"] == stage:
            return s
    raise Failure("%s: no stage '%s' in %s (stages: %s)" % (spec["name"], stage, spec["path"],
                                                          ", ".join(stage_list(spec))))


def part_stages(spec):
    split = spec.get("split")
    if not split or "filter" not in stage_list(spec):
        return []
    return ["filter-part%d" % k for k in range(1, split["parts"] + 1)]


def latest_jobs(spec):
    subs = spec.get("submissions") or []
    return subs[-1]["jobs"] if subs else {}

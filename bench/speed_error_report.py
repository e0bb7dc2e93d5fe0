#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Draws the plots and writes docs/speed-vs-error.md from the tables that
bench/speed_error_bench.cpp writes. Run by scripts/speed-vs-error.

usage: speed_error_report.py DATA_DIR PLOT_DIR REPORT.md
"""

import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter  # noqa: E402

DEFAULT_EPS = 1.0
DEFAULT_CRITERION = "error"
DEFAULT_MAXERROR = 0.002
CRITERIA = ["error", "bbox", "centroid"]
CRITERION_LABEL = {
    "error": "error (ours, default)",
    "bbox": "bbox (PRMan)",
    "centroid": "centroid (Jensen & Buhler)",
}
COLORS = {"error": "#1f77b4", "bbox": "#d62728", "centroid": "#2ca02c",
          "classic": "#1f77b4", "better": "#ff7f0e", "burley": "#9467bd"}


# ---------------------------------------------------------------------------
# Data
# ---------------------------------------------------------------------------

def read_tsv(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v)
            except (TypeError, ValueError):
                pass
    return rows


def read_kv(path):
    """key -> value (text) of a two-column key/value table."""
    if not os.path.exists(path):
        return {}
    with open(path, newline="") as f:
        return {r["key"]: r["value"] for r in csv.DictReader(f, delimiter="\t")}


def curve(rows, case, criterion, profile="classic"):
    """Rows of one curve, sorted by maxsolidangle (time falls, error grows)."""
    out = [r for r in rows if r["case"] == case and r["criterion"] == criterion
           and r["profile"] == profile]
    return sorted(out, key=lambda r: r["maxsolidangle"])


def at_eps(rows, eps):
    for r in rows:
        if abs(r["maxsolidangle"] - eps) < 1e-9:
            return r
    return None


def loglog_interp(x, xs, ys):
    """y at x on the polyline (xs, ys) in log-log; None outside its range."""
    pts = sorted(zip(xs, ys))
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= x <= x1:
            if x1 == x0:
                return y0
            t = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
            return math.exp(math.log(y0) + t * (math.log(y1) - math.log(y0)))
    return None


def error_at_time(c, t, key="rms_pct"):
    return loglog_interp(t, [r["seconds"] for r in c], [r[key] for r in c])


def time_at_error(c, e, key="rms_pct"):
    # Error is monotone in maxsolidangle on every measured curve; interpolate
    # time over error.
    return loglog_interp(e, [r[key] for r in c], [r["seconds"] for r in c])


# ---------------------------------------------------------------------------
# Formatting
# ---------------------------------------------------------------------------

def missing(x):
    return x is None or (isinstance(x, float) and math.isnan(x))


def fs(x):
    """Seconds."""
    if missing(x):
        return "-"
    return f"{x:.2f}" if x < 10 else f"{x:.1f}"


def fp(x):
    """Percent."""
    if missing(x):
        return "-"
    if x < 0.1:
        return f"{x:.3f}"
    if x < 10:
        return f"{x:.2f}"
    return f"{x:.1f}"


def fx(x):
    """A ratio like 3.2x."""
    if missing(x):
        return "-"
    return f"{x:.1f}x" if x < 10 else f"{x:.0f}x"


def fmb(x):
    return "-" if missing(x) else f"{x:.0f}"


def fn(n):
    n = int(n)
    if n >= 1000000:
        return f"{n / 1e6:.2f} M"
    if n >= 1000:
        return f"{n / 1e3:.0f} k"
    return str(n)


def feps(e):
    return f"{e:g}"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |",
           "|" + "|".join("---" for _ in header) + "|"]
    for r in rows:
        out.append("| " + " | ".join(str(x) for x in r) + " |")
    return "\n".join(out)


# ---------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------

def _major(v, _pos):
    return f"{v:g}"


def _minor(v, _pos):
    if v <= 0:
        return ""
    mantissa = v / 10 ** math.floor(math.log10(v))
    return f"{v:g}" if min(abs(mantissa - 2), abs(mantissa - 5)) < 1e-6 else ""


def plain_log_ticks(ax, x=True, y=True):
    """Log axes labelled 0.5, 1, 2, 5, 10 ... instead of powers of ten."""
    for axis, on, lims in ((ax.xaxis, x, ax.get_xlim()), (ax.yaxis, y, ax.get_ylim())):
        if on:
            axis.set_major_formatter(FuncFormatter(_major))
            # Narrow ranges (less than a factor 4) label every minor tick.
            narrow = lims[0] > 0 and lims[1] / lims[0] < 4
            axis.set_minor_formatter(FuncFormatter(_major if narrow else _minor))


def plot_sweep_axes(ax, sweep, case, title, annotate=True, before=None):
    b = curve(before or [], case, DEFAULT_CRITERION)
    if b:
        ax.plot([r["seconds"] for r in b], [r["rms_pct"] for r in b], "x:", color="0.45",
                ms=4, lw=1, label="error criterion before issue 17, RMS")
        bd = at_eps(b, DEFAULT_EPS)
        if bd:
            ax.plot([bd["seconds"]], [bd["rms_pct"]], "*", mfc="none", mec="0.3", ms=12,
                    zorder=5, label="default before issue 17")
    for crit in CRITERIA:
        c = curve(sweep, case, crit)
        if not c:
            continue
        t = [r["seconds"] for r in c]
        ax.plot(t, [r["rms_pct"] for r in c], "o-", color=COLORS[crit], ms=4,
                label=CRITERION_LABEL[crit] + ", RMS")
        ax.plot(t, [r["p99_pct"] for r in c], "--", color=COLORS[crit], lw=0.8,
                alpha=0.6, label="  99th percentile")
        if annotate:
            for r in c:
                ax.annotate(feps(r["maxsolidangle"]), (r["seconds"], r["rms_pct"]),
                            textcoords="offset points", xytext=(4, -9), fontsize=6,
                            color=COLORS[crit])
    d = at_eps(curve(sweep, case, DEFAULT_CRITERION), DEFAULT_EPS)
    if d:
        ax.plot([d["seconds"]], [d["rms_pct"]], "*", color="k", ms=14, zorder=5,
                label="default (error, 1)")
    p = at_eps(curve(sweep, case, "bbox"), DEFAULT_EPS)
    if p:
        ax.plot([p["seconds"]], [p["rms_pct"]], "s", mfc="none", mec="k", ms=9,
                zorder=5, label="PRMan default (bbox, 1)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_ticks(ax)
    ax.set_xlabel("time of the ptfilter library call (s, 2 threads)")
    ax.set_ylabel("|h - e| / mean|e|  (%)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)


def plot_sweep(sweep, cases, plot_dir, before=None):
    files = {}
    for case in cases:
        name = case["case"]
        fig, ax = plt.subplots(figsize=(7, 5))
        plot_sweep_axes(ax, sweep, name,
                        f"{name}: {fn(case['points'])} points (labels: -maxsolidangle)",
                        before=before)
        ax.legend(fontsize=7, loc="upper right")
        fig.tight_layout()
        f = f"sweep-{name}.png"
        fig.savefig(os.path.join(plot_dir, f), dpi=110)
        plt.close(fig)
        files[name] = f
    # Overview: all cases, small.
    n = len(cases)
    cols = 3
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    for i, case in enumerate(cases):
        ax = axes[i // cols][i % cols]
        plot_sweep_axes(ax, sweep, case["case"], case["case"], annotate=False, before=before)
        ax.set_xlabel("time (s)", fontsize=8)
        ax.set_ylabel("RMS / p99 error (%)", fontsize=8)
        ax.tick_params(labelsize=7)
    for j in range(n, rows * cols):
        ax = axes[j // cols][j % cols]
        ax.axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    if n < rows * cols:
        axes[-1][-1].legend(handles, labels, loc="center", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "sweep-all.png"), dpi=100)
    plt.close(fig)
    files["all"] = "sweep-all.png"
    return files


def plot_profiles(profiles, sweep, plot_dir):
    cases = sorted({r["case"] for r in profiles}, key=lambda c: c)
    if not cases:
        return None
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        for prof in ["classic", "better", "burley"]:
            src = sweep if prof == "classic" else profiles
            c = curve(src, case, "error", prof)
            if not c:
                continue
            ax.plot([r["seconds"] for r in c], [r["rms_pct"] for r in c], "o-",
                    color=COLORS[prof], ms=4, label=f"{prof}, RMS")
            ax.plot([r["seconds"] for r in c], [r["p99_pct"] for r in c], "--",
                    color=COLORS[prof], lw=0.8, alpha=0.6, label="  99th percentile")
            d = at_eps(c, DEFAULT_EPS)
            if d:
                ax.plot([d["seconds"]], [d["rms_pct"]], "*", color=COLORS[prof], ms=12)
        ax.set_xscale("log")
        ax.set_yscale("log")
        plain_log_ticks(ax)
        ax.set_title(f"{case}: error criterion, each profile (star: 1)", fontsize=10)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("|h - e| / mean|e|  (%)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "profiles.png"), dpi=100)
    plt.close(fig)
    return "profiles.png"


def scaling_rows(scaling, crit, eps):
    return sorted([r for r in scaling if r["criterion"] == crit
                   and abs(r["maxsolidangle"] - eps) < 1e-9], key=lambda r: r["points"])


def plot_scaling(scaling, plot_dir):
    if not scaling:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    ax = axes[0]
    for crit, label in [("error", "default (error, 1)"), ("bbox", "PRMan (bbox, 1)")]:
        rows = scaling_rows(scaling, crit, 1.0)
        n = [r["points"] for r in rows]
        ax.plot(n, [r["seconds"] for r in rows], "o-", color=COLORS[crit],
                label=label + ", library call")
        ax.plot(n, [r["tool_seconds"] for r in rows], "s:", color=COLORS[crit],
                ms=4, label=label + ", ptfilter end to end")
    rows = scaling_rows(scaling, "error", 1.0)
    if rows:
        n0, t0 = rows[0]["points"], rows[0]["seconds"]
        ns = [rows[0]["points"], rows[-1]["points"]]
        ax.plot(ns, [t0 * x / n0 for x in ns], color="0.6", lw=0.8,
                label="proportional to N")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_ticks(ax, x=False)
    ax.set_xlabel("points N")
    ax.set_ylabel("seconds (2 threads)")
    ax.set_title("marble sphere r = 50 mm: time against N", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[1]
    styles = [("error", 0.5, "o--", "error, 0.5"), ("error", 1.0, "o-", "default (error, 1)"),
              ("error", 2.0, "o-.", "error, 2"), ("bbox", 1.0, "s-", "PRMan (bbox, 1)")]
    for crit, eps, style, label in styles:
        rows = scaling_rows(scaling, crit, eps)
        if not rows:
            continue
        n = [r["points"] for r in rows]
        ax.plot(n, [r["rms_pct"] for r in rows], style, color=COLORS[crit], label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_ticks(ax, x=False)
    ax.set_xlabel("points N")
    ax.set_ylabel("RMS |h - e| / mean|e|  (%)")
    ax.set_title("... and error against N", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "scaling.png"), dpi=100)
    plt.close(fig)
    return "scaling.png"


def plot_brick(brick, plot_dir):
    if not brick:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for i, case in enumerate(sorted({r["case"] for r in brick})):
        rows = sorted([r for r in brick if r["case"] == case], key=lambda r: r["maxerror"])
        color = ["#1f77b4", "#d62728", "#2ca02c"][i % 3]
        ax = axes[0]
        ax.plot([r["rms_pct"] for r in rows], [r["file_mb"] for r in rows], "o-",
                color=color, label=f"{case}, RMS")
        ax.plot([r["p99_pct"] for r in rows], [r["file_mb"] for r in rows], "^--",
                color=color, ms=4, lw=0.8, alpha=0.6, label=f"{case}, 99th percentile")
        for r in rows:
            ax.annotate(feps(r["maxerror"]), (r["rms_pct"], r["file_mb"]),
                        textcoords="offset points", xytext=(4, 3), fontsize=7,
                        color=color)
            if abs(r["maxerror"] - DEFAULT_MAXERROR) < 1e-12:
                ax.plot([r["rms_pct"]], [r["file_mb"]], "*", color="k", ms=12, zorder=5)
        ax = axes[1]
        ax.plot([r["maxerror"] for r in rows], [r["build_seconds"] for r in rows], "o-",
                color=color, label=case)
    ax = axes[0]
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_ticks(ax)
    ax.set_xlabel("lookup error at the points, % of mean (worst channel)")
    ax.set_ylabel("brick map file (MB)")
    ax.set_title("brickmake: size against error (labels: -maxerror, star: default)",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax = axes[1]
    ax.set_xscale("log")
    ax.set_xlabel("-maxerror")
    ax.set_ylabel("build time (s, 2 threads)")
    ax.set_ylim(bottom=0)
    ax.set_title("brickmake: build time", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "brick.png"), dpi=100)
    plt.close(fig)
    return "brick.png"


def plot_model(model, plot_dir):
    if not model:
        return None
    mats = ["marble", "skin1"]
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.6), squeeze=False)
    chc = {"r": "#d62728", "g": "#2ca02c", "b": "#1f77b4"}
    for col, mat in enumerate(mats):
        for row, jittered in enumerate([False, True]):
            ax = axes[row][col]
            for ch in "rgb":
                sel = sorted([r for r in model if r["material"] == mat
                              and r["channel"] == ch and r["profile"] == "classic"
                              and (r["jitter"] > 0) == jittered],
                             key=lambda r: r["spacing_over_mfp"])
                x = [r["spacing_over_mfp"] for r in sel]
                ax.plot(x, [r["ratio_median"] for r in sel], "o-", color=chc[ch], ms=4,
                        label=f"{ch}" + (": median" if jittered else ""))
                if jittered:
                    ax.fill_between(x, [r["ratio_min"] for r in sel],
                                    [r["ratio_max"] for r in sel], color=chc[ch],
                                    alpha=0.12, label=f"{ch}: min-max")
            ax.axhline(1.0, color="k", lw=0.6)
            for y in (0.99, 1.01) if not jittered else (0.95, 1.05):
                ax.axhline(y, color="0.5", lw=0.6, ls=":")
            ax.set_xscale("log", base=2)
            ax.set_xlabel("point spacing h / mean free path 1/sigma_t' (smallest channel)")
            ax.set_ylabel("result / (albedo x E)")
            what = ("jittered by half a spacing: 25 receivers" if jittered
                    else "regular grid")
            ax.set_title(f"{mat}, classic profile, {what}", fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7, ncol=2 if jittered else 1)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "model.png"), dpi=100)
    plt.close(fig)
    return "model.png"


# ---------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------

def compare_default(sweep, case):
    """The default against each classic criterion at equal time / error."""
    d = at_eps(curve(sweep, case, DEFAULT_CRITERION), DEFAULT_EPS)
    out = {"default": d}
    for crit in ["bbox", "centroid"]:
        c = curve(sweep, case, crit)
        if not c or not d:
            continue
        e_eq_t = error_at_time(c, d["seconds"])
        p99_eq_t = error_at_time(c, d["seconds"], "p99_pct")
        t_eq_e = time_at_error(c, d["rms_pct"])
        fastest = max(c, key=lambda r: r["maxsolidangle"])
        finest = min(c, key=lambda r: r["maxsolidangle"])
        out[crit] = {
            "at1": at_eps(c, DEFAULT_EPS),
            "err_at_time": e_eq_t,
            "p99_at_time": p99_eq_t,
            "time_at_err": t_eq_e,
            "fastest": fastest,
            "finest": finest,
        }
    return out


def not_reached(c, ob):
    """The old default's error lies beyond the current curve's ends."""
    fastest = max(c, key=lambda r: r["maxsolidangle"])
    if ob["rms_pct"] > fastest["rms_pct"]:
        return (f"every setting is more accurate (fastest measured, "
                f"{feps(fastest['maxsolidangle'])}: {fs(fastest['seconds'])} s, "
                f"{fp(fastest['rms_pct'])} %)")
    return "-"


def before_text(before, before_machine, sweep, cases):
    """The error criterion now against the same criterion before issue 17."""
    md = ["## Against the evaluation before issue 17", "",
          "The grey dotted curves in the plots are the `error` criterion as it was before "
          "issue 17 (measured by this script at commit "
          f"{before_machine.get('commit', '?')}, {before_machine.get('date', '?')}, "
          f"{before_machine.get('cpu', '?')}, {before_machine.get('nproc', '?')} cores; "
          "the data is kept in `docs/speed-vs-error/before-issue-17/`). Since then: "
          "negligible nodes are monopoles instead of being dropped (that was a bias "
          "towards 0), well separated nodes go into local expansions shared by a whole "
          "receiver group (the fast multipole method's M2L/L2L), the kernels are chosen "
          "at run time per instruction set, the knob's scale was doubled (tau "
          "4e-3 -> 8e-3 per unit of `-maxsolidangle`), the octree's leaves hold up to 16 "
          "points (8 before) and are built in O(N), an expansion may serve receivers "
          "1.2 node radii away (1.5 before), nodes whose sources are all unlit are "
          "dropped whole (they add exactly 0), the kernels read the tables a row of "
          "interleaved channels at a time, and receiver buckets hold up to 128 points "
          "(64 before). Times from different runs of this script are only comparable "
          "on the same machine: see `meta.tsv` and `machine.tsv` for when and where "
          "each ran. *Now at equal error*: the time "
          "the current curve needs for the old default's RMS error; *now at equal time*: "
          "the current RMS error at the old default's time (interpolated; '-' when "
          "outside the measured range).", ""]
    rows = []
    for case in cases:
        name = case["case"]
        ob = at_eps(curve(before, name, DEFAULT_CRITERION), DEFAULT_EPS)
        c = curve(sweep, name, DEFAULT_CRITERION)
        nd = at_eps(c, DEFAULT_EPS)
        if not ob or not nd:
            continue
        t_eq = time_at_error(c, ob["rms_pct"])
        e_eq = error_at_time(c, ob["seconds"])
        rows.append([
            name,
            f"{fs(ob['seconds'])} s, {fp(ob['rms_pct'])} % (p99 {fp(ob['p99_pct'])} %)",
            f"{fs(nd['seconds'])} s, {fp(nd['rms_pct'])} % (p99 {fp(nd['p99_pct'])} %)",
            f"speed {ob['seconds'] / nd['seconds']:.2f}x, error "
            f"{fx(ob['rms_pct'] / nd['rms_pct'])} lower",
            (f"{fs(t_eq)} s ({fx(ob['seconds'] / t_eq)} faster)" if t_eq else
             not_reached(c, ob)),
            (f"{fp(e_eq)} % ({fx(ob['rms_pct'] / e_eq)} less)" if e_eq else "-"),
        ])
    md.append(table(["cloud", "default before", "default now", "default: now against before",
                     "now at equal error", "now at equal time"], rows))
    return "\n".join(md)


def equal_time_cell(x, d):
    if x is None:
        return "-"
    if x["err_at_time"] is None:
        if d["seconds"] < x["fastest"]["seconds"]:
            f = x["fastest"]
            return (f"never as fast (at {feps(f['maxsolidangle'])}: "
                    f"{fs(f['seconds'])} s, {fp(f['rms_pct'])} %)")
        return "-"
    return f"{fp(x['err_at_time'])} % ({fx(x['err_at_time'] / d['rms_pct'])})"


def equal_error_cell(x, d):
    if x is None:
        return "-"
    if x["time_at_err"] is None:
        f = x["finest"]
        if d["rms_pct"] < f["rms_pct"]:
            return (f"> {fs(f['seconds'])} s (not reached: {fp(f['rms_pct'])} % at "
                    f"{feps(f['maxsolidangle'])}; > {fx(f['seconds'] / d['seconds'])})")
        return "-"
    return f"{fs(x['time_at_err'])} s ({fx(x['time_at_err'] / d['seconds'])})"


def model_against_light(data_dir):
    """(material, profile) -> "r g b" L1w from docs/accuracy/data (scripts/accuracy-report),
    or nothing when that report has not been made."""
    acc = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(data_dir))),
                       "accuracy", "data")
    out = {}
    if not os.path.isdir(acc):
        return out
    for name in os.listdir(acc):
        if not name.endswith(".tsv") or name == "cost.tsv":
            continue
        by = {}
        for r in read_tsv(os.path.join(acc, name)):
            by.setdefault(r["profile"], []).append(f"{100 * float(r['l1w']):.0f}")
        for prof, vals in by.items():
            out[(name[:-4], prof)] = " ".join(vals) + " %"
    return out


def main():
    data_dir, plot_dir, report = sys.argv[1], sys.argv[2], sys.argv[3]
    os.makedirs(plot_dir, exist_ok=True)
    cases = read_tsv(os.path.join(data_dir, "cases.tsv"))
    sweep = read_tsv(os.path.join(data_dir, "sweep.tsv"))
    refs = read_tsv(os.path.join(data_dir, "sweep_refs.tsv"))
    profiles = read_tsv(os.path.join(data_dir, "profiles.tsv"))
    prefs = read_tsv(os.path.join(data_dir, "profiles_refs.tsv"))
    scaling = read_tsv(os.path.join(data_dir, "scaling.tsv"))
    model = read_tsv(os.path.join(data_dir, "model.tsv"))
    brick = read_tsv(os.path.join(data_dir, "brick.tsv"))
    meta = read_kv(os.path.join(data_dir, "meta.tsv"))
    machine = read_kv(os.path.join(data_dir, "machine.tsv"))
    # The error criterion as it was before issue 17 (kept, never regenerated).
    before_dir = os.path.join(os.path.dirname(os.path.abspath(data_dir)), "before-issue-17")
    before = read_tsv(os.path.join(before_dir, "sweep.tsv"))
    before_machine = read_kv(os.path.join(before_dir, "machine.tsv"))

    rel = os.path.relpath(plot_dir, os.path.dirname(os.path.abspath(report)))
    data_rel = os.path.relpath(data_dir, os.path.dirname(os.path.abspath(report)))
    sweep_png = plot_sweep(sweep, cases, plot_dir, before)
    prof_png = plot_profiles(profiles, sweep, plot_dir)
    scal_png = plot_scaling(scaling, plot_dir)
    brick_png = plot_brick(brick, plot_dir)
    model_png = plot_model(model, plot_dir)

    md = []
    w = md.append
    threads = machine.get("threads", meta.get("threads", "?"))
    w("# Speed against error")
    w("")
    w("How much time each setting of `ptfilter -ssdiffusion` and `brickmake` costs and how "
      "much error it buys, measured, for choosing `-maxsolidangle`, `-maxerror` and the bake's "
      "point spacing. It also compares our evaluation with the classic algorithm (PRMan's "
      "`bbox` criterion and Jensen & Buhler's `centroid`), which `ptfilter -criterion` runs "
      "so that anyone can reproduce the comparison.")
    w("")
    w("This file, its plots and its data are generated: do not edit them by hand. "
      "Regenerate everything with")
    w("")
    w("```sh")
    w("scripts/speed-vs-error")
    w("```")
    w("")
    bench_min = float(machine.get("bench_seconds", meta.get("seconds_total", "nan"))) / 60
    total_min = float(machine.get("total_seconds", "nan")) / 60
    w(f"(last run: {total_min:.1f} min in all, of which the benchmark {bench_min:.1f} min; "
      f"{machine.get('cpu', '?')}, {machine.get('nproc', '?')} cores, {threads} threads; "
      f"{machine.get('date', '?')}; see [Reproducing](#reproducing)).")
    w("")

    # ------------------------------------------------------------------ defaults
    w("## Where the defaults sit")
    w("")
    w("The default (`-criterion error -maxsolidangle 1`, classic profile) against the "
      "classic criteria on every cloud. *Equal time*: the classic criterion's error when "
      "given the default's time (interpolated on its curve); *equal error*: the time it "
      "needs to reach the default's RMS error. Errors are RMS of |h - e| / mean|e| against "
      "the exact evaluation, worst colour channel (definitions under [Method](#method)).")
    w("")
    rows = []
    comps = {}
    for case in cases:
        name = case["case"]
        c = compare_default(sweep, name)
        comps[name] = c
        d = c["default"]
        if not d:
            continue
        b, j = c.get("bbox"), c.get("centroid")
        rows.append([
            name, fn(case["points"]),
            f"{fs(d['seconds'])} s, {fp(d['rms_pct'])} % (p99 {fp(d['p99_pct'])} %)",
            f"{fs(b['at1']['seconds'])} s, {fp(b['at1']['rms_pct'])} %" if b else "-",
            equal_time_cell(b, d), equal_error_cell(b, d),
            equal_time_cell(j, d), equal_error_cell(j, d),
        ])
    w(table(["cloud", "points", "default: time, RMS error",
             "PRMan default (bbox 1)", "bbox at equal time: RMS (x default)",
             "bbox at equal error: time (x default)",
             "centroid at equal time", "centroid at equal error"], rows))
    w("")
    if "all" in sweep_png:
        w(f"![error against time, every cloud]({rel}/{sweep_png['all']})")
        w("")
    w("Star: the default; open square: PRMan's default (`bbox`, 1). Solid lines: RMS; "
      "dashed: 99th percentile. Per-cloud plots with the `-maxsolidangle` values are in "
      "[Evaluation error against time](#evaluation-error-against-time).")
    w("")
    if before:
        w(before_text(before, before_machine, sweep, cases))
        w("")

    # ------------------------------------------------------------------ why
    w("## Why these defaults")
    w("")
    w(why_text(sweep, cases, comps, model, brick, scaling, profiles))
    w("")

    # ------------------------------------------------------------------ method
    w("## Method")
    w("")
    npts = int(float(meta.get("points", "0")))
    w(f"- **Clouds** (about {fn(npts)} points each for the sweeps; baked clouds get the "
      "`-spacing` that gives that count):")
    w("")
    crow = []
    for case in cases:
        crow.append([case["case"], case["description"], fn(case["points"]),
                     f"{case['material']}, `-unitlength {case['unitlength']:g}`",
                     f"{case['spacing']:.3g} {case['units']}",
                     f"{case['mfp_min']:.3g}",
                     f"{case['dmfp_r']:.3g} / {case['dmfp_g']:.3g} / {case['dmfp_b']:.3g}",
                     f"{case['bbox_diagonal']:.3g}"])
    w(table(["case", "cloud", "points", "material", "spacing sqrt(area/N)",
             "mean free path 1/sigma_t' (smallest)", "dmfp r / g / b", "bounding box diagonal"],
            crow))
    w("")
    samples = meta.get("samples", "?")
    w(f"- **Error.** Each case's exact reference is `sss::evaluate_diffusion_exact` (all "
      f"pairs, double precision, the same point model) at {samples} points drawn at random "
      "from the cloud (blocker points included), computed once per case and profile. For "
      "each colour channel, d = |h - e| / mean|e| over those points (h: the hierarchical "
      "result); the tables give the RMS, the 99th percentile and the maximum of d, each for "
      "the worst channel.")
    w(f"- **Time** is the wall time of the `sss::ssdiffusion` library call (what ptfilter "
      f"runs between reading and writing: material, octree, evaluation, output cloud), on "
      f"{threads} threads; the fastest of three when a call takes under 0.5 s. The scaling "
      "section also times the `ptfilter` executable end to end (reading and writing `.ptc`).")
    w("- **Memory.** `peak MB` is what the call added to the process's resident memory at "
      "its peak (Linux: the peak RSS is reset to the current RSS through "
      "`/proc/self/clear_refs` before the call, after `malloc_trim`; the input cloud is "
      "already in memory and not counted). The scaling section gives the `ptfilter` "
      "process's whole peak RSS (`wait4`), input and output clouds included.")
    w("- **Sweep:** `-maxsolidangle` " + ", ".join(
        feps(e) for e in sorted({r["maxsolidangle"] for r in sweep})) +
      " for each criterion, classic profile; the better and burley profiles with the error "
      "criterion on " + ", ".join(sorted({r["case"] for r in profiles})) +
      f" ({meta.get('profile_samples', '?')} reference points).")
    w("")
    ref_rows = []
    for r in refs + prefs:
        ref_rows.append([r["case"], r["profile"], int(r["samples"]), fn(r["points"]),
                         fs(r["exact_seconds"])])
    w("Cost of the exact references (all pairs, at the sample points only):")
    w("")
    w(table(["case", "profile", "points evaluated", "cloud", "seconds"], ref_rows))
    w("")

    # ------------------------------------------------------------------ sweeps
    w("## Evaluation error against time")
    w("")
    w("One plot and table per cloud. Labels on the points are `-maxsolidangle`. "
      "`far`/`near`: node expansions and point-point terms per receiver.")
    w("")
    for case in cases:
        name = case["case"]
        w(f"### {name}")
        w("")
        w(f"{case['description']}; {fn(case['points'])} points, {case['material']} "
          f"(`-unitlength {case['unitlength']:g}`, scene units {case['units']}).")
        w("")
        if name in sweep_png:
            w(f"![{name}]({rel}/{sweep_png[name]})")
            w("")
        trows = []
        has_bias = all(r.get("bias_pct") is not None for r in sweep)
        for crit in CRITERIA:
            for r in curve(sweep, name, crit):
                mark = " **(default)**" if (crit == DEFAULT_CRITERION and
                                            r["maxsolidangle"] == DEFAULT_EPS) else ""
                row = [crit + mark, feps(r["maxsolidangle"]), fs(r["seconds"]),
                       f"{r['points_per_s'] / 1e3:.0f} k", fp(r["rms_pct"]),
                       fp(r["p99_pct"]), fp(r["max_pct"])]
                if has_bias:
                    row.append(f"{r['bias_pct']:+.3f}")
                row += [f"{r['peak_mb']:.0f}", f"{r['far_terms_per_point']:.0f}",
                        f"{r['near_terms_per_point']:.0f}"]
                trows.append(row)
        w(table(["criterion", "maxsolidangle", "seconds", "points/s", "RMS %", "p99 %",
                 "max %"] + (["bias %"] if has_bias else []) + ["peak MB", "far", "near"],
                trows))
        w("")

    # ------------------------------------------------------------------ profiles
    if profiles:
        w("## Profiles")
        w("")
        w("The error criterion follows each profile's own derivatives, so the knob means "
          "the same for all three. Classic rows are from the sweep above (its own "
          "reference).")
        w("")
        if prof_png:
            w(f"![profiles]({rel}/{prof_png})")
            w("")
        light = model_against_light(data_dir)
        prow = []
        for name in sorted({r["case"] for r in profiles}):
            for prof in ["classic", "better", "burley"]:
                src = sweep if prof == "classic" else profiles
                for r in curve(src, name, "error", prof):
                    if r["maxsolidangle"] not in (0.25, 1.0, 4.0):
                        continue
                    prow.append([name, prof, feps(r["maxsolidangle"]), fs(r["seconds"]),
                                 fp(r["rms_pct"]), fp(r["p99_pct"]), fp(r["max_pct"]),
                                 light.get((name.split("-")[-1], prof), "-")])
        w(table(["case", "profile", "maxsolidangle", "seconds", "RMS %", "p99 %", "max %",
                 "model vs the light: L1w"], prow))
        w("")
        w("The last column is the model's own error, which no setting of the evaluation "
          "changes: the L1 error of r R(r) over the first ten transport mean free paths "
          "against a Monte-Carlo random walk of the light, per colour channel (r g b), from "
          "[accuracy.md](accuracy.md), which also has `-profile pbd` and `-profile mc` (3 % "
          "and less) and what they cost.")
        w("")
        w(f"All values: [{data_rel}/profiles.tsv]({data_rel}/profiles.tsv).")
        w("")

    # ------------------------------------------------------------------ scaling
    if scaling:
        w("## Time against N")
        w("")
        w("The marble sphere (r = 50 mm) at each size: the default and PRMan's default as "
          "the library call (time, memory it added) and as the `ptfilter` executable end to "
          "end (reading and writing the `.ptc`; whole-process peak RSS); the error criterion "
          "at 0.5 and 2 as the library call. Errors against the exact evaluation at "
          f"{meta.get('scaling_samples', '?')} random points (so the 99th percentile and "
          "the maximum are close).")
        w("")
        if scal_png:
            w(f"![time against N]({rel}/{scal_png})")
            w("")
        srows = []
        for r in sorted(scaling, key=lambda r: (r["criterion"] != "error",
                                                r["maxsolidangle"] != 1.0,
                                                r["maxsolidangle"], r["points"])):
            mark = " **(default)**" if (r["criterion"] == DEFAULT_CRITERION and
                                        r["maxsolidangle"] == DEFAULT_EPS) else ""
            srows.append([r["criterion"] + mark, feps(r["maxsolidangle"]), fn(r["points"]),
                          fs(r["seconds"]), f"{r['points_per_s'] / 1e3:.0f} k",
                          fp(r["rms_pct"]), fp(r["p99_pct"]), fp(r["max_pct"]),
                          fmb(r["peak_mb"]), f"{r['far_terms_per_point']:.0f}",
                          fs(r["tool_seconds"]), fmb(r["tool_peak_mb"])])
        w(table(["criterion", "maxsolidangle", "points", "library s", "points/s", "RMS %",
                 "p99 %", "max %", "added MB", "far", "ptfilter s", "ptfilter peak MB"],
                srows))
        w("")
        w(scaling_text(scaling))
        w("")

    # ------------------------------------------------------------------ model
    if model:
        w("## Model error: how coarse can a bake be")
        w("")
        w(model_intro(model))
        w("")
        if model_png:
            w(f"![model error]({rel}/{model_png})")
            w("")
        w(model_table(model))
        w("")
        w(model_text(model))
        w("")

    # ------------------------------------------------------------------ brick
    if brick:
        w("## brickmake: `-maxerror` against size and error")
        w("")
        w("The default `_ssdiffusion` clouds of the sweep (`-maxsolidangle 1`) made into "
          "brick maps; lookups at every point of the cloud with filter radius 0 (the finest "
          "level), against the point's own value. Errors are absolute (the unit of "
          "`-maxerror`) and in % of the channel's mean, worst channel.")
        w("")
        if brick_png:
            w(f"![brick map size against error]({rel}/{brick_png})")
            w("")
        brows = []
        for r in sorted(brick, key=lambda r: (r["case"], r["maxerror"])):
            mark = " **(default)**" if abs(r["maxerror"] - DEFAULT_MAXERROR) < 1e-12 else ""
            brows.append([r["case"], feps(r["maxerror"]) + mark, fs(r["build_seconds"]),
                          f"{r['peak_mb']:.0f}", f"{r['file_mb']:.1f}", int(r["bricks"]),
                          f"{r['rms_abs']:.5f}", f"{r['p99_abs']:.4f}", f"{r['max_abs']:.3f}",
                          fp(r["rms_pct"]), fp(r["p99_pct"]), fp(r["max_pct"])])
        w(table(["cloud", "-maxerror", "build s", "added MB", "file MB", "bricks", "RMS",
                 "p99", "max", "RMS %", "p99 %", "max %"], brows))
        w("")
        w(brick_text(brick, sweep))
        w("")

    # ------------------------------------------------------------------ reproducing
    w("## Reproducing")
    w("")
    w("```sh")
    w("scripts/speed-vs-error             # build, install python3-matplotlib if needed, "
      "run, draw, write this file")
    w("scripts/speed-vs-error --report    # redraw plots and this file from the data only")
    w("scripts/speed-vs-error --quick     # tiny clouds, into out/speed-vs-error-quick/ "
      "(checks the script)")
    w("```")
    w("")
    w("The script runs `build/bin/speed_error_bench -out docs/speed-vs-error/data` "
      "([bench/speed_error_bench.cpp](../bench/speed_error_bench.cpp); `-cases`, `-eps`, "
      "`-n`, `-samples`, `-sections` run parts of it) and then "
      "[bench/speed_error_report.py](../bench/speed_error_report.py). Any single point can "
      "be reproduced with the tools, e.g. `ptfilter -ssdiffusion -material marble "
      "-criterion bbox -maxsolidangle 0.125 in.ptc out.ptc`.")
    w("")
    mrows = [[k, f"`{v}`" if k in ("commit", "compiler") else v]
             for k, v in machine.items() if k not in ("bench_seconds", "total_seconds")]
    secs = [(k[len("seconds_"):], float(v)) for k, v in meta.items()
            if k.startswith("seconds_") and k != "seconds_total"]
    mrows.append(["benchmark sections (s)",
                  ", ".join(f"{k} {v:.0f}" for k, v in secs)])
    w(table(["", "this run"], mrows))
    w("")
    w(f"The raw tables are in [{data_rel}/]({data_rel}/) (tab-separated, one header line).")
    w("")

    with open(report, "w") as f:
        f.write("\n".join(md))


# ---------------------------------------------------------------------------
# Text computed from the data
# ---------------------------------------------------------------------------

def rng(vals, fmt="{:.1f}", unit=""):
    """'a-b' (or 'a') from a list of numbers."""
    vals = [v for v in vals if not missing(v)]
    if not vals:
        return "-"
    lo, hi = fmt.format(min(vals)), fmt.format(max(vals))
    return (lo if lo == hi else f"{lo}-{hi}") + unit


def model_summary(model, mat, bias_limit=0.01, noise_limit=0.05):
    """Per spacing: worst-channel |median - 1| on the regular grid and the worst
    jittered receiver's |ratio - 1| (classic profile); and the coarsest
    spacing at which it and every finer one are within the limits."""
    spacings = sorted({r["spacing_over_mfp"] for r in model if r["material"] == mat})
    per = {}
    for f in spacings:
        sel = [r for r in model if r["material"] == mat and r["profile"] == "classic"
               and r["spacing_over_mfp"] == f]
        reg = [r for r in sel if r["jitter"] == 0]
        jit = [r for r in sel if r["jitter"] > 0]
        per[f] = {
            "bias": max(abs(r["ratio_median"] - 1) for r in reg) if reg else None,
            "noise": max(max(abs(r["ratio_min"] - 1), abs(r["ratio_max"] - 1))
                         for r in jit) if jit else None,
            "dmfp_over_h": min(r["dmfp_over_spacing"] for r in reg) if reg else None,
            "h": reg[0]["spacing_mm"] if reg else None,
        }
    coarsest = None
    for f in spacings:
        p = per[f]
        if p["bias"] is None or p["bias"] > bias_limit or (
                p["noise"] is not None and p["noise"] > noise_limit):
            break
        coarsest = f
    return spacings, per, coarsest


def why_text(sweep, cases, comps, model, brick, scaling, profiles):
    out = []
    names = [c["case"] for c in cases]
    defaults = {n: comps[n]["default"] for n in names if comps[n]["default"]}
    eps_values = sorted({r["maxsolidangle"] for r in sweep})

    # --- what the default gives
    d4 = scaling_rows(scaling, "error", 1.0)
    big = d4[-1] if d4 else None
    out.append("**`-maxsolidangle 1` with the error criterion.**")
    out.append("")
    s = (f"- *What it gives.* On the {len(defaults)} clouds ({rng([c['points'] / 1e3 for c in cases], '{:.0f}')} k "
         f"points) the default takes {rng([d['seconds'] for d in defaults.values()], '{:.2f}', ' s')} "
         f"for RMS errors of {rng([d['rms_pct'] for d in defaults.values()], '{:.2f}', ' %')}; "
         f"the worst 99th percentile is {fp(max(d['p99_pct'] for d in defaults.values()))} % and "
         f"the worst point {fp(max(d['max_pct'] for d in defaults.values()))} %.")
    if big:
        s += (f" On the sphere at {fn(big['points'])} points: {fp(big['rms_pct'])} % RMS, "
              f"{fp(big['p99_pct'])} % at the 99th percentile (the error grows slowly with N, "
              "see [Time against N](#time-against-n)).")
    out.append(s)

    # --- the bias (issue 17: within +-0.05 % at every maxsolidangle up to 1)
    err_rows = [r for r in sweep if r["criterion"] == "error" and r["case"] in names]
    if err_rows and all(r.get("bias_pct") is not None for r in err_rows):
        upto1 = [r for r in err_rows if r["maxsolidangle"] <= 1.0]
        above = [r for r in err_rows if r["maxsolidangle"] > 1.0]
        worst = max(upto1, key=lambda r: abs(r["bias_pct"]))
        s = (f"- *Bias.* The mean signed error (h - e) / mean|e| of the error criterion, "
             f"channel farthest from 0, is within +-{abs(worst['bias_pct']):.3f} % on every "
             f"cloud at every value up to 1 (largest: {worst['case']} at "
             f"{feps(worst['maxsolidangle'])}, {worst['bias_pct']:+.3f} %)")
        if above:
            wa = max(above, key=lambda r: abs(r["bias_pct"]))
            s += (f"; above 1 it grows with the tolerance, to {wa['bias_pct']:+.3f} % "
                  f"({wa['case']} at {feps(wa['maxsolidangle'])})")
        out.append(s + ". The per-cloud tables below give it for every run.")

    # --- the knob around 1
    slower, faster, slopes = [], [], []
    for n in names:
        c = curve(sweep, n, "error")
        d, h, t = at_eps(c, 1.0), at_eps(c, 0.5), at_eps(c, 2.0)
        if d and h:
            slower.append((h["seconds"] / d["seconds"] - 1, h["rms_pct"] / d["rms_pct"]))
        if d and t:
            faster.append((1 - t["seconds"] / d["seconds"], t["rms_pct"] / d["rms_pct"],
                           t["p99_pct"], t["rms_pct"]))
        lo, hi = at_eps(c, 0.25), at_eps(c, 4.0)
        if lo and hi:
            slopes.append(-math.log(hi["seconds"] / lo["seconds"]) / math.log(16))
    if slower and faster:
        s = (f"- *Around 1.* Halving it (0.5) costs {rng([x[0] * 100 for x in slower], '{:.0f}', ' %')} "
             f"more time and multiplies the error by {rng([x[1] for x in slower], '{:.2f}')}; "
             f"doubling it (2) saves {rng([x[0] * 100 for x in faster], '{:.0f}', ' %')} of the "
             f"time and multiplies the error by {rng([x[1] for x in faster], '{:.2f}')} (RMS up "
             f"to {fp(max(x[3] for x in faster))} %, 99th percentile up to "
             f"{fp(max(x[2] for x in faster))} %).")
        if slopes:
            s += (" Between 0.25 and 4 the time goes as maxsolidangle to a power between "
                  f"-{max(slopes):.2f} and -{min(slopes):.2f} while the error is nearly "
                  "proportional to it: there is no knee, so the value is an error target.")
        out.append(s)
    # The largest power of two meeting the target everywhere.
    target_rms = 1.0
    ok = []
    for e in eps_values:
        rows = [at_eps(curve(sweep, n, "error"), e) for n in names]
        if any(r is None for r in rows):
            continue
        worst = max(r["rms_pct"] for r in rows)
        sc = scaling_rows(scaling, "error", e)
        if sc:
            worst = max(worst, max(r["rms_pct"] for r in sc))
        if worst <= target_rms:
            ok.append(e)
    largest = max(ok) if ok else None
    if largest is not None:
        verdict = ("which is the default" if largest == DEFAULT_EPS else
                   f"so the data would allow {feps(largest)} instead of the default 1")
        s = (f"- *The target.* The largest value tried that keeps the RMS error under "
             f"{target_rms:g} % on every cloud and on the sphere up to "
             f"{fn(big['points']) if big else '?'} points is {feps(largest)}, {verdict}. "
             "1 % is comparable with the pipeline's other errors")
        others = []
        for mat in sorted({r["material"] for r in model}):
            spacings, per, coarsest = model_summary(model, mat)
            if coarsest is not None:
                p = per[coarsest]
                others.append(f"{mat} baked at {feps(coarsest)} mean free path is "
                              f"{p['bias'] * 100:.1f} % off on a regular grid")
        bd = [r["rms_pct"] for r in brick if abs(r["maxerror"] - DEFAULT_MAXERROR) < 1e-12]
        if bd:
            others.append(f"brick maps at the default -maxerror add "
                          f"{rng(bd, '{:.2f}', ' %')} RMS")
        if others:
            s += " (" + "; ".join(others) + ")"
        s += (", so a more accurate evaluation would mostly buy digits that the rest of the "
              "pipeline does not keep.")
        out.append(s)

    # --- against the classic criteria
    eq_err, eq_time, t1, e1 = [], [], [], []
    not_reached = []
    for n in names:
        x, d = comps[n].get("bbox"), comps[n]["default"]
        if not (x and d):
            continue
        if x["time_at_err"] is not None:
            eq_err.append(x["time_at_err"] / d["seconds"])
        elif d["rms_pct"] < x["finest"]["rms_pct"]:
            not_reached.append(n)
            eq_err.append(x["finest"]["seconds"] / d["seconds"])
        if x["err_at_time"] is not None:
            eq_time.append(x["err_at_time"] / d["rms_pct"])
        if x["at1"]:
            t1.append(x["at1"]["seconds"] / d["seconds"])
            e1.append(x["at1"]["rms_pct"] / d["rms_pct"])
    s = (f"- *Against PRMan's criterion.* At equal error `bbox` needs "
         f"{rng(eq_err, '{:.1f}', 'x')} the default's time")
    if not_reached:
        s += (f" (on {', '.join(not_reached)} it never reaches the default's error: the "
              "figure is its time at 0.03, a lower bound)")
    s += (f"; at equal time its error is {rng(eq_time, '{:.0f}', 'x')} the default's. At its own "
          f"default (1) it takes {rng(t1, '{:.2f}', 'x')} our time for "
          f"{rng(e1, '{:.0f}', 'x')} our error.")
    out.append(s)
    # centroid against bbox at equal time
    cb = []
    for n in names:
        cc, bb = curve(sweep, n, "centroid"), curve(sweep, n, "bbox")
        for r in bb:
            ec = error_at_time(cc, r["seconds"])
            if ec is not None:
                cb.append(ec / r["rms_pct"])
    c1 = [at_eps(curve(sweep, n, "centroid"), 1.0) for n in names]
    c1 = [r["rms_pct"] for r in c1 if r]
    if cb:
        better = max(cb) < 1
        out.append(f"- *Jensen & Buhler's centroid distance* has {rng(c1, '{:.0f}', ' %')} RMS "
                   "error at 1, unusable at PRMan's default value; at equal time, though, its "
                   f"error is {rng(cb, '{:.2f}', 'x')} that of `bbox`"
                   + (", so of the two classic criteria it is the better one once its "
                      "knob is set low enough." if better else "."))
    out.append("- *PRMan's number.* 1 is also PRMan's default, so scripts that pass "
               "`-maxsolidangle 1` get the default quality, and a user's sense of the knob "
               "(smaller: slower and more accurate) carries over.")
    out.append("")

    # --- profile
    if profiles:
        tr, er = {"better": [], "burley": []}, {"better": [], "burley": []}
        for n in sorted({r["case"] for r in profiles}):
            c0 = at_eps(curve(sweep, n, "error", "classic"), 1.0)
            for p in ("better", "burley"):
                c = at_eps(curve(profiles, n, "error", p), 1.0)
                if c0 and c:
                    tr[p].append(c["seconds"] / c0["seconds"])
                    er[p].append(c["rms_pct"])
        out.append("**Classic profile.** It is PRMan's, so the look matches PRMan's; the "
                   "data does not decide it. At 1 the other profiles cost "
                   f"{rng(tr['better'], '{:.2f}', 'x')} (better) and "
                   f"{rng(tr['burley'], '{:.2f}', 'x')} (burley) the classic's time, with "
                   f"RMS errors of {rng(er['better'], '{:.2f}', ' %')} and "
                   f"{rng(er['burley'], '{:.2f}', ' %')}: the error criterion follows each "
                   "profile's own shape, so the knob means about the same for all three.")
        out.append("")
    if brick:
        out.append(brick_why(brick, sweep))
    return "\n".join(out)


def brick_floor(rows):
    """True when pruning is not what limits the map's error (finest ~ default)."""
    d = [r for r in rows if abs(r["maxerror"] - DEFAULT_MAXERROR) < 1e-12]
    return bool(d) and rows[0]["rms_abs"] > 0.95 * d[0]["rms_abs"]


def brick_why(brick, sweep):
    parts = []
    allowed = []
    for case in sorted({r["case"] for r in brick}):
        rows = sorted([r for r in brick if r["case"] == case], key=lambda r: r["maxerror"])
        d = [r for r in rows if abs(r["maxerror"] - DEFAULT_MAXERROR) < 1e-12]
        diff = at_eps(curve(sweep, case, "error"), 1.0)
        if not d or not diff:
            continue
        d = d[0]
        p = (f"{case}: {d['file_mb']:.1f} MB and {fp(d['rms_pct'])} % RMS lookup error "
             f"(99th percentile {fp(d['p99_pct'])} %) against the diffusion's "
             f"{fp(diff['rms_pct'])} %")
        if brick_floor(rows):
            p += (f", but the same error at {feps(rows[0]['maxerror'])}: there it does not "
                  "come from pruning (see [brickmake](#brickmake--maxerror-against-size-and-"
                  "error))")
        parts.append(p)
        # The largest -maxerror whose lookup error stays under a quarter of the
        # diffusion error, or no worse than at the default (a floor).
        ok = [r for r in rows if r["rms_pct"] <= max(0.25 * diff["rms_pct"],
                                                      1.1 * d["rms_pct"])]
        best = None
        for r in rows:  # the largest such that it and every smaller one pass
            if r not in ok:
                break
            best = r
        if best:
            allowed.append((case, best, d))
    s = ("**brickmake `-maxerror 0.002`.** PRMan documents about half of 1/255 for data in "
         "[0, 1]. The map should add much less error than the diffusion already carries: "
         + "; ".join(parts) + ".")
    looser = [(c, b, d) for c, b, d in allowed if b["maxerror"] > DEFAULT_MAXERROR]
    if allowed and len(looser) == len(allowed):
        m = min(b["maxerror"] for _, b, _ in allowed)
        sizes = []
        for c, b, d in allowed:
            r = [x for x in brick if x["case"] == c and abs(x["maxerror"] - m) < 1e-12][0]
            sizes.append(f"{c} {d['file_mb']:.1f} -> {r['file_mb']:.1f} MB, "
                         f"{fp(r['rms_pct'])} % RMS")
        s += (f" The data would allow a coarser default: at {feps(m)} the lookup error stays "
              "under a quarter of the diffusion's, or no worse than at 0.002, on every map ("
              + "; ".join(sizes) + "). We keep 0.002 because it is PRMan's value, so maps "
              "built from PRMan command lines have the quality their users expect, and a map "
              "of a few MB is rarely what limits a render.")
    return s


def scaling_text(scaling):
    rows = scaling_rows(scaling, "error", 1.0)
    if len(rows) < 2:
        return ""
    a, b = rows[0], rows[-1]
    slope = math.log(b["seconds"] / a["seconds"]) / math.log(b["points"] / a["points"])
    rb = scaling_rows(scaling, "bbox", 1.0)
    s = (f"From {fn(a['points'])} to {fn(b['points'])} points the default's time grows as "
         f"N^{slope:.2f} ({a['points_per_s'] / 1e3:.0f} k points/s at {fn(a['points'])}, "
         f"{b['points_per_s'] / 1e3:.0f} k at {fn(b['points'])}). Its RMS error grows from "
         f"{fp(a['rms_pct'])} % to {fp(b['rms_pct'])} %")
    if len(rb) >= 2:
        s += f" (bbox at 1: {fp(rb[0]['rms_pct'])} % to {fp(rb[-1]['rms_pct'])} %)"
    s += (f", and the far terms per point from {a['far_terms_per_point']:.0f} to "
          f"{b['far_terms_per_point']:.0f}: a denser cloud has a deeper tree, so more nodes "
          "are used whole, each within the tolerance, and their errors add up. ")
    if not missing(b["tool_peak_mb"]):
        s += (f"`ptfilter` on {fn(b['points'])} points takes {fs(b['tool_seconds'])} s end to "
              f"end and peaks at {b['tool_peak_mb']:.0f} MB "
              f"({b['tool_peak_mb'] * 1048576 / b['points']:.0f} bytes per point, input and "
              "output clouds included).")
    return s


def model_intro(model):
    mats = sorted({r["material"] for r in model})
    parts = []
    for m in mats:
        rows = [r for r in model if r["material"] == m]
        side = rows[0]["side_mm"]
        parts.append(f"{m}: {side:.0f} mm")
    receivers = int(model[0]["receivers"])
    truncation = max(1 - r["square_over_albedo"] for r in model) * 100
    return (
        "Separate from the evaluation: how far the point model itself (each point a disk of "
        "its area, exact self term, close disks integrated) is from the continuous surface. "
        "A plane lit uniformly with E = 1 diffuses to exactly albedo x E far from its edges. "
        "The plane is a square grid of points at spacing h (regular, and jittered by half a "
        "spacing as `ptsynth -jitter 0.5` makes), 16 times the largest dmfp across ("
        + ", ".join(parts) + f"); the result is the exact all-pairs evaluation at the "
        f"{receivers} points nearest the centre, divided by the exact integral of the "
        "profile over the same square (albedo x E less the part of the profile beyond the "
        f"edge, at most {truncation:.3f} % here). h is given in mean free paths 1/sigma_t' "
        "of the material's smallest channel: `ptbake -spacing mfp -mfpfraction F` dices at "
        "h = F of that length.")


def model_table(model):
    rows = []
    spacings = sorted({r["spacing_over_mfp"] for r in model})
    for mat in sorted({r["material"] for r in model}):
        for f in spacings:
            sel = [r for r in model if r["material"] == mat and r["spacing_over_mfp"] == f]
            if not sel:
                continue
            cells = [mat, feps(f), f"{sel[0]['spacing_mm']:.3g}", fn(sel[0]["points"])]
            for prof in ["classic", "better", "burley"]:
                reg = {r["channel"]: r for r in sel if r["profile"] == prof and r["jitter"] == 0}
                jit = {r["channel"]: r for r in sel if r["profile"] == prof and r["jitter"] > 0}
                if not reg:
                    continue
                cells.append(" ".join(f"{reg[c]['ratio_median']:.3f}" for c in "rgb"))
                if prof == "classic" and jit:
                    lo = min(jit[c]["ratio_min"] for c in "rgb")
                    hi = max(jit[c]["ratio_max"] for c in "rgb")
                    med = " ".join(f"{jit[c]['ratio_median']:.3f}" for c in "rgb")
                    cells.append(f"{med} ({lo:.2f}-{hi:.2f})")
            rows.append(cells)
    return table(["material", "h / mfp", "h (mm)", "points", "classic, regular: r g b",
                  "classic, jittered: median r g b (min-max)", "better, regular",
                  "burley, regular"], rows)


def model_text(model):
    out = []
    for mat in sorted({r["material"] for r in model}):
        spacings, per, coarsest = model_summary(model, mat)
        worst_bias = max(per[f]["bias"] for f in spacings)
        s = (f"- **{mat}**: on a regular grid the result is within "
             f"{worst_bias * 100:.1f} % of albedo x E at every spacing measured "
             f"({feps(spacings[0])} to {feps(spacings[-1])} mean free paths). Jittered points "
             "add noise: the worst receiver is off by "
             + ", ".join(f"{fp(per[f]['noise'] * 100)} % at {feps(f)}" for f in spacings
                         if per[f]["noise"] is not None) + ".")
        if coarsest is not None:
            p = per[coarsest]
            s += (f" **Coarsest bake: {feps(coarsest)} mean free path** ({p['h']:.2g} mm at "
                  f"`-unitlength 1`; the shortest channel's dmfp is {p['dmfp_over_h']:.1f} "
                  "spacings there)")
            s += (": `ptbake -spacing mfp`." if coarsest == 1 else
                  f": `ptbake -spacing mfp -mfpfraction {feps(coarsest)}`.")
        out.append(s)
    out.append("")
    out.append("*Coarsest bake*: the largest spacing at which, and at every finer one, the "
               "regular grid is within 1 % in every channel and no jittered receiver is off "
               "by more than 5 %. The mean stays close to albedo x E even at 8 mean free "
               "paths, because every point is a disk of its own area and close disks are "
               "integrated: the point model conserves energy. What coarse points cost is noise "
               "where they are irregular (each result depends on how much area its near "
               "neighbours happen to cover), and it grows as the spacing approaches the "
               "shortest channel's dmfp. ptbake's points are regular within a patch, so real "
               "bakes lie between the two cases. This test lights the plane uniformly: it "
               "says nothing about resolving shadows and other lighting detail, which needs "
               "points closer than the dmfp of the channel that should show it.")
    return "\n".join(out)


def brick_text(brick, sweep):
    out = []
    for case in sorted({r["case"] for r in brick}):
        rows = sorted([r for r in brick if r["case"] == case], key=lambda r: r["maxerror"])
        a, b = rows[0], rows[-1]
        s = (f"{case}: from -maxerror {feps(a['maxerror'])} to {feps(b['maxerror'])} the file "
             f"shrinks from {a['file_mb']:.1f} to {b['file_mb']:.1f} MB and the RMS lookup "
             f"error grows from {fp(a['rms_pct'])} % to {fp(b['rms_pct'])} % of the mean")
        if brick_floor(rows):
            s += (f". Up to the default this error does not come from pruning: it is the "
                  f"same at {feps(a['maxerror'])}. It is where the map cannot separate data "
                  "at its finest level")
            if case.startswith("teapot"):
                s += (" (here, looked at by hand: the rim of the thin spout, whose two "
                      "sides are closer than a brick sample and fall into the same normal "
                      "tree; the one-sided data of [brickmake.md](brickmake.md))")
        out.append(s)
    t = [r["build_seconds"] for r in brick]
    return ("- " + ".\n- ".join(out) + ".\n"
            f"- Building takes {rng(t, '{:.2f}', ' s')} whatever -maxerror: splatting the "
            "points dominates, pruning is cheap.")


if __name__ == "__main__":
    main()

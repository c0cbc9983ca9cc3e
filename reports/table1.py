#!/usr/bin/python3
"""Table 1 of RBF Liquids for our scenes, from the JSON files ci/bench-scenes writes.

Usage: table1.py DIR [--gate REFERENCE.toml [--bless | --bless-new] [--levels "6 7"] [--until T]]

Every DIR/<scene>-<dim>d-L<level>-<method>-r<k>.json is one run (liquid run --json). Per scene,
dimension and level: the median over repeats of each figure; the adaptive run's fluid cells and
particles as a share of the regular APIC run's (both measured); seconds per step of grid, ppe,
laplacian, transfers (p2g + g2p), advect and total; seconds per particle-step and per cell-step;
and the paper's row (3D, 16 cores) with the ratio of core-seconds per particle-step, ours over the
paper's. Writes DIR/table1.md and prints it.

With --gate (the scale tier, ci/bench-scenes --paper-sizes): a table of the ratios per scene and
size (adaptive over regular APIC seconds over the window, shares of fluid cells and particles,
core-us per particle-step beside the paper's row at the same h, peak memory), checked against the
accepted ratios in REFERENCE.toml. Entries are per scene, level and window: the first N steps, or
"to T s" for runs to a simulated time (--until T, which ci/bench-scenes passes with
LIQUID_SCALE_UNTIL; the two runs may then take different numbers of steps, so the time ratio is of
their total seconds). Exit 1 naming every ratio that grew past its tolerance, an accepted entry at
a level the run was asked for (--levels, default 6 and 7) that it did not make, or a row of the run
with no accepted entry for its window. --bless writes this run's entries (keeping those of other
levels and windows); --bless-new checks the accepted ones and, when they pass, adds this run's rows
that have none (a first 2^-8 run, a first whole run). Tolerances are kept as the file has them.
"""

import argparse
import json
import math
import pathlib
import re
import statistics
import sys
import tomllib

# RBF Liquids, Table 1 (3D, h, #cells (% of regular), #particles (%), T_grid, T_PPE, T_Lap, T_vel,
# total; seconds per step on a 16-core Ryzen 9 3950X).
PAPER = {
    "dam-break-obstacles": [("Fig. 1", "2^-7", 169e3, 71, 0.8e6, 58, 3.54, 0.43, 0.10, 0.70, 6.18),
                            ("Fig. 1", "2^-8", 745e3, 45, 4.0e6, 32, 27.97, 6.57, 0.60, 5.88, 49.09)],
    "drop": [("Fig. 8", "2^-7", 240e3, 44, 1.4e6, 37, 7.36, 1.25, 0.25, 1.52, 12.97)],
    "quad-dam-break": [("Fig. 12", "2^-7", 201e3, 73, 1.0e6, 56, 5.82, 0.46, 0.12, 0.92, 9.10)],
}
PAPER_CORES = 16
NAME = re.compile(r"^(?P<scene>.+)-(?P<dim>[23])d-L(?P<level>\d+)-(?P<method>[a-z]+-[a-z]+)-r\d+$")


def median_run(runs):
    """Median of every figure over repeated runs."""
    out = {k: statistics.median(r[k] for r in runs)
           for k in ("fluid_cells", "particles", "cells", "regular_cells", "regular_particles", "steps", "time")}
    out["peak_mb"] = statistics.median(r.get("peak_memory_mb", float("nan")) for r in runs)
    phases = set().union(*(r["seconds_per_step"] for r in runs))
    out["sec"] = {p: statistics.median(r["seconds_per_step"].get(p, 0.0) for r in runs) for p in phases}
    out["threads"] = runs[0]["threads"]
    out["repeats"] = len(runs)
    return out


# The phases of a step as the bars and the growth fits show them: (label, keys summed).
PHASES = [("grid", ("grid",)), ("laplacian", ("laplacian",)), ("ppe", ("ppe",)), ("project", ("project",)),
          ("transfers", ("p2g", "g2p")), ("advect", ("advect",))]


def phase_seconds(sec):
    """Seconds per step of each phase of PHASES, and 'other' (the rest of 'total')."""
    out = {label: sum(sec.get(k, 0.0) for k in keys) for label, keys in PHASES}
    out["other"] = max(0.0, sec.get("total", 0.0) - sum(out.values()))
    return out


def pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        return plt
    except ImportError:
        print("table1: matplotlib missing (ci/setup installs python3-matplotlib); no plots", file=sys.stderr)
        return None


def save(plt, fig, ax, folder, name, legend_outside=False):
    """Legend (beside the axes when asked), layout, PNG into folder; returns the file name."""
    if legend_outside:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    else:
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / name, dpi=110)
    plt.close(fig)
    return name


def phase_bars(groups, folder):
    """Stacked bars of each phase's share of a step, one bar per run (scene, h, method)."""
    plt = pyplot()
    if plt is None:
        return []
    lines = []
    for dim in (2, 3):
        keys = sorted(k for k in groups if k[1] == dim)
        if not keys:
            continue
        labels, stacks = [], []
        for scene, _, level in keys:
            for method in ("adaptive-rbf", "regular-rbf", "regular-apic"):
                if method in groups[(scene, dim, level)]:
                    r = median_run(groups[(scene, dim, level)][method])
                    labels.append(f"{scene} 2^-{level}\n{method}")
                    stacks.append(phase_seconds(r["sec"]))
        # Shares of the step, stacked to 100%, with the step's seconds above each bar: sizes differ by
        # orders of magnitude, and a log axis would distort the stack.
        fig, ax = plt.subplots(figsize=(max(6.4, 0.55 * len(labels)), 4.8))
        bottom = [0.0] * len(labels)
        totals = [sum(s.values()) for s in stacks]
        for phase in [p for p, _ in PHASES] + ["other"]:
            values = [100.0 * s[phase] / t if t > 0 else 0.0 for s, t in zip(stacks, totals)]
            ax.bar(range(len(labels)), values, bottom=bottom, label=phase)
            bottom = [b + v for b, v in zip(bottom, values)]
        for i, t in enumerate(totals):
            ax.text(i, 101, f"{t:.3g} s", ha="center", va="bottom", fontsize=6, rotation=90)
        ax.set_ylim(0, 125)
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels(labels, rotation=90, fontsize=6)
        ax.set_ylabel("share of a step (%), seconds per step above")
        ax.set_title(f"Table 1 runs ({dim}D): where a step's time goes")
        name = save(plt, fig, ax, folder, f"table1-phases-{dim}d.png", legend_outside=True)
        lines += ["", f"![seconds per step by phase, {dim}D]({name})"]
    return lines


def fit_exponent(xs, ys):
    """Least-squares slope of log y against log x (points with y > 0)."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0]
    if len(pts) < 2:
        return float("nan")
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else float("nan")


def growth(groups, folder):
    """Per scene, dimension and method with runs at 3 or more sizes: seconds per step of each phase
    against particles, log-log, with the fitted exponent; phases growing faster than linearly
    (exponent above 1.1 between the two largest sizes) are named."""
    series = {}
    for (scene, dim, level), methods in groups.items():
        for method, runs in methods.items():
            series.setdefault((scene, dim, method), []).append((level, median_run(runs)))
    rows, faster, plots = [], [], []
    plt = pyplot()
    for (scene, dim, method), runs in sorted(series.items()):
        if len(runs) < 3:
            continue
        runs.sort()
        particles = [r["particles"] for _, r in runs]
        phases = [phase_seconds(r["sec"]) for _, r in runs]
        totals = [r["sec"].get("total", 0.0) for _, r in runs]
        exps = {label: fit_exponent(particles, [p[label] for p in phases]) for label, _ in PHASES}
        exps["total"] = fit_exponent(particles, totals)
        # Between the two largest sizes only: the smallest trees can be pre-asymptotic (a 3D tree at
        # level 3 has no T-junction, hence no RBF-FD rows), which bends a fit over all sizes.
        last = {label: fit_exponent(particles[-2:], [p[label] for p in phases[-2:]]) for label, _ in PHASES}
        last["total"] = fit_exponent(particles[-2:], totals[-2:])
        levels = ", ".join(f"2^-{l}" for l, _ in runs)
        for what, e in (("all sizes", exps), ("two largest", last)):
            rows.append(f"| {scene}-{dim}d | {method} | {levels} | {particles[0]:.0f} - {particles[-1]:.0f} | {what} | "
                        + " | ".join(f"{e[k]:.2f}" for k in [p for p, _ in PHASES] + ["total"]) + " |")
        faster += [f"{scene}-{dim}d {method}: {k} ({v:.2f} between the two largest sizes, {exps[k]:.2f} over all)"
                   for k, v in last.items() if k != "total" and v > 1.1]
        if plt is not None:
            fig, ax = plt.subplots(figsize=(6.4, 4.8))
            for label, _ in PHASES:
                ys = [p[label] for p in phases]
                if any(y > 0 for y in ys):
                    ax.loglog(particles, ys, marker="o", markersize=3, linewidth=1,
                              label=f"{label} ({exps[label]:.2f})")
            ax.loglog(particles, totals, "k-", marker="s", markersize=3, linewidth=1.5,
                      label=f"total ({exps['total']:.2f})")
            x0, x1 = particles[0], particles[-1]
            ax.loglog([x0, x1], [totals[0], totals[0] * x1 / x0], "k:", linewidth=1, label="slope 1")
            ax.set_xlabel("particles")
            ax.set_ylabel("seconds per step")
            ax.set_title(f"{scene}-{dim}d {method}: cost against work (fitted exponents)")
            name = save(plt, fig, ax, folder, f"table1-growth-{scene}-{dim}d-{method}.png")
            plots.append(f"![growth of {scene}-{dim}d {method}]({name})")
    if not rows:
        return ["", "No scene ran at 3 or more sizes: no growth fit (ci/bench-scenes runs them)."]
    lines = ["", "### How each phase's cost grows with the work", "",
             "Exponent b of seconds per step ~ particles^b (1 is linear): least squares over all the sizes "
             "run, and between the two largest alone.", "",
             "| run | method | h | particles | fit | " + " | ".join(p for p, _ in PHASES) + " | total |",
             "| --- | --- | --- | --- | --- | " + " | ".join("---:" for _ in PHASES) + " | ---: |"] + rows
    lines += ["", "Faster than linear (exponent above 1.1 between the two largest sizes): "
              + ("; ".join(faster) if faster else "none") + "."]
    lines += [""] + plots
    return lines


GATED = ("time", "cells", "particles")
GATE_HELP = {"time": "adaptive / regular APIC seconds over the window", "cells": "adaptive / regular fluid cells",
             "particles": "adaptive / regular particles"}


def read_reference(path):
    """The accepted ratios: {(scene, level, window): {figure: value}}, and the tolerances. Strict: an unknown
    key, a missing one or a value that is not a positive number is an error naming the entry."""
    doc = tomllib.loads(pathlib.Path(path).read_text())
    unknown = set(doc) - {"tolerance", "ratio"}
    if unknown:
        raise ValueError(f"{path}: unknown table(s) {sorted(unknown)} (known: tolerance, ratio)")
    tol = doc.get("tolerance", {})
    if set(tol) != {"time_rel", "share_rel"}:
        raise ValueError(f"{path}: [tolerance] must hold exactly time_rel and share_rel, found {sorted(tol)}")
    accepted = {}
    for k, entry in enumerate(doc.get("ratio", [])):
        keys = {"scene", "level", "window"} | set(GATED)
        if set(entry) != keys:
            raise ValueError(f"{path}: [[ratio]] #{k + 1}: keys {sorted(entry)}, expected {sorted(keys)}")
        if not isinstance(entry["scene"], str) or not isinstance(entry["window"], str) \
                or not isinstance(entry["level"], int) or isinstance(entry["level"], bool):
            raise ValueError(f"{path}: [[ratio]] #{k + 1}: scene and window must be strings and level a whole "
                             f"number, found {entry['scene']!r}, {entry['window']!r}, {entry['level']!r}")
        for f in GATED:
            if not isinstance(entry[f], (int, float)) or not entry[f] > 0 or math.isinf(entry[f]):
                raise ValueError(f"{path}: [[ratio]] #{k + 1} ({entry['scene']}, {entry['level']}): '{f}' "
                                 f"must be a positive number, found {entry[f]!r}")
        key = (entry["scene"], int(entry["level"]), entry["window"])
        if key in accepted:
            raise ValueError(f"{path}: [[ratio]] #{k + 1}: a second entry for {key}")
        accepted[key] = {f: entry[f] for f in GATED}
    for name in ("time_rel", "share_rel"):
        if not isinstance(tol[name], (int, float)) or not 0 <= tol[name] < 10:
            raise ValueError(f"{path}: tolerance.{name} must be a number in [0, 10), found {tol[name]!r}")
    return accepted, tol


def scale_ratios(groups, until=None):
    """Per (scene, level) with both runs: the gated ratios, and what the table prints beside them.
    `until`: the runs went to this simulated time (their window), not a number of steps."""
    rows = {}
    for (scene, dim, level), methods in sorted(groups.items()):
        if dim != 3 or "adaptive-rbf" not in methods or "regular-apic" not in methods:
            continue
        a, g = median_run(methods["adaptive-rbf"]), median_run(methods["regular-apic"])
        ta, tg = a["sec"].get("total", float("nan")), g["sec"].get("total", float("nan"))
        # To a simulated time the two runs may take different numbers of steps: the gain is then the
        # seconds each needs for the whole window. Over N steps it is the ratio of seconds a step (also
        # when the regular run took fewer steps, LIQUID_SCALE_L8_REGULAR_STEPS: printed, not gated).
        ratio = ta * a["steps"] / (tg * g["steps"]) if until else ta / tg
        core_us = 1e6 * ta * a["threads"] / a["particles"]
        paper = [p for p in PAPER.get(scene, []) if p[1] == f"2^-{level}"]
        paper_us = 1e6 * paper[0][10] * PAPER_CORES / paper[0][4] if paper else float("nan")
        rows[(f"{scene}-3d", level)] = {
            "time": ratio, "cells": a["fluid_cells"] / g["fluid_cells"],
            "particles": a["particles"] / g["particles"],
            "window": f"to {until:g} s" if until else f'{a["steps"]:.0f} steps (regular {g["steps"]:.0f})',
            "shown": f'to {until:g} s ({a["steps"]:.0f} steps, regular {g["steps"]:.0f})' if until
                     else f'{a["steps"]:.0f} steps (regular {g["steps"]:.0f})', "ta": ta, "tg": tg,
            "core_us": core_us, "paper_us": paper_us, "per_particle": (ta / a["particles"]) / (tg / g["particles"]),
            "peak_a": a["peak_mb"], "peak_g": g["peak_mb"],
            "same_window": bool(until) or a["steps"] == g["steps"]}
    return rows


def fmt(x, spec):
    """x formatted, or '-' when it is not a number (no paper row at that h, no memory figure)."""
    return "-" if x != x else format(x, spec)


def scale_table(rows):
    lines = ["", "## Scale tier: the gain at the paper's sizes (ci/bench-scenes --paper-sizes)", "",
             "Adaptive RBF against regular APIC at the same finest h, over the stated window from the start (a "
             "number of steps, or a simulated time). speed-up: regular seconds over adaptive, a step's over N "
             "steps and the whole run's to a time (the two may then take different numbers of steps); shares: "
             "adaptive over regular; "
             "per particle-step: adaptive's cost over regular's; core-us: total seconds x threads per particle, "
             "beside the paper's row at the same h (16 cores).", "",
             "| scene | h | window | adaptive s/step | regular s/step | speed-up | fluid cells | particles | "
             "per particle-step | core-us adaptive | core-us paper | ours / paper | peak MB adaptive | "
             "peak MB regular |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for (scene, level), r in rows.items():
        lines.append(
            f"| {scene} | 2^-{level} | {r['shown']} | {r['ta']:.3f} | {r['tg']:.3f} | {1 / r['time']:.2f}x | "
            f"{100 * r['cells']:.0f}% | {100 * r['particles']:.0f}% | {r['per_particle']:.2f} | {r['core_us']:.1f} | "
            f"{fmt(r['paper_us'], '.1f')} | {fmt(r['core_us'] / r['paper_us'], '.3f')} | {fmt(r['peak_a'], '.0f')} | "
            f"{fmt(r['peak_g'], '.0f')} |")
    return lines


# The levels the tier runs unless told otherwise (LIQUID_SCALE_L8=1 adds 8, LIQUID_SCALE_LEVELS picks):
# an accepted ratio at a level the run was not asked for is kept and not checked.
DEFAULT_LEVELS = (6, 7)
DEFAULT_TOLERANCE = {"time_rel": 0.3, "share_rel": 0.05}


def write_reference(path, entries, tol, how):
    """Writes the accepted ratios {(scene, level, window): {figures}} in order, with the tolerances."""
    text = ["# Accepted ratios of the scale tier (ci/bench-scenes --paper-sizes), checked by reports/table1.py.",
            "# Written by LIQUID_SCALE_BLESS=1 (or =new: added rows) ci/bench-scenes --paper-sizes; a commit that",
            "# moves them says why. time: adaptive / regular APIC seconds over the window; cells, particles:",
            "# adaptive / regular. One entry per scene, level and window: the first N steps, or a run to a",
            "# simulated time (LIQUID_SCALE_UNTIL).", "",
            "[tolerance]", f"time_rel = {tol['time_rel']}", f"share_rel = {tol['share_rel']}"]
    for (scene, level, window), e in sorted(entries.items()):
        text += ["", "[[ratio]]", f'scene = "{scene}"', f"level = {level}", f'window = "{window}"']
        text += [f"{f} = {e[f]:.4g}" for f in GATED]
    pathlib.Path(path).write_text("\n".join(text) + "\n")
    print(f"table1: wrote {path}: {how}")


def gate(rows, path, bless, bless_new=False, levels=None):
    """Compares the ratios with the accepted ones (or writes them); returns the exit status. `levels`:
    the levels the run was asked for (default DEFAULT_LEVELS, and those it made)."""
    asked = set(levels or DEFAULT_LEVELS) | {level for (_, level) in rows}
    # A shorter regular window (LIQUID_SCALE_L8_REGULAR_STEPS) is printed, never accepted or checked.
    measured = {(scene, level, r["window"]): {f: r[f] for f in GATED} for (scene, level), r in rows.items()
                if r["same_window"]}
    exists = pathlib.Path(path).exists()
    accepted, tol = read_reference(path) if exists else ({}, dict(DEFAULT_TOLERANCE))
    if bless:  # replaces the entries of the levels and windows this run made; keeps the others
        kept = {k: e for k, e in accepted.items() if k not in measured}
        write_reference(path, kept | measured, tol,
                        f"{len(measured)} entries from this run, {len(kept)} kept of other levels or windows")
        return 0
    if not exists and not bless_new:
        raise OSError(f"{path}: no accepted ratios (LIQUID_SCALE_BLESS=1 or =new writes them)")
    failures, checked = [], 0
    for (scene, level, window), entry in accepted.items():
        row = rows.get((scene, level))
        if row is None and level not in asked:
            print(f"table1 gate: {scene} 2^-{level} over '{window}': level not run (LIQUID_SCALE_L8=1 or "
                  f"LIQUID_SCALE_LEVELS runs it), not checked")
            continue
        if row is None:
            failures.append(f"{path}: {scene} at 2^-{level}: accepted, but this run made no such pair of runs")
            continue
        if row["window"] != window:
            continue  # another window's entry (the first steps beside a whole run)
        checked += 1
        for f in GATED:
            limit = entry[f] * (1 + (tol["time_rel"] if f == "time" else tol["share_rel"]))
            now = row[f]
            status = "ok" if now <= limit else "REGRESSION"
            print(f"table1 gate: {scene} 2^-{level} {GATE_HELP[f]}: accepted {entry[f]:.4g}, now {now:.4g}, "
                  f"allowed {limit:.4g}: {status}")
            if now > limit:
                failures.append(f"{scene} at 2^-{level}: {GATE_HELP[f]} {now:.4g} > {limit:.4g}")
    new = {k: e for k, e in measured.items() if k not in accepted}
    for (scene, level, window) in sorted(new):
        message = f"{scene} at 2^-{level} over '{window}': no accepted ratios for this window"
        if bless_new:
            print(f"table1 gate: {message}; adding this run's")
        else:
            failures.append(f"{message} (LIQUID_SCALE_BLESS=new accepts them once the others pass)")
    print(f"table1 gate: {checked} pairs of runs checked against {path}")
    for f in failures:
        print(f"table1 gate: {f}", file=sys.stderr)
    if failures:
        return 1
    if bless_new and new:
        write_reference(path, accepted | new, tol,
                        f"added {sorted(new)}; the {len(accepted)} accepted entries and the tolerances unchanged")
    return 0


def level_list(text):
    """--levels' value: whole levels separated by spaces or commas."""
    return [int(x) for x in text.replace(",", " ").split()]


def positive_time(text):
    """--until's value: a positive, finite simulated time."""
    t = float(text)
    if not (t > 0 and math.isfinite(t)):
        raise ValueError(text)
    return t


def main():
    parser = argparse.ArgumentParser(prog="table1.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("folder")
    parser.add_argument("--gate", metavar="REFERENCE.toml", dest="reference")
    blessing = parser.add_mutually_exclusive_group()
    blessing.add_argument("--bless", action="store_true")
    blessing.add_argument("--bless-new", action="store_true")
    parser.add_argument("--levels", type=level_list, help="the levels the run was asked for, such as '6 7'")
    parser.add_argument("--until", type=positive_time, help="the runs went to this simulated time")
    args = parser.parse_args()
    reference = args.reference
    if (args.bless or args.bless_new) and reference is None:
        parser.error("--bless and --bless-new need --gate REFERENCE.toml")
    folder = pathlib.Path(args.folder)
    groups = {}
    for path in sorted(folder.glob("*.json")):
        m = NAME.match(path.stem)
        if not m:
            continue
        key = (m["scene"], int(m["dim"]), int(m["level"]))
        groups.setdefault(key, {}).setdefault(m["method"], []).append(json.loads(path.read_text()))
    if not groups:
        print(f"table1: no run files in {folder}", file=sys.stderr)
        return 2
    lines = ["## Table 1 for our scenes (ci/bench-scenes)", "",
             "Seconds per step, median over repeats; % reg: share of the regular APIC run's fluid cells and "
             "particles at the same finest h (both runs made). core-s/particle-step: total x threads / "
             "particles; vs paper: that figure over the paper's first row for the scene (3D only; 16 cores, "
             "h = 2^-7, whatever our h).", "",
             "| scene | h | method | fluid cells | % reg | particles | % reg | grid s | ppe s | laplacian s | "
             "transfer s | advect s | total s | grid % | us/particle-step | us/cell-step | threads | vs paper |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
             "| ---: | ---: | ---: |"]
    for (scene, dim, level), methods in sorted(groups.items()):
        runs = {m: median_run(r) for m, r in methods.items()}
        reg = runs.get("regular-apic")
        # The paper's rows are 3D at h = 2^-7 and 2^-8; cost per particle-step is compared with its
        # first row whatever our h (the paper's sizes do not fit this machine), printed once per scene.
        paper = PAPER.get(scene, []) if dim == 3 else []
        top = max(l for (s2, d2, l) in groups if s2 == scene and d2 == dim)
        for method in ("adaptive-rbf", "regular-rbf", "regular-apic"):
            if method not in runs:
                continue
            r = runs[method]
            sec = r["sec"]
            total = sec.get("total", 0.0)
            # A size run adaptive only (for the growth fit) has no regular run to compare with.
            cell_share = f'{100.0 * r["fluid_cells"] / reg["fluid_cells"]:.0f}%' if reg else "-"
            particle_share = f'{100.0 * r["particles"] / reg["particles"]:.0f}%' if reg else "-"
            core_s = total * r["threads"] / r["particles"] if r["particles"] else float("nan")
            vs = ""
            if paper:
                p = paper[0]
                vs = f"{core_s / (p[10] * PAPER_CORES / p[4]):.2f}"
            lines.append(
                f"| {scene}-{dim}d | 2^-{level} | {method} | {r['fluid_cells']:.0f} | {cell_share} | "
                f"{r['particles']:.0f} | {particle_share} | {sec.get('grid', 0):.4f} | {sec.get('ppe', 0):.4f} | "
                f"{sec.get('laplacian', 0):.4f} | {sec.get('p2g', 0) + sec.get('g2p', 0):.4f} | "
                f"{sec.get('advect', 0):.4f} | {total:.4f} | {100 * sec.get('grid', 0) / total if total else 0:.1f} | "
                f"{1e6 * total / r['particles'] if r['particles'] else 0:.2f} | "
                f"{1e6 * total / r['fluid_cells'] if r['fluid_cells'] else 0:.2f} | {r['threads']} | {vs} |")
        for p in paper if level == top else []:
            lines.append(f"| paper {p[0]} | {p[1]} | adaptive (16 cores) | {p[2]:.0f} | {p[3]}% | {p[4]:.0f} | {p[5]}% | "
                         f"{p[6]:.2f} | {p[7]:.2f} | {p[8]:.2f} | {p[9]:.2f} | - | {p[10]:.2f} | "
                         f"{100 * p[6] / p[10]:.1f} | {1e6 * p[10] / p[4]:.2f} | {1e6 * p[10] / p[2]:.2f} | 16 | 1.00 |")
    lines += phase_bars(groups, folder)
    lines += growth(groups, folder)
    rows = scale_ratios(groups, args.until) if reference else {}
    if reference:
        lines += scale_table(rows)
    text = "\n".join(lines) + "\n"
    (folder / "table1.md").write_text(text)
    print(text)
    if reference:
        try:
            return gate(rows, reference, args.bless, args.bless_new, args.levels)
        except (ValueError, tomllib.TOMLDecodeError, OSError) as e:
            print(f"table1 gate: {e}", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

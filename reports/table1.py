#!/usr/bin/python3
"""Table 1 of RBF Liquids for our scenes, from the JSON files ci/bench-scenes writes.

Usage: table1.py DIR

Every DIR/<scene>-<dim>d-L<level>-<method>-r<k>.json is one run (liquid run --json). Per scene,
dimension and level: the median over repeats of each figure; the adaptive run's fluid cells and
particles as a share of the regular APIC run's (both measured); seconds per step of grid, ppe,
laplacian, transfers (p2g + g2p), advect and total; seconds per particle-step and per cell-step;
and the paper's row (3D, 16 cores) with the ratio of core-seconds per particle-step, ours over the
paper's. Writes DIR/table1.md and prints it.
"""

import json
import pathlib
import re
import statistics
import sys

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
           for k in ("fluid_cells", "particles", "cells", "regular_cells", "regular_particles", "steps")}
    phases = set().union(*(r["seconds_per_step"] for r in runs))
    out["sec"] = {p: statistics.median(r["seconds_per_step"].get(p, 0.0) for r in runs) for p in phases}
    out["threads"] = runs[0]["threads"]
    out["repeats"] = len(runs)
    return out


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    folder = pathlib.Path(sys.argv[1])
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
            cell_share = 100.0 * r["fluid_cells"] / reg["fluid_cells"] if reg else float("nan")
            particle_share = 100.0 * r["particles"] / reg["particles"] if reg else float("nan")
            core_s = total * r["threads"] / r["particles"] if r["particles"] else float("nan")
            vs = ""
            if paper:
                p = paper[0]
                vs = f"{core_s / (p[10] * PAPER_CORES / p[4]):.2f}"
            lines.append(
                f"| {scene}-{dim}d | 2^-{level} | {method} | {r['fluid_cells']:.0f} | {cell_share:.0f}% | "
                f"{r['particles']:.0f} | {particle_share:.0f}% | {sec.get('grid', 0):.4f} | {sec.get('ppe', 0):.4f} | "
                f"{sec.get('laplacian', 0):.4f} | {sec.get('p2g', 0) + sec.get('g2p', 0):.4f} | "
                f"{sec.get('advect', 0):.4f} | {total:.4f} | {100 * sec.get('grid', 0) / total if total else 0:.1f} | "
                f"{1e6 * total / r['particles'] if r['particles'] else 0:.2f} | "
                f"{1e6 * total / r['fluid_cells'] if r['fluid_cells'] else 0:.2f} | {r['threads']} | {vs} |")
        for p in paper if level == top else []:
            lines.append(f"| paper {p[0]} | {p[1]} | adaptive (16 cores) | {p[2]:.0f} | {p[3]}% | {p[4]:.0f} | {p[5]}% | "
                         f"{p[6]:.2f} | {p[7]:.2f} | {p[8]:.2f} | {p[9]:.2f} | - | {p[10]:.2f} | "
                         f"{100 * p[6] / p[10]:.1f} | {1e6 * p[10] / p[4]:.2f} | {1e6 * p[10] / p[2]:.2f} | 16 | 1.00 |")
    text = "\n".join(lines) + "\n"
    (folder / "table1.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

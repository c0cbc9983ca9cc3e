#!/usr/bin/python3
"""Table 1 of Adams et al. 2007 for our SPH scenes, from the JSON files ci/bench-sph-scenes writes.

Usage: table1_sph.py DIR

Every DIR/<scene>-<adaptive|single>-r<k>.json is one run (liquid run --json). Per scene: the median
over repeats of each figure; seconds per step of the paper's phases, adaptive [single resolution]
as the paper prints them; the memory gain (single-resolution particles over adaptive, both
measured) and the speed gain (seconds of stepping per simulated second, single over adaptive: the
two runs' steps differ a little, as their fastest particles do); and the paper's columns beside.
Writes DIR/table1-sph.md and prints it.
"""

import json
import pathlib
import re
import statistics
import sys

# Adams et al. 2007, Table 1: seconds per frame, adaptive [single resolution]; gains memory / speed.
PAPER = {
    "flooding": {"neighbourhood": (28.0, 259.1), "forces": (30.1, 203.9), "projection": (6.3, 17.2),
                 "redistancing": (2.5, 13.1), "elfs": (2.3, None), "resampling": (4.4, None), "gain": (8.0, 6.6)},
    "desk toy": {"neighbourhood": (0.6, 2.2), "forces": (1.3, 3.6), "projection": (0.1, 0.2),
                 "redistancing": (0.05, 0.1), "elfs": (0.08, None), "resampling": (0.05, None), "gain": (3.0, 2.8)},
    "teapot": {"neighbourhood": (10.4, 102.2), "forces": (8.2, 76.6), "projection": (4.4, 14.6),
               "redistancing": (0.9, 6.5), "elfs": (1.2, None), "resampling": (0.7, None), "gain": (7.9, 7.7)},
    "armadillos": {"neighbourhood": (33.2, 222.0), "forces": (36.1, 159.2), "projection": (11.9, 25.4),
                   "redistancing": (2.9, 13.9), "elfs": (2.6, None), "resampling": (4.5, None), "gain": (4.5, 4.3)},
}
# Our scene standing for each of the paper's examples.
COUNTERPART = {"sph-dam-break-2d": "flooding", "sph-dam-break-3d": "flooding", "sph-dam-break-3d-a32": "flooding", "sph-desk-toy-2d": "desk toy",
               "sph-pour-2d": "teapot"}
# The paper's phases and ours: projection = integrate + collisions.
PHASES = [("neighbourhood", ("neighbours",)), ("forces", ("forces",)), ("projection", ("integrate", "collisions")),
          ("redistancing", ("redistance",)), ("elfs", ("elfs",)), ("resampling", ("resample",))]
NAME = re.compile(r"^(?P<scene>.+)-(?P<method>adaptive|single)-r\d+$")


def median_run(runs):
    out = {k: statistics.median(r[k] for r in runs) for k in ("particles", "single_particles", "steps", "time")}
    phases = set().union(*(r["seconds_per_step"] for r in runs))
    out["sec"] = {p: statistics.median(r["seconds_per_step"].get(p, 0.0) for r in runs) for p in phases}
    # Seconds of stepping per simulated second.
    out["per_second"] = statistics.median(r["seconds_per_step"].get("total", 0.0) * r["steps"] / r["time"]
                                          for r in runs)
    out["threads"] = runs[0]["threads"]
    out["repeats"] = len(runs)
    return out


def phase(sec, keys):
    return sum(sec.get(k, 0.0) for k in keys)


def main():
    folder = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "reports/latest/table1-sph")
    runs = {}
    for path in sorted(folder.glob("*.json")):
        m = NAME.match(path.stem)
        if not m:
            continue
        runs.setdefault((m["scene"], m["method"]), []).append(json.loads(path.read_text()))
    scenes = sorted({s for s, _ in runs})
    lines = ["## Table 1 of Adams et al. 2007 for our SPH scenes (ci/bench-sph-scenes)", "",
             "Seconds per step, adaptive [single resolution], medians over repeats; gains: memory (particles, "
             "both runs measured) / speed (seconds of stepping per simulated second). The paper's rows are "
             "seconds per frame on its examples (2007 hardware); compare the gains and the phases' shares, "
             "not the seconds.", ""]
    head = "| run | particles | " + " | ".join(p for p, _ in PHASES) + " | total | gain (memory / speed) |"
    lines += [head, "|" + " --- |" * (len(PHASES) + 4)]
    for scene in scenes:
        a, s = runs.get((scene, "adaptive")), runs.get((scene, "single"))
        if not a or not s:
            continue
        a, s = median_run(a), median_run(s)
        cells = []
        for label, keys in PHASES:
            single = phase(s["sec"], keys)
            cells.append(f"{phase(a['sec'], keys):.2e} [{single:.2e}]" if single > 0 else f"{phase(a['sec'], keys):.2e} [-]")
        memory = s["particles"] / a["particles"] if a["particles"] else float("nan")
        speed = s["per_second"] / a["per_second"] if a["per_second"] else float("nan")
        lines.append(f"| ours: {scene} ({a['repeats']} runs, {a['threads']} threads) | {a['particles']:.0f} "
                     f"[{s['particles']:.0f}] | " + " | ".join(cells) +
                     f" | {a['sec'].get('total', 0):.2e} [{s['sec'].get('total', 0):.2e}] | {memory:.2f}x / {speed:.2f}x |")
        paper = COUNTERPART.get(scene)
        if paper:
            row = PAPER[paper]
            cells = [f"{row[p][0]}s [{row[p][1]}s]" if row[p][1] is not None else f"{row[p][0]}s [-]" for p, _ in PHASES]
            lines.append(f"| paper: {paper} | | " + " | ".join(cells) + f" | | {row['gain'][0]}x / {row['gain'][1]}x |")
    lines.append("")
    text = "\n".join(lines)
    (folder / "table1-sph.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

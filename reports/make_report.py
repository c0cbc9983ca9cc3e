#!/usr/bin/python3
"""Builds the verification report from a suite's output folder.

Usage: make_report.py DIR

Reads DIR/summary.json and, for every case in it, DIR/<case>.json and DIR/<case>.md (written by
`liquid-verify suite`). Writes DIR/README.md: a summary table, then every case's tables and notes,
with a log-log plot (PNG) of every error series a case records under "series", drawn with a
second-order reference slope (linear axes for a series marked "scale": "linear", such as a
quantity over time). Scene runs in DIR/frames/<scene>/ (liquid run --out, with
DIR/frames/<scene>.json from --json) add a picture of their last frame and their Table 1 row;
SPH scene runs in DIR/frames-sph/ likewise (particles by level and the surface mesh);
DIR/table1/table1.md (ci/bench-scenes) and DIR/table1-sph/table1-sph.md (ci/bench-sph-scenes) are
included when present.
"""

import json
import math
import pathlib
import subprocess
import sys


def plot_series(case, series, out_dir):
    """One PNG per group of series; returns the file names written."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("make_report: matplotlib missing (ci/setup installs python3-matplotlib); no plots",
              file=sys.stderr)
        return []
    groups = {}
    for entry in series:
        groups.setdefault(entry["group"], []).append(entry)
    written = []
    for index, (group, entries) in enumerate(groups.items()):
        fig, ax = plt.subplots(figsize=(6.4, 4.8))
        h_all, e_all = [], []
        x_label = entries[0].get("x_label", "h")
        y_label = entries[0].get("y_label", "L-inf error")
        linear = entries[0].get("scale") == "linear"  # a quantity over time, say
        for entry in entries:
            if linear:
                pts = list(zip(entry["h"], entry["error"]))
            else:
                pts = [(h, e) for h, e in zip(entry["h"], entry["error"]) if h and e and e > 0]
            if not pts:
                continue
            hs, es = zip(*pts)
            if linear:
                ax.plot(hs, es, linewidth=1, label=entry["label"])
                continue
            ax.loglog(hs, es, marker="o", markersize=3, linewidth=1, label=entry["label"])
            h_all += hs
            e_all += es
        if h_all and x_label == "h":
            h0, h1 = max(h_all), min(h_all)
            e0 = math.exp(sum(math.log(e) for e in e_all) / len(e_all))
            ax.loglog([h0, h1], [e0, e0 * (h1 / h0) ** 2], "k--", linewidth=1, label="slope 2")
        ax.set_xlabel(x_label)
        ax.set_ylabel(y_label)
        ax.set_title(group, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
        name = f"{case}-{index}.png"
        fig.tight_layout()
        fig.savefig(out_dir / name, dpi=110)
        plt.close(fig)
        written.append(name)
    return written


# What the seed papers report for each case, shown beside our figures.
PAPER = {
    "rbf-fd-consistency": "-",
    "cellgraph-invariants": "-",
    "poisson-neumann-2d": "about 2 for p and grad p (RBF Liquids, Fig. 14)",
    "poisson-neumann-3d": "about 2 for p and grad p (RBF Liquids, Fig. 15)",
    "poisson-dirichlet-levelset-2d": "about 2 for p (RBF Liquids, Fig. 17)",
    "poisson-dirichlet-levelset-3d": "not in the paper; 2 is the goal",
    "poisson-hard": "levels up to 2 tried in the paper (section 8)",
    "poisson-stencil-rules": "1-ring grown by k-ring (section 4.2)",
    "poisson-rbf-degree": "degree 2 (Pi_2, section 7), about 2 for p and grad p",
    "hydrostatic-pool": "still: small drift, spurious speed and pressure error (RBF Liquids, Fig. 16)",
    "transfer-accuracy": "RBF below MLS (RBF Liquids, Fig. 4); RBF keeps more energy than PIC (Fig. 10)",
    "scene-smoke": "-",
    "ppe-solvers": "adaptive BiCGSTAB 2.6x (Jacobi) and 2.5x (ILU, 3x fewer iterations) faster than regular PCG (Sec. 6)",
    "vorticity": "RBF keeps vorticity like APIC, far better than PIC/FLIP (RBF Liquids, Fig. 11)",
    "kinetic-energy": "RBF keeps more kinetic energy than PIC and stays stable (RBF Liquids, Fig. 10)",
    "vorticity-3d": "not in the paper (its Fig. 11 is 2D); the same claim in 3D",
    "kinetic-energy-3d": "RBF keeps more kinetic energy than PIC and stays stable (RBF Liquids, Fig. 10, in 3D)",
    "conditioning": "adaptive PPE worse conditioned but fewer iterations, 68% fewer fluid cells (RBF Liquids, Fig. 13)",
    "ppe-in-scenes": "adaptive BiCGSTAB 2.6x (Jacobi) and 2.5x (ILU, 3x fewer iterations) faster than regular PCG (Sec. 6)",
}


def scene_section(out_dir):
    """Pictures of the last frame of every scene run in DIR/frames, with its Table 1 row."""
    frames = out_dir / "frames"
    if not frames.is_dir():
        return ""
    lines = ["## Scenes", "",
             "`liquid run` on two built-in scenes (2D, default levels): the last frame (cells: air white, "
             "fluid blue, solid grey; particles coloured by speed) and the run's Table 1 row. % reg: share "
             "of a regular grid at the same finest h for the same liquid, computed from the run's own "
             "fluid cells.", ""]
    lines += ["| scene | steps | t (s) | fluid cells | % reg | particles | % reg | grid s | ppe s | laplacian s "
              "| transfer s | total s |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
              "| ---: | ---: |"]
    pictures = []
    for summary in sorted(frames.glob("*.json")):
        name = summary.stem
        s = json.loads(summary.read_text())
        sec = s["seconds_per_step"]
        pct = lambda a, b: 100.0 * a / b if b else 0.0
        lines.append(f"| {name} | {s['steps']} | {s['time']:.3f} | {s['fluid_cells']:.0f} | "
                     f"{pct(s['fluid_cells'], s['regular_cells']):.1f} | {s['particles']:.0f} | "
                     f"{pct(s['particles'], s['regular_particles']):.1f} | {sec.get('grid', 0):.4f} | "
                     f"{sec.get('ppe', 0):.4f} | {sec.get('laplacian', 0):.4f} | "
                     f"{sec.get('p2g', 0) + sec.get('g2p', 0):.4f} | {sec.get('total', 0):.4f} |")
        cells = sorted((frames / name).glob(f"{name}_cells_*.h5"))
        particles = sorted((frames / name).glob(f"{name}_particles_*.h5"))
        if cells and particles:
            png = f"frame-{name}.png"
            done = subprocess.run(["/usr/bin/python3",
                                   str(pathlib.Path(__file__).with_name("frame_picture.py")), str(cells[-1]),
                                   str(particles[-1]), str(out_dir / png),
                                   f"{name}, t = {s['time']:.2f} s (last frame)"])
            if done.returncode == 0:
                pictures.append(f"![{name}]({png})")
    return "\n".join(lines + [""] + pictures) + "\n"


def sph_scene_section(out_dir):
    """Pictures of the last frame of every SPH scene run in DIR/frames-sph, with its Table 1 row."""
    frames = out_dir / "frames-sph"
    if not frames.is_dir():
        return ""
    lines = ["## SPH scenes", "",
             "`liquid run` on SPH scenes (2D): the last frame (particles coloured by level, the distance "
             "surface in red) and the run's Table 1 row (Adams et al. 2007). single res: the level-0 particles "
             "a single-resolution run holds for the same liquid.", ""]
    lines += ["| scene | steps | t (s) | particles | single res | gain | neighbours s | forces s | redistance s "
              "| elfs s | resample s | total s |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
              "| ---: | ---: | ---: |"]
    pictures = []
    for summary in sorted(frames.glob("*.json")):
        name = summary.stem
        s = json.loads(summary.read_text())
        sec = s["seconds_per_step"]
        gain = s["single_particles"] / s["particles"] if s["particles"] else 0.0
        lines.append(f"| {name} | {s['steps']} | {s['time']:.3f} | {s['particles']:.0f} | "
                     f"{s['single_particles']:.0f} | {gain:.2f}x | {sec.get('neighbours', 0):.5f} | "
                     f"{sec.get('forces', 0):.5f} | {sec.get('redistance', 0):.5f} | {sec.get('elfs', 0):.5f} | "
                     f"{sec.get('resample', 0):.5f} | {sec.get('total', 0):.5f} |")
        particles = sorted((frames / name).glob(f"{name}_particles_*.h5"))
        surface = sorted((frames / name).glob(f"{name}_surface_*.h5"))
        if particles and surface:
            png = f"frame-{name}.png"
            done = subprocess.run(["/usr/bin/python3",
                                   str(pathlib.Path(__file__).with_name("sph_frame_picture.py")), str(particles[-1]),
                                   str(surface[-1]), str(out_dir / png),
                                   f"{name}, t = {s['time']:.2f} s (last frame)"])
            if done.returncode == 0:
                pictures.append(f"![{name}]({png})")
    return "\n".join(lines + [""] + pictures) + "\n"


def fmt(value):
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.3f}"
    return str(value)


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out_dir = pathlib.Path(sys.argv[1])
    summary_path = out_dir / "summary.json"
    if not summary_path.exists():
        print(f"make_report: {summary_path} not found; run liquid-verify suite first", file=sys.stderr)
        return 2
    summary = json.loads(summary_path.read_text())
    lines = [f"# Verification report ({summary['suite']} suite)", ""]
    lines += ["| case | result | seconds | order | order_grad | the paper |",
              "| --- | --- | ---: | ---: | ---: | --- |"]
    sections = []
    for item in summary["cases"]:
        name = item["case"]
        record = json.loads((out_dir / f"{name}.json").read_text())
        result = "passed" if record["passed"] else "**FAILED**"
        lines.append(f"| [{name}](#{name}) | {result} | {record['seconds']:.2f} | "
                     f"{fmt(record.get('order'))} | {fmt(record.get('order_grad'))} | {PAPER.get(name, '-')} |")
        body = (out_dir / f"{name}.md").read_text()
        plots = plot_series(name, record.get("series", []), out_dir)
        body += "".join(f"\n![{name} plot {i}]({p})\n" for i, p in enumerate(plots))
        sections.append(f'<a id="{name}"></a>\n\n' + body)
    lines.append("")
    scenes = scene_section(out_dir)
    table1 = out_dir / "table1" / "table1.md"
    if table1.exists():
        # Its pictures lie beside it, in table1/.
        scenes += "\n" + table1.read_text().replace("](table1-", "](table1/table1-")
    scenes += "\n" + sph_scene_section(out_dir)
    table1_sph = out_dir / "table1-sph" / "table1-sph.md"
    if table1_sph.exists():
        scenes += "\n" + table1_sph.read_text()
    report = "\n".join(lines) + "\n" + "\n".join(sections) + "\n" + scenes
    (out_dir / "README.md").write_text(report)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Draws one 2D frame of `liquid run`: the tree's leaf cells (air white, fluid blue, solid grey,
outlined) and the particles coloured by speed.

Usage: frame_picture.py CELLS.h5 PARTICLES.h5 OUT.png [TITLE]

Reads the files liquid run writes (NAME_cells_FFFFFF.h5: /geometry, /fields/type; and
NAME_particles_FFFFFF.h5: /geometry, /fields/speed) with h5py (Debian's python3-h5py).
"""

import sys


def main():
    if len(sys.argv) not in (4, 5):
        print(__doc__, file=sys.stderr)
        return 2
    try:
        import h5py
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import PolyCollection
    except ImportError as e:
        print(f"frame_picture: {e} (ci/setup installs python3-h5py and python3-matplotlib)", file=sys.stderr)
        return 2
    cells_path, particles_path, out = sys.argv[1:4]
    title = sys.argv[4] if len(sys.argv) == 5 else ""
    with h5py.File(cells_path, "r") as f:
        corners = f["geometry"][()]
        if corners.shape[1] != 2:
            print(f"frame_picture: {cells_path} is not a 2D frame", file=sys.stderr)
            return 2
        kind = f["fields/type"][()] if "fields/type" in f else None
    with h5py.File(particles_path, "r") as f:
        x = f["geometry"][()]
        speed = f["fields/speed"][()] if "fields/speed" in f else None
    quads = corners.reshape(-1, 4, 2)
    colours = {0: "white", 1: "#d8e8f8", 2: "#9a9a9a"}
    faces = [colours.get(int(k), "white") for k in kind] if kind is not None else "white"
    fig, ax = plt.subplots(figsize=(6.0, 6.0))
    ax.add_collection(PolyCollection(quads, facecolors=faces, edgecolors="#606060", linewidths=0.25))
    if len(x):
        points = ax.scatter(x[:, 0], x[:, 1], c=speed, s=1.5, cmap="viridis", linewidths=0)
        fig.colorbar(points, ax=ax, shrink=0.7, label="particle speed (m/s)")
    ax.set_xlim(corners[:, 0].min(), corners[:, 0].max())
    ax.set_ylim(corners[:, 1].min(), corners[:, 1].max())
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())

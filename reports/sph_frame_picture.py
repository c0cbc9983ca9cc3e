#!/usr/bin/python3
"""Draws one 2D frame of an SPH `liquid run`: the particles as discs of their spacing, coloured by
level, and the surface mesh (segments) over them.

Usage: sph_frame_picture.py PARTICLES.h5 SURFACE.h5 OUT.png [TITLE]

Reads the files liquid run writes for SPH scenes (NAME_particles_FFFFFF.h5: /geometry,
/fields/level, /fields/radius; NAME_surface_FFFFFF.h5: /geometry, /topology) with h5py.
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
        from matplotlib.collections import LineCollection
    except ImportError as e:
        print(f"sph_frame_picture: {e} (ci/setup installs python3-h5py and python3-matplotlib)", file=sys.stderr)
        return 2
    particles_path, surface_path, out = sys.argv[1:4]
    title = sys.argv[4] if len(sys.argv) == 5 else ""
    with h5py.File(particles_path, "r") as f:
        x = f["geometry"][:]
        level = f["fields/level"][:] if "fields/level" in f else None
    with h5py.File(surface_path, "r") as f:
        vertices = f["geometry"][:]
        segments = f["topology"][:]
    if x.shape[1] != 2:
        print("sph_frame_picture: draws 2D frames only", file=sys.stderr)
        return 2
    fig, ax = plt.subplots(figsize=(6, 6))
    scatter = ax.scatter(x[:, 0], x[:, 1], c=level, s=3, cmap="viridis", vmin=0, vmax=max(3, level.max()) if level is not None else None)
    if level is not None:
        fig.colorbar(scatter, ax=ax, label="level", shrink=0.8)
    ax.add_collection(LineCollection(vertices[segments], colors="crimson", linewidths=0.8))
    ax.set_aspect("equal")
    ax.autoscale()
    ax.set_title(title, fontsize=9)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Renders a plyshell garment VTU (quads coloured by panel and ply, seams as red lines) to a PNG.

Usage: render_garment.py GARMENT.vtu OUT.png [TITLE [ELEV AZIM]]   (needs meshio and matplotlib;
view angles in degrees, default 20 -60)
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import meshio
import numpy as np
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection


def main():
    src, out = sys.argv[1], sys.argv[2]
    title = sys.argv[3] if len(sys.argv) > 3 else src
    elev, azim = (float(sys.argv[4]), float(sys.argv[5])) if len(sys.argv) > 5 else (20.0, -60.0)
    m = meshio.read(src)
    pts = m.points
    fig = plt.figure(figsize=(7, 7))
    ax = fig.add_subplot(111, projection="3d")
    cmap = plt.get_cmap("tab10")
    for block, cells in enumerate(m.cells):
        if cells.type == "quad":
            panel = m.cell_data["panel"][block]
            ply = m.cell_data["ply"][block]
            colours = [cmap((3 * max(p, 0) + max(k, 0)) % 10) for p, k in zip(panel, ply)]
            poly = Poly3DCollection(pts[cells.data], facecolors=colours, edgecolors="k", linewidths=0.1, alpha=0.55)
            ax.add_collection3d(poly)
        elif cells.type == "line":
            ax.add_collection3d(Line3DCollection(pts[cells.data], colors="red", linewidths=2.0))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_title(title)
    ax.view_init(elev=elev, azim=azim)
    fig.savefig(out, dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    main()

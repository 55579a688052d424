#!/usr/bin/env python3
"""Compares two `plyshell solve` runs of the same garment (same mesh, e.g. two element
formulations) at given simulated times: drape difference and seam forces.

Usage: compare_garment_runs.py DIR_A DIR_B NAME [TIME ...]   (needs meshio and numpy)

NAME is the scene name (files NAME_garment.pvd, NAME_garment_NNNN.vtu). Without TIMEs the last
states are compared. The pvd time stamp of step k (from 0) at simulated time t is k + t·1e-9,
and a Dynamic step's time starts at 0, so a TIME is found as the frame of nearest absolute
simulated time (the step durations before it added; pass them with --offsets a,b,... when
the scene's steps are not 0.04 s sewing followed by settling, as in garments/nbc_hood.ron).
Prints per time: the two frame times, the garment size (bounding-box diagonal), RMS and
largest displacement of each run, the largest and RMS distance between the two deformed
meshes (also relative to the size and to the RMS displacement), and per seam row (order of
`seam` cell ids: seam by seam, ply by ply) the mean and largest |seam_force_per_length|.
"""
import re
import sys

import meshio
import numpy as np


def frames(d, name, offsets):
    text = open(f"{d}/{name}_garment.pvd").read()
    out = []
    for stamp, f in re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', text):
        stamp = float(stamp)
        step = int(round(stamp)) if stamp > 0.5 else 0
        out.append(((stamp - step) * 1e9 + sum(offsets[:step]), f"{d}/{f}"))
    return out


def seam_forces(mesh):
    res = {}
    for block, sid, force in zip(mesh.cells, mesh.cell_data["seam"], mesh.cell_data["seam_force_per_length"]):
        if block.type != "line":
            continue
        for s in np.unique(sid):
            res[int(s)] = np.linalg.norm(force[sid == s], axis=1)
    return res


def rms(v):
    return float(np.sqrt((v**2).mean()))


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--offsets")]
    offsets = [0.04]
    for a in sys.argv[1:]:
        if a.startswith("--offsets"):
            offsets = [float(x) for x in a.split("=", 1)[1].split(",")]
    a, b, name = args[:3]
    times = [float(t) for t in args[3:]] or [None]
    fa, fb = frames(a, name, offsets), frames(b, name, offsets)
    for target in times:
        pick = (lambda fs: fs[-1]) if target is None else (lambda fs: min(fs, key=lambda x: abs(x[0] - target)))
        (ta, pa), (tb, pb) = pick(fa), pick(fb)
        ma, mb = meshio.read(pa), meshio.read(pb)
        d = np.linalg.norm(ma.points - mb.points, axis=1)
        size = np.linalg.norm(ma.points.max(0) - ma.points.min(0))
        ua = np.linalg.norm(ma.point_data["displacement"], axis=1)
        ub = np.linalg.norm(mb.point_data["displacement"], axis=1)
        when = "last frames" if target is None else f"t {ta:.4f} / {tb:.4f} s"
        print(
            f"{when}; size {size:.3f} m; |u| rms {rms(ua):.4f} / {rms(ub):.4f} m, max {ua.max():.4f} / {ub.max():.4f} m; "
            f"difference max {d.max():.4f} m ({d.max() / size:.2%} of size), rms {rms(d):.4f} m ({rms(d) / size:.2%} of size, {rms(d) / rms(ua):.1%} of rms |u|)"
        )
        sa, sb = seam_forces(ma), seam_forces(mb)
        for s in sorted(sa):
            x, y = sa[s], sb[s]
            print(f"  seam row {s}: mean {x.mean():.3f} -> {y.mean():.3f} N/m ({(y.mean() - x.mean()) / x.mean():+.1%}), max {x.max():.3f} -> {y.max():.3f} N/m ({(y.max() - x.max()) / x.max():+.1%})")


if __name__ == "__main__":
    main()

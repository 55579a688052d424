"""Writes torso.obj: a closed, outward-oriented torso-like triangle mesh made from
primitives (elliptic cylinder chest, quarter-ellipse shoulders, round neck, flat caps).
Units m; the shoulders' top is at z = 0.53, the base at z = 0. Run: python3 make_torso.py"""
import math

NU = 48
rings = []  # (z, a, b)
for k in range(10):
    z = 0.45 * k / 9
    rings.append((z, 0.16, 0.10))
for k in range(1, 9):  # shoulders: quarter ellipse from (0.16, 0.10) at z 0.45 to the neck at z 0.53
    t = k / 8 * math.pi / 2
    s = math.cos(t)
    rings.append((0.45 + 0.08 * math.sin(t), 0.05 + 0.11 * s, 0.05 + 0.05 * s))
rings.append((0.62, 0.05, 0.05))
v = []
for z, a, b in rings:
    for j in range(NU):
        p = 2 * math.pi * j / NU
        v.append((a * math.cos(p), b * math.sin(p), z))
bottom = len(v)
v.append((0.0, 0.0, 0.0))
top = len(v)
v.append((0.0, 0.0, rings[-1][0]))
f = []
idx = lambda i, j: i * NU + (j % NU)
for i in range(len(rings) - 1):
    for j in range(NU):
        f.append((idx(i, j), idx(i, j + 1), idx(i + 1, j + 1)))
        f.append((idx(i, j), idx(i + 1, j + 1), idx(i + 1, j)))
last = len(rings) - 1
for j in range(NU):
    f.append((bottom, idx(0, j + 1), idx(0, j)))
    f.append((top, idx(last, j), idx(last, j + 1)))
with open("torso.obj", "w") as out:
    out.write("# torso-like closed triangle mesh from primitives (make_torso.py)\n")
    for p in v:
        out.write("v %.6f %.6f %.6f\n" % p)
    for t in f:
        out.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))

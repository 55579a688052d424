#!/usr/bin/env python3
"""Renders a garment on its body to a PNG with the standard library only: the body OBJ
(from `plyshell body`, outward triangles) in grey and the garment — an OBJ
(`*_garment.obj` from `plyshell solve`/`demo`) or a shell VTU of `plyshell solve` (binary,
uncompressed; current positions) — double-sided in colour, front (from +y), right side
(from +x) and oblique orthographic views, z up, Lambert shading with a z-buffer.

Usage: render_on_body.py BODY.obj GARMENT.{obj,vtu} OUT.png [PIXELS_PER_VIEW]
"""
import base64
import math
import re
import struct
import sys
import zlib


def read_obj(path, tag):
    verts, tris = [], []
    for line in open(path):
        if line.startswith("v "):
            verts.append(tuple(float(x) for x in line.split()[1:4]))
        elif line.startswith("f "):
            idx = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
            for k in range(1, len(idx) - 1):
                tris.append((idx[0], idx[k], idx[k + 1], tag))
    return verts, tris


def read_vtu(path, tag):
    """Points and quad/triangle cells of a binary VTU (UInt64 headers, no compression)."""
    text = open(path).read()

    def array(name):
        m = re.search(r'<DataArray type="(\w+)"[^>]*Name="%s"[^>]*>\s*([^<]*)<' % name, text)
        if m is None:
            m = re.search(r'<Points>\s*<DataArray type="(\w+)"[^>]*>\s*([^<]*)<', text) if name == "Points" else None
        kind, data = m.group(1), base64.b64decode(m.group(2).strip())
        n = struct.unpack("<Q", data[:8])[0]
        fmt = {"Float64": "d", "Int64": "q", "UInt8": "B", "Int32": "i"}[kind]
        return struct.unpack("<%d%s" % (n // struct.calcsize(fmt), fmt), data[8:8 + n])

    pts = array("Points")
    verts = [tuple(pts[3 * i:3 * i + 3]) for i in range(len(pts) // 3)]
    conn, offs = array("connectivity"), array("offsets")
    tris, start = [], 0
    for end in offs:
        idx = conn[start:end]
        for k in range(1, len(idx) - 1):
            tris.append((idx[0], idx[k], idx[k + 1], tag))
        start = end
    return verts, tris


def render(verts, tris, size, azim_deg, box):
    a = math.radians(azim_deg)
    d = (-math.sin(a), -math.cos(a), 0.0)
    r = (d[1], -d[0], 0.0)
    xs = [v[0] * r[0] + v[1] * r[1] for v in verts]
    zs = [v[2] for v in verts]
    depth = [v[0] * d[0] + v[1] * d[1] for v in verts]
    span, cz = box
    cx = (min(xs) + max(xs)) / 2
    sx = [(x - cx) / span * size + size / 2 for x in xs]
    sy = [size / 2 - (z - cz) / span * size for z in zs]
    img = [[(255, 255, 255)] * size for _ in range(size)]
    zbuf = [[math.inf] * size for _ in range(size)]
    light = (-0.4 * d[0] + 0.3, -0.4 * d[1] + 0.2, 0.8)
    ln = math.sqrt(sum(c * c for c in light))
    for i, j, k, tag in tris:
        p, q, s = verts[i], verts[j], verts[k]
        u = [q[m] - p[m] for m in range(3)]
        w = [s[m] - p[m] for m in range(3)]
        n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        nn = math.sqrt(sum(c * c for c in n)) or 1.0
        facing = sum(n[m] * d[m] for m in range(3))
        if tag == "body" and facing >= 0:
            continue
        if facing > 0:
            n = (-n[0], -n[1], -n[2])
        shade = 0.35 + 0.65 * max(0.0, sum(n[m] * light[m] for m in range(3)) / nn / ln)
        base = (200, 200, 200) if tag == "body" else (70, 110, 60)
        colour = tuple(int(c * shade) for c in base)
        ax, ay, bx, by, qx, qy = sx[i], sy[i], sx[j], sy[j], sx[k], sy[k]
        area = (bx - ax) * (qy - ay) - (qx - ax) * (by - ay)
        if area == 0:
            continue
        for py in range(max(0, int(min(ay, by, qy))), min(size, int(max(ay, by, qy)) + 1)):
            for px in range(max(0, int(min(ax, bx, qx))), min(size, int(max(ax, bx, qx)) + 1)):
                x, y = px + 0.5, py + 0.5
                l1 = ((bx - x) * (qy - y) - (qx - x) * (by - y)) / area
                l2 = ((qx - x) * (ay - y) - (ax - x) * (qy - y)) / area
                l3 = 1 - l1 - l2
                if l1 < 0 or l2 < 0 or l3 < 0:
                    continue
                z = l1 * depth[i] + l2 * depth[j] + l3 * depth[k]
                if tag == "garment":
                    z -= 1e-3  # the garment wins a tie with the body under it
                if z < zbuf[py][px]:
                    zbuf[py][px] = z
                    img[py][px] = colour
    return img


def write_png(path, rows):
    h, w = len(rows), len(rows[0])
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rows)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    open(path, "wb").write(png)


def main():
    body, garment, out = sys.argv[1], sys.argv[2], sys.argv[3]
    size = int(sys.argv[4]) if len(sys.argv) > 4 else 300
    vb, tb = read_obj(body, "body")
    vg, tg = read_vtu(garment, "garment") if garment.endswith(".vtu") else read_obj(garment, "garment")
    off = len(vb)
    verts = vb + vg
    tris = tb + [(i + off, j + off, k + off, t) for i, j, k, t in tg]
    zs = [v[2] for v in verts]
    rad = max(math.hypot(v[0], v[1]) for v in verts)
    box = (max(2 * rad, max(zs) - min(zs)) * 1.05, (min(zs) + max(zs)) / 2)
    views = [render(verts, tris, size, a, box) for a in (0.0, 90.0, 35.0)]
    rows = [sum((v[y] for v in views), []) for y in range(size)]
    write_png(out, rows)


if __name__ == "__main__":
    main()

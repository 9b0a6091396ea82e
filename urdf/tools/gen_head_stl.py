#!/usr/bin/env python3
"""Generates urdf/meshes/head.stl for drape_bot: a closed ellipsoid (outward winding),
binary STL, semi-axes 0.09 x 0.08 x 0.11 m, centred at the origin. Standard library only.

Usage: python3 urdf/tools/gen_head_stl.py [output.stl]
"""
import math
import struct
import sys
from pathlib import Path

A, B, C = 0.09, 0.08, 0.11  # semi-axes (m): x forward, y left, z up
N_LON, N_LAT = 32, 16


def point(i_lat, i_lon):
    theta = math.pi * i_lat / N_LAT  # 0 at the top pole
    phi = 2.0 * math.pi * (i_lon % N_LON) / N_LON
    return (A * math.sin(theta) * math.cos(phi), B * math.sin(theta) * math.sin(phi), C * math.cos(theta))


def triangles():
    for i in range(N_LAT):
        for j in range(N_LON):
            p00, p01 = point(i, j), point(i, j + 1)
            p10, p11 = point(i + 1, j), point(i + 1, j + 1)
            if i != 0:  # skip degenerate triangles at the top pole
                yield (p00, p10, p01)
            if i != N_LAT - 1:  # and at the bottom pole
                yield (p01, p10, p11)


def normal(a, b, c):
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return tuple(x / length for x in n)


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "meshes" / "head.stl"
    tris = list(triangles())
    with open(out, "wb") as f:
        f.write(b"drape_bot head: ellipsoid 0.09 x 0.08 x 0.11 m".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for a, b, c in tris:
            f.write(struct.pack("<3f", *normal(a, b, c)))
            for p in (a, b, c):
                f.write(struct.pack("<3f", *p))
            f.write(struct.pack("<H", 0))
    print(f"wrote {out} ({len(tris)} triangles)")


if __name__ == "__main__":
    main()

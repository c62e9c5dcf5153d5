#!/usr/bin/env python3
"""Writes examples/ogive_projectile.stl: a tangent-ogive-nosed cylinder, closed, binary STL (mm).

Calibre 5 mm (R = 2.5 mm), calibre-radius-head 3 (ogive radius rho = 15 mm), so the nose is
L_n = sqrt(rho^2 - (rho - R)^2) = 8.29 mm long; a 11.71 mm cylinder behind it (20 mm in all)
and a flat base. The tip is at the origin and the body lies along +z, so the projectile points
down -z. Profile of the nose at height z (0 <= z <= L_n): r(z) = sqrt(rho^2 - (L_n - z)^2) + R - rho.

Run from the repository's root: python3 examples/ogive_projectile.py
"""
import math
import struct

R, CRH, LENGTH = 2.5, 3.0, 20.0
SEGMENTS, NOSE_STATIONS, BODY_STATIONS = 64, 48, 12

rho = CRH * 2.0 * R
nose = math.sqrt(rho**2 - (rho - R) ** 2)


def radius(z):
    if z >= nose:
        return R
    return max(math.sqrt(rho**2 - (nose - z) ** 2) + R - rho, 0.0)


# Stations from the tip (a point) to the base, denser towards the tip where the nose curves most.
zs = [nose * (1.0 - math.cos(0.5 * math.pi * k / NOSE_STATIONS)) for k in range(NOSE_STATIONS + 1)]
zs += [nose + (LENGTH - nose) * k / BODY_STATIONS for k in range(1, BODY_STATIONS + 1)]


def ring(z):
    r = radius(z)
    return [(r * math.cos(2 * math.pi * j / SEGMENTS), r * math.sin(2 * math.pi * j / SEGMENTS), z)
            for j in range(SEGMENTS)]


tris = []
tip = (0.0, 0.0, 0.0)
rings = [ring(z) for z in zs[1:]]
for j in range(SEGMENTS):  # the tip's cone, outward (seen from below: clockwise)
    a, b = rings[0][j], rings[0][(j + 1) % SEGMENTS]
    tris.append((tip, b, a))
for lower, upper in zip(rings, rings[1:]):
    for j in range(SEGMENTS):
        a, b = lower[j], lower[(j + 1) % SEGMENTS]
        c, d = upper[(j + 1) % SEGMENTS], upper[j]
        tris.append((a, b, c))
        tris.append((a, c, d))
base = (0.0, 0.0, LENGTH)
for j in range(SEGMENTS):  # the flat base, outward (+z)
    a, b = rings[-1][j], rings[-1][(j + 1) % SEGMENTS]
    tris.append((base, a, b))

with open("examples/ogive_projectile.stl", "wb") as f:
    f.write(b"strike example: tangent ogive projectile, calibre 5 mm, CRH 3, 20 mm, units mm".ljust(80, b" "))
    f.write(struct.pack("<I", len(tris)))
    for t in tris:
        f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
        for v in t:
            f.write(struct.pack("<3f", *v))
        f.write(b"\0\0")
print(f"{len(tris)} triangles, nose {nose:.3f} mm")

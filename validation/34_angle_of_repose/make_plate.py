#!/usr/bin/env python3
"""Writes plate_r20.stl (millimetres): a flat regular 16-gon at z = 0 whose inscribed circle has a
radius of 20 mm, with a rim of height 1.4 mm (half a particle diameter) along its edge.

Every triangle faces the particles: the plate upwards (+z), the rim inwards. A grain that passes
over the rim is behind it and falls off (kiln's mesh walls are one-sided). The plate is cut into a
strip of long triangles (not a fan about the centre) so that a grain near the axis meets two or
three triangles, not sixteen: the polyhedron-mesh contact tests every triangle under a grain.
Run: python3 make_plate.py"""
import math

INSCRIBED = 20.0  # mm
SIDES = 16
RIM = 1.4  # mm


def facet(out, a, b, c):
    ux, uy, uz = (b[i] - a[i] for i in range(3))
    vx, vy, vz = (c[i] - a[i] for i in range(3))
    n = (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
    norm = math.sqrt(sum(x * x for x in n))
    out.append("  facet normal {:.6e} {:.6e} {:.6e}\n".format(*(x / norm for x in n)))
    out.append("    outer loop\n")
    for p in (a, b, c):
        out.append("      vertex {:.6f} {:.6f} {:.6f}\n".format(*p))
    out.append("    endloop\n  endfacet\n")


def up(out, a, b, c):
    """Triangle a, b, c of the plate, oriented so that its normal is +z."""
    cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    if cross > 0:
        facet(out, a, b, c)
    else:
        facet(out, a, c, b)


def main():
    circum = INSCRIBED / math.cos(math.pi / SIDES)
    # vertices with edge midpoints on the axes' neighbours: vertex k at angle (k + 1/2) 2 pi / SIDES
    ring = [(circum * math.cos(2 * math.pi * (k + 0.5) / SIDES),
             circum * math.sin(2 * math.pi * (k + 0.5) / SIDES), 0.0) for k in range(SIDES)]
    out = ["solid plate_r20\n"]
    # strip: walk inwards from both ends of the polygon, 0, 1, ..., and SIDES-1, SIDES-2, ...
    lo, hi = 0, SIDES - 1
    while hi - lo >= 2:
        up(out, ring[lo], ring[lo + 1], ring[hi])
        if hi - 1 > lo + 1:
            up(out, ring[lo + 1], ring[hi - 1], ring[hi])
        lo, hi = lo + 1, hi - 1
    for k in range(SIDES):
        x0, y0, _ = ring[k]
        x1, y1, _ = ring[(k + 1) % SIDES]
        # rim quad, normal towards the axis (counter-clockwise ring)
        facet(out, (x0, y0, 0.0), (x0, y0, RIM), (x1, y1, 0.0))
        facet(out, (x1, y1, 0.0), (x0, y0, RIM), (x1, y1, RIM))
    out.append("endsolid plate_r20\n")
    with open("plate_r20.stl", "w") as f:
        f.writelines(out)


if __name__ == "__main__":
    main()

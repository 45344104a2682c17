#!/usr/bin/env python3
"""Writes the polyhedron meshes shipped in shapes/ (.obj, millimetres; the .toml files scale them
by 1e-3). Faces are the planar facets of the convex vertex set, found by brute force and ordered
counter-clockwise seen from outside. Run from anywhere: python3 shapes/make_polyhedra.py"""

import itertools
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def box(a, b, c):
    return [(sx * a / 2, sy * b / 2, sz * c / 2) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]


def pyramid(a, h):
    # square base a x a at z = 0, apex at height h (Oschmann 2019, Inv. IV: a = b = h = 3.26 mm)
    return [(-a / 2, -a / 2, 0.0), (a / 2, -a / 2, 0.0), (a / 2, a / 2, 0.0), (-a / 2, a / 2, 0.0),
            (0.0, 0.0, h)]


def icosahedron(edge):
    p = (1 + math.sqrt(5)) / 2
    s = edge / 2  # the golden rectangles (0, +-1, +-p) have edge 2
    pts = []
    for u in (-1, 1):
        for w in (-1, 1):
            pts += [(0.0, u * s, w * p * s), (u * s, w * p * s, 0.0), (w * p * s, 0.0, u * s)]
    return pts


def prism(n, radius, length):
    # regular n-gon inscribed in the circle of `radius` (vertices on the cylinder), axis z
    return [(radius * math.cos(2 * math.pi * k / n), radius * math.sin(2 * math.pi * k / n), z)
            for z in (-length / 2, length / 2) for k in range(n)]


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def facets(pts):
    scale = max(abs(c) for p in pts for c in p)
    tol = 1e-9 * scale
    found = {}
    for i, j, k in itertools.combinations(range(len(pts)), 3):
        n = cross(sub(pts[j], pts[i]), sub(pts[k], pts[i]))
        norm = math.sqrt(dot(n, n))
        if norm < tol * scale:
            continue
        n = tuple(x / norm for x in n)
        d = [dot(n, sub(p, pts[i])) for p in pts]
        if all(x <= tol for x in d):
            pass
        elif all(x >= -tol for x in d):
            n = tuple(-x for x in n)
        else:
            continue
        on = tuple(sorted(m for m, x in enumerate(d) if abs(x) <= tol))
        found.setdefault(on, n)
    faces = []
    for on, n in found.items():
        c = tuple(sum(pts[m][q] for m in on) / len(on) for q in range(3))
        e1 = sub(pts[on[0]], c)
        e1 = tuple(x / math.sqrt(dot(e1, e1)) for x in e1)
        e2 = cross(n, e1)
        faces.append(sorted(on, key=lambda m: math.atan2(dot(sub(pts[m], c), e2),
                                                         dot(sub(pts[m], c), e1))))
    return sorted(faces)


def write(name, pts, what):
    with open(os.path.join(HERE, name + ".obj"), "w") as f:
        f.write(f"# {what}\n# millimetres; written by shapes/make_polyhedra.py\n")
        for p in pts:
            f.write("v {:.12g} {:.12g} {:.12g}\n".format(*(0.0 if abs(x) < 1e-15 else x for x in p)))
        for face in facets(pts):
            f.write("f " + " ".join(str(m + 1) for m in face) + "\n")


write("cube", box(2.26, 2.26, 2.26), "cube, edge 2.26 mm (Oschmann 2019, Inv. IV)")
write("cuboid_6x6x5", box(6.0, 6.0, 5.0), "cuboid 6 x 6 x 5 mm (Oschmann 2019, Inv. II)")
write("plate_10x9x2", box(10.0, 9.0, 2.0), "plate 10 x 9 x 2 mm (Oschmann 2019, Inv. II)")
write("plate_inv4", box(3.39, 3.39, 1.0), "plate 3.39 x 3.39 x 1 mm (Oschmann 2019, Inv. IV)")
write("pyramid", pyramid(3.26, 3.26), "square pyramid, base 3.26 mm, height 3.26 mm (Inv. IV)")
write("icosahedron", icosahedron(1.74), "regular icosahedron, edge 1.74 mm (Inv. IV)")
write("cylinder_8", prism(8, 3.0, 6.0), "8-gon prism inscribed in the 6 x 6 mm cylinder (Inv. II)")
write("cylinder_16", prism(16, 3.0, 6.0), "16-gon prism inscribed in the 6 x 6 mm cylinder (Inv. II)")

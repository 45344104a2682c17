#!/usr/bin/python3
"""Plots the grid convergence of the heat validation cases 20 and 21 from the convergence.csv files
the checks write into the build folder. Usage: validation/plot_heat_convergence.py [build-dir]
Writes validation/heat_convergence.png (matplotlib, Agg backend)."""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "build")


def read(case):
    rows = {}
    with open(os.path.join(build, "validation", case, "convergence.csv")) as f:
        for r in csv.DictReader(f):
            rows.setdefault(r["series"], []).append(
                (float(r["size"]), float(r["centre_error"]), float(r["mean_error"])))
    return rows


fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
ax = axes[0]
for name, rows in read("20_sphere_convection").items():
    h = [r[0] for r in rows]
    ax.loglog(h, [r[1] for r in rows], "o-", label=f"{name}: centre")
    ax.loglog(h, [r[2] for r in rows], "s--", label=f"{name}: mean")
h = [0.025, 0.25]
ax.loglog(h, [0.2 * x * x for x in h], "k:", label="slope 2")
ax.loglog(h, [0.03 * x for x in h], "k-.", label="slope 1")
ax.set_xlabel("cell size / R")
ax.set_ylabel("max |theta - series|")
ax.set_title("20: sphere, Bi = 1")
ax.legend(fontsize=7)
ax = axes[1]
for name, rows in read("21_body_convection").items():
    ax.loglog([r[0] for r in rows], [r[1] for r in rows], "o-", label=name)
h = [1 / 32, 1 / 8]
ax.loglog(h, [0.4 * x * x for x in h], "k:", label="slope 2")
ax.set_xlabel("cell size / body extent")
ax.set_ylabel("max |theta - reference|")
ax.set_title("21: cube (exact), superquadric (32 across)")
ax.legend(fontsize=7)
fig.tight_layout()
out = os.path.join(here, "heat_convergence.png")
fig.savefig(out, dpi=120)
print("wrote", out)

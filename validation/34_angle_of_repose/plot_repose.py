#!/usr/bin/python3
"""Plots validation 34: the surface profiles of the cube and sphere heaps (highest grain centre per
sector and radial bin, all 8 sectors folded onto r) with the lines fitted between 20 % and 80 % of
the plate radius. Reads build/validation/34_angle_of_repose/profile_{cubes,spheres}.csv and
results.csv (written by check.cpp).
Usage: validation/34_angle_of_repose/plot_repose.py [build-dir]; writes repose.png here."""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "build")
results = os.path.join(build, "validation", "34_angle_of_repose")

angle = {}
with open(os.path.join(results, "results.csv")) as f:
    for row in csv.DictReader(f):
        if row["quantity"].endswith(": angle of repose"):
            angle[row["quantity"].split(":")[0]] = float(row["measured"])

fig, ax = plt.subplots(figsize=(7, 4))
for name, colour in (("cubes", "C3"), ("spheres", "C0")):
    with open(os.path.join(results, "profile_" + name + ".csv")) as f:
        head = f.readline()  # "# fit: z = a + b r (m), window lo - hi of r_plate = R"
        words = head.split()
        a, b = float(words[4]), float(words[6])
        lo, hi, plate = float(words[10]), float(words[12]), float(words[-1])
        rows = list(csv.DictReader(f))
    r = [1e3 * float(q["r"]) for q in rows]
    z = [1e3 * float(q["z"]) for q in rows]
    ax.plot(r, z, ".", color=colour, alpha=0.5, ms=4,
            label="{}: surface grains (not covered)".format(name))
    r0, r1 = lo * plate, hi * plate
    ax.plot([1e3 * r0, 1e3 * r1], [1e3 * (a + b * r0), 1e3 * (a + b * r1)], "-", color=colour,
            lw=2, label="{}: fit, {:.1f} deg".format(name, angle[name]))
ax.axvspan(1e3 * lo * plate, 1e3 * hi * plate, color="gray", alpha=0.08)
ax.axvline(1e3 * plate, color="k", lw=0.8, ls=":")
ax.text(1e3 * plate, 0.5, " rim", fontsize=8)
ax.set_xlabel("distance from the axis r (mm)")
ax.set_ylabel("height of the grain centre z (mm)")
ax.set_title("Angle of repose: cubes vs volume-equivalent spheres, mu = 0.5, no rolling resistance",
             fontsize=9)
ax.set_aspect("equal")
ax.grid(alpha=0.3)
ax.legend(fontsize=7, loc="upper right")
fig.tight_layout()
fig.savefig(os.path.join(here, "repose.png"), dpi=130)
print("wrote", os.path.join(here, "repose.png"))

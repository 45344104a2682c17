#!/usr/bin/python3
"""Plots validation 15: solid fraction of poured packings by shape against the published values.
Reads build/validation/15_packing/results.csv (written by check.cpp).
Usage: validation/15_packing/plot_packing.py [build-dir]; writes validation/15_packing/packing.png."""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "build")
phi = {}
m4_seeds = []  # solid fractions of the m = 4 pours, one per seed
spheroid_seeds = {"sphere": [], "prolate_15": [], "prolate_20": []}  # the same for the spheroid test
with open(os.path.join(build, "validation", "15_packing", "results.csv")) as f:
    for row in csv.DictReader(f):
        q = row["quantity"]
        if q.startswith("superball m = 4 seed") and q.endswith("solid fraction"):
            m4_seeds.append(float(row["measured"]))
        elif " seed " in q and q.endswith("solid fraction") and q.split(" seed ")[0] in spheroid_seeds:
            spheroid_seeds[q.split(" seed ")[0]].append(float(row["measured"]))
        elif q.endswith("solid fraction") and "seed" not in q:
            phi[q.split(": ")[0]] = float(row["measured"])
        elif q.startswith("superball m = 4: mean solid fraction"):
            phi["superball m = 4"] = float(row["measured"])

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6), sharey=True)
# Spheroids: aspect ratio. Donev et al. 2004 (Fig. 2, read from the figure, +-0.01).
ax1.plot([1.0, 1.5, 2.0], [0.64, 0.70, 0.69], "s--", color="gray",
         label="Donev et al. 2004 (MRJ, frictionless)")
ax1.plot([1.0, 1.5, 2.0], [phi["spheres"], phi["spheroid 1.5:1"], phi["spheroid 2:1"]], "o-",
         color="C0", label="kiln, poured (this case): means of the seeds")
for x, shape in ((1.0, "sphere"), (1.5, "prolate_15"), (2.0, "prolate_20")):
    ax1.plot([x] * len(spheroid_seeds[shape]), spheroid_seeds[shape], ".", color="C0", alpha=0.5,
             label="kiln, one pour per seed" if shape == "sphere" else None)
ax1.set_xlabel("aspect ratio of prolate spheroids")
ax1.set_ylabel("solid fraction")
ax1.legend(fontsize=8)
# Superballs: m = 2/e. Delaney & Cleary 2010: 0.64 at m = 2, about 0.82 at m = 5 (text).
ax2.plot([2.0, 5.0], [0.64, 0.82], "s--", color="gray",
         label="Delaney & Cleary 2010 (m = 2 and 5)")
ax2.plot([2.0, 3.0, 4.0], [phi["spheres"], phi["superball m = 3"], phi["superball m = 4"]], "o-",
         color="C1", label="kiln, poured (this case)")
if m4_seeds:
    ax2.plot([4.0] * len(m4_seeds), m4_seeds, ".", color="C1", alpha=0.5,
             label=f"kiln, m = 4: {len(m4_seeds)} seeds (mean joined)")
ax2.set_xlabel("superball blockiness m = 2/e")
ax2.legend(fontsize=8)
for ax in (ax1, ax2):
    ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(here, "packing.png"), dpi=120)

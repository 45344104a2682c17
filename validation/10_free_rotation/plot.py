#!/usr/bin/python3
"""Plots the body angular velocity of validation 10 (free rotation of a 1:2:3 ellipsoid).

Usage: /usr/bin/python3 validation/10_free_rotation/plot.py [build/validation/10_free_rotation]
Reads omega_axis{x,y,z}.csv written by the check and writes free_rotation.png next to this script.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
data = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "../../build/validation/10_free_rotation")
titles = {"x": "spin about x (largest I): stable", "y": "spin about y (intermediate I): flips",
          "z": "spin about z (smallest I): stable"}
fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
for ax, axis in zip(axes, "xyz"):
    with open(os.path.join(data, f"omega_axis{axis}.csv")) as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t"]) for r in rows]
    for comp in "xyz":
        ax.plot(t, [float(r["w" + comp]) for r in rows], label=f"omega_{comp} (body)")
    ax.set_title(titles[axis], fontsize=10)
    ax.set_ylabel("rad/s")
    ax.grid(alpha=0.3)
axes[0].legend(loc="upper right", fontsize=8)
axes[-1].set_xlabel("t (s)")
fig.suptitle("Torque-free 1:2:3 ellipsoid, omega = 10 rad/s, perturbation 1e-3, dt = 1 ms")
fig.tight_layout()
fig.savefig(os.path.join(here, "free_rotation.png"), dpi=110)

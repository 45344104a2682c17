#!/usr/bin/env python3
"""Plots restitution.csv (written by check.cpp, copied here) to restitution.png.

Usage: python3 plot.py [restitution.csv] [restitution.png]
"""
import csv
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = Path(__file__).resolve().parent
src = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "restitution.csv"
dst = Path(sys.argv[2]) if len(sys.argv) > 2 else here / "restitution.png"

with open(src, newline="") as f:
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
e = [r["e"] for r in rows]


def clamped(x):
    """e^(1 - (2/pi) asin|beta|): restitution when the contact ends where the force vanishes."""
    lx = math.log(x)
    beta = abs(lx) / math.sqrt(lx * lx + math.pi**2)
    return x ** (1.0 - 2.0 / math.pi * math.asin(beta))


grid = [0.02 + 0.98 * k / 400 for k in range(401)]
fig, (ax, dev) = plt.subplots(1, 2, figsize=(11, 4.6))
ax.plot(grid, grid, "k-", lw=1, label="no clamp: exactly e")
ax.plot(grid, [clamped(x) for x in grid], "k--", lw=1, label=r"clamp: $e^{1-(2/\pi)\,\mathrm{asin}|\beta|}$")
series = [
    ("linear_free", "s", "C0", "linear, no clamp"),
    ("hertz_free", "o", "C1", "Hertz-Mindlin, no clamp"),
    ("linear_clamped", "D", "C2", "linear, clamp"),
    ("hertz_clamped_1ms", "^", "C3", "Hertz-Mindlin, clamp, 1 m/s"),
    ("hertz_clamped_10ms", "v", "C4", "Hertz-Mindlin, clamp, 10 m/s"),
]
for key, marker, color, name in series:
    y = [r[key] for r in rows]
    ax.plot(e, y, marker, mfc="none", color=color, label=name)
    ref = [x if "free" in key else clamped(x) for x in e]
    dev.semilogy(e, [max(abs(a - b), 1e-10) for a, b in zip(y, ref)], marker + "-", mfc="none",
                 color=color, lw=0.8, label=name)
ax.set_xlabel("prescribed restitution e")
ax.set_ylabel("measured rebound ratio (separation / approach speed)")
ax.set_title("kiln head-on impact, dt = 2e-8 s")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
dev.axhline(3e-4, color="C0", ls=":", lw=1, label="linear_tolerance")
dev.axhline(1e-4, color="C1", ls=":", lw=1, label="hertz_tolerance")
dev.set_ylim(1e-10, 1e-3)
dev.set_xlabel("prescribed restitution e")
dev.set_ylabel("|measured - reference|")
dev.set_title("deviation from the reference (floor 1e-10)")
dev.legend(fontsize=7)
dev.grid(alpha=0.3, which="both")
fig.tight_layout()
fig.savefig(dst, dpi=120)
print(f"wrote {dst}")

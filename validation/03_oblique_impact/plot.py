#!/usr/bin/env python3
"""Plots oblique.csv (written by check.cpp, copied here) to oblique.png, in the normalised form of
Maw, Barber & Fawcett's charts: contact-point velocity, spin and tangential restitution after impact
versus the normalised impact angle psi1 = 2 v_t / (mu (1 + e_n) v_n), with the rigid-body impulse
solution and the compliant-contact reference (reference/compliant.csv).

Usage: python3 plot.py [oblique.csv] [oblique.png]
"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = Path(__file__).resolve().parent
src = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "oblique.csv"
dst = Path(sys.argv[2]) if len(sys.argv) > 2 else here / "oblique.png"

with open(src, newline="") as f:
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
sweeps = sorted({r["e"] for r in rows})
with open(here / "reference" / "compliant.csv", newline="") as f:
    ref = [{k: float(v) for k, v in r.items()}
           for r in csv.DictReader(line for line in f if not line.startswith("#"))]
for r in ref:  # psi2 = psi1 e_t, the form the chart shows
    r["psi2"] = r["psi1"] * r["e_t"]
    r["et"] = r["e_t"]

grid = [0.05 * k for k in range(1, 421)]
rigid = {
    "psi2": [max(p - 7.0, 0.0) for p in grid],
    "omega_hat": [5.0 if p >= 7.0 else 5.0 * p / 7.0 for p in grid],
    "et": [1.0 - 7.0 / p if p >= 7.0 else 0.0 for p in grid],
}
panels = [
    ("psi2", r"$\psi_2 = 2u'/(\mu(1+e_n)v_n)$", "contact-point tangential velocity after impact"),
    ("omega_hat", r"$\hat\omega = 2R\omega'/(\mu(1+e_n)v_n)$", "spin after impact"),
    ("et", r"$e_t = u'/u$", "tangential restitution of the contact point"),
]
fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
for ax, (key, ylabel, title) in zip(axes, panels):
    ax.plot(grid, rigid[key], "k-", lw=1, label="rigid body (impulse solution)")
    for e, marker, color in zip(sweeps, ["o", "s"], ["C0", "C3"]):
        pts = [r for r in rows if r["e"] == e]
        ax.plot([r["psi1"] for r in pts], [r[key] for r in pts], marker, ms=5, mfc="none",
                color=color, label=f"kiln, e = {e:g} (e_n = {pts[0]['e_n']:.4f})")
        rp = [r for r in ref if r["e"] == e]
        ax.plot([r["psi1"] for r in rp], [r[key] for r in rp], "-", lw=1, color=color,
                label=f"compliant-contact reference, e = {e:g}")
    ax.axvline(7.0, color="grey", ls=":", lw=1)
    ax.set_xlabel(r"normalised impact angle $\psi_1 = 2v_t/(\mu(1+e_n)v_n)$")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
axes[0].legend(fontsize=8)
axes[2].set_ylim(-0.5, 1.1)
fig.suptitle("Sphere on a plane wall, Hertz-Mindlin, mu = 0.3, v_n = 1 m/s, R = 10 mm (validation 03)", fontsize=11)
fig.tight_layout()
fig.savefig(dst, dpi=120)
print(f"wrote {dst}")

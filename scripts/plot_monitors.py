#!/usr/bin/python3
"""Plots every column of a kiln monitors.csv against time into monitors.png next to it, and the
group temperatures (columns mean_temperature:NAME, one per shape) together into temperatures.png.

Usage: scripts/plot_monitors.py OUTPUT_DIR   (uses Debian's python3-matplotlib)
"""
import csv
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = Path(sys.argv[1])
    with open(out / "monitors.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        print(f"{out}/monitors.csv has no rows", file=sys.stderr)
        return 1
    names = [n for n in rows[0] if n not in ("time", "step")]
    t = [float(r["time"]) for r in rows] if "time" in rows[0] else list(range(len(rows)))
    cols = 2
    lines = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(lines, cols, figsize=(10, 2.6 * lines), squeeze=False, sharex=True)
    for ax, name in zip(axes.flat, names):
        y = [float(r[name]) for r in rows]
        ax.plot(t, y, lw=1.2)
        if name.endswith("energy") and min(y) > 0:
            ax.set_yscale("log")
        ax.set_title(name, fontsize=10)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(names):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(out / "monitors.png", dpi=110)
    print(f"  plot: {out / 'monitors.png'}")
    groups = [n for n in names if n.startswith("mean_temperature:")]
    if groups:
        fig, ax = plt.subplots(figsize=(7, 4.2))
        for name in groups:
            y = [float(r[name]) for r in rows]
            ax.plot(t, y, lw=1.5, label=name.split(":", 1)[1])
        if "mean_temperature" in names:
            y = [float(r["mean_temperature"]) for r in rows]
            ax.plot(t, y, "k--", lw=1.0, label="all particles")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("mean temperature (K)")
        ax.set_title("heat-capacity weighted mean temperature by shape")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=9)
        fig.tight_layout()
        fig.savefig(out / "temperatures.png", dpi=110)
        print(f"  plot: {out / 'temperatures.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""kiln's speed/accuracy atlas: runs one scene at several fidelity levels and tabulates error vs cost.

Usage: scripts/tradeoff.py SWEEP.toml [--out DIR] [--kiln PATH] [--reuse] [--check]

SWEEP.toml names a base case and the levels to run (see docs/performance.md, "The atlas"):

    case = "case.toml"              # base case, relative to the sweep file
    metric = "particle_temperature" # or "bed_height"
    noise_seed = 11                 # optional: the reference level again with this seed, which
                                    # gives the statistical floor of a bulk metric
    [set]                           # changes applied to every level
    "simulation.end_time" = 1.0
    [[level]]
    name = "lumped"
    reference = false               # exactly one level is the reference (the finest)
    [level.set]
    "material.1.heat.model" = "lumped"    # dotted path; integers index arrays of tables;
    "insert.0.radius" = "<delete>"        # the string "<delete>" removes a key

Metrics (final state, read from the last particles/*.vtp with VTK's Python reader):
  particle_temperature: per-particle volume-mean and core temperatures, matched by particle id
      against the reference level (the mechanics do not depend on the heat model, so the same ids
      sit at the same places); error = RMS over particles of the mean-temperature difference (K).
  bed_height: bed height H = 2 mean(z) of the particle centres (exact for a uniform column on a
      floor at z = 0); error = |H - H_ref| / H_ref.

Cost: wall_seconds and heat_wall_seconds of each run's summary.json, and for heat sweeps the thermal
cost per particle and thermal step. Writes DIR/tradeoff.md, DIR/tradeoff.csv and DIR/tradeoff.png
(Debian's python3-matplotlib and python3-vtk9, which libvtk9-dev pulls in).
"""
import argparse
import csv
import json
import math
import re
import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

DELETE = "<delete>"


# --- TOML writing (the subset kiln case files use) -----------------------------------------------
def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        if math.isnan(v):
            return "nan"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def is_table_array(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def toml_dump(doc: dict) -> str:
    out: list[str] = []

    def body(tbl: dict, prefix: str) -> None:
        for k, v in tbl.items():
            if not isinstance(v, dict) and not is_table_array(v):
                out.append(f"{k} = {toml_value(v)}")
        for k, v in tbl.items():
            name = f"{prefix}{k}"
            if isinstance(v, dict):
                out.append(f"\n[{name}]")
                body(v, name + ".")
            elif is_table_array(v):
                for item in v:
                    out.append(f"\n[[{name}]]")
                    body(item, name + ".")

    body(doc, "")
    return "\n".join(out).lstrip("\n") + "\n"


def apply_set(doc: dict, changes: dict, where: str) -> None:
    for path, value in changes.items():
        keys = path.split(".")
        node = doc
        for k in keys[:-1]:
            if isinstance(node, list):
                if not re.fullmatch(r"\d+", k) or int(k) >= len(node):
                    sys.exit(f"tradeoff: {where}: '{path}': '{k}' is not an index of that array")
                node = node[int(k)]
            else:
                node = node.setdefault(k, {})
        last = keys[-1]
        if isinstance(node, list):
            sys.exit(f"tradeoff: {where}: '{path}' ends at an array, name an element's key")
        if value == DELETE:
            node.pop(last, None)
        else:
            node[last] = value


# --- reading results ------------------------------------------------------------------------------
def last_particles_file(run_dir: Path) -> Path:
    pvd = run_dir / "particles.pvd"
    if not pvd.exists():
        sys.exit(f"tradeoff: {run_dir}: no particles.pvd (set [output] vtk_interval)")
    sets = ET.parse(pvd).getroot().findall(".//DataSet")
    return run_dir / sets[-1].get("file")


def read_particles(run_dir: Path) -> dict:
    import vtk  # noqa: PLC0415 (only needed here; import is slow)
    from vtk.util.numpy_support import vtk_to_numpy  # noqa: PLC0415

    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(last_particles_file(run_dir)))
    reader.Update()
    pd = reader.GetOutput()
    data = {"points": vtk_to_numpy(pd.GetPoints().GetData())}
    arrays = pd.GetPointData()
    for i in range(arrays.GetNumberOfArrays()):
        data[arrays.GetArrayName(i)] = vtk_to_numpy(arrays.GetArray(i))
    return data


def metric_value(metric: str, data: dict, ref: dict | None):
    """Returns (error, detail text) against the reference's data (None: the reference itself)."""
    if metric == "bed_height":
        h = 2.0 * float(data["points"][:, 2].mean())
        if ref is None:
            return 0.0, f"H = {1e3 * h:.3f} mm"
        h_ref = 2.0 * float(ref["points"][:, 2].mean())
        return abs(h - h_ref) / h_ref, f"H = {1e3 * h:.3f} mm"
    if metric == "particle_temperature":
        if "temperature_mean" not in data:
            sys.exit("tradeoff: particle_temperature needs a case with [heat]")
        tm = dict(zip(data["id"].tolist(), data["temperature_mean"].tolist()))
        tc = dict(zip(data["id"].tolist(), data["temperature_core"].tolist()))
        if ref is None:
            return 0.0, f"mean T {sum(tm.values()) / len(tm):.3f} K"
        rm = dict(zip(ref["id"].tolist(), ref["temperature_mean"].tolist()))
        rc = dict(zip(ref["id"].tolist(), ref["temperature_core"].tolist()))
        common = sorted(set(tm) & set(rm))
        if len(common) != len(rm):
            sys.exit("tradeoff: particle ids differ from the reference's (the mechanics differ?)")
        rms = math.sqrt(sum((tm[i] - rm[i]) ** 2 for i in common) / len(common))
        core = max(abs(tc[i] - rc[i]) for i in common)
        return rms, f"max core diff {core:.3g} K"
    sys.exit(f"tradeoff: unknown metric '{metric}' (allowed: bed_height, particle_temperature)")


# --- main -----------------------------------------------------------------------------------------
def slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_").lower()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sweep", type=Path)
    ap.add_argument("--out", type=Path, default=None, help="output folder (default out/tradeoff_<sweep>)")
    here = Path(__file__).resolve().parent.parent
    ap.add_argument("--kiln", type=Path, default=here / "build/src/app/kiln")
    ap.add_argument("--reuse", action="store_true", help="keep runs whose summary.json exists")
    ap.add_argument("--check", action="store_true", help="only write the level cases and `kiln check` them")
    args = ap.parse_args()

    with open(args.sweep, "rb") as f:
        sweep = tomllib.load(f)
    base_file = (args.sweep.parent / sweep["case"]).resolve()
    with open(base_file, "rb") as f:
        base = tomllib.load(f)
    metric = sweep.get("metric", "particle_temperature")
    levels = list(sweep.get("level", []))
    refs = [lv for lv in levels if lv.get("reference", False)]
    if len(refs) != 1:
        sys.exit(f"tradeoff: {args.sweep}: exactly one [[level]] needs reference = true")
    if "noise_seed" in sweep:
        noise = dict(refs[0])
        noise["name"] = refs[0]["name"] + f" (seed {sweep['noise_seed']})"
        noise["reference"] = False
        noise["set"] = dict(refs[0].get("set", {}))
        noise["set"]["simulation.seed"] = sweep["noise_seed"]
        noise["noise"] = True
        levels.append(noise)
    out = args.out or Path("out") / f"tradeoff_{slug(args.sweep.parent.name + '_' + args.sweep.stem)}"
    out.mkdir(parents=True, exist_ok=True)

    results = []
    for lv in levels:
        doc = json.loads(json.dumps(base))  # deep copy
        apply_set(doc, sweep.get("set", {}), f"{args.sweep} [set]")
        apply_set(doc, lv.get("set", {}), f"{args.sweep} level '{lv['name']}'")
        run_dir = out / "runs" / slug(lv["name"])
        run_dir.mkdir(parents=True, exist_ok=True)
        case_file = run_dir / "case.toml"
        case_file.write_text(f"# {lv['name']}: written by scripts/tradeoff.py from {base_file}\n"
                             + toml_dump(doc))
        if args.check:
            proc = subprocess.run([str(args.kiln), "check", str(case_file)], cwd=base_file.parent,
                                  text=True, capture_output=True)
            print(f"tradeoff: '{lv['name']}': {'ok' if proc.returncode == 0 else proc.stderr.strip()}")
            continue
        if not (args.reuse and (run_dir / "summary.json").exists()):
            print(f"tradeoff: running '{lv['name']}' ...", flush=True)
            proc = subprocess.run([str(args.kiln), "run", str(case_file), "--out", str(run_dir), "--quiet"],
                                  cwd=base_file.parent, text=True, capture_output=True)
            if proc.returncode != 0:
                sys.exit(f"tradeoff: level '{lv['name']}' failed:\n{proc.stderr}")
        summary = json.loads((run_dir / "summary.json").read_text())
        results.append((lv, run_dir, summary))
    if args.check:
        return 0

    ref_data = read_particles(next(d for lv, d, _ in results if lv.get("reference", False)))
    rows = []
    for lv, run_dir, s in results:
        data = read_particles(run_dir)
        is_ref = lv.get("reference", False)
        err, detail = metric_value(metric, data, None if is_ref else ref_data)
        heat = s.get("heat", {})
        thermal_updates = heat.get("thermal_steps", 0) * s["particles"]
        heat_us = 1e6 * s.get("heat_wall_seconds", 0.0) / thermal_updates if thermal_updates else float("nan")
        rows.append({"level": lv["name"], "group": lv.get("group", ""), "reference": is_ref,
                     "noise": lv.get("noise", False), "error": err, "detail": detail,
                     "wall_s": s["wall_seconds"], "heat_s": s.get("heat_wall_seconds", 0.0),
                     "heat_us_per_particle_step": heat_us,
                     "particle_steps_per_s": s["particle_steps_per_second"],
                     "cells": sum(m.get("cells", 0) for m in heat.get("materials", [])),
                     "mean_iterations": heat.get("mean_iterations", float("nan"))})

    unit = "K (RMS over particles)" if metric == "particle_temperature" else "relative"
    with open(out / "tradeoff.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    lines = [f"Sweep `{args.sweep}` on `{base_file.name}`; metric `{metric}`, error in {unit} "
             "against the reference level.", "",
             "| level | error | detail | wall s | heat s | heat us per particle-step | particle-steps/s |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        tag = " (reference)" if r["reference"] else (" (noise floor)" if r["noise"] else "")
        hus = "-" if math.isnan(r["heat_us_per_particle_step"]) else f"{r['heat_us_per_particle_step']:.3g}"
        lines.append(f"| {r['level']}{tag} | {r['error']:.3g} | {r['detail']} | {r['wall_s']:.2f} | "
                     f"{r['heat_s']:.2f} | {hus} | {r['particle_steps_per_s']:.3g} |")
    (out / "tradeoff.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))

    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(7, 4.5))
    cost_key = "heat_s" if metric == "particle_temperature" else "wall_s"
    floor = None
    for r in rows:
        if r["reference"]:
            continue
        if r["noise"]:
            floor = r["error"]
            continue
        ax.loglog(max(r[cost_key], 1e-3), max(r["error"], 1e-12), "o")
        ax.annotate(r["level"], (max(r[cost_key], 1e-3), max(r["error"], 1e-12)), fontsize=7,
                    xytext=(4, 3), textcoords="offset points")
    if floor is not None:
        ax.axhline(floor, ls="--", color="grey", label="noise floor (reference, other seed)")
        ax.legend(fontsize=8)
    ref_cost = next(r[cost_key] for r in rows if r["reference"])
    ax.axvline(ref_cost, ls=":", color="k")
    ax.set_xlabel("thermal wall time (s)" if cost_key == "heat_s" else "wall time (s)")
    ax.set_ylabel(f"error ({unit})")
    ax.set_title(f"{base_file.parent.name}: {metric} vs cost (dotted: reference's cost)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "tradeoff.png", dpi=120)
    print(f"tradeoff: wrote {out / 'tradeoff.md'}, tradeoff.csv, tradeoff.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())

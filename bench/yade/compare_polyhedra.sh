#!/usr/bin/env bash
# Side-by-side benchmark of kiln polyhedra against Yade 2023 polyhedra on the drop test of
# /work/shared/peers/yade/poly_check.py: 64 random convex polyhedra (~8 mm, 26 vertices each)
# falling from a 4 x 4 x 4 grid onto a plane, dt = 1e-5 s. poly_drop.py (this folder) runs Yade and
# writes the 64 shapes (Yade's local frame = principal frame) and start poses; this script turns
# them into kiln templates and a case (the same bodies at the same places) and runs kiln.
# usage: bench/yade/compare_polyhedra.sh          (STEPS=20000 by default)
# env:   STEPS, KILN (path to the kiln binary), WORK (scratch folder), KILN_THREADS (default 1;
#        Yade always runs with -j1)
# Prints body-steps/s of both codes and their ratio (issue 6 target: kiln >= 100x Yade), then the
# end state of both (centre heights, contacts, kinetic energy).
#
# The physics is the same scene, not the same model: Yade's law is its volumetric one (normal force
# from the overlap volume) with Newton's global damping 0.3; kiln runs Hertz-Mindlin with the same
# E, nu, density and friction coefficient tan(0.5), and restitution 0.5 as its damping. Both drops
# end in a resting layer of bodies, which is what the end-state table compares.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
steps="${STEPS:-20000}"
kiln="${KILN:-$repo/build/src/app/kiln}"
work="${WORK:-$(mktemp -d /tmp/kiln_vs_yade.XXXXXX)}"

if ! command -v yade > /dev/null; then
    apt-get install -y --no-install-recommends yade    # ~0.9 GB installed
fi
[ -x "$kiln" ] || { echo "compare_polyhedra.sh: kiln binary not found at $kiln (set KILN)" >&2; exit 1; }

echo "# kiln vs Yade 2023 polyhedra, 64 bodies, $steps steps of 1e-5 s; Yade -j1, kiln ${KILN_THREADS:-1} thread(s); $(date -u '+%F %T UTC')"
echo "# host: $(nproc) cores; load before: $(uptime | sed 's/.*load average: //'); work: $work"

mkdir -p "$work/home"
(cd "$work" && HOME="$work/home" OMP_NUM_THREADS=1 yade -j1 -n -x "$here/poly_drop.py" "$work" \
    "$steps" > yade.out 2>&1) || { echo "Yade failed, see $work/yade.out" >&2; exit 1; }

/usr/bin/python3 - "$work" "$steps" <<'PY'
import json, math, sys
work, steps = sys.argv[1], int(sys.argv[2])
bodies = json.load(open(f"{work}/particles.json"))
for b in bodies:
    with open(f"{work}/shapes/{b['shape']}.toml", "w") as f:
        f.write(f'kind = "polyhedron"\ndescription = "Yade random polyhedron {b["shape"]}"\n'
                f'mesh = "{b["shape"]}.obj"\nscale = 1.0\n')
lines = [
    "# Written by bench/yade/compare_polyhedra.sh: the bodies of poly_drop.py (Yade) for kiln.",
    "[simulation]", 'name = "yade_poly_drop"', "time_step = 1e-5",
    f"end_time = {steps * 1e-5!r}", "gravity = [0, 0, -9.81]", "",
    "[[material]]", 'name = "poly"', "youngs_modulus = 1e7", "poisson_ratio = 0.25",
    "density = 2600", "restitution = 0.5", f"friction = {math.tan(0.5)!r}", "",
    "[contact]", 'model = "hertz_mindlin"', 'narrow_phase = "newton"', "skin = 5e-4", "",
    "[[wall]]", 'type = "plane"', 'material = "poly"', "point = [0, 0, 0]", "normal = [0, 0, 1]", "",
]
for b in bodies:
    p, q = b["position"], b["orientation"]
    lines += ["[[particle]]", 'material = "poly"', f'shape = "{b["shape"]}"',
              f"position = [{p[0]!r}, {p[1]!r}, {p[2]!r}]",
              f"orientation = [{q[0]!r}, {q[1]!r}, {q[2]!r}, {q[3]!r}]", ""]
lines += ["[output]", "vtk_interval = 0", f"monitor_interval = {steps * 1e-5 / 10!r}",
          'monitors = ["time", "kinetic_energy", "contacts", "wall_contacts", "mean_height", "max_height"]',
          "progress = false", ""]
open(f"{work}/case.toml", "w").write("\n".join(lines))
PY

(cd "$work" && OMP_NUM_THREADS="${KILN_THREADS:-1}" /usr/bin/time -o kiln.time -f "%U %S" \
    "$kiln" run case.toml --out kiln > kiln.out 2>&1) || { echo "kiln failed, see $work/kiln.out" >&2; exit 1; }
# kiln's start-up alone (reading the case, 64 convex hulls), to take out of its CPU time.
sed "s/^end_time = .*/end_time = 1e-5/" "$work/case.toml" > "$work/startup.toml"
(cd "$work" && /usr/bin/time -o kiln_startup.time -f "%U %S" "$kiln" run startup.toml \
    --out kiln_startup > /dev/null 2>&1) || { echo "kiln failed, see $work" >&2; exit 1; }
echo "# load after: $(uptime | sed 's/.*load average: //')"

/usr/bin/python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
y = json.load(open(f"{work}/yade.json"))
s = json.load(open(f"{work}/kiln/summary.json"))
m = s["final_monitors"]
pk, py = s["particle_steps_per_second"], y["body_steps_per_second"]
# CPU time: the fair measure on a loaded host. kiln's run loop = its whole CPU time less that of a
# one-step run (start-up: reading the case, 64 convex hulls); Yade's is measured around O.run.
def cpu(path):
    user, system = map(float, open(path).read().split()[-2:])
    return user + system
startup = cpu(f"{work}/kiln_startup.time")
ck, cy = cpu(f"{work}/kiln.time") - startup, y["cpu_seconds"]
work_units = y["bodies"] * y["steps"]
print("\n| code | wall (s) | body-steps/s (wall) | kiln / Yade (wall) | CPU (s) | body-steps/s (CPU) | kiln / Yade (CPU) |")
print("|---|---|---|---|---|---|---|")
print(f"| Yade 2023.02a | {y['wall_seconds']:.2f} | {py:.4g} | | {cy:.2f} | {work_units / cy:.4g} | |")
print(f"| kiln | {s['wall_seconds']:.2f} | {pk:.4g} | **{pk / py:.1f}x** | {ck:.2f} | {work_units / ck:.4g} | **{cy / ck:.1f}x** |")
print(f"(kiln start-up, not counted: {startup:.2f} s CPU)")
print("\n| code | mean centre height (mm) | highest centre (mm) | body-body contacts | body-wall contacts | kinetic energy (J) |")
print("|---|---|---|---|---|---|")
print(f"| Yade | {1e3 * y['mean_height']:.2f} | {1e3 * y['max_height']:.2f} | {y['contacts']} | {y['wall_contacts']} | {y['kinetic_energy']:.3e} |")
print(f"| kiln | {1e3 * m['mean_height']:.2f} | {1e3 * m['max_height']:.2f} | {m['contacts']:.0f} | {m['wall_contacts']:.0f} | {m['kinetic_energy']:.3e} |")
PY

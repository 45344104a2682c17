#!/usr/bin/env bash
# Side-by-side benchmark of kiln clumps against LIGGGHTS 3.8 multisphere on the scene of
# in.pour_multisphere (/work/shared/peers/liggghts, or $PEERS): N rigid two-sphere clumps
# (r = 2 mm, centres 2 mm apart) poured into a 0.1 x 0.1 x 0.2 m box, Hertz with tangential
# history, dt = 1e-5 s. kiln runs pour_multisphere.toml with the template dimer_2mm.toml (this
# folder).
# usage: bench/liggghts/compare_multisphere.sh [N ...]   (default N = 2000; STEPS=20000 by default)
# env:   STEPS, KILN (path to the kiln binary), WORK (scratch folder), PEERS (folder of
#        in.pour_multisphere), KILN_THREADS (default 1; LIGGGHTS always runs on one)
# Prints, per N: clump-steps/s of both codes (LIGGGHTS' atoms are the member spheres, 2 per clump)
# and their ratio (issue 6 target: kiln >= 3x), then the kinetic energy at the end and the contacts
# per member sphere of both runs (kiln: coordination / 2, its coordination counting element
# contacts per clump; LIGGGHTS: c_cnave of contact/atom).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
source "$here/common.sh"
peers="${PEERS:-/work/shared/peers/liggghts}"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(2000)
[ -f "$peers/in.pour_multisphere" ] || { echo "compare_multisphere.sh: $peers/in.pour_multisphere missing (set PEERS)" >&2; exit 1; }

liggghts_prepare compare_multisphere.sh kiln_vs_liggghts_ms
echo "# kiln clumps vs LIGGGHTS 3.8 multisphere, in.pour_multisphere, $steps steps of 1e-5 s; LIGGGHTS 1 thread, kiln ${KILN_THREADS:-1}; $(date -u '+%F %T UTC')"

results=()
for n in "${sizes[@]}"; do
    liggghts_run_pair "$n" "$peers/in.pour_multisphere" "$here/pour_multisphere.toml" \
        "$here/dimer_2mm.toml"
done
echo "# load after: $(uptime | sed 's/.*load average: //')"

/usr/bin/python3 - "$here" "$steps" "${results[@]}" <<'PY'
import json, sys

sys.path.insert(0, sys.argv[1])
from liggghts_log import read_log as liggghts

steps = int(sys.argv[2])

perf, phys = [], []
for item in sys.argv[3:]:
    n, d = item.split(":", 1)
    loop, last = liggghts(f"{d}/log.liggghts")
    s = json.load(open(f"{d}/kiln/summary.json"))
    m = s["final_monitors"]
    clumps = int(n)
    pss_l = clumps * steps / loop
    pss_k = s["particle_steps_per_second"]
    perf.append((n, last["Atoms"], loop, pss_l, s["wall_seconds"], pss_k, pss_k / pss_l))
    phys.append((n, last["KinEng"], m["kinetic_energy"], last["cnave"], 0.5 * m["coordination"]))

print(f"\n| clumps | LIGGGHTS atoms | LIGGGHTS loop time (s) | LIGGGHTS clump-steps/s "
      f"| kiln wall (s) | kiln clump-steps/s | kiln / LIGGGHTS |")
print("|---|---|---|---|---|---|---|")
for n, atoms, tl, pl, tk, pk, r in perf:
    print(f"| {n} | {atoms:.0f} | {tl:.2f} | {pl/1e6:.3f} M | {tk:.2f} | {pk/1e6:.3f} M | {r:.2f}x |")

# Different random packings: compare end statistics only (see compare.sh for the tolerances).
print(f"\n| clumps | KE end LIGGGHTS (J) | KE end kiln (J) | contacts per sphere LIGGGHTS "
      f"| contacts per sphere kiln |")
print("|---|---|---|---|---|")
for n, kl, kk, cl, ck in phys:
    print(f"| {n} | {kl:.3e} | {kk:.3e} | {cl:.3f} | {ck:.3f} |")
PY

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
steps="${STEPS:-20000}"
kiln="${KILN:-$repo/build/src/app/kiln}"
peers="${PEERS:-/work/shared/peers/liggghts}"
work="${WORK:-$(mktemp -d /tmp/kiln_vs_liggghts_ms.XXXXXX)}"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(2000)

if ! command -v liggghts > /dev/null; then
    # --no-install-recommends: the recommended packages pull ParaView and remove libvtk9-dev.
    apt-get install -y --no-install-recommends liggghts
fi
[ -x "$kiln" ] || { echo "compare_multisphere.sh: kiln binary not found at $kiln (set KILN)" >&2; exit 1; }
[ -f "$peers/in.pour_multisphere" ] || { echo "compare_multisphere.sh: $peers/in.pour_multisphere missing (set PEERS)" >&2; exit 1; }

end_time=$(/usr/bin/python3 -c "print(repr($steps * 1e-5))")
echo "# kiln clumps vs LIGGGHTS 3.8 multisphere, in.pour_multisphere, $steps steps of 1e-5 s; LIGGGHTS 1 thread, kiln ${KILN_THREADS:-1}; $(date -u '+%F %T UTC')"
echo "# host: $(nproc) cores; load before: $(uptime | sed 's/.*load average: //'); work: $work"

results=()
for n in "${sizes[@]}"; do
    dir="$work/n$n"
    mkdir -p "$dir"
    cp "$peers/in.pour_multisphere" "$here/dimer_2mm.toml" "$dir/"
    (cd "$dir" && OMP_NUM_THREADS=1 liggghts -in in.pour_multisphere -var N "$n" -var steps "$steps" \
        -log log.liggghts > liggghts.out 2>&1) || { echo "LIGGGHTS failed, see $dir" >&2; exit 1; }
    sed -e "s/^count = .*/count = $n/" -e "s/^end_time = .*/end_time = $end_time/" \
        "$here/pour_multisphere.toml" > "$dir/case.toml"
    (cd "$dir" && OMP_NUM_THREADS="${KILN_THREADS:-1}" "$kiln" run case.toml --out kiln \
        > kiln.out 2>&1) || { echo "kiln failed, see $dir" >&2; exit 1; }
    results+=("$n:$dir")
done
echo "# load after: $(uptime | sed 's/.*load average: //')"

/usr/bin/python3 - "$steps" "${results[@]}" <<'PY'
import json, re, sys

steps = int(sys.argv[1])

def liggghts(log):
    """Loop time of the last run and the last thermo row (columns by header name)."""
    loop, header, rows = None, None, []
    for line in open(log):
        w = line.split()
        if w[:1] == ["Step"]:
            header, rows = w, []
        elif line.startswith("Loop time"):
            loop = float(re.search(r"Loop time of ([0-9.eE+-]+)", line).group(1))
        elif header and len(w) == len(header):
            try:
                rows.append(dict(zip(header, map(float, w))))
            except ValueError:
                pass
    return loop, rows[-1]

perf, phys = [], []
for item in sys.argv[2:]:
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

#!/usr/bin/env bash
# Side-by-side benchmark of kiln against LIGGGHTS 3.8 on the scene of in.pour_spheres (this folder).
# usage: bench/liggghts/compare.sh [N ...]          (default N = 5000; STEPS=20000 by default)
# env:   STEPS (time steps, dt = 1e-5 s), KILN (path to the kiln binary), WORK (scratch folder),
#        KILN_THREADS (threads of the kiln run, default 1; LIGGGHTS always runs on one),
#        OMP_WAIT_POLICY (passed on; set it to passive when the host is oversubscribed)
# Prints, per N: particle-steps/s of both codes and their ratio, then kinetic energy and mean
# coordination number at the end of both runs. Both codes run one after the other, LIGGGHTS on one
# thread, kiln on KILN_THREADS.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
steps="${STEPS:-20000}"
kiln="${KILN:-$repo/build/src/app/kiln}"
work="${WORK:-$(mktemp -d /tmp/kiln_vs_liggghts.XXXXXX)}"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(5000)

if ! command -v liggghts > /dev/null; then
    # --no-install-recommends: the recommended packages pull ParaView and remove libvtk9-dev.
    apt-get install -y --no-install-recommends liggghts
fi
[ -x "$kiln" ] || { echo "compare.sh: kiln binary not found at $kiln (set KILN)" >&2; exit 1; }

end_time=$(/usr/bin/python3 -c "print(repr($steps * 1e-5))")
echo "# kiln vs LIGGGHTS 3.8, in.pour_spheres, $steps steps of 1e-5 s; LIGGGHTS 1 thread, kiln ${KILN_THREADS:-1}; $(date -u '+%F %T UTC')"
echo "# host: $(nproc) cores; load before: $(uptime | sed 's/.*load average: //'); work: $work"

results=()
for n in "${sizes[@]}"; do
    dir="$work/n$n"
    mkdir -p "$dir"
    cp "$here/in.pour_spheres" "$dir/"
    (cd "$dir" && OMP_NUM_THREADS=1 liggghts -in in.pour_spheres -var N "$n" -var steps "$steps" \
        -log log.liggghts > liggghts.out 2>&1) || { echo "LIGGGHTS failed, see $dir" >&2; exit 1; }
    sed -e "s/^count = .*/count = $n/" -e "s/^end_time = .*/end_time = $end_time/" \
        "$here/pour_spheres.toml" > "$dir/case.toml"
    (cd "$dir" && OMP_NUM_THREADS="${KILN_THREADS:-1}" "$kiln" run case.toml --out kiln \
        > kiln.out 2>&1) || { echo "kiln failed, see $dir" >&2; exit 1; }
    results+=("$n:$dir")
done
echo "# load after: $(uptime | sed 's/.*load average: //')"

/usr/bin/python3 - "$steps" "${results[@]}" <<'PY'
import json, re, sys

steps = int(sys.argv[1])

def liggghts(log):
    """Loop time of the last run and the last thermo row (columns by header name: KinEng = ke, cnave = c_cnave)."""
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
    last = rows[-1]
    return loop, last["Atoms"], last["KinEng"], last["cnave"]

def rel(a, b):
    return abs(a - b) / abs(b) if b else float("nan")

perf, phys = [], []
for item in sys.argv[2:]:
    n, d = item.split(":", 1)
    loop, atoms, ke_l, cn_l = liggghts(f"{d}/log.liggghts")
    s = json.load(open(f"{d}/kiln/summary.json"))
    m = s["final_monitors"]
    pss_l = atoms * steps / loop
    pss_k = s["particle_steps_per_second"]
    perf.append((n, loop, pss_l, s["wall_seconds"], pss_k, pss_k / pss_l))
    phys.append((n, ke_l, m["kinetic_energy"], rel(m["kinetic_energy"], ke_l),
                 cn_l, m["coordination"], rel(m["coordination"], cn_l)))

print(f"\n| N | LIGGGHTS loop time (s) | LIGGGHTS particle-steps/s | kiln wall (s) "
      f"| kiln particle-steps/s | kiln / LIGGGHTS |")
print("|---|---|---|---|---|---|")
for n, tl, pl, tk, pk, r in perf:
    print(f"| {n} | {tl:.2f} | {pl/1e6:.2f} M | {tk:.2f} | {pk/1e6:.2f} M | {r:.2f}x |")

# Insertion differs (different random packings), so trajectories differ: compare end statistics.
# Fair tolerance: 15 % on the mean coordination number of the settled bed; the kinetic energy of a
# nearly settled bed is a small residual (1e-4 J against ~0.2 J in flight) and only its order of
# magnitude is meaningful (factor 2).
print(f"\n| N | KE end LIGGGHTS (J) | KE end kiln (J) | rel. diff | coordination LIGGGHTS "
      f"| coordination kiln | rel. diff |")
print("|---|---|---|---|---|---|---|")
ok = True
for n, kl, kk, dk, cl, ck, dc in phys:
    print(f"| {n} | {kl:.3e} | {kk:.3e} | {dk:.0%} | {cl:.3f} | {ck:.3f} | {dc:.1%} |")
    ok &= dc <= 0.15 and 0.5 <= kk / kl <= 2.0 if kl > 0 else False
print("\nphysics cross-check (coordination within 15 %, final KE within a factor 2):",
      "PASS" if ok else "FAIL")
PY

#!/usr/bin/env bash
# Side-by-side benchmark of kiln against LIGGGHTS 3.8 on the scene of in.pour_spheres (this folder).
# usage: bench/liggghts/compare.sh [N ...]          (default N = 5000; STEPS=20000 by default;
#        above N = 10000 the box is made taller, see below)
# env:   STEPS (time steps, dt = 1e-5 s), KILN (path to the kiln binary), WORK (scratch folder),
#        KILN_THREADS (threads of the kiln run, default 1; LIGGGHTS always runs on one),
#        OMP_WAIT_POLICY (passed on; set it to passive when the host is oversubscribed)
# Prints, per N: particle-steps/s of both codes and their ratio, then kinetic energy and mean
# coordination number at the end of both runs. Both codes run one after the other, LIGGGHTS on one
# thread, kiln on KILN_THREADS.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
source "$here/common.sh"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(5000)

liggghts_prepare compare.sh kiln_vs_liggghts
echo "# kiln vs LIGGGHTS 3.8, in.pour_spheres, $steps steps of 1e-5 s; LIGGGHTS 1 thread, kiln ${KILN_THREADS:-1}; $(date -u '+%F %T UTC')"

results=()
for n in "${sizes[@]}"; do
    if [ "$n" -le 10000 ]; then
        liggghts_run_pair "$n" "$here/in.pour_spheres" "$here/pour_spheres.toml"
    else
        # The 0.1 x 0.1 x 0.2 m box takes about 10 000 spheres of 4 mm (50 000 would fill 84 % of
        # it). Above 10 000 both codes get a box N / 10000 times taller with the same cross-section,
        # its insertion region scaled in z by the same factor (0.01-0.19 m -> 0.05-0.95 m at
        # N = 50 000), as notes/limits.md ran N = 50 000: the insertion's solid fraction stays that
        # of N = 10 000; the drop is taller, so at 20 000 steps much of the charge is still falling.
        s=$(/usr/bin/python3 -c "print($n / 10000)")
        top=$(/usr/bin/python3 -c "print(f'{0.2 * $s:.4f}')")
        lo=$(/usr/bin/python3 -c "print(f'{0.01 * $s:.4f}')")
        hi=$(/usr/bin/python3 -c "print(f'{0.19 * $s:.4f}')")
        mkdir -p "$work/tall$n"
        sed -e "s/ 0\.0 0\.20 units box/ 0.0 $top units box/" -e "s/zplane  0\.20$/zplane  $top/" \
            -e "s/ 0\.01 0\.19 units box/ $lo $hi units box/" "$here/in.pour_spheres" \
            > "$work/tall$n/in.pour_spheres"
        sed -e "s/^max = \[0\.05, 0\.05, 0\.2\]/max = [0.05, 0.05, $top]/" \
            -e "s/min = \[-0\.048, -0\.048, 0\.01\], max = \[0\.048, 0\.048, 0\.19\]/min = [-0.048, -0.048, $lo], max = [0.048, 0.048, $hi]/" \
            "$here/pour_spheres.toml" > "$work/tall$n/pour_spheres.toml"
        # Each rewrite must have happened: a missed pattern would run a different scene silently.
        [ "$(grep -c -e " $top units box" -e "zplane  $top" -e " $lo $hi units box" \
            "$work/tall$n/in.pour_spheres")" -eq 3 ] &&
            [ "$(grep -c -e "0.05, $top\]" -e "0.048, $hi\]" "$work/tall$n/pour_spheres.toml")" \
                -eq 2 ] || { echo "compare.sh: tall-box rewrite failed" >&2; exit 1; }
        echo "# N = $n: box ${s}x taller (z 0-$top m), insertion z $lo-$hi m"
        liggghts_run_pair "$n" "$work/tall$n/in.pour_spheres" "$work/tall$n/pour_spheres.toml"
    fi
done
echo "# load after: $(uptime | sed 's/.*load average: //')"

/usr/bin/python3 - "$here" "$steps" "${results[@]}" <<'PY'
import json, sys

sys.path.insert(0, sys.argv[1])
from liggghts_log import read_log

steps = int(sys.argv[2])

def liggghts(log):
    """Loop time and, from the last thermo row, atoms, kinetic energy (ke) and c_cnave."""
    loop, last = read_log(log)
    return loop, last["Atoms"], last["KinEng"], last["cnave"]

def rel(a, b):
    return abs(a - b) / abs(b) if b else float("nan")

perf, phys = [], []
for item in sys.argv[3:]:
    n, d = item.split(":", 1)
    loop, atoms, ke_l, cn_l = liggghts(f"{d}/log.liggghts")
    s = json.load(open(f"{d}/kiln/summary.json"))
    m = s["final_monitors"]
    pss_l = atoms * steps / loop
    pss_k = s["particle_steps_per_second"]
    # User seconds of the whole processes (start-up and insertion included): steadier than the
    # loop times on a loaded host, where a descheduled process still ticks the wall clock.
    user_l = float(open(f"{d}/liggghts.time").read().split()[0])
    user_k = float(open(f"{d}/kiln.time").read().split()[0])
    perf.append((n, loop, pss_l, s["wall_seconds"], pss_k, pss_k / pss_l, user_l, user_k))
    phys.append((n, ke_l, m["kinetic_energy"], rel(m["kinetic_energy"], ke_l),
                 cn_l, m["coordination"], rel(m["coordination"], cn_l)))

print(f"\n| N | LIGGGHTS loop time (s) | LIGGGHTS particle-steps/s | kiln wall (s) "
      f"| kiln particle-steps/s | kiln / LIGGGHTS | user s LIGGGHTS / kiln (whole process) "
      f"| ratio of user s |")
print("|---|---|---|---|---|---|---|---|")
for n, tl, pl, tk, pk, r, ul, uk in perf:
    print(f"| {n} | {tl:.2f} | {pl/1e6:.2f} M | {tk:.2f} | {pk/1e6:.2f} M | {r:.2f}x "
          f"| {ul:.2f} / {uk:.2f} | {ul / uk:.2f}x |")

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

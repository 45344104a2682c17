#!/usr/bin/env bash
# Two threads against one on the lattice scenes of bench/lattice_scene.hpp (343 particles of about
# 6 mm collapsing into a box; build/bench/kiln_scene_steps), per shape and phase:
#   collapse: steps 4000-8000, settled: steps 16000-20000 (as bench/contact_ratios.sh).
# Prints the wall-clock time per step with one and with two threads, the speed-up, and whether
# both runs end with the same checksum of the positions (they must: the threads change no bit).
# A busy second core makes the two-thread runs slower, not faster (docs/performance.md,
# "Threads"): run it on a quiet host.
#
# Usage: bench/thread_speedup.sh [ROUNDS [KIND...]]  (default 1 round; kinds: sphere, the clump
# cylinder_12, the polyhedra cube, icosahedron and cylinder_16, the superquadrics sq08 and
# superball). The table gives the fastest run of each over the rounds. Needs a Release build with
# benchmarks (scripts/setup.sh), or KILN_SCENE_STEPS pointing at a kiln_scene_steps binary.
set -euo pipefail
script=bench/thread_speedup.sh
default_rounds=1
default_kinds=(sphere cylinder_12 cube icosahedron cylinder_16 sq08 superball)
source "$(dirname "${BASH_SOURCE[0]}")/scene_args.sh"

out=$(mktemp)
trap 'rm -f "$out"' EXIT
echo "# $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for r in $(seq 1 "$rounds"); do
    for phase in collapse settled; do
        if [[ $phase == collapse ]]; then warm=4000; else warm=16000; fi
        for k in "${kinds[@]}"; do
            for t in 1 2; do
                line=$(KILN_SCENE_THREADS=$t "$bin" "$k" "$warm" 4000 2>/dev/null) || {
                    echo "bench/thread_speedup.sh: kiln_scene_steps $k failed" >&2
                    exit 1
                }
                # kind cpu_ms_per_step X ... checksum C wall_ms_per_step W
                read -r _ _ _ _ _ _ _ _ sum _ wall <<<"$line"
                echo "$phase $k $t $wall $sum" >>"$out"
            done
        done
    done
done
/usr/bin/python3 - "$out" <<'EOF'
import sys
best, sums = {}, {}
for line in open(sys.argv[1]):
    phase, kind, threads, wall, checksum = line.split()
    key = (phase, kind, threads)
    best[key] = min(best.get(key, float("inf")), float(wall))
    sums.setdefault((phase, kind), set()).add(checksum)
print("| phase | kind | 1 thread, ms/step | 2 threads, ms/step | speed-up | same checksum |")
print("|---|---|---|---|---|---|")
order = []
for phase, kind, _ in best:
    if (phase, kind) not in order:
        order.append((phase, kind))
for phase, kind in order:
    one, two = best[(phase, kind, "1")], best[(phase, kind, "2")]
    same = "yes" if len(sums[(phase, kind)]) == 1 else "NO"
    print(f"| {phase} | {kind} | {one:.4f} | {two:.4f} | {one / two:.2f}x | {same} |")
EOF

#!/usr/bin/env bash
# Two threads against one on clump pours of thousands of bodies (the lattice scenes of
# thread_speedup.sh have 343), whole runs from insertion to a settled bed: the LIGGGHTS multisphere
# scene (bench/liggghts/pour_multisphere.toml: two-sphere clumps of 2 mm poured into a
# 0.1 x 0.1 x 0.2 m box, Hertz-Mindlin, dt = 1e-5 s) and the same scene with the seed's 36-sphere
# cylinders (shapes/cylinder_36.toml). Prints the wall-clock seconds of `kiln run` with one and two
# threads (whole runs: insertion and output included), the speed-up, and whether both runs wrote
# the same monitors (they must: the threads change no bit).
# A busy second core makes the two-thread runs slower, not faster (docs/performance.md,
# "Threads"): run it on a quiet host.
#
# Usage: bench/clump_threads.sh [ROUNDS]   (default 1; the table gives the fastest run of each)
# Env:   KILN (the kiln binary, default build/src/app/kiln), DIMERS (4000), DIMER_STEPS (20000),
#        CYLINDERS (1500), CYLINDER_STEPS (30000).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
kiln=${KILN:-"$here/build/src/app/kiln"}
[[ -x $kiln ]] || {
    echo "bench/clump_threads.sh: no kiln binary at $kiln (scripts/setup.sh builds it)" >&2
    exit 1
}
rounds=${1:-1}
[[ $rounds =~ ^[1-9][0-9]*$ ]] || {
    echo "bench/clump_threads.sh: ROUNDS must be a positive integer, got '$rounds'" >&2
    exit 2
}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$here/bench/liggghts/dimer_2mm.toml" "$work/"
# scene NAME SHAPE COUNT STEPS: a copy of pour_multisphere.toml with those values.
scene() {
    sed -e "s/^count = .*/count = $3/" -e "s/^end_time = .*/end_time = $(
        /usr/bin/python3 -c "print($4 * 1e-5)"
    )/" -e "s/^shape = .*/shape = \"$2\"/" "$here/bench/liggghts/pour_multisphere.toml" \
        >"$work/$1.toml"
}
scene dimers dimer_2mm "${DIMERS:-4000}" "${DIMER_STEPS:-20000}"
scene cylinders cylinder_36 "${CYLINDERS:-1500}" "${CYLINDER_STEPS:-30000}"
echo "# $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
times="$work/times"
for r in $(seq 1 "$rounds"); do
    for s in dimers cylinders; do
        for t in 1 2; do
            (cd "$work" && OMP_NUM_THREADS=$t /usr/bin/time -f '%e' -o "$s.$t.time" \
                "$kiln" run "$s.toml" --out "$s.$t" --quiet) || {
                echo "bench/clump_threads.sh: kiln run $s.toml failed" >&2
                exit 1
            }
            echo "$s $t $(cat "$work/$s.$t.time")" >>"$times"
        done
        same=no
        cmp -s "$work/$s.1/monitors.csv" "$work/$s.2/monitors.csv" && same=yes
        echo "$s same $same" >>"$times"
    done
done
/usr/bin/python3 - "$times" <<'EOF'
import sys
best, same = {}, {}
for line in open(sys.argv[1]):
    s, t, v = line.split()
    if t == "same":
        same[s] = same.get(s, True) and v == "yes"
    else:
        best[(s, t)] = min(best.get((s, t), 1e99), float(v))
print("| scene | 1 thread, wall s | 2 threads, wall s | speed-up | same monitors |")
print("|---|---|---|---|---|")
for s in ("dimers", "cylinders"):
    one, two = best[(s, "1")], best[(s, "2")]
    print(f"| {s} | {one:.2f} | {two:.2f} | {one / two:.2f}x | {'yes' if same[s] else 'NO'} |")
if not all(same.values()):
    sys.exit("bench/clump_threads.sh: one and two threads wrote different monitors")
EOF

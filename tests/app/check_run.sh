#!/usr/bin/env bash
# Command-line regression test: `kiln run` on a tiny case writes every output file, and a restart
# from its checkpoint completes; `kiln check` on a bad file fails with a located message.
set -euo pipefail
kiln=$1
here=$(cd "$(dirname "$0")" && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

"$kiln" run "$here/tiny.toml" --out "$out/run" --quiet
for f in case.resolved.toml summary.json monitors.csv particles.pvd walls.vtp checkpoint.bin \
         particles/particles_000000.vtp; do
    [ -s "$out/run/$f" ] || { echo "missing output $f"; exit 1; }
done
grep -q '"status": "completed"' "$out/run/summary.json" || { echo "run did not complete"; exit 1; }
grep -q '^# kiln ' "$out/run/case.resolved.toml" || { echo "resolved case lacks the version line"; exit 1; }
rows=$(($(wc -l < "$out/run/monitors.csv") - 1))
[ "$rows" -eq 21 ] || { echo "expected 21 monitor rows, got $rows"; exit 1; }

"$kiln" run "$here/tiny.toml" --restart "$out/run/checkpoint.bin" --out "$out/restart" --quiet
grep -q '"status": "completed"' "$out/restart/summary.json" || { echo "restart did not complete"; exit 1; }

# A restart into the folder of the run it continues extends that run's output: stop at 0.01 s,
# run on past the checkpoint to 0.015 s (those rows and frames must be dropped), restart from the
# 0.01 s checkpoint to the end, and the monitors must equal the straight run's byte for byte.
sed 's/^end_time = 0.02/end_time = 0.01/' "$here/tiny.toml" > "$out/half.toml"
sed 's/^end_time = 0.02/end_time = 0.015/' "$here/tiny.toml" > "$out/more.toml"
"$kiln" run "$out/half.toml" --out "$out/cont" --quiet
cp "$out/cont/checkpoint.bin" "$out/at10ms.bin"
"$kiln" run "$out/more.toml" --restart "$out/cont/checkpoint.bin" --out "$out/cont" --quiet
"$kiln" run "$here/tiny.toml" --restart "$out/at10ms.bin" --out "$out/cont" --quiet
cmp "$out/run/monitors.csv" "$out/cont/monitors.csv" || { echo "continued monitors differ"; exit 1; }
frames_run=$(grep -c '<DataSet' "$out/run/particles.pvd")
frames_cont=$(grep -c '<DataSet' "$out/cont/particles.pvd")
[ "$frames_run" -eq "$frames_cont" ] || { echo "frames: $frames_cont continued, $frames_run straight"; exit 1; }
cmp "$out/run/particles/particles_000002.vtp" "$out/cont/particles/particles_000002.vtp" \
    || { echo "last frame differs"; exit 1; }

# The same with heat: a hot floor, resolved spheres, field output; a restart from the 0.01 s
# checkpoint must continue the temperatures bit for bit (monitors equal byte for byte).
heat='
[material.heat]
conductivity = 1.0
specific_heat = 800
initial_temperature = 300
model = "resolved"
radial_cells = 3
polar_cells = 4
azimuthal_cells = 6

[heat]
step_multiple = 20
heat_transfer_coefficient = 20
flow_direction = [0, 0, -1]
field_output = true
'
{ sed 's/^normal = \[0, 0, 1\]/normal = [0, 0, 1]\ntemperature = 500/' "$here/tiny.toml";
  echo 'monitors = ["time", "mean_temperature", "max_temperature", "thermal_energy"]';
  echo "$heat"; } > "$out/heat.toml"
sed 's/^end_time = 0.02/end_time = 0.01/' "$out/heat.toml" > "$out/heat_half.toml"
"$kiln" run "$out/heat.toml" --out "$out/heat" --quiet
grep -q '"heat": {' "$out/heat/summary.json" || { echo "summary lacks the heat object"; exit 1; }
[ -s "$out/heat/fields/fields_000000.vtu" ] || { echo "missing field output"; exit 1; }
"$kiln" run "$out/heat_half.toml" --out "$out/heat_cont" --quiet
"$kiln" run "$out/heat.toml" --restart "$out/heat_cont/checkpoint.bin" --out "$out/heat_cont" --quiet
cmp "$out/heat/monitors.csv" "$out/heat_cont/monitors.csv" || { echo "heat restart differs"; exit 1; }
awk -F, 'NR > 1 && $3 > 300.000001 { hot = 1 } END { exit !hot }' "$out/heat/monitors.csv" \
    || { echo "the hot floor heated nothing"; exit 1; }

# `kiln check` refuses what `kiln run` refuses at start-up (scene set-up, not the reader): a time
# step above the Rayleigh step.
sed 's/^time_step = 1e-5/time_step = 1e-3/' "$out/heat.toml" > "$out/big_step.toml"
set +e
msg=$("$kiln" check "$out/big_step.toml" 2>&1)
code=$?
set -e
[ "$code" -eq 2 ] || { echo "time step above Rayleigh: check exit code $code, expected 2"; exit 1; }
echo "$msg" | grep -q "simulation.time_step: .*must be below the Rayleigh step" \
    || { echo "unexpected check message: $msg"; exit 1; }
"$kiln" check "$out/heat.toml" > /dev/null || { echo "check refused the good heat case"; exit 1; }
# Every shipped case reads (shape templates, meshes and monitor names included).
for c in "$here"/../../cases/*/case.toml; do
    "$kiln" check "$c" > /dev/null || { echo "kiln check refused the shipped case $c"; exit 1; }
done

set +e
msg=$("$kiln" check "$here/bad.toml" 2>&1)
code=$?
set -e
[ "$code" -eq 2 ] || { echo "bad case: exit code $code, expected 2"; exit 1; }
echo "$msg" | grep -q "bad.toml:2: simulation.time_step: -1e-05 s is out of range; allowed: value > 0" \
    || { echo "unexpected message: $msg"; exit 1; }
echo "command-line checks passed"

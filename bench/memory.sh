#!/usr/bin/env bash
# Memory per particle of kiln by heat model: runs a few steps of a lattice of N spheres (r = 1 mm,
# glass-like) with each model and prints the peak resident set size (GNU time's %M) and the bytes
# per particle, taken as the slope between two particle counts (so fixed costs such as the program,
# the libraries and one grid template drop out). Usage: bench/memory.sh [N_SMALL N_LARGE]
# (default 10000 100000). Needs /usr/bin/time (Debian package `time`) and a built kiln
# (build/src/app/kiln, or $KILN). Figures: docs/performance.md, "Memory".
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
kiln=${KILN:-"$here/build/src/app/kiln"}
n_small=${1:-10000}
n_large=${2:-100000}
[[ -x /usr/bin/time ]] || { echo "bench/memory.sh: needs /usr/bin/time (apt-get install time)" >&2; exit 1; }
[[ -x $kiln ]] || { echo "bench/memory.sh: no kiln at $kiln (build first: scripts/setup.sh)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# heat table of each model; "resolved" grids have about 500 cells (the issue's memory target).
heat_table() {
    case $1 in
    none) echo "" ;;
    lumped) printf '[material.heat]\nconductivity = 1.0\nspecific_heat = 800\nmodel = "lumped"\n' ;;
    spherical) printf '[material.heat]\nconductivity = 1.0\nspecific_heat = 800\nmodel = "resolved"\ngrid = "spherical"\nradial_cells = 8\npolar_cells = 6\nazimuthal_cells = 10\n' ;;
    cartesian) printf '[material.heat]\nconductivity = 1.0\nspecific_heat = 800\nmodel = "resolved"\ngrid = "cartesian"\ncells_across = 10\n' ;;
    esac
}

# Peak RSS (kB) of a 3-step run of n particles with heat model $2.
peak_kb() {
    local n=$1 model=$2
    # cubic lattice with spacing 2.2 mm, side length for n particles
    local side
    side=$(python3 -c "import math; print(math.ceil($n ** (1/3)))")
    local len
    len=$(python3 -c "print($side * 2.2e-3)")
    local heat_section=""
    [[ $model != none ]] && heat_section=$'[heat]\nstep_multiple = 1\nheat_transfer_coefficient = 10\n'
    cat >"$work/case.toml" <<EOF
[simulation]
time_step = 1e-6
end_time = 3e-6
[[material]]
name = "glass"
youngs_modulus = 5e6
poisson_ratio = 0.3
density = 2500
restitution = 0.5
friction = 0.3
$(heat_table "$model")
[[insert]]
type = "lattice"
material = "glass"
region = { min = [0, 0, 0], max = [$len, $len, $len] }
count = $n
radius = 1e-3
spacing = 2.2e-3
$heat_section
[output]
vtk_interval = 0
EOF
    /usr/bin/time -f %M -o "$work/rss" "$kiln" run "$work/case.toml" --out "$work/out" --quiet >/dev/null
    local cells
    cells=$(python3 -c "import json; s=json.load(open('$work/out/summary.json')); print(sum(m['cells'] for m in s.get('heat', {}).get('materials', [])), s['particles'])")
    echo "$(cat "$work/rss") $cells"
}

printf '%-10s %12s %12s %8s %16s\n' model "RSS N=$n_small" "RSS N=$n_large" cells "bytes/particle"
for model in none lumped spherical cartesian; do
    read -r kb1 cells n1 < <(peak_kb "$n_small" $model)
    read -r kb2 _ n2 < <(peak_kb "$n_large" $model)
    per=$(python3 -c "print(round(($kb2 - $kb1) * 1024 / ($n2 - $n1)))")
    printf '%-10s %9.1f MB %9.1f MB %8s %16s\n' $model "$(python3 -c "print($kb1/1024)")" \
        "$(python3 -c "print($kb2/1024)")" "$cells" "$per"
done

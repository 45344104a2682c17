#!/usr/bin/env bash
# Installs what is missing, builds kiln and runs the showcase case (cases/hot_shapes: cubes,
# superballs, ellipsoids, clumps and spheres with resolved temperature fields on a hot floor).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/scripts/setup.sh" "$here/build"
cd "$here"
./build/src/app/kiln run cases/hot_shapes/case.toml --out out/hot_shapes
/usr/bin/python3 "$here/scripts/plot_monitors.py" out/hot_shapes || echo "(no plot: python3-matplotlib missing)"

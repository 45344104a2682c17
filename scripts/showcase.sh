#!/usr/bin/env bash
# Installs what is missing, builds kiln and runs the showcase case (cases/pour).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/scripts/setup.sh" "$here/build"
cd "$here"
./build/src/app/kiln run cases/pour/case.toml --out out/pour
/usr/bin/python3 "$here/scripts/plot_monitors.py" out/pour || echo "(no plot: python3-matplotlib missing)"

#!/usr/bin/env bash
# Installs what is missing, builds kiln and runs the whole test suite (unit and validation) with ctest.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/scripts/setup.sh" "$here/build"
cd "$here/build"
ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" "$@"

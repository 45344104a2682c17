#!/usr/bin/env bash
# Installs what is missing, builds kiln and runs the test suite (unit, regression and validation)
# with ctest. Without arguments every test runs except those labelled validation_long (cases that
# take tens of minutes on one core, listed in validation/README.md); run those with
# `scripts/test.sh -L validation_long`, or everything with `scripts/test.sh -LE none`.
# Any arguments are passed to ctest instead of the default selection.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/scripts/setup.sh" "$here/build"
cd "$here/build"
if (($# == 0)); then
    set -- -LE validation_long
fi
ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" "$@"

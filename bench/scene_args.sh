# Shared start of the scripts that run build/bench/kiln_scene_steps over shapes
# (contact_ratios.sh, thread_speedup.sh); sourced, not run. Expects `script` (the caller's name,
# for messages), `default_rounds` and the array `default_kinds`; reads the caller's arguments
# [ROUNDS [KIND...]] and sets `here` (the repository), `bin` (the binary: KILN_SCENE_STEPS or the
# Release build's), `rounds` and the array `kinds`; stops with a message on a missing binary or
# a bad ROUNDS.
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${KILN_SCENE_STEPS:-"$here/build/bench/kiln_scene_steps"}
[[ -x $bin ]] || {
    echo "$script: no kiln_scene_steps at $bin (build with -DKILN_BUILD_BENCH=ON)" >&2
    exit 1
}
rounds=${1:-$default_rounds}
[[ $rounds =~ ^[1-9][0-9]*$ ]] || {
    echo "$script: ROUNDS must be a positive integer, got '$rounds'" >&2
    exit 2
}
shift || true
kinds=("$@")
((${#kinds[@]} > 0)) || kinds=("${default_kinds[@]}")

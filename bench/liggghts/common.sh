# Shared part of the LIGGGHTS side-by-side scripts (compare.sh, compare_multisphere.sh); sourced,
# not run. Expects `here` (this folder) and `repo` to be set by the caller.
# env: STEPS (default 20000 time steps of 1e-5 s), KILN (kiln binary), WORK (scratch folder),
#      KILN_THREADS (threads of the kiln run, default 1; LIGGGHTS always runs on one).

steps="${STEPS:-20000}"
kiln="${KILN:-$repo/build/src/app/kiln}"
end_time=$(/usr/bin/python3 -c "print(repr($steps * 1e-5))")

# liggghts_prepare SCRIPT WORK_PREFIX: installs LIGGGHTS if missing, checks the kiln binary, sets
# `work` and prints the run header.
liggghts_prepare() {
    local script="$1"
    work="${WORK:-$(mktemp -d "/tmp/$2.XXXXXX")}"
    if ! command -v liggghts > /dev/null; then
        # --no-install-recommends: the recommended packages pull ParaView and remove libvtk9-dev.
        apt-get install -y --no-install-recommends liggghts
    fi
    [ -x "$kiln" ] || { echo "$script: kiln binary not found at $kiln (set KILN)" >&2; exit 1; }
    echo "# host: $(nproc) cores; load before: $(uptime | sed 's/.*load average: //'); work: $work"
}

# liggghts_run_pair N INPUT CASE [FILE ...]: in $work/nN, runs LIGGGHTS on INPUT (with -var N and
# -var steps) and kiln on CASE (its `count` and `end_time` lines rewritten), one after the other;
# FILEs are copied next to them. Each run's user, system and wall seconds of the whole process
# (start-up and insertion included) go to liggghts.time and kiln.time. Appends "N:dir" to the
# array `results`.
liggghts_run_pair() {
    local n="$1" input="$2" case="$3"
    shift 3
    local dir="$work/n$n"
    mkdir -p "$dir"
    cp "$input" "$@" "$dir/"
    (cd "$dir" && OMP_NUM_THREADS=1 /usr/bin/time -f '%U %S %e' -o liggghts.time \
        liggghts -in "$(basename "$input")" -var N "$n" -var steps "$steps" -log log.liggghts \
        > liggghts.out 2>&1) ||
        { echo "LIGGGHTS failed, see $dir" >&2; exit 1; }
    sed -e "s/^count = .*/count = $n/" -e "s/^end_time = .*/end_time = $end_time/" \
        "$case" > "$dir/case.toml"
    (cd "$dir" && OMP_NUM_THREADS="${KILN_THREADS:-1}" /usr/bin/time -f '%U %S %e' -o kiln.time \
        "$kiln" run case.toml --out kiln > kiln.out 2>&1) || { echo "kiln failed, see $dir" >&2; exit 1; }
    results+=("$n:$dir")
}

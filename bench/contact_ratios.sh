#!/usr/bin/env bash
# Cost per contact of each particle shape against a sphere contact (issue 6 target: "within 10x
# of a sphere contact for the shapes the seed uses"), in the two phases of the lattice scene of
# bench/lattice_scene.hpp (343 particles of about 6 mm collapsing into a box):
#   collapse: steps 4000-8000 (few contacts per body, many near misses),
#   settled:  steps 16000-20000 (a resting pile).
# The cost is the process CPU time of the whole step divided by its element contacts (particle and
# wall contacts; build/bench/kiln_scene_steps), so a sphere contact carries the same overheads as
# the others. Rounds go through every shape in turn, so a busy spell of the host touches all of
# them alike; the table gives the median over the rounds (the sphere runs three times per round)
# and the ratio of the medians to the sphere's median in the same phase, with the range of that
# ratio over the sphere's fastest and slowest runs, and the ratio of the fastest runs (on a host
# shared with other machines a run is only ever slowed down, so the fastest is the steadiest),
# and a verdict: "yes" where both ratios are within 10x, "at the line" where the larger is within
# 10.5x, "no" otherwise, "no (floor)" where the shape's contact-free step alone (the same
# particles spaced apart, spinning, no gravity: per-particle work only) costs as much as the
# whole step that 10 sphere contacts per contact allow. A last column splits per-contact from
# per-particle work: the step less its contact-free floor, per contact, against the same figure of
# the sphere ("contacts' own share"). It is a diagnosis, not the target: the floor comes from a
# different scene (no gravity, nothing touching), so it only estimates the per-particle work of
# the timed steps, and the issue's cost per contact is the whole step's.
#
# Usage: bench/contact_ratios.sh [ROUNDS [KIND...]]  (default 3 rounds; kinds: every shape of the
# seed: sphere, the clumps cylinder_12 and cylinder_36, the boxes cube, cuboid_6x6x5, plate_10x9x2
# and plate_inv4, the polyhedra pyramid, icosahedron, cylinder_8 and cylinder_16 (the seed's
# prisms of 8 and 16 edges, Inv. II); any shipped shape name or
# sq08/sq03 works). Needs a Release build with benchmarks (scripts/setup.sh), or
# KILN_SCENE_STEPS pointing at a kiln_scene_steps binary. KILN_RATIOS_PLOT=FILE.png also draws the
# ratios (python3-matplotlib): per shape and phase the median ratio with its range, the 10x line,
# and what the contact-free floor alone would give. Figures: docs/performance.md.
set -euo pipefail
script=bench/contact_ratios.sh
default_rounds=3
default_kinds=(sphere cylinder_12 cylinder_36 cube cuboid_6x6x5 plate_10x9x2 plate_inv4 pyramid
    icosahedron cylinder_8 cylinder_16)
source "$(dirname "${BASH_SOURCE[0]}")/scene_args.sh"
[[ " ${kinds[*]} " == *" sphere "* ]] || kinds=(sphere "${kinds[@]}")

out=$(mktemp)
trap 'rm -f "$out"' EXIT
echo "# $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for r in $(seq 1 "$rounds"); do
    for phase in collapse settled; do
        if [[ $phase == collapse ]]; then warm=4000; else warm=16000; fi
        for k in "${kinds[@]}"; do
            # The sphere scene times only ~40 ms per run, so its runs scatter most; as the
            # denominator of every ratio it runs three times per round.
            repeats=1
            [[ $k == sphere ]] && repeats=3
            for _ in $(seq 1 $repeats); do
                line=$("$bin" "$k" "$warm" 4000 2>/dev/null) || {
                    echo "bench/contact_ratios.sh: kiln_scene_steps $k failed" >&2
                    exit 1
                }
                # kind cpu_ms_per_step X contacts_per_particle Y cpu_ns_per_contact Z checksum C
                read -r _ _ ms _ cpp _ ns _ <<<"$line"
                echo "$r $phase $k $ms $cpp $ns" >>"$out"
            done
        done
    done
    # The floor: the same shape's contact-free step (KILN_SCENE_FREE=1: per-particle work alone).
    for k in "${kinds[@]}"; do
        line=$(KILN_SCENE_FREE=1 "$bin" "$k" 100 4000 2>/dev/null) || {
            echo "bench/contact_ratios.sh: kiln_scene_steps $k (contact-free) failed" >&2
            exit 1
        }
        read -r _ _ ms _ <<<"$line"
        echo "$r floor $k $ms 0 0" >>"$out"
    done
    echo "# round $r of $rounds done, load $(cut -d' ' -f1 /proc/loadavg)" >&2
done

# Debian's interpreter (it has python3-matplotlib from scripts/setup.sh), else the first on PATH.
py=/usr/bin/python3
[[ -x $py ]] || py=python3
"$py" - "$out" "${KILN_RATIOS_PLOT:-}" <<'EOF'
import collections
import statistics
import sys

rows = collections.defaultdict(list)
order = []
for line in open(sys.argv[1]):
    r, phase, kind, ms, cpp, ns = line.split()
    if kind not in order:
        order.append(kind)
    rows[(phase, kind)].append((float(ns), float(cpp), float(ms)))
# The last column: the step's cost per particle against the sphere scene's (the same number of
# particles), i.e. the per-contact ratio times the shape's contacts per particle over the
# sphere's; it tells per-body work from per-contact work where a shape touches little.
# The verdict against issue 6's target (within 10x of a sphere contact): "yes" where the ratio
# of the medians and that of the fastest runs are both at most 10, "at the line" where one of them
# is above 10 but neither above 10.5, "no" otherwise.
def verdict(median_ratio, fastest_ratio):
    if max(median_ratio, fastest_ratio) <= 10.0:
        return "yes"
    if max(median_ratio, fastest_ratio) <= 10.5:
        return "at the line"
    return "no"


# The last two columns: the budget, the step that 10 sphere contacts per contact allow
# (10 x the sphere's median ns per contact x the shape's contacts per step), and the floor, the
# median step of the same shape without any contact (kiln_scene_steps with KILN_SCENE_FREE=1:
# the kicks, the drift, the rotation, the walls' tests and the list, per particle). Where the
# floor reaches the budget, no narrow phase and no contact law, however fast, can bring the shape
# within 10x: the verdict says "no (floor)"; the per-particle work has to fall first.
def contacts_per_step(step_ms, ns_per_contact):
    """Contacts per step of a run: its step over its cost per contact (the same 343 particles in
    every scene)."""
    return 1e6 * step_ms / ns_per_contact if ns_per_contact > 0 else 0.0


def own_ns(step_ms, floor_ms, contacts):
    """ns per contact of the step less its contact-free floor (the contacts' own share)."""
    return 1e6 * (step_ms - floor_ms) / contacts if contacts > 0 else 0.0


def median_floor(kind):
    """The median contact-free step of `kind` (ms)."""
    return statistics.median(x[2] for x in rows[("floor", kind)])


plotted = {}
print("| phase | shape | contacts per particle | us per step | ns per contact: median (range) "
      "| x a sphere contact (range) | fastest / sphere's fastest | x a sphere per step "
      "| within 10x | budget at 10x, us per step | contact-free floor, us per step "
      "| contacts' own share, x a sphere's |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for phase in ("collapse", "settled"):
    ref_runs = [v[0] for v in rows[(phase, "sphere")]]
    ref = statistics.median(ref_runs)
    ref_step = statistics.median(x[2] for x in rows[(phase, "sphere")])
    ref_own = own_ns(ref_step, median_floor("sphere"), contacts_per_step(ref_step, ref))
    plotted[phase] = []
    for kind in order:
        v = rows[(phase, kind)]
        ns = [x[0] for x in v]
        med = statistics.median(ns)
        step = statistics.median(x[2] for x in v)
        cpp = statistics.median(x[1] for x in v)
        contacts = contacts_per_step(step, med)
        budget = 10.0 * ref * contacts / 1e3  # us
        floor_ms = median_floor(kind)
        floor = 1e3 * floor_ms  # us
        word = verdict(med / ref, min(ns) / min(ref_runs))
        if word != "yes" and floor >= budget:
            word = "no (floor)"
        own = own_ns(step, floor_ms, contacts)
        own_ratio = f"{own / ref_own:.1f}" if ref_own > 0 else "-"
        # the ratio the floor alone would give (contacts costing nothing)
        floor_ratio = 1e3 * floor / contacts / ref if contacts > 0 else 0.0
        plotted[phase].append((kind, med / ref, med / max(ref_runs), med / min(ref_runs),
                               floor_ratio))
        print(f"| {phase} | {kind} | {cpp:.2f} "
              f"| {1e3 * step:.1f} "
              f"| {med:.1f} ({min(ns):.1f}-{max(ns):.1f}) | {med / ref:.1f} "
              f"({med / max(ref_runs):.1f}-{med / min(ref_runs):.1f}) "
              f"| {min(ns) / min(ref_runs):.1f} | {step / ref_step:.1f} "
              f"| {word} | {budget:.1f} | {floor:.1f} | {own_ratio} |")

if len(sys.argv) > 2 and sys.argv[2]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    shapes = [k for k, *_ in plotted["collapse"] if k != "sphere"]
    fig, ax = plt.subplots(figsize=(8, 0.55 * len(shapes) + 2.0))
    for offset, phase, colour in ((-0.18, "collapse", "tab:orange"), (0.18, "settled", "tab:blue")):
        by_kind = {k: v for k, *v in plotted[phase]}
        y = [i + offset for i in range(len(shapes))]
        mid = [by_kind[k][0] for k in shapes]
        lo = [by_kind[k][0] - by_kind[k][1] for k in shapes]
        hi = [by_kind[k][2] - by_kind[k][0] for k in shapes]
        ax.barh(y, mid, height=0.34, color=colour, alpha=0.8, label=f"{phase}: median (range)")
        ax.errorbar(mid, y, xerr=[lo, hi], fmt="none", ecolor="k", elinewidth=0.8, capsize=2)
        ax.scatter([by_kind[k][3] for k in shapes], y, marker="|", s=120, color="k", zorder=3,
                   label="contact-free step alone" if phase == "settled" else None)
    ax.axvline(10.0, color="crimson", lw=1.5, label="target: 10x")
    ax.set_xscale("log")
    ax.set_xlim(0.5, 100)
    ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    ax.set_yticks(range(len(shapes)))
    ax.set_yticklabels(shapes)
    ax.invert_yaxis()
    ax.set_xlabel("cost per contact, x a sphere contact in the same phase (whole step / contacts)")
    ax.set_title("kiln cost per contact by shape (bench/contact_ratios.sh)", fontsize=10)
    ax.grid(axis="x", which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.11), ncol=2)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    print(f"(plot: {sys.argv[2]})")
EOF

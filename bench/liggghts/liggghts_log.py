"""Reads a LIGGGHTS log for the side-by-side scripts (compare.sh, compare_multisphere.sh)."""
import re


def read_log(path):
    """Loop time (s) of the last run and its last thermo row as a dict keyed by column header
    (e.g. Atoms, KinEng, cnave)."""
    loop, header, rows = None, None, []
    for line in open(path):
        w = line.split()
        if w[:1] == ["Step"]:
            header, rows = w, []
        elif line.startswith("Loop time"):
            loop = float(re.search(r"Loop time of ([0-9.eE+-]+)", line).group(1))
        elif header and len(w) == len(header):
            try:
                rows.append(dict(zip(header, map(float, w))))
            except ValueError:
                pass
    if loop is None or not rows:
        raise SystemExit(f"{path}: no 'Loop time' line or no thermo rows (did LIGGGHTS finish?)")
    return loop, rows[-1]

#!/usr/bin/env python3
"""The literature map's pendulum cells beside the classic Fortran code of the same method.

The map's `pendulum` case is Scenario S01 (m = l = 1, g = 13.75..., released
horizontally, t in [0, 20], checked at t = 20 against the exact solution), the
scenario `data/fortran_anchors.csv` holds for RADAU5, DASSL, ODASSL and MEBDF
on the same formulations. For every finished cell whose solver has a Fortran
peer (radau5 - RADAU5, bdf - DASSL, odbdf - ODASSL, mebdf - MEBDF) and whose
formulation the peer ran, prints both errors and step counts at the same
nominal tolerance and the difference in correct digits (positive: `dae` is the
more accurate). The map's error is the largest error of the differential
unknowns scaled by max(1, |y*|), the anchors' the largest absolute error of
x, y, v, w: the same number on this solution (|y*| <= 1 at t = 20 but for w).

Closes with a count per solver: of the map's inaccurate cells, how many are
within half a digit of the Fortran code or better (the method as its authors
built it misses the bar there too) and how many fall short of it.
EXTREMES.md section 5, "Session 14".

    ./target/release/dae sweep --literature --jobs 1 --max-steps 100000 --quiet --out /tmp/lit
    python3 scripts/map_vs_fortran.py /tmp/lit/map.json
"""

import collections
import csv
import json
import math
import sys

PEERS = {"radau5": "radau5", "bdf": "dassl", "odbdf": "odassl", "mebdf": "mebdf"}
HALF_DIGIT = 0.5


def anchors(path):
    """(code, formulation, tol) -> (err_true, steps) on S01."""
    rows = {}
    with open(path) as f:
        reader = csv.DictReader(line for line in f if not line.startswith("#"))
        for r in reader:
            if r["scenario"] == "S01" and r["status"] == "ok":
                rows[(r["solver"], r["formulation"], float(r["tol"]))] = (
                    float(r["err_true"]),
                    int(r["steps"]),
                )
    return rows


def main(map_path, anchors_path="data/fortran_anchors.csv"):
    peer_rows = anchors(anchors_path)
    with open(map_path) as f:
        doc = json.load(f)
    counts = collections.defaultdict(lambda: [0, 0, 0])
    for case in doc["cases"]:
        if case["scene"] != "pendulum":
            continue
        by_row = collections.defaultdict(list)
        for cell in case["cells"]:
            if cell["class"] not in ("accurate", "inaccurate"):
                continue
            peer = PEERS.get(cell["solver"])
            ref = peer and peer_rows.get((peer, cell["formulation"], cell["tol"]))
            if not ref or not (ref[0] > 0 and cell["err"] > 0):
                continue
            by_row[(cell["solver"], cell["formulation"])].append((cell, ref))
        for (solver, formulation), cells in by_row.items():
            print(f"{solver}({formulation}) against {PEERS[solver].upper()}")
            print("    tol    class   dae err / steps    Fortran err / steps   digits")
            for cell, (ref_err, ref_steps) in cells:
                digits = math.log10(ref_err / cell["err"])
                print(
                    f"  {cell['tol']:6.0e}  {cell['class']:10} {cell['err']:9.1e} / {cell['steps']:6}"
                    f"  {ref_err:9.1e} / {ref_steps:6}   {digits:+5.1f}"
                )
                if cell["class"] == "inaccurate":
                    c = counts[solver]
                    c[0] += 1
                    c[1 if digits >= -HALF_DIGIT else 2] += 1
    print()
    print("inaccurate cells with a Fortran peer: within half a digit of it or better / short of it")
    for solver, (total, level, short) in sorted(counts.items()):
        print(f"  {solver:7} {total:3} cells: {level:3} / {short:3}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(*sys.argv[1:])

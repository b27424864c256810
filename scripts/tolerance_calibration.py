#!/usr/bin/env python3
"""What a tolerance calibration would buy the multistep methods on the literature map.

Reads the `map.json` of a literature map run over tolerances 1e-4 ... 1e-12 and
asks, for every cell of the map's grid (1e-4 ... 1e-10) that finished or hit
the step limit: would the run at tol / 10**s have met the map's bar for tol
(scd >= -log10(tol) - 2)?  s = 0 is the map as it is; s = 1, 2 are a method
that integrates internally at a tolerance 10 or 100 times tighter than the
user's (as RADAU5 maps its own tolerance).  Prints, per solver and per scene,
how many cells would then be accurate and the geometric mean of the step
ratio (the calibrated run's steps over the plain one's, on the cells that
become or stay accurate).  EXTREMES.md section 5, "Session 13".

    ./target/release/dae sweep --literature --solvers bdf,odbdf,mebdf,idec \
        --tols 1e-4,1e-5,1e-6,1e-7,1e-8,1e-9,1e-10,1e-11,1e-12 \
        --jobs 1 --max-steps 100000 --quiet --out /tmp/map13_bdf
    python3 scripts/tolerance_calibration.py /tmp/map13_bdf/map.json
"""

import collections
import json
import math
import sys

GRID = range(4, 11)  # the map's tolerances, as -log10
FINISHED = ("accurate", "inaccurate")


def load(path):
    """Cells by (scene, solver, formulation, -log10 tol)."""
    with open(path) as f:
        doc = json.load(f)
    cells = {}
    for case in doc["cases"]:
        for cell in case["cells"]:
            if cell["tol"] is None:  # not applicable: no tolerance runs
                continue
            k = round(-math.log10(cell["tol"]))
            cells[(case["scene"], cell["solver"], cell["formulation"], k)] = cell
    return cells


def meets(cell, k):
    """Whether a finished cell has the digits the map asks at tol 1e-k."""
    return (
        cell is not None
        and cell["class"] in FINISHED
        and cell["scd"] is not None
        and cell["scd"] >= k - 2
    )


def main():
    cells = load(sys.argv[1] if len(sys.argv) > 1 else "/tmp/map13_bdf/map.json")
    for shift in (0, 1, 2):
        by_solver = collections.defaultdict(lambda: [0, 0, []])
        by_scene = collections.defaultdict(lambda: [0, 0])
        for (scene, solver, form, k), cell in sorted(cells.items()):
            if k not in GRID or cell["class"] not in FINISHED + ("step_limit",):
                continue
            tighter = cells.get((scene, solver, form, k + shift))
            by_solver[solver][1] += 1
            by_scene[scene][1] += 1
            if meets(tighter, k):
                by_solver[solver][0] += 1
                by_scene[scene][0] += 1
                if cell["steps"]:
                    by_solver[solver][2].append(tighter["steps"] / cell["steps"])
        print(f"internal tolerance = tol / 1e{shift}:")
        for solver, (ok, total, ratios) in by_solver.items():
            mean = math.exp(sum(map(math.log, ratios)) / len(ratios)) if ratios else float("nan")
            print(f"  {solver:6} {ok:4} of {total:4} accurate, steps x{mean:.2f}")
        print("  by scene: " + ", ".join(f"{s} {ok}/{n}" for s, (ok, n) in by_scene.items()))


if __name__ == "__main__":
    main()

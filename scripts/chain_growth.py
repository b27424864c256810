#!/usr/bin/env python3
"""The chain's cost per step against its size (issue 24, done-when 1;
BENCHMARKS.md §16f, §16g).

For N = 20, 50, 100, 200, 400 writes the N-link chain (scripts/chain.py)
and runs `dae run --tol 1e-6 --format json` with radau5(ggl1) (least of 3
runs) and bdf(rcd0) (least of 7: its runs take milliseconds), prints steps
and the CPU of `Solver::run` (`tsim_s`) per accepted step, then the
least-squares exponent of that time in N over N = 50 ... 400.

Usage: scripts/chain_growth.py [DAE]   (default target/release/dae)
"""
import json
import math
import os
import subprocess
import sys
import tempfile

repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
dae = sys.argv[1] if len(sys.argv) > 1 else os.path.join(repo, "target", "release", "dae")
sizes = [20, 50, 100, 200, 400]
fit = [50, 100, 200, 400]

with tempfile.TemporaryDirectory() as tmp:
    for n in sizes:
        subprocess.run([sys.executable, os.path.join(repo, "scripts", "chain.py"), str(n),
                        os.path.join(tmp, f"chain{n}")], check=True, capture_output=True)
    per_step = {}
    for solver, form, repeats in [("radau5", "ggl1", 3), ("bdf", "rcd0", 7)]:
        for n in sizes:
            best = None
            for _ in range(repeats):
                out = subprocess.run([dae, "run", os.path.join(tmp, f"chain{n}.toml"), "--solver", solver,
                                      "--formulation", form, "--tol", "1e-6", "--format", "json"],
                                     capture_output=True, text=True, check=True).stdout
                run = json.loads(out)
                if run["status"] != "ok":
                    sys.exit(f"{solver}({form}) N = {n}: {run['status']}: {run['error']}")
                steps = run["stats"]["steps"]
                ms = 1000.0 * run["tsim_s"] / steps
                best = ms if best is None else min(best, ms)
            per_step[(solver, n)] = best
            print(f"{solver}({form}) N = {n}: {steps} steps, {best:.4f} ms/step", flush=True)
    for solver in ["radau5", "bdf"]:
        xs = [math.log(n) for n in fit]
        ys = [math.log(per_step[(solver, n)]) for n in fit]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
        print(f"{solver}: time per step ~ N^{slope:.2f} over N = {fit[0]} ... {fit[-1]}")

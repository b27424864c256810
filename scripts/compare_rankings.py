#!/usr/bin/env python3
"""Compare the rankings of two sweeps of the same grid (BENCHMARKS.md §7).

    scripts/compare_rankings.py A/results.json B/results.json

For each sweep: the Pareto front and the fastest pair per target error by
tsim_s (CPU time of the integrating thread, what `dae sweep` ranks by) and,
recomputed here with the same rule, by wall_s (wall-clock time). Prints
them side by side and whether they are the same; exits 1 when the CPU-time
rankings differ.
"""
import json
import sys

TARGETS = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]


def runs(path):
    with open(path) as f:
        doc = json.load(f)
    return [r for r in doc["runs"] if r["status"] == "ok" and r.get("err") is not None]


def key(r):
    return f'{r["solver"]}({r["formulation"]}) {r["tol"]:g}'


def front(rs, t):
    """Runs no other run beats on both time t and err (the sweep's rule)."""
    out = []
    for a in rs:
        beaten = any(
            b[t] <= a[t] and b["err"] <= a["err"] and (b[t] < a[t] or b["err"] < a["err"])
            for b in rs
        )
        if not beaten:
            out.append(a)
    out.sort(key=lambda r: (r[t], r["err"]))
    return [key(r) for r in out]


def targets(rs, t):
    out = []
    for target in TARGETS:
        met = [r for r in rs if r["err"] <= target]
        best = min(met, key=lambda r: (r[t], r["err"]), default=None)
        out.append(f"<= {target:.0e}: {key(best) if best else 'none'}")
    return out


def main():
    a, b = runs(sys.argv[1]), runs(sys.argv[2])
    same_cpu = True
    for t in ["tsim_s", "wall_s"]:
        for what, f in [("Pareto front", front), ("fastest per target", targets)]:
            ra, rb = f(a, t), f(b, t)
            same = ra == rb
            if t == "tsim_s":
                same_cpu &= same
            print(f"## {what} by {t}: {'SAME' if same else 'DIFFERENT'}")
            width = max(len(x) for x in ra + rb + ["first"])
            print(f"  {'first':<{width}}  second")
            for i in range(max(len(ra), len(rb))):
                x = ra[i] if i < len(ra) else ""
                y = rb[i] if i < len(rb) else ""
                print(f"  {x:<{width}}  {y}{'' if x == y else '   <-'}")
    ratio = lambda rs, t: sum(r[t] for r in rs)
    print(
        f"total tsim_s: {ratio(a, 'tsim_s'):.3f} -> {ratio(b, 'tsim_s'):.3f}; "
        f"total wall_s: {ratio(a, 'wall_s'):.3f} -> {ratio(b, 'wall_s'):.3f}"
    )
    sys.exit(0 if same_cpu else 1)


if __name__ == "__main__":
    main()

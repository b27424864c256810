#!/usr/bin/env python3
"""Compare the rankings of two sweeps of the same grid (BENCHMARKS.md §8, §8c).

    scripts/compare_rankings.py [--rule tie|old] [--resolution R] A/results.json B/results.json

For each sweep: the Pareto front and the fastest pair per target error by
tsim_s (CPU time of the integrating thread, what `dae sweep` ranks by) and,
recomputed here with the same rule, by wall_s (wall-clock time). Prints
them side by side and whether they are the same; exits 1 when the CPU-time
rankings differ.

Rules (src/sweep/pareto.rs states the same):
  tie (default): timing resolution R (default 0.05, pareto::TIME_RESOLUTION):
      two times within a factor 1 + R are tied. Fastest per target: of the
      runs with err <= target, the least time t_min; every run with time
      <= t_min * (1 + R) is tied; the smallest err wins, then the fewest
      steps, then the fewest residual evaluations, then the name (solver,
      formulation, tol). Pareto front: the runs picked so for some error
      level (each run's err taken as a target), by increasing time; a front
      run within R of the one before it is marked "≈".
  old: the rule before the resolution: front = runs no run beats on both
      time and err (ties of both kept), sorted by (time, err); fastest per
      target = least time, ties by err, then the order of the runs.
"""
import argparse
import json
import sys

TARGETS = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]


def runs(path):
    with open(path) as f:
        doc = json.load(f)
    return [r for r in doc["runs"] if r["status"] == "ok" and r.get("err") is not None]


def key(r):
    return f'{r["solver"]}({r["formulation"]}) {r["tol"]:g}'


# ------------------------------------------------------------ the old rule


def old_front(rs, t, _res):
    """Runs no other run beats on both time t and err."""
    out = []
    for a in rs:
        beaten = any(
            b[t] <= a[t] and b["err"] <= a["err"] and (b[t] < a[t] or b["err"] < a["err"])
            for b in rs
        )
        if not beaten:
            out.append(a)
    out.sort(key=lambda r: (r[t], r["err"]))
    return [(key(r), "") for r in out]


def old_targets(rs, t, _res):
    out = []
    for target in TARGETS:
        met = [r for r in rs if r["err"] <= target]
        best = min(met, key=lambda r: (r[t], r["err"]), default=None)
        out.append((f"<= {target:.0e}: {key(best) if best else 'none'}", ""))
    return out


# ------------------------------------------------ the rule with a resolution


def preference(r):
    """Smaller err, then fewer steps, fewer evaluations, then the name."""
    stats = r.get("stats", {})
    return (
        r["err"],
        stats.get("steps", 0),
        stats.get("residual_evals", 0),
        r["solver"],
        r["formulation"],
        r["tol"],
    )


def tied(a, b, res):
    lo, hi = min(a, b), max(a, b)
    return hi <= lo or hi <= lo * (1.0 + max(res, 0.0))


def pick(sorted_rs, t, res):
    """Of candidates sorted by preference: the first tied with the fastest."""
    if not sorted_rs:
        return None
    t_min = min(r[t] for r in sorted_rs)
    return next(r for r in sorted_rs if tied(r[t], t_min, res))


def tie_front(rs, t, res):
    s = sorted(rs, key=preference)
    front = []
    for i, r in enumerate(s):
        if i + 1 < len(s) and s[i + 1]["err"] == r["err"]:
            continue
        best = pick(s[: i + 1], t, res)
        if all(best is not f for f in front):
            front.append(best)
    front.reverse()
    out = []
    for i, r in enumerate(front):
        mark = "≈" if i > 0 and tied(front[i - 1][t], r[t], res) else ""
        out.append((key(r), mark))
    return out


def tie_targets(rs, t, res):
    s = sorted(rs, key=preference)
    out = []
    for target in TARGETS:
        met = [r for r in s if r["err"] <= target]
        best = pick(met, t, res)
        if best is None:
            out.append((f"<= {target:.0e}: none", ""))
            continue
        t_min = min(r[t] for r in met)
        others = [key(r) for r in met if r is not best and tied(r[t], t_min, res)]
        out.append((f"<= {target:.0e}: {key(best)}", f"tied: {', '.join(others)}" if others else ""))
    return out


RULES = {"tie": (tie_front, tie_targets), "old": (old_front, old_targets)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("first")
    ap.add_argument("second")
    ap.add_argument("--rule", choices=sorted(RULES), default="tie", help="ranking rule (default: tie)")
    ap.add_argument(
        "--resolution", type=float, default=0.05, help="relative timing resolution of the tie rule (default 0.05)"
    )
    args = ap.parse_args()
    a, b = runs(args.first), runs(args.second)
    front, targets = RULES[args.rule]
    res = args.resolution
    print(f"rule: {args.rule}" + (f", timing resolution {res:g}" if args.rule == "tie" else ""))
    same_cpu = True
    for t in ["tsim_s", "wall_s"]:
        for what, f in [("Pareto front", front), ("fastest per target", targets)]:
            # Entries are (run, note); only the runs are compared. The notes
            # (a front run's "≈", a pick's tied runs) show where the clock
            # could not order runs; they may differ between sweeps.
            ra, rb = f(a, t, res), f(b, t, res)
            same = [x for x, _ in ra] == [y for y, _ in rb]
            if t == "tsim_s":
                same_cpu &= same
            print(f"## {what} by {t}: {'SAME' if same else 'DIFFERENT'}")
            cells = lambda e: f"{e[0]} {e[1]}".rstrip()
            width = max(len(cells(x)) for x in ra + rb + [("first", "")])
            print(f"  {'first':<{width}}  second")
            for i in range(max(len(ra), len(rb))):
                x = ra[i] if i < len(ra) else ("", "")
                y = rb[i] if i < len(rb) else ("", "")
                print(f"  {cells(x):<{width}}  {cells(y)}{'' if x[0] == y[0] else '   <-'}")

    def total(rs, t):
        return sum(r[t] for r in rs)

    print(
        f"total tsim_s: {total(a, 'tsim_s'):.3f} -> {total(b, 'tsim_s'):.3f}; "
        f"total wall_s: {total(a, 'wall_s'):.3f} -> {total(b, 'wall_s'):.3f}"
    )
    sys.exit(0 if same_cpu else 1)


if __name__ == "__main__":
    main()

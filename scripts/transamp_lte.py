#!/usr/bin/env python3
"""One BDF1 step of the IVP Test Set's transistor amplifier against its exact
local error: what DASSL's estimate sees and what the propagated one sees
(BENCHMARKS.md §18).

    dae run scenes/literature/transamp.toml --solver bdf --formulation rcd0 \
        --tol 1e-9 --trajectory /tmp/transamp.csv        # DASSL: add nothing,
    python3 scripts/transamp_lte.py /tmp/transamp.csv 0.043714

The trajectory must come from a run with DASSL's estimate in its order-one
cycle (the default's check switches the run to the propagated estimate; use
a build with `Estimate::Dassl`, or any two consecutive accepted states of
equal spacing). From the two accepted states before time T (spacing h) the
script takes one BDF1 step of size H = ω h (predictor: the line through the
two states), ω = 1/4 … 16, and prints per unknown, weighted by
1/(tol (1 + |y|)) as `dae run --tol` weighs them:

  lte  the step's local error against the exact solution from the same
       start (Radau IIA, 40 substeps, Newton to 1e-15);
  e    DASSL's estimate y − y⁽⁰⁾;
  ẽ    the propagated estimate G⁻¹ (c E e), G = c E − J, c = 1/H.

Needs numpy only. The model is the Test Set's `M y' = f(t, y)` (transamp.f).
"""
import bisect
import csv
import math
import sys

import numpy as np

UB, UF, ALPHA, BETA = 6.0, 0.026, 0.99, 1e-6
C1, C2, C3, C4, C5 = 1e-6, 2e-6, 3e-6, 4e-6, 5e-6
TOL = 1e-9


def f(t, y):
    y1, y2, y3, y4, y5, y6, y7, y8 = y
    ue = 0.1 * math.sin(200 * math.pi * t)
    g1 = BETA * (math.exp((y2 - y3) / UF) - 1)
    g2 = BETA * (math.exp((y5 - y6) / UF) - 1)
    return np.array([
        (y1 - ue) / 1000,
        y2 / 9000 + (y2 - UB) / 9000 + (1 - ALPHA) * g1,
        y3 / 9000 - g1,
        (y4 - UB) / 9000 + ALPHA * g1,
        y5 / 9000 + (y5 - UB) / 9000 + (1 - ALPHA) * g2,
        y6 / 9000 - g2,
        (y7 - UB) / 9000 + ALPHA * g2,
        y8 / 9000,
    ])


M = np.zeros((8, 8))
for (i, j, c) in [(0, 0, -C1), (0, 1, C1), (1, 0, C1), (1, 1, -C1), (2, 2, -C2),
                  (3, 3, -C3), (3, 4, C3), (4, 3, C3), (4, 4, -C3), (5, 5, -C4),
                  (6, 6, -C5), (6, 7, C5), (7, 6, C5), (7, 7, -C5)]:
    M[i, j] = c


def jac(t, y, eps=1e-7):
    j = np.zeros((8, 8))
    for k in range(8):
        d = np.zeros(8)
        d[k] = eps
        j[:, k] = (f(t, y + d) - f(t, y - d)) / (2 * eps)
    return j


def bdf1(t0, y0, h, guess):
    y = guess.copy()
    for _ in range(30):
        r = M @ (y - y0) / h - f(t0 + h, y)
        dy = np.linalg.solve(M / h - jac(t0 + h, y), -r)
        y = y + dy
        if np.max(abs(dy)) < 1e-15:
            break
    return y


S6 = math.sqrt(6)
A = np.array([[(88 - 7 * S6) / 360, (296 - 169 * S6) / 1800, (-2 + 3 * S6) / 225],
              [(296 + 169 * S6) / 1800, (88 + 7 * S6) / 360, (-2 - 3 * S6) / 225],
              [(16 - S6) / 36, (16 + S6) / 36, 1 / 9]])
C = np.array([(4 - S6) / 10, (4 + S6) / 10, 1.0])


def radau_step(t0, y0, h):
    """Radau IIA (order 5) on M y' = f: M (Y_i − y0) = h Σ a_ij f(Y_j)."""
    stages = np.tile(y0, (3, 1))
    for _ in range(50):
        r = np.concatenate([M @ (stages[i] - y0)
                            - h * sum(A[i, j] * f(t0 + C[j] * h, stages[j]) for j in range(3))
                            for i in range(3)])
        g = np.zeros((24, 24))
        for i in range(3):
            for j in range(3):
                g[8 * i:8 * i + 8, 8 * j:8 * j + 8] = \
                    (M if i == j else 0) - h * A[i, j] * jac(t0 + C[j] * h, stages[j])
        d = np.linalg.solve(g, -r).reshape(3, 8)
        stages = stages + d
        if np.max(abs(d)) < 1e-15:
            break
    return stages[2]


def exact(t0, y0, h, n=40):
    y = y0.copy()
    for k in range(n):
        y = radau_step(t0 + k * h / n, y, h / n)
    return y


def main():
    rows = [list(map(float, r)) for r in list(csv.reader(open(sys.argv[1])))[1:]]
    times = [r[0] for r in rows]
    j = bisect.bisect_left(times, float(sys.argv[2]))
    (t2, *y2), (t1, *y1) = rows[j - 2], rows[j - 1]
    y2, y1 = np.array(y2), np.array(y1)
    h = t1 - t2
    print(f"t = {t1:.8e}, h = {h:.3e}; weighted by 1/(tol (1 + |y|)), tol = {TOL:g}")
    fmt = lambda v: " ".join(f"{x:9.2e}" for x in v)
    for omega in (0.25, 0.5, 1, 2, 4, 8, 16):
        step = omega * h
        predictor = y1 + omega * (y1 - y2)
        y = bdf1(t1, y1, step, predictor)
        w = 1 / (TOL * (1 + abs(y)))
        e = y - predictor
        c = 1 / step
        carried = np.linalg.solve(c * M - jac(t1 + step, y), c * (M @ e))
        print(f"H/h = {omega:5.2f}  lte {fmt((y - exact(t1, y1, step)) * w)}")
        print(f"               e   {fmt(e * w)}")
        print(f"               ẽ   {fmt(carried * w)}")


if __name__ == "__main__":
    main()

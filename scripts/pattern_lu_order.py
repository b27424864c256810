#!/usr/bin/env python3
"""Updates of partial pivoting on radau5's sensitivity stage system, by column order.

The exact sensitivity solve of radau5 (`collocation/stagger.rs`, `Direct`)
factorises the 3N x 3N matrix (A^-1 / h) (x) E - blockdiag(J(Y_k)) on its
non-zeros (`linalg/pattern_lu.rs`), eliminating the columns in storage order
(stage-major). This replays that elimination - partial pivoting among each
column's structural candidates, fill included - on the pendulum's rcd0
(N = 5: x, y, v, w, lambda; E = diag(1, 1, 1, 1, 0)) with Radau IIA's A^-1
and J at plausible stage values, and counts the updates a_ij -= l_ik u_kj
for the stage-major order, a variable-major one, and the best of random
orders. BENCHMARKS.md section 20.

    python3 scripts/pattern_lu_order.py
"""

import numpy as np

AINV = np.array([
    [3.224744871391589, 1.1678400846904056, -0.25319726474218085],
    [-3.5678400846904057, 0.775255128608411, 1.0531972647421808],
    [5.531972647421808, -7.531972647421808, 5.0],
])
N = 5
E = np.diag([1.0, 1.0, 1.0, 1.0, 0.0])


def jacobian(x, y, v, w, lam, g=13.75):
    """d f / d(x, y, v, w, lambda) of the pendulum's rcd0 (m = l = 1)."""
    j = np.zeros((N, N))
    j[0, 2] = j[1, 3] = 1.0
    j[2, 0], j[2, 4] = -2 * lam, -2 * x
    j[3, 1], j[3, 4] = -2 * lam, -2 * y
    j[4] = [-8 * x * lam, -8 * y * lam - 2 * g, 4 * v, 4 * w, -4 * (x * x + y * y)]
    return j


def stage_matrix(h, stages):
    """The matrix and its structural pattern (stage-major)."""
    a = np.zeros((3 * N, 3 * N))
    pattern = np.zeros((3 * N, 3 * N), bool)
    structural = jacobian(0.3, 0.4, 0.5, 0.6, 0.7) != 0
    for k in range(3):
        for j in range(3):
            block = (slice(k * N, k * N + N), slice(j * N, j * N + N))
            a[block] = AINV[k, j] / h * E - (jacobian(*stages[k]) if k == j else 0)
            pattern[block] = (E != 0) | (structural if k == j else False)
    return a, pattern


def updates(a, pattern, order):
    """Updates of partial pivoting over the columns in `order`."""
    a, nz = a[:, order].copy(), pattern[:, order].copy()
    n = len(a)
    pivoted = [False] * n
    count = 0
    for k in range(n):
        candidates = [i for i in range(n) if not pivoted[i] and nz[i, k]]
        p = max(candidates, key=lambda i: abs(a[i, k]))
        pivoted[p] = True
        lower = [i for i in candidates if i != p]
        for i in lower:
            a[i, k] /= a[p, k]
        for j in range(k + 1, n):
            if nz[p, j]:
                for i in lower:
                    a[i, j] -= a[i, k] * a[p, j]
                    nz[i, j] = True
                    count += 1
    return count


def main():
    rng = np.random.default_rng(1)
    stages = [(np.cos(t), np.sin(t), -3 * np.sin(t), 3 * np.cos(t), 20 + 5 * t)
              for t in (0.1, 0.2, 0.3)]
    stage_major = list(range(3 * N))
    variable_major = [k * N + i for i in range(N) for k in range(3)]
    for h in (1e-3, 2.7e-3, 1e-2):
        a, pattern = stage_matrix(h, stages)
        best = min(updates(a, pattern, list(rng.permutation(3 * N))) for _ in range(3000))
        print(f"h = {h:.1e}: stage-major {updates(a, pattern, stage_major)}, "
              f"variable-major {updates(a, pattern, variable_major)}, "
              f"best of 3 000 random orders {best}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Write the N-link planar pendulum chain of BENCHMARKS.md §9 as a model
and a scene.

N point masses on massless rigid links of length l, the first link hinged
at the origin, in Cartesian coordinates: positions (x_i, y_i), velocities
(u_i, v_i), one multiplier la_i per link (index 3; 5N unknowns). The start
is the chain stretched out horizontally at rest (x_i = i·l, y_i = 0): on
the constraints, the multipliers left to consistent initialisation.

Usage: scripts/chain.py N OUT_STEM   (writes OUT_STEM.dae and OUT_STEM.toml)
"""
import os
import sys


def model(n):
    idx = range(1, n + 1)
    lines = [
        f"/// A planar chain of {n} pendulums (written by scripts/chain.py).",
        f"pub Chain{n} {{",
        "    parameters { m = 1.0, l = 1.0, g = 9.81 }",
        "    differential { " + ", ".join(f"{c}{i}" for c in "xyuv" for i in idx) + " }",
        "    algebraic { " + ", ".join(f"la{i}" for i in idx) + " }",
        "    equations {",
    ]
    for i in idx:
        lines += [f"        der(x{i}) = u{i};", f"        der(y{i}) = v{i};"]
    for i in idx:
        dx = "x1" if i == 1 else f"(x{i} - x{i - 1})"
        dy = "y1" if i == 1 else f"(y{i} - y{i - 1})"
        fx, fy = f"-2*la{i}*{dx}", f"-2*la{i}*{dy}"
        if i < n:
            fx += f" + 2*la{i + 1}*(x{i + 1} - x{i})"
            fy += f" + 2*la{i + 1}*(y{i + 1} - y{i})"
        lines += [f"        m*der(u{i}) = {fx};", f"        m*der(v{i}) = {fy} - m*g;"]
    for i in idx:
        if i == 1:
            lines.append("        0 = x1^2 + y1^2 - l^2;")
        else:
            lines.append(f"        0 = (x{i} - x{i - 1})^2 + (y{i} - y{i - 1})^2 - l^2;")
    lines += ["    }", "}"]
    return "\n".join(lines) + "\n"


def scene(n, stem):
    lines = [
        f"# A planar chain of {n} pendulums, stretched out horizontally at rest",
        f"# (scripts/chain.py {n} {stem}). No reference: work and set-up only.",
        f'name = "chain{n}"',
        f'model = "{os.path.basename(stem)}.dae"',
        "",
        "[initial]",
    ]
    for i in range(1, n + 1):
        lines += [f"x{i} = {float(i)!r}", f"y{i} = 0.0", f"u{i} = 0.0", f"v{i} = 0.0"]
    lines += [
        "",
        "[time]",
        "end = 1.0",
        "check_every = 1.0",
        "",
        "[reference]",
        'kind = "none"',
        "",
        "[sweep]",
        'solvers = ["radau5", "bdf"]',
        'formulations = ["ggl1", "rcd0"]',
        "tolerances = [1e-6]",
    ]
    return "\n".join(lines) + "\n"


def main():
    n, stem = int(sys.argv[1]), sys.argv[2]
    with open(stem + ".dae", "w") as f:
        f.write(model(n))
    with open(stem + ".toml", "w") as f:
        f.write(scene(n, stem))


if __name__ == "__main__":
    main()

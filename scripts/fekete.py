#!/usr/bin/env python3
"""Write the IVP Test Set's Fekete problem as a model and a scene.

The problem (Mazzia & Magherini, *Test Set for IVP Solvers*, release 2.4,
problem "Fekete"): N points p_i on the unit sphere, velocities q_i, moving
in the field of the logarithmic potential -sum_{i<j} log |p_i - p_j| with
damping alpha = 0.5, each held on the sphere by a multiplier lambda_i:

    p_i' = q_i
    q_i' = sum_{j != i} (p_i - p_j) / |p_i - p_j|^2 - alpha q_i + 2 lambda_i p_i
    0    = |p_i|^2 - 1

This is the index-3 form. The Test Set integrates the index-2 form with a
second multiplier mu_i (p_i' = q_i + 2 mu_i p_i, 0 = 2 p_i . q_i): that is
the `ggl1` formulation `dae` derives from this model, 8N unknowns (160 for
N = 20). The start is the Test Set's: the points on four circles of
latitude (the angles below), at rest; the multipliers are left to
consistent initialisation. No reference values are written: the Test Set
publishes them for N = 20 only, at t = 1000.

Usage: scripts/fekete.py N OUT_STEM   (writes OUT_STEM.dae and OUT_STEM.toml)
"""
import math
import os
import sys


def start(n):
    """The Test Set's starting points, extended by cycling its four circles when N != 20."""
    circles = [  # (count, longitude offset, latitude)
        (3, math.pi / 13, 3 * math.pi / 8),
        (7, math.pi / 29, math.pi / 8),
        (6, math.pi / 7, -2 * math.pi / 15),
        (4, math.pi / 17, -15 * math.pi / 32),
    ]
    pts = []
    if n == 20:
        for count, off, beta in circles:
            for k in range(1, count + 1):
                a = 2 * math.pi * k / count + off
                pts.append((math.cos(a) * math.cos(beta), math.sin(a) * math.cos(beta), math.sin(beta)))
    else:  # a spiral: distinct points for any N
        for i in range(n):
            z = 1 - (2 * i + 1) / n
            r = math.sqrt(1 - z * z)
            a = i * math.pi * (3 - math.sqrt(5))
            pts.append((r * math.cos(a), r * math.sin(a), z))
    return pts


def model(n):
    idx = range(1, n + 1)
    diff = [f"{c}{i}" for c in "xyzuvw" for i in idx]
    lines = [
        f"/// The IVP Test Set's Fekete problem with {n} points (written by scripts/fekete.py).",
        f"pub Fekete{n} {{",
        "    parameters { alpha = 0.5 }",
        "    differential { " + ", ".join(diff) + " }",
        "    algebraic { " + ", ".join(f"la{i}" for i in idx) + " }",
        "    definitions {",
    ]
    for i in idx:
        for j in range(i + 1, n + 1):
            lines.append(f"        r{i}_{j} = (x{i} - x{j})^2 + (y{i} - y{j})^2 + (z{i} - z{j})^2;")
    lines += ["    }", "    equations {"]
    for i in idx:
        for c, v in zip("xyz", "uvw"):
            lines.append(f"        der({c}{i}) = {v}{i};")
    for i in idx:
        for c, v in zip("xyz", "uvw"):
            terms = []
            for j in idx:
                if j != i:
                    r = f"r{min(i, j)}_{max(i, j)}"
                    terms.append(f"({c}{i} - {c}{j})/{r}")
            lines.append(f"        der({v}{i}) = " + " + ".join(terms) + f" - alpha*{v}{i} + 2*la{i}*{c}{i};")
    for i in idx:
        lines.append(f"        0 = x{i}^2 + y{i}^2 + z{i}^2 - 1;")
    lines += ["    }", "}"]
    return "\n".join(lines) + "\n"


def scene(n, stem):
    pts = start(n)
    lines = [
        f"# The IVP Test Set's Fekete problem, {n} points (scripts/fekete.py {n} {stem}).",
        "# No reference: the run measures work and set-up only.",
        f'name = "fekete{n}"',
        f'model = "{os.path.basename(stem)}.dae"',
        "",
        "[initial]",
    ]
    for i, p in enumerate(pts, 1):
        for c, val in zip("xyz", p):
            lines.append(f"{c}{i} = {val!r}")
    for i in range(1, n + 1):
        for v in "uvw":
            lines.append(f"{v}{i} = 0.0")
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

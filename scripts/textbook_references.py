#!/usr/bin/env python3
"""Reference tables of the textbook DAEs of issue 23 (scenes/*_reference.csv).

    scripts/textbook_references.py            # write the CSVs beside the scenes
    scripts/textbook_references.py --check    # also verify every closed form

Each closed form is the one named in the doc comment of its model
(scenes/<name>.dae), written out below and evaluated at 50 significant
digits with mpmath at the scene's check times; the CSVs keep 25 digits. With
`--check`, sympy substitutes each closed form into every equation of its
model, as the model file writes it, and asserts that each residual
simplifies to zero identically in t (and, for the CSTR, that the start is
the closed form at t = 0). Nothing here comes from a run of dae.

The transistor amplifier's reference is not computed: it is the IVP Test
Set's published solution at t = 0.2 (`solut` in transamp.f), copied into
scenes/transamp_reference.csv by hand.

Needs python3 with mpmath and (for --check) sympy.
"""
import sys
from pathlib import Path

import mpmath as mp

mp.mp.dps = 50
SCENES = Path(__file__).resolve().parent.parent / "scenes"


def times(end, step, start=0):
    """start + k*step, k = 1 .. (end-start)/step, exactly (as decimal strings)."""
    n = int(round((end - start) / step))
    return [mp.mpf(start) + k * mp.mpf(str(step)) for k in range(1, n + 1)]


# ---------------------------------------------------------------- closed forms
# Each returns a dict name -> value at t (mpmath), in the model's names.


def linear_chain(t):
    return {"x1": mp.sin(t), "x2": mp.cos(t), "x3": -mp.sin(t)}


CSTR = dict(k1=1, k2=1, k3=1, k4=1, k5=1, c0=1, tf0=1)


def cstr(t):
    p = {k: mp.mpf(v) for k, v in CSTR.items()}
    u = mp.mpf(1) / 2 + mp.sin(t) / 10
    du = mp.cos(t) / 10
    ddu = -mp.sin(t) / 10
    r = p["k1"] * (p["c0"] - u) - du
    dr = -p["k1"] * du - ddu
    # T = k4 / ln(k5 u / R); T' by the chain rule.
    q = p["k5"] * u / r
    dq = p["k5"] * (du * r - u * dr) / r**2
    temp = p["k4"] / mp.log(q)
    dtemp = -p["k4"] * dq / (q * mp.log(q) ** 2)
    tc = temp + (dtemp - p["k1"] * (p["tf0"] - temp) - p["k2"] * r) / p["k3"]
    return {"C": u, "T": temp, "R": r, "TC": tc}


MNA = dict(c1=1, c2=1, r1=1, r2=1, v0=1, w=1)


def mna_cv_loop(t):
    p = {k: mp.mpf(v) for k, v in MNA.items()}
    a = 1 / ((p["r1"] + p["r2"]) * (p["c1"] + p["c2"]))
    b = p["c1"] / (p["c1"] + p["c2"])
    w, v0 = p["w"], p["v0"]
    bb = b * w**2 * v0 / (w**2 + a**2)
    aa = a * bb / w
    e1 = v0 * mp.sin(w * t)
    de1 = v0 * w * mp.cos(w * t)
    e2 = aa * (mp.cos(w * t) - mp.exp(-a * t)) + bb * mp.sin(w * t)
    de2 = aa * (-w * mp.sin(w * t) + a * mp.exp(-a * t)) + bb * w * mp.cos(w * t)
    e3 = p["r2"] * e2 / (p["r1"] + p["r2"])
    jv = -p["c1"] * (de1 - de2)
    return {"e1": e1, "e2": e2, "e3": e3, "jv": jv}


GHP_ETA = 1


def gear_hsu_petzold(t):
    y2 = mp.sin(t) + mp.exp(-t)
    y1 = mp.exp(-t) - GHP_ETA * t * y2
    return {"y1": y1, "y2": y2}


def jay_index2(t):
    return {"y1": mp.exp(t), "y2": mp.exp(-2 * t), "z": mp.exp(2 * t)}


# (scene, closed form, column order, check times, what the CSV says)
TABLES = [
    (
        "linear_chain",
        linear_chain,
        ["x1", "x2", "x3"],
        times(10, 0.5),
        "x1 = sin t, x2 = cos t, x3 = -sin t",
    ),
    (
        "cstr",
        cstr,
        ["C", "T", "R", "TC"],
        times(1, 0.1),
        "C = u = 1/2 + sin(t)/10, R = k1 (c0 - u) - u', T = k4 / ln(k5 u / R), "
        "TC = T + (T' - k1 (tf0 - T) - k2 R) / k3; k1..k5 = c0 = tf0 = 1",
    ),
    (
        "mna_cv_loop",
        mna_cv_loop,
        ["e1", "e2", "e3", "jv"],
        times(10, 0.5),
        "e1 = v0 sin wt, e2 = A (cos wt - exp(-a t)) + B sin wt, e3 = r2 e2/(r1 + r2), "
        "jv = -c1 (e1' - e2'); a = 1/((r1 + r2)(c1 + c2)), b = c1/(c1 + c2), "
        "B = b w^2 v0/(w^2 + a^2), A = a B / w; all constants 1",
    ),
    (
        "gear_hsu_petzold",
        gear_hsu_petzold,
        ["y1", "y2"],
        times(3, 0.25),
        "y2 = f2 - f1' = sin t + exp(-t), y1 = f1 - eta t y2 = exp(-t) - t y2; eta = 1",
    ),
    (
        "jay_index2",
        jay_index2,
        ["y1", "y2", "z"],
        times(1, 0.1),
        "y1 = exp(t), y2 = exp(-2t), z = exp(2t) (Jay 1993, Example 7)",
    ),
]


def write_tables():
    for scene, form, cols, ts, what in TABLES:
        lines = [
            f"# {scene}: closed form at the check times, evaluated by "
            "scripts/textbook_references.py",
            f"# with mpmath at 50 digits (25 kept): {what}.",
            "t," + ",".join(cols),
        ]
        for t in ts:
            vals = form(t)
            row = [mp.nstr(t, 10)] + [mp.nstr(vals[c], 25) for c in cols]
            lines.append(",".join(row))
        path = SCENES / f"{scene}_reference.csv"
        path.write_text("\n".join(lines) + "\n")
        print(f"wrote {path} ({len(ts)} times)")


# ---------------------------------------------------------------- sympy check


def check_closed_forms():
    import sympy as sp

    t = sp.symbols("t", real=True)
    D = lambda e: sp.diff(e, t)  # noqa: E731

    def zero(name, residuals):
        for i, r in enumerate(residuals):
            s = sp.simplify(sp.expand(r))
            assert s == 0, f"{name}: residual {i} = {s}"
            # and numerically at a few points, at 40 digits
            for tv in (sp.Rational(1, 3), sp.Rational(7, 10), sp.Integer(2)):
                v = sp.N(r.subs(t, tv), 40)
                assert abs(v) < sp.Float("1e-35"), f"{name}: residual {i} at {tv} = {v}"
        print(f"{name}: {len(residuals)} equations hold identically")

    # linear chain
    x1, x2, x3 = sp.sin(t), sp.cos(t), -sp.sin(t)
    zero("linear_chain", [D(x1) - x2, D(x2) - x3, x1 - sp.sin(t)])

    # CSTR: the model's equations with the closed form of the docstring
    k1, k2, k3, k4, k5, c0, tf0 = (sp.Integer(CSTR[k]) for k in ("k1", "k2", "k3", "k4", "k5", "c0", "tf0"))
    u = sp.Rational(1, 2) + sp.sin(t) / 10
    C = u
    R = k1 * (c0 - u) - D(u)
    T = k4 / sp.log(k5 * u / R)
    TC = T + (D(T) - k1 * (tf0 - T) - k2 * R) / k3
    zero(
        "cstr",
        [
            D(C) - (k1 * (c0 - C) - R),
            D(T) - (k1 * (tf0 - T) + k2 * R - k3 * (T - TC)),
            R - k5 * sp.exp(-k4 / T) * C,
            C - (sp.Rational(1, 2) + sp.sin(t) / 10),
        ],
    )
    # R > 0 and k5 C > R on [0, 1] (T finite and positive there)
    for k in range(0, 101):
        tv = sp.Rational(k, 100)
        rv, qv = sp.N(R.subs(t, tv)), sp.N((k5 * C / R).subs(t, tv))
        assert rv > 0 and qv > 1, (tv, rv, qv)

    # MNA
    c1, c2, r1, r2, v0, w = (sp.Integer(MNA[k]) for k in ("c1", "c2", "r1", "r2", "v0", "w"))
    a = 1 / ((r1 + r2) * (c1 + c2))
    b = c1 / (c1 + c2)
    B = b * w**2 * v0 / (w**2 + a**2)
    A = a * B / w
    e1 = v0 * sp.sin(w * t)
    e2 = A * (sp.cos(w * t) - sp.exp(-a * t)) + B * sp.sin(w * t)
    e3 = r2 * e2 / (r1 + r2)
    jv = -c1 * (D(e1) - D(e2))
    zero(
        "mna_cv_loop",
        [
            c1 * D(e1) - c1 * D(e2) + jv,
            c1 * D(e2) - c1 * D(e1) + c2 * D(e2) + (e2 - e3) / r1,
            (e3 - e2) / r1 + e3 / r2,
            e1 - v0 * sp.sin(w * t),
        ],
    )
    assert e2.subs(t, 0) == 0 and e1.subs(t, 0) == 0

    # Gear-Hsu-Petzold
    eta = sp.Integer(GHP_ETA)
    y2 = sp.sin(t) + sp.exp(-t)
    y1 = sp.exp(-t) - eta * t * y2
    zero(
        "gear_hsu_petzold",
        [y1 + eta * t * y2 - sp.exp(-t), D(y1) + eta * t * D(y2) + (1 + eta) * y2 - sp.sin(t)],
    )

    # Jay 1993, Example 7, and the two roots of the hidden constraint at t = 0
    y1, y2, z = sp.exp(t), sp.exp(-2 * t), sp.exp(2 * t)
    zero(
        "jay_index2",
        [D(y1) - y1 * y2**2 * z**2, D(y2) - (y1**2 * y2**2 - 3 * y2**2 * z), y1**2 * y2 - 1],
    )
    zz = sp.symbols("z")
    hidden = 2 * zz**2 - 3 * zz + 1  # d/dt(y1^2 y2) at y1 = y2 = 1
    assert sorted(sp.solve(hidden, zz)) == [sp.Rational(1, 2), 1]
    print("jay_index2: the hidden constraint at t = 0 has the roots z = 1/2 and z = 1")


if __name__ == "__main__":
    write_tables()
    if "--check" in sys.argv[1:]:
        check_closed_forms()

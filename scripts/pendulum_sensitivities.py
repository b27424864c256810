#!/usr/bin/env python3
"""Exact parametric sensitivities of the simple pendulum (issue 25, done-when 2).

The pendulum of `scenes/pendulum.dae` (m = 1, rod length l, gravity g, the
mass released at rest from the horizontal, x = l, y = 0) in closed form:
with theta the angle from the downward vertical, x = l sin(theta),
y = -l cos(theta), and theta(t) = Theta(tau), tau = t sqrt(g / l), where
Theta'' = -sin(Theta), Theta(0) = pi/2, Theta'(0) = 0 has the classical
solution (Whittaker & Watson §22.8; Lawden, "Elliptic functions and
applications", §5.2)

    sin(Theta / 2) = k sn(K - tau | k^2),   k = sin(pi/4),  K = K(k^2),

and Theta'(tau) = -2 k cn dn / cos(Theta / 2) (the derivative of the same
identity). Velocities: v = l cos(Theta) Theta' sqrt(g/l), w = l sin(Theta)
Theta' sqrt(g/l).

The sensitivities d{x,y,v,w}/d{g,l} are derivatives of this closed form,
taken by mpmath's high-precision numerical differentiation at 60 digits
(the closed form is analytic in g and l near the scene's values: K, k do
not depend on them), and printed to 17 significant digits. The release
from the horizontal is kept as l changes (x(0) = l): that is what a
consistent initial sensitivity of the scene's start x = 1 = l, y = 0 gives
(the constraint x^2 + y^2 = l^2 differentiated in l).

Usage: scripts/pendulum_sensitivities.py > data/pendulum_sensitivities.csv
"""
import mpmath as mp

mp.mp.dps = 60
G0 = mp.mpf("13.7503716373294544")
L0 = mp.mpf(1)
K_MOD = mp.sin(mp.pi / 4)
M = K_MOD**2
K = mp.ellipk(M)


def state(t, g, l):
    """x, y, v, w at time t for gravity g and length l."""
    tau = t * mp.sqrt(g / l)
    u = K - tau
    sn, cn, dn = (mp.ellipfun(f, u, m=M) for f in ("sn", "cn", "dn"))
    half = mp.asin(K_MOD * sn)
    theta = 2 * half
    dtheta = -2 * K_MOD * cn * dn / mp.cos(half)  # dTheta/dtau
    rate = mp.sqrt(g / l)
    return (
        l * mp.sin(theta),
        -l * mp.cos(theta),
        l * mp.cos(theta) * dtheta * rate,
        l * mp.sin(theta) * dtheta * rate,
    )


def main():
    names = ("x", "y", "v", "w")
    print("# Exact sensitivities of the pendulum released horizontally "
          "(scripts/pendulum_sensitivities.py; closed form by Jacobi elliptic functions,")
    print("# derivatives by mpmath at 60 digits). g = 13.7503716373294544, l = 1, m = 1.")
    print("t,parameter,unknown,value,derivative")
    for t in (2, 4, 20):
        t = mp.mpf(t)
        values = state(t, G0, L0)
        # check: the constraint holds and the energy is that of the release
        x, y, v, w = values
        assert abs(x * x + y * y - L0 * L0) < mp.mpf(10) ** -50
        assert abs((v * v + w * w) / 2 + G0 * y) < mp.mpf(10) ** -45
        for p in ("g", "l"):
            for i, name in enumerate(names):
                if p == "g":
                    d = mp.diff(lambda gg: state(t, gg, L0)[i], G0)
                else:
                    d = mp.diff(lambda ll: state(t, G0, ll)[i], L0)
                print(f"{mp.nstr(t, 3)},{p},{name},{mp.nstr(values[i], 17)},{mp.nstr(d, 17)}")


if __name__ == "__main__":
    main()

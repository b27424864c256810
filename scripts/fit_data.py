#!/usr/bin/env python3
"""Observations for the parameter-fit example (issue 25, done-when 4).

The pendulum of `scenes/pendulum.dae` (m = 1) with true gravity G_TRUE and
rod length L_TRUE, released at rest from the horizontal (x = l, y = 0), in
closed form: with Theta the angle from the downward vertical, x = l sin
Theta, y = -l cos Theta, Theta(t) = Th(tau), tau = t sqrt(g / l), where
Th'' = -sin Th, Th(0) = pi/2, Th'(0) = 0 has the classical solution
(Whittaker & Watson §22.8; Lawden, "Elliptic functions and applications",
§5.2)

    sin(Th / 2) = k sn(K - tau | k^2),   k = sin(pi/4),  K = K(k^2)

(the same closed form as scripts/pendulum_sensitivities.py). The positions
are evaluated with mpmath at 40 digits at t = 0.1, 0.2, ..., 5.0 (50
times, about two periods) and printed to 17 significant digits; only the
horizontal coordinate x is observed: the observations add to it
independent Gaussian noise of standard deviation SIGMA from Python's
Mersenne Twister seeded with SEED (random.Random(SEED).gauss, in time
order), rounded to 1e-9 m. The exact y is printed beside x so that a
reader can check every exact position lies on the circle of radius l.

Usage: scripts/fit_data.py > data/fit_pendulum.csv
"""
import random

import mpmath as mp

mp.mp.dps = 40
G_TRUE = mp.mpf("9.81")
L_TRUE = mp.mpf(1)
SIGMA = 0.01
SEED = 25
TIMES = [mp.mpf(k) / 10 for k in range(1, 51)]
K_MOD = mp.sin(mp.pi / 4)
M = K_MOD**2
K = mp.ellipk(M)


def position(t, g, l):
    """x, y at time t for gravity g and length l."""
    tau = t * mp.sqrt(g / l)
    sn = mp.ellipfun("sn", K - tau, m=M)
    theta = 2 * mp.asin(K_MOD * sn)
    return l * mp.sin(theta), -l * mp.cos(theta)


def main():
    rng = random.Random(SEED)
    print("# Noisy observations of the pendulum's x(t) for examples/fit_pendulum.rs and")
    print("# tests/fit.rs, written by scripts/fit_data.py: exact positions from the Jacobi-elliptic")
    print(f"# closed form (mpmath, 40 digits), g = {G_TRUE}, l = {L_TRUE}, m = 1, released at rest at")
    print(f"# x = l, y = 0; x_obs = x_exact + N(0, sigma^2), sigma = {SIGMA}, seed {SEED} (y not observed).")
    print("t,x_exact,y_exact,x_obs")
    for t in TIMES:
        x, y = position(t, G_TRUE, L_TRUE)
        # check: on the circle
        assert abs(x * x + y * y - L_TRUE**2) < mp.mpf(10) ** -35
        xo = round(float(x) + rng.gauss(0.0, SIGMA), 9)
        print(f"{mp.nstr(t, 3)},{mp.nstr(x, 17)},{mp.nstr(y, 17)},{xo:.9f}")


if __name__ == "__main__":
    main()

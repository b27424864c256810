//! Radau IIA (s = 3), the tableau of [`crate::radau5`] and
//! [`crate::odradau`], as the collocation engine's values
//! ([`crate::collocation`]).

use crate::collocation::tableau::{Collocation, EndPoint, NewtonStop, Policy, StepRule, Tableau};

/// Radau IIA of order 5 (RADAU5's coefficients).
pub(crate) struct RadauIIA;

impl Collocation for RadauIIA {
    const TABLEAU: Tableau = Tableau {
        c: C,
        ainv: AINV,
        gamma: GAMMA,
        alpha: ALPHA,
        beta: BETA,
        t: T,
        ti: TI,
        dd: DD,
        end: EndPoint::LastStage,
    };
    const POLICY: Policy = Policy {
        step: StepRule::Proposed,
        newton: NewtonStop::Tolerance,
        max_newton: super::NIT,
        thet: super::THET,
        tolerance_factor: super::tolerance_factor,
    };

    #[inline(always)]
    fn divided_differences(z1: f64, z2: f64, z3: f64) -> [f64; 3] {
        divided_differences(z1, z2, z3)
    }

    #[inline(always)]
    fn polynomial_increment(d: &[f64; 3], s: f64) -> f64 {
        polynomial_increment(d, s)
    }

    #[inline(always)]
    fn end_slope(z: [f64; 3], _d: &[f64; 3]) -> f64 {
        AINV[2][0] * z[0] + AINV[2][1] * z[1] + AINV[2][2] * z[2]
    }
}

/// Nodes `c₁ = (4 − √6)/10`, `c₂ = (4 + √6)/10`, `c₃ = 1`.
const C1: f64 = 0.1550510257216822;
const C2: f64 = 0.6449489742783178;
const C: [f64; 3] = [C1, C2, 1.0];
const C1M1: f64 = C1 - 1.0;
const C2M1: f64 = C2 - 1.0;
const C1MC2: f64 = C1 - C2;

/// `A⁻¹` of the Radau IIA(3) matrix `A` (the stage derivatives of the
/// collocation polynomial are `(1/h) A⁻¹ Z`).
const AINV: [[f64; 3]; 3] = [
    [3.224744871391589, 1.1678400846904056, -0.25319726474218085],
    [-3.5678400846904057, 0.775255128608411, 1.0531972647421808],
    [5.531972647421808, -7.531972647421808, 5.0],
];

/// Real eigenvalue `γ = 1/γ₀` of `A⁻¹`, `γ₀ = (6 + 81^(1/3) − 9^(1/3))/30`.
const GAMMA: f64 = 3.637834252744496;
/// Complex pair `α ± iβ` of eigenvalues of `A⁻¹`.
const ALPHA: f64 = 2.6810828736277523;
const BETA: f64 = 3.0504301992474105;

/// `T` with `T⁻¹ A⁻¹ T = diag(γ, [[α, −β], [β, α]])`, normalised as in
/// HW IV.8 (`T₃₂ = 1`, `T₃₃ = 0`).
const T: [[f64; 3]; 3] = [
    [
        0.09123239487089295,
        -0.1412552950209542,
        -0.030029194105147424,
    ],
    [0.241717932707107, 0.20412935229379994, 0.3829421127572619],
    [0.966048182615093, 1.0, 0.0],
];
/// `T⁻¹`.
const TI: [[f64; 3]; 3] = [
    [4.325579890063155, 0.33919925181580984, 0.5417705399358749],
    [
        -4.178718591551905,
        -0.32768282076106237,
        0.47662355450055044,
    ],
    [-0.5028726349457868, 2.571926949855605, -0.5960392048282249],
];

/// `d_i = e_i/γ₀` of the embedded error estimate (HW IV.8 (8.20)):
/// `(−(13 + 7√6)/3, (−13 + 7√6)/3, −1/3)`.
const DD: [f64; 3] = [-10.048809399827416, 1.382142733160749, -1.0 / 3.0];

/// Divided differences `d₁, d₂, d₃` of the collocation polynomial of a step,
/// relative to its end value, on the nodes `s = 0, c₂ − 1, c₁ − 1, −1` of
/// `s = (t − t_{n+1})/h`, where it takes the values `0, Z₂ − Z₃, Z₁ − Z₃,
/// −Z₃` (RADAU5's `CONT`).
fn divided_differences(z1: f64, z2: f64, z3: f64) -> [f64; 3] {
    let d1 = (z2 - z3) / C2M1;
    let d12 = (z1 - z2) / C1MC2;
    let d2 = (d12 - d1) / C1M1;
    let d23 = (d12 - z1 / C1) / C2;
    [d1, d2, d2 - d23]
}

/// `u(s) = s (d₁ + (s − c₂ + 1)(d₂ + (s − c₁ + 1) d₃))`: the polynomial minus
/// its end value.
fn polynomial_increment(d: &[f64; 3], s: f64) -> f64 {
    s * (d[0] + (s - C2M1) * (d[1] + (s - C1M1) * d[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn radau_a() -> [[f64; 3]; 3] {
        let s6 = 6f64.sqrt();
        [
            [
                (88.0 - 7.0 * s6) / 360.0,
                (296.0 - 169.0 * s6) / 1800.0,
                (-2.0 + 3.0 * s6) / 225.0,
            ],
            [
                (296.0 + 169.0 * s6) / 1800.0,
                (88.0 + 7.0 * s6) / 360.0,
                (-2.0 - 3.0 * s6) / 225.0,
            ],
            [(16.0 - s6) / 36.0, (16.0 + s6) / 36.0, 1.0 / 9.0],
        ]
    }

    #[test]
    fn coefficients_are_consistent() {
        crate::collocation::tableau::check::transformation::<RadauIIA>(&radau_a());
        assert!((C1 - (4.0 - 6f64.sqrt()) / 10.0).abs() < 1e-16);
        assert!((DD[0] + (13.0 + 7.0 * 6f64.sqrt()) / 3.0).abs() < 1e-14);
        assert!((DD[1] - (-13.0 + 7.0 * 6f64.sqrt()) / 3.0).abs() < 1e-14);
        let g0 = (6.0 + 81f64.cbrt() - 9f64.cbrt()) / 30.0;
        assert!((GAMMA - 1.0 / g0).abs() < 1e-14);
    }

    #[test]
    fn collocation_polynomial_interpolates_the_stages() {
        let (y0, z) = (2.0, [0.3, -0.7, 1.1]);
        let d = divided_differences(z[0], z[1], z[2]);
        let p = |s: f64| y0 + z[2] + polynomial_increment(&d, s);
        assert!((p(0.0) - (y0 + z[2])).abs() < 1e-14);
        assert!((p(C2M1) - (y0 + z[1])).abs() < 1e-14);
        assert!((p(C1M1) - (y0 + z[0])).abs() < 1e-14);
        assert!((p(-1.0) - y0).abs() < 1e-14);
        // Its derivative at s = 0 is h Y'_3 = (A⁻¹ Z)_3.
        let eps = 1e-6;
        let slope = (p(eps) - p(-eps)) / (2.0 * eps);
        let yd3: f64 = (0..3).map(|j| AINV[2][j] * z[j]).sum();
        assert!((slope - yd3).abs() < 1e-8, "{slope} vs {yd3}");
    }
}

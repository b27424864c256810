//! What the collocation engine is told about a method: three values and
//! the interpolation of its collocation polynomial.
//!
//! - the [`Tableau`]: the coefficients of a three-stage collocation method
//!   whose `A⁻¹` has one real eigenvalue `γ` and a complex pair `α ± iβ`
//!   (so that RADAU5's transformed Newton iteration, one real and one
//!   complex system of size `N`, applies), the embedded error estimate,
//!   and how a step ends ([`EndPoint`]: at the last stage of a stiffly
//!   accurate method, or at the polynomial's end value made consistent by
//!   a projection);
//! - the [`Policy`]: the step-size rule ([`StepRule`]), the Newton
//!   iteration's stopping rule ([`NewtonStop`]) and budget, Jacobian reuse,
//!   and the tolerance map;
//! - the stage solve (square LU or projected least squares), chosen per
//!   run: [`super::solve::StageSolve`].
//!
//! Radau IIA ([`crate::radau5`], also [`crate::odradau`] with the least-
//! squares stage solve) and Gauss–Legendre ([`crate::gauss`]) are the two
//! implementations of [`Collocation`].

/// The coefficients of a three-stage collocation method (see the
/// [module documentation](self)).
pub(crate) struct Tableau {
    /// Nodes `c_i`.
    pub(crate) c: [f64; 3],
    /// `A⁻¹`: the stage derivatives are `(1/h) A⁻¹ Z`.
    pub(crate) ainv: [[f64; 3]; 3],
    /// Real eigenvalue of `A⁻¹`.
    pub(crate) gamma: f64,
    /// Complex pair `α ± iβ` of eigenvalues of `A⁻¹`.
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    /// `T` with `T⁻¹ A⁻¹ T = diag(γ, [[α, −β], [β, α]])`, normalised so
    /// that `T₃₂ = 1` and `T₃₃ = 0` (the kernels rely on it).
    pub(crate) t: [[f64; 3]; 3],
    /// `T⁻¹`.
    pub(crate) ti: [[f64; 3]; 3],
    /// `d_i = e_i/γ₀` of the embedded error estimate `err = (γ/h E₀ −
    /// J)⁻¹ [f(t_n, y_n) + E (1/h) Σ d_i Z_i]`, `γ₀ = 1/γ` (HW IV.8
    /// (8.19)–(8.20)).
    pub(crate) dd: [f64; 3],
    /// Where a step ends.
    pub(crate) end: EndPoint,
}

/// Where a step of a collocation method ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum EndPoint {
    /// Stiffly accurate (`c₃ = 1`): `y_{n+1} = y_n + Z₃`, consistent as
    /// the last stage is.
    LastStage,
    /// `y_{n+1} = y_n + Σ e_i Z_i` (`e = bᵀA⁻¹`), the collocation
    /// polynomial's end value, which meets the algebraic rows only up to
    /// the interpolation error: it is projected onto them after every
    /// step, and so are the values reported at output times (see
    /// [`crate::gauss`]).
    Projected([f64; 3]),
}

impl EndPoint {
    /// Whether the end point (and the output) is projected.
    pub(crate) const fn projected(self) -> bool {
        matches!(self, EndPoint::Projected(_))
    }
}

/// How the engine runs a method: its step-size rule, Newton iteration and
/// tolerance map (see the [module documentation](self)).
pub(crate) struct Policy {
    /// How the error estimate becomes the next step size.
    pub(crate) step: StepRule,
    /// When the Newton iteration stops.
    pub(crate) newton: NewtonStop,
    /// Newton iterations allowed per step attempt (RADAU5's `NIT`), also
    /// the reference of the controller's safety factor.
    pub(crate) max_newton: usize,
    /// The Jacobian is kept for the next step while the observed
    /// contraction factor stays at or below this (RADAU5's `THET`).
    pub(crate) thet: f64,
    /// The factor applied to `rtol_i` and `atol_i` (the tolerance map) of
    /// the unknown with these tolerances.
    pub(crate) tolerance_factor: fn(f64, f64) -> f64,
}

/// How the error estimate becomes the next step size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StepRule {
    /// RADAU5's controller proposes every step (HW IV.8 (8.21)–(8.25)).
    Proposed,
    /// The step size is held constant until the error test asks for a
    /// change (a symmetric method, see `control::Hold`).
    Held,
}

/// When the simplified Newton iteration of a step attempt stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum NewtonStop {
    /// RADAU5's bound, relative to the internal tolerance; a slowly
    /// converging iteration is abandoned early for a shorter step.
    Tolerance,
    /// Towards round-off, whatever the tolerance (a symmetric method,
    /// see [`crate::gauss`]): the bound is `units` units of round-off, or
    /// `drift · tol · (h/T)²` (`T` the horizon) where that is larger; the
    /// iteration is not abandoned early, it runs to `max_newton`.
    RoundOff {
        /// The bound in units of round-off.
        units: f64,
        /// The coefficient of the drift bound.
        drift: f64,
    },
}

impl NewtonStop {
    /// Whether a slowly converging iteration is abandoned early.
    pub(crate) const fn slow_exit(self) -> bool {
        matches!(self, NewtonStop::Tolerance)
    }
}

/// A three-stage collocation method: its [`Tableau`] and [`Policy`] as
/// values, and the Newton form of its collocation polynomial.
///
/// The collocation polynomial of a step is stored in Newton form on four
/// nodes `0, ν₁, ν₂, ν₃` of `s = (t − t_{n+1})/h` (the end point first,
/// where it is `0` relative to the end value), as `cont = [y_{n+1}, d₁, d₂,
/// d₃]`; the three functions below are the method's (its nodes), called in
/// the engine's innermost loops.
pub(crate) trait Collocation: 'static {
    /// The coefficients.
    const TABLEAU: Tableau;
    /// How the engine runs the method.
    const POLICY: Policy;

    /// Divided differences `d₁, d₂, d₃` of the collocation polynomial
    /// relative to its end value, from the stage increments.
    fn divided_differences(z1: f64, z2: f64, z3: f64) -> [f64; 3];

    /// The polynomial minus its end value at `s`.
    fn polynomial_increment(d: &[f64; 3], s: f64) -> f64;

    /// `h y'(t_{n+1})` from the stage increments and the divided
    /// differences.
    fn end_slope(z: [f64; 3], d: &[f64; 3]) -> f64;
}

/// The collocation polynomial `cont` (`4N`) of the step `[t − h, t]` at
/// `tau` into `out`.
pub(super) fn dense<K: Collocation>(
    n: usize,
    cont: &[f64],
    tau: f64,
    t: f64,
    h: f64,
    out: &mut [f64],
) {
    let s = (tau - t) / h;
    for k in 0..n {
        let d = [cont[n + k], cont[2 * n + k], cont[3 * n + k]];
        out[k] = cont[k] + K::polynomial_increment(&d, s);
    }
}

/// What every tableau's constants must satisfy, for the tests of each.
#[cfg(test)]
pub(crate) mod check {
    use super::Collocation;

    /// A 3 × 3 matrix.
    pub(crate) type M3 = [[f64; 3]; 3];

    fn mul(a: &M3, b: &M3) -> M3 {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    fn assert_close(a: &M3, b: &M3, tol: f64) {
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (a[i][j] - b[i][j]).abs() < tol,
                    "({i},{j}): {} vs {}",
                    a[i][j],
                    b[i][j]
                );
            }
        }
    }

    /// `K`'s constants against its matrix `a`: `AINV` inverts it, `T` and
    /// `TI` are inverses, `T⁻¹ A⁻¹ T = diag(γ, [[α, −β], [β, α]])`, the
    /// row sums of `a` are the nodes, and `T₃₂ = 1`, `T₃₃ = 0` (the
    /// kernels' normalisation).
    pub(crate) fn transformation<K: Collocation>(a: &M3) {
        let i3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_close(&mul(a, &K::TABLEAU.ainv), &i3, 1e-14);
        assert_close(&mul(&K::TABLEAU.t, &K::TABLEAU.ti), &i3, 1e-14);
        let lambda = mul(&mul(&K::TABLEAU.ti, &K::TABLEAU.ainv), &K::TABLEAU.t);
        let (g, al, be) = (K::TABLEAU.gamma, K::TABLEAU.alpha, K::TABLEAU.beta);
        assert_close(
            &lambda,
            &[[g, 0.0, 0.0], [0.0, al, -be], [0.0, be, al]],
            1e-13,
        );
        for (row, c) in a.iter().zip(K::TABLEAU.c) {
            assert!((row.iter().sum::<f64>() - c).abs() < 1e-15);
        }
        assert_eq!((K::TABLEAU.t[2][1], K::TABLEAU.t[2][2]), (1.0, 0.0));
    }
}

//! Gauss–Legendre collocation of order 6 for index-1 DAEs: a symmetric
//! method, held at a constant step, for long horizons.
//!
//! # Why
//!
//! Over 1000 periods of the pendulum (Scenario S02) the error of
//! [`crate::radau5`] is a phase error that grows like `t²`: Radau IIA damps
//! (`|R(iy)| < 1`), the energy drifts linearly, and with it the period. A
//! symmetric method applied with a constant step to a reversible problem
//! has no such drift; its phase error grows like `t` (Hairer, Lubich &
//! Wanner, *Geometric Numerical Integration*, XI). Gauss–Legendre with
//! three stages is symmetric, of the highest order a three-stage method
//! can have (6, against Radau IIA's 5), A-stable with `|R(iy)| = 1`, and
//! its `A⁻¹` has — like Radau IIA's — one real eigenvalue and a complex
//! pair: the whole linear algebra of [`crate::radau5`] (one real and one
//! complex system of size `N` per Newton iteration, RADAU5's Jacobian and
//! factorisation reuse, the straight-line kernels) serves it unchanged.
//! On S02 it reaches the errors of `radau5` with a tenth of its steps
//! (BENCHMARKS.md §6d).
//!
//! # Discretisation
//!
//! The formulation `E(t, y) y' = f(t, y)` is discretised as in
//! [`crate::radau5`] — the collocation conditions `E(Y_i) Y'_i = f(t_n +
//! c_i h, Y_i)` at the nodes `c = 1/2 ∓ √15/10, 1/2` — except that the
//! method is not stiffly accurate: the step ends at the collocation
//! polynomial's value at `t_n + h`,
//!
//! ```text
//!     y_{n+1} = y_n + Σ_i d_i Z_i ,   d = bᵀA⁻¹ = (5/3, −4/3, 5/3) .
//! ```
//!
//! For an index-1 formulation the differential unknowns of the stages do
//! not depend on the algebraic unknowns of `y_n` (those are fixed by the
//! constraints at every stage) and keep the order 6 at the step points;
//! the algebraic ones are recomputed at each end point (below). The
//! symmetric method does not damp: formulations of index 2 or 3, whose
//! errors it would not control, are refused
//! ([`NotApplicable::IndexTooHigh`]). Of the pendulum's formulations `rcd0`
//! and `psi0` qualify; `rcd0` is the one to use. Its position constraint is
//! not among its rows, but `xv + yw` is a quadratic invariant of `rcd0`,
//! which Gauss–Legendre collocation keeps exactly, so nothing drifts.
//! `psi0`'s projected rows are not reversible in the same way: its energy
//! drifts and its error grows like that of a non-symmetric method.
//!
//! It is a method for oscillatory, non-stiff mechanical systems over long
//! horizons, not for stiff ones: `|R(∞)| = 1` damps nothing, and the held
//! step cannot follow a fast transient. On Andrews' squeezer it reaches the
//! end at 1e-4 … 1e-10 on `rcd0` and `mex0`, with 9.6–10 significant digits
//! from 1e-8 on (the arithmetic's limit on this problem; BENCHMARKS §11c).
//! In natural form (a state-dependent mass matrix, whose rcd0 the
//! solvers make semi-explicit at run time, `core/eliminate.rs`) it reaches
//! the end at 1e-4 … 1e-10 with 135–1 480 steps (radau5: 346–5 711).

//! # Step size: constant where it can be
//!
//! The embedded error estimate is RADAU5's construction for this tableau
//! (an order-3 formula with `b̂₀ = γ₀`, `γ₀ = 1/γ`; HW IV.8 (8.19)):
//!
//! ```text
//!     err = (γ/h E₀ − J)⁻¹ [ f(t_n, y_n) + E(y_n) (1/h) Σ_i d̂_i Z_i ] ,
//! ```
//!
//! measured with the index-scaled weights of [`crate::radau5`]. It is used
//! to keep the step constant, not to steer it step by step (see the
//! controller's `Hold`): the step is reviewed after a window of steps and
//! set so that the largest estimate of the window is 0.3; it is shortened
//! at once only when an estimate exceeds 0.8, and the window doubles when
//! a lengthening had to be taken back. On a periodic motion the step
//! settles within a period or two at what the hardest part of the orbit
//! needs and stays there, which is what keeps the method symmetric.
//!
//! # Tolerance map
//!
//! The estimate is `O(h⁴)` and the global error `O(h⁶)`; the error test
//! runs at `tol' = 0.25 tol^(2/3)` (see [`internal_tolerance`]), so that the
//! global error, `∝ h⁶ ∝ tol'^(3/2)`, is proportional to the user's
//! tolerance — RADAU5's own map is `0.1 tol^(2/3)`, for the same reason. On
//! the pendulum over 20 s the error is 0.4–1.1 times the tolerance from
//! `10⁻⁵` to `10⁻¹¹` (BENCHMARKS §6d).
//!
//! # The Newton iteration runs (almost) to round-off
//!
//! An iteration stopped at a tolerance leaves an error of one sign, step
//! after step, which a symmetric method does not forgive: on the pendulum's
//! rcd0 it made `xv + yw` — a quadratic invariant Gauss–Legendre keeps
//! exactly — drift linearly, the position quadratically and the phase like
//! `t³` (measured at `h = 1/160`: with a bound of 10 units of round-off
//! the error was 1.8·10⁻¹⁰, 1.9·10⁻⁷ and 1.9·10⁻⁴ after 20, 200 and
//! 2000 s; with 0.1 units 6·10⁻¹¹ after 200 s). A systematic error `δ` per step grows over `N = T/h` steps into
//! a phase error of order `N² δ`, so the iteration stops at
//!
//! ```text
//!     max( NEWTON_ROUND_OFF · u ,  NEWTON_DRIFT · tol · (h/T)² )
//! ```
//!
//! (weighted, `T` the horizon; [`NEWTON_ROUND_OFF`], [`NEWTON_DRIFT`]), or
//! when its increments have stopped contracting at a few hundred units of
//! round-off: near round-off over S02's 2000 s, some sweeps earlier over
//! S01's 20 s. It is not abandoned early for slow convergence; up to
//! [`MAX_NEWTON`] iterations are allowed. A step still costs about twice
//! the residual evaluations of a `radau5` step. With a leading matrix that
//! is not constant (`E(t)`, or `E(y)` as in `psi0`, `mex0`), the first
//! increment never ends the iteration, whatever the contraction carried
//! from the step before: the iteration matrix holds `E` of the Jacobian's
//! point, and on Gear–Hsu–Petzold's `rcd0` it contracts at 0.46, which a
//! stop after one increment turned into 1.6 digits at tol 1e-4.

//! # End points of index-1 formulations
//!
//! The algebraic unknowns at `y_{n+1}` (from `d` above, with `R(∞) = −1`)
//! would carry an error that alternates in sign from step to step and
//! inflates the error estimate; and they converge only with the stage
//! order unless they are recomputed from the algebraic rows (HW VI.1).
//! After each step Newton steps make the end point consistent:
//! `E(y_{n+1}) δ = 0` on the differential rows (the differential part is
//! kept) and `f_a(t, y_{n+1} + δ) = 0` linearised on the algebraic rows
//! (the constraint rows whose row of `E` is zero). For `rcd0` this
//! recomputes `λ` alone.
//!
//! With a constant `E`, the Jacobian the next step would take anyway is
//! taken at the end point before the projection, and one step solves rows
//! linear in the algebraic unknowns exactly (quadratically otherwise);
//! when the next step keeps an older Jacobian, `f` is evaluated again and
//! the step repeated until a correction is a thousandth of the tolerance.
//! One step with the Jacobian of the step's start was enough on the
//! pendulum, whose coefficient of `λ` does not change along the motion,
//! not on Pantelides' reactor (`rcd0`: the coefficient of `TC` changes by
//! a tenth over a step, which left `TC` 4.7·10⁻⁶ off at tol 1e-8 where
//! the differential unknowns were right to 3·10⁻¹¹) nor on Jay's
//! (`z²` in its constraint: `z` 2.6·10⁻⁷ off at 1e-9); now 4·10⁻¹¹ and
//! 4·10⁻¹⁰ (EXTREMES.md colloc13).
//!
//! # Dense output: projected the same way
//!
//! Between the step points the collocation polynomial meets the algebraic
//! rows at the nodes only and misses them elsewhere by its interpolation
//! error, `O(h⁴)` against the step points' `O(h⁷)`: with the long steps an
//! order-6 method takes, that was 100 times the tolerance on Andrews'
//! squeezer (`mex0` at tol 1e-7: position residual 1.7e-5 between steps).
//! The values reported at output times ([`crate::Options::output_times`],
//! [`crate::Integrator::advance_to`]) are therefore projected as the end point is
//! (the same factorised matrix, up to three simplified Newton steps with
//! `f` re-evaluated until a correction is a thousandth of the tolerance,
//! each counted in `residual_evals`): the position
//! residual of that run at `dae run`'s verification samples falls to
//! 3.2e-9. On the pendulum's `psi0` the outputs lie on the circle to
//! round-off; `rcd0`'s `λ` at the output times is the consistent one. The
//! stored dense output ([`crate::DenseOutput`], [`crate::Solution::at`])
//! and event location take the dense output unprojected: a polynomial
//! through projected values would miss the constraints between them, and
//! the projection needs the system, which a [`crate::Solution`] does not
//! hold. Ask for the times you need as output times.
//!
//! # Dense output of the step points' order
//!
//! The collocation polynomial's own error between the step points is
//! `O(h⁴)` (stage order 3) against the step points' `O(h⁶)`: with the
//! tolerance map (`h⁴ ∝ tol'` ∝ `tol^(2/3)`) it grew relative to the
//! tolerance as the tolerance fell, and on the literature map's short
//! horizons it was the largest error at tight tolerances (the reactor at
//! 1e-10: 2.2·10⁻⁸ at the check times, 6·10⁻¹³ at the step points;
//! EXTREMES.md colloc13). The dense output is therefore the Hermite
//! polynomial through the values and slopes of the last four step points
//! (`core::hermite`, degree 7 from the fourth step on, 5 on the second
//! and third, the cubic through `t₀` and `t₁` on the first — `O(h⁴)` on
//! that one step), whose error is of the step points' order, with the
//! slopes from the equations at each projected end point
//! (`collocation::slopes`):
//!
//! - where the zero columns of `E` are the algebraic unknowns (`rcd0`,
//!   the reactor, Jay's problem), `E_Rd y'_d = f_R` on the rows of `E`
//!   that are not zero gives the differential unknowns' slopes from the
//!   end point's own `f`, at no evaluation; the algebraic unknowns keep
//!   the collocation polynomial, and the output projection solves them
//!   from the interpolated differential ones;
//! - where a row of `E` holds an algebraic unknown's derivative
//!   (Gear–Hsu–Petzold's `y1' + ηt y2'`, `psi0`'s projected rows), every
//!   slope solves `E_R y' = f_R` with the differentiated algebraic rows
//!   `∂f_a/∂t + J_a y' = 0`, as a correction of the collocation
//!   polynomial's end slope (the iteration's `J_a` may be a few steps
//!   old), with the directional derivative of `f_a` by a central
//!   difference: two evaluations of `f` per step.
//!
//! The slopes are taken only where a value between step points can be
//! asked for (stored dense output, events, an output time inside the
//! horizon). The stepping itself is unchanged (the next step's starting
//! values extrapolate the collocation polynomial): steps, Jacobians and
//! factorisations are those of the collocation output. With constant
//! steps the error between the steps falls 2⁶-fold as the step halves, and
//! from the fourth step on it is the step points' own (tests/gauss.rs).
//! On the literature map the reactor at 1e-10 reaches scd 11.0 (7.67),
//! Gear–Hsu–Petzold 13.3 (7.69), Jay at 1e-9 and 1e-10 9.6 and 10.5 (6.99,
//! 7.79), with the same steps (EXTREMES.md gd14).

//! # Example
//!
//! ```
//! use dae::dae_solvers::{gauss::Gauss, init, NotApplicable};
//! use dae::models::builtin::Pendulum;
//! use dae::prelude::*;
//!
//! // The pendulum with the multiplier from the acceleration constraint
//! // (rcd0, index 1).
//! let sys = Pendulum::default().rcd0();
//! let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
//! let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 20.0 };
//! let solution = Gauss.solve(&problem, &Options::with_tol(1e-8))?;
//! // Ten periods (2 s each at the paper's g): back at the start.
//! let y = solution.last().unwrap();
//! assert!((y[0] - 1.0).abs() < 1e-6 && y[1].abs() < 1e-6);
//! // Index 2 is refused.
//! let rcd1 = Pendulum::default().rcd1();
//! assert!(matches!(Gauss.accepts(rcd1.info()), Err(NotApplicable::IndexTooHigh { .. })));
//! # Ok::<(), SolveError>(())
//! ```

use crate::collocation::tableau::{Collocation, EndPoint, NewtonStop, Policy, StepRule, Tableau};
use crate::collocation::{self, StageSolveKind};
use crate::core::policy;
use crate::{NotApplicable, Options, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;

/// Three-stage Gauss–Legendre collocation (see the
/// [module documentation](self)).
pub struct Gauss;

/// Highest index of an unknown `gauss` integrates.
pub const MAX_INDEX: u8 = 1;

/// Newton iterations allowed per step attempt: the iteration runs to
/// round-off (see [`NEWTON_ROUND_OFF`]).
pub const MAX_NEWTON: usize = 20;

/// The Jacobian (and with a constant step the factorisations) is kept
/// while the contraction factor stays at or below this.
pub const THET: f64 = 0.001;

/// The Newton iteration stops when its estimated remaining error is this
/// many units of round-off (in the weighted norm): at round-off, not at
/// the tolerance (see the [module documentation](self)).
pub const NEWTON_ROUND_OFF: f64 = 0.1;

/// The Newton iteration may stop earlier, at `NEWTON_DRIFT · tol · (h/T)²`
/// (weighted), where `T` is the horizon: a systematic iteration error `δ`
/// per step becomes a phase error of order `(T/h)² δ`.
pub const NEWTON_DRIFT: f64 = 0.2;

/// The tolerance the error test uses for a user tolerance `tol > 0`:
/// `TOL_MAP · tol^(2/3)`, never below the round-off floor `100 ε` (see the
/// [module documentation](self)).
pub fn internal_tolerance(tol: f64) -> f64 {
    (TOL_MAP * tol.powf(2.0 / 3.0)).max(100.0 * f64::EPSILON)
}

/// The constant of the tolerance map `tol' = TOL_MAP · tol^(2/3)`: over ten
/// periods of the pendulum (S01) the error is then 0.4–1.1 times the
/// tolerance from `10⁻⁵` to `10⁻¹¹` (BENCHMARKS.md §6d).
pub const TOL_MAP: f64 = 0.25;

impl Solver for Gauss {
    fn name(&self) -> &'static str {
        "gauss"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::square(info)?;
        policy::max_index(info, MAX_INDEX)
    }

    fn integrator<'a>(
        &self,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<crate::Integrator<'a>, SolveError> {
        self.accepts(problem.system.info())?;
        collocation::integrator::<GaussLegendre>(problem, options, StageSolveKind::Square)
    }
}

/// The factor applied to `rtol_i` and `atol_i`: `internal_tolerance(tol)/tol`
/// for the relative tolerance (the absolute one where it is zero).
fn tolerance_factor(rtol: f64, atol: f64) -> f64 {
    let tol = if rtol > 0.0 { rtol } else { atol };
    if tol > 0.0 {
        internal_tolerance(tol) / tol
    } else {
        1.0
    }
}

/// The tableau of three-stage Gauss–Legendre collocation.
pub(crate) struct GaussLegendre;

/// Nodes `1/2 − √15/10, 1/2, 1/2 + √15/10`.
const C: [f64; 3] = [0.11270166537925831, 0.5, 0.8872983346207417];

/// The nodes of the Newton form relative to the end point, `s = c_i − 1`,
/// last node first.
const NU1: f64 = C[2] - 1.0;
const NU2: f64 = C[1] - 1.0;
const NU3: f64 = C[0] - 1.0;

/// `bᵀA⁻¹`: `y_{n+1} = y_n + Σ d_i Z_i`.
const END: [f64; 3] = [5.0 / 3.0, -4.0 / 3.0, 5.0 / 3.0];

/// `A⁻¹`.
const AINV: [[f64; 3]; 3] = [
    [5.0, 1.1639777949432226, -0.1639777949432225],
    [-5.727486121839514, 2.0, 0.7274861218395141],
    [10.163977794943223, -9.163977794943223, 5.0],
];

impl Collocation for GaussLegendre {
    const TABLEAU: Tableau = Tableau {
        c: C,
        ainv: AINV,
        // The real root of `z³ − 12z² + 60z − 120` (the denominator of the
        // (3,3) Padé approximation).
        gamma: 4.644370709252171,
        alpha: 3.6778146453739144,
        beta: 3.5087619195674433,
        t: [
            [
                0.07215185205520017,
                -0.08224123057363067,
                -0.0601207386193085,
            ],
            [
                0.11883257874127781,
                0.053065090742061394,
                0.3162050511322916,
            ],
            [1.0, 1.0, 0.0],
        ],
        ti: [
            [5.991698084937801, 1.1392142951557354, 0.43231211378385836],
            [-5.991698084937801, -1.1392142951557354, 0.5676878862161416],
            [
                -1.2462132735862315,
                2.9255596461923137,
                -0.25773520127343247,
            ],
        ],
        dd: [-13.121638910345695, 4.0 / 3.0, -0.21169442298763852],
        end: EndPoint::Projected(END),
    };
    const POLICY: Policy = Policy {
        step: StepRule::Held,
        newton: NewtonStop::RoundOff {
            units: NEWTON_ROUND_OFF,
            drift: NEWTON_DRIFT,
        },
        max_newton: MAX_NEWTON,
        thet: THET,
        tolerance_factor,
    };

    /// On the nodes `0, c₃ − 1, c₂ − 1, c₁ − 1`, with the values `0` and
    /// `Z_i − Σ_j d_j Z_j`.
    #[inline(always)]
    fn divided_differences(z1: f64, z2: f64, z3: f64) -> [f64; 3] {
        let ze = END[0] * z1 + END[1] * z2 + END[2] * z3;
        let (a, b, c) = (z3 - ze, z2 - ze, z1 - ze);
        let d1 = a / NU1;
        let d12 = (b - a) / (NU2 - NU1);
        let d2 = (d12 - d1) / NU2;
        let d23 = (c - b) / (NU3 - NU2);
        let d123 = (d23 - d12) / (NU3 - NU1);
        [d1, d2, (d123 - d2) / NU3]
    }

    #[inline(always)]
    fn polynomial_increment(d: &[f64; 3], s: f64) -> f64 {
        s * (d[0] + (s - NU1) * (d[1] + (s - NU2) * d[2]))
    }

    #[inline(always)]
    fn end_slope(_z: [f64; 3], d: &[f64; 3]) -> f64 {
        d[0] - NU1 * (d[1] - NU2 * d[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::collocation::tableau::check::{self, M3};

    fn gauss_a() -> M3 {
        let r = 15f64.sqrt();
        [
            [5.0 / 36.0, 2.0 / 9.0 - r / 15.0, 5.0 / 36.0 - r / 30.0],
            [5.0 / 36.0 + r / 24.0, 2.0 / 9.0, 5.0 / 36.0 - r / 24.0],
            [5.0 / 36.0 + r / 30.0, 2.0 / 9.0 + r / 15.0, 5.0 / 36.0],
        ]
    }

    type G = GaussLegendre;

    #[test]
    fn coefficients_are_consistent() {
        let a = gauss_a();
        check::transformation::<G>(&a);
        let (g, al, be) = (G::TABLEAU.gamma, G::TABLEAU.alpha, G::TABLEAU.beta);
        // The eigenvalues are the roots of the Padé denominator.
        let p = |z: f64| ((z - 12.0) * z + 60.0) * z - 120.0;
        assert!(p(g).abs() < 1e-12);
        assert!((al + al + g - 12.0).abs() < 1e-13);
        assert!(((al * al + be * be) * g - 120.0).abs() < 1e-11);
        // bᵀA⁻¹ is END.
        let b = [5.0 / 18.0, 4.0 / 9.0, 5.0 / 18.0];
        for (i, e) in END.iter().enumerate() {
            let d: f64 = (0..3).map(|k| b[k] * G::TABLEAU.ainv[k][i]).sum();
            assert!((d - e).abs() < 1e-14);
        }
        // The embedded formula: b̂ = b + (γ₀ d̂ᵀ A) with b̂₀ = γ₀ integrates
        // 1, t, t² exactly on the nodes 0, c₁, c₂, c₃.
        let g0 = 1.0 / g;
        let bh: Vec<f64> = (0..3)
            .map(|i| b[i] + g0 * (0..3).map(|j| G::TABLEAU.dd[j] * a[j][i]).sum::<f64>())
            .collect();
        for k in 0..3 {
            let q: f64 =
                (0..3).map(|i| bh[i] * C[i].powi(k)).sum::<f64>() + if k == 0 { g0 } else { 0.0 };
            assert!(
                (q - 1.0 / f64::from(k + 1)).abs() < 1e-13,
                "degree {k}: {q}"
            );
        }
    }

    #[test]
    fn collocation_polynomial_interpolates_the_stages() {
        // Z_i = p(c_i) for a cubic p with p(0) = 0: the Newton form
        // reproduces it at every node, at the end point and at the start.
        let p = |s: f64| s * (0.7 - s * (1.3 + 0.4 * s));
        let z = [p(C[0]), p(C[1]), p(C[2])];
        let d = G::divided_differences(z[0], z[1], z[2]);
        let end: f64 = (0..3).map(|i| END[i] * z[i]).sum();
        assert!((end - p(1.0)).abs() < 1e-14, "{end} vs {}", p(1.0));
        for s in [0.0, 0.1, 0.5, 0.9, 1.0] {
            let u = end + G::polynomial_increment(&d, s - 1.0);
            assert!((u - p(s)).abs() < 1e-14, "s = {s}: {u} vs {}", p(s));
        }
        // The slope at the end: p'(1) = 0.7 − 2.6 − 1.2.
        assert!((G::end_slope(z, &d) - (0.7 - 2.6 - 1.2)).abs() < 1e-13);
    }
}

//! Radau IIA of order 5 for quasi-linear DAEs, after RADAU5 of Hairer & Wanner.
//!
//! # Discretisation
//!
//! The formulation `E(t, y) y' = f(t, y)` (square; `E` may be singular and may
//! depend on `t` and `y`) is discretised by the three-stage Radau IIA collocation
//! method (Hairer & Wanner, *Solving Ordinary Differential Equations II*,
//! §IV.5, §IV.8 and §VII.8 — "HW" below). With the stage increments
//! `Z_i = Y_i − y_n` and the derivatives of the collocation polynomial at the
//! nodes,
//!
//! ```text
//!     Y'_i = (1/h) Σ_j (A⁻¹)_ij Z_j ,                 i = 1, 2, 3,
//! ```
//!
//! the stage equations are the collocation conditions
//!
//! ```text
//!     G_i(Z) = E(Y_i) Y'_i − f(t_n + c_i h, Y_i) = 0 ,  y_{n+1} = y_n + Z_3
//! ```
//!
//! (the method is stiffly accurate, `c_3 = 1`). For a constant `E` this is
//! exactly RADAU5's system `(h⁻¹A⁻¹ ⊗ M) Z = F(Z)`; evaluating `E` at every
//! stage value is what lets the projected formulations `psi1` and `psi0`,
//! whose leading matrix depends on `y`, be integrated at all.
//!
//! # Simplified Newton iteration (HW IV.8)
//!
//! The iteration matrix `h⁻¹ A⁻¹ ⊗ E₀ − I ⊗ J` is frozen at a point
//! `(t_n, y_n)`, with `E₀ = E(y_n)` and
//!
//! ```text
//!     J = ∂f/∂y (t_n, y_n) − ∂(E(y) z)/∂y |_(y_n, z = y'_n) ,
//! ```
//!
//! `y'_n` being the derivative of the last collocation polynomial (the second
//! term vanishes for a constant `E`). The eigen-decomposition
//! `T⁻¹ A⁻¹ T = Λ = diag(γ, [[α, −β], [β, α]])` and the change of unknowns
//! `ΔZ = (T ⊗ I) ΔW` split each iteration into one real and one complex
//! linear system of size `N`,
//!
//! ```text
//!     (γ/h E₀ − J) ΔW₁ = R₁ ,   ((α + iβ)/h E₀ − J)(ΔW₂ + iΔW₃) = R₂ + iR₃ ,
//! ```
//!
//! with `R = −(T⁻¹ ⊗ I) G(Z)`, residuals always taken with the true `E(Y_i)`.
//! Both matrices are factorised by partial-pivoting LU in storage allocated
//! before the step loop. Jacobians and factorisations are reused across steps
//! exactly as RADAU5 reuses them: the Jacobian is kept while the observed
//! contraction factor `θ` stays below `10⁻³`, the factorisation while in
//! addition the proposed step ratio lies in `[1, 1.2]`. The iteration stops
//! when `η_k ‖ΔW_k‖ ≤ κ·tol` with `η_k = θ_k/(1 − θ_k)` (HW IV.8 (8.10)–
//! (8.13)); it is abandoned early, with a smaller step, when the predicted
//! error after the remaining iterations stays above `κ·tol`.
//!
//! # Error estimate and error scaling (HW IV.8 (8.19)–(8.20), VII.8)
//!
//! ```text
//!     err = (γ/h E₀ − J)⁻¹ [ f(t_n, y_n) + E(y_n) (1/h) Σ_i d_i Z_i ] ,
//!     d = (−(13 + 7√6)/3, (−13 + 7√6)/3, −1/3) ,
//! ```
//!
//! RADAU5's estimate with `E` in place of the mass matrix, refined on the
//! first step and after a rejection (where the plain estimate may be too
//! pessimistic for stiff components) by replacing `f(t_n, y_n)` with
//! `f(t_n, y_n + err)`. The norm is
//!
//! ```text
//!     ‖err‖ = sqrt( (1/N) Σ_i (err_i / sc_i)² ),
//!     sc_i = (atol_i + rtol_i |y_n,i|) / h^(k_i − 1),
//! ```
//!
//! where `k_i` is the index of unknown `i` in the formulation
//! (`info().variables[i].index`): the estimate of an index-`k` component is
//! `O(h^(1−k))` larger than its true local error, which RADAU5 compensates in
//! the same way for its `NIND2`/`NIND3` components (HW VII.8, "Error
//! estimation for index 2 and 3").
//!
//! # Tolerances: not loosened, tightened towards proportionality
//!
//! Fortran RADAU5 replaces the user's `RTOL` by `0.1 RTOL^(2/3)` (and `ATOL`
//! in proportion) before it starts: its estimate controls the embedded
//! order-3 solution, `O(h⁴)`, while the delivered solution has local error
//! `O(h⁶)`, and the power `2/3` makes the latter roughly proportional to the
//! user's tolerance. For `RTOL < 10⁻³` this *loosens* the tolerance (the
//! paper's RADAU5 at `RTOL = 10⁻¹²` ran at `10⁻⁹`), so here it is not done.
//! The tolerance is instead tightened at loose tolerances so that the
//! *global* error becomes proportional to it: with `h ∝ tol'^(1/4)` the
//! global error of the order-5 method behaves like `h⁵ ∝ tol'^(5/4)`, so
//!
//! ```text
//!     tol' = tol · (τ / tol)^(1/5)          for tol > τ = 10^(−12.5),
//!     tol' = max(tol, 100 ε)                otherwise,
//! ```
//!
//! applied as one factor to `rtol_i` and `atol_i` (see [`internal_tolerance`]).
//! The anchor `τ`, just below the tightest tolerance of the paper, makes the
//! map the identity there and `tol' ≈ tol/30` at `tol = 10⁻⁵`. Without it a
//! tolerance of `10⁻⁵` lets the pendulum of Scenario S02 drift a full swing
//! out of phase over its 1000 periods (error sums of `10³`–`10⁴`) while the
//! error test is met at every step. Below `100 ε ≈ 2.2·10⁻¹⁴` the estimate
//! is round-off and cannot be made smaller (RADAU5 refuses
//! `RTOL ≤ 10 u` outright); such tolerances are raised to that floor, the
//! only case in which the user's tolerance is loosened.
//!
//! # Step size (HW IV.8 (8.21)–(8.25))
//!
//! `h_new = h / q` with `q = clamp(‖err‖^(1/4) / fac, 1/8, 5)`,
//! `fac = min(0.9, 0.9 (2 NIT + 1) / (NIT_used + 2 NIT))`, combined with
//! Gustafsson's predictive controller
//!
//! ```text
//!     q_pred = (h_acc / h) (‖err‖² / ‖err_acc‖)^(1/4) / 0.9 ,   q = max(q, q_pred),
//! ```
//!
//! `h_acc`, `err_acc` being those of the previous accepted step. After a
//! rejected first step `h` is divided by 10, after a diverging Newton
//! iteration by 2, after a too slowly converging one by the factor its
//! contraction predicts. The step is kept (with its factorisation) when
//! `h_new/h ∈ [1, 1.2]` and the Jacobian was reused.
//!
//! # Dense output
//!
//! The collocation polynomial of the last step, stored in Newton form on the
//! nodes `0, c₂ − 1, c₁ − 1, −1` of `s = (t − t_{n+1})/h` (RADAU5's
//! `CONTR5`), gives the output at any time of the step and, extrapolated,
//! the starting values of the next Newton iteration. Output times never
//! shorten a step. The last step ends exactly at `t_end`; when one more
//! step of the proposed size would leave a short remainder, the rest is
//! split into two equal steps instead (a large step ratio at the end would
//! cost the index-2 and index-3 components accuracy where they are
//! reported).
//!
//! # Failure
//!
//! Every failure is a typed [`SolveError`], within the budgets of
//! `core::control` shared by all methods: a singular iteration matrix is
//! retried with halved steps ([`SolveError::SingularMatrix`] after five in a
//! row), a failed Newton iteration likewise
//! ([`SolveError::NewtonFailure`] after ten in a row, or
//! [`SolveError::NonFinite`] after ten non-finite residuals), steps below
//! `4 ε max(|t|, ε (t_end − t₀))` give [`SolveError::StepSizeTooSmall`], and
//! [`crate::Options::max_steps`] attempted steps [`SolveError::StepLimit`].
//! The error norm is the one of `core::weights`, with the index-scaled
//! weights `h^(k_i−1)/sc_i`.

pub(crate) mod tableau;

use crate::collocation::{self, StageSolveKind};
use crate::core::policy;
use crate::options::Options;
use crate::{NotApplicable, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;
use tableau::RadauIIA;

/// 3-stage Radau IIA of order 5 (see the [module documentation](self)).
///
/// The paper's pendulum in the GGL formulation (`ggl1` appends the
/// multiplier `eta` of the velocity constraint to the unknowns; consistent
/// initialisation computes it and `lambda`):
///
/// ```
/// use dae::dae_solvers::{init, radau5::Radau5};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().ggl1();
/// assert_eq!(sys.info().variables.len(), 6); // x, y, v, w, lambda, eta
/// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
/// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 2.0 };
/// let solution = Radau5.solve(&problem, &Options::with_tol(1e-8))?;
/// // One period (2 s at the paper's g): back at the start.
/// let y = solution.last().unwrap();
/// assert!((y[0] - 1.0).abs() < 1e-6 && y[1].abs() < 1e-6);
/// println!("{} steps, {} LU factorisations", solution.stats.steps, solution.stats.factorizations);
/// # Ok::<(), SolveError>(())
/// ```
pub struct Radau5;

impl Solver for Radau5 {
    fn name(&self) -> &'static str {
        "radau5"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::square(info)
    }

    fn integrator<'a>(
        &self,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<crate::Integrator<'a>, SolveError> {
        self.accepts(problem.system.info())?;
        policy::leading_constant_in_time(self.name(), problem)?;
        collocation::integrator::<RadauIIA>(problem, options, StageSolveKind::Square)
    }
}

// ---------------------------------------------------------------------------
// Tuning: RADAU5's defaults (the engine's own are in `collocation`)
// ---------------------------------------------------------------------------

/// Maximal Newton iterations per step (`NIT`).
const NIT: usize = 7;
/// Recompute the Jacobian only when the contraction factor exceeded this
/// (`THET`).
const THET: f64 = 0.001;

// ---------------------------------------------------------------------------
// The tolerance map (see the module documentation)
// ---------------------------------------------------------------------------

/// Anchor `τ = 10^(−12.5)` of the tolerance map: tolerances at or below it
/// are used as given.
const TOL_ANCHOR: f64 = 3.162_277_660_168_379e-13;

/// Round-off floor `100 ε` of relative tolerances.
const TOL_FLOOR: f64 = 100.0 * f64::EPSILON;

/// From this tolerance down (the smallest relative tolerance, or absolute
/// where all relative ones are zero) the integration is run for the last
/// digits: the updates of `t` and `y` are summed with compensation, and
/// RADAU5's Newton bound is multiplied by [`TIGHT_NEWTON`] (the collocation
/// engine's rule, shared with [`crate::gauss`] and [`crate::odradau`]).
/// Measured in BENCHMARKS.md §6b; above it nothing changes, bit for bit.
///
/// ```
/// assert!(dae_solvers::radau5::TIGHT_TOL <= 1e-10);
/// ```
pub const TIGHT_TOL: f64 = collocation::TIGHT_TOL;

/// The factor on RADAU5's Newton bound at tight tolerances.
///
/// ```
/// assert!(dae_solvers::radau5::TIGHT_NEWTON < 1.0);
/// ```
pub const TIGHT_NEWTON: f64 = collocation::TIGHT_NEWTON;

/// The tolerance the error test uses for a user tolerance `tol > 0`:
/// `tol (τ/tol)^(1/5)` above `τ = 10^(−12.5)`, `tol` itself below, and
/// never less than the round-off floor `100 ε ≈ 2.2·10⁻¹⁴` (see the module
/// documentation). Larger than `tol` only below that floor.
pub fn internal_tolerance(tol: f64) -> f64 {
    if tol > TOL_ANCHOR {
        tol * (TOL_ANCHOR / tol).powf(0.2)
    } else {
        tol.max(TOL_FLOOR)
    }
}

/// The factor `internal_tolerance(rtol_i)/rtol_i` applied to `rtol_i` and
/// `atol_i` (as RADAU5 scales `ATOL` with `RTOL`); a purely absolute
/// tolerance (`rtol_i = 0`) is tightened like a relative one but not floored.
pub(crate) fn tolerance_factor(rtol: f64, atol: f64) -> f64 {
    if rtol > 0.0 {
        internal_tolerance(rtol) / rtol
    } else if atol > TOL_ANCHOR {
        (TOL_ANCHOR / atol).powf(0.2)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerance_map_never_loosens() {
        for e in 0..=136 {
            let tol = 10f64.powf(-0.1 * f64::from(e));
            let t = internal_tolerance(tol);
            assert!(t <= tol && t >= TOL_FLOOR, "{tol}: {t}");
        }
        assert_eq!(internal_tolerance(1e-13), 1e-13);
        assert_eq!(internal_tolerance(1e-16), TOL_FLOOR);
        assert!((internal_tolerance(TOL_ANCHOR) - TOL_ANCHOR).abs() < 1e-28);
        // Global-error proportionality: tol'^(5/4) ∝ tol.
        let ratio = (internal_tolerance(1e-5) / internal_tolerance(1e-10)).powf(1.25);
        assert!((ratio / 1e5 - 1.0).abs() < 1e-9);
    }
}

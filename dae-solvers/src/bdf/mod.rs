//! Variable-order, variable-step BDF in fixed-leading-coefficient form, after
//! DASSL and DASPK (Brenan, Campbell & Petzold, *Numerical Solution of
//! Initial-Value Problems in Differential-Algebraic Equations*, SIAM 1996,
//! chapter 5 — "BCP" below).
//!
//! # The problem
//!
//! A square quasi-linear DAE
//!
//! ```text
//!     F(t, y, y') = E(t, y) y' − f(t, y) = 0,        y ∈ ℝᴺ,
//! ```
//!
//! integrated from consistent initial values `y(t₀) = y₀` supplied by the
//! caller; the initial derivative `y'₀` is computed here (see
//! [Initial derivative](#initial-derivative)).
//!
//! # The method (BCP ch. 5, basic formulas)
//!
//! At step `n+1` of size `h = t_{n+1} − t_n` and order `k` the solution is
//! represented by the *modified divided differences* `φ_i` of the engine
//! (`multistep::divided`, which also gives the predictor `y⁽⁰⁾`,
//! `y'⁽⁰⁾` — the polynomial through the last `k+1` solution values — and
//! the coefficients `ψ_i, α_i, β_i, γ_i, σ_i` below).
//!
//! *Corrector* (fixed leading coefficient): the polynomial that interpolates
//! the predictor at the `k` points `t_{n+1} − jh`, `j = 1..k` (equally
//! spaced, whatever the past steps were) and satisfies the DAE at `t_{n+1}`:
//!
//! ```text
//!     y' = y'⁽⁰⁾ + c_J (y − y⁽⁰⁾),     c_J = −α_s/h,   α_s = −Σ_{j=1}^{k} 1/j,
//!     F(t_{n+1}, y, y'⁽⁰⁾ + c_J (y − y⁽⁰⁾)) = 0.
//! ```
//!
//! Because `c_J` depends on `h` and `k` only, the iteration matrix
//!
//! ```text
//!     G = ∂F/∂y + c_J ∂F/∂y' = ∂(E(t, y) y')/∂y − ∂f/∂y + c_J E(t, y)
//! ```
//!
//! can be reused over many steps of different size (BCP ch. 5, nonlinear
//! system solution). A modified
//! Newton iteration solves the corrector; when `c_J` has changed since `G`
//! was factored, each Newton update is damped by `2/(1 + c_J/c_J^old)`.
//! Its convergence rate `ρ` is estimated from successive updates, and the
//! iteration is accepted when `ρ/(1−ρ) · ‖δ‖ ≤ 0.33`, abandoned when
//! `ρ > 0.9` or after four iterations. `G` is
//! re-evaluated and re-factored when `c_J/c_J^old ∉ [0.6, 5/3]` or when the
//! iteration fails with an old matrix.
//!
//! *Error estimate* (BCP ch. 5): with `e = y_{n+1} − y⁽⁰⁾` the accumulated
//! Newton corrections, the local error of the step is estimated as
//! `C_k ‖e‖` with `C_k = max(|α_{k+1} + α_s − α⁰|, α_{k+1})`,
//! `α⁰ = −Σ_{i=1}^{k} α_i`; the step is accepted when it is at most one in
//! the weighted RMS norm `‖v‖ = (Σ (v_i w_i)²/N)^{1/2}` over the `N`
//! components in the test, `w_i = 1/(atol_i + rtol_i |y_{n,i}|)`.
//!
//! *The propagated estimate* ([`Options::estimate`], not in DASSL). `e`
//! measures a differential component's local error, but for an algebraic
//! one it measures how wrongly that unknown's own history extrapolates —
//! its curvature — while the step's error in it is the error the
//! constraints carry over from the differential components. Each term `v`
//! of the test and of the order selection (`e`, `φ*_k + e`, …) can
//! therefore also be carried through the factored iteration matrix,
//! `ṽ = G⁻¹ (c_J E v)` — for an index-1 DAE the linearised constraints'
//! image of `v`'s differential part, RADAU5's filter (Hairer & Wanner
//! IV.8; Shampine 1980) — and the norm taken of `max(|v_i|, |ṽ_i|)`,
//! never below DASSL's. By default
//! ([`Estimate::Checked`](crate::options::Estimate::Checked)) the first
//! error test after each new iteration matrix or rejected step compares
//! the two norms of `e`; once the propagated one is more than ten times
//! DASSL's, the run propagates every term to its end. On the IVP Test
//! Set's transistor amplifier the amplifier's output is an algebraic
//! combination `≈ 144 ×` the transistor's input: at equal steps DASSL's
//! `e` of it misses the step's error 20–30-fold, at a doubled step it sees
//! half of it (BENCHMARKS.md §18), and DASSL's controller then alternates,
//! in bursts over the rest of the run, between an accepted order-one step
//! and a doubled, rejected one (1.4 M steps at 1e-10, 6 digits).
//! Propagated, the estimate grows like `h^{k+1}` and the run takes 22 983
//! steps to 9.2 digits. On the pendulum the check never fires and the run
//! is DASSL's.
//! [`Estimate::Dassl`](crate::options::Estimate::Dassl) never checks (the
//! Fortran reproduction, `examples/bdf_s02`).
//!
//! *Order and step selection* (BCP ch. 5, stepsize and order selection):
//! the leading error terms at orders `k−2 … k+1` are estimated from `e` and
//! the differences `φ*` (`TERK`, `TERKM1`, …). The order is lowered when the lower-order terms
//! decrease less regularly, raised after `k+1` steps of constant size when
//! the `(k+2)`-nd difference is small, and the next step is
//! `h·r`, `r = (2·EST + 10⁻⁴)^{−1/(k+1)}`, changed only when `r ≥ 2`
//! (then `r = 2`) or `r ≤ 1` (then clamped to `[0.5, 0.9]`). The start is
//! DASSL's: order one, a step `h₀ ≤ 0.5/‖y'₀‖`, then order +1 and step ×2
//! at every step until the first failure or lowering (`IPHASE`).
//! Failures: error test — first `r = 0.9 (2·EST)^{−1/(k+1)}` clamped to
//! `[0.25, 0.9]`, second `r = 1/4`, later order one and `r = 1/4`; Newton
//! failure and singular `G` — `r = 1/4`, within the failure budget of
//! `core::control` (ten Newton failures, five singular matrices, ten
//! non-finite residuals on one step).
//!
//! *An estimate that stops falling with the step* (not in DASSL; the
//! engine's `multistep::stale`, shared with `mebdf`): an order-one attempt
//! whose estimate stays put while the step is cut below 0.3 of the last
//! rejected one measures a stale value, not the step — the run restarts at
//! order one from the attempt's value (where DASSL ends with a step size
//! too small); three steps in a row whose second rejection did not bring
//! the estimate down fall to order one. Neither fires on S02, the solver
//! harness, the DASSL reproduction (`examples/bdf_s02`) or the literature
//! map's bdf/odbdf cells: every step count there is DASSL's, unchanged.
//!
//! *Dense output* (DASSL's DDATRP): between steps the solution is the
//! polynomial of degree `k` through the last `k+1` solution values,
//! `y(t) = Σ_{i=1}^{k+1} c_i(t) φ_i(n+1)`.
//!
//! # Options
//!
//! - [`Options::max_order`] bounds the order; [`Options::fixed_order`] `= k`
//!   (adaptive steps) raises the order to `k` as fast as the start allows and
//!   never lowers it by order selection — only DASSL's emergency fall-back to
//!   order one after three error-test failures on one step, followed by a
//!   rise of one order per step.
//! - [`Options::h0`] replaces the initial step, [`Options::h_max`] bounds
//!   every step, [`Options::max_steps`] counts accepted and rejected steps.
//! - The step size falling below `4 ε max(|t|, ε (t_end − t₀))` is
//!   [`SolveError::StepSizeTooSmall`]. The last steps are adjusted so that
//!   the integration ends exactly at `t_end` without a tiny final step: a
//!   step is stretched by up to 10 % to reach `t_end`, or what remains of
//!   two steps is split evenly.
//! - Output at [`Options::output_times`] is interpolated (the steps do not
//!   stop there).
//!
//! # Index-2 formulations (DASPK)
//!
//! By default ([`Options::index2_in_error_test`] `= None`, decided in
//! [`crate::core::policy::bdf_error_test`]; `Some(false)` says the same
//! explicitly, `Some(true)` keeps them), unknowns whose
//! [`VarInfo::index`](dae_core::system::VarInfo) is two or more (Lagrange
//! multipliers of index-2 formulations) get weight zero in the error test,
//! which then averages over the remaining components only. For an index-2
//! multiplier the difference between corrector and predictor is not an
//! estimate of a local error that shrinks like `h^{k+1}` (BCP ch. 3 on BDF
//! for index-2 systems, ch. 5 on higher-index systems in DASSL); kept in
//! the test it drives the step size to zero (DASPK's `INFO(16)`; the
//! paper's DASSL/DASPK runs show it).
//!
//! The Newton convergence norm keeps them, with their full weights, as
//! DASPK does (its `INFO(16)` zeroes the weights of the error test only,
//! `VT`; the corrector is measured with `WT`). The iteration's error in an
//! index-2 unknown is not seen in the other components: on a linear
//! index-2 circuit (`scenes/mna_cv_loop.dae`, `ori2`) with the multiplier
//! out of the Newton norm too, the iterations that converged in the node
//! potentials left the source current `jv` with errors up to 3e-2 at tol
//! 1e-6 (scd 1.2); on the pendulum's `rcd1`, `ggl1` and `psi1` the runs
//! take 31–60 % fewer steps with the multiplier in the norm (S01, S02;
//! EXTREMES.md "ix2bdf13"). An update at the round-off floor of the
//! index-scaled norm (`h^(k−1)` for index `k`, Hairer & Wanner VII.8) also
//! counts as converged: round-off in the rows reaches an index-2 unknown
//! multiplied by `c_J ∼ 1/h` (the engine's `multistep::newton_norm`).
//!
//! # Initial derivative, fixed step size, resources
//!
//! As every multistep family: the engine's (`multistep`) initial
//! derivative and consistency check, constant-step run with its adaptive
//! start-up, and buffers allocated before the step loop. With a constant
//! step the order is `k` ([`Options::fixed_order`], else
//! [`Options::max_order`]) and every step after the start-up is the
//! classical constant-step BDF-`k` formula.

mod corrector;
mod history;
mod order;
mod step;

use crate::core::block::Block;
use crate::core::matrix::{Corrector, SquareLu};
use crate::core::policy;
use crate::multistep::run::{self, Orders};
use crate::{NotApplicable, Options, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;
use step::Integrator;

/// Variable-order (1–5), variable-step BDF in fixed-leading-coefficient form
/// (DASSL/DASPK). See the [module documentation](self).
///
/// The pendulum in the index-1 formulation `rcd0` (its multiplier is
/// algebraic, index 1), with output every half second:
///
/// ```
/// use dae::dae_solvers::{bdf::Bdf, init};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd0();
/// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
/// let options = Options { output_times: vec![0.5, 1.0, 1.5], ..Options::with_tol(1e-8) };
/// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 2.0 };
/// let solution = Bdf.solve(&problem, &options)?;
/// assert_eq!(solution.t, [0.5, 1.0, 1.5, 2.0]);
/// // Half a period: the pendulum is at the other side, x = -1.
/// assert!((solution.y[1][0] + 1.0).abs() < 1e-4);
/// # Ok::<(), SolveError>(())
/// ```
pub struct Bdf;

impl Solver for Bdf {
    fn name(&self) -> &'static str {
        "bdf"
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
        policy::hessenberg(problem.system, problem.t0, problem.y0, options)?;
        policy::leading_constant_in_time(self.name(), problem)?;
        policy::variable_step_index3(self.name(), problem.system.info(), options)?;
        integrator::<Block<SquareLu>>(problem, options)
    }
}

/// Highest order of the method.
const MAX_ORDER: usize = 5;
/// Columns of the history array `φ` (orders up to 5 use `φ_1 … φ_{k+2}`).
const NCOL: usize = MAX_ORDER + 2;
/// Unit round-off.
const EPS: f64 = f64::EPSILON;

/// The stepper of the BDF method on `problem`, the corrector solved by
/// `L` (square LU, or least squares for [`crate::odbdf`]), started at
/// `t₀`; the caller has checked that the solver accepts the formulation.
pub(crate) fn integrator<'a, L: Corrector + 'a>(
    problem: &Problem<'a>,
    options: &'a Options,
) -> Result<crate::Integrator<'a>, SolveError> {
    problem.check(problem.system.info().unknowns(), options)?;
    options.check_orders(MAX_ORDER, "the BDF methods (bdf, odbdf)")?;
    let sys = crate::core::eliminate::algebraic_rows(problem);
    let info = sys.info();

    // Components in the error test, and in the Newton norm (all but a
    // sensitivity left out of the error control: DASPK).
    let mut in_test = policy::bdf_error_test(info, options);
    crate::core::block::restrict_error_test(&mut in_test, sys.blocks());
    let in_newton = crate::core::block::in_error_test(info.unknowns(), sys.blocks());

    let orders = Orders {
        of_option: |k| k,
        formula_steps: |k| k,
        startup: MAX_ORDER,
    };
    run::integrator(sys, problem, options, orders, move |sys, cfg| {
        let masks = [&in_test[..], &in_newton[..]];
        Integrator::<L>::new(sys, &options.tol, masks, cfg, options.estimate)
    })
}

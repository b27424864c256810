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
//!     F(t, y, y') = E(y) y' − f(t, y) = 0,        y ∈ ℝᴺ,
//! ```
//!
//! integrated from consistent initial values `y(t₀) = y₀` supplied by the
//! caller; the initial derivative `y'₀` is computed here (see
//! [Initial derivative](#initial-derivative)).
//!
//! # The method (BCP ch. 5, basic formulas)
//!
//! At step `n+1` of size `h = t_{n+1} − t_n` and order `k` the solution is
//! represented by the *modified divided differences*
//!
//! ```text
//!     φ_1(n) = y_n,   φ_{i+1}(n) = ψ_1(n)⋯ψ_i(n) · y[t_n, …, t_{n−i}],
//!     ψ_i(n+1) = t_{n+1} − t_{n+1−i},
//! ```
//!
//! rescaled for the new step to `φ*_i(n) = β_i(n+1) φ_i(n)` with
//! `β_i(n+1) = Π_{j<i} ψ_j(n+1)/ψ_j(n)`.
//!
//! *Predictor*: the polynomial through the last `k+1` solution values,
//!
//! ```text
//!     y⁽⁰⁾ = Σ_{i=1}^{k+1} φ*_i(n),      y'⁽⁰⁾ = Σ_{i=2}^{k+1} γ_i(n+1) φ*_i(n),
//!     γ_1 = 0,  γ_i = γ_{i−1} + α_{i−1}/h,   α_i = h/ψ_i(n+1).
//! ```
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
//!     G = ∂F/∂y + c_J ∂F/∂y' = ∂(E(y) y')/∂y − ∂f/∂y + c_J E(y)
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
//! multipliers of index-2 formulations) get weight zero in the error test and
//! in the Newton convergence norm, which then averages over the remaining
//! components only. For an index-2 multiplier the difference between
//! corrector and predictor is not an estimate of a local error that shrinks
//! like `h^{k+1}` (BCP ch. 3 on BDF for index-2 systems, ch. 5 on
//! higher-index systems in DASSL); kept in the test it drives the step
//! size to zero (DASPK's `INFO(16)`; the paper's DASSL/DASPK runs show it).
//!
//! # Initial derivative
//!
//! `y'₀` is computed as by [`crate::init::initial_derivative`]: the
//! minimum-norm least-squares solution of `E(y₀) y' = f(t₀, y₀)` (by SVD, so
//! the derivatives of purely algebraic unknowns are zero), completed in the
//! null space of `E(y₀)` by the time derivatives of the model's constraint
//! chain, `G_y(t₀,y₀) y' + ∂g/∂t = 0` — again in the least-squares
//! minimum-norm sense and without changing `E y'`. For the projected
//! formulations this recovers the derivatives that `E` leaves undetermined,
//! so the first predictor is right. Two choices differ from that function:
//! the rank of `E` is the numerical rank at round-off (`σ ≤ N ε σ_max` counts
//! as zero), so that every nonsingular `E` is inverted however badly it is
//! scaled, and a constraint chain that cannot be differentiated at `t₀` (not
//! finite) leaves the null-space components at zero instead of failing. The
//! initial values are then checked: a row whose residual exceeds what a
//! perturbation of every unknown by its tolerance could cause gives
//! [`SolveError::InconsistentInitialValues`].
//!
//! # Fixed step size (convergence studies)
//!
//! With [`Options::fixed_step`] the grid is `t₀ + jh` with
//! `h = (t_end − t₀)/⌈(t_end − t₀)/fixed_step⌉`, the order is
//! [`Options::fixed_order`] (else [`Options::max_order`]) and there is no
//! error test. A `k`-step method needs `k` starting values: `y(t₀ + jh)`,
//! `j = 1 … k−1`, are computed by this solver in adaptive mode with the
//! caller's tolerances (choose them well below the discretisation error to
//! observe the order) and interpolated onto the grid; from then on every
//! step is the classical constant-step BDF-`k` formula. Starting with lower
//! orders at the given step would cap the observed order at two. The work
//! counters include the start-up run; [`Options::record_steps`] lists the
//! grid points. The corrector may take up to 20 Newton iterations (no
//! smaller step can rescue it) and a failure is final.
//!
//! # Resources
//!
//! All buffers — history, iteration matrix and its in-place LU
//! factorisation, output rows — are allocated before the step loop; the loop
//! itself does not allocate, except to record every step when
//! [`Options::record_steps`] asks for it.

use crate::core::control::{self, Budget, Failure as Fail};
use crate::core::driver::{self, Method};
use crate::core::matrix::{Corrector, Rows, SquareLu};
use crate::core::newton::{Contraction, Rule, Verdict};
use crate::core::policy;
use crate::core::weights::Weights;
use crate::init::{check_residuals, initial_derivative_with, DerivativeRule};
use crate::options::Tolerances;
use crate::{NotApplicable, Options, Problem, Solution, SolveError, Solver, Stats};
use dae_core::system::{DaeSystem, FormulationInfo};
use nalgebra::DMatrix;

/// Variable-order (1–5), variable-step BDF in fixed-leading-coefficient form
/// (DASSL/DASPK). See the [module documentation](self).
pub struct Bdf;

impl Solver for Bdf {
    fn name(&self) -> &'static str {
        "bdf"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::square(info)
    }

    fn solve(&self, problem: &Problem<'_>, options: &Options) -> Result<Solution, SolveError> {
        self.accepts(problem.system.info())?;
        integrate::<SquareLu>(problem, options)
    }
}

/// Highest order of the method.
const MAX_ORDER: usize = 5;
/// Columns of the history array `φ` (orders up to 5 use `φ_1 … φ_{k+2}`).
const NCOL: usize = MAX_ORDER + 2;
/// Newton iterations per attempt (DASSL's `MAXIT`).
const MAX_NEWTON_ITERATIONS: usize = 4;
/// Newton iterations per step in fixed-step mode, where a failure cannot be
/// cured by a smaller step: the modified Newton iteration converges only
/// linearly, and convergence studies ask for tight tolerances.
const MAX_NEWTON_ITERATIONS_FIXED_STEP: usize = 20;
/// Convergence test `ρ/(1−ρ)·‖δ‖ ≤ NEWTON_TOL` (DASSL's 0.33).
const NEWTON_TOL: f64 = 0.33;
/// The same for a least-squares corrector (`odbdf`), ten times tighter: its
/// iterate satisfies the constraint rows only to the accuracy of the
/// iteration, and the error estimate `y − y⁽⁰⁾` carries what is left of it.
/// Measured on the pendulum (ovd0 and psi0; S01 at tol 1e-6, 1e-8, 1e-10,
/// S02 at 1e-8; BENCHMARKS.md §3b): 2.6–11× smaller errors with 25–42 %
/// fewer steps than with 0.33.
const NEWTON_TOL_LEAST_SQUARES: f64 = 0.033;
/// Re-evaluate the iteration matrix when `c_J/c_J^old` leaves
/// `[(1−XRATE)/(1+XRATE), (1+XRATE)/(1−XRATE)]`.
const XRATE: f64 = 0.25;
/// Unit round-off.
const EPS: f64 = f64::EPSILON;

/// Integrate `problem` with the BDF method, the corrector solved by `L`
/// (square LU, or least squares for [`crate::odbdf`]); the caller has
/// checked that the solver accepts the formulation.
pub(crate) fn integrate<L: Corrector>(
    problem: &Problem<'_>,
    options: &Options,
) -> Result<Solution, SolveError> {
    let sys = problem.system;
    let info = sys.info();
    problem.check(info.unknowns(), options)?;
    let t0 = problem.t0;

    // Components in the error test and the Newton norm.
    let in_test = policy::bdf_error_test(info, options);

    let mut spent = Stats::default();
    let yp0 = initial_derivative_with(sys, t0, problem.y0, &DerivativeRule::SOLVER)?;
    spent.residual_evals += 1; // its f(t0, y0)
    check_residuals(sys, &options.tol, t0, problem.y0, &yp0, &mut spent)?;

    let run = Run {
        sys,
        options,
        in_test: &in_test,
        t0,
        t_end: problem.t_end,
        y0: problem.y0,
        yp0: &yp0,
        spent,
    };
    match options.fixed_step {
        Some(h) => run.fixed::<L>(h),
        None => run.adaptive::<L>(),
    }
}

/// Everything a run needs, and what the driver is asked to do with it.
struct Run<'a> {
    sys: &'a dyn DaeSystem,
    options: &'a Options,
    in_test: &'a [bool],
    t0: f64,
    t_end: f64,
    y0: &'a [f64],
    yp0: &'a [f64],
    /// Work before the first step (the initial derivative and the
    /// consistency check), counted with the first run.
    spent: Stats,
}

impl<'a> Run<'a> {
    /// An integrator with settings `cfg` whose work counters start at
    /// `stats`.
    fn integrator<L: Corrector>(&self, cfg: Config, stats: Stats) -> Integrator<'a, L> {
        let mut integ = Integrator::<L>::new(self.sys, &self.options.tol, self.in_test, cfg);
        integ.stats = stats;
        integ
    }

    /// Error-controlled integration over `[t0, t_end]`.
    fn adaptive<L: Corrector>(&self) -> Result<Solution, SolveError> {
        let opts = self.options;
        let span = self.t_end - self.t0;
        let (maxord, fixed_order) = match opts.fixed_order {
            Some(k) => (k, true),
            None => (opts.max_order, false),
        };
        let cfg = Config {
            maxord,
            fixed_order,
            fixed_step: false,
            hmax: opts.h_max.unwrap_or(span),
            max_steps: opts.max_steps,
            t_end: self.t_end,
            span,
        };
        let mut integ = self.integrator::<L>(cfg, self.spent);
        let h0 = match opts.h0 {
            // Clipped before φ_2 = h y'₀ is formed, which could overflow.
            Some(h) => h.min(cfg.hmax).min(span),
            None => integ.initial_step(self.y0, self.yp0),
        };
        integ.start(self.t0, self.y0, self.yp0, h0);
        driver::solve(&mut integ, opts, self.t0, self.t_end)
    }

    /// Constant step size, order `k`, no error control; the `k−1` starting
    /// values come from an adaptive run at the caller's tolerances, which
    /// the driver runs first ([`driver::solve_with_startup`]).
    fn fixed<L: Corrector>(&self, h_request: f64) -> Result<Solution, SolveError> {
        let opts = self.options;
        let span = self.t_end - self.t0;
        let k = opts.fixed_order.unwrap_or(opts.max_order);
        let ratio = span / h_request;
        if !ratio.is_finite() || ratio > opts.max_steps as f64 {
            return Err(SolveError::StepLimit {
                t: self.t0,
                max_steps: opts.max_steps,
            });
        }
        let nsteps = if (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) {
            ratio.round()
        } else {
            ratio.ceil()
        }
        .max(1.0) as usize;
        let h = span / nsteps as f64;
        let grid = |j: usize| {
            if j == nsteps {
                self.t_end
            } else {
                self.t0 + j as f64 * h
            }
        };
        // The constant-step run, within what is left of the step budget
        // after the work `spent` before it.
        let constant = |spent: Stats| Config {
            maxord: k,
            fixed_order: true,
            fixed_step: true,
            hmax: h,
            max_steps: opts.max_steps.saturating_sub(spent.steps + spent.rejected),
            t_end: self.t_end,
            span,
        };

        // Starting values y(t0 + j h), j = 1 … m.
        let m = (k - 1).min(nsteps);
        if m == 0 {
            // Order one starts from y₀ and y'₀ alone.
            let mut integ = self.integrator::<L>(constant(self.spent), self.spent);
            integ.start(self.t0, self.y0, self.yp0, h);
            return driver::solve(&mut integ, opts, self.t0, self.t_end);
        }
        let cfg = Config {
            maxord: MAX_ORDER,
            fixed_order: false,
            fixed_step: false,
            hmax: span,
            max_steps: opts.max_steps,
            t_end: grid(m),
            span,
        };
        let mut startup = self.integrator::<L>(cfg, self.spent);
        let h0 = startup.initial_step(self.y0, self.yp0).min(h);
        startup.start(self.t0, self.y0, self.yp0, h0);
        let build = |startup: &Integrator<'a, L>, values: &[Vec<f64>]| {
            if m == nsteps {
                return None;
            }
            let mut integ = self.integrator::<L>(constant(startup.stats), Stats::default());
            // Values at t0, …, t0 + (k−1) h, oldest first.
            let mut history: Vec<&[f64]> = Vec::with_capacity(k);
            history.push(self.y0);
            history.extend(values.iter().map(|v| v.as_slice()));
            integ.start_from_history(grid(k - 1), &history, h);
            Some(integ)
        };
        driver::solve_with_startup(
            &mut startup,
            (1..=m).map(grid),
            build,
            opts,
            self.t0,
            self.t_end,
        )
    }
}

/// Settings of one integrator.
#[derive(Clone, Copy, Debug)]
struct Config {
    /// Largest order.
    maxord: usize,
    /// Never lower the order; raise it to `maxord` as soon as possible.
    fixed_order: bool,
    /// Constant step, no error test.
    fixed_step: bool,
    /// Largest step.
    hmax: f64,
    /// Step attempts allowed (accepted + rejected).
    max_steps: usize,
    /// Where to stop (never stepped over).
    t_end: f64,
    /// Length of the whole horizon (scale of the smallest step).
    span: f64,
}

/// Whether the iteration matrix is current.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum JacState {
    /// Must be evaluated and factored before the next Newton iteration.
    Needed,
    /// Evaluated during the current step attempt.
    Fresh,
    /// Evaluated on an earlier step (DASSL's `JCALC = 1`).
    Stale,
}

/// Why a step attempt was rejected.
#[derive(Clone, Copy, Debug)]
enum Failure {
    /// The corrector did not converge.
    Newton(Fail),
    /// The local error estimate exceeded the tolerance.
    ErrorTest(ErrorTest),
}

/// Result of DASSL's error test (block 4), kept for order selection.
#[derive(Clone, Copy, Debug)]
struct ErrorTest {
    /// `C_k ‖e‖`: the step is accepted when at most 1.
    err: f64,
    /// Error estimate at the order proposed for the next step.
    est: f64,
    /// Proposed order (`k` or `k−1`).
    knew: usize,
    /// `(k+1)·σ_{k+1}‖e‖`: leading error term at order `k`.
    terk: f64,
    /// Same at order `k−1`.
    terkm1: f64,
    /// `σ_k ‖e + φ*_{k+1}‖`: error estimate at order `k−1`.
    erkm1: f64,
}

/// State and workspace of the DASSL step (`N` unknowns, `M ≥ N` rows).
struct Integrator<'a, L> {
    sys: &'a dyn DaeSystem,
    cfg: Config,
    n: usize,
    constant_leading: bool,
    /// Error weights (zero for components out of the test).
    weights: Weights,

    /// Current time `t_n` (after a step: `t_{n+1}`).
    t: f64,
    /// Step size of the next attempt.
    h: f64,
    /// Step size of the last accepted step.
    hold: f64,
    /// Order of the next attempt.
    k: usize,
    /// Order of the last accepted step (0 before the first).
    kold: usize,
    /// Number of steps taken with the current `h` and `k` (capped).
    ns: usize,
    /// Initial phase: raise order and double `h` after every step.
    ramp: bool,
    /// The current step reaches `t_end`: snap `t` to it.
    last: bool,

    psi: [f64; NCOL],
    alpha: [f64; NCOL],
    beta: [f64; NCOL],
    gamma: [f64; NCOL],
    sigma: [f64; NCOL],
    /// Leading coefficient `c_J = −α_s/h`.
    cj: f64,
    /// `c_J` with which the iteration matrix was formed.
    cjold: f64,
    /// Error constant `C_k`.
    ck: f64,
    /// Newton rate factor `ρ/(1−ρ)` (100 when unknown).
    s: f64,
    jac: JacState,
    /// Newton iterations of the last attempt.
    last_iterations: usize,

    /// History `φ_1 … φ_{NCOL}`, column `j` at `phi[j n .. (j+1) n]`.
    phi: Vec<f64>,
    y: Vec<f64>,
    yp: Vec<f64>,
    /// Residual (`M`), then Newton update (`N`); scratch of length `N`.
    delta: Vec<f64>,
    /// Accumulated corrections `y − y⁽⁰⁾`.
    e: Vec<f64>,
    /// Iteration matrix, factored in place.
    lu: L,
    /// Row classes of a least-squares corrector.
    rows: Rows,
    /// `E(y)`.
    lead: DMatrix<f64>,
    /// `∂(E(y) y')/∂y`.
    lead_jac: DMatrix<f64>,

    stats: Stats,
    /// Step attempts (accepted + rejected) and failures on this step.
    budget: Budget,
}

impl<L: Corrector> Method for Integrator<'_, L> {
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.phi[..self.n]
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        self.interpolate(tau, out)
    }
    fn finished(&self) -> bool {
        self.t >= self.cfg.t_end
    }
    fn step(&mut self) -> Result<(), SolveError> {
        Integrator::step(self)
    }
    fn stats(&self) -> Stats {
        self.stats
    }
}

impl<'a, L: Corrector> Integrator<'a, L> {
    /// Allocate every buffer of the step loop.
    fn new(sys: &'a dyn DaeSystem, tol: &Tolerances, in_test: &[bool], cfg: Config) -> Self {
        let info = sys.info();
        let (m, n) = (info.equations(), info.unknowns());
        Integrator {
            sys,
            cfg,
            n,
            constant_leading: info.constant_leading,
            weights: Weights::new(tol, |_| 1.0, in_test.to_vec(), vec![0; n]),
            t: 0.0,
            h: 0.0,
            hold: 0.0,
            k: 1,
            kold: 0,
            ns: 0,
            ramp: true,
            last: false,
            psi: [0.0; NCOL],
            alpha: [0.0; NCOL],
            beta: [0.0; NCOL],
            gamma: [0.0; NCOL],
            sigma: [0.0; NCOL],
            cj: 0.0,
            cjold: 0.0,
            ck: 0.0,
            s: 100.0,
            jac: JacState::Needed,
            last_iterations: 0,
            phi: vec![0.0; n * NCOL],
            y: vec![0.0; n],
            yp: vec![0.0; n],
            delta: vec![0.0; m],
            e: vec![0.0; n],
            lu: L::new(m, n),
            rows: Rows::new(info),
            lead: DMatrix::zeros(m, n),
            lead_jac: DMatrix::zeros(m, n),
            stats: Stats::default(),
            budget: Budget::new(cfg.max_steps),
        }
    }

    /// DASSL's initial step: `0.001·(t_end − t₀)`, reduced so that
    /// `h ‖y'₀‖ ≤ 0.5`, and at most `h_max`.
    fn initial_step(&mut self, y0: &[f64], yp0: &[f64]) -> f64 {
        self.weights.update(y0);
        let mut h = 0.001 * self.cfg.span;
        let ypnorm = self.norm(yp0);
        if ypnorm > 0.5 / h {
            h = 0.5 / ypnorm;
        }
        h.min(self.cfg.hmax)
    }

    /// Start at `(t0, y0, y'0)` with order one and step `h`:
    /// `φ_1 = y₀`, `φ_2 = h y'₀`, `ψ_1 = h`.
    fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        let n = self.n;
        self.t = t0;
        self.h = h;
        self.k = 1;
        self.kold = 0;
        self.hold = 0.0;
        self.ns = 0;
        self.ramp = !self.cfg.fixed_step;
        self.psi[0] = h;
        self.cj = 1.0 / h;
        self.cjold = self.cj;
        self.s = 100.0;
        self.jac = JacState::Needed;
        self.phi.fill(0.0);
        self.phi[..n].copy_from_slice(y0);
        for (p, v) in self.phi[n..2 * n].iter_mut().zip(yp0) {
            *p = h * v;
        }
    }

    /// Start a constant-step run of order `k = values.len()` at `t` from the
    /// values at `t − (k−1)h, …, t` (oldest first): with equal spacing the
    /// modified divided differences are backward differences,
    /// `φ_{i+1} = ∇ⁱ y`. `φ_{k+1} = 0`: the first predictor has degree
    /// `k−1`, which leaves the corrector — the classical BDF-`k` — unchanged.
    fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64) {
        let n = self.n;
        let k = values.len();
        self.t = t;
        self.h = h;
        self.hold = h;
        self.k = k;
        self.kold = k;
        self.ns = 0;
        self.ramp = false;
        for (i, p) in self.psi.iter_mut().enumerate() {
            *p = (i + 1) as f64 * h;
        }
        self.cj = 1.0 / h;
        self.cjold = self.cj;
        self.s = 100.0;
        self.jac = JacState::Needed;
        self.phi.fill(0.0);
        // Difference table: after pass i, work[j] holds ∇ⁱ y at the j-th
        // point; store ∇ⁱ y at the newest point in φ_{i+1}.
        let mut work: Vec<Vec<f64>> = values.iter().map(|v| v.to_vec()).collect();
        for i in 0..k {
            self.phi[i * n..(i + 1) * n].copy_from_slice(&work[k - 1]);
            for j in (i + 1..k).rev() {
                let (lo, hi) = work.split_at_mut(j);
                for (a, b) in hi[0].iter_mut().zip(&lo[j - 1]) {
                    *a -= b;
                }
            }
        }
    }

    /// The weighted RMS norm over the components in the test.
    fn norm(&self, v: &[f64]) -> f64 {
        self.weights.norm(v)
    }

    /// Smallest step allowed at `t`.
    fn hmin(&self) -> f64 {
        control::h_min(self.t, self.cfg.span)
    }

    /// Take one step (retrying with smaller steps or lower order as needed).
    fn step(&mut self) -> Result<(), SolveError> {
        self.weights.update(&self.phi[..self.n]);

        // Step size limits and the end of the horizon.
        let remaining = self.cfg.t_end - self.t;
        let h_before = self.h;
        if !self.cfg.fixed_step {
            self.h = self.h.min(self.cfg.hmax);
        }
        // Reach t_end without a step that is tiny next to its predecessors:
        // stretch the last step by up to 10 %, or split what remains of two
        // steps into two equal ones.
        self.last = if self.cfg.fixed_step {
            remaining <= 1.5 * self.h
        } else {
            self.h >= remaining
                || (remaining <= 1.1 * self.h && remaining <= self.cfg.hmax)
                || remaining - self.h <= 4.0 * EPS * self.cfg.t_end.abs()
        };
        if self.last {
            self.h = remaining;
        } else if !self.cfg.fixed_step && remaining < 2.0 * self.h {
            self.h = 0.5 * remaining;
        }
        if self.kold == 0 && self.h != h_before {
            self.rescale_first_step(h_before);
        }
        if !self.last && self.h < self.hmin() {
            return Err(SolveError::StepSizeTooSmall {
                t: self.t,
                h: self.h,
            });
        }

        let mut nef = 0usize;
        loop {
            self.budget.attempt(self.t)?;
            let t_old = self.t;
            self.set_coefficients();
            self.t = if self.last {
                self.cfg.t_end
            } else {
                t_old + self.h
            };

            let failure = match self.corrector() {
                Ok(()) if self.cfg.fixed_step => {
                    self.accept(None);
                    self.budget.accepted();
                    if L::LEAST_SQUARES {
                        // The point a least-squares corrector converges to
                        // depends on its matrix: with constant steps a
                        // matrix kept for many steps would bias every step
                        // the same way. A fresh one each step.
                        self.jac = JacState::Needed;
                    }
                    return Ok(());
                }
                Ok(()) => {
                    let test = self.error_test();
                    if test.err <= 1.0 {
                        self.accept(Some(test));
                        self.budget.accepted();
                        return Ok(());
                    }
                    Failure::ErrorTest(test)
                }
                Err(fail) => Failure::Newton(fail),
            };

            // Block 6: the step failed.
            self.stats.rejected += 1;
            self.restore(t_old);
            self.ramp = false;
            self.last = false;
            let h_failed = self.h;
            let hmin = self.hmin();
            match failure {
                Failure::Newton(fail) => {
                    if self.cfg.fixed_step {
                        return Err(self.newton_error(fail, h_failed));
                    }
                    self.h *= 0.25;
                    let limit_hit = self.budget.failed(fail);
                    if limit_hit || self.h < hmin {
                        return Err(self.newton_error(fail, h_failed));
                    }
                }
                Failure::ErrorTest(test) => {
                    nef += 1;
                    if nef == 1 {
                        self.k = test.knew;
                        let r = 0.9 * (2.0 * test.est + 1e-4).powf(-1.0 / (self.k + 1) as f64);
                        self.h *= r.clamp(0.25, 0.9);
                    } else {
                        // From the third failure on, order one, as DASSL:
                        // at higher orders an algebraic component left off
                        // its constraint by the Newton tolerance is an error
                        // estimate that does not shrink with h. With a fixed
                        // order it is raised again after the step.
                        self.k = if nef == 2 { test.knew } else { 1 };
                        self.h *= 0.25;
                    }
                    if self.h < hmin {
                        return Err(SolveError::StepSizeTooSmall {
                            t: self.t,
                            h: self.h,
                        });
                    }
                }
            }
            if self.kold == 0 {
                self.rescale_first_step(h_failed);
            }
        }
    }

    /// Before the first step `φ_2 = h y'₀` and `ψ_1 = h` follow `h`.
    fn rescale_first_step(&mut self, h_prev: f64) {
        let n = self.n;
        let r = self.h / h_prev;
        self.psi[0] = self.h;
        for p in &mut self.phi[n..2 * n] {
            *p *= r;
        }
    }

    /// The typed error for a Newton failure at the current time with step
    /// size `h`.
    fn newton_error(&self, fail: Fail, h: f64) -> SolveError {
        Budget::error(fail, self.t, h, self.last_iterations)
    }

    /// Block 1: coefficients `ψ, α, β, γ, σ` of the new step, `c_J`, `C_k`,
    /// and `φ → φ*`. They are recomputed unless `h` and `k` have been
    /// constant for `k+1` steps.
    fn set_coefficients(&mut self) {
        let k = self.k;
        let h = self.h;
        if h != self.hold || k != self.kold {
            self.ns = 0;
        }
        self.ns = (self.ns + 1).min(self.kold + 2);
        if k + 1 >= self.ns {
            self.beta[0] = 1.0;
            self.alpha[0] = 1.0;
            self.gamma[0] = 0.0;
            self.sigma[0] = 1.0;
            let mut temp1 = h;
            for i in 1..=k {
                let temp2 = self.psi[i - 1];
                self.psi[i - 1] = temp1;
                self.beta[i] = self.beta[i - 1] * self.psi[i - 1] / temp2;
                temp1 = temp2 + h;
                self.alpha[i] = h / temp1;
                self.sigma[i] = i as f64 * self.sigma[i - 1] * self.alpha[i];
                self.gamma[i] = self.gamma[i - 1] + self.alpha[i - 1] / h;
            }
            self.psi[k] = temp1;
        }
        let mut alphas = 0.0;
        let mut alpha0 = 0.0;
        for i in 0..k {
            alphas -= 1.0 / (i + 1) as f64;
            alpha0 -= self.alpha[i];
        }
        let cjlast = self.cj;
        self.cj = -alphas / h;
        self.ck = (self.alpha[k] + alphas - alpha0).abs().max(self.alpha[k]);

        // A new iteration matrix when c_J has moved too far.
        let ratio = self.cj / self.cjold;
        let lo = (1.0 - XRATE) / (1.0 + XRATE);
        if !(lo..=1.0 / lo).contains(&ratio) {
            self.jac = JacState::Needed;
        }
        if self.cj != cjlast {
            self.s = 100.0;
        }

        // φ → φ*.
        let n = self.n;
        if self.ns <= k {
            for j in self.ns..=k {
                let b = self.beta[j];
                for p in &mut self.phi[j * n..(j + 1) * n] {
                    *p *= b;
                }
            }
        }
    }

    /// Undo block 1 after a failed attempt.
    fn restore(&mut self, t_old: f64) {
        let n = self.n;
        let k = self.k;
        self.t = t_old;
        if self.ns <= k {
            for j in self.ns..=k {
                let b = 1.0 / self.beta[j];
                for p in &mut self.phi[j * n..(j + 1) * n] {
                    *p *= b;
                }
            }
        }
        for i in 0..k {
            self.psi[i] = self.psi[i + 1] - self.h;
        }
    }

    /// Block 2: predictor `y⁽⁰⁾ = Σ φ*_i`, `y'⁽⁰⁾ = Σ γ_i φ*_i`.
    fn predict(&mut self) {
        let n = self.n;
        self.y.copy_from_slice(&self.phi[..n]);
        self.yp.fill(0.0);
        for j in 1..=self.k {
            let g = self.gamma[j];
            let col = &self.phi[j * n..(j + 1) * n];
            for ((y, yp), p) in self.y.iter_mut().zip(self.yp.iter_mut()).zip(col) {
                *y += p;
                *yp += g * p;
            }
        }
    }

    /// `δ = F(t, y, y')`.
    fn residual(&mut self) -> Result<(), Fail> {
        self.sys
            .residual(self.t, &self.y, &self.yp, &mut self.delta);
        self.stats.residual_evals += 1;
        if self.delta.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(Fail::NonFinite("residual"))
        }
    }

    /// Evaluate `G = ∂(E(y) y')/∂y − ∂f/∂y + c_J E(y)` at the predictor and
    /// factor it in place.
    fn form_iteration_matrix(&mut self) -> Result<(), Fail> {
        let sys = self.sys;
        sys.rhs_jacobian(self.t, &self.y, self.lu.matrix_mut());
        sys.leading(&self.y, &mut self.lead);
        if !self.constant_leading {
            sys.leading_jacobian(&self.y, &self.yp, &mut self.lead_jac);
        }
        self.stats.jacobian_evals += 1;
        let cj = self.cj;
        let a = self.lu.matrix_mut().as_mut_slice();
        for (g, e) in a.iter_mut().zip(self.lead.as_slice()) {
            *g = cj * e - *g;
        }
        if !self.constant_leading {
            for (g, l) in a.iter_mut().zip(self.lead_jac.as_slice()) {
                *g += l;
            }
        }
        if !a.iter().all(|v| v.is_finite()) {
            return Err(Fail::NonFinite("iteration matrix"));
        }
        self.cjold = cj;
        self.s = 100.0;
        self.jac = JacState::Fresh;
        self.stats.factorizations += 1;
        if L::LEAST_SQUARES {
            self.rows.update(&self.lead, self.weights.get());
        }
        self.lu.factor(&self.rows).map_err(|_| Fail::Singular)
    }

    /// Block 3: solve the corrector, re-evaluating the iteration matrix once
    /// if an old one fails.
    fn corrector(&mut self) -> Result<(), Fail> {
        loop {
            let stale = self.jac == JacState::Stale;
            match self.newton() {
                Ok(()) => {
                    self.jac = JacState::Stale;
                    return Ok(());
                }
                Err(Fail::Singular) => {
                    self.jac = JacState::Needed;
                    return Err(Fail::Singular);
                }
                Err(_) if stale => self.jac = JacState::Needed,
                Err(fail) => {
                    if self.jac == JacState::Fresh {
                        self.jac = JacState::Stale;
                    }
                    return Err(fail);
                }
            }
        }
    }

    /// Modified Newton iteration on the corrector from the predictor.
    fn newton(&mut self) -> Result<(), Fail> {
        self.predict();
        let pnorm = self.norm(&self.y);
        self.e.fill(0.0);
        self.last_iterations = 0;
        self.residual()?;
        if self.jac == JacState::Needed {
            self.form_iteration_matrix()?;
        }
        let damping = if self.cj != self.cjold {
            2.0 / (1.0 + self.cj / self.cjold)
        } else {
            1.0
        };
        let maxit = if self.cfg.fixed_step {
            MAX_NEWTON_ITERATIONS_FIXED_STEP
        } else {
            MAX_NEWTON_ITERATIONS
        };
        let kappa = if L::LEAST_SQUARES {
            NEWTON_TOL_LEAST_SQUARES
        } else {
            NEWTON_TOL
        };
        let mut monitor = Contraction::new(Rule::Dassl, maxit, kappa, self.s);
        loop {
            if damping != 1.0 {
                for d in &mut self.delta {
                    *d *= damping;
                }
            }
            self.lu.solve(&mut self.delta);
            self.stats.newton_iterations += 1;
            self.last_iterations += 1;
            let cj = self.cj;
            for (((y, yp), e), d) in self
                .y
                .iter_mut()
                .zip(self.yp.iter_mut())
                .zip(self.e.iter_mut())
                .zip(&self.delta)
            {
                *y -= d;
                *e -= d;
                *yp -= cj * d;
            }
            // An overflowing update is a diverging iteration, not a fault of
            // the problem: the step is retried smaller.
            let delnrm = self.norm(&self.delta);
            let verdict = monitor.observe(delnrm, 100.0 * EPS * pnorm);
            self.s = monitor.eta;
            match verdict {
                Verdict::Converged => return Ok(()),
                Verdict::Diverged | Verdict::TooSlow { .. } => return Err(Fail::Newton),
                Verdict::Continue => {}
            }
            // Non-finite at an iterate (not at the predictor): divergence.
            self.residual().map_err(|_| Fail::Newton)?;
        }
    }

    /// Block 4: local error estimate and the error terms of orders
    /// `k−2 … k` (BCP ch. 5).
    fn error_test(&mut self) -> ErrorTest {
        let n = self.n;
        let k = self.k;
        let enorm = self.norm(&self.e);
        let erk = self.sigma[k] * enorm;
        let terk = (k + 1) as f64 * erk;
        let mut test = ErrorTest {
            err: self.ck * enorm,
            est: erk,
            knew: k,
            terk,
            terkm1: 0.0,
            erkm1: 0.0,
        };
        if k > 1 {
            for ((d, p), e) in self
                .delta
                .iter_mut()
                .zip(&self.phi[k * n..(k + 1) * n])
                .zip(&self.e)
            {
                *d = p + e;
            }
            let erkm1 = self.sigma[k - 1] * self.norm(&self.delta);
            let terkm1 = k as f64 * erkm1;
            let lower = if k > 2 {
                for (d, p) in self.delta.iter_mut().zip(&self.phi[(k - 1) * n..k * n]) {
                    *d += p;
                }
                let erkm2 = self.sigma[k - 2] * self.norm(&self.delta);
                let terkm2 = (k - 1) as f64 * erkm2;
                terkm1.max(terkm2) <= terk
            } else {
                terkm1 <= 0.5 * terk
            };
            test.erkm1 = erkm1;
            test.terkm1 = terkm1;
            if lower && !self.cfg.fixed_order {
                test.knew = k - 1;
                test.est = erkm1;
            }
        }
        if test.err.is_nan() {
            test.err = f64::INFINITY;
        }
        test
    }

    /// Block 5: accept the step, choose order and step size of the next one
    /// (not in fixed-step mode), and update the differences `φ`.
    fn accept(&mut self, test: Option<ErrorTest>) {
        let n = self.n;
        let k = self.k;
        let kdiff = k as isize - self.kold as isize;
        self.kold = k;
        self.hold = self.h;
        self.stats.steps += 1;

        let mut hnew = self.h;
        if let Some(test) = test {
            let maxord = self.cfg.maxord;
            if test.knew + 1 == k || k == maxord {
                self.ramp = false;
            }
            if self.ramp {
                self.k = k + 1;
                hnew = 2.0 * self.h;
            } else {
                let mut newk = k;
                let mut est = test.est;
                if self.cfg.fixed_order {
                    newk = (k + 1).min(maxord);
                } else if test.knew + 1 == k {
                    newk = k - 1;
                    est = test.erkm1;
                } else if k < maxord && k + 1 < self.ns && kdiff != 1 {
                    for ((d, e), p) in self
                        .delta
                        .iter_mut()
                        .zip(&self.e)
                        .zip(&self.phi[(k + 1) * n..(k + 2) * n])
                    {
                        *d = e - p;
                    }
                    let erkp1 = self.norm(&self.delta) / (k + 2) as f64;
                    let terkp1 = (k + 2) as f64 * erkp1;
                    if k == 1 {
                        if terkp1 < 0.5 * test.terk {
                            newk = k + 1;
                            est = erkp1;
                        }
                    } else if test.terkm1 <= test.terk.min(terkp1) {
                        newk = k - 1;
                        est = test.erkm1;
                    } else if terkp1 < test.terk {
                        newk = k + 1;
                        est = erkp1;
                    }
                }
                self.k = newk;
                let r = (2.0 * est + 1e-4).powf(-1.0 / (newk + 1) as f64);
                if r >= 2.0 {
                    hnew = 2.0 * self.h;
                } else if r <= 1.0 {
                    hnew = self.h * r.clamp(0.5, 0.9);
                }
            }
        }
        self.h = hnew;

        // φ_{k+2} = e (for the order-raise test), φ_{k+1} += e, then
        // φ_i += φ_{i+1} for i = k … 1: the differences at t_{n+1}.
        if k < self.cfg.maxord {
            self.phi[(k + 1) * n..(k + 2) * n].copy_from_slice(&self.e);
        }
        for (p, e) in self.phi[k * n..(k + 1) * n].iter_mut().zip(&self.e) {
            *p += e;
        }
        for j in (0..k).rev() {
            let (lo, hi) = self.phi.split_at_mut((j + 1) * n);
            for (a, b) in lo[j * n..].iter_mut().zip(&hi[..n]) {
                *a += b;
            }
        }
    }

    /// Dense output (DDATRP): the interpolating polynomial of the last step,
    /// `y(t) = Σ_{i=1}^{k+1} c_i φ_i`, `c_1 = 1`,
    /// `c_{i+1} = c_i (t − t_{n+1} + ψ_{i−1})/ψ_i` (`ψ_0 = 0`).
    fn interpolate(&self, tout: f64, out: &mut [f64]) {
        let n = self.n;
        out.copy_from_slice(&self.phi[..n]);
        let dt = tout - self.t;
        let mut c = 1.0;
        let mut gamma = dt / self.psi[0];
        for j in 1..=self.kold {
            c *= gamma;
            gamma = (dt + self.psi[j - 1]) / self.psi[j];
            for (o, p) in out.iter_mut().zip(&self.phi[j * n..(j + 1) * n]) {
                *o += c * p;
            }
        }
    }
}

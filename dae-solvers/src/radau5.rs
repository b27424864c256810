//! Radau IIA of order 5 for quasi-linear DAEs, after RADAU5 of Hairer & Wanner.
//!
//! # Discretisation
//!
//! The formulation `E(y) y' = f(t, y)` (square; `E` may be singular and may
//! depend on `y`) is discretised by the three-stage Radau IIA collocation
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

use crate::core::control::{self, Budget, Failure};
use crate::core::driver::{self, Method};
use crate::core::matrix::{Rows, SquareStages, StageSystems};
use crate::core::newton::{Contraction, Rule, Verdict};
use crate::core::policy;
use crate::core::weights::Weights;
use crate::linalg::{mat_vec, Singular};
use crate::options::Options;
use crate::{NotApplicable, Problem, Solution, SolveError, Solver, Stats};
use dae_core::system::{DaeSystem, FormulationInfo};
use nalgebra::DMatrix;

/// 3-stage Radau IIA of order 5 (see the [module documentation](self)).
pub struct Radau5;

impl Solver for Radau5 {
    fn name(&self) -> &'static str {
        "radau5"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::square(info)
    }

    fn solve(&self, problem: &Problem<'_>, options: &Options) -> Result<Solution, SolveError> {
        self.accepts(problem.system.info())?;
        integrate::<SquareStages>(problem, options)
    }
}

/// Integrate with Radau IIA 5, the stage systems solved by `S` (square LU,
/// or least squares for [`crate::odradau`]); the caller has checked that
/// the solver accepts the formulation.
pub(crate) fn integrate<S: StageSystems>(
    problem: &Problem<'_>,
    options: &Options,
) -> Result<Solution, SolveError> {
    problem.check(problem.system.info().unknowns(), options)?;
    let mut integrator = Integrator::<S>::new(problem, options);
    integrator.start()?;
    driver::solve(&mut integrator, options, problem.t0, problem.t_end)
}

// ---------------------------------------------------------------------------
// Coefficients of Radau IIA (s = 3) and of RADAU5's transformation
// ---------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------
// Tuning: RADAU5's defaults
// ---------------------------------------------------------------------------

/// Maximal Newton iterations per step (`NIT`).
const NIT: usize = 7;
/// Maximal Newton iterations per step with a fixed step size, which cannot
/// be reduced instead.
const NIT_FIXED: usize = 30;
/// Safety factor of the step-size controller.
const SAFE: f64 = 0.9;
/// Recompute the Jacobian only when the contraction factor exceeded this
/// (`THET`).
const THET: f64 = 0.001;
/// Keep the step size and the factorisation when `h_new/h ∈ [QUOT1, QUOT2]`.
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
/// Step ratios are bounded by `1/FACL ≤ h_new/h ≤ 1/FACR`.
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;
/// Unit round-off.
const UROUND: f64 = f64::EPSILON * 0.5;
/// Initial step when [`Options::h0`] is not given (RADAU5's default).
const H0_DEFAULT: f64 = 1e-6;

// ---------------------------------------------------------------------------
// The tolerance map (see the module documentation)
// ---------------------------------------------------------------------------

/// Anchor `τ = 10^(−12.5)` of the tolerance map: tolerances at or below it
/// are used as given.
const TOL_ANCHOR: f64 = 3.162_277_660_168_379e-13;

/// Round-off floor `100 ε` of relative tolerances.
const TOL_FLOOR: f64 = 100.0 * f64::EPSILON;

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
fn tolerance_factor(options: &Options, i: usize) -> f64 {
    let r = options.tol.rtol(i);
    if r > 0.0 {
        internal_tolerance(r) / r
    } else {
        let a = options.tol.atol(i);
        if a > TOL_ANCHOR {
            (TOL_ANCHOR / a).powf(0.2)
        } else {
            1.0
        }
    }
}

// ---------------------------------------------------------------------------
// The integrator
// ---------------------------------------------------------------------------

/// Every buffer the step loop touches, allocated once (`N` unknowns, `M`
/// equations).
struct Work<S> {
    /// `y_n`.
    y: Vec<f64>,
    /// Stage increments `Z_1, Z_2, Z_3` (stage-major, `3N`).
    z: Vec<f64>,
    /// Transformed Newton right-hand sides (stride `M`), then increments
    /// `ΔW` (the first `N` of each block).
    dw: Vec<f64>,
    /// Stage residuals `G_i(Z)` (stride `M`).
    res: Vec<f64>,
    /// A stage value `Y_i`.
    ys: Vec<f64>,
    /// A stage derivative `Y'_i`.
    yd: Vec<f64>,
    /// `f(t_n, y_n)` (`M`).
    f0: Vec<f64>,
    /// `y'(t_n)` from the last collocation polynomial (for `∂(E z)/∂y`).
    yp: Vec<f64>,
    /// Error weights, index-scaled.
    weights: Weights,
    /// Row classes of the least-squares systems.
    rows: Rows,
    /// Collocation polynomial of the last accepted step (`4N`).
    cont: Vec<f64>,
    /// Error estimate (`M` in, `N` out) and temporaries.
    err: Vec<f64>,
    tmp: Vec<f64>,
    fm: Vec<f64>,
    ez: Vec<f64>,
    /// `J = ∂f/∂y − ∂(E z)/∂y` at the Jacobian point.
    jac: DMatrix<f64>,
    /// `∂(E z)/∂y`.
    ljac: DMatrix<f64>,
    /// `E` at the Jacobian point (`E₀` of the iteration matrices).
    e_jac: DMatrix<f64>,
    /// `E(y_n)`.
    e_n: DMatrix<f64>,
    /// `γ/h E₀ − J` and `(α + iβ)/h E₀ − J`, factorised.
    stages: S,
}

impl<S: StageSystems> Work<S> {
    fn new(info: &FormulationInfo, options: &Options) -> Self {
        let (m, n) = (info.equations(), info.unknowns());
        let v = |len: usize| vec![0.0; len];
        let mat = || DMatrix::zeros(m, n);
        Work {
            y: v(n),
            z: v(3 * n),
            dw: v(3 * m),
            res: v(3 * m),
            ys: v(n),
            yd: v(n),
            f0: v(m),
            yp: v(n),
            weights: Weights::new(
                &options.tol,
                |i| tolerance_factor(options, i),
                vec![true; n],
                info.variables
                    .iter()
                    .map(|var| i32::from(var.index.max(1)) - 1)
                    .collect(),
            ),
            rows: Rows::new(info),
            cont: v(4 * n),
            err: v(m),
            tmp: v(n),
            fm: v(m),
            ez: v(m),
            jac: mat(),
            ljac: mat(),
            e_jac: mat(),
            e_n: mat(),
            stages: S::new(m, n),
        }
    }
}

/// Outcome of one simplified Newton iteration.
enum Newton {
    /// Converged after this many iterations.
    Converged(usize),
    /// Converging too slowly: retry with the step multiplied by `factor`.
    TooSlow { iterations: usize, factor: f64 },
    /// Diverged or did not converge within `NIT` iterations.
    Diverged(usize),
    /// A residual or an increment was not finite.
    NonFinite(usize),
}

/// What the step loop does next (RADAU5's labels 10, 20, 30).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Next {
    /// Evaluate the Jacobian, factorise, step.
    Jacobian,
    /// Factorise with the current `h`, step.
    Factor,
    /// Step with the current factorisation.
    Step,
}

struct Integrator<'a, S> {
    sys: &'a dyn DaeSystem,
    options: &'a Options,
    n: usize,
    m: usize,
    t0: f64,
    t_end: f64,
    constant_leading: bool,
    w: Work<S>,
    stats: Stats,
    /// Contraction monitor; its `η` is carried from step to step and its
    /// `θ` decides Jacobian reuse.
    newton: Contraction,
    /// Step-size controller state.
    c: Control,
}

/// RADAU5's controller state (its `FIRST`, `REJECT`, `CALJAC`, `HOLD`,
/// `HACC`, `ERRACC`, `LAST`) between and within steps.
struct Control {
    /// Time of the last accepted step (`t₀` at first).
    t: f64,
    /// Step size of the next attempt.
    h: f64,
    /// Largest step.
    h_max: f64,
    /// Constant step size (no error control), if any.
    fixed: Option<f64>,
    /// The next attempt reaches `t_end`.
    last: bool,
    /// `t_end` reached.
    done: bool,
    first: bool,
    reject: bool,
    caljac: bool,
    /// Size of the last accepted step.
    h_old: f64,
    h_acc: f64,
    err_acc: f64,
    budget: Budget,
    next: Next,
}

impl Control {
    /// After a failed attempt: factorise again with the Jacobian of this
    /// step, or evaluate a new one if it is old.
    fn after_failure(&self) -> Next {
        if self.caljac {
            Next::Factor
        } else {
            Next::Jacobian
        }
    }

    /// A step ending within this of `t_end` is stretched to it: round-off
    /// for adaptive steps, a relative 1e-8 for fixed ones.
    fn end_slack(&self, t: f64, h: f64, t_end: f64) -> f64 {
        match self.fixed {
            Some(_) => 1e-8 * h,
            None => 100.0 * UROUND * t.abs().max(t_end.abs()),
        }
    }
}

impl<S: StageSystems> Method for Integrator<'_, S> {
    fn t(&self) -> f64 {
        self.c.t
    }
    fn y(&self) -> &[f64] {
        &self.w.y
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        dense(self.n, &self.w.cont, tau, self.c.t, self.c.h_old, out)
    }
    fn finished(&self) -> bool {
        self.c.done
    }
    fn step(&mut self) -> Result<(), SolveError> {
        Integrator::step(self)
    }
    fn stats(&self) -> Stats {
        self.stats
    }
}

impl<'a, S: StageSystems> Integrator<'a, S> {
    fn new(problem: &Problem<'a>, options: &'a Options) -> Self {
        let info = problem.system.info();
        let (m, n) = (info.equations(), info.unknowns());
        let mut w = Work::<S>::new(info, options);
        w.y.copy_from_slice(problem.y0);
        // RADAU5: fnewt = max(10 u / rtol, min(0.03, rtol^(1/2))), here
        // with the smallest relative tolerance (an absolute one where all
        // relative tolerances are zero), kept above 10 u.
        let rmin = w
            .weights
            .rtol()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let r = if rmin > 0.0 {
            rmin
        } else {
            w.weights
                .atol()
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
        };
        let r = r.max(10.0 * UROUND);
        let fnewt = (10.0 * UROUND / r).max(0.03f64.min(r.sqrt()));
        let rule = Rule::Radau5 {
            slow_exit: options.fixed_step.is_none(),
        };
        let span = problem.t_end - problem.t0;
        Integrator {
            sys: problem.system,
            options,
            n,
            m,
            t0: problem.t0,
            t_end: problem.t_end,
            constant_leading: info.constant_leading,
            w,
            stats: Stats::default(),
            newton: Contraction::new(rule, NIT, fnewt, 1.0),
            c: Control {
                t: problem.t0,
                h: 0.0,
                h_max: options.h_max.unwrap_or(span).min(span),
                fixed: options.fixed_step,
                last: false,
                done: false,
                first: true,
                reject: false,
                caljac: false,
                h_old: 0.0,
                h_acc: 0.0,
                err_acc: 1e-2,
                budget: Budget::new(options.max_steps),
                next: Next::Jacobian,
            },
        }
    }

    /// `f(t, y_n)` into `f0`, and `E(y_n)` when it is not constant (or
    /// `first`).
    fn evaluate_at_step_point(&mut self, t: f64, first: bool) -> Result<(), SolveError> {
        self.sys.rhs(t, &self.w.y, &mut self.w.f0);
        self.stats.residual_evals += 1;
        if self.w.f0.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                t,
                what: "residual",
            });
        }
        if first || !self.constant_leading {
            self.sys.leading(&self.w.y, &mut self.w.e_n);
            if self.w.e_n.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::NonFinite {
                    t,
                    what: "leading matrix",
                });
            }
        }
        Ok(())
    }

    /// Evaluate at `t₀` and choose the first step.
    fn start(&mut self) -> Result<(), SolveError> {
        let (t0, t_end) = (self.t0, self.t_end);
        let span = t_end - t0;
        self.evaluate_at_step_point(t0, true)?;
        let c = &mut self.c;
        c.h = match c.fixed {
            Some(hf) => hf,
            // A tiny h0 is raised to well above the smallest step.
            None => self
                .options
                .h0
                .unwrap_or(H0_DEFAULT)
                .min(c.h_max)
                .max(100.0 * control::h_min(t0, span)),
        };
        if t0 + c.h >= t_end - c.end_slack(t0, c.h, t_end) {
            c.h = span;
            c.last = true;
        }
        c.h_old = c.h;
        c.h_acc = c.h;
        Ok(())
    }

    /// One accepted step from `c.t` (RADAU5's loop from label 10 to the
    /// acceptance of a step), then the size of the next one.
    fn step(&mut self) -> Result<(), SolveError> {
        let t_end = self.t_end;
        let span = t_end - self.t0;
        loop {
            let (t, h, fixed) = (self.c.t, self.c.h, self.c.fixed);
            if fixed.is_none() && h < control::h_min(t, span) {
                return Err(SolveError::StepSizeTooSmall { t, h });
            }
            if self.c.next == Next::Jacobian {
                self.jacobian(t)?;
                self.c.caljac = true;
                self.c.next = Next::Factor;
            }
            if self.c.next == Next::Factor {
                if self.factor(h).is_err() {
                    let c = &mut self.c;
                    if fixed.is_some() || c.budget.failed(Failure::Singular) {
                        return Err(SolveError::SingularMatrix { t, h });
                    }
                    c.h *= 0.5;
                    c.reject = true;
                    c.last = false;
                    c.next = c.after_failure();
                    continue;
                }
                self.stats.factorizations += 1;
            }
            self.c.budget.attempt(t)?;

            // ---- one step attempt from t with h ----
            self.w.weights.update_scaled(&self.w.y, h);
            self.starting_values(self.c.first, h / self.c.h_old);

            let outcome = self.newton(t, h, fixed.is_none());
            let newt = match outcome {
                Newton::Converged(k) => k,
                Newton::TooSlow { iterations, .. }
                | Newton::Diverged(iterations)
                | Newton::NonFinite(iterations) => iterations,
            };
            self.stats.newton_iterations += newt;

            let failed_factor = match outcome {
                Newton::Converged(_) => None,
                Newton::TooSlow { factor, .. } => Some(factor),
                Newton::Diverged(_) | Newton::NonFinite(_) => Some(0.5),
            };
            // Error estimate and proposed step (adaptive mode only).
            let mut err = 0.0;
            let mut h_new = h;
            let mut non_finite = matches!(outcome, Newton::NonFinite(_));
            let mut newton_failed = failed_factor.is_some();
            if !newton_failed && fixed.is_none() {
                err = self.error_norm(t, h, self.c.first || self.c.reject);
                if err.is_finite() {
                    h_new = h / classical_quotient(err, newt);
                } else {
                    non_finite = true;
                    newton_failed = true;
                }
            }

            let c = &mut self.c;
            if newton_failed {
                // ---- Newton failure (RADAU5's label 78) ----
                self.stats.rejected += 1;
                let failure = if non_finite {
                    Failure::NonFinite("residual")
                } else {
                    Failure::Newton
                };
                let exhausted = c.budget.failed(failure);
                if fixed.is_some() && !c.caljac {
                    c.next = Next::Jacobian;
                    continue;
                }
                if fixed.is_some() || exhausted {
                    return Err(Budget::error(failure, t, h, newt));
                }
                c.h *= failed_factor.unwrap_or(0.5);
                c.reject = true;
                c.last = false;
                c.next = c.after_failure();
                continue;
            }

            if err >= 1.0 {
                // ---- rejected by the error test ----
                self.stats.rejected += 1;
                c.reject = true;
                c.last = false;
                if c.first {
                    c.h *= 0.1;
                } else {
                    c.h = h_new;
                }
                c.next = c.after_failure();
                continue;
            }

            // ---- accepted ----
            c.budget.accepted();
            if fixed.is_none() {
                if self.stats.steps > 0 {
                    let quot = (h / h_new).max(predictive_quotient(err, c.err_acc, h, c.h_acc));
                    h_new = h / quot;
                }
                c.h_acc = h;
                c.err_acc = err.max(1e-2);
            }
            c.first = false;
            c.t = if c.last { t_end } else { t + h };
            c.h_old = h;
            c.caljac = false;
            self.advance(h);
            self.stats.steps += 1;
            let t = self.c.t;
            if self.w.y.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::NonFinite {
                    t,
                    what: "solution",
                });
            }
            if self.c.last {
                self.c.done = true;
                return Ok(());
            }
            self.evaluate_at_step_point(t, false)?;
            self.next_step(h_new);
            return Ok(());
        }
    }

    /// Size of the next step after one accepted with proposal `h_new`, and
    /// whether the factorisation (or the Jacobian) can be kept.
    fn next_step(&mut self, mut h_new: f64) {
        let t_end = self.t_end;
        let small_theta = self.newton.theta <= THET;
        let c = &mut self.c;
        let (t, h) = (c.t, c.h);
        if let Some(hf) = c.fixed {
            let remaining = t_end - t;
            let h_next = if t + hf >= t_end - c.end_slack(t, hf, t_end) {
                c.last = true;
                remaining
            } else {
                hf
            };
            let new_h = h_next != h;
            c.h = h_next;
            c.next = match (small_theta, new_h) {
                (true, false) => Next::Step,
                (true, true) => Next::Factor,
                (false, _) => Next::Jacobian,
            };
            return;
        }
        h_new = h_new.min(c.h_max);
        if c.reject {
            h_new = h_new.min(h);
        }
        c.reject = false;
        if t + h_new >= t_end - c.end_slack(t, h_new, t_end) {
            c.h = t_end - t;
            c.last = true;
        } else {
            if t + 2.0 * h_new > t_end {
                // Split the rest evenly rather than end with a short step:
                // after a large step-size ratio the index-2 and index-3
                // components lose accuracy (HW VII.4), and the last step is
                // where they are reported.
                h_new = 0.5 * (t_end - t);
            }
            let qt = h_new / h;
            if small_theta && (QUOT1..=QUOT2).contains(&qt) {
                c.next = Next::Step;
                return;
            }
            c.h = h_new;
        }
        c.next = if small_theta {
            Next::Factor
        } else {
            Next::Jacobian
        };
    }

    /// `J = ∂f/∂y − ∂(E z)/∂y` and `E₀` at `(t, y_n)`.
    fn jacobian(&mut self, t: f64) -> Result<(), SolveError> {
        let w = &mut self.w;
        self.sys.rhs_jacobian(t, &w.y, &mut w.jac);
        if !self.constant_leading {
            self.sys.leading_jacobian(&w.y, &w.yp, &mut w.ljac);
            for (j, l) in w.jac.as_mut_slice().iter_mut().zip(w.ljac.as_slice()) {
                *j -= l;
            }
        }
        w.e_jac.copy_from(&w.e_n);
        self.stats.jacobian_evals += 1;
        if w.jac.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                t,
                what: "jacobian",
            });
        }
        Ok(())
    }

    /// Factorise `γ/h E₀ − J` and `(α + iβ)/h E₀ − J`.
    fn factor(&mut self, h: f64) -> Result<(), Singular> {
        let w = &mut self.w;
        if S::LEAST_SQUARES {
            w.weights.update_scaled(&w.y, h);
            w.rows.update(&w.e_jac, w.weights.get());
        }
        w.stages
            .factor(&w.e_jac, &w.jac, GAMMA / h, ALPHA / h, BETA / h, &w.rows)
    }

    /// Zero on the first step, otherwise the last collocation polynomial
    /// extrapolated to the new nodes (`ratio = h / h_old`).
    fn starting_values(&mut self, first: bool, ratio: f64) {
        let n = self.n;
        let w = &mut self.w;
        if first {
            w.z.fill(0.0);
            return;
        }
        for (i, &ci) in C.iter().enumerate() {
            let s = ci * ratio;
            for k in 0..n {
                let d = [w.cont[n + k], w.cont[2 * n + k], w.cont[3 * n + k]];
                w.z[i * n + k] = polynomial_increment(&d, s);
            }
        }
    }

    /// Stage residuals `G_i(Z) = E(Y_i) Y'_i − f(t + c_i h, Y_i)` into `res`.
    fn stage_residuals(&mut self, t: f64, h: f64) {
        let (n, m) = (self.n, self.m);
        let w = &mut self.w;
        for (i, &ci) in C.iter().enumerate() {
            for k in 0..n {
                let (z1, z2, z3) = (w.z[k], w.z[n + k], w.z[2 * n + k]);
                w.ys[k] = w.y[k] + w.z[i * n + k];
                w.yd[k] = (AINV[i][0] * z1 + AINV[i][1] * z2 + AINV[i][2] * z3) / h;
            }
            self.sys
                .residual(t + ci * h, &w.ys, &w.yd, &mut w.res[i * m..(i + 1) * m]);
        }
        self.stats.residual_evals += 3;
    }

    /// Simplified Newton iteration for the stage increments (RADAU5's loop
    /// at label 40). `may_shorten` allows the early exit on slow
    /// convergence; without it (fixed-step mode) up to `NIT_FIXED`
    /// iterations are made.
    fn newton(&mut self, t: f64, h: f64, may_shorten: bool) -> Newton {
        let (n, m) = (self.n, self.m);
        let max_iter = if may_shorten { NIT } else { NIT_FIXED };
        let eta = self.newton.eta.max(UROUND).powf(0.8);
        self.newton.restart(max_iter, eta, THET);
        loop {
            self.stage_residuals(t, h);
            let w = &mut self.w;
            if w.res.iter().any(|v| !v.is_finite()) {
                return Newton::NonFinite(self.newton.iterations());
            }
            // R = −(T⁻¹ ⊗ I) G.
            for k in 0..m {
                let (g1, g2, g3) = (w.res[k], w.res[m + k], w.res[2 * m + k]);
                for (r, ti) in TI.iter().enumerate() {
                    w.dw[r * m + k] = -(ti[0] * g1 + ti[1] * g2 + ti[2] * g3);
                }
            }
            w.stages.solve_real(&mut w.dw[..m]);
            let (re, im) = w.dw[m..].split_at_mut(m);
            w.stages.solve_complex(re, im);

            let dyno = w.weights.norm_blocks(&w.dw, m, 3);
            if !dyno.is_finite() {
                return Newton::NonFinite(self.newton.iterations() + 1);
            }
            let verdict = self.newton.observe(dyno, 0.0);
            let iterations = self.newton.iterations();
            match verdict {
                Verdict::Diverged => return Newton::Diverged(iterations),
                Verdict::TooSlow { factor } => {
                    return Newton::TooSlow { iterations, factor };
                }
                Verdict::Continue | Verdict::Converged => {}
            }

            // Z += (T ⊗ I) ΔW   (T₃₂ = 1, T₃₃ = 0).
            let w = &mut self.w;
            for k in 0..n {
                let (a1, a2, a3) = (w.dw[k], w.dw[m + k], w.dw[2 * m + k]);
                w.z[k] += T[0][0] * a1 + T[0][1] * a2 + T[0][2] * a3;
                w.z[n + k] += T[1][0] * a1 + T[1][1] * a2 + T[1][2] * a3;
                w.z[2 * n + k] += T[2][0] * a1 + a2;
            }
            if verdict == Verdict::Converged {
                return Newton::Converged(iterations);
            }
        }
    }

    /// Scaled norm of the embedded error estimate; NaN if it is not finite.
    fn error_norm(&mut self, t: f64, h: f64, refine: bool) -> f64 {
        let (n, m) = (self.n, self.m);
        let w = &mut self.w;
        // tmp = (1/h) Σ d_i Z_i,  ez = E(y_n) tmp.
        for k in 0..n {
            w.tmp[k] = (DD[0] * w.z[k] + DD[1] * w.z[n + k] + DD[2] * w.z[2 * n + k]) / h;
        }
        mat_vec(&w.e_n, &w.tmp, &mut w.ez);
        for k in 0..m {
            w.err[k] = w.f0[k] + w.ez[k];
        }
        w.stages.solve_real(&mut w.err);
        let mut err = w.weights.norm(&w.err[..n]);
        if err >= 1.0 && refine {
            for k in 0..n {
                w.ys[k] = w.y[k] + w.err[k];
            }
            self.sys.rhs(t, &w.ys, &mut w.fm);
            self.stats.residual_evals += 1;
            for k in 0..m {
                w.err[k] = w.fm[k] + w.ez[k];
            }
            w.stages.solve_real(&mut w.err);
            err = w.weights.norm(&w.err[..n]);
        }
        if err.is_nan() {
            f64::NAN
        } else {
            err.max(1e-10)
        }
    }

    /// Accept the step: `y_{n+1} = y_n + Z_3`, the new collocation
    /// polynomial (Newton form on `s = 0, c₂ − 1, c₁ − 1, −1`) and
    /// `y'_{n+1} = Y'_3`.
    fn advance(&mut self, h: f64) {
        let n = self.n;
        let w = &mut self.w;
        for k in 0..n {
            let (z1, z2, z3) = (w.z[k], w.z[n + k], w.z[2 * n + k]);
            w.y[k] += z3;
            let d = divided_differences(z1, z2, z3);
            w.cont[k] = w.y[k];
            w.cont[n + k] = d[0];
            w.cont[2 * n + k] = d[1];
            w.cont[3 * n + k] = d[2];
            w.yp[k] = (AINV[2][0] * z1 + AINV[2][1] * z2 + AINV[2][2] * z3) / h;
        }
    }
}

/// The collocation polynomial `cont` (`4N`) of the step `[t − h, t]` at
/// `tau` into `out`.
fn dense(n: usize, cont: &[f64], tau: f64, t: f64, h: f64, out: &mut [f64]) {
    let s = (tau - t) / h;
    for k in 0..n {
        let d = [cont[n + k], cont[2 * n + k], cont[3 * n + k]];
        out[k] = cont[k] + polynomial_increment(&d, s);
    }
}

/// The classical step-size quotient `q = h/h_new` (HW IV.8 (8.21)):
/// `clamp(‖err‖^(1/4) / fac, 1/8, 5)` with the safety factor
/// `fac = min(0.9, 0.9 (2 NIT + 1) / (newt + 2 NIT))` lowered when Newton
/// needed many iterations.
fn classical_quotient(err: f64, newt: usize) -> f64 {
    let fac = SAFE.min(SAFE * (2 * NIT + 1) as f64 / (newt + 2 * NIT) as f64);
    FACR.max(FACL.min(err.sqrt().sqrt() / fac))
}

/// Gustafsson's predictive quotient (HW IV.8 (8.25)):
/// `clamp((h_acc/h) (‖err‖² / ‖err_acc‖)^(1/4) / 0.9, 1/8, 5)`, with
/// `h_acc`, `err_acc` of the previous accepted step.
fn predictive_quotient(err: f64, err_acc: f64, h: f64, h_acc: f64) -> f64 {
    ((h_acc / h) * (err * err / err_acc).sqrt().sqrt() / SAFE).clamp(FACR, FACL)
}

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

    fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    fn assert_close(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], tol: f64) {
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

    const I3: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn coefficients_are_consistent() {
        let a = radau_a();
        assert_close(&mul(&a, &AINV), &I3, 1e-14);
        assert_close(&mul(&T, &TI), &I3, 1e-14);
        let lambda = mul(&mul(&TI, &AINV), &T);
        let expect = [[GAMMA, 0.0, 0.0], [0.0, ALPHA, -BETA], [0.0, BETA, ALPHA]];
        assert_close(&lambda, &expect, 1e-13);
        // Row sums of A are the nodes; the last row is b (stiff accuracy).
        for i in 0..3 {
            assert!((a[i].iter().sum::<f64>() - C[i]).abs() < 1e-15);
        }
        assert!((C1 - (4.0 - 6f64.sqrt()) / 10.0).abs() < 1e-16);
        assert!((DD[0] + (13.0 + 7.0 * 6f64.sqrt()) / 3.0).abs() < 1e-14);
        assert!((DD[1] - (-13.0 + 7.0 * 6f64.sqrt()) / 3.0).abs() < 1e-14);
        let g0 = (6.0 + 81f64.cbrt() - 9f64.cbrt()) / 30.0;
        assert!((GAMMA - 1.0 / g0).abs() < 1e-14);
    }

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

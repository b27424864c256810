//! The linearly implicit Euler method with iterated defect correction
//! (IDeC) for semi-explicit DAEs of index 1 and 2, after S. Somali,
//! *Iterated defect correction methods for non-linear DAEs of index 2*
//! (seed 002 of the project).
//!
//! # The basic scheme
//!
//! For `E y' = f(t, y)` with a constant leading matrix (semi-explicit:
//! `E = diag(I, 0)`, or the pendulum's `diag(1, 1, m, m, 0)`), the linearly
//! implicit Euler method (LIE) is
//!
//! ```text
//!     (E − h J) (η_{k+1} − η_k) = h f(t_k, η_k),        J = ∂f/∂y,
//! ```
//!
//! one linear solve per step, no Newton iteration. For `y' = f(y, z),
//! 0 = g(y)` its constraint rows read `g(y_k) + g_y (y_{k+1} − y_k) = 0`:
//! the new value lies on the linearised constraint, which determines the
//! index-2 unknowns `z_{k+1}`. The method has order one in every component
//! (seed §3, an asymptotic error expansion in powers of `h`).
//!
//! # Iterated defect correction (seed §2)
//!
//! The steps are grouped into intervals of `m` steps of equal size. On an
//! interval, `p^[j]` is the polynomial of degree `m` through the current
//! approximation `η^[j]` at the `m + 1` nodes — all components, the
//! algebraic ones included, as in the seed's `P^[j]` and `Q^[j]`. Its
//! defect
//!
//! ```text
//!     d^[j](t) = E p^[j]'(t) − f(t, p^[j](t))
//! ```
//!
//! (the seed's `d₁ = P' − f(P, Q)` on the differential rows and
//! `d₂ = −g(P)` on the constraint rows) defines the *neighbouring problem*
//! `E y' = f(t, y) + d^[j](t)`, whose exact solution is `p^[j]`. Solved by
//! the same LIE with the same matrix (the defect is sampled at the step's
//! start, as `f` is), it gives `π^[j]`, and `π^[j] − η^[j]` estimates the
//! error the scheme makes; the correction removes it from the basic
//! solution:
//!
//! ```text
//!     η^[j+1]_k = η^[0]_k − (π^[j]_k − η^[j]_k)         (seed (2.5a), (2.5b)).
//! ```
//!
//! The algebraic components are corrected by the same formula; the only
//! index-2 specific point is that the neighbouring problem's constraint rows
//! carry `−g(p^[j])`, so that `π^[j]` satisfies the *perturbed* linearised
//! constraint and the correction of `z` sees exactly the scheme's error in
//! `z`. After `j` corrections the order is `min(j + 1, m)` in the
//! differential and the algebraic components alike (seed §4, Theorem);
//! [`Idec::j`] and [`Idec::m`] are the two parameters.
//!
//! # Constant steps (`Options::fixed_step = Some(h)`): the seed's scheme
//!
//! `J` is evaluated once, at `(t₀, y₀)`, and frozen for the whole
//! integration, as in the seed ((2.2)); `E − hJ` is factorised once (again
//! for a last, shorter interval). Each level `η^[l]` and each `π^[j]`
//! continues from its own value at the end of the previous interval — the
//! seed's *global connection* ((2.7), (3.6)): the neighbouring problems
//! of consecutive intervals form one piecewise problem on the whole
//! horizon, so `π^[j] − η^[j]` estimates the *global* error of the scheme.
//! The reported solution is `η^[J]`. When `m h` does not divide the
//! horizon, the last interval has `m` equal steps of the remaining length
//! over `m`; it starts afresh from `η^[J]` with a Jacobian there (levels
//! carried over hold the error expansion of the old step, which a new step
//! would mix with its own: the index-2 unknowns went wrong by `O(1)`). [`Idec::levels`] returns every `η^[l]` at `t_end`, the
//! seed's tables.
//!
//! Every level and every `π^[j]` is a running sum over the whole horizon
//! (`y_{k+1} = y_k + Δ`), so with constant steps the sums are compensated:
//! each value carried from step to step is held as `hi + lo` and updated
//! with exact two-sums, and the corrections and the interpolant's
//! derivative are formed from both parts (`f`, `J` and the solves see `hi`
//! only). The scheme is the same; only its round-off changes. Error
//! control (below) restarts every `m` steps and keeps plain sums.
//!
//! # Constant steps on the pendulum (`Idec::levels_with`, `Jacobian::EveryStep`)
//!
//! The frozen Jacobian goes non-finite on the pendulum (t ≈ 0.5). With the
//! global connection kept and `J` evaluated at every Euler step at that
//! step's own point (the basic solution at `η^[0]_k`, each neighbouring
//! problem at `π^[j]_k`) the orders are 1, 2, 3, 4 after 0…3 corrections on
//! `rcd1` and `ggl1`, in x, y, v, w and in λ (t = 1, `examples/
//! idec_pendulum.rs`). Measured alternatives that do *not* give them: a
//! Jacobian per interval at the best value with the global connection
//! (2.DC and 3.DC stay at order ≈ 2: the constraint rows are linearised at
//! a point that jumps at every interval start, a sawtooth in `t` that the
//! error expansion inherits); any restart of the levels from the accepted
//! value (order 2, with or without a Jacobian per step, with or without
//! extrapolating `z` at the first node). Over S01's 20 s the uncorrected
//! basic solution's phase error is O(1) for `h ≥ 1e-4`; from `h ≈ 1.25e-5`
//! down the levels show orders 1, 2, 3 at t = 20. With plain sums the third
//! correction reached a round-off floor (about 1e-8, growing like `1/h`
//! with the number of steps) before its order 4 showed; with the
//! compensated sums it falls to 1e-12 and below (docs/bench_idec.md §5).
//! The interval ends are summed with compensation (`core::onestep`, as
//! the collocation engine's steps at tight tolerances; before, `t₀ + n m h`):
//! a plain sum over 10⁵ intervals drifted until the last interval looked
//! shorter than `m h`, which restarted every level from the best value there.
//!
//! # Variable steps (the default)
//!
//! A Jacobian frozen at `t₀` cannot carry the pendulum over 20 s: on a
//! nonlinear problem `E − hJ(t₀)` stops being a good approximation of the
//! scheme's matrix and the constraint rows are no longer linearised at the
//! right point, so the step size collapses. With error control the
//! Jacobian is therefore evaluated afresh at the start of every interval
//! (kept for retries of that interval), and every level starts the interval
//! from the accepted value (local connection: `π^[j] − η^[j]` then
//! estimates the error made on this interval, which is what a step-size
//! controller needs). The Euler step `h` is constant on an interval and
//! chosen per interval:
//!
//! * each Euler step evaluates `f` at its *end* time, `(E − hJ)(η_{k+1} −
//!   η_k) = h f(t_{k+1}, η_k)`, and so does the neighbouring problem,
//!   whose defect is therefore sampled at the step's end node `t_{k+1}`
//!   (the seed samples both at `t_k`). Both are the linearly implicit
//!   Euler method of order one, but they differ in what the corrections
//!   converge to: `η^[j+1] = η^[j]` when the sampled defect vanishes, so
//!   the limit is the polynomial that collocates at the sampled nodes. At
//!   `0 … m − 1` that is a method with an explicit first stage whose
//!   stability function is unbounded at infinity: on a stiff problem the
//!   corrections amplify the stiff components until `h ‖J‖` is of order
//!   one (the transistor amplifier of the IVP Test Set took 301 644 Euler
//!   steps at tol 1e-4 and crawled to the step limit from 1e-5 on, the
//!   estimate falling only like `h^2.3` at `h ≈ 2e-5`). At `1 … m` the
//!   limit is collocation ending at the last node, stiffly accurate: the
//!   amplifier takes 4 220 steps at 1e-4 and 189 640 at 1e-10, every
//!   tolerance reaching the published values (EXTREMES.md, "idec on the
//!   literature map"). The price is `m` more evaluations of `f` per
//!   interval (level 0's defect is no longer the basic solution's `f`);
//! * error estimate: `err = ‖η^[J] − η^[J−1]‖` at the end of the interval,
//!   the difference between the last two corrections, in the core's
//!   weighted RMS norm with the weights of the interval's start value;
//! * controller: `h_new = h · clamp(0.9 · err^(−1/(q+1)), 0.2, 5)`, with
//!   `q = min(J, m)` the order of `η^[J−1]`; no increase right after a
//!   rejection; the last interval is stretched to `t_end`, and a remainder of
//!   less than two intervals is split evenly;
//! * the solution reported is `η^[J]`; dense output on an interval is its
//!   interpolating polynomial of degree `m` (below).
//!
//! **Index 2 is refused with error control** ([`NotApplicable::RestartedIndexTwo`];
//! the constant-step scheme takes it). The restart costs order in the index-2
//! unknowns: the Euler values `z_1 … z_m` carry an `O(h)` error set by the
//! constraint rows, while `z_0` is the accepted value, so the interpolant
//! of `z` has a jump of `O(h)` between the first two nodes that the
//! corrections cannot remove; the seed's global connection sees that jump
//! once (at `t₀`), a restarted interval every time. On the constant-step
//! test problem, restarting every interval drops the observed order of
//! 3.DC to about 1. With error control on `rcd1` and `ggl1` of the
//! pendulum, the estimate of `λ` then behaves like `h²` (index-scaled) and
//! the number of steps grows like `tol^(−1/2)`; the error still follows
//! the tolerance (`5·10² – 2·10³ · tol` at t = 20 of S01). On `rcd0` (index 1) the
//! steps grow like `tol^(−1/3)`. (Measured with the defect sampled at the
//! steps' start; sampled at their end, as now, the index-2 forms of the
//! literature map finish, in far fewer steps, but short of the digits the
//! tolerance asks at most tolerances — pendulum, car axis, Jay's problem,
//! the CV loop — hence the refusal.) Replacing `z_0` by its extrapolation from
//! `z_1 … z_m` was tried and did not help (the constraint residual of the
//! differential unknowns jumps too). With the defect sampled at the steps'
//! start the interior nodes' algebraic values also stayed off by more than
//! the ends' (λ of the pendulum at tol 1e-8 over 5 s, `rcd0`: 4.3e-4
//! against 3.8e-6), and dense output took them from a cubic through the
//! last four ends; sampled at the end (the limit collocates at the interior
//! nodes too) the interval's own polynomial is as accurate between the
//! ends as at them (`tests/idec.rs`,
//! `dense_output_of_lambda_follows_the_interval_ends`). The global connection is not used
//! with error control: its basic solution `η^[0]` is an uncorrected
//! first-order solution over the whole horizon, far outside the asymptotic
//! regime the corrections rely on for a 20 s pendulum run, and the
//! difference of two levels would estimate the global, not the local,
//! error.
//!
//! # Counters and failures
//!
//! `Stats::steps` counts accepted Euler steps (`m` per interval),
//! `rejected` rejected intervals, `residual_evals` evaluations of `f`
//! (`2 m J` per interval with constant steps: `m` for the basic solution,
//! `m` for each neighbouring problem, `m` for the defect of each level
//! after the first; with error control `m` more, for level 0's defect),
//! `jacobian_evals` and `factorizations` as
//! named; there is no Newton iteration (`newton_iterations = 0`).
//! [`Options::max_steps`] bounds the interval attempts. Failures are the
//! core's typed errors within its budgets: a singular `E − hJ` or a
//! non-finite value halves `h` (with error control; at once the typed error
//! with constant steps), a step below `core::control::h_min` is
//! [`SolveError::StepSizeTooSmall`].
//!
//! # What it accepts
//!
//! Square formulations with a constant leading matrix and unknowns of index
//! at most 2: `rcd1`, `rcd0`, `ggl1` of the pendulum, those of index 2
//! (`rcd1`, `ggl1`) with a constant step only (above); `ori2` (index 3),
//! `psi1`/`psi0` (`E(y)`) and the overdetermined ones are refused, typed.
//! A model with a constant mass matrix is taken in rcd0 too, whose
//! acceleration rows keep `G(q)·v'`: [`Solver::solve`] makes those rows
//! algebraic first, which leaves `E` constant (the [`Idec::levels`] of the
//! seed's scheme refuses it).
//!
//! # Example
//!
//! ```no_run
//! use dae_core::system::DaeSystem;
//! use dae_solvers::idec::Idec;
//! use dae_solvers::{Options, Problem, SolveError, Solver};
//!
//! fn run(sys: &dyn DaeSystem, y0: &[f64]) -> Result<(), SolveError> {
//!     let idec = Idec { j: 3, m: 4 };
//!     let problem = Problem { system: sys, t0: 0.0, y0, t_end: 0.4 };
//!     // The seed's scheme with h = 0.025: LIE, 1.DC, 2.DC, 3.DC at t_end.
//!     let levels = idec.levels(&problem, 0.025)?;
//!     assert_eq!(levels.len(), 4);
//!     // Error-controlled.
//!     let solution = idec.solve(&problem, &Options::with_tol(1e-8))?;
//!     println!("{:?} after {} steps", solution.last(), solution.stats.steps);
//!     Ok(())
//! }
//! ```

mod run;
mod sweep;

pub use crate::core::lagrange::MAX_DEGREE;

use crate::core::eliminate::Formulation;
use crate::core::{driver, policy};
use crate::{NotApplicable, Options, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;
use run::Integrator;

/// Where the constant-step scheme ([`Idec::levels_with`]) evaluates the
/// Jacobian `J` of its matrix `E − hJ`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Jacobian {
    /// Once, at `(t₀, y₀)`, for the whole integration: the seed's scheme
    /// (2.2), one factorisation.
    Frozen,
    /// At the start of every Euler step, at that step's own point: the
    /// basic solution at `η^[0]_k`, each neighbouring problem at its own
    /// `π^[j]_k` (`m (J + 1)` Jacobians and factorisations per interval).
    /// Each level's matrix is then a smooth function of its own solution,
    /// so its error expansion stays smooth across intervals; a Jacobian per
    /// interval (evaluated at the best value) does not have that property
    /// and costs the corrections their order on the pendulum (module
    /// documentation, "Constant steps on the pendulum").
    EveryStep,
}

/// Most corrections [`Idec::j`] may ask for.
pub const MAX_CORRECTIONS: usize = 12;

/// Safety factor of the step-size controller.
const FAC: f64 = 0.9;
/// Bounds of the step-size ratio `h_new / h`.
const RATIO_MIN: f64 = 0.2;
const RATIO_MAX: f64 = 5.0;

/// The linearly implicit Euler method with `j` defect corrections on
/// intervals of `m` steps (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Idec {
    /// Number of corrections `J` (`0 ≤ J ≤ MAX_CORRECTIONS`; at least 1
    /// with error control, which compares the last two). Default 3.
    pub j: usize,
    /// Interpolation degree `m`, also the steps per interval
    /// (`1 ≤ m ≤ MAX_DEGREE`). The order is `min(J + 1, m)`. Default 4.
    pub m: usize,
}

impl Default for Idec {
    /// `m = 4`, `J = 3`: order 4, the seed's setting.
    fn default() -> Self {
        Idec { j: 3, m: 4 }
    }
}

impl Idec {
    /// The parameters in range for `options` ([`SolveError::InvalidInput`]
    /// otherwise).
    fn check(&self, options: &Options) -> Result<(), SolveError> {
        if !(1..=MAX_DEGREE).contains(&self.m) {
            return Err(SolveError::invalid(format!(
                "idec: interpolation degree m = {} must be in 1..={MAX_DEGREE}",
                self.m
            )));
        }
        if self.j > MAX_CORRECTIONS {
            return Err(SolveError::invalid(format!(
                "idec: j = {} corrections, at most {MAX_CORRECTIONS}",
                self.j
            )));
        }
        if self.j == 0 && options.fixed_step.is_none() {
            return Err(SolveError::invalid(
                "idec: error control compares the last two corrections and needs j ≥ 1 \
                 (j = 0 only with a fixed step)",
            ));
        }
        Ok(())
    }

    /// Validate and build the integrator of `problem` on its formulation
    /// `sys` (the problem's, or its constant-`E` presentation) at `t₀`.
    fn start<'a>(
        &self,
        problem: &Problem<'_>,
        sys: Formulation<'a>,
        options: &Options,
    ) -> Result<Integrator<'a>, SolveError> {
        self.accepts(sys.info())?;
        // The scheme itself needs `E` constant: `solve` presents a constant
        // mass matrix's rcd0 so (`eliminate::constant_leading`); `levels`
        // does not.
        policy::constant_leading(sys.info())?;
        problem.check(sys.info().unknowns(), options)?;
        self.check(options)?;
        // Error control restarts every interval: outside the theory on
        // index-2 unknowns ("Known limitation" above).
        if options.fixed_step.is_none() && sys.info().max_index() >= 2 {
            return Err(NotApplicable::RestartedIndexTwo.into());
        }
        Integrator::new(self, sys, problem, options)
    }

    /// The seed's scheme with the constant Euler step `h` (Jacobian frozen
    /// at `t₀`): every level `η^[0]` (LIE), `η^[1]` (1.DC), …, `η^[J]` at
    /// `t_end`.
    pub fn levels(&self, problem: &Problem<'_>, h: f64) -> Result<Vec<Vec<f64>>, SolveError> {
        self.levels_with(problem, h, Jacobian::Frozen)
    }

    /// The constant-step scheme with the global connection and the
    /// Jacobian as `jacobian` says: every level at `t_end`, as
    /// [`Idec::levels`]. The attempt budget is at least the number of
    /// intervals the step needs (S01 at h = 2e-7: 2.6·10⁷ intervals, more
    /// than the default [`Options::max_steps`]).
    pub fn levels_with(
        &self,
        problem: &Problem<'_>,
        h: f64,
        jacobian: Jacobian,
    ) -> Result<Vec<Vec<f64>>, SolveError> {
        let defaults = Options::default();
        let intervals = ((problem.t_end - problem.t0) / (self.m as f64 * h)).abs();
        let options = Options {
            fixed_step: Some(h),
            max_steps: if intervals.is_finite() {
                defaults.max_steps.max(intervals.ceil() as usize + 2)
            } else {
                defaults.max_steps
            },
            ..defaults
        };
        let mut integrator = self.start(problem, Formulation::Given(problem.system), &options)?;
        integrator.sweep.every_step = jacobian == Jacobian::EveryStep;
        driver::drive(&mut integrator, |_| {})?;
        Ok(integrator.levels())
    }
}

impl Solver for Idec {
    fn name(&self) -> &'static str {
        "idec"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::square(info)?;
        policy::constant_leading_once_eliminated(info)?;
        policy::max_index(info, 2)
    }

    fn integrator<'a>(
        &self,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<crate::Integrator<'a>, SolveError> {
        self.accepts(problem.system.info())?;
        let sys = crate::core::eliminate::constant_leading(problem)?;
        let integrator = self.start(problem, sys, options)?;
        Ok(crate::Integrator::new(
            Box::new(integrator),
            problem,
            options,
        ))
    }
}

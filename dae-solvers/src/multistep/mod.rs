//! The multistep engine shared by `bdf`, `odbdf` and `mebdf`: what a
//! multistep family does alike, written once; the family keeps its
//! formulas (predictor, corrector or stages, error estimate, order and
//! step proposal, dense output).
//!
//! - [`Common`]: the state every multistep step carries — settings,
//!   error weights, the step point and the step of the next attempt, the
//!   work counters, the attempt loop's budgets ([`Steps`]), the error-test
//!   failures of the step, the iteration matrix's state and the Newton
//!   rate carried from step to step; DASSL's initial step
//!   ([`Common::initial_step`]), the time a step reaches
//!   ([`Common::t_next`]) and DASSL's fall-back to order one after the
//!   third error-test failure on a step ([`Common::fall_back`]).
//! - [`Family`]: what a family implements — one attempt, its start from
//!   `y₀, y'₀` or from equally spaced values, its solution and dense
//!   output; the engine makes every family a [`Method`] for the driver and
//!   an [`Attempts`] for the attempt loop of `core::attempt` (retries,
//!   budgets, the smallest step, the end of the horizon).
//! - [`corrector`]: the modified Newton iteration of a corrector (the
//!   iteration loop, DASSL's iteration counts, the reuse of an iteration
//!   matrix from an earlier step and the one retry with a fresh matrix,
//!   as values of a [`corrector::Reuse`]).
//! - [`run`]: a run from the problem — the initial derivative and the
//!   consistency check, the error-controlled run with DASSL's initial step,
//!   or the constant-step run with its start-up (`core::startup`).
//! - [`backward`]: backward differences on an equally spaced grid — the
//!   history of MEBDF, and the start of a constant-step BDF run from
//!   equally spaced values.
//! - [`stale`]: an error estimate that stops falling with the step, and
//!   its cures (the fall-back to order one, a restart from the attempt's
//!   value).
//! - [`propagate`]: the error estimate carried through the iteration
//!   matrix onto the algebraic components, and the check that switches a
//!   run to it ([`crate::options::Estimate`]).
//! - [`newton_norm`]: the Newton norm of a corrector whose error test
//!   leaves index-2 unknowns out (DASPK), with the round-off floor of the
//!   index-scaled norm.
//!
//! Where the families differ the engine takes values: the attempt loop's
//! [`Policy`] (`DASSL`, `MEBDF`), the matrix reuse ([`corrector::Reuse`]),
//! the order counts of a run ([`run::Orders`]). BDF's history (modified
//! divided differences with a fixed leading coefficient, DASSL) and MEBDF's
//! three stages are the families' own.
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
//! With [`crate::Options::fixed_step`] the grid is `t₀ + jh` with
//! `h = (t_end − t₀)/⌈(t_end − t₀)/fixed_step⌉`, the order that of
//! [`crate::Options::fixed_order`] (else [`crate::Options::max_order`]) and
//! there is no error test. A `k`-step formula needs `k` starting values:
//! `y(t₀ + jh)`, `j = 1 … k−1`, are computed by the same method in adaptive
//! mode with the caller's tolerances (choose them well below the
//! discretisation error to observe the order) and interpolated onto the
//! grid; from then on every step is the constant-step formula. Starting
//! with lower orders at the given step would cap the observed order at two.
//! The work counters include the start-up run; [`crate::Options::record_steps`]
//! lists the grid points. A corrector may take up to 20 Newton iterations
//! (no smaller step can rescue it) and a failure is final.
//!
//! # Resources
//!
//! All buffers — history, iteration matrix and its factorisation, output
//! rows — are allocated before the step loop; the loop itself does not
//! allocate, except to record every step when
//! [`crate::Options::record_steps`] asks for it and to keep the dense output
//! when [`crate::Options::dense_output`] does.

pub(crate) mod backward;
pub(crate) mod corrector;
pub(crate) mod divided;
pub(crate) mod newton_norm;
pub(crate) mod propagate;
pub(crate) mod run;
pub(crate) mod stale;

use crate::core::attempt::{self, Attempts, Outcome, Policy, Steps};
use crate::core::control::Failure;
use crate::core::driver::Method;
use crate::core::matrix::JacState;
use crate::core::weights::Weights;
use crate::{SolveError, Stats};

/// Settings of one multistep integrator (the order in the family's count).
pub(crate) use crate::core::control::StepConfig as Config;

/// Error-test failures on one step from which on the retry falls back to
/// order one ([`Common::fall_back`]).
pub(crate) const FALL_BACK_AFTER: usize = 3;

/// `ρ/(1−ρ)` of a Newton iteration before a rate has been measured.
pub(crate) const UNKNOWN_RATE: f64 = 100.0;

/// The state every multistep step carries (see the
/// [module documentation](self)).
pub(crate) struct Common {
    /// Settings of this run.
    pub(crate) cfg: Config,
    /// Unknowns `N`.
    pub(crate) n: usize,
    /// Error weights.
    pub(crate) weights: Weights,
    /// Current time `t_n` (during an attempt, for BDF: `t_{n+1}`).
    pub(crate) t: f64,
    /// Step size of the next attempt.
    pub(crate) h: f64,
    /// The current attempt reaches `t_end`: its end is `t_end` itself.
    pub(crate) last: bool,
    /// The initial phase (no rejected step yet): the family may grow the
    /// step and the order faster.
    pub(crate) ramp: bool,
    /// Work counters (of this run, and of the work before it that it was
    /// started with).
    pub(crate) stats: Stats,
    /// The attempt loop's state: budgets, limits, the end rule.
    pub(crate) steps: Steps,
    /// Error-test failures on this step.
    pub(crate) error_failures: usize,
    /// Newton iterations of the last corrector solve.
    pub(crate) last_iterations: usize,
    /// Whether the iteration matrix (or its Jacobian) is current.
    pub(crate) jac: JacState,
    /// Newton rate factor `ρ/(1−ρ)` carried between iterations
    /// ([`UNKNOWN_RATE`] when unknown).
    pub(crate) rate: f64,
}

impl Common {
    /// The state of a run with settings `cfg` on `n` unknowns, weights
    /// `weights`, the attempt loop's factors `policy`.
    pub(crate) fn new(cfg: Config, n: usize, weights: Weights, policy: Policy) -> Self {
        Common {
            cfg,
            n,
            weights,
            t: 0.0,
            h: 0.0,
            last: false,
            ramp: true,
            stats: Stats::default(),
            steps: Steps::new(
                policy,
                cfg.max_steps,
                cfg.t_end,
                cfg.span,
                cfg.hmax,
                cfg.fixed_step,
            ),
            error_failures: 0,
            last_iterations: 0,
            jac: JacState::Needed,
            rate: UNKNOWN_RATE,
        }
    }

    /// DASSL's initial step: `0.001·(t_end − t₀)`, reduced so that
    /// `h ‖y'₀‖ ≤ 0.5` (weights of `y₀`, unscaled), and at most `h_max`.
    pub(crate) fn initial_step(&mut self, y0: &[f64], yp0: &[f64]) -> f64 {
        self.weights.update(y0);
        let mut h = 0.001 * self.cfg.span;
        let ypnorm = self.weights.norm(yp0);
        if ypnorm > 0.5 / h {
            h = 0.5 / ypnorm;
        }
        h.min(self.cfg.hmax)
    }

    /// Count a rejected error test on this step (the initial phase
    /// ends); how many there have been.
    pub(crate) fn error_test_failed(&mut self) -> usize {
        self.ramp = false;
        self.error_failures += 1;
        self.error_failures
    }

    /// The retry of a step whose error test keeps failing: order one
    /// (into `order`) and a quarter of the step — from the
    /// [`FALL_BACK_AFTER`]-th failure on one step, as DASSL, or when the
    /// family sees that the estimate does not measure the step. At higher
    /// orders an algebraic component left off its constraint by the Newton
    /// tolerance is an error estimate that does not shrink with `h`; with a
    /// fixed order the order is raised again after the step.
    pub(crate) fn fall_back(&self, order: &mut usize) -> f64 {
        *order = 1;
        0.25 * self.h
    }

    /// The outcome of an attempt that failed before its error test with
    /// `failure`: the initial phase ends, and the attempt loop retries with
    /// the step its policy gives.
    pub(crate) fn failed(&mut self, failure: Failure) -> Outcome {
        self.ramp = false;
        Outcome::failed(failure, self.last_iterations)
    }

    /// The time the current attempt reaches from `t`: `t + h`, or `t_end`
    /// itself for the last step.
    pub(crate) fn t_next(&self) -> f64 {
        if self.last {
            self.cfg.t_end
        } else {
            self.t + self.h
        }
    }
}

/// What a multistep family implements; the engine makes it a [`Method`]
/// and an [`Attempts`].
pub(crate) trait Family {
    /// The shared state.
    fn ms(&self) -> &Common;
    /// The shared state, to change.
    fn ms_mut(&mut self) -> &mut Common;
    /// The solution at the current step point.
    fn value(&self) -> &[f64];
    /// Dense output of the last accepted step at `tau`.
    fn dense_at(&self, tau: f64, out: &mut [f64]);
    /// Before the first attempt of a step (the error-test failures are
    /// already reset): the family's own per-step state.
    fn begin_step(&mut self);
    /// The step of the next attempt changed from `h_before` to `ms().h`.
    fn step_changed(&mut self, h_before: f64);
    /// One attempt from the current step point with the current step and
    /// order (see [`Attempts::attempt`]).
    fn attempt_once(&mut self) -> Result<Outcome, SolveError>;
    /// Start at `(t0, y0, y'0)` with step `h`: order one (adaptive), or
    /// the constant-step run's order from `y₀` and `y'₀` alone.
    fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64);
    /// Start a constant-step run of the run's order at `t` from the values
    /// at `t − (m−1)h, …, t` (oldest first).
    fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64);
}

impl<F: Family> Method for F {
    fn t(&self) -> f64 {
        self.ms().t
    }
    fn y(&self) -> &[f64] {
        self.value()
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        self.dense_at(tau, out)
    }
    fn dense_degree(&self) -> usize {
        // The polynomial of the last step's order through the last values.
        self.ms().cfg.max_order
    }
    fn finished(&self) -> bool {
        self.ms().t >= self.ms().cfg.t_end
    }
    fn step(&mut self) -> Result<(), SolveError> {
        self.ms_mut().error_failures = 0;
        self.begin_step();
        attempt::step(self)
    }
    fn stats(&self) -> Stats {
        self.ms().stats
    }
}

impl<F: Family> Attempts for F {
    fn steps(&mut self) -> &mut Steps {
        &mut self.ms_mut().steps
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.ms_mut().stats
    }
    fn point(&self) -> (f64, f64) {
        (self.ms().t, self.ms().h)
    }
    fn set_step(&mut self, h: f64, last: bool) {
        let ms = self.ms_mut();
        let h_before = ms.h;
        ms.h = h;
        ms.last = last;
        self.step_changed(h_before);
    }
    #[inline(always)]
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        self.attempt_once()
    }
}

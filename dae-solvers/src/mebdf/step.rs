//! The integrator: its state and workspace beyond the engine's
//! ([`Common`]), the engine's view of it ([`Family`]), and one attempt
//! with the order and step of its retry after a rejected error test.

use super::coeffs::{Coefficients, MAX_ORDER};
use crate::core::attempt::{Outcome, Policy, Retry};
use crate::core::control::Failure;
use crate::core::eliminate::Formulation;
use crate::core::matrix::JacState;
use crate::core::newton::FloorWalk;
use crate::core::shifted::Shifted;
use crate::core::weights::{self, Weights};
use crate::init::{initial_derivative_with, DerivativeRule};
use crate::multistep::backward::History;
use crate::multistep::{Common, Config, Family, FALL_BACK_AFTER};
use crate::options::Tolerances;
use crate::SolveError;

/// Columns of the difference table: `∇^0 … ∇^(MAX_ORDER+1)` (the order-raise
/// estimate at the highest order needs `∇^(MAX_ORDER+2) y_{n+1}`, one more
/// than stored at `t_n`).
const NB: usize = MAX_ORDER + 2;

/// An order-one attempt whose step is at most this fraction of the last
/// rejected order-one attempt's on the same step, ...
const STALLED_CUT: f64 = 0.3;
/// ... and whose error estimate is still above this fraction of that
/// attempt's, has an estimate that does not fall with the step (an
/// order-one estimate falls like `h²`, 11× for the cut above): see
/// [`Integrator::restart`].
const STALLED_FALL: f64 = 0.5;

/// Steps in a row whose second rejected attempt had an estimate that did
/// not fall with the step ([`STALLED_FALL`]) before the order falls to one
/// (see [`Integrator::attempt_step`]). One such step is no evidence: on the
/// pendulum at tol 1e-10 (rcd1, ggl1) falling at the first cost 45 % more
/// steps (824 → 1223, the solver harness).
const STALLED_STEPS: usize = 3;

/// Steps accepted the usual way before another [`Integrator::restart`]: a
/// stalled estimate that returns within them is not one stale value but
/// the method failing on the problem, and the step is rejected as before
/// (measured: mebdf on the cart pendulum's index-3 `ori2`, which fails at
/// every tolerance, restarted on every other step and crawled to the end
/// with 2.4 million steps and an energy drift of 6e-3 at tol 1e-7).
const RESTART_SPACING: usize = 20;

/// State and workspace of the MEBDF step (`N` unknowns).
pub(super) struct Integrator<'a> {
    /// The engine's state: settings, weights (index-scaled), step point
    /// and step, counters, budgets, whether `J` is current, the carried
    /// rate `θ/(1−θ)`.
    pub(super) ms: Common,
    /// The formulation.
    pub(super) sys: Formulation<'a>,
    /// The formulas.
    pub(super) coef: Coefficients,
    /// Unknowns in the error estimate: index at most two (the index-3
    /// multipliers are left out, see the module documentation).
    pub(super) estimated: Vec<bool>,
    /// `sqrt(N / N_estimated)`: turns the norm over all `N` unknowns of a
    /// difference with the left-out entries zeroed into the root mean
    /// square over the estimated ones.
    pub(super) estimate_scale: f64,
    /// Differences of the past values.
    pub(super) hist: History,

    /// Order of the next attempt.
    pub(super) p: usize,
    /// Order of the last accepted step (0 before the first).
    pub(super) p_old: usize,
    /// Accepted steps since the last change of step size or order.
    pub(super) same: usize,
    /// Steps accepted since the last [`Integrator::restart`].
    pub(super) since_restart: usize,

    /// `E` (constant), `J = ∂f/∂y` at the last evaluation and
    /// `E/(hβ) − J`, factored.
    pub(super) matrix: Shifted,

    /// The predictor `P(t_{n+1})` of degree `p`.
    pub(super) ypred: Vec<f64>,
    /// Stage 1: `ȳ_{n+1}` (BDF); the solution when `p = 1`.
    pub(super) y1: Vec<f64>,
    /// Stage 2: `ȳ_{n+2}` (BDF).
    pub(super) y2: Vec<f64>,
    /// Stage 3: `y_{n+1}` (the modified extended formula).
    pub(super) y3: Vec<f64>,
    /// The known part `c` of the stage being solved, `E (y + c) = hβ f`.
    pub(super) c: Vec<f64>,
    /// `ȳ_{n+1} + c_1`, `E d_1 = hβ f̄_{n+1}`.
    pub(super) d1: Vec<f64>,
    /// `ȳ_{n+2} + c_2`, `E d_2 = hβ f̄_{n+2}`.
    pub(super) d2: Vec<f64>,
    /// Back values `y_n, …, y_{n−k+1}`, one column each.
    pub(super) back: Vec<f64>,
    /// The stage's derivative `(y + c)/(hβ)`.
    pub(super) yp: Vec<f64>,
    /// Residual, then Newton update; scratch.
    pub(super) delta: Vec<f64>,

    /// Step and error of the last order-one attempt rejected by the error
    /// test on this step (see [`Integrator::restart`]).
    order_one: Option<(f64, f64)>,
    /// Step and error of the first attempt rejected by the error test on
    /// this step (see [`STALLED_FALL`] in [`Integrator::attempt_step`]).
    first_rejection: Option<(f64, f64)>,
    /// Consecutive steps with a stalled second rejection (see
    /// [`STALLED_STEPS`]), and whether this step had one.
    stalls: usize,
    stalled_this_step: bool,
    /// A walk of Newton failures down the round-off floor ([`FloorWalk`]).
    /// On Andrews' squeezer in `rcd0` at 1e-10 (EXTREMES.md §5, lit10) the
    /// stage increments stayed at 0.02–0.27 of the tolerance from
    /// h = 1.1e-10 down to 2.7e-17, where the run ended in `newton_failure`
    /// (the floor exit, [`super::stages`]' `ROUND_OFF_FLOOR`, was then 0.01).
    floor_walk: FloorWalk,
}

impl Family for Integrator<'_> {
    fn ms(&self) -> &Common {
        &self.ms
    }
    fn ms_mut(&mut self) -> &mut Common {
        &mut self.ms
    }
    fn value(&self) -> &[f64] {
        self.hist.y()
    }
    fn dense_at(&self, tau: f64, out: &mut [f64]) {
        self.hist
            .interpolate(self.ms.t, tau, self.p_old.max(1), out)
    }
    fn begin_step(&mut self) {
        self.order_one = None;
        self.first_rejection = None;
        if !self.stalled_this_step {
            self.stalls = 0;
        }
        self.stalled_this_step = false;
    }
    fn step_changed(&mut self, _h_before: f64) {
        self.fit_history();
    }
    fn attempt_once(&mut self) -> Result<Outcome, SolveError> {
        self.attempt_step()
    }
    fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        Integrator::start(self, t0, y0, yp0, h)
    }
    fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64) {
        self.start_from_values(t, values, h, self.ms.cfg.max_order)
    }
}

impl<'a> Integrator<'a> {
    /// Allocate every buffer of the step loop; index-`k` unknowns are
    /// weighted by `h^(k−1)`.
    pub(super) fn new(sys: Formulation<'a>, tol: &Tolerances, cfg: Config) -> Self {
        let info = sys.info();
        let n = info.unknowns();
        let estimated: Vec<bool> = info.variables.iter().map(|v| v.index <= 2).collect();
        let count = estimated.iter().filter(|&&b| b).count().max(1);
        let mut matrix = Shifted::new(n);
        // `E` is constant (in `t` and `y`: `eliminate::constant_leading`
        // made it so or refused), so any point serves.
        sys.leading(0.0, &vec![0.0; n], &mut matrix.lead);
        let weights = Weights::new(tol, |_| 1.0, vec![true; n], weights::index_powers(info));
        Integrator {
            ms: Common::new(cfg, n, weights, Policy::MEBDF),
            sys: sys.clone(),
            coef: Coefficients::new(),
            hist: History::new(n, NB),
            estimated,
            estimate_scale: (n.max(1) as f64 / count as f64).sqrt(),
            p: 1,
            p_old: 0,
            same: 0,
            since_restart: RESTART_SPACING,
            matrix,
            ypred: vec![0.0; n],
            y1: vec![0.0; n],
            y2: vec![0.0; n],
            y3: vec![0.0; n],
            c: vec![0.0; n],
            d1: vec![0.0; n],
            d2: vec![0.0; n],
            back: vec![0.0; n * MAX_ORDER],
            yp: vec![0.0; n],
            delta: vec![0.0; n],
            order_one: None,
            first_rejection: None,
            stalls: 0,
            stalled_this_step: false,
            floor_walk: FloorWalk::default(),
        }
    }

    /// Start at `(t0, y0, y'0)` with step `h`: order one, or with a
    /// constant step the run's order (the straight line through `y₀` with
    /// slope `y'₀` is its history).
    pub(super) fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        self.ms.t = t0;
        self.ms.h = h;
        self.p = if self.ms.cfg.fixed_step {
            self.ms.cfg.max_order
        } else {
            1
        };
        self.p_old = 0;
        self.hist.start(y0, yp0, h);
    }

    /// Start a constant-step run of order `p` at `t` from the values at
    /// `t − (m−1)h, …, t` (oldest first).
    pub(super) fn start_from_values(&mut self, t: f64, values: &[&[f64]], h: f64, p: usize) {
        self.ms.t = t;
        self.ms.h = h;
        self.p = p;
        self.p_old = values.len().saturating_sub(1);
        self.ms.ramp = false;
        self.hist.start_from_values(values, h);
    }

    /// One attempt from `t` with `h` and order `p`; after a rejected
    /// error test, the order and step of the retry.
    fn attempt_step(&mut self) -> Result<Outcome, SolveError> {
        self.floor_walk.attempt(self.ms.h);
        self.ms.weights.update_scaled(self.hist.y(), self.ms.h);
        let err = match self.attempt() {
            Ok(()) if self.ms.cfg.fixed_step => {
                self.accept(0.0);
                return Ok(Outcome::Accepted);
            }
            Ok(()) => self.error_estimate(),
            Err(failure) => {
                if failure == Failure::Newton {
                    let at = (self.ms.t, self.ms.h);
                    let (w, info) = (&self.ms.weights, self.sys.info());
                    self.floor_walk.failed(at, &self.delta, w, info)?;
                }
                self.ms.ramp = false;
                return Ok(Outcome::Failed {
                    failure,
                    retry: Retry::Policy,
                    iterations: self.ms.last_iterations,
                });
            }
        };
        if err <= 1.0 {
            self.accept(err);
            return Ok(Outcome::Accepted);
        }
        if self.p == 1 {
            if let Some((h_prev, err_prev)) = self.order_one {
                if self.ms.h <= STALLED_CUT * h_prev
                    && err > STALLED_FALL * err_prev
                    && self.since_restart >= RESTART_SPACING
                {
                    self.restart()?;
                    return Ok(Outcome::Accepted);
                }
            }
            self.order_one = Some((self.ms.h, err));
        }
        let failures = self.ms.error_test_failed();
        // A second rejection whose estimate fell by less than half on a
        // step at least 10 % shorter, at an order that predicts a fall by
        // `(h₂/h₁)^(p+1)`, on STALLED_STEPS steps in a row: the estimate
        // does not measure the step (the history's algebraic values are off
        // their equations). Order one then, DASSL's fall-back after the
        // third failure ([`Common::fall_back`]), where the stall is cured by
        // `restart`. Measured on the transistor amplifier
        // (`transamp`, tol 1e-5, EXTREMES.md §5 session 8): at order 6 the
        // estimate stayed at 1.0–1.8 from h = 1e-13 down to 1e-16, every
        // step accepted at the third attempt with a step 0.64 × the last, so
        // neither the third-failure fall-back nor the order selection
        // (after p + 1 steps of one size) came, and the run ended in
        // `newton_failure` at h = 6e-17.
        let stalled = self.p > 1
            && failures == 2
            && self
                .first_rejection
                .is_some_and(|(h1, e1)| self.ms.h <= 0.9 * h1 && err > STALLED_FALL * e1);
        if failures == 1 {
            self.first_rejection = Some((self.ms.h, err));
        }
        if stalled {
            // Once per step: the second rejection comes once.
            self.stalled_this_step = true;
            self.stalls += 1;
        }
        let h = if stalled && self.stalls >= STALLED_STEPS {
            self.stalls = 0;
            self.ms.fall_back(&mut self.p)
        } else if failures >= FALL_BACK_AFTER {
            self.ms.fall_back(&mut self.p)
        } else {
            self.reject(err)
        };
        Ok(Outcome::ErrorTest { h })
    }

    /// Accept the current order-one attempt although its error estimate
    /// exceeds one, and start afresh from it at order one: the estimate has
    /// stopped falling with the step (see [`STALLED_FALL`]), so it measures
    /// the last accepted value, not this step. That value is inconsistent:
    /// its algebraic unknowns miss their equations by more than the
    /// tolerance, and the limit of the order-one estimate as `h → 0` is that
    /// miss. This happens when an algebraic unknown's weight grows between
    /// steps, because Newton converged under the weights of the value before.
    /// The attempt, taken at a step that has shrunk by at least 4× three
    /// times on this step, has solved those equations again. Its `y'` is
    /// recomputed ([`initial_derivative_with`]) and the Jacobian renewed.
    ///
    /// Measured on Andrews' squeezer in `rcd0` at tol 1e-5: at t = 0.0211
    /// one acceleration (about 2 in size, between values of 10⁵) was 8e-4 off
    /// its equation. The order-one estimate stayed at 2.48 from h = 1e-6
    /// down to h = 3e-17, and the run stopped with `step_size_too_small`.
    fn restart(&mut self) -> Result<(), SolveError> {
        let t = self.ms.t_next();
        let y = self.y1.clone();
        let yp = initial_derivative_with(&*self.sys, t, &y, &DerivativeRule::SOLVER)?;
        self.ms.stats.residual_evals += 1;
        self.ms.stats.steps += 1;
        let h = self.ms.h;
        self.start(t, &y, &yp, h);
        self.since_restart = 0;
        self.same = 0;
        self.ms.ramp = true;
        self.ms.jac = JacState::Needed;
        Ok(())
    }

    /// Bring the history to the step size of the next attempt (the
    /// polynomial of the current order).
    fn fit_history(&mut self) {
        if self.ms.h != self.hist.h {
            self.hist.rescale(self.ms.h, self.p);
            self.same = 0;
        }
    }

    /// After an accepted step of error norm `err` (0 with a constant step):
    /// choose order and step of the next one, and advance the history.
    fn accept(&mut self, err: f64) {
        let (p_next, r) = if self.ms.cfg.fixed_step {
            (self.p, 1.0)
        } else {
            self.propose(err)
        };
        let y = if self.p == 1 { &self.y1 } else { &self.y3 };
        self.hist.advance(y);
        self.ms.t = self.ms.t_next();
        self.ms.stats.steps += 1;
        self.since_restart += 1;
        self.p_old = self.p;
        if p_next != self.p || r != 1.0 {
            self.same = 0;
        }
        self.p = p_next;
        self.ms.h *= r;
    }
}

//! The integrator: its state and workspace beyond the engine's
//! ([`Common`]), the engine's view of it ([`Family`]), and one attempt
//! with the order and step of its retry after a rejected error test.

use super::coeffs::{Coefficients, MAX_ORDER};
use crate::core::attempt::{Outcome, Policy};
use crate::core::control::Failure;
use crate::core::eliminate::Formulation;
use crate::core::newton::FloorWalk;
use crate::core::policy;
use crate::core::shifted::Shifted;
use crate::core::weights::{self, Weights};
use crate::multistep::backward::History;
use crate::multistep::corrector::{self, Reuse};
use crate::multistep::stale::{self, Stale};
use crate::multistep::{propagate::Propagation, Common, Config, Family, FALL_BACK_AFTER};
use crate::{Options, SolveError};

/// Columns of the difference table: `∇^0 … ∇^(MAX_ORDER+1)` (the order-raise
/// estimate at the highest order needs `∇^(MAX_ORDER+2) y_{n+1}`, one more
/// than stored at `t_n`).
const NB: usize = MAX_ORDER + 2;

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
    /// Unknowns in the error estimate: index at most one, and the
    /// differential ones of index two ([`policy::index_scaled_error_test`]).
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

    /// `E` (constant), `J = ∂f/∂y` at the last evaluation and
    /// `E/(hβ) − J`, factored.
    pub(super) matrix: Shifted,

    /// The predictor `P(t_{n+1})` of degree `p`.
    pub(super) ypred: Vec<f64>,
    /// The stages' iterates: `ȳ_{n+1}` (BDF; the solution when `p = 1`),
    /// `ȳ_{n+2}` (BDF), `y_{n+1}` (the modified extended formula).
    pub(super) stage: [Vec<f64>; 3],
    /// The known part `c` of the stage being solved, `E (y + c) = hβ f`.
    pub(super) c: Vec<f64>,
    /// `ȳ_{n+1} + c_1` and `ȳ_{n+2} + c_2`: `E d_i = hβ f̄_{n+i}`.
    pub(super) d: [Vec<f64>; 2],
    /// Back values `y_n, …, y_{n−k+1}`, one column each.
    pub(super) back: Vec<f64>,
    /// The stage being solved: its index in `stage`, its `t` and `1/(hβ)`.
    pub(super) solving: (usize, f64, f64),
    /// The stage's derivative `(y + c)/(hβ)`.
    pub(super) yp: Vec<f64>,
    /// Residual, then Newton update; scratch.
    pub(super) delta: Vec<f64>,

    /// The family's estimate or the propagated one ([`Propagation`]).
    pub(super) estimate: Propagation,
    /// An error estimate that stops falling with the step ([`Stale`]).
    stale: Stale,
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
        self.stale.begin_step();
    }
    /// Bring the history to the step size of the next attempt (the
    /// polynomial of the current order).
    fn step_changed(&mut self, _h_before: f64) {
        if self.ms.h != self.hist.h {
            self.hist.rescale(self.ms.h, self.p);
            self.same = 0;
        }
    }
    /// One attempt from `t` with `h` and order `p`; after a rejected
    /// error test, the order and step of the retry.
    fn attempt_once(&mut self) -> Result<Outcome, SolveError> {
        self.floor_walk.attempt(self.ms.h);
        self.ms.weights.update_scaled(self.hist.y(), self.ms.h);
        let err = match corrector::solve_reusing(self, Reuse::MEBDF, Self::stages) {
            // A constant step has no error test.
            Ok(()) if self.ms.cfg.fixed_step => 0.0,
            Ok(()) => self.estimate_at(self.p),
            Err(failure) => {
                if failure == Failure::Newton {
                    let at = (self.ms.t, self.ms.h);
                    let (w, info) = (&self.ms.weights, self.sys.info());
                    self.floor_walk.failed(at, &self.delta, w, info)?;
                }
                return Ok(self.ms.failed(failure));
            }
        };
        if err <= 1.0 {
            self.accept(err);
            return Ok(Outcome::Accepted);
        }
        if self.stale.restart_due(self.ms.h, err, self.p) {
            let (sys, y) = (self.sys.clone(), self.stage[0].clone());
            stale::restart(self, &*sys, self.ms.t_next(), &y)?;
            return Ok(Outcome::Accepted);
        }
        let failures = self.ms.error_test_failed();
        // DASSL's fall-back after the third failure ([`Common::fall_back`]),
        // or when the estimate does not measure the step.
        let h = if self.stale.fall_back_due(self.ms.h, err, self.p, failures)
            || failures >= FALL_BACK_AFTER
        {
            self.ms.fall_back(&mut self.p)
        } else {
            self.reject(err)
        };
        Ok(Outcome::ErrorTest { h })
    }
    /// Start at `(t0, y0, y'0)` with step `h`: order one, or with a
    /// constant step the run's order (the straight line through `y₀` with
    /// slope `y'₀` is its history).
    fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        self.ms.t = t0;
        self.ms.h = h;
        self.p = if self.ms.cfg.fixed_step {
            self.ms.cfg.max_order
        } else {
            1
        };
        self.p_old = 0;
        self.same = 0;
        self.hist.start(y0, yp0, h);
    }
    /// Start a constant-step run of the run's order at `t` from the values
    /// at `t − (m−1)h, …, t` (oldest first).
    fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64) {
        self.ms.t = t;
        self.ms.h = h;
        self.p = self.ms.cfg.max_order;
        self.p_old = values.len().saturating_sub(1);
        self.ms.ramp = false;
        self.hist.start_from_values(values, h);
    }
}

impl<'a> Integrator<'a> {
    /// Allocate every buffer of the step loop; index-`k` unknowns are
    /// weighted by `h^(k−1)`.
    pub(super) fn new(sys: Formulation<'a>, options: &Options, cfg: Config) -> Self {
        let (info, Options { tol, estimate, .. }) = (sys.info(), options);
        let n = info.unknowns();
        let estimated = policy::index_scaled_error_test(info);
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
            matrix,
            ypred: vec![0.0; n],
            stage: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            c: vec![0.0; n],
            d: [vec![0.0; n], vec![0.0; n]],
            back: vec![0.0; n * MAX_ORDER],
            solving: (0, 0.0, 0.0),
            yp: vec![0.0; n],
            delta: vec![0.0; n],
            estimate: Propagation::new(*estimate, info, n),
            stale: Stale::default(),
            floor_walk: FloorWalk::default(),
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
        self.hist.advance(&self.stage[self.solution()]);
        self.ms.t = self.ms.t_next();
        self.ms.stats.steps += 1;
        self.stale.accepted();
        self.p_old = self.p;
        if p_next != self.p || r != 1.0 {
            self.same = 0;
        }
        self.p = p_next;
        self.ms.h *= r;
    }
}

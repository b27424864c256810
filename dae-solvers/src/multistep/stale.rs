//! An error estimate that does not measure the step: the rejections of a
//! step whose estimate stops falling as the step is cut, and the two cures —
//! the fall-back to order one ([`Common::fall_back`]) when it happens at a
//! higher order on several steps in a row, and a restart at order one from
//! the attempt's value ([`restart`]) when it happens at order one.
//!
//! An estimate of order `p` falls like `h^(p+1)` with the step. When it
//! stays put while the step shrinks, it measures the last accepted value,
//! not the step: an algebraic unknown of that value misses its equation by
//! more than the tolerance (the Newton iteration converged under the
//! weights of the value before, and its weight has grown since). No step is
//! then short enough, and the run ends in `step_size_too_small` or
//! `newton_failure`.
//!
//! Written for `mebdf` (Cash's code has neither cure; the measurements are
//! below) and used by `bdf`/`odbdf` too (DASSL has neither either): it sees
//! only the step, the estimate and the order of each rejected attempt and
//! the error-test failures the engine counts ([`Common::error_test_failed`]),
//! and [`restart`] starts a family through [`Family::start`]. In bdf it
//! fires on none of the runs whose step counts are pinned to DASSL's (S02,
//! the solver harness, `examples/bdf_s02`, the literature map's bdf and
//! odbdf cells are unchanged to the step); it is there for the runs where
//! DASSL's rules end in a step size too small.

use super::{Common, Family};
use crate::core::matrix::JacState;
use crate::init::{initial_derivative_with, DerivativeRule};
use crate::SolveError;
use dae_core::system::DaeSystem;

/// An order-one attempt whose step is at most this fraction of the last
/// rejected order-one attempt's on the same step, ...
const STALLED_CUT: f64 = 0.3;
/// ... and whose error estimate is still above this fraction of that
/// attempt's, has an estimate that does not fall with the step (an
/// order-one estimate falls like `h²`, 11× for the cut above): see
/// [`Stale::restart_due`].
const STALLED_FALL: f64 = 0.5;

/// Steps in a row whose second rejected attempt had an estimate that did
/// not fall with the step ([`STALLED_FALL`]) before the order falls to one
/// (see [`Stale::fall_back_due`]). One such step is no evidence: on the
/// pendulum at tol 1e-10 (rcd1, ggl1) mebdf falling at the first cost 45 %
/// more steps (824 → 1223, the solver harness).
const STALLED_STEPS: usize = 3;

/// Steps accepted the usual way before another [`restart`]: a stalled
/// estimate that returns within them is not one stale value but the
/// method failing on the problem, and the step is rejected as before
/// (measured: mebdf on the cart pendulum's index-3 `ori2`, which fails at
/// every tolerance, restarted on every other step and crawled to the end
/// with 2.4 million steps and an energy drift of 6e-3 at tol 1e-7).
const RESTART_SPACING: usize = 20;

/// The rejections of the current step, as far as a stale estimate needs
/// them (see the [module documentation](self)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stale {
    /// Step and error of the last order-one attempt rejected by the error
    /// test on this step (see [`Stale::restart_due`]).
    order_one: Option<(f64, f64)>,
    /// Step and error of the first attempt rejected by the error test on
    /// this step (see [`Stale::fall_back_due`]).
    first_rejection: Option<(f64, f64)>,
    /// Consecutive steps with a stalled second rejection (see
    /// [`STALLED_STEPS`]), and whether this step had one.
    stalls: usize,
    stalled_this_step: bool,
    /// Steps accepted since the last [`restart`].
    since_restart: usize,
}

impl Default for Stale {
    fn default() -> Self {
        Stale {
            order_one: None,
            first_rejection: None,
            stalls: 0,
            stalled_this_step: false,
            since_restart: RESTART_SPACING,
        }
    }
}

impl Stale {
    /// Before the first attempt of a step.
    pub(crate) fn begin_step(&mut self) {
        self.order_one = None;
        self.first_rejection = None;
        if !self.stalled_this_step {
            self.stalls = 0;
        }
        self.stalled_this_step = false;
    }

    /// A step accepted the usual way.
    pub(crate) fn accepted(&mut self) {
        self.since_restart += 1;
    }

    /// An attempt of step `h` and order `order` rejected with estimate
    /// `err`, before the failure is counted: whether to accept it and
    /// [`restart`] from it — an order-one attempt at most [`STALLED_CUT`]
    /// of the last rejected one on this step whose estimate is above
    /// [`STALLED_FALL`] of that one's, and no restart within the last
    /// [`RESTART_SPACING`] steps.
    ///
    /// Measured on Andrews' squeezer in `rcd0` at tol 1e-5 (mebdf): at
    /// t = 0.0211 one acceleration (about 2 in size, between values of 10⁵)
    /// was 8e-4 off its equation. The order-one estimate stayed at 2.48 from
    /// h = 1e-6 down to h = 3e-17, and the run stopped with
    /// `step_size_too_small`; restarted, it runs to the end.
    pub(crate) fn restart_due(&mut self, h: f64, err: f64, order: usize) -> bool {
        if order == 1 {
            if let Some((h_prev, err_prev)) = self.order_one {
                if h <= STALLED_CUT * h_prev
                    && err > STALLED_FALL * err_prev
                    && self.since_restart >= RESTART_SPACING
                {
                    self.since_restart = 0;
                    return true;
                }
            }
            self.order_one = Some((h, err));
        }
        false
    }

    /// The same attempt rejected, `failures` the error-test failures of
    /// this step with it ([`Common::error_test_failed`]): whether to fall
    /// back to order one.
    ///
    /// A second rejection whose estimate fell by less than half on a step
    /// at least 10 % shorter, at an order that predicts a fall by
    /// `(h₂/h₁)^(p+1)`, on [`STALLED_STEPS`] steps in a row: the estimate
    /// does not measure the step. Order one then, where the stall is cured
    /// by [`restart`]. Measured on the transistor amplifier (`transamp`,
    /// mebdf at tol 1e-5, EXTREMES.md §5 session 8): at order 6 the
    /// estimate stayed at 1.0–1.8 from h = 1e-13 down to 1e-16, every step
    /// accepted at the third attempt with a step 0.64 × the last, so
    /// neither the third-failure fall-back nor the order selection (after
    /// p + 1 steps of one size) came, and the run ended in `newton_failure`
    /// at h = 6e-17.
    pub(crate) fn fall_back_due(
        &mut self,
        h: f64,
        err: f64,
        order: usize,
        failures: usize,
    ) -> bool {
        let stalled = order > 1
            && failures == 2
            && self
                .first_rejection
                .is_some_and(|(h1, e1)| h <= 0.9 * h1 && err > STALLED_FALL * e1);
        if failures == 1 {
            self.first_rejection = Some((h, err));
        }
        if !stalled {
            return false;
        }
        // Once per step: the second rejection comes once.
        self.stalled_this_step = true;
        self.stalls += 1;
        if self.stalls < STALLED_STEPS {
            return false;
        }
        self.stalls = 0;
        true
    }
}

/// Accept the current attempt of `family` (on `sys`) at its value `y` at
/// `t` although its error estimate exceeds one, and start afresh from it at
/// order one with the same step ([`Family::start`]): the estimate has
/// stopped falling with the step ([`Stale::restart_due`]), so it measures
/// the last accepted value, not this step. That value is inconsistent: its
/// algebraic unknowns miss their equations by more than the tolerance, and
/// the limit of the order-one estimate as `h → 0` is that miss. This
/// happens when an algebraic unknown's weight grows between steps, because
/// Newton converged under the weights of the value before. The attempt,
/// taken at a step that has shrunk by at least 4× three times on this step,
/// has solved those equations again. Its `y'` is recomputed
/// ([`initial_derivative_with`]) and the Jacobian renewed; the step counts
/// as taken.
pub(crate) fn restart<F: Family + ?Sized>(
    family: &mut F,
    sys: &dyn DaeSystem,
    t: f64,
    y: &[f64],
) -> Result<(), SolveError> {
    let yp = initial_derivative_with(sys, t, y, &DerivativeRule::SOLVER)?;
    let ms: &mut Common = family.ms_mut();
    ms.stats.residual_evals += 1;
    ms.stats.steps += 1;
    let h = ms.h;
    family.start(t, y, &yp, h);
    let ms = family.ms_mut();
    ms.ramp = true;
    ms.jac = JacState::Needed;
    Ok(())
}

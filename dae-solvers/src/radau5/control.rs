//! RADAU5's step-size control: the controller state between and within
//! steps, what the step loop does next, the size of the next step after an
//! accepted one, and the classical and predictive step-size quotients.

use super::step::Integrator;
use super::tableau::Collocation;
use super::{FACL, FACR, QUOT1, QUOT2, SAFE, UROUND};
use crate::core::control::Budget;
use crate::core::matrix::StageSystems;

/// What the step loop does next (RADAU5's labels 10, 20, 30).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Next {
    /// Evaluate the Jacobian, factorise, step.
    Jacobian,
    /// Factorise with the current `h`, step.
    Factor,
    /// Step with the current factorisation.
    Step,
}

/// RADAU5's controller state (its `FIRST`, `REJECT`, `CALJAC`, `HOLD`,
/// `HACC`, `ERRACC`, `LAST`) between and within steps.
pub(super) struct Control {
    /// Time of the last accepted step (`t₀` at first).
    pub(super) t: f64,
    /// Rounding error of `t` (compensated summation of the steps).
    pub(super) t_lo: f64,
    /// Step size of the next attempt.
    pub(super) h: f64,
    /// Largest step.
    pub(super) h_max: f64,
    /// Constant step size (no error control), if any.
    pub(super) fixed: Option<f64>,
    /// The next attempt reaches `t_end`.
    pub(super) last: bool,
    /// `t_end` reached.
    pub(super) done: bool,
    /// No step accepted yet (`FIRST`).
    pub(super) first: bool,
    /// The last attempt was rejected (`REJECT`).
    pub(super) reject: bool,
    /// The Jacobian was evaluated for the current step (`CALJAC`).
    pub(super) caljac: bool,
    /// Size of the last accepted step.
    pub(super) h_old: f64,
    /// Size of the previous accepted step, for the predictive controller
    /// (`HACC`).
    pub(super) h_acc: f64,
    /// Its error norm, at least `10⁻²` (`ERRACC`).
    pub(super) err_acc: f64,
    /// Attempted steps and the failure budgets.
    pub(super) budget: Budget,
    /// What the step loop does next.
    pub(super) next: Next,
    /// The quasi-constant step rule of a symmetric method.
    pub(super) hold: Hold,
}

impl Control {
    /// After a failed attempt: factorise again with the Jacobian of this
    /// step, or evaluate a new one if it is old.
    pub(super) fn after_failure(&self) -> Next {
        if self.caljac {
            Next::Factor
        } else {
            Next::Jacobian
        }
    }

    /// A step ending within this of `t_end` is stretched to it: round-off
    /// for adaptive steps, a relative 1e-8 for fixed ones.
    pub(super) fn end_slack(&self, t: f64, h: f64, t_end: f64) -> f64 {
        match self.fixed {
            Some(_) => 1e-8 * h,
            None => 100.0 * UROUND * t.abs().max(t_end.abs()),
        }
    }
}

/// The step-size rule of a symmetric method ([`Collocation::QUASI_CONSTANT`]):
/// the step is held constant and changed only when it must be.
///
/// A symmetric method on a reversible problem keeps the error of periodic
/// motion growing linearly in time — but only at constant step size; a step
/// that follows the error estimate through every swing of a pendulum makes
/// the method non-symmetric, and the phase error grows quadratically again
/// (Hairer, Lubich & Wanner, *Geometric Numerical Integration*, VIII.1).
/// So, after a start-up in which RADAU5's controller sets the scale (until
/// its first proposal to shorten the step):
///
/// - a step is shortened at once when the error test rejects it or its
///   proposal is shorter than the current step (an estimate above
///   `≈ 0.66`), to the proposal;
/// - a step is lengthened only when the proposals of `window` accepted
///   steps in a row have all been at least twice the current step, to the
///   smallest of them;
/// - a shortening that follows a lengthening doubles `window` (from 16):
///   on periodic motion the window soon spans a whole period, and the step
///   settles at what the hardest part of the orbit needs.
#[derive(Clone, Debug)]
pub(super) struct Hold {
    /// The start-up is over.
    settled: bool,
    /// Accepted steps whose proposals must all allow a doubling.
    window: usize,
    /// Accepted steps in a row whose proposal was at least twice the step.
    calm: usize,
    /// The smallest of their proposals.
    calm_min: f64,
    /// The step was lengthened and has not been shortened since.
    raised: bool,
}

impl Default for Hold {
    fn default() -> Self {
        Hold {
            settled: false,
            window: Hold::FIRST_WINDOW,
            calm: 0,
            calm_min: f64::INFINITY,
            raised: false,
        }
    }
}

impl Hold {
    /// The first window.
    const FIRST_WINDOW: usize = 16;
    /// Proposals must allow at least this ratio for a lengthening.
    const RAISE: f64 = 2.0;
    /// A shortened step is this fraction of the proposal: room for the
    /// estimate to grow `(1/0.75)⁴ ≈ 3` times before the next shortening.
    const SHORTEN: f64 = 0.75;

    /// The next step after one of size `h` accepted with `proposal`.
    pub(super) fn accepted(&mut self, h: f64, proposal: f64) -> f64 {
        if !self.settled {
            if proposal >= h {
                return proposal;
            }
            self.settled = true;
        }
        if proposal < h {
            self.shortened();
            return Self::SHORTEN * proposal;
        }
        if proposal >= Self::RAISE * h {
            self.calm += 1;
            self.calm_min = self.calm_min.min(proposal);
            if self.calm >= self.window {
                let longer = self.calm_min;
                self.calm = 0;
                self.calm_min = f64::INFINITY;
                self.raised = true;
                return longer;
            }
        } else {
            self.calm = 0;
            self.calm_min = f64::INFINITY;
        }
        h
    }

    /// A step was rejected (it is retried shorter).
    pub(super) fn rejected(&mut self) {
        self.settled = true;
        self.shortened();
    }

    fn shortened(&mut self) {
        if self.raised {
            self.window *= 2;
            self.raised = false;
        }
        self.calm = 0;
        self.calm_min = f64::INFINITY;
    }
}

impl<S: StageSystems, K: Collocation> Integrator<'_, S, K> {
    /// Size of the next step after one accepted with proposal `h_new`, and
    /// whether the factorisation (or the Jacobian) can be kept.
    pub(super) fn next_step(&mut self, mut h_new: f64) {
        let t_end = self.t_end;
        let theta = if K::SLOW_EXIT {
            self.newton.theta
        } else {
            // Iterated towards round-off: the last ratios are noise.
            self.newton.theta_first
        };
        let small_theta = theta <= K::THET;
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
}

/// The classical step-size quotient `q = h/h_new` (HW IV.8 (8.21)):
/// `clamp(‖err‖^(1/4) / fac, 1/8, 5)` with the safety factor
/// `fac = min(0.9, 0.9 (2 nit + 1) / (newt + 2 nit))` (`nit` = RADAU5's
/// `NIT`) lowered when Newton
/// needed many iterations.
pub(super) fn classical_quotient(err: f64, newt: usize, nit: usize) -> f64 {
    let fac = SAFE.min(SAFE * (2 * nit + 1) as f64 / (newt + 2 * nit) as f64);
    FACR.max(FACL.min(err.sqrt().sqrt() / fac))
}

/// Gustafsson's predictive quotient (HW IV.8 (8.25)):
/// `clamp((h_acc/h) (‖err‖² / ‖err_acc‖)^(1/4) / 0.9, 1/8, 5)`, with
/// `h_acc`, `err_acc` of the previous accepted step.
pub(super) fn predictive_quotient(err: f64, err_acc: f64, h: f64, h_acc: f64) -> f64 {
    ((h_acc / h) * (err * err / err_acc).sqrt().sqrt() / SAFE).clamp(FACR, FACL)
}

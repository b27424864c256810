//! RADAU5's step-size control: the controller state between and within
//! steps, what the step loop does next, the size of the next step after an
//! accepted one, and the classical and predictive step-size quotients.

use super::step::Integrator;
use super::{FACL, FACR, NIT, QUOT1, QUOT2, SAFE, THET, UROUND};
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

impl<S: StageSystems> Integrator<'_, S> {
    /// Size of the next step after one accepted with proposal `h_new`, and
    /// whether the factorisation (or the Jacobian) can be kept.
    pub(super) fn next_step(&mut self, mut h_new: f64) {
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
}

/// The classical step-size quotient `q = h/h_new` (HW IV.8 (8.21)):
/// `clamp(‖err‖^(1/4) / fac, 1/8, 5)` with the safety factor
/// `fac = min(0.9, 0.9 (2 NIT + 1) / (newt + 2 NIT))` lowered when Newton
/// needed many iterations.
pub(super) fn classical_quotient(err: f64, newt: usize) -> f64 {
    let fac = SAFE.min(SAFE * (2 * NIT + 1) as f64 / (newt + 2 * NIT) as f64);
    FACR.max(FACL.min(err.sqrt().sqrt() / fac))
}

/// Gustafsson's predictive quotient (HW IV.8 (8.25)):
/// `clamp((h_acc/h) (‖err‖² / ‖err_acc‖)^(1/4) / 0.9, 1/8, 5)`, with
/// `h_acc`, `err_acc` of the previous accepted step.
pub(super) fn predictive_quotient(err: f64, err_acc: f64, h: f64, h_acc: f64) -> f64 {
    ((h_acc / h) * (err * err / err_acc).sqrt().sqrt() / SAFE).clamp(FACR, FACL)
}

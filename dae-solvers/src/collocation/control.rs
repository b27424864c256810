//! RADAU5's step-size control: the controller state between and within
//! steps, what the step loop does next, the size of the next step after an
//! accepted one, and the classical and predictive step-size quotients.

use super::step::Integrator;
use super::tableau::Collocation;
use super::{FACL, FACR, QUOT1, QUOT2, SAFE};
use crate::core::newton::Stall;
use crate::core::onestep::OneStep;

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
/// `HACC`, `ERRACC`, `LAST`) between and within steps: the core's
/// one-step state ([`OneStep`]: `t`, `h`, `FIRST`, `REJECT`, `LAST`, the
/// attempt loop's state) and RADAU5's own.
pub(super) struct Control {
    /// The step point, the steps, the first, last and rejected flags, the
    /// attempt loop's state.
    pub(super) one: OneStep,
    /// The Jacobian was evaluated for the current step (`CALJAC`).
    pub(super) caljac: bool,
    /// Size of the previous accepted step, for the predictive controller
    /// (`HACC`).
    pub(super) h_acc: f64,
    /// Its error norm, at least `10⁻²` (`ERRACC`).
    pub(super) err_acc: f64,
    /// What the step loop does next.
    pub(super) next: Next,
    /// The quasi-constant step rule of a symmetric method.
    pub(super) hold: Hold,
    /// Newton failures of this step whose increments do not shrink with it.
    pub(super) stall: Stall,
}

impl Control {
    /// When the iteration matrix must change (a failed attempt, or a slow
    /// contraction on an accepted step): factorise again with the Jacobian
    /// of this step if it is fresh, else evaluate a new one.
    pub(super) fn renewed(&self) -> Next {
        if self.caljac {
            Next::Factor
        } else {
            Next::Jacobian
        }
    }
}

/// The step-size rule of a symmetric method ([`super::tableau::StepRule::Held`]):
/// the step is held constant and changed only when it must be.
///
/// A symmetric method on a reversible problem keeps the error of periodic
/// motion growing linearly in time — but only at constant step size; a step
/// that follows the error estimate through every swing of a pendulum makes
/// the method non-symmetric, and the phase error grows quadratically again
/// (Hairer, Lubich & Wanner, *Geometric Numerical Integration*, VIII.1).
/// So, after a start-up in which RADAU5's controller sets the scale (until
/// its first proposal to shorten the step), the step is set from the
/// largest error estimate `e_max` seen at the current step size, aiming at
/// `AIM` (`‖err‖ ∝ h⁴`):
///
/// - at once, to `h (AIM/‖err‖)^(1/4)`, when an accepted step's estimate
///   exceeds `SHORTEN_AT` (a rejected step is retried with RADAU5's
///   proposal);
/// - after `window` accepted steps, to `h (AIM/e_max)^(1/4)` if that
///   differs from `h` by more than `CHANGE`;
/// - a shortening that follows a lengthening doubles `window` (from 16):
///   on periodic motion the window soon spans a whole period, and the step
///   settles where the hardest part of the orbit has the estimate `AIM`,
///   whatever the point of the orbit the start-up ended at.
#[derive(Clone, Debug)]
pub(super) struct Hold {
    /// The start-up is over.
    settled: bool,
    /// Accepted steps between reviews of the step size.
    window: usize,
    /// Accepted steps at the current step size since the last review.
    count: usize,
    /// The largest estimate among them.
    err_max: f64,
    /// The step was lengthened and has not been shortened since.
    raised: bool,
}

impl Default for Hold {
    fn default() -> Self {
        Hold {
            settled: false,
            window: Hold::FIRST_WINDOW,
            count: 0,
            err_max: 0.0,
            raised: false,
        }
    }
}

impl Hold {
    /// The first window.
    const FIRST_WINDOW: usize = 16;
    /// The estimate the step size aims at, at its largest over a window.
    const AIM: f64 = 0.3;
    /// An accepted estimate above this shortens the step at once.
    const SHORTEN_AT: f64 = 0.8;
    /// A review changes the step only by more than this ratio.
    const CHANGE: f64 = 1.1;
    /// Largest lengthening of one review.
    const MAX_RAISE: f64 = 4.0;

    /// The next step after one of size `h` accepted with the estimate
    /// `err` and RADAU5's `proposal`.
    pub(super) fn accepted(&mut self, h: f64, err: f64, proposal: f64) -> f64 {
        if !self.settled {
            if proposal >= h {
                return proposal;
            }
            self.settled = true;
        }
        if err > Self::SHORTEN_AT {
            self.shortened();
            return h * (Self::AIM / err).sqrt().sqrt();
        }
        self.count += 1;
        self.err_max = self.err_max.max(err);
        if self.count < self.window {
            return h;
        }
        let ideal = h * (Self::AIM / self.err_max).sqrt().sqrt();
        self.count = 0;
        self.err_max = 0.0;
        if ideal > Self::CHANGE * h {
            self.raised = true;
            ideal.min(Self::MAX_RAISE * h)
        } else if ideal * Self::CHANGE < h {
            self.shortened();
            ideal
        } else {
            h
        }
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
        self.count = 0;
        self.err_max = 0.0;
    }
}

impl<K: Collocation> Integrator<'_, K> {
    /// The last Newton iteration contracted fast enough for its Jacobian
    /// to be kept (`θ ≤ THET`).
    pub(super) fn small_theta(&self) -> bool {
        let theta = if K::POLICY.newton.slow_exit() {
            self.newton.theta
        } else {
            // Iterated towards round-off: the last ratios are noise.
            self.newton.theta_first
        };
        theta <= K::POLICY.thet
    }

    /// Size of the next step after one accepted with proposal `h_new`, and
    /// whether the factorisation (or the Jacobian) can be kept.
    pub(super) fn next_step(&mut self, h_new: f64) {
        let small_theta = self.small_theta();
        let c = &mut self.c;
        let one = &mut c.one;
        let (t, h) = (one.t, one.h);
        if let Some(hf) = one.fixed {
            let (h_next, last) = one.steps.toward_end(t, hf);
            one.last = last;
            let new_h = h_next != h;
            one.h = h_next;
            c.next = match (small_theta, new_h) {
                (true, false) => Next::Step,
                (true, true) => Next::Factor,
                (false, _) => c.renewed(),
            };
            return;
        }
        let h_new = one.after_accept(h, h_new);
        let (h_end, last) = one.steps.toward_end(t, h_new);
        one.last = last;
        if !last {
            let qt = h_end / h;
            if small_theta && (QUOT1..=QUOT2).contains(&qt) {
                c.next = Next::Step;
                return;
            }
        }
        one.h = h_end;
        c.next = if small_theta {
            Next::Factor
        } else {
            c.renewed()
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

//! The state a one-step method carries from one accepted step to the next,
//! as the attempt loop ([`super::attempt`]) sees it: the step point `t`
//! (summed with compensation when asked), the step of the next attempt,
//! the last accepted step, a constant step if any, whether the next
//! attempt is the last, whether the run is done, whether a step has been
//! accepted yet, whether the last attempt was rejected, and the loop's own
//! state ([`Steps`]: budgets, limits, the end rule) with RADAU5's policy.
//!
//! Shared by the collocation engine (radau5, gauss, odradau: its
//! controller keeps beside it only what is RADAU5's — the Jacobian and
//! factorisation flags, the predictive controller's memory, the held step
//! of a symmetric method) and by idec, whose loop step is an interval of
//! `m` Euler steps ([`OneStep::new`]'s `unit`). As `multistep::Common` is
//! for the multistep families.

use super::attempt::{Policy, Steps};
use super::control;
use crate::linalg::two_sum;
use crate::{Options, Problem};

/// A one-step method's state between its attempts (see the
/// [module documentation](self)).
#[derive(Clone, Debug)]
pub(crate) struct OneStep {
    /// End of the last accepted step (`t₀` at first).
    pub(crate) t: f64,
    /// Rounding error of `t` when the steps are summed with compensation
    /// ([`OneStep::compensated`]), else zero.
    pub(crate) t_lo: f64,
    /// Sum the steps into `t` with compensation (a rounding of `ulp(t)`
    /// per step is not small against the error after 10⁵–10⁷ steps); the
    /// collocation engine sums its stage updates into `y` the same way
    /// when this is set (tight tolerances, `collocation::TIGHT_TOL`).
    pub(crate) compensated: bool,
    /// Step of the next attempt, in the loop's unit.
    pub(crate) h: f64,
    /// Size of the last accepted step (the first step before one is).
    pub(crate) h_old: f64,
    /// Constant step (no error control), in the method's unit, if any.
    pub(crate) fixed: Option<f64>,
    /// The next attempt reaches `t_end`.
    pub(crate) last: bool,
    /// `t_end` reached.
    pub(crate) done: bool,
    /// No step accepted yet (RADAU5's `FIRST`).
    pub(crate) first: bool,
    /// The last attempt was rejected (RADAU5's `REJECT`).
    pub(crate) reject: bool,
    /// The attempt loop's state: budgets, limits, the end rule.
    pub(crate) steps: Steps,
}

impl OneStep {
    /// At `t₀` of `problem`, for a method whose loop step is `unit` of its
    /// own steps (`1`; idec: the `m` Euler steps of an interval), which
    /// [`Options::h0`], [`Options::h_max`] and [`Options::fixed_step`]
    /// count: the largest step `h_max` (at most the horizon), the first
    /// step (the constant one, or [`control::first_step`]), both in the
    /// loop's unit; RADAU5's policy ([`Policy::HALVE`]).
    pub(crate) fn new(problem: &Problem<'_>, options: &Options, unit: f64) -> Self {
        let (t0, span) = (problem.t0, problem.t_end - problem.t0);
        let h_max = options.h_max.unwrap_or(span).min(span / unit);
        let h = match options.fixed_step {
            Some(h) => h,
            None => control::first_step(options.h0, h_max, t0, span),
        };
        OneStep {
            t: t0,
            t_lo: 0.0,
            compensated: false,
            h: unit * h,
            h_old: unit * h,
            fixed: options.fixed_step,
            last: false,
            done: false,
            first: true,
            reject: false,
            steps: Steps::new(
                Policy::HALVE,
                options.max_steps,
                problem.t_end,
                span,
                unit * h_max,
                options.fixed_step.is_some(),
            ),
        }
    }

    /// The attempt of step `h` from `t` is accepted: `t` moves to its end
    /// (`t_end` itself for the last), `h` is the last accepted step, the
    /// run is done after the last.
    pub(crate) fn accept(&mut self, h: f64) {
        if self.last {
            (self.t, self.t_lo) = (self.steps.t_end, 0.0);
        } else if self.compensated {
            (self.t, self.t_lo) = two_sum(self.t, h + self.t_lo);
        } else {
            self.t += h;
        }
        self.first = false;
        self.h_old = h;
        self.done = self.last;
    }

    /// The proposal `h_new` for the step after one of size `h` just
    /// accepted: no longer than `h` right after a rejection (HW IV.8,
    /// RADAU5); the rejection is then over.
    pub(crate) fn after_accept(&mut self, h: f64, h_new: f64) -> f64 {
        let h_new = if self.reject { h_new.min(h) } else { h_new };
        self.reject = false;
        h_new
    }
}

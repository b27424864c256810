//! The step-attempt loop every method family runs (as ARKODE's shared
//! step loop): a family implements *one attempt* from its current step
//! point with the proposed step (form or reuse its iteration matrix, solve,
//! estimate the error, propose the next step and order) and says how it
//! ended ([`Outcome`]); this module owns what happens around it, once for
//! every family:
//!
//! - the end of the horizon ([`EndRule`]): before every attempt, the step
//!   is bounded by `h_max` and brought to reach `t_end` without a tiny last
//!   step;
//! - the smallest step ([`control::h_min`]) before the first attempt of a
//!   step and after every shrink: below it, [`SolveError::StepSizeTooSmall`]
//!   — or, when a failure before the error test shrank the step, that
//!   failure's own error, which names the cause (as DASSL's `IDID`);
//! - the budgets ([`Budget`]): the attempts of the whole run and the
//!   failures of each kind on one step;
//! - the retries: after the error test the family's proposal, after a
//!   failure before it the family's own factor (a Newton iteration that
//!   says how much shorter the step must be) or its policy's factor for
//!   that kind of failure ([`Policy`]), or — once, with a constant step —
//!   the same step with a fresh matrix ([`Retry::Refresh`]);
//! - the classification of a failure into its typed [`SolveError`]
//!   ([`Budget::error`]).
//!
//! The factors are data of each family's [`Policy`], not code: RADAU5
//! halves the step after a failed Newton iteration, DASSL quarters it.

use super::control::{self, Budget, Failure};
use crate::{SolveError, Stats};

/// How one step attempt ended.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Outcome {
    /// The step passed its error test (or needs none: a constant step)
    /// and the family has advanced to its end.
    Accepted,
    /// Rejected by the error test; the family's proposal for the retry
    /// (its order, if it has one, is already set).
    ErrorTest {
        /// The step to retry with.
        h: f64,
    },
    /// Failed before the error test: the Newton iteration, the iteration
    /// matrix or a non-finite value.
    Failed {
        /// What failed.
        failure: Failure,
        /// How to retry.
        retry: Retry,
        /// Newton iterations of the attempt (for the typed error).
        iterations: usize,
    },
}

impl Outcome {
    /// Failed before the error test with `failure` after `iterations`
    /// Newton iterations, retried with the step shortened by the policy's
    /// factor for it ([`Retry::Policy`]).
    pub(crate) fn failed(failure: Failure, iterations: usize) -> Self {
        Outcome::Failed {
            failure,
            retry: Retry::Policy,
            iterations,
        }
    }
}

/// How to retry after a failure before the error test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Retry {
    /// With the step shortened by the policy's factor for the failure.
    Policy,
    /// With the step shortened by this factor (a Newton iteration that
    /// estimated how much shorter the step must be).
    Shrink(f64),
    /// With the same step and a fresh iteration matrix (also with a
    /// constant step, where nothing can be shortened).
    Refresh,
}

/// How a family reaches `t_end`: the one rule, with the family's factors.
///
/// Before every attempt, from `t` with the proposed step `h` (bounded by
/// `h_max` unless the step is constant): the attempt is the last when it
/// reaches `t_end` up to a slack (round-off, `100 ε max(|t|, |t_end|)`; a
/// constant step also `10⁻⁸ h`: a constant step summed over 10⁵ steps
/// drifts by more than round-off, and the last step must not be taken for
/// a short one), or when stretching it by up to `stretch` (a constant
/// step: `fixed_stretch`) reaches `t_end`; it then ends at `t_end` — with
/// `h` itself when that lands on `t_end` up to the slack (a constant step
/// keeps its factorisation). Otherwise, an adaptive step that leaves less
/// than another step splits what remains into two equal steps (after a
/// large step-size ratio the index-2 and index-3 components lose accuracy,
/// HW VII.4, and the last step is where they are reported).
#[derive(Clone, Copy, Debug)]
pub(crate) struct EndRule {
    /// An adaptive step is stretched by up to this factor to reach
    /// `t_end` (within `h_max`).
    pub(crate) stretch: f64,
    /// A constant step is stretched by up to this factor.
    pub(crate) fixed_stretch: f64,
    /// The rule also shapes the retry after a rejected attempt; else the
    /// retry is never the last (DASSL: the retry's step is the failed
    /// step shrunk, and the steps after it reach `t_end`).
    pub(crate) on_retry: bool,
}

impl EndRule {
    /// The step toward `t_end` from `t` for the proposal `h`, and whether
    /// it is the last.
    pub(crate) fn apply(&self, t: f64, h: f64, t_end: f64, h_max: f64, fixed: bool) -> (f64, bool) {
        let remaining = t_end - t;
        let h = if fixed { h } else { h.min(h_max) };
        let round_off = 100.0 * f64::EPSILON * t.abs().max(t_end.abs());
        let slack = if fixed {
            (1e-8 * h).max(round_off)
        } else {
            round_off
        };
        let stretched = if fixed {
            remaining <= self.fixed_stretch * h
        } else {
            remaining <= self.stretch * h && remaining <= h_max
        };
        if remaining - h <= slack || stretched {
            (remaining, true)
        } else if !fixed && remaining < 2.0 * h {
            (0.5 * remaining, false)
        } else {
            (h, false)
        }
    }
}

/// A family's factors: how much a failure before the error test shortens
/// the step, and how it reaches `t_end`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Policy {
    /// After a Newton failure (divergence, too slow convergence).
    pub(crate) newton: f64,
    /// After a singular iteration matrix.
    pub(crate) singular: f64,
    /// After a non-finite residual or value.
    pub(crate) non_finite: f64,
    /// The end of the horizon.
    pub(crate) end: EndRule,
}

impl Policy {
    /// RADAU5's (and IDeC's): half the step after every failure; no
    /// stretch of the last step.
    pub(crate) const HALVE: Policy = Policy {
        newton: 0.5,
        singular: 0.5,
        non_finite: 0.5,
        end: EndRule {
            stretch: 1.0,
            fixed_stretch: 1.0,
            on_retry: true,
        },
    };
    /// DASSL's (BDF): a quarter of the step after every failure; the
    /// last adaptive step stretched by up to 10 %, a constant one by up to
    /// 50 % (its grid divides the horizon: the stretch absorbs the drift
    /// of the summed steps); a retry is never the last. (Shaping the retry
    /// too moves the last steps of 12 bdf records of the harness and the
    /// start-up values of the constant-step order test, whose observed
    /// order 3 then reads 3.45 at the finest step.)
    pub(crate) const DASSL: Policy = Policy {
        newton: 0.25,
        singular: 0.25,
        non_finite: 0.25,
        end: EndRule {
            stretch: 1.1,
            fixed_stretch: 1.5,
            on_retry: false,
        },
    };
    /// MEBDF's: DASSL's, the retry shaped by the end rule too.
    pub(crate) const MEBDF: Policy = Policy {
        end: EndRule {
            on_retry: true,
            ..Policy::DASSL.end
        },
        ..Policy::DASSL
    };

    /// The factor after `failure`.
    fn shrink(&self, failure: Failure) -> f64 {
        match failure {
            Failure::Newton => self.newton,
            Failure::Singular => self.singular,
            Failure::NonFinite(_) => self.non_finite,
        }
    }
}

/// The loop's own state in a family: the budgets, the family's policy and
/// the limits of the run.
#[derive(Clone, Debug)]
pub(crate) struct Steps {
    /// Attempts of the run and failures on this step.
    pub(crate) budget: Budget,
    /// The family's factors.
    pub(crate) policy: Policy,
    /// Where to stop (never stepped over).
    pub(crate) t_end: f64,
    /// Length of the whole horizon (scale of the smallest step).
    pub(crate) span: f64,
    /// Largest step.
    pub(crate) h_max: f64,
    /// Constant step: no error test, no shrinking.
    pub(crate) fixed: bool,
}

impl Steps {
    /// The loop of a run of at most `max_steps` attempts toward `t_end` on
    /// a horizon of length `span`.
    pub(crate) fn new(
        policy: Policy,
        max_steps: usize,
        t_end: f64,
        span: f64,
        h_max: f64,
        fixed: bool,
    ) -> Self {
        Steps {
            budget: Budget::new(max_steps),
            policy,
            t_end,
            span,
            h_max,
            fixed,
        }
    }

    /// The step toward `t_end` from `t` for the proposal `h`, and whether
    /// it is the last ([`EndRule`]).
    pub(crate) fn toward_end(&self, t: f64, h: f64) -> (f64, bool) {
        self.policy
            .end
            .apply(t, h, self.t_end, self.h_max, self.fixed)
    }

    /// [`SolveError::StepSizeTooSmall`] when the adaptive step `h` from `t`
    /// is below the smallest step.
    fn check(&self, t: f64, h: f64) -> Result<(), SolveError> {
        if !self.fixed && h < control::h_min(t, self.span) {
            return Err(SolveError::StepSizeTooSmall { t, h });
        }
        Ok(())
    }
}

/// One method family's attempts, as the loop sees them.
pub(crate) trait Attempts {
    /// The loop's state.
    fn steps(&mut self) -> &mut Steps;
    /// Work counters (the loop counts rejected attempts).
    fn stats_mut(&mut self) -> &mut Stats;
    /// The current step point and the step of the next attempt.
    fn point(&self) -> (f64, f64);
    /// The next attempt takes step `h`, the last one when `last`.
    fn set_step(&mut self, h: f64, last: bool);
    /// One attempt from the current step point with the current step; a
    /// typed error stops the run (a non-finite Jacobian, a failed
    /// re-start).
    fn attempt(&mut self) -> Result<Outcome, SolveError>;
    /// The typed error for a failure that ends the step (its budget is
    /// spent or the retry would be below the smallest step): the failure's
    /// own ([`Budget::error`]) unless the family knows more about it (a
    /// Newton iteration stalled at round-off, radau5's
    /// [`SolveError::RoundOffFloor`]).
    fn failure_error(&self, failure: Failure, t: f64, h: f64, iterations: usize) -> SolveError {
        Budget::error(failure, t, h, iterations)
    }
}

/// One accepted step of `family`: attempts, retried within the budgets.
pub(crate) fn step<A: Attempts + ?Sized>(family: &mut A) -> Result<(), SolveError> {
    let (t, h) = family.point();
    let (h, last) = family.steps().toward_end(t, h);
    family.set_step(h, last);
    if !last {
        family.steps().check(t, h)?;
    }
    loop {
        let (t, h) = family.point();
        family.steps().budget.attempt(t)?;
        let outcome = family.attempt()?;
        let h_next = match outcome {
            Outcome::Accepted => {
                family.steps().budget.accepted();
                return Ok(());
            }
            Outcome::ErrorTest { h } => {
                family.stats_mut().rejected += 1;
                h
            }
            Outcome::Failed {
                failure,
                retry,
                iterations,
            } => {
                family.stats_mut().rejected += 1;
                let steps = family.steps();
                let exhausted = steps.budget.failed(failure);
                let h_next = match retry {
                    Retry::Policy => h * steps.policy.shrink(failure),
                    Retry::Shrink(factor) => h * factor,
                    Retry::Refresh => h,
                };
                // A retry below the smallest step is the failure's own
                // error too: it names the cause (DASSL's IDID = -7, -8).
                if exhausted
                    || (steps.fixed && retry != Retry::Refresh)
                    || steps.check(t, h_next).is_err()
                {
                    return Err(family.failure_error(failure, t, h, iterations));
                }
                h_next
            }
        };
        let steps = family.steps();
        steps.check(t, h_next)?;
        let (h, last) = if steps.policy.end.on_retry {
            steps.toward_end(t, h_next)
        } else {
            (h_next, false)
        };
        family.set_step(h, last);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn end_rule_stretches_splits_and_keeps_a_step_that_lands() {
        let rule = Policy::DASSL.end;
        // 5 % short of t_end: stretched to it.
        assert_eq!(rule.apply(0.0, 0.95, 1.0, 10.0, false), (1.0, true));
        // Less than two steps left: two equal steps.
        assert_eq!(rule.apply(0.0, 0.7, 1.0, 10.0, false), (0.5, false));
        // Bounded by h_max first.
        assert_eq!(rule.apply(0.0, 0.7, 1.0, 0.2, false), (0.2, false));
        let halve = Policy::HALVE.end;
        assert_eq!(halve.apply(0.0, 0.95, 1.0, 10.0, false), (0.5, false));
        // Within the slack of a constant step: the last, made to reach
        // t_end.
        let h = 0.1;
        let t = 0.9 + 1e-10;
        let (h_last, last) = halve.apply(t, h, 1.0, 10.0, true);
        assert!(last && h_last < h);
        // One that does not reach it is cut to what remains.
        assert!((halve.apply(0.95, h, 1.0, 10.0, true).0 - 0.05).abs() < 1e-15);
    }
}

//! Step-size limits and failure budgets shared by every method.
//!
//! - The smallest step: `h_min(t) = 4 ε max(|t|, ε (t_end − t₀))` (DASSL's
//!   rule: a step shorter than a few units in the last place of `t` no
//!   longer advances the solution). A step below it is
//!   [`SolveError::StepSizeTooSmall`].
//! - Failures on one step, counted until a step is accepted: ten Newton
//!   failures (divergence or too slow convergence), five singular
//!   iteration matrices, ten non-finite residuals; one more is the typed
//!   error of that kind.
//! - [`crate::Options::max_steps`] step attempts (accepted and rejected) in
//!   all: [`SolveError::StepLimit`].

use crate::SolveError;

/// Smallest step allowed at `t` on a horizon of length `span`.
pub(crate) fn h_min(t: f64, span: f64) -> f64 {
    4.0 * f64::EPSILON * t.abs().max(f64::EPSILON * span)
}

/// First step of a one-step method when [`crate::Options::h0`] is not
/// given (RADAU5's default).
pub(crate) const H0_DEFAULT: f64 = 1e-6;

/// The first step of a one-step method (the collocation engine, idec's
/// Euler step): the caller's `h0` or [`H0_DEFAULT`], at most `h_max`, and a
/// tiny one raised to well above the smallest step at `t0`.
pub(crate) fn first_step(h0: Option<f64>, h_max: f64, t0: f64, span: f64) -> f64 {
    h0.unwrap_or(H0_DEFAULT)
        .min(h_max)
        .max(100.0 * h_min(t0, span))
}

/// An error norm as an error test takes it: a NaN (a NaN in the solution
/// or in its estimate) rejects the attempt as an infinite norm does, since
/// every comparison with a NaN is false. bdf's and mebdf's error tests.
pub(crate) fn error_norm(err: f64) -> f64 {
    if err.is_nan() {
        f64::INFINITY
    } else {
        err
    }
}

/// Newton failures tolerated on one step.
pub(crate) const MAX_NEWTON_FAILURES: usize = 10;
/// Singular iteration matrices tolerated on one step.
pub(crate) const MAX_SINGULAR: usize = 5;
/// Non-finite residuals tolerated on one step.
pub(crate) const MAX_NON_FINITE: usize = 10;

/// Why a step attempt failed before its error test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Failure {
    /// The Newton iteration diverged or converged too slowly.
    Newton,
    /// The iteration matrix is singular.
    Singular,
    /// A residual (or the named quantity) was not finite.
    NonFinite(&'static str),
}

/// Failure counters of the current step and the attempt budget.
#[derive(Clone, Debug)]
pub(crate) struct Budget {
    max_attempts: usize,
    attempts: usize,
    newton: usize,
    singular: usize,
    non_finite: usize,
}

impl Budget {
    /// A budget of `max_attempts` step attempts.
    pub(crate) fn new(max_attempts: usize) -> Self {
        Budget {
            max_attempts,
            attempts: 0,
            newton: 0,
            singular: 0,
            non_finite: 0,
        }
    }

    /// Count a step attempt at `t`; [`SolveError::StepLimit`] when none is
    /// left.
    pub(crate) fn attempt(&mut self, t: f64) -> Result<(), SolveError> {
        if self.attempts >= self.max_attempts {
            return Err(SolveError::StepLimit {
                t,
                max_steps: self.max_attempts,
            });
        }
        self.attempts += 1;
        Ok(())
    }

    /// A step was accepted: the failure counters start again.
    pub(crate) fn accepted(&mut self) {
        self.newton = 0;
        self.singular = 0;
        self.non_finite = 0;
    }

    /// Count a failure; `true` when it exhausts its budget.
    pub(crate) fn failed(&mut self, failure: Failure) -> bool {
        let (count, limit) = match failure {
            Failure::Newton => (&mut self.newton, MAX_NEWTON_FAILURES),
            Failure::Singular => (&mut self.singular, MAX_SINGULAR),
            Failure::NonFinite(_) => (&mut self.non_finite, MAX_NON_FINITE),
        };
        *count += 1;
        *count >= limit
    }

    /// The typed error for `failure` at `t` with step `h` after
    /// `iterations` Newton iterations.
    pub(crate) fn error(failure: Failure, t: f64, h: f64, iterations: usize) -> SolveError {
        match failure {
            Failure::Newton => SolveError::NewtonFailure { t, h, iterations },
            Failure::Singular => SolveError::SingularMatrix { t, h },
            Failure::NonFinite(what) => SolveError::NonFinite { t, what },
        }
    }
}

/// The constant step for a request `h_request` on a horizon of length
/// `span`: `span/⌈span/h_request⌉` (a ratio within `10⁻⁹` of an integer
/// counts as that integer), with the number of steps;
/// [`SolveError::StepLimit`] at `t0` when that exceeds `max_steps`.
pub(crate) fn constant_grid(
    span: f64,
    h_request: f64,
    max_steps: usize,
    t0: f64,
) -> Result<(usize, f64), SolveError> {
    let ratio = span / h_request;
    if !ratio.is_finite() || ratio > max_steps as f64 {
        return Err(SolveError::StepLimit { t: t0, max_steps });
    }
    let nsteps = if (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) {
        ratio.round()
    } else {
        ratio.ceil()
    }
    .max(1.0) as usize;
    Ok((nsteps, span / nsteps as f64))
}

/// Settings of a multistep integrator's step loop (BDF, MEBDF): the order
/// range, fixed order or step, and the limits of the driver.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StepConfig {
    /// Largest order (in the method's own count).
    pub(crate) max_order: usize,
    /// Never lower the order by order selection; raise it to `max_order`
    /// as soon as possible.
    pub(crate) fixed_order: bool,
    /// Constant step, no error test.
    pub(crate) fixed_step: bool,
    /// Largest step.
    pub(crate) hmax: f64,
    /// Step attempts allowed (accepted + rejected).
    pub(crate) max_steps: usize,
    /// Where to stop (never stepped over).
    pub(crate) t_end: f64,
    /// Length of the whole horizon (scale of the smallest step).
    pub(crate) span: f64,
}

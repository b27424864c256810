//! The corrector's modified Newton iteration, once for every multistep
//! family: the iteration loop around a family's solve-and-update
//! ([`iterate`]), the iterations it may take ([`max_iterations`]), and the
//! reuse of an iteration matrix from an earlier step with one retry with a
//! fresh matrix when the old one fails ([`solve_reusing`], its rule a
//! [`Reuse`] value).

use super::{Common, Family};
use crate::core::control::Failure;
use crate::core::matrix::JacState;
use crate::core::newton::{Contraction, Verdict};

/// Newton iterations of a constant-step run, where a failure cannot be
/// cured by a smaller step: the modified Newton iteration converges only
/// linearly, and convergence studies ask for tight tolerances.
const MAX_ITERATIONS_FIXED_STEP: usize = 20;

/// The Newton iterations a corrector solve may take: `adaptive` (DASSL's
/// `MAXIT` is 4), or [`MAX_ITERATIONS_FIXED_STEP`] with a constant step.
pub(crate) fn max_iterations(ms: &Common, adaptive: usize) -> usize {
    if ms.cfg.fixed_step {
        MAX_ITERATIONS_FIXED_STEP
    } else {
        adaptive
    }
}

/// How a family keeps an iteration matrix over steps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reuse {
    /// A non-finite residual at an iterate with a matrix from an earlier
    /// step is retried with a fresh matrix too (DASSL), not only a Newton
    /// failure.
    pub(crate) retry_non_finite: bool,
    /// A matrix formed in a failed attempt is kept for the retry as one
    /// from an earlier step (DASSL: a shorter retry changes `c_J` enough to
    /// form a new one anyway); else it is formed afresh (MEBDF).
    pub(crate) keep_after_failure: bool,
}

impl Reuse {
    /// DASSL's.
    pub(crate) const DASSL: Reuse = Reuse {
        retry_non_finite: true,
        keep_after_failure: true,
    };
    /// MEBDF's.
    pub(crate) const MEBDF: Reuse = Reuse {
        retry_non_finite: false,
        keep_after_failure: false,
    };
}

/// Solve the corrector with `solve` (which forms the matrix when
/// [`Common::jac`] is [`JacState::Needed`], marking it
/// [`JacState::Fresh`]); a failure with a matrix from an earlier step is
/// retried once with a fresh one. After success the matrix is one from an
/// earlier step for the next attempt.
#[inline(always)]
pub(crate) fn solve_reusing<F: Family + ?Sized>(
    family: &mut F,
    reuse: Reuse,
    mut solve: impl FnMut(&mut F) -> Result<(), Failure>,
) -> Result<(), Failure> {
    loop {
        let stale = family.ms().jac == JacState::Stale;
        let result = solve(family);
        let jac = &mut family.ms_mut().jac;
        match result {
            Ok(()) => {
                *jac = JacState::Stale;
                return Ok(());
            }
            Err(Failure::Newton) if stale => *jac = JacState::Needed,
            Err(Failure::NonFinite(_)) if stale && reuse.retry_non_finite => {
                *jac = JacState::Needed
            }
            Err(fail) => {
                *jac = match (fail, *jac) {
                    (Failure::Singular, _) => JacState::Needed,
                    (_, JacState::Fresh) if reuse.keep_after_failure => JacState::Stale,
                    (_, state) if reuse.keep_after_failure => state,
                    _ => JacState::Needed,
                };
                return Err(fail);
            }
        }
    }
}

/// One corrector's modified Newton iteration, as [`iterate`] sees it.
pub(crate) trait Iteration {
    /// The shared state (the counters and the carried rate).
    fn ms(&mut self) -> &mut Common;
    /// Solve for the update from the residual (in place), apply it to the
    /// iterate and return the update's weighted norm.
    fn update(&mut self) -> f64;
    /// The residual at the iterate; `false` when it is not finite.
    fn residual(&mut self) -> bool;
}

/// The modified Newton iteration from a residual already evaluated,
/// judged by `monitor` with DASSL's round-off bound `tiny` (`100 ε ‖y⁽⁰⁾‖`):
/// the rate it measures is carried in [`Common::rate`]; a non-finite
/// residual at an iterate (not at the predictor) is divergence.
#[inline(always)]
pub(crate) fn iterate<I: Iteration + ?Sized>(
    it: &mut I,
    mut monitor: Contraction,
    tiny: f64,
) -> Result<(), Failure> {
    loop {
        let norm = it.update();
        let ms = it.ms();
        ms.stats.newton_iterations += 1;
        ms.last_iterations += 1;
        // An overflowing update is a diverging iteration, not a fault of
        // the problem: the step is retried smaller.
        let verdict = monitor.observe(norm, tiny);
        ms.rate = monitor.eta;
        match verdict {
            Verdict::Converged => return Ok(()),
            Verdict::Diverged | Verdict::TooSlow { .. } => return Err(Failure::Newton),
            Verdict::Continue => {}
        }
        if !it.residual() {
            return Err(Failure::Newton);
        }
    }
}

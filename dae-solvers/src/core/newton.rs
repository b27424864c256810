//! The contraction monitor of a simplified Newton iteration.
//!
//! A simplified Newton iteration `x_{k+1} = x_k − M⁻¹ F(x_k)` with a frozen
//! matrix `M` converges linearly. With `‖Δ_k‖` the norm of its `k`-th
//! increment, the contraction factor `θ` is estimated from successive
//! increments, and the distance to the solution is bounded by
//! `η ‖Δ_k‖`, `η = θ/(1 − θ)` (Hairer & Wanner IV.8 (8.10)–(8.13); Brenan,
//! Campbell & Petzold ch. 5). After each increment the monitor says
//! [`Verdict::Continue`], [`Verdict::Converged`] (`η ‖Δ_k‖ ≤ κ`),
//! [`Verdict::TooSlow`] (the iterations left cannot reach `κ`: retry with a
//! smaller step, by the factor given) or [`Verdict::Diverged`].
//!
//! The two classical codes estimate `θ` differently, and both are kept
//! ([`Rule`]) because the step counts of the methods built on them are
//! pinned to those codes:
//!
//! - RADAU5: `θ_k = sqrt(q_k q_{k−1})` with `q_k = ‖Δ_k‖/‖Δ_{k−1}‖` (the
//!   first estimate is `q_2`), divergence at `θ ≥ 0.99`, and an early exit
//!   when `η ‖Δ_k‖ θ^(k_max − k − 1) ≥ κ`; before both, convergence when
//!   the increments have stopped contracting at the round-off floor
//!   (`θ ≥ 0.9` or `q_k ≥ 0.9` with `‖Δ_k‖ ≤ 0.3`, see
//!   `ROUND_OFF_FLOOR`), and no early exit below that floor, where slow
//!   contraction may be noise;
//! - DASSL: `θ_k = (‖Δ_k‖/‖Δ_1‖)^(1/(k−1))`, divergence at `θ > 0.9`, and
//!   convergence as soon as `‖Δ_k‖ ≤ 100 ε ‖y‖`; a method may give it a
//!   round-off floor (`floor`, zero in DASSL and `bdf`): `θ > 0.9` at an
//!   increment below it is convergence, not divergence.
//!
//! `η` persists from one iteration to the next (a method may carry it
//! across steps, as both codes do).

/// What the iteration does after an increment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Verdict {
    /// Iterate once more.
    Continue,
    /// The iterate is within `κ` of the solution.
    Converged,
    /// The remaining iterations cannot reach `κ`: retry with the step size
    /// multiplied by `factor`.
    TooSlow {
        /// Step-size factor.
        factor: f64,
    },
    /// Diverging, or no convergence within the iteration limit.
    Diverged,
}

/// How `θ` is estimated and judged (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rule {
    /// RADAU5's estimate; the early exit when `slow_exit`.
    Radau5 {
        /// Stop early with [`Verdict::TooSlow`] (adaptive steps).
        slow_exit: bool,
    },
    /// DASSL's estimate.
    Dassl,
}

/// Unit round-off.
const UROUND: f64 = f64::EPSILON * 0.5;

/// RADAU5 rule: `θ` at which the increments have stopped contracting.
const STAGNANT: f64 = 0.9;

/// RADAU5 rule: an increment of at most this weighted norm (0.3 of the
/// tolerance) that no longer contracts (`θ ≥` [`STAGNANT`]) is the
/// round-off of the residual and the linear solves, not a distance still to
/// go: the iterate is as close as the arithmetic allows, within the
/// tolerance, and the iteration has converged (the error test then judges
/// the step). Without this exit a badly scaled iteration matrix whose
/// round-off floor lies above `κ` — Andrews' squeezer at tol ≤ 1e-8, where
/// accelerations of 5·10⁵ meet angles of 15 — is declared divergent at
/// every step size until the step collapses. The raw ratio `q_k` is tested
/// besides the smoothed `θ`: noise makes increments grow and shrink in turn,
/// which `θ = sqrt(q_k q_{k−1})` averages to ≈ 0.4. Below the floor the
/// early "too slow" exit is not taken either: it would shrink a step whose
/// increments do not depend on the step.
///
/// Measured on the squeezer's `rcd0` at tol 1e-9 (every increment printed):
/// the increments stagnate between 0.03 and 0.34 at every step size from
/// 1e-5 down to 6e-9, where the run used to stop (`newton_failure`). With
/// the floor at 1e-2 (its value until 2026-11-24) radau5 failed there at
/// 1e-9 and 1e-10; at 0.1 at 1e-10; at 0.3 it reaches the end at both, with
/// 9.57 significant digits, the arithmetic's limit on this problem. Elsewhere
/// only `rcd0` at tol ≤ 1e-10 moved (S01 3 of 248 runs, S02 4 of 68 at
/// 1e-9…1e-12: fewer rejected steps, errors within ±13 %; BENCHMARKS §2d).
pub(crate) const ROUND_OFF_FLOOR: f64 = 0.3;

/// State of one Newton iteration (see the [module documentation](self)).
pub(crate) struct Contraction {
    rule: Rule,
    /// Iterations allowed.
    max_iter: usize,
    /// Convergence bound `κ`.
    pub(crate) kappa: f64,
    /// Increments so far.
    k: usize,
    /// `‖Δ_1‖` (DASSL) or `‖Δ_{k−1}‖` (RADAU5).
    reference: f64,
    /// `q_{k−1}` (RADAU5).
    q_prev: f64,
    /// Current contraction estimate `θ`.
    pub(crate) theta: f64,
    /// The first observed ratio `q₂ = ‖Δ₂‖/‖Δ₁‖` of this iteration (RADAU5
    /// rule; the initial `θ` until there is one): the contraction of the
    /// iteration matrix, before round-off can mask it.
    pub(crate) theta_first: f64,
    /// The smallest ratio `q_k` of this iteration (RADAU5 rule): the
    /// strongest contraction seen, the evidence that the matrix is good.
    q_min: f64,
    /// `η = θ/(1 − θ)`, carried between iterations.
    pub(crate) eta: f64,
    /// Increments of at most this norm that no longer contract are
    /// round-off: [`ROUND_OFF_FLOOR`] for the RADAU5 rule, 0 (never, DASSL's
    /// own rule) for the DASSL rule, unless a method sets its own.
    pub(crate) floor: f64,
    /// A second, higher floor for a method whose `floor` is a few hundred
    /// units of round-off (`gauss`, iterating towards round-off): increments
    /// that stagnate at or below it count as converged too, but only when
    /// the iteration has contracted strongly at some increment (`q_min` ≤
    /// [`STRONG_CONTRACTION`]), so the matrix is good and the stagnation is
    /// the round-off of a badly scaled problem, not slow convergence. 0:
    /// none.
    pub(crate) noise_floor: f64,
}

/// The contraction `q_k` at or below which, seen once in an iteration, that
/// iteration's later stagnation under [`Contraction::noise_floor`] is taken
/// for round-off.
///
/// Measured on Andrews' squeezer, `gauss(rcd0)` at tol 1e-8 (every
/// increment printed): `q₂` is 2·10⁻⁴ … 5·10⁻³ at steps of 10⁻⁵ … 6·10⁻⁸,
/// and the increments then stagnate at 3–7·10⁻⁷ (weighted), some 10⁶ units
/// of round-off, where the drift bound asks for 10⁻¹¹: every attempt was
/// declared divergent until the step collapsed (`newton_failure` at
/// t = 0.0227). On `mex0` at tol 1e-9 the first ratio is weaker — 0.01 …
/// 0.1, the predictor's error is corrected nonlinearly — and the next
/// ones 2·10⁻³ … 10⁻², before the same stagnation at 10⁻⁶: the strongest
/// ratio, not the first, tells a good matrix (until 2026-11-27 the first
/// was tested, and `mex0` failed at t = 0.0204 at 1e-9 and 1e-10). A
/// stale or poor iteration matrix contracts at 0.1 or worse throughout;
/// 0.01 keeps those out.
const STRONG_CONTRACTION: f64 = 0.01;

impl Contraction {
    /// A monitor for `rule` converging at `η ‖Δ‖ ≤ kappa`; `eta` is the
    /// starting value of `η` (carried from earlier iterations, or large
    /// when unknown).
    pub(crate) fn new(rule: Rule, max_iter: usize, kappa: f64, eta: f64) -> Self {
        Contraction {
            rule,
            max_iter,
            kappa,
            k: 0,
            reference: 0.0,
            q_prev: 0.0,
            theta: 0.0,
            theta_first: 0.0,
            q_min: f64::INFINITY,
            eta,
            floor: match rule {
                Rule::Radau5 { .. } => ROUND_OFF_FLOOR,
                Rule::Dassl => 0.0,
            },
            noise_floor: 0.0,
        }
    }

    /// Restart for a new iteration with the carried `η` and initial `θ`.
    pub(crate) fn restart(&mut self, max_iter: usize, eta: f64, theta: f64) {
        self.max_iter = max_iter;
        self.k = 0;
        self.reference = 0.0;
        self.q_prev = 0.0;
        self.eta = eta;
        self.theta = theta;
        self.theta_first = theta;
        self.q_min = f64::INFINITY;
    }

    /// Increments observed in this iteration.
    pub(crate) fn iterations(&self) -> usize {
        self.k
    }

    /// The iteration that has just converged ended with increments that no
    /// longer contracted (`θ` or the last ratio at least [`STAGNANT`]): it
    /// stopped at its round-off floor, not because the increments fell
    /// below `κ`. (An iteration converged at its first increment has no
    /// ratio: not stagnant.)
    pub(crate) fn stagnant(&self) -> bool {
        self.k > 1 && self.q_prev.max(self.theta) >= STAGNANT
    }

    /// Judge the increment of norm `norm`; `tiny` is DASSL's round-off
    /// bound `100 ε ‖y‖` (ignored by the RADAU5 rule). A non-finite norm
    /// diverges.
    #[inline]
    pub(crate) fn observe(&mut self, norm: f64, tiny: f64) -> Verdict {
        self.k += 1;
        let k = self.k;
        if !norm.is_finite() {
            return Verdict::Diverged;
        }
        match self.rule {
            Rule::Radau5 { slow_exit } => {
                if k > 1 && k < self.max_iter {
                    let q = norm / self.reference;
                    self.theta = if k == 2 {
                        self.theta_first = q;
                        q
                    } else {
                        (q * self.q_prev).sqrt()
                    };
                    self.q_prev = q;
                    self.q_min = self.q_min.min(q);
                    if q.max(self.theta) >= STAGNANT
                        && (norm <= self.floor
                            || (norm <= self.noise_floor && self.q_min <= STRONG_CONTRACTION))
                    {
                        return Verdict::Converged;
                    }
                    if self.theta >= 0.99 {
                        return Verdict::Diverged;
                    }
                    self.eta = self.theta / (1.0 - self.theta);
                    let remaining = (self.max_iter - k - 1) as i32;
                    // Near the round-off floor slow contraction may be
                    // noise: iterate on, so that stagnation is seen (above).
                    if slow_exit && norm > self.floor {
                        let predicted = self.eta * norm * self.theta.powi(remaining) / self.kappa;
                        if predicted >= 1.0 {
                            let q = predicted.clamp(1e-4, 20.0);
                            let factor = 0.8 * q.powf(-1.0 / (4.0 + f64::from(remaining)));
                            return Verdict::TooSlow { factor };
                        }
                    }
                }
                self.reference = norm.max(UROUND);
                if self.eta * norm <= self.kappa {
                    return Verdict::Converged;
                }
            }
            Rule::Dassl => {
                if norm <= tiny {
                    return Verdict::Converged;
                }
                if k == 1 {
                    self.reference = norm;
                } else {
                    let q = norm / self.reference;
                    // `x^1 = x` exactly: no power at the second increment,
                    // the usual last one.
                    self.theta = if k == 2 {
                        q
                    } else {
                        q.powf(1.0 / (k - 1) as f64)
                    };
                    if self.theta > 0.9 {
                        return if norm <= self.floor {
                            Verdict::Converged
                        } else {
                            Verdict::Diverged
                        };
                    }
                    self.eta = self.theta / (1.0 - self.theta);
                }
                if self.eta * norm <= self.kappa {
                    return Verdict::Converged;
                }
            }
        }
        if k >= self.max_iter {
            Verdict::Diverged
        } else {
            Verdict::Continue
        }
    }
}

/// Newton failures on one step, for telling a step that is too long from
/// an iteration that no step can help: the increments of the failed
/// iterations, as the step is shortened, either shrink with it (the
/// predictor's error and the nonlinearity scale with powers of `h`) or they
/// do not — the round-off of a residual whose terms are far larger than the
/// tolerance of an unknown they determine (a multiplier balancing a stiff
/// spring of 10⁷ N/m, asked for to 10⁻⁸), where halving the step ten more
/// times only walks it down to `newton_failure` at `h ≈ 10⁻¹¹`.
///
/// [`Stall::failed`] is told the weighted norm of the last increment of each
/// failed iteration; it answers `true` (and [`Stall::stalled`] stays `true`)
/// once [`STALL_FAILURES`] failures in a row have increments between
/// [`STALL_MIN`] and [`STALL_MAX`] (of the order of the tolerance: noise,
/// not a gross divergence) that vary by at most [`STALL_SPREAD`], or by the
/// square root of the step's shrink when that is more, while the step has
/// shrunk by [`STALL_SHRINK`] or more. Any other failure starts
/// the count again, as does an accepted step or one rejected by its error
/// test ([`Stall::converged`]).
///
/// The same failures separated by steps whose iterations converged at the
/// round-off floor are a walk down it ([`Stall::walked`]): that one ends
/// the run when it is seen, since the step it shrinks is not retried
/// within one step's failure budget but step after step.
///
/// It names a failure, it does not cause one: the step is still shrunk
/// within the failure budget — the thresholds are heuristics, and a run
/// that shorter steps would get through must not be ended on them — and
/// only when the budget or the smallest step ends it does a stall make the
/// error [`crate::SolveError::RoundOffFloor`] instead of `newton_failure`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Stall {
    count: usize,
    h_first: f64,
    h_last: f64,
    lo: f64,
    hi: f64,
    /// Failures of the current walk (see [`Stall::walked`]); 0: none.
    walk: usize,
    /// The longest step attempted during the walk.
    walk_from: f64,
}

/// Failed iterations in a row that make a stall.
pub(crate) const STALL_FAILURES: usize = 4;
/// Smallest increment (weighted norm) of a stall: below it the iteration
/// converges under the round-off floor ([`ROUND_OFF_FLOOR`]).
pub(crate) const STALL_MIN: f64 = 0.05;
/// Largest increment of a stall: beyond a few tolerances the failure is a
/// divergence, whatever its cause.
pub(crate) const STALL_MAX: f64 = 4.0;
/// Largest ratio between the stalled increments.
pub(crate) const STALL_SPREAD: f64 = 2.0;
/// The step must have shrunk by at least this factor over the stall (three
/// halvings), in which increments that scale with `h` would have fallen by
/// more than [`STALL_SPREAD`].
pub(crate) const STALL_SHRINK: f64 = 8.0;
/// Failures that make a walk down the round-off floor ([`Stall::walked`]).
pub(crate) const WALK_FAILURES: usize = 8;
/// The step must have shrunk by at least this factor over a walk: far more
/// than the halvings of a stall in a row, since steps accepted at the floor
/// separate its failures.
pub(crate) const WALK_SHRINK: f64 = 1e4;

impl Stall {
    /// The iteration of an attempt with step `h` converged (the step was
    /// then accepted or failed its error test): the count of failures in
    /// a row starts again; the walk goes on if the iteration converged at
    /// its round-off floor (`stagnant`, [`Contraction::stagnant`]) and
    /// ends if its increments fell below `κ`.
    ///
    /// `stagnant` is asked only during a walk: outside one this costs what
    /// resetting the count did.
    pub(crate) fn converged(&mut self, stagnant: impl FnOnce() -> bool, h: f64) {
        self.count = 0;
        if self.walk > 0 {
            if stagnant() {
                self.walk_from = self.walk_from.max(h);
            } else {
                self.walk = 0;
            }
        }
    }

    /// The step of the first failure counted (of the walk, once it ended
    /// the run).
    pub(crate) fn first_step(&self) -> f64 {
        if self.walked() {
            self.walk_from
        } else {
            self.h_first
        }
    }

    /// The run walks down the round-off floor: since the last iteration
    /// that converged below `κ`, every iteration has either stagnated at
    /// the floor or failed with increments between [`STALL_MIN`] and
    /// [`STALL_MAX`], [`WALK_FAILURES`] failures or more, and the step has
    /// shrunk by [`WALK_SHRINK`] from the longest one attempted meanwhile.
    ///
    /// The failures of a stall in a row ([`Stall::stalled`]) are separated
    /// here by steps accepted at the floor: the increments of the unknown
    /// at its floor are a few quanta of round-off, some under the floor
    /// ([`ROUND_OFF_FLOOR`], converged) and some over it (failed, the step
    /// cut), whatever the step, and the step, grown by less after an
    /// acceptance than it is cut after a failure, drifts down to the
    /// smallest step — `rcd0` of the stiff spring (`tests/stiff_spring.rs`)
    /// from 5·10⁻⁴ to 10⁻¹⁶ in 63 attempts at t = 0.0594, its runs of up
    /// to five failures in a row too uneven (0.30–0.64) to be a stall. A
    /// step too long is cured by shrinking it: its iterations converge
    /// below `κ` again, which ends the walk.
    pub(crate) fn walked(&self) -> bool {
        self.walk >= WALK_FAILURES && self.h_last * WALK_SHRINK <= self.walk_from
    }

    /// The failures counted so far make a stall.
    pub(crate) fn stalled(&self) -> bool {
        self.count >= STALL_FAILURES && self.h_last * STALL_SHRINK <= self.h_first
    }

    /// An iteration at step `h` failed with a last increment of weighted
    /// norm `norm`; `true` when the failures make a stall.
    pub(crate) fn failed(&mut self, h: f64, norm: f64) -> bool {
        if !(STALL_MIN..=STALL_MAX).contains(&norm) {
            (self.count, self.walk) = (0, 0);
            return false;
        }
        if self.walk == 0 {
            self.walk_from = h;
        }
        self.walk += 1;
        self.walk_from = self.walk_from.max(h);
        if self.count == 0 {
            (self.h_first, self.lo, self.hi) = (h, norm, norm);
        } else {
            self.lo = self.lo.min(norm);
            self.hi = self.hi.max(norm);
        }
        self.count += 1;
        self.h_last = h;
        // Increments that scale with the step fall at least as it shrinks;
        // noise at a floor spreads without following it. The spread
        // allowed grows with the square root of the shrink: Andrews'
        // squeezer, odradau(ovd0) at 1e-9 (EXTREMES.md §5, lit10), failed
        // ten times in a row at t = 0.0203 from h = 1.8e-6 to 6.0e-9 with
        // increments of 0.34–1.6 of the tolerance, never within
        // [`STALL_SPREAD`] over eight halvings, and was called
        // `newton_failure`.
        let spread = STALL_SPREAD.max((self.h_first / h).sqrt());
        if self.hi > spread * self.lo {
            // Increments that changed this much are not a floor: count
            // from this failure on.
            (self.count, self.h_first, self.lo, self.hi) = (1, h, norm, norm);
        }
        self.stalled()
    }
}

/// [`crate::SolveError::RoundOffFloor`] at `t` with step `h`, the stall
/// seen from `h_from`, naming the unknown `unknown` of `info` (the one with
/// the largest weighted increment, `level`, of the last failed iteration).
pub(crate) fn round_off_floor(
    info: &dae_core::system::FormulationInfo,
    (t, h, h_from): (f64, f64, f64),
    unknown: usize,
    level: f64,
) -> crate::SolveError {
    crate::SolveError::RoundOffFloor {
        t,
        h,
        h_from,
        unknown: info
            .variables
            .get(unknown)
            .map_or_else(|| format!("#{unknown}"), |v| v.name.clone()),
        level,
    }
}

/// A walk down a round-off floor as a multistep corrector sees it:
/// [`WALK_FAILURES`] Newton failures in a row on one step, none after a
/// step longer than the walk's first, the step cut [`WALK_SHRINK`]-fold, and
/// the last weighted increment at least [`STALL_MIN`] of the tolerance
/// (the collocation engine follows the same walk with [`Stall`], which also
/// watches the converged iterations in between). Used by mebdf; a service
/// for any corrector that sees only its failures.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FloorWalk {
    h_from: f64,
    count: usize,
}

impl FloorWalk {
    /// Before an attempt with step `h`: a step longer than the walk's
    /// first ends the walk.
    pub(crate) fn attempt(&mut self, h: f64) {
        if h > self.h_from {
            *self = Self::default();
        }
    }

    /// After a Newton failure at `(t, h)` with last increments `delta`:
    /// the typed error once the walk is long enough.
    pub(crate) fn failed<S: crate::core::weights::Sum>(
        &mut self,
        (t, h): (f64, f64),
        delta: &[f64],
        weights: &crate::core::weights::Weights<S>,
        info: &dae_core::system::FormulationInfo,
    ) -> Result<(), crate::SolveError> {
        if self.count == 0 || h > self.h_from {
            *self = Self {
                h_from: h,
                count: 0,
            };
        }
        self.count += 1;
        let level = weights.norm(delta);
        if self.count < WALK_FAILURES
            || h * WALK_SHRINK > self.h_from
            || level.is_nan()
            || level < STALL_MIN
        {
            return Ok(());
        }
        let unknown = crate::core::weights::largest_weighted(delta, weights.get(), delta.len(), 1);
        Err(round_off_floor(info, (t, h, self.h_from), unknown, level))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_contraction_converges_and_estimates_theta() {
        for rule in [Rule::Radau5 { slow_exit: true }, Rule::Dassl] {
            let mut c = Contraction::new(rule, 10, 1e-6, 1.0);
            let mut norm = 1.0;
            let mut verdict = Verdict::Continue;
            while verdict == Verdict::Continue {
                verdict = c.observe(norm, 0.0);
                norm *= 0.1;
            }
            assert_eq!(verdict, Verdict::Converged, "{rule:?}");
            assert!((c.theta - 0.1).abs() < 1e-12, "{rule:?}: {}", c.theta);
        }
    }

    #[test]
    fn growth_diverges_and_slow_contraction_exits_early() {
        let mut c = Contraction::new(Rule::Dassl, 4, 0.33, 100.0);
        assert_eq!(c.observe(1.0, 0.0), Verdict::Continue);
        assert_eq!(c.observe(2.0, 0.0), Verdict::Diverged);
        let mut c = Contraction::new(Rule::Radau5 { slow_exit: true }, 7, 1e-3, 1.0);
        assert_eq!(c.observe(1.0, 0.0), Verdict::Continue);
        assert!(matches!(c.observe(0.9, 0.0), Verdict::TooSlow { factor } if factor < 1.0));
        assert_eq!(c.observe(f64::NAN, 0.0), Verdict::Diverged);
        // Round-off: DASSL accepts a negligible first increment at once.
        let mut c = Contraction::new(Rule::Dassl, 4, 0.33, 100.0);
        assert_eq!(c.observe(1e-20, 1e-14), Verdict::Converged);
    }

    #[test]
    fn dassl_rule_accepts_stagnation_below_its_floor_only_when_given_one() {
        // DASSL's own rule (and bdf's): growth is divergence, however small.
        let mut c = Contraction::new(Rule::Dassl, 5, 0.01, 100.0);
        assert_eq!(c.observe(1e-3, 1e-9), Verdict::Continue);
        assert_eq!(c.observe(2e-3, 1e-9), Verdict::Diverged);
        // With a floor (mebdf): below it, round-off, converged; above it,
        // still divergence.
        let mut c = Contraction::new(Rule::Dassl, 5, 0.01, 100.0);
        c.floor = 1e-2;
        assert_eq!(c.observe(1e-3, 1e-9), Verdict::Continue);
        assert_eq!(c.observe(2e-3, 1e-9), Verdict::Converged);
        let mut c = Contraction::new(Rule::Dassl, 5, 0.01, 100.0);
        c.floor = 1e-2;
        assert_eq!(c.observe(0.3, 1e-9), Verdict::Continue);
        assert_eq!(c.observe(0.6, 1e-9), Verdict::Diverged);
    }

    #[test]
    fn radau5_accepts_increments_stagnating_at_the_round_off_floor() {
        // Increments that stop contracting far below the tolerance but
        // above a tight κ: round-off, converged.
        let mut c = Contraction::new(Rule::Radau5 { slow_exit: true }, 7, 1e-5, 1.0);
        assert_eq!(c.observe(3e-3, 0.0), Verdict::Continue);
        assert_eq!(c.observe(2.9e-3, 0.0), Verdict::Converged);
        // Up to 0.3 of the tolerance, growing or shrinking in turn (the
        // squeezer's rcd0 at 1e-9: 0.155, then 0.34, then 0.18).
        let mut c = Contraction::new(Rule::Radau5 { slow_exit: true }, 7, 1e-5, 1.0);
        assert_eq!(c.observe(0.31, 0.0), Verdict::Continue);
        assert_eq!(c.observe(0.18, 0.0), Verdict::Continue);
        assert_eq!(c.observe(0.29, 0.0), Verdict::Converged);
        // The same stagnation at the tolerance's size is no convergence.
        let mut c = Contraction::new(Rule::Radau5 { slow_exit: true }, 7, 1e-5, 1.0);
        assert_eq!(c.observe(0.6, 0.0), Verdict::Continue);
        assert!(matches!(c.observe(0.59, 0.0), Verdict::TooSlow { .. }));
        let mut c = Contraction::new(Rule::Radau5 { slow_exit: true }, 7, 1e-5, 1.0);
        assert_eq!(c.observe(0.6, 0.0), Verdict::Continue);
        assert_eq!(c.observe(0.62, 0.0), Verdict::Diverged);
    }

    #[test]
    fn noise_floor_accepts_round_off_stagnation_after_a_strong_contraction_only() {
        // gauss: a floor of a few hundred units of round-off, and the noise
        // floor at 0.3. The squeezer's rcd0 at 1e-8 (h = 9.4e-7): 0.89,
        // 2e-4, 8.5e-7, 4.2e-7, 3.6e-7, 7.3e-7 — stagnation at round-off.
        let gauss = || {
            let mut c = Contraction::new(Rule::Radau5 { slow_exit: false }, 20, 1e-11, 1.0);
            c.floor = 1e-13;
            c.noise_floor = ROUND_OFF_FLOOR;
            c.restart(20, 1.0, 0.001);
            c
        };
        let mut c = gauss();
        for norm in [0.89, 2e-4, 8.5e-7, 4.2e-7, 3.6e-7] {
            assert_eq!(c.observe(norm, 0.0), Verdict::Continue);
        }
        assert_eq!(c.observe(7.3e-7, 0.0), Verdict::Converged);
        // Without the noise floor (before): divergence.
        let mut c = gauss();
        c.noise_floor = 0.0;
        for norm in [0.89, 2e-4, 8.5e-7, 4.2e-7, 3.6e-7] {
            assert_eq!(c.observe(norm, 0.0), Verdict::Continue);
        }
        assert_eq!(c.observe(7.3e-7, 0.0), Verdict::Diverged);
        // A weak first contraction (a poor matrix): the same stagnation is
        // not taken for round-off.
        let mut c = gauss();
        for norm in [1e-3, 2e-4] {
            assert_eq!(c.observe(norm, 0.0), Verdict::Continue);
        }
        assert_eq!(c.observe(2.1e-4, 0.0), Verdict::Continue);
        // With a strong first contraction it would have been converged.
        let mut c = gauss();
        for norm in [1e-3, 5e-6] {
            assert_eq!(c.observe(norm, 0.0), Verdict::Continue);
        }
        assert_eq!(c.observe(5.2e-6, 0.0), Verdict::Converged);
        // A weak first ratio and strong later ones (the predictor's error
        // corrected nonlinearly): the squeezer's mex0 at 1e-9, h = 1.08e-4.
        let mut c = gauss();
        for norm in [490.3, 46.96, 0.5054, 1.049e-3, 6.095e-5, 1.442e-6, 6.761e-7] {
            assert_eq!(c.observe(norm, 0.0), Verdict::Continue);
        }
        assert_eq!(c.observe(1.270e-6, 0.0), Verdict::Converged);
    }

    #[test]
    fn a_walk_is_failures_at_the_floor_between_steps_accepted_at_it() {
        // The stiff spring's rcd0 at t = 0.0595 (k = 1e9, tol 1e-8): the
        // increments of λ are 1–4 roundings of the spring's length, weighted
        // 0.14–0.63 whatever the step; every other attempt fails (the step
        // halved) and the others converge at the floor (the step grown by
        // ~1.5): the step drifts down without a stall in a row.
        let walk = |clean_at: Option<usize>| {
            let mut s = Stall::default();
            let mut h = 6.5e-4;
            for i in 0..60 {
                assert!(!s.failed(h, [0.55, 0.35, 0.62][i % 3]), "{i}");
                if s.walked() {
                    return Some((i, h));
                }
                h *= 0.5;
                s.converged(|| clean_at != Some(i), h);
                h *= 1.3;
                assert!(!s.walked());
            }
            None
        };
        // Ended when the step has shrunk 10⁴-fold (1.3/2 per failure: 22
        // failures), not at the smallest step.
        let (i, h) = walk(None).unwrap();
        assert_eq!(i, 22);
        assert!(h * WALK_SHRINK <= 6.5e-4 && h > 1e-9, "{h}");
        // One iteration converged below κ (a step too long, cured by
        // shrinking it) starts the walk again.
        let (i, _) = walk(Some(10)).unwrap();
        assert_eq!(i, 33);
        // So does a failure outside the band (a gross divergence): the
        // walk after it is counted from its own first failure.
        let mut s = Stall::default();
        let mut h = 1.0;
        let mut fail = |s: &mut Stall, norm: f64| {
            let h_failed = h;
            s.failed(h, norm);
            h *= 1e-1;
            s.converged(|| true, h);
            h_failed
        };
        for _ in 0..8 {
            fail(&mut s, 0.5);
        }
        assert!(s.walked());
        fail(&mut s, 50.0);
        assert!(!s.walked());
        let first = fail(&mut s, 0.5);
        for _ in 0..6 {
            fail(&mut s, 0.5);
            assert!(!s.walked());
        }
        fail(&mut s, 0.5);
        assert!(s.walked());
        assert_eq!(s.first_step(), first);
        // Failures at the floor with the step kept (a constant step, a
        // step grown back after each cut): no walk.
        let mut s = Stall::default();
        for _ in 0..50 {
            s.failed(1e-3, 0.5);
            s.converged(|| true, 2e-3);
        }
        assert!(!s.walked());
    }

    #[test]
    fn a_noisy_stall_over_a_long_shrink_is_a_stall() {
        // Andrews' squeezer, odradau(ovd0) at 1e-9, t = 0.0203: ten Newton
        // failures in a row, the last increments (weighted) as the step
        // was cut from 1.8e-6 to 6.0e-9; never within a factor 2 over
        // eight halvings, within the square root of the shrink from the
        // fourth on.
        let trace = [
            (1.773e-6, 0.371),
            (8.609e-7, 0.340),
            (4.304e-7, 0.534),
            (2.152e-7, 1.096),
            (1.122e-7, 1.005),
            (5.852e-8, 1.263),
            (3.788e-8, 0.710),
            (1.975e-8, 1.058),
            (1.087e-8, 0.770),
            (5.977e-9, 1.585),
        ];
        let mut s = Stall::default();
        let stalled: Vec<bool> = trace.iter().map(|&(h, n)| s.failed(h, n)).collect();
        assert_eq!(
            stalled,
            [false, false, false, false, false, false, false, true, true, true]
        );
        // The same increments halving with the step are not one.
        let mut s = Stall::default();
        for (i, &(h, _)) in trace.iter().enumerate() {
            assert!(!s.failed(h, 3.0 * h / trace[0].0), "{i}");
        }
    }

    #[test]
    fn a_stall_is_increments_that_do_not_shrink_with_the_step() {
        // The stiff spring's multiplier: 0.3–0.65 of the tolerance at every
        // step from 2.4e-8 down (`tests/stiff_spring.rs`).
        let mut s = Stall::default();
        let mut h = 2.4e-8;
        let mut stalled = Vec::new();
        for norm in [0.58, 0.56, 0.64, 0.65, 0.65] {
            stalled.push(s.failed(h, norm));
            h *= 0.5;
        }
        assert_eq!(stalled, [false, false, false, true, true]);
        // Increments that shrink with the step are a step too long.
        let mut s = Stall::default();
        let mut h = 1e-3;
        let mut norm = 3.0;
        for _ in 0..10 {
            assert!(!s.failed(h, norm));
            h *= 0.5;
            norm *= 0.5;
        }
        // Four flat failures without enough shrinking are not one either
        // (a constant step retried, a failure at the same h).
        let mut s = Stall::default();
        for _ in 0..6 {
            assert!(!s.failed(1e-3, 0.5));
        }
        // Gross divergence is not a stall, and resets the count.
        let mut s = Stall::default();
        let mut h = 1e-3;
        for norm in [0.5, 0.5, 0.5, 50.0, 0.5, 0.5, 0.5] {
            assert!(!s.failed(h, norm));
            h *= 0.5;
        }
        assert!(s.failed(h, 0.5));
        s.converged(|| false, h);
        assert!(!s.failed(h * 0.5, 0.5));
    }
}

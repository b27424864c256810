//! The integrator and its step loop (RADAU5's loop from label 10 to the
//! acceptance of a step): the start at `t₀`, one accepted step with its
//! retries, and the driver's view of it.

use super::control::{classical_quotient, predictive_quotient, Control, Hold, Next};
use super::slopes::Slopes;
use super::solve::StageSolveKind;
use super::stages::{Newton, Work};
use super::stagger::rhs_for_error;
use super::tableau::{dense, Collocation, NewtonStop, StepRule};
use super::{smallest_tolerance, TIGHT_NEWTON, TIGHT_TOL, UROUND};
use crate::core::attempt::{self, Attempts, Outcome, Retry, Steps};
use crate::core::control::{Budget, Failure};
use crate::core::driver::Method;
use crate::core::eliminate::Formulation;
use crate::core::newton::{Contraction, Rule, Stall};
use crate::core::onestep::OneStep;
use crate::linalg::all_finite;
use crate::options::Options;
use crate::{Problem, SolveError, Stats};

/// The round-off floor of a Newton iteration run towards round-off, in
/// units of round-off.
const ROUND_OFF: f64 = 1e3;

/// The state of one collocation integration: the formulation, the buffers
/// of the step loop, the work counters, the contraction monitor and the
/// step-size controller.
pub(super) struct Integrator<'a, K> {
    /// The formulation.
    pub(super) sys: Formulation<'a>,
    /// Unknowns `N`.
    pub(super) n: usize,
    /// Equations `M` (`M = N` unless the stage systems are least squares).
    pub(super) m: usize,
    /// Start of the horizon.
    pub(super) t0: f64,
    /// `E` does not depend on `y`.
    pub(super) constant_leading: bool,
    /// Every buffer of the step loop.
    pub(super) w: Work,
    /// Work counters.
    pub(super) stats: Stats,
    /// Contraction monitor; its `η` is carried from step to step and its
    /// `θ` decides Jacobian reuse.
    pub(super) newton: Contraction,
    /// Step-size controller state.
    pub(super) c: Control,
    /// The tableau.
    pub(super) method: std::marker::PhantomData<K>,
    /// Newton bounds of a method iterating towards round-off: the floor,
    /// and the coefficient `c` of the drift bound `c h²` (see
    /// [`crate::gauss`]); zero otherwise.
    pub(super) newton_floor: f64,
    pub(super) newton_drift: f64,
    /// The last failed Newton iteration: its last increment's weighted
    /// norm and the unknown that dominated it.
    pub(super) newton_last: (f64, usize),
    /// The step points' slopes and Hermite polynomial: the dense output
    /// of a method that is not stiffly accurate ([`super::slopes`]).
    pub(super) slopes: Slopes,
    /// Whether a value between step points can be asked for (else the
    /// step points' slopes are not taken).
    pub(super) interpolate: bool,
}

impl<K: Collocation> Method for Integrator<'_, K> {
    fn t(&self) -> f64 {
        self.c.one.t
    }
    fn y(&self) -> &[f64] {
        &self.w.y
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        let tau = tau - self.c.one.t_lo;
        dense::<K>(
            self.n,
            &self.w.cont,
            tau,
            self.c.one.t,
            self.c.one.h_old,
            out,
        );
        if self.slopes.hermite.ready() {
            self.slopes.hermite.eval(tau, out);
        }
    }
    fn output(&self, tau: f64, out: &mut [f64]) {
        self.dense(tau, out);
        if K::TABLEAU.end.projected() {
            self.project_output(tau, out);
        }
    }
    fn dense_degree(&self) -> usize {
        if self.slopes.active() {
            // The Hermite polynomial through the last step points.
            2 * crate::core::hermite::POINTS - 1
        } else {
            // The collocation polynomial of three stages.
            3
        }
    }
    fn finished(&self) -> bool {
        self.c.one.done
    }
    fn step(&mut self) -> Result<(), SolveError> {
        attempt::step(self)
    }
    fn stats(&self) -> Stats {
        let mut stats = self.stats;
        stats.residual_evals += self.w.output.borrow().residual_evals;
        stats
    }
}

impl<K: Collocation> Attempts for Integrator<'_, K> {
    fn steps(&mut self) -> &mut Steps {
        &mut self.c.one.steps
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.stats
    }
    fn point(&self) -> (f64, f64) {
        (self.c.one.t, self.c.one.h)
    }
    fn set_step(&mut self, h: f64, last: bool) {
        let c = &mut self.c;
        if h != c.one.h && c.next == Next::Step {
            c.next = Next::Factor;
        }
        c.one.h = h;
        c.one.last = last;
    }
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        Integrator::attempt(self)
    }
    fn failure_error(&self, failure: Failure, t: f64, h: f64, iterations: usize) -> SolveError {
        if failure == Failure::Newton && self.c.stall.stalled() {
            return self.round_off_floor(t, h);
        }
        Budget::error(failure, t, h, iterations)
    }
}

impl<K: Collocation> Integrator<'_, K> {
    /// [`SolveError::RoundOffFloor`] at `t` with step `h`, naming the
    /// unknown that dominated the last failed iteration ([`Stall`]).
    fn round_off_floor(&self, t: f64, h: f64) -> SolveError {
        let (level, unknown) = self.newton_last;
        crate::core::newton::round_off_floor(
            self.sys.info(),
            (t, h, self.c.stall.first_step()),
            unknown,
            level,
        )
    }
}

/// Most simplified Newton steps of the end-point projection (a method that
/// is not stiffly accurate).
const PROJECTION_STEPS: usize = 4;

/// With a constant `E` and a Jacobian older than the end point, the
/// end-point projection stops at a correction of this weighted norm (a
/// thousandth of the tolerance, as the projected dense output).
const PROJECTION_FLOOR: f64 = 1e-3;

impl<'a, K: Collocation> Integrator<'a, K> {
    /// The integrator of `problem` on its formulation `sys` (the problem's,
    /// or a presentation of it) at `t₀`, its buffers allocated; nothing is
    /// evaluated before [`Integrator::start`].
    pub(super) fn new(
        sys: Formulation<'a>,
        problem: &Problem<'_>,
        options: &'a Options,
        solve: StageSolveKind,
    ) -> Self {
        let info = sys.info();
        let (m, n) = (info.equations(), info.unknowns());
        let mut w = Work::new::<K>(&*sys, options, solve);
        w.y.copy_from_slice(problem.y0);
        // RADAU5: fnewt = max(10 u / rtol, min(0.03, rtol^(1/2))), here
        // with the smallest relative tolerance (an absolute one where all
        // relative tolerances are zero), kept above 10 u.
        let r = smallest_tolerance(
            w.weights.rtol().iter().copied(),
            w.weights.atol().iter().copied(),
        );
        let r = r.max(10.0 * UROUND);
        // The user's tolerance, before the tolerance map: it decides the
        // tight mode and a symmetric method's drift bound.
        let user = smallest_tolerance(
            (0..n).map(|i| options.tol.rtol(i)),
            (0..n).map(|i| options.tol.atol(i)),
        );
        let compensated = user <= TIGHT_TOL;
        // Not at index 3: there the multipliers carry a round-off of
        // `ε/h²` that a tighter bound only iterates on. An overdetermined
        // formulation has no differentiation index (`None`) and gets it.
        let tight_newton = compensated && info.d_index.is_none_or(|k| k < 3);
        let span = problem.t_end - problem.t0;
        let fnewt = match K::POLICY.newton {
            NewtonStop::Tolerance => {
                (10.0 * UROUND / r).max(0.03f64.min(r.sqrt()))
                    * if tight_newton { TIGHT_NEWTON } else { 1.0 }
            }
            // Towards round-off, whatever the tolerance.
            NewtonStop::RoundOff { units, .. } => units * UROUND / r,
        };
        // The drift bound of a method iterating towards round-off: an
        // error of one sign per step, `δ`, grows over `N = T/h` steps into
        // a phase error of order `N² δ`; `δ ≤ DRIFT · tol (h/T)²` keeps it
        // at a fraction of the tolerance.
        let newton_drift = match K::POLICY.newton {
            NewtonStop::Tolerance => 0.0,
            NewtonStop::RoundOff { drift, .. } => drift * user / r / (span * span),
        };
        let rule = Rule::Radau5 {
            slow_exit: K::POLICY.newton.slow_exit() && options.fixed_step.is_none(),
        };
        let mut newton = Contraction::new(rule, K::POLICY.max_newton, fnewt, 1.0);
        if let Some(st) = &mut w.stagger {
            // The sensitivities' iteration: the state's bound, without the
            // early exit (their equations are linear: an iteration that
            // contracts converges, and each costs products only).
            st.newton = Contraction::new(
                Rule::Radau5 { slow_exit: false },
                K::POLICY.max_newton,
                fnewt,
                1.0,
            );
        }
        if matches!(K::POLICY.newton, NewtonStop::RoundOff { .. }) {
            // Iterating towards round-off: stagnation counts as convergence
            // only at a few hundred units of round-off.
            newton.floor = ROUND_OFF * UROUND / r;
            // Unless the increments stagnate at the problem's own round-off
            // after a strong contraction: see `noise_floor`.
            newton.noise_floor = crate::core::newton::ROUND_OFF_FLOOR;
        }
        // The Hermite dense output is kept only where a value between step
        // points can be asked for: stored dense output, events, or an
        // output time inside the horizon (not `t_end` alone, a step point).
        let between = options.dense_output
            || !problem.system.event_names().is_empty()
            || options
                .output_times
                .iter()
                .any(|&t| t > problem.t0 && t < problem.t_end);
        Integrator {
            interpolate: between,
            sys: sys.clone(),
            n,
            m,
            t0: problem.t0,
            constant_leading: info.constant_leading,
            method: std::marker::PhantomData,
            newton_floor: fnewt,
            newton_drift,
            newton_last: (0.0, 0),
            slopes: Slopes::none(),
            w,
            stats: Stats::default(),
            newton,
            c: Control {
                one: OneStep {
                    compensated,
                    ..OneStep::new(problem, options, 1.0)
                },
                caljac: false,
                h_acc: 0.0,
                err_acc: 1e-2,
                next: Next::Jacobian,
                hold: Hold::default(),
                stall: Stall::default(),
            },
        }
    }

    /// `f(t, y_n)` into `f0`, and `E(t, y_n)` when it is not constant (or
    /// `first`).
    ///
    /// `E` comes first: a formulation may choose its rows where `E` is
    /// evaluated (`mex0`'s dummy derivatives, a numerical selector), and
    /// `f` must be those rows'.
    fn evaluate_at_step_point(&mut self, t: f64, first: bool) -> Result<(), SolveError> {
        if first || !self.constant_leading {
            self.w.e_n.leading(&*self.sys, t, &self.w.y);
            if !all_finite(self.w.e_n.values()) {
                return Err(SolveError::NonFinite {
                    t,
                    what: "leading matrix",
                });
            }
        }
        let w = &mut self.w;
        rhs_for_error(&*self.sys, w.stagger.as_ref(), t, &w.y, &mut w.f0);
        self.stats.residual_evals += 1;
        if !all_finite(&self.w.f0) {
            return Err(SolveError::NonFinite {
                t,
                what: "residual",
            });
        }
        Ok(())
    }

    /// Evaluate at `t₀` and choose the first step.
    pub(super) fn start(&mut self) -> Result<(), SolveError> {
        let t0 = self.t0;
        self.evaluate_at_step_point(t0, true)?;
        let sys = self.sys.clone();
        self.find_algebraic_rows(sys.info())?;
        self.setup_slopes();
        let c = &mut self.c;
        (c.one.h, c.one.last) = c.one.steps.toward_end(t0, c.one.h);
        c.one.h_old = c.one.h;
        c.h_acc = c.one.h;
        Ok(())
    }

    /// One attempt from `c.one.t` with `c.one.h` (RADAU5's loop from label 10 to
    /// the acceptance of a step); when accepted, the size of the next one.
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        let (t, h, fixed) = (self.c.one.t, self.c.one.h, self.c.one.fixed);
        if self.c.next == Next::Jacobian {
            self.jacobian(t)?;
            self.c.caljac = true;
            self.c.next = Next::Factor;
        }
        if self.c.next == Next::Factor {
            if self.factor(h).is_err() {
                let c = &mut self.c;
                c.one.reject = true;
                c.next = c.renewed();
                return Ok(Outcome::failed(Failure::Singular, 0));
            }
            self.stats.factorizations += 1;
        }

        // ---- one step attempt from t with h ----
        self.w.weights.update_scaled(&self.w.y, h);
        self.starting_values(self.c.one.first, h / self.c.one.h_old);

        let outcome = self.newton(t, h, fixed.is_none());
        let newt = match outcome {
            Newton::Converged(k) => k,
            Newton::TooSlow { iterations, .. }
            | Newton::Diverged(iterations)
            | Newton::NonFinite(iterations) => iterations,
        };
        self.stats.newton_iterations += newt;

        let retry = match outcome {
            Newton::Converged(_) => None,
            Newton::TooSlow { factor, .. } => Some(Retry::Shrink(factor)),
            Newton::Diverged(_) | Newton::NonFinite(_) => Some(Retry::Policy),
        };
        // Error estimate and proposed step (adaptive mode only).
        let mut err = 0.0;
        let mut h_new = h;
        let mut non_finite = matches!(outcome, Newton::NonFinite(_));
        let mut retry = retry;
        if retry.is_none() && fixed.is_none() {
            err = self.error_norm(t, h, self.c.one.first || self.c.one.reject);
            if err.is_finite() {
                h_new = h / classical_quotient(err, newt, K::POLICY.max_newton);
            } else {
                non_finite = true;
                retry = Some(Retry::Policy);
            }
        }

        // Failed iterations whose increments stay put as the step shrinks
        // (`Stall`): what the failure that ends the step is called.
        if retry.is_some() && !non_finite && fixed.is_none() {
            self.c.stall.failed(h, self.newton_last.0);
            // Failures at the floor between steps accepted at it, the step
            // cut 10⁴-fold meanwhile: no shorter step can help. Not for a
            // method iterating towards round-off (`gauss`), whose every
            // iteration may stop at its floor, so that nothing would end a
            // walk in a whole run: measured on radau5 only.
            if matches!(K::POLICY.newton, NewtonStop::Tolerance) && self.c.stall.walked() {
                return Err(self.round_off_floor(t, h));
            }
        }
        let c = &mut self.c;
        if let Some(mut retry) = retry {
            // ---- Newton failure (RADAU5's label 78) ----
            let failure = if non_finite {
                Failure::NonFinite("residual")
            } else {
                Failure::Newton
            };
            if fixed.is_some() && !c.caljac {
                c.next = Next::Jacobian;
                retry = Retry::Refresh;
            } else {
                if matches!(K::POLICY.step, StepRule::Held) {
                    c.hold.rejected();
                }
                c.one.reject = true;
                c.next = c.renewed();
            }
            return Ok(Outcome::Failed {
                failure,
                retry,
                iterations: newt,
            });
        }

        c.stall.converged(|| self.newton.stagnant(), h);
        if err >= 1.0 {
            // ---- rejected by the error test ----
            c.one.reject = true;
            let h = if c.one.first { 0.1 * h } else { h_new };
            if matches!(K::POLICY.step, StepRule::Held) {
                c.hold.rejected();
            }
            c.next = c.renewed();
            return Ok(Outcome::ErrorTest { h });
        }

        // ---- accepted ----
        if fixed.is_none() {
            if self.stats.steps > 0 {
                let quot = (h / h_new).max(predictive_quotient(err, c.err_acc, h, c.h_acc));
                h_new = h / quot;
            }
            c.h_acc = h;
            c.err_acc = err.max(1e-2);
            if matches!(K::POLICY.step, StepRule::Held) {
                h_new = c.hold.accepted(h, err, h_new);
            }
        }
        c.one.accept(h);
        c.caljac = false;
        self.advance(h);
        self.stats.steps += 1;
        let t = self.c.one.t;
        if !all_finite(&self.w.y) {
            return Err(SolveError::NonFinite {
                t,
                what: "solution",
            });
        }
        if K::TABLEAU.end.projected() {
            // Not stiffly accurate: the end point is made consistent,
            // keeping the differential part of the step just taken:
            // `E(y_n)`, not `E(y_{n+1})`, where the rows a formulation
            // chooses may change (`mex0`).
            if !self.constant_leading {
                self.w.e_step.copy_from(self.w.e_n.dense());
            }
            self.evaluate_at_step_point(t, false)?;
            // With a constant `E`, the next step's Jacobian, when it is to
            // take a new one, is taken here, at the end point before its
            // projection: the projection's Newton step is then exact where
            // the algebraic rows are linear in the algebraic unknowns
            // (their columns of `J` do not depend on them), and quadratic
            // otherwise. Not with a state-dependent `E` (psi0, mex0),
            // whose projection evaluates `f` and `E` after every step
            // anyway, and where `mex0` chooses its rows where `E` is
            // evaluated: taken before the projection, its Jacobian cost
            // S01 a digit at 1e-8 (measured).
            let fresh = self.constant_leading && !self.c.one.done && !self.small_theta();
            if fresh {
                self.jacobian(t)?;
            }
            self.project_end_point(t, h, fresh)?;
            self.push_slopes();
            if fresh {
                // The Jacobian is this end point's: `next_step` below
                // factorises it rather than taking another.
                self.c.caljac = true;
            }
        }
        if self.c.one.done {
            return Ok(Outcome::Accepted);
        }
        if !K::TABLEAU.end.projected() {
            self.evaluate_at_step_point(t, false)?;
        }
        self.next_step(h_new);
        Ok(Outcome::Accepted)
    }

    /// Make the end point of an accepted step consistent (a method that
    /// is not stiffly accurate, see [`crate::gauss`]): simplified Newton
    /// steps on the algebraic rows ([`Integrator::project`]), the
    /// differential part of the step kept. `fresh`: the iteration's `J`
    /// was just taken at this end point.
    ///
    /// With a constant `E`, one step with a fresh `J` suffices; with the
    /// `J` of the step's start (or older), whose algebraic columns may
    /// have changed over the step, `f` is evaluated again after each step
    /// and the iteration runs until a correction is below
    /// [`PROJECTION_FLOOR`] (measured: on the reactor's `rcd0` one step left
    /// a tenth of the correction, the coolant temperature `TC` 4.7e-6 off
    /// at tol 1e-8, 470 times the error of the differential unknowns). A
    /// constraint kept as a row of a state-dependent `E` (psi0, mex0) is
    /// nonlinear in the state: `f` and `E` are evaluated again after each
    /// step, until a correction is at the Newton floor; a dummy state left
    /// one step off its constraint loses the method's order.
    fn project_end_point(&mut self, t: f64, h: f64, fresh: bool) -> Result<(), SolveError> {
        for k in 0..PROJECTION_STEPS {
            let size = self.project(t, h, k == 0, !fresh)?;
            if self.constant_leading {
                // `f` was updated by the linearisation.
                if fresh || size <= PROJECTION_FLOOR {
                    break;
                }
                self.evaluate_at_step_point(t, false)?;
                continue;
            }
            let converged = size <= self.newton_floor;
            if converged && self.c.one.last {
                break;
            }
            self.evaluate_at_step_point(t, false)?;
            if converged {
                break;
            }
        }
        Ok(())
    }
}

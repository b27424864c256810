//! The corrector (block 3): the iteration matrix `G = ∂F/∂y + c_J ∂F/∂y'`,
//! when it is evaluated and factored, and the modified Newton iteration
//! from the predictor.

use super::step::Integrator;
use super::EPS;
use crate::core::control::Failure as Fail;
use crate::core::matrix::Corrector;
use crate::core::newton::{Contraction, Rule, Verdict};
use crate::linalg::{all_finite, small};

/// Newton iterations per attempt (DASSL's `MAXIT`).
const MAX_NEWTON_ITERATIONS: usize = 4;
/// Newton iterations per step in fixed-step mode, where a failure cannot be
/// cured by a smaller step: the modified Newton iteration converges only
/// linearly, and convergence studies ask for tight tolerances.
const MAX_NEWTON_ITERATIONS_FIXED_STEP: usize = 20;
/// Convergence test `ρ/(1−ρ)·‖δ‖ ≤ NEWTON_TOL` (DASSL's 0.33).
const NEWTON_TOL: f64 = 0.33;
/// The same for a least-squares corrector (`odbdf`), ten times tighter: its
/// iterate satisfies the constraint rows only to the accuracy of the
/// iteration, and the error estimate `y − y⁽⁰⁾` carries what is left of it.
/// Measured on the pendulum (ovd0 and psi0; S01 at tol 1e-6, 1e-8, 1e-10,
/// S02 at 1e-8; BENCHMARKS.md §3b): 2.6–11× smaller errors with 25–42 %
/// fewer steps than with 0.33.
const NEWTON_TOL_LEAST_SQUARES: f64 = 0.033;

pub(super) use crate::core::matrix::JacState;

impl<L: Corrector> Integrator<'_, L> {
    /// `δ = F(t, y, y')`.
    fn residual(&mut self) -> Result<(), Fail> {
        self.sys
            .residual(self.t, &self.y, &self.yp, &mut self.delta);
        self.stats.residual_evals += 1;
        if all_finite(&self.delta) {
            Ok(())
        } else {
            Err(Fail::NonFinite("residual"))
        }
    }

    /// Evaluate `G = ∂(E(y) y')/∂y − ∂f/∂y + c_J E(y)` at the predictor and
    /// factor it in place.
    fn form_iteration_matrix(&mut self) -> Result<(), Fail> {
        let sys = self.sys;
        sys.rhs_jacobian(self.t, &self.y, self.lu.matrix_mut());
        sys.leading(&self.y, &mut self.lead);
        if !self.constant_leading {
            sys.leading_jacobian(&self.y, &self.yp, &mut self.lead_jac);
        }
        self.stats.jacobian_evals += 1;
        let cj = self.cj;
        let a = self.lu.matrix_mut().as_mut_slice();
        for (g, e) in a.iter_mut().zip(self.lead.as_slice()) {
            *g = cj * e - *g;
        }
        if !self.constant_leading {
            for (g, l) in a.iter_mut().zip(self.lead_jac.as_slice()) {
                *g += l;
            }
        }
        if !all_finite(a) {
            return Err(Fail::NonFinite("iteration matrix"));
        }
        self.cjold = cj;
        self.s = 100.0;
        self.jac = JacState::Fresh;
        self.stats.factorizations += 1;
        if L::LEAST_SQUARES {
            self.rows.update(&self.lead, self.weights.get());
        }
        self.lu.factor(&self.rows).map_err(|_| Fail::Singular)
    }

    /// Block 3: solve the corrector, re-evaluating the iteration matrix once
    /// if an old one fails.
    pub(super) fn corrector(&mut self) -> Result<(), Fail> {
        loop {
            let stale = self.jac == JacState::Stale;
            match self.newton() {
                Ok(()) => {
                    self.jac = JacState::Stale;
                    return Ok(());
                }
                Err(Fail::Singular) => {
                    self.jac = JacState::Needed;
                    return Err(Fail::Singular);
                }
                Err(_) if stale => self.jac = JacState::Needed,
                Err(fail) => {
                    if self.jac == JacState::Fresh {
                        self.jac = JacState::Stale;
                    }
                    return Err(fail);
                }
            }
        }
    }

    /// Modified Newton iteration on the corrector from the predictor.
    fn newton(&mut self) -> Result<(), Fail> {
        self.predict();
        let pnorm = self.norm(&self.y);
        self.e.fill(0.0);
        self.last_iterations = 0;
        self.residual()?;
        if self.jac == JacState::Needed {
            self.form_iteration_matrix()?;
        }
        let damping = if self.cj != self.cjold {
            2.0 / (1.0 + self.cj / self.cjold)
        } else {
            1.0
        };
        let maxit = if self.cfg.fixed_step {
            MAX_NEWTON_ITERATIONS_FIXED_STEP
        } else {
            MAX_NEWTON_ITERATIONS
        };
        let kappa = if L::LEAST_SQUARES {
            NEWTON_TOL_LEAST_SQUARES
        } else {
            NEWTON_TOL
        };
        let mut monitor = Contraction::new(Rule::Dassl, maxit, kappa, self.s);
        loop {
            if damping != 1.0 {
                for d in &mut self.delta {
                    *d *= damping;
                }
            }
            self.lu.solve(&mut self.delta);
            self.stats.newton_iterations += 1;
            self.last_iterations += 1;
            small::correct(&mut self.y, &mut self.yp, &mut self.e, &self.delta, self.cj);
            // An overflowing update is a diverging iteration, not a fault of
            // the problem: the step is retried smaller.
            let delnrm = self.norm(&self.delta);
            let verdict = monitor.observe(delnrm, 100.0 * EPS * pnorm);
            self.s = monitor.eta;
            match verdict {
                Verdict::Converged => return Ok(()),
                Verdict::Diverged | Verdict::TooSlow { .. } => return Err(Fail::Newton),
                Verdict::Continue => {}
            }
            // Non-finite at an iterate (not at the predictor): divergence.
            self.residual().map_err(|_| Fail::Newton)?;
        }
    }
}

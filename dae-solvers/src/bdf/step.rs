//! The integrator (DASSL's `DDASTP`): the state and workspace of the step
//! beyond the engine's ([`Common`]), the engine's view of it
//! ([`Family`]), and one attempt with the order and step of its retry after
//! a rejected error test (block 6).

use super::corrector::Convergence;
use super::NCOL;
use crate::core::attempt::{Outcome, Policy};
use crate::core::eliminate::Formulation;
use crate::core::matrix::{Corrector, JacState, Matrix, Rows, Structure};
use crate::core::weights::Weights;
use crate::multistep::divided::Divided;
use crate::multistep::newton_norm::NewtonNorm;
use crate::multistep::propagate::Propagation;
use crate::multistep::stale::{self, Stale};
use crate::multistep::{Common, Config, Family, FALL_BACK_AFTER};
use crate::options::{Estimate, Tolerances};
use crate::SolveError;

/// State and workspace of the DASSL step (`N` unknowns, `M ≥ N` rows).
pub(super) struct Integrator<'a, L> {
    /// The engine's state: settings, weights (zero for components out of
    /// the test), step point and step, counters, budgets, the iteration
    /// matrix's state and the carried rate `ρ/(1−ρ)`.
    pub(super) ms: Common,
    /// The formulation.
    pub(super) sys: Formulation<'a>,
    /// `E` does not depend on `y`.
    pub(super) constant_leading: bool,
    /// The Newton norm where it differs from the error test's (index-2
    /// unknowns: in the Newton norm, out of the test, as DASPK).
    pub(super) newton: Option<NewtonNorm>,

    /// Order of the next attempt.
    pub(super) k: usize,
    /// The history: modified divided differences and their coefficients.
    pub(super) hist: Divided<NCOL>,
    /// Leading coefficient `c_J = −α_s/h`.
    pub(super) cj: f64,
    /// `c_J` with which the iteration matrix was formed.
    pub(super) cjold: f64,
    /// Error constant `C_k`.
    pub(super) ck: f64,
    /// The corrector's convergence rule (see [`Convergence`]).
    pub(super) convergence: Convergence,

    /// The corrector's iterate `y` (the predictor `y⁽⁰⁾` at first).
    pub(super) y: Vec<f64>,
    /// Its derivative `y'⁽⁰⁾ + c_J (y − y⁽⁰⁾)`.
    pub(super) yp: Vec<f64>,
    /// Residual (`M`), then Newton update (`N`); scratch of length `N`.
    pub(super) delta: Vec<f64>,
    /// Accumulated corrections `y − y⁽⁰⁾`.
    pub(super) e: Vec<f64>,
    /// Iteration matrix, factored in place.
    pub(super) lu: L,
    /// Row classes of a least-squares corrector.
    pub(super) rows: Rows,
    /// `E(y)`. Like `rhs_jac` and `lead_jac`, compressed on the run's
    /// iteration pattern for a large sparse square system
    /// ([`Structure::of`]), dense otherwise.
    pub(super) lead: Matrix,
    /// `∂f/∂y`.
    pub(super) rhs_jac: Matrix,
    /// `∂(E(y) y')/∂y`.
    pub(super) lead_jac: Matrix,
    /// An error estimate that stops falling with the step ([`Stale`]).
    pub(super) stale: Stale,
    /// DASSL's estimate or the propagated one ([`Propagation`]).
    pub(super) estimate: Propagation,
}

impl<L: Corrector> Family for Integrator<'_, L> {
    fn ms(&self) -> &Common {
        &self.ms
    }
    fn ms_mut(&mut self) -> &mut Common {
        &mut self.ms
    }
    fn value(&self) -> &[f64] {
        self.hist.col(0)
    }
    fn dense_at(&self, tau: f64, out: &mut [f64]) {
        // DDATRP's polynomial through the last `kold + 1` values.
        self.hist.interpolate(self.ms.t, tau, out)
    }
    fn begin_step(&mut self) {
        self.ms.weights.update(self.hist.col(0));
        self.stale.begin_step();
    }
    fn step_changed(&mut self, h_before: f64) {
        // Before the first step `φ_2 = h y'₀` follows the step.
        if self.hist.kold == 0 && self.ms.h != h_before {
            self.hist.rescale_first_step(h_before, self.ms.h);
        }
    }
    #[inline(always)]
    fn attempt_once(&mut self) -> Result<Outcome, SolveError> {
        self.attempt()
    }
    fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        Integrator::start(self, t0, y0, yp0, h)
    }
    fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64) {
        Integrator::start_from_history(self, t, values, h)
    }
}

impl<'a, L: Corrector> Integrator<'a, L> {
    /// Allocate every buffer of the step loop.
    pub(super) fn new(
        sys: Formulation<'a>,
        tol: &Tolerances,
        [in_test, in_newton]: [&[bool]; 2],
        cfg: Config,
        estimate: Estimate,
    ) -> Self {
        let info = sys.info();
        let (m, n) = (info.equations(), info.unknowns());
        let structure = if L::LEAST_SQUARES {
            None
        } else {
            Structure::of(&*sys)
        };
        let matrix = || Matrix::new(m, n, structure.as_ref());
        let weights = Weights::new(tol, |_| 1.0, in_test.to_vec(), vec![0; n]);
        Integrator {
            ms: Common::new(cfg, n, weights, Policy::DASSL),
            newton: NewtonNorm::of(tol, info, in_test, in_newton),
            sys: sys.clone(),
            constant_leading: info.constant_leading,
            k: 1,
            hist: Divided::new(n),
            cj: 0.0,
            cjold: 0.0,
            ck: 0.0,
            convergence: Convergence::of::<L>(info),
            y: vec![0.0; n],
            yp: vec![0.0; n],
            delta: vec![0.0; m],
            e: vec![0.0; n],
            lu: L::with_blocks(m, n, sys.blocks()),
            rows: Rows::new(info),
            lead: matrix(),
            rhs_jac: matrix(),
            lead_jac: matrix(),
            stale: Stale::default(),
            estimate: Propagation::new(estimate, info, m),
        }
    }

    /// One attempt from `t` with `h` and order `k` (DDASTP's blocks 1–5;
    /// block 6 after a failure: the order and step of the retry).
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        let t_old = self.ms.t;
        self.set_coefficients();
        self.ms.t = self.ms.t_next();
        let failure = match self.corrector() {
            Ok(()) if self.ms.cfg.fixed_step => {
                self.accept(None);
                if L::LEAST_SQUARES {
                    // The point a least-squares corrector converges to
                    // depends on its matrix: with constant steps a matrix
                    // kept for many steps would bias every step the same
                    // way. A fresh one each step.
                    self.ms.jac = JacState::Needed;
                }
                return Ok(Outcome::Accepted);
            }
            Ok(()) => {
                let test = self.error_test();
                if test.err <= 1.0 {
                    self.accept(Some(test));
                    self.stale.accepted();
                    return Ok(Outcome::Accepted);
                }
                if self.stale.restart_due(self.ms.h, test.err, self.k) {
                    let (sys, y) = (self.sys.clone(), self.y.clone());
                    stale::restart(self, &*sys, self.ms.t, &y)?;
                    return Ok(Outcome::Accepted);
                }
                Err(test)
            }
            Err(failure) => Ok(failure),
        };

        // Block 6: the step failed.
        self.ms.t = t_old;
        self.hist.restore(self.ms.h, self.k);
        Ok(match failure {
            Ok(failure) => self.ms.failed(failure),
            Err(test) => {
                let nef = self.ms.error_test_failed();
                let stalled = self.stale.fall_back_due(self.ms.h, test.err, self.k, nef);
                let h = if stalled || nef >= FALL_BACK_AFTER {
                    self.ms.fall_back(&mut self.k)
                } else if nef == 1 {
                    self.k = test.knew;
                    let r: f64 = 0.9 * (2.0 * test.est + 1e-4).powf(-1.0 / (self.k + 1) as f64);
                    self.ms.h * r.clamp(0.25, 0.9)
                } else {
                    self.k = test.knew;
                    0.25 * self.ms.h
                };
                Outcome::ErrorTest { h }
            }
        })
    }
}

//! The integrator and its step loop (DASSL's `DDASTP`): the settings of a
//! run, the state and workspace of the step, the driver's view of it, and
//! one accepted step with its retries after failed attempts (block 6).

use super::corrector::JacState;
use super::NCOL;
use crate::core::attempt::{self, Attempts, Outcome, Policy, Retry, Steps};
use crate::core::driver::Method;
use crate::core::eliminate::Formulation;
use crate::core::matrix::{Corrector, Matrix, Rows, Structure};
use crate::core::weights::Weights;
use crate::options::Tolerances;
use crate::{SolveError, Stats};

/// Settings of one integrator (the order in this method's count).
pub(super) use crate::core::control::StepConfig as Config;

/// State and workspace of the DASSL step (`N` unknowns, `M ≥ N` rows).
pub(super) struct Integrator<'a, L> {
    /// The formulation.
    pub(super) sys: Formulation<'a>,
    /// Settings of this run.
    pub(super) cfg: Config,
    /// Unknowns `N`.
    pub(super) n: usize,
    /// `E` does not depend on `y`.
    pub(super) constant_leading: bool,
    /// Error weights (zero for components out of the test).
    pub(super) weights: Weights,

    /// Current time `t_n` (after a step: `t_{n+1}`).
    pub(super) t: f64,
    /// Step size of the next attempt.
    pub(super) h: f64,
    /// Step size of the last accepted step.
    pub(super) hold: f64,
    /// Order of the next attempt.
    pub(super) k: usize,
    /// Order of the last accepted step (0 before the first).
    pub(super) kold: usize,
    /// Number of steps taken with the current `h` and `k` (capped).
    pub(super) ns: usize,
    /// Initial phase: raise order and double `h` after every step.
    pub(super) ramp: bool,
    /// The current step reaches `t_end`: snap `t` to it.
    pub(super) last: bool,

    /// `ψ_i = t_{n+1} − t_{n+1−i}`.
    pub(super) psi: [f64; NCOL],
    /// `α_i = h/ψ_i`.
    pub(super) alpha: [f64; NCOL],
    /// `β_i = Π_{j<i} ψ_j(n+1)/ψ_j(n)`, the rescaling `φ → φ*`.
    pub(super) beta: [f64; NCOL],
    /// `γ_i` of the predicted derivative.
    pub(super) gamma: [f64; NCOL],
    /// `σ_i` of the error terms.
    pub(super) sigma: [f64; NCOL],
    /// Leading coefficient `c_J = −α_s/h`.
    pub(super) cj: f64,
    /// `c_J` with which the iteration matrix was formed.
    pub(super) cjold: f64,
    /// Error constant `C_k`.
    pub(super) ck: f64,
    /// Newton rate factor `ρ/(1−ρ)` ([`super::corrector::UNKNOWN_RATE`] when unknown).
    pub(super) s: f64,
    /// The corrector's convergence rule (see [`super::corrector::Convergence`]).
    pub(super) convergence: super::corrector::Convergence,
    /// Whether the iteration matrix is current.
    pub(super) jac: JacState,
    /// Newton iterations of the last attempt.
    pub(super) last_iterations: usize,

    /// History `φ_1 … φ_{NCOL}`, column `j` at `phi[j n .. (j+1) n]`.
    pub(super) phi: Vec<f64>,
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

    /// Work counters (of this run, and of the work before it that it was
    /// started with).
    pub(super) stats: Stats,
    /// The attempt loop's state: budgets, limits, the end rule.
    pub(super) steps: Steps,
    /// Error-test failures on this step.
    pub(super) error_failures: usize,
}

impl<L: Corrector> Method for Integrator<'_, L> {
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.phi[..self.n]
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        self.interpolate(tau, out)
    }
    fn dense_degree(&self) -> usize {
        // DDATRP's polynomial through the last `kold + 1` values.
        self.cfg.max_order
    }
    fn finished(&self) -> bool {
        self.t >= self.cfg.t_end
    }
    fn step(&mut self) -> Result<(), SolveError> {
        self.weights.update(&self.phi[..self.n]);
        self.error_failures = 0;
        attempt::step(self)
    }
    fn stats(&self) -> Stats {
        self.stats
    }
}

impl<L: Corrector> Attempts for Integrator<'_, L> {
    fn steps(&mut self) -> &mut Steps {
        &mut self.steps
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.stats
    }
    fn point(&self) -> (f64, f64) {
        (self.t, self.h)
    }
    fn set_step(&mut self, h: f64, last: bool) {
        let h_before = self.h;
        self.h = h;
        self.last = last;
        // Before the first step `φ_2 = h y'₀` follows the step.
        if self.kold == 0 && h != h_before {
            self.rescale_first_step(h_before);
        }
    }
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        Ok(Integrator::attempt(self))
    }
}

impl<'a, L: Corrector> Integrator<'a, L> {
    /// Allocate every buffer of the step loop.
    pub(super) fn new(
        sys: Formulation<'a>,
        tol: &Tolerances,
        in_test: &[bool],
        cfg: Config,
    ) -> Self {
        let info = sys.info();
        let (m, n) = (info.equations(), info.unknowns());
        let structure = if L::LEAST_SQUARES {
            None
        } else {
            Structure::of(&*sys)
        };
        let matrix = || Matrix::new(m, n, structure.as_ref());
        Integrator {
            sys: sys.clone(),
            cfg,
            n,
            constant_leading: info.constant_leading,
            weights: Weights::new(tol, |_| 1.0, in_test.to_vec(), vec![0; n]),
            t: 0.0,
            h: 0.0,
            hold: 0.0,
            k: 1,
            kold: 0,
            ns: 0,
            ramp: true,
            last: false,
            psi: [0.0; NCOL],
            alpha: [0.0; NCOL],
            beta: [0.0; NCOL],
            gamma: [0.0; NCOL],
            sigma: [0.0; NCOL],
            cj: 0.0,
            cjold: 0.0,
            ck: 0.0,
            s: super::corrector::UNKNOWN_RATE,
            convergence: super::corrector::Convergence::of::<L>(info),
            jac: JacState::Needed,
            last_iterations: 0,
            phi: vec![0.0; n * NCOL],
            y: vec![0.0; n],
            yp: vec![0.0; n],
            delta: vec![0.0; m],
            e: vec![0.0; n],
            lu: L::with_blocks(m, n, sys.blocks()),
            rows: Rows::new(info),
            lead: matrix(),
            rhs_jac: matrix(),
            lead_jac: matrix(),
            stats: Stats::default(),
            steps: Steps::new(
                Policy::DASSL,
                cfg.max_steps,
                cfg.t_end,
                cfg.span,
                cfg.hmax,
                cfg.fixed_step,
            ),
            error_failures: 0,
        }
    }

    /// DASSL's initial step: `0.001·(t_end − t₀)`, reduced so that
    /// `h ‖y'₀‖ ≤ 0.5`, and at most `h_max`.
    pub(super) fn initial_step(&mut self, y0: &[f64], yp0: &[f64]) -> f64 {
        self.weights.update(y0);
        let mut h = 0.001 * self.cfg.span;
        let ypnorm = self.norm(yp0);
        if ypnorm > 0.5 / h {
            h = 0.5 / ypnorm;
        }
        h.min(self.cfg.hmax)
    }

    /// The weighted RMS norm over the components in the test.
    pub(super) fn norm(&self, v: &[f64]) -> f64 {
        self.weights.norm(v)
    }

    /// One attempt from `t` with `h` and order `k` (DDASTP's blocks 1–5;
    /// block 6 after a failure: the order and step of the retry).
    fn attempt(&mut self) -> Outcome {
        let t_old = self.t;
        self.set_coefficients();
        self.t = if self.last {
            self.cfg.t_end
        } else {
            t_old + self.h
        };
        let failure = match self.corrector() {
            Ok(()) if self.cfg.fixed_step => {
                self.accept(None);
                if L::LEAST_SQUARES {
                    // The point a least-squares corrector converges to
                    // depends on its matrix: with constant steps a matrix
                    // kept for many steps would bias every step the same
                    // way. A fresh one each step.
                    self.jac = JacState::Needed;
                }
                return Outcome::Accepted;
            }
            Ok(()) => {
                let test = self.error_test();
                if test.err <= 1.0 {
                    self.accept(Some(test));
                    return Outcome::Accepted;
                }
                Err(test)
            }
            Err(failure) => Ok(failure),
        };

        // Block 6: the step failed.
        self.restore(t_old);
        self.ramp = false;
        match failure {
            Ok(failure) => Outcome::Failed {
                failure,
                retry: Retry::Policy,
                iterations: self.last_iterations,
            },
            Err(test) => {
                self.error_failures += 1;
                let nef = self.error_failures;
                let h = if nef == 1 {
                    self.k = test.knew;
                    let r: f64 = 0.9 * (2.0 * test.est + 1e-4).powf(-1.0 / (self.k + 1) as f64);
                    self.h * r.clamp(0.25, 0.9)
                } else {
                    // From the third failure on, order one, as DASSL: at
                    // higher orders an algebraic component left off its
                    // constraint by the Newton tolerance is an error
                    // estimate that does not shrink with h. With a fixed
                    // order it is raised again after the step.
                    self.k = if nef == 2 { test.knew } else { 1 };
                    0.25 * self.h
                };
                Outcome::ErrorTest { h }
            }
        }
    }
}

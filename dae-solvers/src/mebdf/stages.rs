//! The three stages of a step and their simplified Newton iterations, all
//! with the one iteration matrix `E/(hβ) − J`.
//!
//! With the back values `y_{n+1−j}` and `k = max(p − 1, 1)`:
//!
//! 1. `ȳ_{n+1}` from BDF-`k`: `E (ȳ_{n+1} + c_1) = hβ f(t_{n+1}, ȳ_{n+1})`,
//!    `c_1 = Σ_{j≥1} α_j y_{n+1−j}` (for `p = 1` this is the step);
//! 2. `ȳ_{n+2}` from BDF-`k` one step further, with `ȳ_{n+1}` as the
//!    newest value: `c_2 = α_1 ȳ_{n+1} + Σ_{j≥2} α_j y_{n+2−j}`;
//! 3. `y_{n+1}` from EBDF-`k` with `b̂_0 f_{n+1}` split as
//!    `β f(y_{n+1}) + (b̂_0 − β) f̄_{n+1}` (Cash's modification): since
//!    `hβ f̄_{n+i}` is `E d_i`, `d_i = ȳ_{n+i} + c_i`, this is again
//!    `E (y + c_3) = hβ f(t_{n+1}, y)` with
//!    `c_3 = Σ_{j≥1} â_j y_{n+1−j} − (b̂_0 − β)/β d_1 − b̂_1/β d_2`.
//!
//! Every stage is `F(t, y, (y + c)/(hβ)) = 0`, solved from its predictor
//! with the matrix `E/(hβ) − J` (`J = ∂f/∂y`, evaluated at the first
//! predictor of the step when it is due and kept over steps until a Newton
//! iteration fails with it; refactored whenever `hβ` changes). Increments
//! are measured in the index-scaled norm of `core::weights`; convergence by
//! DASSL's rate estimate (`core::newton`).

use super::step::Integrator;
use crate::core::control::Failure;
use crate::core::eval;
use crate::core::matrix::JacState;
use crate::core::newton::{Contraction, Rule};
use crate::multistep::corrector::{self, Iteration};
use crate::multistep::{Common, UNKNOWN_RATE};

/// Newton iterations per stage.
const MAX_ITER: usize = 5;
/// Convergence `η ‖Δ‖ ≤ KAPPA`: tighter than DASSL's 0.33, since the errors
/// of the first two stages enter the third through `d_1`, `d_2`.
const KAPPA: f64 = 0.01;

/// Increments of at most this weighted norm that have stopped contracting
/// (`θ > 0.9`) are the round-off of the residual and the solve: converged,
/// not diverging. DASSL's rule has no such floor. Measured on Andrews'
/// squeezer in rcd0 at tol 1e-9: the stage increments stagnate at
/// 1e-4 … 1e-3, and without the floor every step size was declared
/// divergent until `newton_failure`; with it the run at 1e-9 reaches the
/// end (6.5 digits). At 1e-10 the increments of `gaa` stagnate at
/// 0.02–0.27 from h = 1e-10 down to 3e-17 (EXTREMES.md §5, lit10): with
/// the floor at 0.01 (its value until lit10) the run walked down to
/// `newton_failure` at h = 2.7e-17; at 0.3, RADAU5's
/// ([`crate::core::newton::ROUND_OFF_FLOOR`]), it reaches the end (7.3
/// digits, 2 095 steps).
const ROUND_OFF_FLOOR: f64 = 0.3;

/// Smallest rate factor carried into a new iteration: a first increment is
/// accepted alone only when it is below `KAPPA/ETA_MIN`.
const ETA_MIN: f64 = 0.05;

/// `c += Σ_j coef[j] · back_j`, `back_j` the `j`-th column of `back` (the
/// back values `y_n, y_{n−1}, …`).
fn accumulate(c: &mut [f64], coef: &[f64], back: &[f64]) {
    for (a, col) in coef.iter().zip(back.chunks_exact(c.len())) {
        for (ci, b) in c.iter_mut().zip(col) {
            *ci += a * b;
        }
    }
}

impl Integrator<'_> {
    /// The step number `k` of the formulas at order `p`.
    pub(super) fn steps_of(p: usize) -> usize {
        p.saturating_sub(1).max(1)
    }

    /// Solve the three stages of the current attempt from `t` to `t + h`
    /// (one for `p = 1`); the engine retries them once with a fresh `J`
    /// when an old one fails (MEBDF's reuse, [`corrector::solve_reusing`]).
    pub(super) fn stages(&mut self) -> Result<(), Failure> {
        let n = self.ms.n;
        let p = self.p;
        let k = Self::steps_of(p);
        let h = self.ms.h;
        let t1 = self.ms.t_next();
        let t2 = t1 + h;
        let beta = self.coef.bdf_beta[k];
        let hb = h * beta;
        for j in 0..k {
            self.hist
                .eval(-(j as f64), j, &mut self.back[j * n..(j + 1) * n]);
        }
        let alpha = self.coef.bdf_alpha[k];

        // Stage 1.
        self.c.fill(0.0);
        accumulate(&mut self.c, &alpha[1..=k], &self.back);
        self.hist.eval(1.0, p, &mut self.ypred);
        self.stage[0].copy_from_slice(&self.ypred);
        self.ensure_matrix(t1, hb)?;
        self.iterate(t1, hb, 0)?;
        if p == 1 {
            return Ok(());
        }
        self.known_part_out(0);

        // Stage 2: ȳ_{n+1} is the newest value (stage 3 starts from it too).
        let [y1, y2, y3] = &mut self.stage;
        for (c, y) in self.c.iter_mut().zip(&*y1) {
            *c = alpha[1] * y;
        }
        accumulate(&mut self.c, &alpha[2..=k], &self.back);
        self.hist.eval(2.0, p, y2);
        for ((y2, y1), yp) in y2.iter_mut().zip(&*y1).zip(&self.ypred) {
            *y2 += y1 - yp;
        }
        y3.copy_from_slice(y1);
        self.iterate(t2, hb, 1)?;
        self.known_part_out(1);

        // Stage 3: the modified extended formula.
        let a = self.coef.ebdf_a[k];
        let w1 = (self.coef.ebdf_b0[k] - beta) / beta;
        let w2 = self.coef.ebdf_b1[k] / beta;
        let [d1, d2] = &self.d;
        for ((c, d1), d2) in self.c.iter_mut().zip(d1).zip(d2) {
            *c = -w1 * d1 - w2 * d2;
        }
        accumulate(&mut self.c, &a[1..=k], &self.back);
        self.iterate(t1, hb, 2)
    }

    /// `d_i = ȳ_{n+i} + c_i` after stage `i + 1` (`E d_i = hβ f̄_{n+i}`).
    fn known_part_out(&mut self, i: usize) {
        for ((d, y), c) in self.d[i].iter_mut().zip(&self.stage[i]).zip(&self.c) {
            *d = y + c;
        }
    }

    /// Evaluate `J` at the predictor when due, and factor `E/(hβ) − J`
    /// when `J` or `hβ` changed.
    fn ensure_matrix(&mut self, t: f64, hb: f64) -> Result<(), Failure> {
        if self.ms.jac == JacState::Needed {
            // A non-finite `J` is found in the matrix below.
            self.matrix
                .jacobian(&*self.sys, &mut self.ms.stats, t, &self.stage[0]);
            self.ms.jac = JacState::Fresh;
        }
        if self.matrix.factor(1.0 / hb, 1.0, &mut self.ms.stats)? {
            self.ms.rate = UNKNOWN_RATE;
        }
        Ok(())
    }

    /// `δ = F(t, y, y')` for the iterate `y` of the stage being solved,
    /// counted.
    fn evaluate_residual(&mut self) -> Result<(), Failure> {
        let (s, t, _) = self.solving;
        let point = (t, &self.stage[s][..], &self.yp[..]);
        eval::residual(&*self.sys, &mut self.ms.stats, point, &mut self.delta)
    }

    /// Simplified Newton iteration on `F(t, y, (y + c)/(hβ)) = 0` from the
    /// current value `y` of stage `s`.
    fn iterate(&mut self, t: f64, hb: f64, s: usize) -> Result<(), Failure> {
        let inv = 1.0 / hb;
        self.solving = (s, t, inv);
        for ((yp, yi), c) in self.yp.iter_mut().zip(&self.stage[s]).zip(&self.c) {
            *yp = (yi + c) * inv;
        }
        self.ms.last_iterations = 0;
        self.evaluate_residual()?;
        let tiny = 100.0 * f64::EPSILON * self.ms.weights.norm(&self.stage[s]);
        let maxit = corrector::max_iterations(&self.ms, MAX_ITER);
        let mut monitor = Contraction::new(Rule::Dassl, maxit, KAPPA, self.ms.rate.max(ETA_MIN));
        monitor.floor = ROUND_OFF_FLOOR;
        corrector::iterate(self, monitor, tiny)
    }
}

/// The Newton iteration of the stage being solved
/// ([`Integrator::solving`]).
impl Iteration for Integrator<'_> {
    fn ms(&mut self) -> &mut Common {
        &mut self.ms
    }
    fn update(&mut self) -> f64 {
        let (s, _, inv) = self.solving;
        self.matrix.solve(&mut self.delta);
        let y = &mut self.stage[s];
        for ((yi, yp), d) in y.iter_mut().zip(self.yp.iter_mut()).zip(&self.delta) {
            *yi -= d;
            *yp -= d * inv;
        }
        self.ms.weights.norm(&self.delta)
    }
    fn residual(&mut self) -> bool {
        self.evaluate_residual().is_ok()
    }
}

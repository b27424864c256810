//! The history of the step: the modified divided differences `φ` and the
//! coefficients `ψ, α, β, γ, σ` over them — starting them from `y₀, y'₀` or
//! from equally spaced values, rescaling them for the next step (block 1)
//! and undoing that after a failure, the predictor (block 2), their update
//! after an accepted step, and dense output.

use super::corrector::JacState;
use super::step::Integrator;
use crate::core::matrix::Corrector;
use crate::linalg::small;

/// Re-evaluate the iteration matrix when `c_J/c_J^old` leaves
/// `[(1−XRATE)/(1+XRATE), (1+XRATE)/(1−XRATE)]`.
const XRATE: f64 = 0.25;

impl<L: Corrector> Integrator<'_, L> {
    /// Start at `(t0, y0, y'0)` with order one and step `h`:
    /// `φ_1 = y₀`, `φ_2 = h y'₀`, `ψ_1 = h`.
    pub(super) fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        let n = self.n;
        self.t = t0;
        self.h = h;
        self.k = 1;
        self.kold = 0;
        self.hold = 0.0;
        self.ns = 0;
        self.ramp = !self.cfg.fixed_step;
        self.psi[0] = h;
        self.cj = 1.0 / h;
        self.cjold = self.cj;
        self.s = 100.0;
        self.jac = JacState::Needed;
        self.phi.fill(0.0);
        self.phi[..n].copy_from_slice(y0);
        for (p, v) in self.phi[n..2 * n].iter_mut().zip(yp0) {
            *p = h * v;
        }
    }

    /// Start a constant-step run of order `k = values.len()` at `t` from the
    /// values at `t − (k−1)h, …, t` (oldest first): with equal spacing the
    /// modified divided differences are backward differences,
    /// `φ_{i+1} = ∇ⁱ y`. `φ_{k+1} = 0`: the first predictor has degree
    /// `k−1`, which leaves the corrector — the classical BDF-`k` — unchanged.
    pub(super) fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64) {
        let n = self.n;
        let k = values.len();
        self.t = t;
        self.h = h;
        self.hold = h;
        self.k = k;
        self.kold = k;
        self.ns = 0;
        self.ramp = false;
        for (i, p) in self.psi.iter_mut().enumerate() {
            *p = (i + 1) as f64 * h;
        }
        self.cj = 1.0 / h;
        self.cjold = self.cj;
        self.s = 100.0;
        self.jac = JacState::Needed;
        self.phi.fill(0.0);
        // Difference table: after pass i, work[j] holds ∇ⁱ y at the j-th
        // point; store ∇ⁱ y at the newest point in φ_{i+1}.
        let mut work: Vec<Vec<f64>> = values.iter().map(|v| v.to_vec()).collect();
        for i in 0..k {
            self.phi[i * n..(i + 1) * n].copy_from_slice(&work[k - 1]);
            for j in (i + 1..k).rev() {
                let (lo, hi) = work.split_at_mut(j);
                for (a, b) in hi[0].iter_mut().zip(&lo[j - 1]) {
                    *a -= b;
                }
            }
        }
    }

    /// Before the first step `φ_2 = h y'₀` and `ψ_1 = h` follow `h`.
    pub(super) fn rescale_first_step(&mut self, h_prev: f64) {
        let n = self.n;
        let r = self.h / h_prev;
        self.psi[0] = self.h;
        for p in &mut self.phi[n..2 * n] {
            *p *= r;
        }
    }

    /// Block 1: coefficients `ψ, α, β, γ, σ` of the new step, `c_J`, `C_k`,
    /// and `φ → φ*`. They are recomputed unless `h` and `k` have been
    /// constant for `k+1` steps.
    pub(super) fn set_coefficients(&mut self) {
        let k = self.k;
        let h = self.h;
        if h != self.hold || k != self.kold {
            self.ns = 0;
        }
        self.ns = (self.ns + 1).min(self.kold + 2);
        if k + 1 >= self.ns {
            self.beta[0] = 1.0;
            self.alpha[0] = 1.0;
            self.gamma[0] = 0.0;
            self.sigma[0] = 1.0;
            let mut temp1 = h;
            for i in 1..=k {
                let temp2 = self.psi[i - 1];
                self.psi[i - 1] = temp1;
                self.beta[i] = self.beta[i - 1] * self.psi[i - 1] / temp2;
                temp1 = temp2 + h;
                self.alpha[i] = h / temp1;
                self.sigma[i] = i as f64 * self.sigma[i - 1] * self.alpha[i];
                self.gamma[i] = self.gamma[i - 1] + self.alpha[i - 1] / h;
            }
            self.psi[k] = temp1;
        }
        let mut alphas = 0.0;
        let mut alpha0 = 0.0;
        for i in 0..k {
            alphas -= 1.0 / (i + 1) as f64;
            alpha0 -= self.alpha[i];
        }
        let cjlast = self.cj;
        self.cj = -alphas / h;
        self.ck = (self.alpha[k] + alphas - alpha0).abs().max(self.alpha[k]);

        // A new iteration matrix when c_J has moved too far.
        let ratio = self.cj / self.cjold;
        let lo = (1.0 - XRATE) / (1.0 + XRATE);
        if !(lo..=1.0 / lo).contains(&ratio) {
            self.jac = JacState::Needed;
        }
        if self.cj != cjlast {
            self.s = 100.0;
        }

        // φ → φ*.
        let n = self.n;
        if self.ns <= k {
            for j in self.ns..=k {
                small::scale(&mut self.phi[j * n..(j + 1) * n], self.beta[j]);
            }
        }
    }

    /// Undo block 1 after a failed attempt.
    pub(super) fn restore(&mut self, t_old: f64) {
        let n = self.n;
        let k = self.k;
        self.t = t_old;
        if self.ns <= k {
            for j in self.ns..=k {
                small::scale(&mut self.phi[j * n..(j + 1) * n], 1.0 / self.beta[j]);
            }
        }
        for i in 0..k {
            self.psi[i] = self.psi[i + 1] - self.h;
        }
    }

    /// Block 2: predictor `y⁽⁰⁾ = Σ φ*_i`, `y'⁽⁰⁾ = Σ γ_i φ*_i`.
    pub(super) fn predict(&mut self) {
        small::predict(&self.phi, &self.gamma, self.k, &mut self.y, &mut self.yp);
    }

    /// After a step of order `k` accepted with corrections `e`: the
    /// differences at `t_{n+1}`.
    pub(super) fn update_differences(&mut self, k: usize) {
        let n = self.n;
        // φ_{k+2} = e (for the order-raise test), φ_{k+1} += e, then
        // φ_i += φ_{i+1} for i = k … 1: the differences at t_{n+1}.
        if k < self.cfg.max_order {
            self.phi[(k + 1) * n..(k + 2) * n].copy_from_slice(&self.e);
        }
        small::add_assign(&mut self.phi[k * n..(k + 1) * n], &self.e);
        for j in (0..k).rev() {
            let (lo, hi) = self.phi.split_at_mut((j + 1) * n);
            small::add_assign(&mut lo[j * n..], &hi[..n]);
        }
    }

    /// Dense output (DDATRP): the interpolating polynomial of the last step,
    /// `y(t) = Σ_{i=1}^{k+1} c_i φ_i`, `c_1 = 1`,
    /// `c_{i+1} = c_i (t − t_{n+1} + ψ_{i−1})/ψ_i` (`ψ_0 = 0`).
    pub(super) fn interpolate(&self, tout: f64, out: &mut [f64]) {
        let n = self.n;
        out.copy_from_slice(&self.phi[..n]);
        let dt = tout - self.t;
        let mut c = 1.0;
        let mut gamma = dt / self.psi[0];
        for j in 1..=self.kold {
            c *= gamma;
            gamma = (dt + self.psi[j - 1]) / self.psi[j];
            for (o, p) in out.iter_mut().zip(&self.phi[j * n..(j + 1) * n]) {
                *o += c * p;
            }
        }
    }
}

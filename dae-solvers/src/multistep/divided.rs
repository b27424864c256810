//! Modified divided differences on a variable grid, DASSL's history (BCP
//! ch. 5 — Brenan, Campbell & Petzold, *Numerical Solution of
//! Initial-Value Problems in Differential-Algebraic Equations*, SIAM 1996):
//! their start from `y₀, y'₀` or from equally spaced values, the
//! coefficients of a step and the rescaling `φ → φ*` (DDASTP's block 1)
//! and its undoing after a failure, the predictor (block 2), the update
//! after an accepted step, and dense output (DDATRP).
//!
//! At step `n+1` of size `h = t_{n+1} − t_n` and order `k` the solution is
//! represented by
//!
//! ```text
//!     φ_1(n) = y_n,   φ_{i+1}(n) = ψ_1(n)⋯ψ_i(n) · y[t_n, …, t_{n−i}],
//!     ψ_i(n+1) = t_{n+1} − t_{n+1−i},
//! ```
//!
//! rescaled for the new step to `φ*_i(n) = β_i(n+1) φ_i(n)` with
//! `β_i(n+1) = Π_{j<i} ψ_j(n+1)/ψ_j(n)`. The predictor is the polynomial
//! through the last `k+1` solution values,
//!
//! ```text
//!     y⁽⁰⁾ = Σ_{i=1}^{k+1} φ*_i(n),      y'⁽⁰⁾ = Σ_{i=2}^{k+1} γ_i(n+1) φ*_i(n),
//!     γ_1 = 0,  γ_i = γ_{i−1} + α_{i−1}/h,   α_i = h/ψ_i(n+1),
//! ```
//!
//! and between steps the solution is the polynomial of degree `k` through
//! the last `k+1` values, `y(t) = Σ_{i=1}^{k+1} c_i(t) φ_i(n+1)`.

use super::backward;
use crate::linalg::small;

/// The differences `φ_1 … φ_{NCOL}` and their coefficients, for orders up
/// to `NCOL − 2`.
pub(crate) struct Divided<const NCOL: usize> {
    n: usize,
    /// `φ_1 … φ_{NCOL}`, column `j` at `phi[j n .. (j+1) n]`.
    pub(crate) phi: Vec<f64>,
    /// `ψ_i = t_{n+1} − t_{n+1−i}`.
    pub(crate) psi: [f64; NCOL],
    /// `α_i = h/ψ_i`.
    pub(crate) alpha: [f64; NCOL],
    /// `β_i = Π_{j<i} ψ_j(n+1)/ψ_j(n)`, the rescaling `φ → φ*`.
    pub(crate) beta: [f64; NCOL],
    /// `γ_i` of the predicted derivative.
    pub(crate) gamma: [f64; NCOL],
    /// `σ_i` of the error terms.
    pub(crate) sigma: [f64; NCOL],
    /// Number of steps taken with the current `h` and `k` (capped).
    pub(crate) ns: usize,
    /// Step size of the last accepted step.
    pub(crate) hold: f64,
    /// Order of the last accepted step (0 before the first).
    pub(crate) kold: usize,
}

impl<const NCOL: usize> Divided<NCOL> {
    /// Storage for `n` unknowns.
    pub(crate) fn new(n: usize) -> Self {
        Divided {
            n,
            phi: vec![0.0; n * NCOL],
            psi: [0.0; NCOL],
            alpha: [0.0; NCOL],
            beta: [0.0; NCOL],
            gamma: [0.0; NCOL],
            sigma: [0.0; NCOL],
            ns: 0,
            hold: 0.0,
            kold: 0,
        }
    }

    /// Column `j` (`φ_{j+1}`).
    pub(crate) fn col(&self, j: usize) -> &[f64] {
        &self.phi[j * self.n..(j + 1) * self.n]
    }

    /// Start from `(y0, y'0)` with order one and step `h`:
    /// `φ_1 = y₀`, `φ_2 = h y'₀`, `ψ_1 = h`.
    pub(crate) fn start(&mut self, y0: &[f64], yp0: &[f64], h: f64) {
        let n = self.n;
        self.kold = 0;
        self.hold = 0.0;
        self.ns = 0;
        self.psi[0] = h;
        self.phi.fill(0.0);
        self.phi[..n].copy_from_slice(y0);
        for (p, v) in self.phi[n..2 * n].iter_mut().zip(yp0) {
            *p = h * v;
        }
    }

    /// Start at order `k = values.len()` from the values at
    /// `t − (k−1)h, …, t` (oldest first): with equal spacing the modified
    /// divided differences are backward differences, `φ_{i+1} = ∇ⁱ y`.
    /// `φ_{k+1} = 0`: the first predictor has degree `k−1`, which leaves a
    /// constant-step corrector of order `k` unchanged.
    pub(crate) fn start_from_values(&mut self, values: &[&[f64]], h: f64) {
        let k = values.len();
        self.hold = h;
        self.kold = k;
        self.ns = 0;
        for (i, p) in self.psi.iter_mut().enumerate() {
            *p = (i + 1) as f64 * h;
        }
        let mut work: Vec<f64> = values
            .iter()
            .rev()
            .flat_map(|v| v.iter().copied())
            .collect();
        backward::differences(&mut work, k - 1, self.n, &mut self.phi);
    }

    /// Before the first step `φ_2 = h y'₀` and `ψ_1 = h` follow the step
    /// `h` (from `h_prev`).
    pub(crate) fn rescale_first_step(&mut self, h_prev: f64, h: f64) {
        let n = self.n;
        let r = h / h_prev;
        self.psi[0] = h;
        for p in &mut self.phi[n..2 * n] {
            *p *= r;
        }
    }

    /// Block 1: coefficients `ψ, α, β, γ, σ` of the step `h` at order `k`,
    /// and `φ → φ*`. They are recomputed unless `h` and `k` have been
    /// constant for `k+1` steps. Returns `α_s = −Σ_{j=1}^{k} 1/j` and
    /// `α⁰ = −Σ_{i=1}^{k} α_i`.
    #[inline(always)]
    pub(crate) fn set_coefficients(&mut self, h: f64, k: usize) -> (f64, f64) {
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
        // φ → φ*.
        let n = self.n;
        if self.ns <= k {
            for j in self.ns..=k {
                small::scale(&mut self.phi[j * n..(j + 1) * n], self.beta[j]);
            }
        }
        (alphas, alpha0)
    }

    /// Undo block 1 after a failed attempt with step `h` at order `k`.
    pub(crate) fn restore(&mut self, h: f64, k: usize) {
        let n = self.n;
        if self.ns <= k {
            for j in self.ns..=k {
                small::scale(&mut self.phi[j * n..(j + 1) * n], 1.0 / self.beta[j]);
            }
        }
        for i in 0..k {
            self.psi[i] = self.psi[i + 1] - h;
        }
    }

    /// Block 2: predictor `y⁽⁰⁾ = Σ φ*_i`, `y'⁽⁰⁾ = Σ γ_i φ*_i` at order `k`.
    pub(crate) fn predict(&self, k: usize, y: &mut [f64], yp: &mut [f64]) {
        small::predict(&self.phi, &self.gamma, k, y, yp);
    }

    /// After a step of order `k` accepted with corrections `e`: the
    /// differences at `t_{n+1}` (`φ_{k+2} = e` for the order-raise test
    /// when `k < max_order`).
    #[inline(always)]
    pub(crate) fn update(&mut self, k: usize, e: &[f64], max_order: usize) {
        let n = self.n;
        // φ_{k+2} = e, φ_{k+1} += e, then φ_i += φ_{i+1} for i = k … 1.
        if k < max_order {
            self.phi[(k + 1) * n..(k + 2) * n].copy_from_slice(e);
        }
        small::add_assign(&mut self.phi[k * n..(k + 1) * n], e);
        for j in (0..k).rev() {
            let (lo, hi) = self.phi.split_at_mut((j + 1) * n);
            small::add_assign(&mut lo[j * n..], &hi[..n]);
        }
    }

    /// Dense output (DDATRP) at `tout` on the last step, which ended at
    /// `t`: `y(t) = Σ_{i=1}^{k+1} c_i φ_i`, `c_1 = 1`,
    /// `c_{i+1} = c_i (t − t_{n+1} + ψ_{i−1})/ψ_i` (`ψ_0 = 0`).
    pub(crate) fn interpolate(&self, t: f64, tout: f64, out: &mut [f64]) {
        let n = self.n;
        out.copy_from_slice(&self.phi[..n]);
        let dt = tout - t;
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

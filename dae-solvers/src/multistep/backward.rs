//! Backward differences `∇^m y_n`, `m = 0 … NB−1`, on the equally spaced
//! grid `t_n − j h` — the polynomial through the past solution values, as
//! in Cash's MEBDF code, which keeps its history so ([`History`]). It gives
//! the back values the formulas need, the predictors, the differences of
//! the error estimates, dense output, and its rescaling to a new step size
//! (interpolation: the new grid's values are read off the polynomial,
//! Nordsieck-style). A constant-step BDF run starts from the same table
//! ([`differences`]): on an equally spaced grid its modified divided
//! differences are backward differences.
//!
//! With `s = (t − t_n)/h` the polynomial is
//!
//! ```text
//!     P(t_n + s h) = Σ_m c_m(s) ∇^m y_n,   c_0 = 1,  c_m(s) = c_{m−1}(s) (s + m − 1)/m,
//! ```
//!
//! so `P(t_{n+1}) = Σ_m ∇^m y_n` and `y_{n+1} − Σ_{m≤q} ∇^m y_n = ∇^(q+1) y_{n+1}`.

/// `d[m] = ∇^m` (columns of `n`) at the newest of the values
/// `work[0..=q]` (columns of `n`, newest first; overwritten), `d[m] = 0`
/// for the columns above `q`.
pub(crate) fn differences(work: &mut [f64], q: usize, n: usize, d: &mut [f64]) {
    d.fill(0.0);
    d[..n].copy_from_slice(&work[..n]);
    for m in 1..=q {
        for j in 0..=q - m {
            let (lo, hi) = work.split_at_mut((j + 1) * n);
            for (a, b) in lo[j * n..].iter_mut().zip(&hi[..n]) {
                *a -= b;
            }
        }
        d[m * n..(m + 1) * n].copy_from_slice(&work[..n]);
    }
}

/// Backward differences at `t_n` with spacing `h`, and a scratch table.
pub(crate) struct History {
    n: usize,
    /// Columns `NB` of the table.
    nb: usize,
    /// `∇^m y_n` at `d[m n .. (m+1) n]`.
    d: Vec<f64>,
    /// Scratch of the same shape (rescaling).
    work: Vec<f64>,
    /// The spacing of the grid.
    pub(crate) h: f64,
}

impl History {
    /// Storage for `n` unknowns and the differences `∇^0 … ∇^(nb−1)`.
    pub(crate) fn new(n: usize, nb: usize) -> Self {
        History {
            n,
            nb,
            d: vec![0.0; n * nb],
            work: vec![0.0; n * nb],
            h: 0.0,
        }
    }

    /// Column `m`.
    fn col(&self, m: usize) -> &[f64] {
        &self.d[m * self.n..(m + 1) * self.n]
    }

    /// The current value `y_n`.
    pub(crate) fn y(&self) -> &[f64] {
        self.col(0)
    }

    /// Start from `y₀, y'₀` with spacing `h`: the straight line
    /// `∇^0 = y₀`, `∇^1 = h y'₀`.
    pub(crate) fn start(&mut self, y0: &[f64], yp0: &[f64], h: f64) {
        let n = self.n;
        self.d.fill(0.0);
        self.d[..n].copy_from_slice(y0);
        for (d, v) in self.d[n..2 * n].iter_mut().zip(yp0) {
            *d = h * v;
        }
        self.h = h;
    }

    /// Start from equally spaced values (oldest first, spacing `h`).
    pub(crate) fn start_from_values(&mut self, values: &[&[f64]], h: f64) {
        let n = self.n;
        let q = values.len().min(self.nb);
        self.work.fill(0.0);
        for (j, v) in values.iter().rev().take(q).enumerate() {
            self.work[j * n..(j + 1) * n].copy_from_slice(v);
        }
        self.differences(q - 1);
        self.h = h;
    }

    /// `out = Σ_{m=0}^{q} c_m(s) ∇^m y_n`: the polynomial of degree `q` at
    /// `t_n + s h` (exact back values for `s = −j`, `j ≤ q`).
    pub(crate) fn eval(&self, s: f64, q: usize, out: &mut [f64]) {
        out.copy_from_slice(self.col(0));
        let mut c = 1.0;
        for m in 1..=q.min(self.nb - 1) {
            c *= (s + (m - 1) as f64) / m as f64;
            if c == 0.0 {
                break;
            }
            for (o, d) in out.iter_mut().zip(self.col(m)) {
                *o += c * d;
            }
        }
    }

    /// `out = y − Σ_{m=0}^{q} ∇^m y_n = ∇^(q+1) y_{n+1}` for `y = y_{n+1}`.
    pub(crate) fn difference_to(&self, y: &[f64], q: usize, out: &mut [f64]) {
        out.copy_from_slice(y);
        for m in 0..=q.min(self.nb - 1) {
            for (o, d) in out.iter_mut().zip(self.col(m)) {
                *o -= d;
            }
        }
    }

    /// After an accepted step: the differences at `t_{n+1}` from `y_{n+1}`,
    /// `∇^m y_{n+1} = ∇^(m−1) y_{n+1} − ∇^(m−1) y_n`.
    pub(crate) fn advance(&mut self, y: &[f64]) {
        let n = self.n;
        for (i, &yi) in y.iter().enumerate() {
            let mut cur = yi;
            for m in 0..self.nb {
                let old = self.d[m * n + i];
                self.d[m * n + i] = cur;
                cur -= old;
            }
        }
    }

    /// Change the spacing to `h_new`: the values of the polynomial of
    /// degree `q` at `t_n − j h_new`, `j = 0 … q`, and their differences;
    /// the higher differences are dropped.
    pub(crate) fn rescale(&mut self, h_new: f64, q: usize) {
        let n = self.n;
        let q = q.min(self.nb - 1);
        let r = h_new / self.h;
        // Evaluate into the scratch table while the table itself is read.
        let mut work = std::mem::take(&mut self.work);
        for j in 0..=q {
            self.eval(-(j as f64) * r, q, &mut work[j * n..(j + 1) * n]);
        }
        self.work = work;
        self.differences(q);
        self.h = h_new;
    }

    /// The table from the values `work[0..=q]` (newest first).
    fn differences(&mut self, q: usize) {
        differences(&mut self.work, q, self.n, &mut self.d);
    }

    /// Dense output on the last step `[t_n − h, t_n]` with the polynomial of
    /// degree `q` through `y_n, …, y_{n−q}`.
    pub(crate) fn interpolate(&self, t_n: f64, tau: f64, q: usize, out: &mut [f64]) {
        self.eval((tau - t_n) / self.h, q, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_is_reproduced_and_rescaled_exactly() {
        let p = |t: f64| 1.0 + t - 2.0 * t * t + 0.5 * t * t * t;
        let h = 0.1;
        let vals: Vec<[f64; 1]> = (0..5).map(|j| [p(j as f64 * h)]).collect();
        let refs: Vec<&[f64]> = vals.iter().map(|v| v.as_slice()).collect();
        let mut hist = History::new(1, 10);
        hist.start_from_values(&refs, h);
        let t_n = 0.4;
        let mut out = [0.0];
        hist.eval(1.0, 4, &mut out);
        assert!((out[0] - p(t_n + h)).abs() < 1e-13);
        hist.rescale(0.25, 3);
        hist.eval(-1.0, 3, &mut out);
        assert!((out[0] - p(t_n - 0.25)).abs() < 1e-12);
        hist.interpolate(t_n, 0.33, 3, &mut out);
        assert!((out[0] - p(0.33)).abs() < 1e-12);
        // Advancing by the exact value keeps the cubic.
        hist.advance(&[p(t_n + 0.25)]);
        hist.eval(1.0, 3, &mut out);
        assert!((out[0] - p(t_n + 0.5)).abs() < 1e-12);
        let mut e = [0.0];
        hist.difference_to(&[p(t_n + 0.5)], 3, &mut e);
        assert!(e[0].abs() < 1e-12);
    }
}

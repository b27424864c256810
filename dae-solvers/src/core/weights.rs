//! Error weights and the one norm.
//!
//! Component `i` of a vector `v` is measured against its tolerance:
//!
//! ```text
//!     w_i = h^(k_i − 1) / (atol_i + rtol_i |y_i|)        (0 outside the test)
//!     ‖v‖ = sqrt( (1/N_test) Σ (v_i w_i)² ) ,
//! ```
//!
//! where `k_i` is the index of unknown `i` when the method scales errors by
//! the index (Radau IIA, Hairer & Wanner VII.8: the estimate of an index-`k`
//! component is `O(h^(1−k))` larger than its local error), and `k_i = 1`
//! otherwise; `N_test` counts the components in the error test (DASPK leaves
//! index-2 unknowns out of a BDF error test). The sum is scaled by its
//! largest term against overflow, as DASSL's `DDANRM` does, and a NaN
//! anywhere gives NaN. Every error test and every Newton iteration of every
//! method uses this norm.

use crate::linalg::with_size;
use crate::options::Tolerances;

/// Error weights of the `N` unknowns, updated from the solution as the
/// integration proceeds (see the [module documentation](self)).
pub(crate) struct Weights {
    rtol: Vec<f64>,
    atol: Vec<f64>,
    /// `k_i − 1` when the method scales by the index, else 0.
    index_power: Vec<i32>,
    in_test: Vec<bool>,
    inv_count: f64,
    w: Vec<f64>,
}

impl Weights {
    /// Weights for tolerances multiplied by `factor(i)` (a method's
    /// internal tolerance map; `1` for none), with components `in_test`
    /// counted, and index scaling by `index_power[i] = k_i − 1` (all zero
    /// for none).
    pub(crate) fn new(
        tol: &Tolerances,
        factor: impl Fn(usize) -> f64,
        in_test: Vec<bool>,
        index_power: Vec<i32>,
    ) -> Self {
        let n = in_test.len();
        let count = in_test.iter().filter(|&&b| b).count().max(1);
        Weights {
            rtol: (0..n).map(|i| factor(i) * tol.rtol(i)).collect(),
            atol: (0..n).map(|i| factor(i) * tol.atol(i)).collect(),
            index_power,
            in_test,
            inv_count: 1.0 / count as f64,
            w: vec![0.0; n],
        }
    }

    /// Relative tolerances in force (after the method's map).
    pub(crate) fn rtol(&self) -> &[f64] {
        &self.rtol
    }

    /// Absolute tolerances in force.
    pub(crate) fn atol(&self) -> &[f64] {
        &self.atol
    }

    /// The current weights.
    pub(crate) fn get(&self) -> &[f64] {
        &self.w
    }

    /// `w_i = 1/(atol_i + rtol_i |y_i|)`, zero outside the test.
    pub(crate) fn update(&mut self, y: &[f64]) {
        for (i, (w, yi)) in self.w.iter_mut().zip(y).enumerate() {
            *w = if self.in_test[i] {
                1.0 / (self.atol[i] + self.rtol[i] * yi.abs())
            } else {
                0.0
            };
        }
    }

    /// `w_i = h^(k_i − 1)/(atol_i + rtol_i |y_i|)`, the index-scaled
    /// weights for step size `h` (a scale below the smallest normal number
    /// counts as that number).
    pub(crate) fn update_scaled(&mut self, y: &[f64], h: f64) {
        let hinv = 1.0 / h;
        let n = self.w.len();
        let (w, y) = (&mut self.w[..], &y[..n]);
        let (atol, rtol) = (&self.atol[..n], &self.rtol[..n]);
        let (in_test, power) = (&self.in_test[..n], &self.index_power[..n]);
        for i in 0..n {
            if !in_test[i] {
                w[i] = 0.0;
                continue;
            }
            let base = atol[i] + rtol[i] * y[i].abs();
            let factor = match power[i] {
                0 => 1.0,
                1 => hinv,
                2 => hinv * hinv,
                p => hinv.powi(p),
            };
            w[i] = 1.0 / (base * factor).max(f64::MIN_POSITIVE);
        }
    }

    /// `‖v‖` over the first `N` entries of `v`.
    pub(crate) fn norm(&self, v: &[f64]) -> f64 {
        self.norm_blocks(v, v.len().min(self.w.len()), 1)
    }

    /// `‖v‖` of `blocks` vectors stored `stride` apart in `v` (the stages of
    /// a Runge–Kutta method), as one vector of `blocks · N` entries.
    pub(crate) fn norm_blocks(&self, v: &[f64], stride: usize, blocks: usize) -> f64 {
        let n = self.w.len().min(stride);
        // One block (an error estimate) and three (Radau's stages) are the
        // calls of every step: constant block counts for them too.
        with_size!(n, |N| match blocks {
            1 => norm_kernel(&self.w[..N], v, stride, 1, N, self.inv_count),
            3 => norm_kernel(&self.w[..N], v, stride, 3, N, self.inv_count),
            _ => norm_kernel(&self.w[..N], v, stride, blocks, N, self.inv_count),
        })
    }
}

/// [`Weights::norm_blocks`] for `n` weights (a constant where the caller
/// can make it one).
#[inline(always)]
fn norm_kernel(
    w: &[f64],
    v: &[f64],
    stride: usize,
    blocks: usize,
    n: usize,
    inv_count: f64,
) -> f64 {
    // One pass for the largest term, one for the scaled sum. A NaN entry is
    // passed over by the first (`x > vmax` is false) and makes the sum NaN
    // in the second; only where the second pass is skipped is it looked for.
    let mut vmax = 0.0_f64;
    for b in 0..blocks {
        let vb = &v[b * stride..][..n];
        for i in 0..n {
            let x = (vb[i] * w[i]).abs();
            if x > vmax {
                vmax = x;
            }
        }
    }
    if vmax == 0.0 || !vmax.is_finite() {
        let nan = (0..blocks).any(|b| {
            let vb = &v[b * stride..][..n];
            (0..n).any(|i| (vb[i] * w[i]).is_nan())
        });
        return if nan { f64::NAN } else { vmax };
    }
    let mut sum = 0.0;
    for b in 0..blocks {
        let vb = &v[b * stride..][..n];
        for i in 0..n {
            let x = vb[i] * w[i] / vmax;
            sum += x * x;
        }
    }
    vmax * (sum * inv_count / blocks as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norm_is_the_weighted_rms_over_the_test() {
        let tol = Tolerances::uniform(0.5);
        let mut w = Weights::new(&tol, |_| 1.0, vec![true, true, false], vec![0, 0, 1]);
        w.update(&[1.0, 3.0, 100.0]);
        assert_eq!(w.get(), &[1.0, 0.5, 0.0]);
        // sqrt((3² + 2²)/2), the third component out of the test.
        let n = w.norm(&[3.0, 4.0, 1e300]);
        assert!((n - (13.0f64 / 2.0).sqrt()).abs() < 1e-15);
        assert!(w.norm(&[f64::NAN, 0.0, 0.0]).is_nan());
        // A NaN among finite, among infinite entries, and one made of
        // `∞ · 0` (an infinite entry with weight zero is out of the test).
        assert!(w.norm(&[2.0, f64::NAN, 0.0]).is_nan());
        assert!(w.norm(&[f64::INFINITY, f64::NAN, 0.0]).is_nan());
        assert_eq!(w.norm(&[f64::INFINITY, 1.0, 0.0]), f64::INFINITY);
        assert!(w.norm(&[1.0, 1.0, f64::INFINITY]).is_nan());
        for blocks in [1, 2, 3, 4] {
            let mut v = vec![1.0; 3 * blocks];
            v[3 * blocks - 2] = f64::NAN;
            assert!(w.norm_blocks(&v, 3, blocks).is_nan(), "{blocks} blocks");
        }
        assert_eq!(w.norm(&[1e308, 1e308, 0.0]), 1e308 * (1.25f64 / 2.0).sqrt());
        // Two blocks of the same vector have the same norm as one.
        let b = w.norm_blocks(&[3.0, 4.0, 0.0, 3.0, 4.0, 0.0], 3, 2);
        assert!((b - n).abs() < 1e-15);
    }

    #[test]
    fn index_scaling_divides_by_powers_of_h() {
        let tol = Tolerances::uniform(1.0);
        let mut w = Weights::new(&tol, |i| [1.0, 2.0, 1.0][i], vec![true; 3], vec![0, 1, 2]);
        w.update_scaled(&[0.0, 0.0, 0.0], 0.1);
        let g = w.get();
        assert!((g[0] - 1.0).abs() < 1e-15);
        assert!((g[1] - 0.1 / 2.0).abs() < 1e-15);
        assert!((g[2] - 0.01).abs() < 1e-15);
    }
}

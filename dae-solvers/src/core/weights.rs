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
//! index-2 unknowns out of a BDF error test). A NaN anywhere gives NaN.
//!
//! The sum of squares is formed one of two ways ([`Sum`]): scaled by its
//! largest term, as DASSL's `DDANRM` does (safe from overflow by
//! construction, two passes), or plain, as RADAU5 and SUNDIALS'
//! `N_VWrmsNorm` do (one pass; measured again scaled only where it
//! overflowed, may have underflowed or is NaN). The two differ in the last
//! bits only. Every error test and every Newton iteration of every
//! method uses this norm.

use std::marker::PhantomData;

use crate::linalg::with_size;
use crate::options::Tolerances;
use dae_core::system::FormulationInfo;

/// Error weights of the `N` unknowns, updated from the solution as the
/// integration proceeds (see the [module documentation](self)).
#[derive(Clone)]
pub(crate) struct Weights<S = Scaled> {
    rtol: Vec<f64>,
    atol: Vec<f64>,
    /// `k_i − 1` when the method scales by the index, else 0.
    index_power: Vec<i32>,
    in_test: Vec<bool>,
    inv_count: f64,
    w: Vec<f64>,
    sum: PhantomData<S>,
}

/// How [`Weights::norm_blocks`] forms its sum of squares: [`Scaled`] or
/// [`Plain`], a type parameter of the weights (no test per call). The two
/// agree to rounding.
///
/// The collocation family sums plainly: one pass instead of two is 3.2 % of
/// radau5's instructions on the pendulum (BENCHMARKS §12e). The multistep
/// families keep DASSL's scaled sum: a DASSL-type step-size sequence turns
/// the last bit of a norm into a different sequence within a few hundred
/// steps (bdf on S01 at 1e-8: 5 918 steps with the scaled sum, 5 394 with
/// the plain one, every step the same up to step 1 740), and the port is
/// checked step for step against DDASSL.
pub(crate) trait Sum: Clone {
    /// `‖v‖` of `blocks` vectors of `n` entries `stride` apart, weighted
    /// by `w`, the sum divided by `blocks` and multiplied by `inv_count`.
    fn norm(w: &[f64], v: &[f64], stride: usize, blocks: usize, n: usize, inv_count: f64) -> f64;
}

/// Scaled by the largest term, two passes (DASSL's `DDANRM`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Scaled;

/// Plain, one pass (RADAU5, `N_VWrmsNorm`), with the scaled sum as the
/// fallback where the plain one is not safe.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Plain;

impl Sum for Scaled {
    #[inline(always)]
    fn norm(w: &[f64], v: &[f64], stride: usize, blocks: usize, n: usize, inv_count: f64) -> f64 {
        scaled_norm(w, v, stride, blocks, n, inv_count)
    }
}

impl Sum for Plain {
    #[inline(always)]
    fn norm(w: &[f64], v: &[f64], stride: usize, blocks: usize, n: usize, inv_count: f64) -> f64 {
        plain_norm(w, v, stride, blocks, n, inv_count)
    }
}

/// The index scaling [`Weights::new`] takes for the unknowns of `info`:
/// the power `k − 1` of `h` for an unknown of index `k` (index 0 as 1).
/// Used by the collocation engine and by mebdf.
pub(crate) fn index_powers(info: &FormulationInfo) -> Vec<i32> {
    info.variables
        .iter()
        .map(|var| i32::from(var.index.max(1)) - 1)
        .collect()
}

impl<S: Sum> Weights<S> {
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
            sum: PhantomData,
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
        // Every slice cut to `n` first: no bounds test in the loop (this
        // runs at every step of a multistep method).
        let n = self.w.len().min(y.len());
        let (w, y) = (&mut self.w[..n], &y[..n]);
        let (atol, rtol, in_test) = (&self.atol[..n], &self.rtol[..n], &self.in_test[..n]);
        for i in 0..n {
            w[i] = if in_test[i] {
                1.0 / (atol[i] + rtol[i] * y[i].abs())
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
            1 => S::norm(&self.w[..N], v, stride, 1, N, self.inv_count),
            3 => S::norm(&self.w[..N], v, stride, 3, N, self.inv_count),
            _ => S::norm(&self.w[..N], v, stride, blocks, N, self.inv_count),
        })
    }
}

/// Below this sum of squares some terms may have lost digits to underflow
/// (a term `x²` under the smallest normal number, `2.2e-308`, is denormal):
/// with the sum at least `1e-250`, what such terms could add is below
/// `1e-58` of it.
const UNDERFLOW_SAFE: f64 = 1e-250;

/// The unknown with the largest weighted entry `|v_j w_j|` over the first
/// `blocks` blocks of `m` rows of `v` (rows beyond the weights' length
/// count as none; the first of equal entries, NaN passed over): the one a
/// stalled Newton iteration names ([`crate::SolveError::RoundOffFloor`]).
pub(crate) fn largest_weighted(v: &[f64], weights: &[f64], m: usize, blocks: usize) -> usize {
    let mut best = (0, 0.0);
    for block in v.chunks(m).take(blocks) {
        for (j, (d, w)) in block.iter().zip(weights).enumerate() {
            let x = (d * w).abs();
            if x > best.1 {
                best = (j, x);
            }
        }
    }
    best.0
}

/// [`Plain`] for `n` weights (a constant where the caller can make it
/// one): one pass; a sum that overflowed, may have underflowed, or is NaN
/// is measured again by [`scaled_norm`].
#[inline(always)]
fn plain_norm(w: &[f64], v: &[f64], stride: usize, blocks: usize, n: usize, inv_count: f64) -> f64 {
    let mut sum = 0.0;
    for b in 0..blocks {
        let vb = &v[b * stride..][..n];
        for i in 0..n {
            let x = vb[i] * w[i];
            sum += x * x;
        }
    }
    if sum.is_finite() && sum >= UNDERFLOW_SAFE {
        return (sum * inv_count / blocks as f64).sqrt();
    }
    scaled_fallback(w, v, stride, blocks, n, inv_count)
}

/// [`scaled_norm`] out of the plain sum's way (rarely taken).
#[cold]
#[inline(never)]
fn scaled_fallback(
    w: &[f64],
    v: &[f64],
    stride: usize,
    blocks: usize,
    n: usize,
    inv_count: f64,
) -> f64 {
    scaled_norm(w, v, stride, blocks, n, inv_count)
}

/// [`Scaled`]: the sum scaled by its largest term, safe from
/// overflow and underflow (DASSL's `DDANRM`). A NaN entry is passed over by
/// the first pass (`x > vmax` is false) and makes the sum NaN in the
/// second; only where the second pass is skipped is it looked for.
#[inline(always)]
fn scaled_norm(
    w: &[f64],
    v: &[f64],
    stride: usize,
    blocks: usize,
    n: usize,
    inv_count: f64,
) -> f64 {
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
        rms_over_the_test::<Scaled>(&tol);
        rms_over_the_test::<Plain>(&tol);
        // In between, the plain sum and the scaled one agree to rounding.
        let mut scaled =
            Weights::<Scaled>::new(&tol, |_| 1.0, vec![true, true, false], vec![0, 0, 1]);
        let mut plain =
            Weights::<Plain>::new(&tol, |_| 1.0, vec![true, true, false], vec![0, 0, 1]);
        scaled.update(&[1.0, 3.0, 100.0]);
        plain.update(&[1.0, 3.0, 100.0]);
        for v in [[3.0, 4.0, 0.0], [1e-100, 2e-100, 5.0], [1e150, 1e149, 0.0]] {
            assert!((plain.norm(&v) / scaled.norm(&v) - 1.0).abs() < 4.0 * f64::EPSILON);
        }
    }

    fn rms_over_the_test<S: Sum + std::fmt::Debug + Default>(tol: &Tolerances) {
        let sum = S::default();
        {
            let mut w = Weights::<S>::new(tol, |_| 1.0, vec![true, true, false], vec![0, 0, 1]);
            w.update(&[1.0, 3.0, 100.0]);
            assert_eq!(w.get(), &[1.0, 0.5, 0.0]);
            // sqrt((3² + 2²)/2), the third component out of the test.
            let n = w.norm(&[3.0, 4.0, 1e300]);
            assert!((n - (13.0f64 / 2.0).sqrt()).abs() < 1e-15, "{sum:?}");
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
            // Squares that overflow, and squares that underflow: measured
            // scaled, not as infinity or zero.
            assert_eq!(w.norm(&[1e308, 1e308, 0.0]), 1e308 * (1.25f64 / 2.0).sqrt());
            let tiny = w.norm(&[1e-200, 0.0, 0.0]);
            assert!(
                (tiny / (1e-200 / 2f64.sqrt()) - 1.0).abs() < 1e-15,
                "{tiny}"
            );
            assert_eq!(w.norm(&[0.0, 0.0, 5.0]), 0.0);
            // Two blocks of the same vector have the same norm as one.
            let b = w.norm_blocks(&[3.0, 4.0, 0.0, 3.0, 4.0, 0.0], 3, 2);
            assert!((b - n).abs() < 1e-15);
        }
    }

    #[test]
    fn index_scaling_divides_by_powers_of_h() {
        let tol = Tolerances::uniform(1.0);
        let mut w =
            Weights::<Scaled>::new(&tol, |i| [1.0, 2.0, 1.0][i], vec![true; 3], vec![0, 1, 2]);
        w.update_scaled(&[0.0, 0.0, 0.0], 0.1);
        let g = w.get();
        assert!((g[0] - 1.0).abs() < 1e-15);
        assert!((g[1] - 0.1 / 2.0).abs() < 1e-15);
        assert!((g[2] - 0.01).abs() < 1e-15);
    }
}

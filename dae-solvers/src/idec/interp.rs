//! The interpolating polynomial of one interval: degree `m` through the
//! `m + 1` equally spaced nodes `θ = 0, 1, …, m` (`t = t_i + θ h`), in
//! Lagrange form.
//!
//! Two things are needed of it: its derivative at the nodes `0 … m − 1`
//! where the defect is sampled (the differentiation matrix `D`, computed
//! once, `p'(t_i + k h) = (1/h) Σ_l D_kl η_l`), and its value anywhere in
//! the interval for dense output (the Lagrange weights, computed on the
//! stack).

/// Highest interpolation degree (bounds the stack arrays of dense output;
/// equally spaced interpolation of higher degree is ill-conditioned
/// anyway).
pub const MAX_DEGREE: usize = 8;

/// Differentiation matrix of the Lagrange basis on the nodes `0 … m`.
pub(super) struct Nodes {
    /// Degree `m`.
    m: usize,
    /// `D_kl = l_l'(k)`, row-major, `(m + 1)²` entries.
    d: Vec<f64>,
}

impl Nodes {
    /// The nodes of degree `m` (`1 ≤ m ≤ MAX_DEGREE`).
    pub(super) fn new(m: usize) -> Self {
        let n = m + 1;
        let mut d = vec![0.0; n * n];
        for k in 0..n {
            for l in 0..n {
                d[k * n + l] = if k == l {
                    // l_k'(k) = Σ_{q ≠ k} 1/(k − q)
                    (0..n)
                        .filter(|&q| q != k)
                        .map(|q| 1.0 / (k as f64 - q as f64))
                        .sum()
                } else {
                    // l_l'(k) = Π_{q ≠ l, k} (k − q) / Π_{q ≠ l} (l − q)
                    let num: f64 = (0..n)
                        .filter(|&q| q != l && q != k)
                        .map(|q| k as f64 - q as f64)
                        .product();
                    let den: f64 = (0..n)
                        .filter(|&q| q != l)
                        .map(|q| l as f64 - q as f64)
                        .product();
                    num / den
                };
            }
        }
        Nodes { m, d }
    }

    /// The degree.
    pub(super) fn degree(&self) -> usize {
        self.m
    }

    /// `out = Σ_l D_kl values(l)`: `h` times the derivative at node `k` of
    /// the polynomial through `values(0) … values(m)` (each of length
    /// `out.len()`).
    pub(super) fn derivative<'v>(
        &self,
        k: usize,
        values: impl Fn(usize) -> &'v [f64],
        out: &mut [f64],
    ) {
        let n = self.m + 1;
        out.fill(0.0);
        for l in 0..n {
            let c = self.d[k * n + l];
            for (o, v) in out.iter_mut().zip(values(l)) {
                *o += c * v;
            }
        }
    }

    /// As [`Nodes::derivative`], for values given as unevaluated sums
    /// `hi(l) + lo(l)` (the compensated sums of the constant-step scheme),
    /// from the differences to node `k`: `out = Σ_{l ≠ k} D_kl ((hi(l) −
    /// hi(k)) + (lo(l) − lo(k)))`, which is the same polynomial derivative
    /// since every row of `D` sums to zero. The sum of `D_kl hi(l)` cancels
    /// values of size 1 to an `h p'` of size `h`, an absolute round-off of
    /// `|D| · ulp(hi)` per step; the differences of neighbouring nodes are
    /// exact (Sterbenz) and of size `h`, so that round-off goes.
    pub(super) fn derivative_compensated<'v>(
        &self,
        k: usize,
        hi: impl Fn(usize) -> &'v [f64],
        lo: impl Fn(usize) -> &'v [f64],
        out: &mut [f64],
    ) {
        let n = self.m + 1;
        out.fill(0.0);
        let (hi_k, lo_k) = (hi(k), lo(k));
        for l in (0..n).filter(|&l| l != k) {
            let (c, hi_l, lo_l) = (self.d[k * n + l], hi(l), lo(l));
            for (i, o) in out.iter_mut().enumerate() {
                *o += c * ((hi_l[i] - hi_k[i]) + (lo_l[i] - lo_k[i]));
            }
        }
    }
}

pub(super) use crate::linalg::two_sum;

/// The Lagrange weights `l_0(θ) … l_m(θ)` on the nodes `0 … m` into the
/// first `m + 1` entries of the result.
pub(super) fn weights(m: usize, theta: f64) -> [f64; MAX_DEGREE + 1] {
    let mut w = [0.0; MAX_DEGREE + 1];
    for (l, wl) in w.iter_mut().enumerate().take(m + 1) {
        let mut p = 1.0;
        for q in 0..=m {
            if q != l {
                p *= (theta - q as f64) / (l as f64 - q as f64);
            }
        }
        *wl = p;
    }
    w
}

/// Interval ends that [`Ends`] interpolates the algebraic unknowns
/// through: four, a cubic (measured on the pendulum, `rcd0` and `ggl1`: a
/// quadratic is up to 1.4× worse, degrees 4 and 5 are no better).
pub(super) const ENDS: usize = 4;

/// The algebraic unknowns at the last [`ENDS`] accepted interval ends, for
/// dense output with error control.
///
/// Restarted intervals leave the algebraic unknowns at the interior nodes
/// further off (the module documentation, "Known limitation") than at the
/// interval ends, where the error control measures them: the interior
/// nodes' polynomial put the pendulum's `λ` between the ends 114× (`rcd0`)
/// and 4× (`ggl1`, `rcd1`) further from the exact solution than at the ends
/// (tol 1e-8, t ∈ [0, 5]). The algebraic unknowns' dense output is
/// therefore the polynomial through the accepted ends, in Lagrange form on
/// their (unequal) times.
pub(super) struct Ends {
    /// Which unknowns are algebraic.
    algebraic: Vec<usize>,
    /// Times of the stored ends, oldest first (`len() ≤ ENDS`).
    t: Vec<f64>,
    /// Their algebraic values, `algebraic.len()` per end, oldest first.
    values: Vec<f64>,
}

impl Ends {
    /// The history of `y0` at `t0`, for the unknowns `algebraic`.
    pub(super) fn new(algebraic: Vec<usize>, t0: f64, y0: &[f64]) -> Self {
        let mut ends = Ends {
            algebraic,
            t: Vec::with_capacity(ENDS),
            values: Vec::new(),
        };
        ends.values.reserve(ENDS * ends.algebraic.len());
        ends.push(t0, y0);
        ends
    }

    /// Record the accepted value `y` at the end `t`, dropping the oldest
    /// end once [`ENDS`] are held.
    pub(super) fn push(&mut self, t: f64, y: &[f64]) {
        let k = self.algebraic.len();
        if self.t.len() == ENDS {
            self.t.remove(0);
            self.values.drain(..k);
        }
        self.t.push(t);
        self.values.extend(self.algebraic.iter().map(|&i| y[i]));
    }

    /// Overwrite the algebraic entries of `out` with the polynomial through
    /// the stored ends at `tau` (between the last two; a constant when only
    /// the start is held).
    pub(super) fn interpolate(&self, tau: f64, out: &mut [f64]) {
        let k = self.algebraic.len();
        for &i in &self.algebraic {
            out[i] = 0.0;
        }
        for (a, &ta) in self.t.iter().enumerate() {
            let w: f64 = self
                .t
                .iter()
                .enumerate()
                .filter(|&(b, _)| b != a)
                .map(|(_, &tb)| (tau - tb) / (ta - tb))
                .product();
            for (&i, v) in self.algebraic.iter().zip(&self.values[a * k..(a + 1) * k]) {
                out[i] += w * v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Degree-`m` interpolation reproduces polynomials of degree `m`
    /// exactly, values and derivatives.
    #[test]
    fn exact_for_polynomials_of_the_degree() {
        for m in 1..=MAX_DEGREE {
            let p = |x: f64| {
                (0..=m)
                    .map(|e| (e as f64 + 1.0) * x.powi(e as i32))
                    .sum::<f64>()
            };
            let dp = |x: f64| {
                (1..=m)
                    .map(|e| (e as f64 + 1.0) * e as f64 * x.powi(e as i32 - 1))
                    .sum::<f64>()
            };
            let values: Vec<[f64; 1]> = (0..=m).map(|k| [p(k as f64)]).collect();
            let nodes = Nodes::new(m);
            for k in 0..=m {
                let mut out = [0.0];
                nodes.derivative(k, |l| &values[l][..], &mut out);
                let want = dp(k as f64);
                // Relative to the data (up to 9·8⁸ for m = 8): the weights
                // sum values of that size to a derivative of size 2 at
                // node 0, so round-off is relative to the values.
                let scale = values.iter().map(|v| v[0].abs()).fold(1.0, f64::max);
                assert!((out[0] - want).abs() <= 1e-12 * scale, "m {m} k {k}");
                // The same from differences, the values split into a high
                // and a low part.
                let hi: Vec<[f64; 1]> = values.iter().map(|v| [f64::from(v[0] as f32)]).collect();
                let lo: Vec<[f64; 1]> =
                    values.iter().zip(&hi).map(|(v, h)| [v[0] - h[0]]).collect();
                let mut split = [0.0];
                nodes.derivative_compensated(k, |l| &hi[l][..], |l| &lo[l][..], &mut split);
                assert!(
                    (split[0] - want).abs() <= 1e-12 * scale,
                    "m {m} k {k}, hi + lo"
                );
            }
            for theta in [0.0, 0.3, 1.7, m as f64 - 0.2, m as f64] {
                let w = weights(m, theta);
                let v: f64 = (0..=m).map(|l| w[l] * values[l][0]).sum();
                let want = p(theta);
                assert!(
                    (v - want).abs() <= 1e-9 * want.abs().max(1.0),
                    "m {m} θ {theta}"
                );
            }
        }
    }

    /// The ends' polynomial reproduces a cubic on unequal times from the
    /// fourth end on, touches only the algebraic unknowns, and keeps the
    /// newest four.
    #[test]
    fn ends_interpolate_the_algebraic_unknowns() {
        let cubic = |t: f64| 2.0 - t + 0.5 * t * t - 3.0 * t.powi(3);
        let y = |t: f64| [10.0 + t, cubic(t), -1.0, 7.0 * t];
        let mut ends = Ends::new(vec![1, 3], 0.0, &y(0.0));
        let mut out = [f64::NAN, f64::NAN, 5.0, f64::NAN];
        // The start alone: constant.
        ends.interpolate(0.1, &mut out);
        assert_eq!(out[1], cubic(0.0));
        assert_eq!(out[3], 0.0);
        for t in [0.1, 0.25, 0.3, 0.7, 0.75] {
            ends.push(t, &y(t));
        }
        assert_eq!(ends.t, [0.25, 0.3, 0.7, 0.75]);
        for tau in [0.7, 0.72, 0.75] {
            ends.interpolate(tau, &mut out);
            assert!((out[1] - cubic(tau)).abs() < 1e-12, "τ {tau}");
            assert!((out[3] - 7.0 * tau).abs() < 1e-12, "τ {tau}");
        }
        assert!(out[0].is_nan() && out[2] == 5.0);
    }

    /// `two_sum` returns the rounding error of the sum exactly, whichever
    /// operand is larger.
    #[test]
    fn two_sum_is_exact() {
        let half_ulp = f64::EPSILON / 2.0;
        let cases = [
            ((1.0, 1e-17), (1.0, 1e-17)),
            ((1e-17, 1.0), (1.0, 1e-17)),
            ((-1e-17, -1.0), (-1.0, -1e-17)),
            // Ties round to even, up or down.
            ((1.0, half_ulp), (1.0, half_ulp)),
            (
                (1.0 + f64::EPSILON, half_ulp),
                (1.0 + 2.0 * f64::EPSILON, -half_ulp),
            ),
            ((-2.5, 2.5), (0.0, 0.0)),
        ];
        for ((a, b), want) in cases {
            assert_eq!(two_sum(a, b), want, "{a} + {b}");
        }
        // An Euler update of size 4e-7 on a value of size 3: the error is
        // b − (s − a), both differences exact here.
        let (a, b) = (3.0_f64.sqrt(), 4e-7 / 3.0);
        let (s, e) = two_sum(a, b);
        assert_eq!(e, b - (s - a));
        assert!(e != 0.0 && e.abs() <= 2.0 * half_ulp);
    }
}

//! The Lagrange polynomial of degree `m` through values at the `m + 1`
//! equally spaced nodes `θ = 0, 1, …, m` of a step (`t = t_i + θ h`), for
//! any method that interpolates its values on such nodes (IDeC's defect
//! and dense output; the collocation engine keeps its polynomial in Newton
//! form in its kernels): its derivative at the nodes (the differentiation
//! matrix `D`, computed once, `p'(t_i + k h) = (1/h) Σ_l D_kl y_l`), also
//! for values held as compensated sums, and its value anywhere (the
//! Lagrange weights, on the stack).

/// Highest interpolation degree (bounds the stack arrays of dense output;
/// equally spaced interpolation of higher degree is ill-conditioned
/// anyway).
pub const MAX_DEGREE: usize = 8;

/// Differentiation matrix of the Lagrange basis on the nodes `0 … m`.
pub(crate) struct Nodes {
    /// Degree `m`.
    m: usize,
    /// `D_kl = l_l'(k)`, row-major, `(m + 1)²` entries.
    d: Vec<f64>,
}

impl Nodes {
    /// The nodes of degree `m` (`1 ≤ m ≤ MAX_DEGREE`).
    pub(crate) fn new(m: usize) -> Self {
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
    pub(crate) fn degree(&self) -> usize {
        self.m
    }

    /// `out = Σ_l D_kl values(l)`: `h` times the derivative at node `k` of
    /// the polynomial through `values(0) … values(m)` (each of length
    /// `out.len()`).
    pub(crate) fn derivative<'v>(
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
    pub(crate) fn derivative_compensated<'v>(
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

    /// `out = p(θ)`, the polynomial through `values(0) … values(m)` at
    /// `t_i + θ h`.
    pub(crate) fn evaluate<'v>(
        &self,
        theta: f64,
        values: impl Fn(usize) -> &'v [f64],
        out: &mut [f64],
    ) {
        let w = weights(self.m, theta);
        out.fill(0.0);
        for (l, wl) in w.iter().enumerate().take(self.m + 1) {
            for (o, v) in out.iter_mut().zip(values(l)) {
                *o += wl * v;
            }
        }
    }
}

/// The Lagrange weights `l_0(θ) … l_m(θ)` on the nodes `0 … m` into the
/// first `m + 1` entries of the result.
fn weights(m: usize, theta: f64) -> [f64; MAX_DEGREE + 1] {
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
}

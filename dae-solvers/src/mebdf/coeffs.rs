//! The constant-step coefficients of the formulas: the `k`-step BDF of the
//! two predicting stages, the `k`-step extended BDF (EBDF) the corrector is
//! made of, and the error constants of every order — all from their order
//! conditions, solved once when an integrator is built.
//!
//! With `s = (t − t_{n+1})/h`, the values `y_{n+1−j}` at `s = −j` and the
//! derivatives at `s = 0` (and, for the EBDF, at `s = 1`):
//!
//! ```text
//!     BDF-k :  Σ_{j=0}^{k} α_j y_{n+1−j} = h β y'_{n+1},                     α_0 = 1, order k;
//!     EBDF-k:  Σ_{j=0}^{k} â_j y_{n+1−j} = h (b̂_0 y'_{n+1} + b̂_1 y'_{n+2}),   â_0 = 1, order k+1.
//! ```
//!
//! The order conditions are exactness on `y = s^m`: `m = 0 … k` for the BDF
//! (`k+1` unknowns `α_1 … α_k, β`), `m = 0 … k+1` for the EBDF (`k+2`
//! unknowns). The error constant of a formula of order `p` is the residual
//! on `s^(p+1)/(p+1)!`: its local error is `C h^(p+1) y^(p+1)`, about
//! `C ∇^(p+1) y_{n+1}` (Cash 1980; Hairer & Wanner, *Solving ODEs II*,
//! V.3 for the BDF constants `1/2, 2/9, 3/22, 12/125, …`).

/// Highest order of the method (a 7-step EBDF corrector).
pub(super) const MAX_ORDER: usize = 8;
/// Largest number of steps of the formulas: `MAX_ORDER − 1` for the
/// corrector, one more for the error constant at `MAX_ORDER + 1`.
const MAX_K: usize = MAX_ORDER;

/// The coefficients of every step number (index `k`, 1 … [`MAX_K`]).
#[derive(Default)]
pub(super) struct Coefficients {
    /// `α_j` of BDF-`k` (`α_0 = 1` at index 0).
    pub(super) bdf_alpha: [[f64; MAX_K + 1]; MAX_K + 1],
    /// `β` of BDF-`k`.
    pub(super) bdf_beta: [f64; MAX_K + 1],
    /// `â_j` of EBDF-`k`.
    pub(super) ebdf_a: [[f64; MAX_K + 1]; MAX_K + 1],
    /// `b̂_0` of EBDF-`k`.
    pub(super) ebdf_b0: [f64; MAX_K + 1],
    /// `b̂_1` (the future point) of EBDF-`k`.
    pub(super) ebdf_b1: [f64; MAX_K + 1],
    /// `|C_p|`, the error constant of the method of order `p` (index `p`,
    /// 1 … `MAX_ORDER + 1`): BDF-1 for `p = 1`, EBDF-`(p−1)` above.
    pub(super) error_constant: [f64; MAX_K + 2],
}

/// `(−j)^m` as a float (`0^0 = 1`).
fn power(j: usize, m: usize) -> f64 {
    (-(j as f64)).powi(m as i32)
}

/// `m!`.
fn factorial(m: usize) -> f64 {
    (1..=m).map(|i| i as f64).product()
}

/// Solve the `n × n` system `a x = b` (row-major, `n ≤ MAX_K + 2`) by
/// Gaussian elimination with partial pivoting; the solution in `b`.
fn solve_small(a: &mut [[f64; MAX_K + 2]; MAX_K + 2], b: &mut [f64; MAX_K + 2], n: usize) {
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        b.swap(col, pivot);
        let (top, bottom) = a.split_at_mut(col + 1);
        let pivot_row = &top[col];
        for (off, row) in bottom[..n - col - 1].iter_mut().enumerate() {
            let f = row[col] / pivot_row[col];
            for (x, y) in row[col..n].iter_mut().zip(&pivot_row[col..n]) {
                *x -= f * y;
            }
            b[col + 1 + off] -= f * b[col];
        }
    }
    for row in (0..n).rev() {
        let mut s = b[row];
        for c in row + 1..n {
            s -= a[row][c] * b[c];
        }
        b[row] = s / a[row][row];
    }
}

impl Coefficients {
    /// Solve the order conditions of every formula.
    pub(super) fn new() -> Self {
        let mut c = Coefficients::default();
        for k in 1..=MAX_K {
            // BDF-k in backward differences (exact, no linear solve):
            // Σ_{i=1}^{k} ∇^i y_{n+1}/i = h y'_{n+1}, ∇^i y_{n+1} =
            // Σ_j (−1)^j C(i, j) y_{n+1−j}; divided by Σ 1/i.
            let mut alpha = [0.0; MAX_K + 1];
            for i in 1..=k {
                let mut binom = 1.0;
                for (j, a) in alpha.iter_mut().enumerate().take(i + 1) {
                    if j > 0 {
                        binom *= (i + 1 - j) as f64 / j as f64;
                    }
                    let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
                    *a += sign * binom / i as f64;
                }
            }
            let lead = alpha[0];
            for (dst, a) in c.bdf_alpha[k].iter_mut().zip(&alpha) {
                *dst = a / lead;
            }
            c.bdf_beta[k] = 1.0 / lead;

            // EBDF-k: unknowns â_1 … â_k, b̂_0, b̂_1; rows m = 0 … k+1:
            // Σ_j â_j (−j)^m − b̂_0 [m = 1] − b̂_1 m = −[m = 0].
            let mut a = [[0.0; MAX_K + 2]; MAX_K + 2];
            let mut b = [0.0; MAX_K + 2];
            for m in 0..=k + 1 {
                for j in 1..=k {
                    a[m][j - 1] = power(j, m);
                }
                a[m][k] = if m == 1 { -1.0 } else { 0.0 };
                a[m][k + 1] = -(m as f64);
                b[m] = if m == 0 { -1.0 } else { 0.0 };
            }
            solve_small(&mut a, &mut b, k + 2);
            c.ebdf_a[k][0] = 1.0;
            c.ebdf_a[k][1..=k].copy_from_slice(&b[..k]);
            c.ebdf_b0[k] = b[k];
            c.ebdf_b1[k] = b[k + 1];
        }
        // Error constants: BDF-1 at order 1, EBDF-(p−1) at order p ≥ 2.
        let bdf1 = (0..=1)
            .map(|j| c.bdf_alpha[1][j] * power(j, 2))
            .sum::<f64>();
        c.error_constant[1] = (bdf1 / factorial(2)).abs();
        for p in 2..=MAX_K + 1 {
            let k = p - 1;
            let lhs: f64 = (0..=k).map(|j| c.ebdf_a[k][j] * power(j, p + 1)).sum();
            let rhs = (p + 1) as f64 * c.ebdf_b1[k];
            c.error_constant[p] = ((lhs - rhs) / factorial(p + 1)).abs();
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_coefficients() {
        let c = Coefficients::new();
        // BDF-2: y_{n+1} − 4/3 y_n + 1/3 y_{n−1} = 2/3 h y'_{n+1}.
        assert!((c.bdf_alpha[2][1] + 4.0 / 3.0).abs() < 1e-14);
        assert!((c.bdf_alpha[2][2] - 1.0 / 3.0).abs() < 1e-14);
        assert!((c.bdf_beta[2] - 2.0 / 3.0).abs() < 1e-14);
        // β of BDF-k is 1/Σ 1/j.
        for k in 1..=MAX_K {
            let s: f64 = (1..=k).map(|j| 1.0 / j as f64).sum();
            assert!((c.bdf_beta[k] - 1.0 / s).abs() < 1e-12, "k = {k}");
        }
        // EBDF-1: y_{n+1} − y_n = h (3/2 y'_{n+1} − 1/2 y'_{n+2}).
        assert!((c.ebdf_a[1][1] + 1.0).abs() < 1e-14);
        assert!((c.ebdf_b0[1] - 1.5).abs() < 1e-14);
        assert!((c.ebdf_b1[1] + 0.5).abs() < 1e-14);
        // Error constant of BDF-1 is 1/2; of EBDF-1 (order 2) 5/12.
        assert!((c.error_constant[1] - 0.5).abs() < 1e-14);
        assert!((c.error_constant[2] - 5.0 / 12.0).abs() < 1e-14);
        // Each EBDF is exact on s^(k+1) and not on s^(k+2).
        for k in 1..MAX_K {
            let p = k + 1;
            let on = |m: usize| -> f64 {
                let lhs: f64 = (0..=k).map(|j| c.ebdf_a[k][j] * power(j, m)).sum();
                let rhs = if m == 1 { c.ebdf_b0[k] } else { 0.0 } + m as f64 * c.ebdf_b1[k];
                lhs - rhs
            };
            assert!(on(p).abs() < 1e-8 * factorial(p), "k = {k}");
            assert!(on(p + 1).abs() > 1e-6, "k = {k}");
        }
    }
}

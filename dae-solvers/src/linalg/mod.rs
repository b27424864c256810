//! Dense linear algebra in storage allocated once: the square LU
//! factorisation of the iteration matrices ([`lu`]), the constrained
//! least-squares solver of the overdetermined methods ([`lstsq`]), and the
//! matrix–vector product [`mat_vec`] that writes into a caller's buffer.

/// Calls `$body` (a generic closure-like macro body over a constant size)
/// with `n` a compile-time constant for the sizes of the formulations a
/// step loop meets most (1 … 12 unknowns), and with the run-time `n`
/// otherwise. The kernels are written once; the constant copies let the
/// compiler unroll the short loops and drop their bounds checks, which is
/// most of the cost of a norm or a stage update of 5 entries. (The LU
/// kernels go further: `build.rs` writes them out in straight lines.)
macro_rules! with_size {
    ($n:expr, |$c:ident| $body:expr) => {
        match $n {
            1 => {
                const $c: usize = 1;
                $body
            }
            2 => {
                const $c: usize = 2;
                $body
            }
            3 => {
                const $c: usize = 3;
                $body
            }
            4 => {
                const $c: usize = 4;
                $body
            }
            5 => {
                const $c: usize = 5;
                $body
            }
            6 => {
                const $c: usize = 6;
                $body
            }
            7 => {
                const $c: usize = 7;
                $body
            }
            8 => {
                const $c: usize = 8;
                $body
            }
            9 => {
                const $c: usize = 9;
                $body
            }
            10 => {
                const $c: usize = 10;
                $body
            }
            11 => {
                const $c: usize = 11;
                $body
            }
            12 => {
                const $c: usize = 12;
                $body
            }
            _ => {
                #[allow(non_snake_case)]
                let $c: usize = $n;
                $body
            }
        }
    };
}

pub(crate) use with_size;

pub(crate) mod lstsq;
pub(crate) mod lu;
pub(crate) mod pattern_lu;
pub(crate) mod small;
#[cfg(feature = "sparse")]
pub(crate) mod sparse;
#[cfg(not(feature = "sparse"))]
#[path = "sparse_off.rs"]
pub(crate) mod sparse;
pub(crate) mod sparse_lstsq;

pub(crate) use lstsq::ConstrainedLstsq;
pub(crate) use lu::{ComplexLu, DenseLu, Pivoting, Singular};
pub(crate) use pattern_lu::PatternLu;

use nalgebra::DMatrix;

/// `out = m v` for a column-major `M × N` matrix `m` (`v` of length `N`,
/// `out` of length `M`), without allocating.
pub(crate) fn mat_vec(m: &DMatrix<f64>, v: &[f64], out: &mut [f64]) {
    let rows = out.len();
    let a = m.as_slice();
    with_size!(rows, |R| {
        let out = &mut out[..R];
        out.fill(0.0);
        for (j, &vj) in v.iter().enumerate() {
            let col = &a[j * R..(j + 1) * R];
            for i in 0..R {
                out[i] += col[i] * vj;
            }
        }
    })
}

/// `a + b` as `(s, e)` with `s = fl(a + b)` and `s + e = a + b` exactly
/// (Knuth's two-sum; no condition on the sizes of `a` and `b`, so a
/// component passing through zero is summed exactly too).
#[inline]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// Whether every entry of `v` is finite: `x · 0` is zero for a finite `x`
/// and NaN otherwise, so one multiplication and one addition per entry decide
/// it, without a branch per entry.
pub(crate) fn all_finite(v: &[f64]) -> bool {
    v.iter().fold(0.0, |acc, &x| acc + x * 0.0) == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mat_vec_of_a_rectangular_matrix() {
        let m = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let mut out = [7.0; 3];
        mat_vec(&m, &[1.0, -1.0], &mut out);
        assert_eq!(out, [-1.0, -1.0, -1.0]);
    }

    #[test]
    fn all_finite_sees_every_kind_of_non_finite_entry() {
        assert!(all_finite(&[]));
        assert!(all_finite(&[0.0, -1e308, 1e308, f64::MIN_POSITIVE]));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(!all_finite(&[1.0, bad, 2.0]));
            assert!(!all_finite(&[f64::INFINITY, bad]));
        }
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

//! Dense linear algebra in storage allocated once: the square LU
//! factorisation of the iteration matrices ([`lu`]), the constrained
//! least-squares solver of the overdetermined methods ([`lstsq`]), and the
//! matrix–vector product [`mat_vec`] that writes into a caller's buffer.

pub(crate) mod lstsq;
pub(crate) mod lu;

pub(crate) use lstsq::ConstrainedLstsq;
pub(crate) use lu::{DenseLu, Pivoting, Singular};

use nalgebra::DMatrix;

/// `out = m v` for a column-major `M × N` matrix `m` (`v` of length `N`,
/// `out` of length `M`), without allocating.
pub(crate) fn mat_vec(m: &DMatrix<f64>, v: &[f64], out: &mut [f64]) {
    let rows = out.len();
    let a = m.as_slice();
    out.fill(0.0);
    for (j, &vj) in v.iter().enumerate() {
        let col = &a[j * rows..(j + 1) * rows];
        for (o, &aij) in out.iter_mut().zip(col) {
            *o += aij * vj;
        }
    }
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
}

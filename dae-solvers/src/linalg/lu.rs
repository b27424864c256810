//! Dense LU factorisation with partial pivoting, in place in storage
//! allocated once.
//!
//! `nalgebra::LU::new` allocates on every call, which a step loop must not.
//! [`DenseLu`] owns an `N × N` column-major matrix and its pivots: the
//! caller writes the matrix ([`DenseLu::matrix_mut`], or
//! [`DenseLu::factor_from`] entry by entry), [`DenseLu::factor`] overwrites
//! it with its factors `P A = L U` (unit lower `L`, row interchanges applied
//! to whole rows, as LAPACK stores them), and [`DenseLu::solve`] solves with
//! them in place. The kernels [`factor_in_place`] and [`solve_in_place`]
//! work on storage the caller provides and never allocate. Both are generic
//! over the field: `f64`, and `Complex<f64>` for RADAU5's complex system,
//! pivoting on `|re| + |im|` as LINPACK's complex routines do.
//!
//! The two solvers of this crate factorise with different conventions,
//! chosen by [`Pivoting`]: the BDF solver follows DASSL's LINPACK routines
//! (`DGEFA`/`DGESL`, whose column layout gives the same floating-point
//! operations in the same order), RADAU5 refuses non-finite pivots as well.
//! Besides the singular pivots, the two differ only in skipping updates by
//! an exact zero, which can change a result only in the sign of a zero or
//! where an entry is infinite or NaN.

use nalgebra::{ComplexField, DMatrix};

/// The factorisation met a pivot that [`Pivoting`] counts as singular.
#[derive(Debug)]
pub(crate) struct Singular;

/// When a pivot is singular, and which updates are skipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pivoting {
    /// LINPACK's `DGEFA`/`DGESL`, as DASSL uses them: singular only when the
    /// largest candidate pivot is exactly zero (a NaN or infinite pivot is
    /// used); the elimination skips a column whose entry in the pivot row is
    /// zero, and forward substitution a zero component of the permuted
    /// right-hand side (`DAXPY` with a zero multiplier).
    Linpack,
    /// Singular when the largest candidate pivot is zero or not finite;
    /// every update is carried out.
    Checked,
}

/// LU factors with partial pivoting of an `N × N` matrix, in storage
/// allocated by [`DenseLu::new`] (see the [module documentation](self)).
pub(crate) struct DenseLu<F> {
    /// The matrix, then its factors: `U` on and above the diagonal, the
    /// multipliers of `L` below it.
    a: DMatrix<F>,
    /// Row interchanged with row `k` at elimination step `k`.
    piv: Vec<usize>,
    pivoting: Pivoting,
}

impl<F: ComplexField<RealField = f64> + Copy> DenseLu<F> {
    /// Storage for an `n × n` matrix (zero) and its pivots.
    pub(crate) fn new(n: usize, pivoting: Pivoting) -> Self {
        DenseLu {
            a: DMatrix::from_element(n, n, F::zero()),
            piv: vec![0; n],
            pivoting,
        }
    }

    /// The matrix to factorise; [`DenseLu::factor`] overwrites it.
    pub(crate) fn matrix_mut(&mut self) -> &mut DMatrix<F> {
        &mut self.a
    }

    /// Factorise the matrix in place, `P A = L U`.
    pub(crate) fn factor(&mut self) -> Result<(), Singular> {
        let n = self.piv.len();
        factor_in_place(self.a.as_mut_slice(), n, &mut self.piv, self.pivoting)
    }

    /// Overwrite the matrix with `entry(i, j)` and factorise it.
    pub(crate) fn factor_from(
        &mut self,
        mut entry: impl FnMut(usize, usize) -> F,
    ) -> Result<(), Singular> {
        let n = self.piv.len();
        for (j, col) in self.a.as_mut_slice().chunks_exact_mut(n.max(1)).enumerate() {
            for (i, a) in col.iter_mut().enumerate() {
                *a = entry(i, j);
            }
        }
        self.factor()
    }

    /// Solve `A x = b` in place with the factors of [`DenseLu::factor`].
    pub(crate) fn solve(&self, b: &mut [F]) {
        solve_in_place(self.a.as_slice(), &self.piv, b, self.pivoting);
    }
}

/// Factorise the `n × n` column-major matrix `a` in place, `P A = L U` with
/// unit lower `L` (row interchanges applied to whole rows); `piv[k]` is the
/// row interchanged with row `k` at step `k`. Stops at the first singular
/// pivot (see [`Pivoting`]), leaving `a` and `piv` partly factorised.
pub(crate) fn factor_in_place<F: ComplexField<RealField = f64> + Copy>(
    a: &mut [F],
    n: usize,
    piv: &mut [usize],
    pivoting: Pivoting,
) -> Result<(), Singular> {
    debug_assert!(a.len() == n * n && piv.len() == n);
    let skip_zeros = pivoting == Pivoting::Linpack;
    for k in 0..n {
        let ck = k * n;
        let mut p = k;
        let mut pmax = a[ck + k].norm1();
        for (i, v) in a[ck + k + 1..ck + n].iter().enumerate() {
            let v = v.norm1();
            if v > pmax {
                pmax = v;
                p = k + 1 + i;
            }
        }
        piv[k] = p;
        let singular = match pivoting {
            Pivoting::Linpack => pmax == 0.0,
            Pivoting::Checked => !(pmax > 0.0 && pmax.is_finite()),
        };
        if singular {
            return Err(Singular);
        }
        if p != k {
            for col in a.chunks_exact_mut(n) {
                col.swap(k, p);
            }
        }
        let inv = F::one() / a[ck + k];
        for l in &mut a[ck + k + 1..ck + n] {
            *l *= inv;
        }
        let (left, right) = a.split_at_mut(ck + n);
        let lcol = &left[ck + k + 1..];
        for col in right.chunks_exact_mut(n) {
            let akj = col[k];
            if skip_zeros && akj == F::zero() {
                continue;
            }
            for (c, &lik) in col[k + 1..].iter_mut().zip(lcol) {
                *c -= lik * akj;
            }
        }
    }
    Ok(())
}

/// Solve `A x = b` in place with the factors and pivots of
/// [`factor_in_place`] (with the same `pivoting`).
pub(crate) fn solve_in_place<F: ComplexField<RealField = f64> + Copy>(
    a: &[F],
    piv: &[usize],
    b: &mut [F],
    pivoting: Pivoting,
) {
    let n = piv.len();
    debug_assert!(a.len() == n * n && b.len() == n);
    let skip_zeros = pivoting == Pivoting::Linpack;
    for (k, &p) in piv.iter().enumerate() {
        b.swap(k, p);
    }
    for k in 0..n {
        let bk = b[k];
        if skip_zeros && bk == F::zero() {
            continue;
        }
        let lcol = &a[k * n + k + 1..(k + 1) * n];
        for (bi, &lik) in b[k + 1..].iter_mut().zip(lcol) {
            *bi -= lik * bk;
        }
    }
    for k in (0..n).rev() {
        b[k] /= a[k * n + k];
        let bk = b[k];
        for (bi, &uik) in b[..k].iter_mut().zip(&a[k * n..k * n + k]) {
            *bi -= uik * bk;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Complex;

    fn entry(i: usize, j: usize) -> f64 {
        ((i * 7 + j * 3) % 5) as f64 - 2.0 + if i == j { 0.5 } else { 0.0 }
    }

    #[test]
    fn lu_solves_real_and_complex_systems() {
        let n = 4;
        for pivoting in [Pivoting::Checked, Pivoting::Linpack] {
            let mut lu = DenseLu::<f64>::new(n, pivoting);
            lu.factor_from(entry).unwrap();
            let x: Vec<f64> = (0..n).map(|i| i as f64 - 1.5).collect();
            let mut b: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|j| entry(i, j) * x[j]).sum())
                .collect();
            lu.solve(&mut b);
            for (u, v) in b.iter().zip(&x) {
                assert!((u - v).abs() < 1e-12);
            }

            let centry =
                |i: usize, j: usize| Complex::new(entry(i, j), (i as f64) - (j as f64) * 0.3);
            let mut clu = DenseLu::<Complex<f64>>::new(n, pivoting);
            clu.factor_from(centry).unwrap();
            let cx: Vec<Complex<f64>> = (0..n)
                .map(|i| Complex::new(1.0 - i as f64, 0.25 * i as f64))
                .collect();
            let mut cb: Vec<Complex<f64>> = (0..n)
                .map(|i| (0..n).map(|j| centry(i, j) * cx[j]).sum())
                .collect();
            clu.solve(&mut cb);
            for (u, v) in cb.iter().zip(&cx) {
                assert!((u - v).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn singular_pivots_follow_the_convention() {
        for pivoting in [Pivoting::Checked, Pivoting::Linpack] {
            let mut lu = DenseLu::<f64>::new(2, pivoting);
            assert!(lu.factor_from(|i, _| i as f64).is_err());
            let nan = lu.factor_from(|_, _| f64::NAN);
            assert_eq!(nan.is_err(), pivoting == Pivoting::Checked);
            // The matrix as written, factorised in place.
            lu.matrix_mut().copy_from_slice(&[0.0, 2.0, 1.0, 3.0]);
            lu.factor().unwrap();
            let mut b = [1.0, 5.0];
            lu.solve(&mut b);
            assert_eq!(b, [1.0, 1.0]);
        }
    }

    /// DASSL's LINPACK layout (negated multipliers, interchanges applied
    /// column by column) and the LAPACK layout used here perform the same
    /// operations: the solutions agree to the bit.
    #[test]
    fn linpack_convention_matches_dgefa_dgesl_bit_for_bit() {
        fn dgefa_dgesl(a: &mut [f64], n: usize, b: &mut [f64]) -> bool {
            let mut piv = vec![0; n];
            for k in 0..n {
                let ck = k * n;
                let mut p = k;
                let mut amax = a[ck + k].abs();
                for i in k + 1..n {
                    if a[ck + i].abs() > amax {
                        amax = a[ck + i].abs();
                        p = i;
                    }
                }
                piv[k] = p;
                if amax == 0.0 {
                    return false;
                }
                a.swap(ck + p, ck + k);
                let t = -1.0 / a[ck + k];
                for v in &mut a[ck + k + 1..ck + n] {
                    *v *= t;
                }
                for j in k + 1..n {
                    a.swap(j * n + p, j * n + k);
                    let t = a[j * n + k];
                    if t != 0.0 {
                        for i in k + 1..n {
                            a[j * n + i] += t * a[ck + i];
                        }
                    }
                }
            }
            for k in 0..n {
                b.swap(piv[k], k);
                let t = b[k];
                if t != 0.0 {
                    for i in k + 1..n {
                        b[i] += t * a[k * n + i];
                    }
                }
            }
            for k in (0..n).rev() {
                b[k] /= a[k * n + k];
                let t = -b[k];
                for i in 0..k {
                    b[i] += t * a[k * n + i];
                }
            }
            true
        }
        let n = 7;
        let mut seed = 0x2545_f491_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 2001) as f64 / 1000.0 - 1.0
        };
        for trial in 0..200 {
            let mut a: Vec<f64> = (0..n * n).map(|_| next()).collect();
            // Some exact zeros, to exercise the skipped updates.
            for v in a.iter_mut().step_by(3 + trial % 4) {
                *v = 0.0;
            }
            let b: Vec<f64> = (0..n).map(|_| next()).collect();
            let mut reference = (a.clone(), b.clone());
            let ok = dgefa_dgesl(&mut reference.0, n, &mut reference.1);
            let mut lu = DenseLu::<f64>::new(n, Pivoting::Linpack);
            lu.matrix_mut().copy_from_slice(&a);
            assert_eq!(lu.factor().is_ok(), ok, "trial {trial}");
            if ok {
                let mut x = b.clone();
                lu.solve(&mut x);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&x), bits(&reference.1), "trial {trial}");
            }
        }
    }
}

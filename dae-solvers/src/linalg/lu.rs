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

use nalgebra::DMatrix;

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

impl Pivoting {
    fn singular(self, pmax: f64) -> bool {
        match self {
            Pivoting::Linpack => pmax == 0.0,
            Pivoting::Checked => !(pmax > 0.0 && pmax.is_finite()),
        }
    }
}

/// LU factors with partial pivoting of a real `N × N` matrix, in storage
/// allocated by [`DenseLu::new`] (see the [module documentation](self)).
pub(crate) struct DenseLu {
    /// The matrix, then its factors: `U` on and above the diagonal, the
    /// multipliers of `L` below it.
    a: DMatrix<f64>,
    /// Row interchanged with row `k` at elimination step `k`.
    piv: Vec<usize>,
    pivoting: Pivoting,
}

impl DenseLu {
    /// Storage for an `n × n` matrix (zero) and its pivots.
    pub(crate) fn new(n: usize, pivoting: Pivoting) -> Self {
        DenseLu {
            a: DMatrix::zeros(n, n),
            piv: vec![0; n],
            pivoting,
        }
    }

    /// The matrix to factorise; [`DenseLu::factor`] overwrites it.
    pub(crate) fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
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
        mut entry: impl FnMut(usize, usize) -> f64,
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
    pub(crate) fn solve(&self, b: &mut [f64]) {
        solve_in_place(self.a.as_slice(), &self.piv, b, self.pivoting);
    }
}

/// LU factors with partial pivoting of a complex `N × N` matrix kept as
/// two real arrays (real and imaginary parts, column-major): RADAU5's
/// complex system without a complex number type. The arithmetic is that of
/// `num_complex` operation for operation (products `(ac − bd) + i(ad +
/// bc)`, quotients through `|c|²`, pivots by `|re| + |im|` as LINPACK's
/// complex routines choose them), so the factors are those of a
/// `Complex<f64>` elimination to the bit — a test checks this. Pivots
/// follow [`Pivoting::Checked`] (the only user is Radau IIA).
pub(crate) struct ComplexLu {
    re: Vec<f64>,
    im: Vec<f64>,
    piv: Vec<usize>,
}

impl ComplexLu {
    /// Storage for an `n × n` matrix (zero) and its pivots.
    pub(crate) fn new(n: usize) -> Self {
        ComplexLu {
            re: vec![0.0; n * n],
            im: vec![0.0; n * n],
            piv: vec![0; n],
        }
    }

    /// The real and imaginary parts to write (column-major) before
    /// [`ComplexLu::factor`].
    pub(crate) fn parts_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        (&mut self.re, &mut self.im)
    }

    /// Factorise the matrix in place, `P A = L U`.
    pub(crate) fn factor(&mut self) -> Result<(), Singular> {
        let n = self.piv.len();
        with_size!(n, |N| complex_factor(
            &mut self.re[..N * N],
            &mut self.im[..N * N],
            &mut self.piv[..N],
            N
        ))
    }

    /// Overwrite the matrix with `entry(i, j) = (re, im)` and factorise it.
    #[cfg(test)]
    pub(crate) fn factor_from(
        &mut self,
        mut entry: impl FnMut(usize, usize) -> (f64, f64),
    ) -> Result<(), Singular> {
        let n = self.piv.len();
        for j in 0..n {
            for i in 0..n {
                (self.re[j * n + i], self.im[j * n + i]) = entry(i, j);
            }
        }
        self.factor()
    }

    /// Solve `A x = b` in place, `b = re + i im` (length `N` each).
    pub(crate) fn solve(&self, re: &mut [f64], im: &mut [f64]) {
        let n = self.piv.len();
        with_size!(n, |N| complex_solve(
            &self.re[..N * N],
            &self.im[..N * N],
            &self.piv[..N],
            &mut re[..N],
            &mut im[..N],
            N
        ))
    }
}

/// Factorise the `n × n` column-major matrix `a` in place, `P A = L U` with
/// unit lower `L` (row interchanges applied to whole rows); `piv[k]` is the
/// row interchanged with row `k` at step `k`. Stops at the first singular
/// pivot (see [`Pivoting`]), leaving `a` and `piv` partly factorised.
pub(crate) fn factor_in_place(
    a: &mut [f64],
    n: usize,
    piv: &mut [usize],
    pivoting: Pivoting,
) -> Result<(), Singular> {
    debug_assert!(a.len() == n * n && piv.len() == n);
    with_size!(n, |N| real_factor(
        &mut a[..N * N],
        &mut piv[..N],
        N,
        pivoting
    ))
}

#[inline(always)]
fn real_factor(
    a: &mut [f64],
    piv: &mut [usize],
    n: usize,
    pivoting: Pivoting,
) -> Result<(), Singular> {
    let skip_zeros = pivoting == Pivoting::Linpack;
    for k in 0..n {
        let ck = k * n;
        let mut p = k;
        let mut pmax = a[ck + k].abs();
        for i in k + 1..n {
            let v = a[ck + i].abs();
            if v > pmax {
                pmax = v;
                p = i;
            }
        }
        piv[k] = p;
        if pivoting.singular(pmax) {
            return Err(Singular);
        }
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let inv = 1.0 / a[ck + k];
        for i in k + 1..n {
            a[ck + i] *= inv;
        }
        for j in k + 1..n {
            let cj = j * n;
            let akj = a[cj + k];
            if skip_zeros && akj == 0.0 {
                continue;
            }
            for i in k + 1..n {
                a[cj + i] -= a[ck + i] * akj;
            }
        }
    }
    Ok(())
}

/// Solve `A x = b` in place with the factors and pivots of
/// [`factor_in_place`] (with the same `pivoting`).
pub(crate) fn solve_in_place(a: &[f64], piv: &[usize], b: &mut [f64], pivoting: Pivoting) {
    let n = piv.len();
    debug_assert!(a.len() == n * n && b.len() == n);
    with_size!(n, |N| real_solve(
        &a[..N * N],
        &piv[..N],
        &mut b[..N],
        N,
        pivoting
    ))
}

#[inline(always)]
fn real_solve(a: &[f64], piv: &[usize], b: &mut [f64], n: usize, pivoting: Pivoting) {
    let skip_zeros = pivoting == Pivoting::Linpack;
    for (k, &p) in piv[..n].iter().enumerate() {
        b.swap(k, p);
    }
    for k in 0..n {
        let bk = b[k];
        if skip_zeros && bk == 0.0 {
            continue;
        }
        for i in k + 1..n {
            b[i] -= a[k * n + i] * bk;
        }
    }
    for k in (0..n).rev() {
        b[k] /= a[k * n + k];
        let bk = b[k];
        for i in 0..k {
            b[i] -= a[k * n + i] * bk;
        }
    }
}

/// `1 / (c + i d)` as `num_complex` computes it.
#[inline(always)]
fn complex_recip(c: f64, d: f64) -> (f64, f64) {
    let norm_sqr = c * c + d * d;
    let re = 1.0 * c + 0.0 * d;
    let im = 0.0 * c - 1.0 * d;
    (re / norm_sqr, im / norm_sqr)
}

/// `(a + i b)(c + i d)` as `num_complex` computes it.
#[inline(always)]
fn complex_mul(a: f64, b: f64, c: f64, d: f64) -> (f64, f64) {
    (a * c - b * d, a * d + b * c)
}

#[inline(always)]
fn complex_factor(
    re: &mut [f64],
    im: &mut [f64],
    piv: &mut [usize],
    n: usize,
) -> Result<(), Singular> {
    for k in 0..n {
        let ck = k * n;
        let mut p = k;
        let mut pmax = re[ck + k].abs() + im[ck + k].abs();
        for i in k + 1..n {
            let v = re[ck + i].abs() + im[ck + i].abs();
            if v > pmax {
                pmax = v;
                p = i;
            }
        }
        piv[k] = p;
        if Pivoting::Checked.singular(pmax) {
            return Err(Singular);
        }
        if p != k {
            for j in 0..n {
                re.swap(j * n + k, j * n + p);
                im.swap(j * n + k, j * n + p);
            }
        }
        let (ir, ii) = complex_recip(re[ck + k], im[ck + k]);
        for i in k + 1..n {
            (re[ck + i], im[ck + i]) = complex_mul(re[ck + i], im[ck + i], ir, ii);
        }
        for j in k + 1..n {
            let cj = j * n;
            let (ar, ai) = (re[cj + k], im[cj + k]);
            for i in k + 1..n {
                let (pr, pi) = complex_mul(re[ck + i], im[ck + i], ar, ai);
                re[cj + i] -= pr;
                im[cj + i] -= pi;
            }
        }
    }
    Ok(())
}

#[inline(always)]
fn complex_solve(re: &[f64], im: &[f64], piv: &[usize], br: &mut [f64], bi: &mut [f64], n: usize) {
    for (k, &p) in piv[..n].iter().enumerate() {
        br.swap(k, p);
        bi.swap(k, p);
    }
    for k in 0..n {
        let (xr, xi) = (br[k], bi[k]);
        for i in k + 1..n {
            let (pr, pi) = complex_mul(re[k * n + i], im[k * n + i], xr, xi);
            br[i] -= pr;
            bi[i] -= pi;
        }
    }
    for k in (0..n).rev() {
        let (c, d) = (re[k * n + k], im[k * n + k]);
        let norm_sqr = c * c + d * d;
        let (xr, xi) = (br[k], bi[k]);
        let (xr, xi) = ((xr * c + xi * d) / norm_sqr, (xi * c - xr * d) / norm_sqr);
        br[k] = xr;
        bi[k] = xi;
        for i in 0..k {
            let (pr, pi) = complex_mul(re[k * n + i], im[k * n + i], xr, xi);
            br[i] -= pr;
            bi[i] -= pi;
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
        for n in [1, 4, 5, 13] {
            for pivoting in [Pivoting::Checked, Pivoting::Linpack] {
                let mut lu = DenseLu::new(n, pivoting);
                lu.factor_from(entry).unwrap();
                let x: Vec<f64> = (0..n).map(|i| i as f64 - 1.5).collect();
                let mut b: Vec<f64> = (0..n)
                    .map(|i| (0..n).map(|j| entry(i, j) * x[j]).sum())
                    .collect();
                lu.solve(&mut b);
                for (u, v) in b.iter().zip(&x) {
                    assert!((u - v).abs() < 1e-11, "n = {n}: {u} vs {v}");
                }

                let centry =
                    |i: usize, j: usize| Complex::new(entry(i, j), (i as f64) - (j as f64) * 0.3);
                let mut clu = ComplexLu::new(n);
                clu.factor_from(|i, j| (centry(i, j).re, centry(i, j).im))
                    .unwrap();
                let cx: Vec<Complex<f64>> = (0..n)
                    .map(|i| Complex::new(1.0 - i as f64, 0.25 * i as f64))
                    .collect();
                let cb: Vec<Complex<f64>> = (0..n)
                    .map(|i| (0..n).map(|j| centry(i, j) * cx[j]).sum())
                    .collect();
                let mut re: Vec<f64> = cb.iter().map(|z| z.re).collect();
                let mut im: Vec<f64> = cb.iter().map(|z| z.im).collect();
                clu.solve(&mut re, &mut im);
                for ((u, w), v) in re.iter().zip(&im).zip(&cx) {
                    assert!((Complex::new(*u, *w) - v).norm() < 1e-11, "n = {n}");
                }
            }
        }
    }

    /// The split-storage complex elimination performs `num_complex`'s
    /// operations in the same order as an elimination on `Complex<f64>`
    /// (the kernel RADAU5's complex system used before): the factors and
    /// solutions agree to the bit, for every size the kernels specialise
    /// and one beyond.
    #[test]
    fn complex_kernel_matches_a_complex_number_elimination_bit_for_bit() {
        fn reference(a: &mut [Complex<f64>], n: usize, b: &mut [Complex<f64>]) -> bool {
            let mut piv = vec![0; n];
            for k in 0..n {
                let ck = k * n;
                let mut p = k;
                let mut pmax = a[ck + k].re.abs() + a[ck + k].im.abs();
                for i in k + 1..n {
                    let v = a[ck + i].re.abs() + a[ck + i].im.abs();
                    if v > pmax {
                        pmax = v;
                        p = i;
                    }
                }
                piv[k] = p;
                if !(pmax > 0.0 && pmax.is_finite()) {
                    return false;
                }
                for j in 0..n {
                    a.swap(j * n + k, j * n + p);
                }
                let inv = Complex::new(1.0, 0.0) / a[ck + k];
                for i in k + 1..n {
                    a[ck + i] *= inv;
                }
                for j in k + 1..n {
                    let akj = a[j * n + k];
                    for i in k + 1..n {
                        let l = a[ck + i];
                        a[j * n + i] -= l * akj;
                    }
                }
            }
            for (k, &p) in piv.iter().enumerate() {
                b.swap(k, p);
            }
            for k in 0..n {
                let bk = b[k];
                for i in k + 1..n {
                    b[i] -= a[k * n + i] * bk;
                }
            }
            for k in (0..n).rev() {
                b[k] /= a[k * n + k];
                let bk = b[k];
                for i in 0..k {
                    b[i] -= a[k * n + i] * bk;
                }
            }
            true
        }
        let mut seed = 0x9e37_79b9_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 20001) as f64 / 10000.0 - 1.0
        };
        for n in 1..=13 {
            for trial in 0..20 {
                let a: Vec<Complex<f64>> =
                    (0..n * n).map(|_| Complex::new(next(), next())).collect();
                let b: Vec<Complex<f64>> = (0..n).map(|_| Complex::new(next(), next())).collect();
                let (mut ra, mut rb) = (a.clone(), b.clone());
                let ok = reference(&mut ra, n, &mut rb);
                let mut lu = ComplexLu::new(n);
                assert_eq!(
                    lu.factor_from(|i, j| (a[j * n + i].re, a[j * n + i].im))
                        .is_ok(),
                    ok
                );
                if !ok {
                    continue;
                }
                let bits = |v: f64| v.to_bits();
                for (z, (r, i)) in ra.iter().zip(lu.re.iter().zip(&lu.im)) {
                    assert_eq!(
                        (bits(z.re), bits(z.im)),
                        (bits(*r), bits(*i)),
                        "n {n} #{trial}"
                    );
                }
                let mut re: Vec<f64> = b.iter().map(|z| z.re).collect();
                let mut im: Vec<f64> = b.iter().map(|z| z.im).collect();
                lu.solve(&mut re, &mut im);
                for (z, (r, i)) in rb.iter().zip(re.iter().zip(&im)) {
                    assert_eq!(
                        (bits(z.re), bits(z.im)),
                        (bits(*r), bits(*i)),
                        "n {n} #{trial}"
                    );
                }
            }
        }
    }

    #[test]
    fn singular_pivots_follow_the_convention() {
        for pivoting in [Pivoting::Checked, Pivoting::Linpack] {
            let mut lu = DenseLu::new(2, pivoting);
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
            let mut lu = DenseLu::new(n, Pivoting::Linpack);
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

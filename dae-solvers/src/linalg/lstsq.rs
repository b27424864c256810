//! Equality-constrained, weighted linear least squares in storage allocated
//! once: the Newton corrector of the overdetermined methods.
//!
//! # Problem
//!
//! The overdetermined BDF and Radau methods (in the manner of ODASSL and
//! QUALIDAES) iterate on an `M × N` system `A δ = b` with `M ≥ N`. Some of
//! its rows, the *exact* rows (the constraints of the DAE), must hold
//! exactly; the others are satisfied in a weighted least-squares sense.
//! With `C` the `p` exact rows of `A`, `D` the `q = M − p` others,
//! `b = (b_C, b_D)` split alike and `S = diag(s_i)` the positive weights of
//! the rows of `D`, [`ConstrainedLstsq`] solves the LSE problem
//!
//! ```text
//!     minimise ‖S (D δ − b_D)‖₂   subject to   C δ = b_C .
//! ```
//!
//! It has a unique solution exactly when `C` has full row rank `p` and `S D`
//! has full column rank on the null space of `C` (which needs `p ≤ N` and
//! `q ≥ N − p`, hence `M ≥ N`). For a square nonsingular `A` that solution
//! is `A⁻¹ b`, whatever the weights and whichever rows are exact: the
//! minimum is then zero.
//!
//! # Method: the null-space method with Householder QR
//!
//! 1. Householder QR of the transposed constraints,
//!    `Cᵀ = Q [R; 0]` with `Q = H₁ ⋯ H_p` orthogonal (`N × N`) and `R`
//!    upper triangular (`p × p`). With `δ = Q [u; v]` (`u` of length `p`,
//!    `v` of length `N − p`), the constraints read `Rᵀ u = b_C`: they fix
//!    `u` and leave `v` free.
//! 2. The weighted rows in the new unknowns, `S D Q = [D₁ D₂]` (`D₁` of
//!    `p` columns, `D₂` of `N − p`; the reflectors `H_k` are applied to the
//!    rows of `S D`), and the Householder QR `D₂ = P [T; 0]` with `T`
//!    upper triangular (`(N − p) × (N − p)`).
//! 3. Solution:
//!
//! ```text
//!     Rᵀ u = b_C                                   (forward substitution)
//!     r    = S b_D − D₁ u
//!     T v  = (Pᵀ r)[..N − p]                        (back substitution)
//!     δ    = Q [u; v] .
//! ```
//!
//! The objective is `‖D₁ u + D₂ v − S b_D‖₂ = ‖D₂ v − r‖₂`, a plain least
//! squares problem in `v`, minimised by step 3. The residual of the weighted
//! rows is then orthogonal to the range of `D₂`, i.e. `(S D)ᵀ S (D δ − b_D)`
//! lies in the range of `Cᵀ`: the optimality condition of the LSE problem,
//! with Lagrange multipliers. No normal equations are formed, so the
//! conditioning is that of `C` and of `D₂`, not their squares.
//!
//! [`ConstrainedLstsq::factor`] carries out steps 1 and 2 (the exact rows
//! may be anywhere in `A` and may change from one factorisation to the
//! next; they are gathered through index arrays), [`ConstrainedLstsq::solve`]
//! step 3, for any number of right-hand sides. Neither allocates.
//!
//! # Rank test
//!
//! [`ConstrainedLstsq::factor`] returns [`Singular`] when `p > N`, when
//! `q < N − p`, when an entry of `A` or the weight of a weighted row is not
//! finite or a weight is not positive, and when a diagonal entry of `R` or of
//! `T` is zero, not finite, or not above
//!
//! ```text
//!     N ε ‖c_k‖          (resp. N ε ‖d_k‖) ,
//! ```
//!
//! `c_k` being the `k`-th constraint row, `d_k` the `k`-th column of `D₂`
//! before its QR, and `ε` the machine epsilon. `|R_kk|` is the part of `c_k`
//! orthogonal to the rows before it and is judged against `c_k` itself, and
//! likewise `|T_kk|` against `d_k`: the test does not see how a constraint
//! row, or a column of `D₂`, is scaled (an iteration matrix `c E − J` has
//! columns of size `1/h` beside columns of size one, and an `h` of 1e-15
//! must not make it "singular"). The QR factorisations do not pivot, so the
//! test is not rank-revealing in general: it catches exact and
//! round-off-level dependence (repeated or zero constraint rows, unknowns
//! absent from every row), while an ill-conditioned but numerically
//! full-rank system goes through and shows in large, inaccurate solutions,
//! which the Newton iteration's convergence test detects; as a
//! round-off-sized pivot passes [`super::DenseLu`].
//!
//! # Cost
//!
//! With `k = N − p`, factorisation takes about
//! `2p²(N − p/3) + 4pqN + 2k²(q − k/3)` flops besides the `O(MN)` gathering:
//! for a square `A`, `N³(4/3 + 2t² − 2t³)` with `t = p/N`, between `4N³/3`
//! (no or only exact rows) and `44N³/27 ≈ 1.63N³` (`t = 2/3`), against
//! `2N³/3` for LU. A solve takes `O(MN)`, about
//! `p² + 2qp + 4qk + k² + 4pN` flops.

use super::Singular;
use nalgebra::DMatrix;

/// Factorisation of an `M × N` equality-constrained weighted least-squares
/// problem, in storage allocated by [`ConstrainedLstsq::new`] (see the
/// [module documentation](self)).
pub(crate) struct ConstrainedLstsq {
    m: usize,
    n: usize,
    /// The matrix `A`, written by the caller.
    a: DMatrix<f64>,
    /// `N × p` column-major (leading dimension `N`, room for `p = N`): `Cᵀ`,
    /// then `R` on and above the diagonal and the reflectors `H_k` below it
    /// (the unit first entry implicit).
    ct: Vec<f64>,
    /// The scalars `τ_k` of `H_k = I − τ_k v_k v_kᵀ` for `Cᵀ`.
    tau_c: Vec<f64>,
    /// `q × N` column-major (leading dimension `q`, room for `q = M`):
    /// `S D`, then `[D₁ D₂]`, then `D₁` and the QR factors of `D₂` (`T` and
    /// the reflectors of `P`) in the same layout as `ct`.
    sd: Vec<f64>,
    /// The scalars `τ_k` of the reflectors of `P`.
    tau_d: Vec<f64>,
    /// Rows of `A` that are exact (the first `p` entries).
    exact_rows: Vec<usize>,
    /// Rows of `A` that are weighted (the first `q` entries) ...
    weighted_rows: Vec<usize>,
    /// ... and their weights.
    row_weight: Vec<f64>,
    /// Length `M + N`: a row of `S D` times a reflector while factorising; `u`
    /// then `r` while solving.
    work: Vec<f64>,
    /// Number of exact rows of the current factorisation, the held
    /// combinations included (see [`ConstrainedLstsq::factor`]) ...
    p: usize,
    /// ... of which rows of `A` (the first `p_rows`); the others are the
    /// combinations `held` (`(p − p_rows) × q`, row-major, in the order of
    /// `weighted_rows`).
    p_rows: usize,
    held: Vec<f64>,
    /// Number of weighted rows of the current factorisation.
    q: usize,
    /// Norms of the columns of a factor before its QR (the rank test).
    norms: Vec<f64>,
    /// Whether the last [`ConstrainedLstsq::factor`] succeeded.
    factored: bool,
}

impl ConstrainedLstsq {
    /// Storage for an `m × n` system (zero). `m ≥ n ≥ 1` is the intended
    /// use; with `m < n` every [`ConstrainedLstsq::factor`] fails.
    pub(crate) fn new(m: usize, n: usize) -> Self {
        ConstrainedLstsq {
            m,
            n,
            a: DMatrix::zeros(m, n),
            ct: vec![0.0; n * n],
            tau_c: vec![0.0; n],
            sd: vec![0.0; m * n],
            tau_d: vec![0.0; n],
            exact_rows: vec![0; m],
            weighted_rows: vec![0; m],
            row_weight: vec![0.0; m],
            work: vec![0.0; m + n],
            norms: vec![0.0; n],
            p: 0,
            p_rows: 0,
            held: Vec::new(),
            q: 0,
            factored: false,
        }
    }

    /// The `M × N` matrix `A` to factorise. [`ConstrainedLstsq::factor`]
    /// consumes it: write it anew before each factorisation.
    pub(crate) fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        &mut self.a
    }

    /// Factorise `A` (see the [module documentation](self)): rows `i` with
    /// `exact[i]` are held exactly, every other row is weighted by
    /// `weight[i]` (positive and finite; the weights of exact rows are
    /// ignored). Fails with [`Singular`] as the module documentation
    /// details, after which [`ConstrainedLstsq::solve`] returns NaN.
    ///
    /// # Panics
    ///
    /// If `exact` or `weight` is not of length `M`.
    ///
    /// With `held` non-empty, the combinations of the weighted rows it
    /// holds are held exactly besides: each a row `v` of `held` (`r × q`
    /// row-major, `q` the number of weighted rows, in their order in `A`),
    /// the constraint `vᵀ D δ = vᵀ b_D`; the weighted rows stay in the
    /// objective. Fails with [`Singular`] also when the exact rows and the
    /// combinations number more than `N`, or when `held` is not a whole
    /// number of rows of length `q`.
    pub(crate) fn factor(
        &mut self,
        exact: &[bool],
        weight: &[f64],
        held: &[f64],
    ) -> Result<(), Singular> {
        let (m, n) = (self.m, self.n);
        assert!(
            exact.len() == m && weight.len() == m,
            "ConstrainedLstsq::factor: exact and weight must have one entry per row"
        );
        self.factored = false;
        if !super::all_finite(self.a.as_slice()) {
            return Err(Singular);
        }

        let (p, q) = split_rows(
            exact,
            weight,
            n,
            &mut self.exact_rows,
            &mut self.weighted_rows,
            &mut self.row_weight,
        )?;
        let r = if held.is_empty() {
            0
        } else if q > 0 && held.len().is_multiple_of(q) {
            held.len() / q
        } else {
            return Err(Singular);
        };
        let p_rows = p;
        let p = p_rows + r;
        if p > n {
            return Err(Singular);
        }
        (self.p, self.p_rows, self.q) = (p, p_rows, q);
        self.held.clear();
        self.held.extend_from_slice(held);
        let a = self.a.as_slice();

        // Step 1: Cᵀ = Q [R; 0], the exact rows of A then the held
        // combinations of its weighted rows.
        let ct = &mut self.ct[..n * p];
        let (ct_rows, ct_held) = ct.split_at_mut(n * p_rows);
        for (col, &i) in ct_rows.chunks_exact_mut(n).zip(&self.exact_rows[..p_rows]) {
            for (j, c) in col.iter_mut().enumerate() {
                *c = a[j * m + i];
            }
        }
        for (col, v) in ct_held.chunks_exact_mut(n).zip(held.chunks_exact(q.max(1))) {
            for (j, c) in col.iter_mut().enumerate() {
                let aj = &a[j * m..(j + 1) * m];
                *c = v
                    .iter()
                    .zip(&self.weighted_rows[..q])
                    .map(|(&v, &i)| v * aj[i])
                    .sum();
            }
        }
        column_norms(ct, n, &mut self.norms[..p]);
        householder_qr(ct, n, p, &mut self.tau_c[..p]);
        if !full_rank(ct, n, &self.norms[..p], n) {
            return Err(Singular);
        }

        // Step 2: S D Q = [D₁ D₂], then D₂ = P [T; 0].
        let sd = &mut self.sd[..q * n];
        if q > 0 {
            for (j, col) in sd.chunks_exact_mut(q).enumerate() {
                let aj = &a[j * m..(j + 1) * m];
                for ((s, &i), &w) in col
                    .iter_mut()
                    .zip(&self.weighted_rows[..q])
                    .zip(&self.row_weight[..q])
                {
                    *s = w * aj[i];
                }
            }
            // S D ← S D H_k for k = 1, …, p: with y = S D v_k,
            // S D ← S D − τ_k y v_kᵀ, on columns k.. only.
            let y = &mut self.work[..q];
            for (k, &tau) in self.tau_c[..p].iter().enumerate() {
                if tau == 0.0 {
                    continue;
                }
                let v = &ct[k * n + k + 1..(k + 1) * n];
                let cols = &mut sd[k * q..];
                let (first, rest) = cols.split_at_mut(q);
                y.copy_from_slice(first);
                for (col, &vj) in rest.chunks_exact(q).zip(v) {
                    axpy(vj, col, y);
                }
                axpy(-tau, y, first);
                for (col, &vj) in rest.chunks_exact_mut(q).zip(v) {
                    axpy(-tau * vj, y, col);
                }
            }
        }
        let k = n - p;
        let d2 = &mut sd[p * q..];
        column_norms(d2, q, &mut self.norms[..k]);
        householder_qr(d2, q, k, &mut self.tau_d[..k]);
        if !full_rank(d2, q, &self.norms[..k], n) {
            return Err(Singular);
        }
        self.factored = true;
        Ok(())
    }

    /// Solve in place with the factors of [`ConstrainedLstsq::factor`]: on
    /// entry `b[..M]` is the right-hand side (in the row order of `A`), on
    /// exit `b[..N]` is the solution `δ` and `b[N..M]` is garbage. Does not
    /// allocate. After a failed (or without a) factorisation, fills `b` with
    /// NaN.
    pub(crate) fn solve(&mut self, b: &mut [f64]) {
        let (m, n, p, q) = (self.m, self.n, self.p, self.q);
        if !self.factored {
            b.fill(f64::NAN);
            return;
        }
        debug_assert!(b.len() >= m);
        let k = n - p;
        let (u, r) = self.work.split_at_mut(p);
        let r = &mut r[..q];
        let p_rows = self.p_rows;
        for (uj, &i) in u.iter_mut().zip(&self.exact_rows[..p_rows]) {
            *uj = b[i];
        }
        for (uj, v) in u[p_rows..].iter_mut().zip(self.held.chunks_exact(q.max(1))) {
            *uj = v
                .iter()
                .zip(&self.weighted_rows[..q])
                .map(|(&v, &i)| v * b[i])
                .sum();
        }
        for ((ri, &i), &w) in r
            .iter_mut()
            .zip(&self.weighted_rows[..q])
            .zip(&self.row_weight[..q])
        {
            *ri = w * b[i];
        }

        // Rᵀ u = b_C: row j of Rᵀ is column j of R.
        for j in 0..p {
            let col = &self.ct[j * n..j * n + j + 1];
            u[j] = (u[j] - dot(&col[..j], &u[..j])) / col[j];
        }

        // r = S b_D − D₁ u, then Pᵀ r.
        for (col, &uj) in self.sd[..p * q].chunks_exact(q.max(1)).zip(u.iter()) {
            axpy(-uj, col, r);
        }
        let d2 = &self.sd[p * q..n * q];
        for (j, &tau) in self.tau_d[..k].iter().enumerate() {
            let col = &d2[j * q..(j + 1) * q];
            reflect(&col[j + 1..], tau, &mut r[j..]);
        }

        // T v = (Pᵀ r)[..k], column by column.
        for j in (0..k).rev() {
            let col = &d2[j * q..j * q + j + 1];
            r[j] /= col[j];
            let vj = r[j];
            axpy(-vj, &col[..j], &mut r[..j]);
        }

        // δ = Q [u; v] = H₁ (H₂ ( ⋯ H_p [u; v])).
        let x = &mut b[..n];
        x[..p].copy_from_slice(u);
        x[p..].copy_from_slice(&r[..k]);
        for (j, &tau) in self.tau_c[..p].iter().enumerate().rev() {
            let col = &self.ct[j * n..(j + 1) * n];
            reflect(&col[j + 1..], tau, &mut x[j..]);
        }
    }
}

/// Split the rows of an `M × N` system by `exact`: the indices of the exact
/// rows into `exact_rows`, those of the weighted rows into `weighted_rows`
/// and their weights into `row_weight`; returns their numbers `(p, q)`.
/// Fails with [`Singular`] when a weight of a weighted row is not positive
/// and finite, when `p > N`, or when `p + q < N`.
pub(crate) fn split_rows(
    exact: &[bool],
    weight: &[f64],
    n: usize,
    exact_rows: &mut [usize],
    weighted_rows: &mut [usize],
    row_weight: &mut [f64],
) -> Result<(usize, usize), Singular> {
    let (mut p, mut q) = (0, 0);
    for (i, (&e, &w)) in exact.iter().zip(weight).enumerate() {
        if e {
            exact_rows[p] = i;
            p += 1;
        } else {
            if !(w > 0.0 && w.is_finite()) {
                return Err(Singular);
            }
            weighted_rows[q] = i;
            row_weight[q] = w;
            q += 1;
        }
    }
    if p > n || p + q < n {
        return Err(Singular);
    }
    Ok((p, q))
}

/// An orthonormal basis of the null space of the `p × n` matrix `C`, given
/// as `Cᵀ` in `ct` (`n × p` column-major, overwritten by its QR factors):
/// the last `n − p` columns of `Q` in `Cᵀ = Q [R; 0]`, written to `z`
/// (`n × (n − p)` column-major). `tau` and `norms` are workspaces of length
/// at least `p`. Fails with [`Singular`] when `p > n`, when an entry is not
/// finite, or when `C` fails the rank test of the
/// [module documentation](self). Does not allocate.
pub(crate) fn null_space(
    ct: &mut [f64],
    n: usize,
    p: usize,
    tau: &mut [f64],
    norms: &mut [f64],
    z: &mut [f64],
) -> Result<(), Singular> {
    if p > n || ct[..n * p].iter().any(|v| !v.is_finite()) {
        return Err(Singular);
    }
    let ct = &mut ct[..n * p];
    column_norms(ct, n, &mut norms[..p]);
    householder_qr(ct, n, p, &mut tau[..p]);
    if !full_rank(ct, n, &norms[..p], n) {
        return Err(Singular);
    }
    // Column l of Z is Q e_{p+l} = H₁ (H₂ ( ⋯ H_p e_{p+l})).
    for (l, col) in z[..n * (n - p)].chunks_exact_mut(n).enumerate() {
        col.fill(0.0);
        col[p + l] = 1.0;
        for (j, &t) in tau[..p].iter().enumerate().rev() {
            let v = &ct[j * n..(j + 1) * n];
            reflect(&v[j + 1..], t, &mut col[j..]);
        }
    }
    Ok(())
}

/// Solve the problem of the [module documentation](self) for one
/// right-hand side, allocating: a convenience for tests and initialisation.
///
/// # Panics
///
/// If `exact`, `weight` or `b` does not have one entry per row of `a`.
#[cfg(test)]
pub(crate) fn lstsq(
    a: &DMatrix<f64>,
    exact: &[bool],
    weight: &[f64],
    b: &[f64],
) -> Result<Vec<f64>, Singular> {
    let (m, n) = a.shape();
    assert!(b.len() == m, "lstsq: b must have one entry per row of a");
    let mut ls = ConstrainedLstsq::new(m, n);
    ls.matrix_mut().copy_from(a);
    ls.factor(exact, weight, &[])?;
    let mut x = b.to_vec();
    ls.solve(&mut x);
    x.truncate(n);
    Ok(x)
}

/// Householder QR in place of the `rows × cols` column-major matrix `a`
/// (leading dimension `rows`, `cols ≤ rows`): `R` on and above the diagonal,
/// the reflectors below it, their scalars in `tau`.
fn householder_qr(a: &mut [f64], rows: usize, cols: usize, tau: &mut [f64]) {
    debug_assert!(cols <= rows && a.len() >= rows * cols && tau.len() == cols);
    for (k, tk) in tau.iter_mut().enumerate() {
        let (left, right) = a[..rows * cols].split_at_mut((k + 1) * rows);
        let col = &mut left[k * rows + k..];
        *tk = reflector(col);
        let v = &col[1..];
        for cj in right.chunks_exact_mut(rows) {
            reflect(v, *tk, &mut cj[k..]);
        }
    }
}

/// Turn `x` into the reflector `H = I − τ v vᵀ` with `v = (1, x[1..])` and
/// `H x = (β, 0, …, 0)`, storing `β` in `x[0]` and returning `τ` (as LAPACK's
/// `DLARFG`: `τ = 0`, `H = I` when `x[1..]` is zero).
fn reflector(x: &mut [f64]) -> f64 {
    let Some((head, tail)) = x.split_first_mut() else {
        return 0.0;
    };
    let alpha = *head;
    let tail_norm = norm2(tail);
    if tail_norm == 0.0 {
        return 0.0;
    }
    let beta = -alpha.signum() * alpha.hypot(tail_norm);
    // |α − β| = |α| + ‖x[1..]‖: no cancellation.
    let scale = 1.0 / (alpha - beta);
    for v in tail.iter_mut() {
        *v *= scale;
    }
    *head = beta;
    (beta - alpha) / beta
}

/// `y ← (I − τ v vᵀ) y` with `v = (1, v_tail)`.
fn reflect(v_tail: &[f64], tau: f64, y: &mut [f64]) {
    if tau == 0.0 {
        return;
    }
    let Some((y0, y_tail)) = y.split_first_mut() else {
        return;
    };
    let s = tau * (*y0 + dot(v_tail, y_tail));
    *y0 -= s;
    axpy(-s, v_tail, y_tail);
}

/// Whether the diagonal of the upper triangle of `a` (leading dimension
/// `ld`, one column per entry of `norms`, the column norms before the QR)
/// passes the rank test of the module documentation, with `n` unknowns.
fn full_rank(a: &[f64], ld: usize, norms: &[f64], n: usize) -> bool {
    norms.iter().enumerate().all(|(j, &nu)| {
        let d = a[j * ld + j].abs();
        d.is_finite() && d > n as f64 * f64::EPSILON * nu
    })
}

/// Euclidean norms of the `norms.len()` columns (leading dimension `ld`)
/// of `a`.
fn column_norms(a: &[f64], ld: usize, norms: &mut [f64]) {
    for (nu, col) in norms.iter_mut().zip(a.chunks_exact(ld.max(1))) {
        *nu = col.iter().map(|v| v * v).sum::<f64>().sqrt();
    }
}

/// Euclidean norm, scaled against overflow and underflow.
fn norm2(x: &[f64]) -> f64 {
    let amax = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if amax == 0.0 || !amax.is_finite() {
        return amax;
    }
    let inv = 1.0 / amax;
    amax * x.iter().map(|v| (v * inv) * (v * inv)).sum::<f64>().sqrt()
}

fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// `y ← y + α x`.
fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, &xi) in y.iter_mut().zip(x) {
        *yi += alpha * xi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;
    use proptest::collection::vec;
    use proptest::prelude::*;

    /// Deterministic pseudo-random numbers in `[-1, 1]`.
    fn rng(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 20_001) as f64 / 10_000.0 - 1.0
        }
    }

    fn random(m: usize, n: usize, next: &mut impl FnMut() -> f64) -> DMatrix<f64> {
        DMatrix::from_fn(m, n, |_, _| next())
    }

    fn pattern(m: usize, exact_rows: &[usize]) -> Vec<bool> {
        (0..m).map(|i| exact_rows.contains(&i)).collect()
    }

    fn max_abs(v: &[f64]) -> f64 {
        v.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    fn assert_close(x: &[f64], y: &[f64], rel: f64, what: &str) {
        let scale = max_abs(y).max(1e-300);
        let err = x
            .iter()
            .zip(y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            err <= rel * scale,
            "{what}: |x − y| = {err:e} > {rel:e}·{scale:e}\n x = {x:?}\n y = {y:?}"
        );
    }

    /// `(C, S D, b_C, S b_D)`.
    #[allow(clippy::type_complexity)]
    fn split(
        a: &DMatrix<f64>,
        exact: &[bool],
        weight: &[f64],
        b: &[f64],
    ) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>, DVector<f64>) {
        let n = a.ncols();
        let ci: Vec<usize> = (0..a.nrows()).filter(|&i| exact[i]).collect();
        let di: Vec<usize> = (0..a.nrows()).filter(|&i| !exact[i]).collect();
        let c = DMatrix::from_fn(ci.len(), n, |k, j| a[(ci[k], j)]);
        let sd = DMatrix::from_fn(di.len(), n, |k, j| weight[di[k]] * a[(di[k], j)]);
        let bc = DVector::from_fn(ci.len(), |k, _| b[ci[k]]);
        let sbd = DVector::from_fn(di.len(), |k, _| weight[di[k]] * b[di[k]]);
        (c, sd, bc, sbd)
    }

    /// The solution from the KKT system
    /// `[[DᵀS²D, Cᵀ], [C, 0]] [δ; λ] = [DᵀS² b_D; b_C]`.
    fn kkt(a: &DMatrix<f64>, exact: &[bool], weight: &[f64], b: &[f64]) -> Vec<f64> {
        let (c, sd, bc, sbd) = split(a, exact, weight, b);
        let (n, p) = (a.ncols(), c.nrows());
        let mut k = DMatrix::zeros(n + p, n + p);
        k.view_mut((0, 0), (n, n))
            .copy_from(&(sd.transpose() * &sd));
        k.view_mut((0, n), (n, p)).copy_from(&c.transpose());
        k.view_mut((n, 0), (p, n)).copy_from(&c);
        let mut rhs = DVector::zeros(n + p);
        rhs.rows_mut(0, n).copy_from(&(sd.transpose() * sbd));
        rhs.rows_mut(n, p).copy_from(&bc);
        let sol = k.lu().solve(&rhs).expect("KKT system singular");
        sol.as_slice()[..n].to_vec()
    }

    /// Largest `|C δ − b_C|`, relative to `‖C‖∞ ‖δ‖∞ + ‖b_C‖∞`.
    fn constraint_defect(a: &DMatrix<f64>, exact: &[bool], b: &[f64], x: &[f64]) -> f64 {
        let mut worst = 0.0_f64;
        for i in (0..a.nrows()).filter(|&i| exact[i]) {
            let row: f64 = (0..a.ncols()).map(|j| a[(i, j)] * x[j]).sum();
            let scale =
                (0..a.ncols()).map(|j| a[(i, j)].abs()).sum::<f64>() * max_abs(x) + b[i].abs();
            worst = worst.max((row - b[i]).abs() / scale.max(1e-300));
        }
        worst
    }

    #[test]
    fn square_nonsingular_systems_match_lu() {
        let n = 6;
        let mut next = rng(0x9e37_79b9);
        for trial in 0..20 {
            let a = random(n, n, &mut next) + DMatrix::identity(n, n) * 2.0;
            let b: Vec<f64> = (0..n).map(|_| 3.0 * next()).collect();
            let weight: Vec<f64> = (0..n).map(|_| 1.5 + next()).collect();
            let reference = a
                .clone()
                .lu()
                .solve(&DVector::from_column_slice(&b))
                .unwrap();
            let patterns: [&[usize]; 6] = [
                &[],
                &[0, 3],
                &[1, 2, 5],
                &[5],
                &[4, 0, 2, 1, 3],
                &[0, 1, 2, 3, 4, 5],
            ];
            for rows in patterns {
                let exact = pattern(n, rows);
                let x = lstsq(&a, &exact, &weight, &b).unwrap();
                assert_close(
                    &x,
                    reference.as_slice(),
                    1e-12,
                    &format!("trial {trial}, exact {rows:?}"),
                );
            }
        }
    }

    #[test]
    fn without_exact_rows_the_weighted_normal_equations_hold() {
        let (m, n) = (11, 5);
        let mut next = rng(0x1234_5678);
        for trial in 0..20 {
            let a = random(m, n, &mut next);
            let b: Vec<f64> = (0..m).map(|_| 2.0 * next()).collect();
            let weight: Vec<f64> = (0..m).map(|_| 1.2 + next()).collect();
            let exact = vec![false; m];
            let x = lstsq(&a, &exact, &weight, &b).unwrap();
            let s2 = DMatrix::from_diagonal(&DVector::from_fn(m, |i, _| weight[i] * weight[i]));
            let normal = a.transpose() * &s2 * &a;
            let rhs = a.transpose() * &s2 * DVector::from_column_slice(&b);
            let reference = normal.cholesky().unwrap().solve(&rhs);
            assert_close(&x, reference.as_slice(), 1e-10, &format!("trial {trial}"));
        }
    }

    #[test]
    fn exact_rows_hold_and_the_solution_matches_the_kkt_system() {
        let (m, n) = (12, 6);
        let mut next = rng(0x0bad_cafe);
        let patterns: [&[usize]; 4] = [&[2, 7, 11], &[0], &[11, 3, 5, 8, 1], &[10, 9, 8, 0, 4, 6]];
        for trial in 0..10 {
            let a = random(m, n, &mut next);
            let b: Vec<f64> = (0..m).map(|_| 5.0 * next()).collect();
            let weight: Vec<f64> = (0..m).map(|_| 2.0 + 1.5 * next()).collect();
            for rows in patterns {
                let exact = pattern(m, rows);
                let x = lstsq(&a, &exact, &weight, &b).unwrap();
                let defect = constraint_defect(&a, &exact, &b, &x);
                assert!(
                    defect <= 1e-13,
                    "trial {trial}, exact {rows:?}: defect {defect:e}"
                );
                assert_close(
                    &x,
                    &kkt(&a, &exact, &weight, &b),
                    1e-10,
                    &format!("trial {trial}, exact {rows:?}"),
                );
            }
        }
    }

    #[test]
    fn weights_matter_but_not_their_scale() {
        let (m, n) = (8, 3);
        let mut next = rng(0xfeed_f00d);
        let a = random(m, n, &mut next);
        let b: Vec<f64> = (0..m).map(|_| next()).collect();
        let weight: Vec<f64> = (0..m).map(|_| 1.0 + 0.5 * next()).collect();
        let exact = pattern(m, &[4]);
        let x = lstsq(&a, &exact, &weight, &b).unwrap();

        let mut heavier = weight.clone();
        heavier[1] *= 10.0;
        let y = lstsq(&a, &exact, &heavier, &b).unwrap();
        let change = x
            .iter()
            .zip(&y)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max);
        assert!(
            change > 1e-3,
            "reweighting a row changed δ by only {change:e}"
        );
        // The heavier row is fitted better.
        let resid = |x: &[f64]| (0..n).map(|j| a[(1, j)] * x[j]).sum::<f64>() - b[1];
        assert!(resid(&y).abs() < resid(&x).abs());

        // The weight of an exact row is ignored.
        let mut other = weight.clone();
        other[4] = 1e6;
        assert_close(
            &lstsq(&a, &exact, &other, &b).unwrap(),
            &x,
            1e-15,
            "exact row weight",
        );

        let scaled: Vec<f64> = weight.iter().map(|w| 7.3 * w).collect();
        assert_close(
            &lstsq(&a, &exact, &scaled, &b).unwrap(),
            &x,
            1e-12,
            "scaled weights",
        );
    }

    #[test]
    fn null_space_is_orthonormal_and_annihilated() {
        let mut next = rng(5);
        for (p, n) in [(1, 2), (3, 5), (2, 6), (4, 4)] {
            let c = random(p, n, &mut next);
            let mut ct: Vec<f64> = c.transpose().as_slice().to_vec();
            let (mut tau, mut norms) = (vec![0.0; p], vec![0.0; p]);
            let mut z = vec![f64::NAN; n * (n - p)];
            null_space(&mut ct, n, p, &mut tau, &mut norms, &mut z).expect("full rank");
            let z = DMatrix::from_column_slice(n, n - p, &z);
            let ztz = z.transpose() * &z;
            assert!(
                (ztz - DMatrix::identity(n - p, n - p)).amax() < 1e-14,
                "{p}x{n}: ZᵀZ"
            );
            assert!((&c * &z).amax() < 1e-14 * c.amax(), "{p}x{n}: C Z");
        }
        // Dependent rows are refused.
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 2.0, 4.0, 6.0]);
        let mut ct: Vec<f64> = c.transpose().as_slice().to_vec();
        let mut z = vec![0.0; 3];
        let (mut tau, mut norms) = (vec![0.0; 2], vec![0.0; 2]);
        assert!(null_space(&mut ct, 3, 2, &mut tau, &mut norms, &mut z).is_err());
    }

    #[test]
    fn singular_problems_are_refused_without_panicking() {
        let (m, n) = (7, 4);
        let mut next = rng(0x5eed);
        let a = random(m, n, &mut next);
        let weight = vec![1.0; m];
        let b = vec![1.0; m];
        let ok = |a: &DMatrix<f64>, exact: &[bool], weight: &[f64]| {
            lstsq(a, exact, weight, &b[..a.nrows()]).is_ok()
        };
        assert!(ok(&a, &pattern(m, &[1, 5]), &weight));

        // Two equal constraint rows.
        let mut twice = a.clone();
        let row = twice.row(1).clone_owned();
        twice.row_mut(5).copy_from(&row);
        assert!(!ok(&twice, &pattern(m, &[1, 5]), &weight));
        // ... and nearly equal ones (round-off level).
        twice[(5, 2)] *= 1.0 + f64::EPSILON;
        assert!(!ok(&twice, &pattern(m, &[1, 5]), &weight));
        // Equal rows are fine when one of them is weighted ...
        assert!(ok(&twice, &pattern(m, &[1]), &weight));
        // ... but not when the weighted rows cannot fix the unknowns the
        // exact rows leave free.
        let mut square = a.rows(0, n).clone_owned();
        assert!(ok(&square, &pattern(n, &[0, 1, 2]), &weight[..n]));
        square.row_mut(3).fill(0.0);
        assert!(!ok(&square, &pattern(n, &[0, 1, 2]), &weight[..n]));
        // A zero constraint row, a zero column.
        let mut zero_row = a.clone();
        zero_row.row_mut(3).fill(0.0);
        assert!(!ok(&zero_row, &pattern(m, &[3]), &weight));
        let mut zero_col = a.clone();
        zero_col.column_mut(2).fill(0.0);
        assert!(!ok(&zero_col, &pattern(m, &[]), &weight));
        assert!(!ok(&zero_col, &pattern(m, &[0, 6]), &weight));

        // Too few rows in all, more exact rows than unknowns.
        let wide = random(3, 4, &mut next);
        assert!(lstsq(&wide, &[false; 3], &[1.0; 3], &[1.0; 3]).is_err());
        assert!(lstsq(&wide, &[true; 3], &[1.0; 3], &[1.0; 3]).is_err());
        assert!(!ok(&a, &pattern(m, &[0, 1, 2, 3, 4]), &weight));

        // NaN and infinite entries, unusable weights.
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut poisoned = a.clone();
            poisoned[(6, 3)] = bad;
            assert!(!ok(&poisoned, &pattern(m, &[]), &weight));
            assert!(!ok(&poisoned, &pattern(m, &[6]), &weight));
            let mut w = weight.clone();
            w[2] = bad;
            assert!(!ok(&a, &pattern(m, &[]), &w));
        }
        for bad in [0.0, -1.0] {
            let mut w = weight.clone();
            w[2] = bad;
            assert!(!ok(&a, &pattern(m, &[1]), &w));
        }

        // Solving after a failed factorisation gives NaN, not a panic or a
        // stale solution.
        let mut ls = ConstrainedLstsq::new(m, n);
        ls.matrix_mut().copy_from(&a);
        ls.factor(&pattern(m, &[1]), &weight, &[]).unwrap();
        ls.matrix_mut().copy_from(&twice);
        assert!(ls.factor(&pattern(m, &[1, 5]), &weight, &[]).is_err());
        let mut x = b.clone();
        ls.solve(&mut x);
        assert!(x.iter().all(|v| v.is_nan()));
    }

    #[test]
    fn refactorising_with_other_exact_rows_leaves_no_stale_state() {
        let (m, n) = (9, 5);
        let mut next = rng(0xabcd_ef01);
        let mut ls = ConstrainedLstsq::new(m, n);
        assert_eq!((ls.m, ls.n), (m, n));
        let patterns: [&[usize]; 5] = [&[0, 4, 8], &[], &[7], &[0, 4, 8], &[1, 2, 3, 5, 6]];
        for (trial, rows) in patterns.into_iter().enumerate() {
            let a = random(m, n, &mut next);
            let weight: Vec<f64> = (0..m).map(|_| 1.0 + 0.9 * next()).collect();
            let exact = pattern(m, rows);
            ls.matrix_mut().copy_from(&a);
            ls.factor(&exact, &weight, &[]).unwrap();
            // Two right-hand sides with the same factors.
            for _ in 0..2 {
                let b: Vec<f64> = (0..m).map(|_| next()).collect();
                let mut x = b.clone();
                ls.solve(&mut x);
                let reference = kkt(&a, &exact, &weight, &b);
                assert_close(
                    &x[..n],
                    &reference,
                    1e-10,
                    &format!("trial {trial}, exact {rows:?}"),
                );
                assert!(constraint_defect(&a, &exact, &b, &x[..n]) <= 1e-13);
            }
        }
    }

    /// A well-conditioned random system: its first `n` rows (before the rows
    /// are shuffled) are strictly diagonally dominant, so any subset of them
    /// may be exact and the weighted rows still determine the rest.
    fn system() -> impl Strategy<Value = (DMatrix<f64>, Vec<bool>, Vec<f64>, Vec<f64>)> {
        (1usize..=8)
            .prop_flat_map(|n| (Just(n), n..=2 * n))
            .prop_flat_map(|(n, m)| {
                (
                    Just(n),
                    Just(m),
                    vec(-1.0..1.0_f64, m * n),
                    vec(any::<bool>(), n),
                    Just((0..m).collect::<Vec<usize>>()).prop_shuffle(),
                    vec(0.1..10.0_f64, m),
                    vec(-10.0..10.0_f64, m),
                )
            })
            .prop_map(|(n, m, entries, mask, perm, weight, b)| {
                let mut a = DMatrix::zeros(m, n);
                let mut exact = vec![false; m];
                for (i, &row) in perm.iter().enumerate() {
                    for j in 0..n {
                        let shift = if i == j { (n + 1) as f64 } else { 0.0 };
                        a[(row, j)] = entries[i * n + j] + shift;
                    }
                    exact[row] = i < n && mask[i];
                }
                (a, exact, weight, b)
            })
    }

    proptest! {
        #[test]
        fn random_systems_are_feasible_and_optimal((a, exact, weight, b) in system()) {
            let n = a.ncols();
            let x = lstsq(&a, &exact, &weight, &b).unwrap();
            prop_assert!(x.iter().all(|v| v.is_finite()));
            let defect = constraint_defect(&a, &exact, &b, &x);
            prop_assert!(defect <= 1e-13, "constraint defect {:e}", defect);

            // Optimality: (S D)ᵀ S (D δ − b_D) lies in the range of Cᵀ.
            let (c, sd, _, sbd) = split(&a, &exact, &weight, &b);
            let xv = DVector::from_column_slice(&x);
            let r = &sd * &xv - &sbd;
            let mut g = sd.transpose() * &r;
            if c.nrows() > 0 {
                let lambda = (&c * c.transpose()).lu().solve(&(&c * &g)).unwrap();
                g -= c.transpose() * lambda;
            }
            let scale = sd.norm() * (sd.norm() * xv.norm() + sbd.norm());
            prop_assert!(
                g.norm() <= 1e-12 * scale.max(1e-300) * n as f64,
                "projected gradient {:e}, scale {:e}", g.norm(), scale
            );
        }
    }
}

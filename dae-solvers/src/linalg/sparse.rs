//! Sparse LU factorisation of large square iteration matrices, by faer
//! (COLAMD fill-reducing column ordering, partial pivoting by rows).
//!
//! A [`Pattern`] holds the structural non-zeros (compressed column) and
//! their symbolic analysis, made once per pattern; a [`SparseFactor`]
//! factorises a matrix of that pattern numerically (once per Jacobian) and
//! solves with it: the first matrix with partial pivoting, the next ones
//! refactorised on its pivot order while those pivots stay large enough
//! (as KLU's `klu_refactor`). Radau's real and complex systems share one
//! pattern.
//!
//! A pattern comes either from the derivation (a system that reports its
//! structural non-zeros, [`Pattern::from_compressed`]: the step loops
//! then evaluate `E` and `J` in compressed form and the matrix comes as
//! its values in the pattern's order), or from a first dense matrix
//! ([`Pattern::new`]: a system that reports no structure), in which case
//! it grows (and its analysis is made again) when an entry outside it
//! becomes non-zero, so that no accidental zero of the first Jacobian is
//! taken for a structural one. See [`crate::core::matrix::SPARSE_FROM`]
//! for when this path is taken.

use super::Singular;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::simplicial::{self, SimplicialLu};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuSymbolicParams, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;

/// The structural non-zeros of an `n × n` matrix (compressed column, rows
/// ascending in each column, the diagonal always included) and their
/// symbolic LU analysis.
pub(crate) struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicLu<usize>,
    /// How many analyses were made (one, unless the pattern grew).
    pub(crate) analyses: usize,
}

impl Pattern {
    /// The entries `(r, c)` of an `n × n` matrix where `nonzero(r, c)`,
    /// and the diagonal. `Singular` when the analysis fails (faer out of
    /// memory).
    pub(crate) fn new(n: usize, nonzero: impl Fn(usize, usize) -> bool) -> Result<Self, Singular> {
        let (col_ptr, row_idx) = scan(n, |r, c| r == c || nonzero(r, c));
        let symbolic = analyse(n, &col_ptr, &row_idx)?;
        Ok(Pattern {
            n,
            col_ptr,
            row_idx,
            symbolic,
            analyses: 1,
        })
    }

    /// The pattern given in compressed-column form (`col_ptr` of length
    /// `n + 1`, the rows of each column ascending, the diagonal included
    /// by the caller) and its analysis. `Singular` when the analysis fails.
    pub(crate) fn from_compressed(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> Result<Self, Singular> {
        let symbolic = analyse(n, &col_ptr, &row_idx)?;
        Ok(Pattern {
            n,
            col_ptr,
            row_idx,
            symbolic,
            analyses: 1,
        })
    }

    /// Number of stored entries.
    pub(crate) fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Make sure every `(r, c)` with `nonzero(r, c)` is in the pattern:
    /// a new entry adds it, with the entries already there, and makes the
    /// analysis again (`O(n²)` tests of `nonzero`).
    pub(crate) fn cover(&mut self, nonzero: impl Fn(usize, usize) -> bool) -> Result<(), Singular> {
        let n = self.n;
        let inside = |r: usize, c: usize| {
            self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]]
                .binary_search(&r)
                .is_ok()
        };
        let grows = (0..n).any(|c| (0..n).any(|r| nonzero(r, c) && !inside(r, c)));
        if !grows {
            return Ok(());
        }
        let (col_ptr, row_idx) = scan(n, |r, c| r == c || nonzero(r, c) || inside(r, c));
        self.symbolic = analyse(n, &col_ptr, &row_idx)?;
        (self.col_ptr, self.row_idx) = (col_ptr, row_idx);
        self.analyses += 1;
        Ok(())
    }

    fn structure(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// Compressed-column indices of the entries where `keep(r, c)`.
fn scan(n: usize, keep: impl Fn(usize, usize) -> bool) -> (Vec<usize>, Vec<usize>) {
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for c in 0..n {
        row_idx.extend((0..n).filter(|&r| keep(r, c)));
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

fn analyse(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<SymbolicLu<usize>, Singular> {
    let s = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
    // Simplicial always: its factors are what [`SparseFactor`] keeps and
    // refactorises (KLU, which IDA uses, is simplicial too).
    let params = LuSymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
        ..Default::default()
    };
    factorize_symbolic_lu(s, params).map_err(|_| Singular)
}

/// Smallest ratio `|pivot| / max |candidate|` in a column that a kept pivot
/// order accepts on refactorisation (threshold partial pivoting with
/// `u = 0.1`, UMFPACK's default): a pivot smaller than a tenth of another
/// entry of its column below the diagonal makes the next factorisation a
/// full one, with a new pivot order.
const REFACTOR_THRESHOLD: f64 = 0.1;

/// The scalars of the factorisations: `f64` and `c64`.
pub(crate) trait Entry:
    ComplexField<Real = f64>
    + Copy
    + std::ops::SubAssign
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
}
impl<T> Entry for T where
    T: ComplexField<Real = f64>
        + Copy
        + std::ops::SubAssign
        + std::ops::Mul<Output = T>
        + std::ops::Div<Output = T>
{
}

/// `P_r A P_c = L U` in compressed columns, indices in the permuted
/// order: `L` unit lower (its strictly lower entries), `U`'s strictly
/// upper entries with their rows ascending in each column, and `U`'s
/// diagonal apart.
struct Factors<T> {
    l_ptr: Vec<usize>,
    l_row: Vec<usize>,
    l_val: Vec<T>,
    u_ptr: Vec<usize>,
    u_row: Vec<usize>,
    u_val: Vec<T>,
    diag: Vec<T>,
    /// Pivot step `k` → row of `A`.
    row_perm: Vec<usize>,
    /// Row of `A` → pivot step.
    row_perm_inv: Vec<usize>,
    /// Step `j` → column of `A` (the analysis' fill-reducing order).
    col_perm: Vec<usize>,
}

impl<T> Factors<T> {
    fn new() -> Self {
        Factors {
            l_ptr: Vec::new(),
            l_row: Vec::new(),
            l_val: Vec::new(),
            u_ptr: Vec::new(),
            u_row: Vec::new(),
            u_val: Vec::new(),
            diag: Vec::new(),
            row_perm: Vec::new(),
            row_perm_inv: Vec::new(),
            col_perm: Vec::new(),
        }
    }
}

/// The numeric LU of one matrix of a [`Pattern`] (`T`: `f64` or `c64`).
///
/// The first factorisation of a pattern is faer's simplicial LU with
/// partial pivoting (Gilbert–Peierls: a symbolic reach per column). Its
/// factors are kept in [`Factors`], and the next matrix of the same
/// pattern is *refactorised* on them (KLU's `klu_refactor`, which IDA's
/// KLU solver calls for every Jacobian after the first): the pivot order
/// and the patterns of `L` and `U` are kept and only the values computed,
/// left-looking, with no search and no reach. A kept pivot below
/// [`REFACTOR_THRESHOLD`] of its column makes a full factorisation with
/// new pivots instead. The solves run on the kept factors.
pub(crate) struct SparseFactor<T> {
    lu: SimplicialLu<usize, T>,
    factors: Factors<T>,
    /// `factors` hold a factorisation of the current analysis.
    valid: bool,
    values: Vec<T>,
    /// Dense work vector of length `n`, zero between uses.
    work: Vec<T>,
    /// The solution of the singularity test.
    probe: Vec<T>,
    stack: MemBuffer,
    /// The analysis the scratch space was sized for.
    sized_for: usize,
    /// Full factorisations and refactorisations made (tests).
    #[cfg(test)]
    counts: (usize, usize),
}

impl<T: Entry> SparseFactor<T> {
    /// Empty: the first [`SparseFactor::factor`] sizes it.
    pub(crate) fn new() -> Self {
        SparseFactor {
            lu: SimplicialLu::new(),
            factors: Factors::new(),
            valid: false,
            values: Vec::new(),
            work: Vec::new(),
            probe: Vec::new(),
            stack: MemBuffer::new(StackReq::EMPTY),
            sized_for: 0,
            #[cfg(test)]
            counts: (0, 0),
        }
    }

    /// Factorise the matrix whose entries are `value(r, c)` on `p` (the
    /// caller has made `p` cover its non-zeros). `Singular` when a pivot
    /// is zero or not finite (tested by a solve with a vector of ones).
    pub(crate) fn factor(
        &mut self,
        p: &Pattern,
        value: impl Fn(usize, usize) -> T,
    ) -> Result<(), Singular> {
        self.factor_indexed(p, |_, r, c| value(r, c))
    }

    /// [`SparseFactor::factor`] with the entries given as `value(k, r, c)`,
    /// `k` the entry's position in the pattern's order (a matrix held as
    /// values on the pattern reads `values[k]`).
    pub(crate) fn factor_indexed(
        &mut self,
        p: &Pattern,
        value: impl Fn(usize, usize, usize) -> T,
    ) -> Result<(), Singular> {
        if self.sized_for != p.analyses || self.values.len() != p.nnz() {
            let req = simplicial::factorize_simplicial_numeric_lu_scratch::<usize, T>(p.n, p.n);
            self.stack = MemBuffer::new(req);
            self.values.clear();
            self.values.resize(p.nnz(), T::zero_impl());
            self.work.clear();
            self.work.resize(p.n, T::zero_impl());
            self.sized_for = p.analyses;
            self.valid = false;
        }
        for c in 0..p.n {
            for k in p.col_ptr[c]..p.col_ptr[c + 1] {
                self.values[k] = value(k, p.row_idx[k], c);
            }
        }
        if !(self.valid && self.refactor(p)) {
            self.valid = false;
            self.full(p)?;
            self.valid = true;
        }
        // A zero pivot is not refused by the factorisation: it makes an
        // infinite or NaN solution.
        let mut probe = std::mem::take(&mut self.probe);
        probe.clear();
        probe.resize(p.n, T::one_impl());
        self.solve(p, &mut probe);
        let finite = probe.iter().all(|v| T::is_finite_impl(v));
        self.probe = probe;
        if finite {
            Ok(())
        } else {
            Err(Singular)
        }
    }

    /// faer's factorisation with partial pivoting, its factors kept.
    fn full(&mut self, p: &Pattern) -> Result<(), Singular> {
        #[cfg(test)]
        {
            self.counts.0 += 1;
        }
        let n = p.n;
        let f = &mut self.factors;
        f.row_perm.resize(n, 0);
        f.row_perm_inv.resize(n, 0);
        let a = SparseColMatRef::new(p.structure(), &self.values);
        simplicial::factorize_simplicial_numeric_lu(
            &mut f.row_perm,
            &mut f.row_perm_inv,
            &mut self.lu,
            a,
            p.symbolic.col_perm(),
            MemStack::new(&mut self.stack),
        )
        .map_err(|_| Singular)?;
        f.col_perm.clear();
        f.col_perm
            .extend_from_slice(p.symbolic.col_perm().arrays().0);
        let (l, u) = (self.lu.l_factor_unsorted(), self.lu.u_factor_unsorted());
        f.l_ptr.clear();
        f.l_row.clear();
        f.l_val.clear();
        f.u_ptr.clear();
        f.u_row.clear();
        f.u_val.clear();
        f.diag.clear();
        f.diag.resize(n, T::zero_impl());
        f.l_ptr.push(0);
        f.u_ptr.push(0);
        let mut column: Vec<(usize, T)> = Vec::new();
        for j in 0..n {
            for (&r, &v) in l.row_idx_of_col_raw(j).iter().zip(l.val_of_col(j)) {
                if r != j {
                    f.l_row.push(r);
                    f.l_val.push(v);
                }
            }
            f.l_ptr.push(f.l_row.len());
            column.clear();
            for (&r, &v) in u.row_idx_of_col_raw(j).iter().zip(u.val_of_col(j)) {
                if r == j {
                    f.diag[j] = v;
                } else {
                    column.push((r, v));
                }
            }
            // Ascending rows: the order in which a refactorisation
            // applies the earlier columns of L.
            column.sort_unstable_by_key(|&(r, _)| r);
            for &(r, v) in &column {
                f.u_row.push(r);
                f.u_val.push(v);
            }
            f.u_ptr.push(f.u_row.len());
        }
        Ok(())
    }

    /// The values of `L` and `U` for the matrix in `values` on the kept
    /// pivot order and patterns, left-looking column by column; `false`
    /// (the factors then to be made anew) when a kept pivot is zero,
    /// not finite, or below [`REFACTOR_THRESHOLD`] of its column.
    fn refactor(&mut self, p: &Pattern) -> bool {
        #[cfg(test)]
        {
            self.counts.1 += 1;
        }
        let f = &mut self.factors;
        let x = &mut self.work;
        let zero = T::zero_impl();
        for j in 0..p.n {
            // Column j of P_r A P_c, scattered; every entry lies in the
            // kept pattern of L(:, j), U(:, j) or the diagonal (the reach
            // of the first factorisation contains A's pattern).
            let pj = f.col_perm[j];
            for k in p.col_ptr[pj]..p.col_ptr[pj + 1] {
                x[f.row_perm_inv[p.row_idx[k]]] = self.values[k];
            }
            for q in f.u_ptr[j]..f.u_ptr[j + 1] {
                let k = f.u_row[q];
                let xk = x[k];
                x[k] = zero;
                f.u_val[q] = xk;
                if xk != zero {
                    for r in f.l_ptr[k]..f.l_ptr[k + 1] {
                        let i = f.l_row[r];
                        x[i] -= f.l_val[r] * xk;
                    }
                }
            }
            let pivot = x[j];
            x[j] = zero;
            let column = f.l_ptr[j]..f.l_ptr[j + 1];
            let largest = f.l_row[column.clone()]
                .iter()
                .fold(0.0_f64, |m, &i| m.max(T::abs1_impl(&x[i])));
            let size = T::abs1_impl(&pivot);
            if !(size > 0.0 && size.is_finite() && size >= REFACTOR_THRESHOLD * largest) {
                for &i in &f.l_row[column] {
                    x[i] = zero;
                }
                return false;
            }
            f.diag[j] = pivot;
            for r in column {
                let i = f.l_row[r];
                f.l_val[r] = x[i] / pivot;
                x[i] = zero;
            }
        }
        true
    }

    /// `x ← A⁻¹ x` with the factors of the last [`SparseFactor::factor`].
    pub(crate) fn solve(&mut self, p: &Pattern, x: &mut [T]) {
        let f = &self.factors;
        let w = &mut self.work;
        for (wk, &r) in w.iter_mut().zip(&f.row_perm) {
            *wk = x[r];
        }
        for j in 0..p.n {
            let wj = w[j];
            for r in f.l_ptr[j]..f.l_ptr[j + 1] {
                let i = f.l_row[r];
                w[i] -= f.l_val[r] * wj;
            }
        }
        for j in (0..p.n).rev() {
            let wj = w[j] / f.diag[j];
            w[j] = wj;
            for q in f.u_ptr[j]..f.u_ptr[j + 1] {
                let i = f.u_row[q];
                w[i] -= f.u_val[q] * wj;
            }
        }
        let zero = T::zero_impl();
        for (wj, &c) in w.iter_mut().zip(&f.col_perm) {
            x[c] = *wj;
            *wj = zero;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::c64;

    /// A tridiagonal matrix with a zero on the diagonal (pivoting needed)
    /// and one entry far off the band.
    fn entry(r: usize, c: usize) -> f64 {
        if r == c {
            if r == 2 {
                0.0
            } else {
                4.0 + r as f64
            }
        } else if r.abs_diff(c) == 1 {
            1.0 + 0.1 * (r + 2 * c) as f64
        } else if (r, c) == (0, 5) {
            -2.0
        } else {
            0.0
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // r indexes the rows of a product
    fn real_and_complex_solves_match_the_dense_products() {
        let n = 6;
        let p = Pattern::new(n, |r, c| entry(r, c) != 0.0).expect("analysed");
        let mut real = SparseFactor::<f64>::new();
        real.factor(&p, entry).expect("nonsingular");
        let b: Vec<f64> = (0..n).map(|i| 1.0 - 0.3 * i as f64).collect();
        let mut x = b.clone();
        real.solve(&p, &mut x);
        for r in 0..n {
            let ax: f64 = (0..n).map(|c| entry(r, c) * x[c]).sum();
            assert!((ax - b[r]).abs() < 1e-13, "row {r}: {ax} vs {}", b[r]);
        }
        let z = |r: usize, c: usize| c64::new(entry(r, c), if r == c { 0.5 } else { 0.0 });
        let mut complex = SparseFactor::<c64>::new();
        complex.factor(&p, z).expect("nonsingular");
        let bz: Vec<c64> = b.iter().map(|&v| c64::new(v, -v)).collect();
        let mut xz = bz.clone();
        complex.solve(&p, &mut xz);
        for r in 0..n {
            let ax: c64 = (0..n).map(|c| z(r, c) * xz[c]).sum();
            assert!((ax - bz[r]).norm() < 1e-13, "row {r}");
        }
    }

    /// `A x` for the test matrix `a` of size `n`.
    fn product(n: usize, a: impl Fn(usize, usize) -> f64, x: &[f64]) -> Vec<f64> {
        (0..n)
            .map(|r| (0..n).map(|c| a(r, c) * x[c]).sum())
            .collect()
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // r indexes the rows of a product
    fn refactorisations_keep_the_pivots_and_solve_like_full_factorisations() {
        let n = 6;
        let p = Pattern::new(n, |r, c| entry(r, c) != 0.0).expect("analysed");
        let b: Vec<f64> = (0..n).map(|i| 1.0 - 0.3 * i as f64).collect();
        let mut kept = SparseFactor::<f64>::new();
        // Values that move but keep every pivot large in its column: the
        // second and third matrices are refactorised on the first's
        // pivots, and solve as a fresh factorisation does.
        for (step, s) in [0.0, 0.05, 0.1].into_iter().enumerate() {
            let a = |r: usize, c: usize| {
                let v = entry(r, c);
                if v == 0.0 {
                    0.0
                } else {
                    v * (1.0 + s * (r + 2 * c) as f64)
                }
            };
            kept.factor(&p, a).expect("nonsingular");
            assert_eq!(
                kept.counts,
                (1, step),
                "one full factorisation, then refactorisations"
            );
            let mut fresh = SparseFactor::<f64>::new();
            fresh.factor(&p, a).expect("nonsingular");
            let (mut x, mut y) = (b.clone(), b.clone());
            kept.solve(&p, &mut x);
            fresh.solve(&p, &mut y);
            for (r, (ax, br)) in product(n, a, &x).iter().zip(&b).enumerate() {
                assert!(
                    (ax - br).abs() < 1e-13,
                    "step {step}, row {r}: {ax} vs {br}"
                );
            }
            for (xi, yi) in x.iter().zip(&y) {
                assert!((xi - yi).abs() < 1e-13 * (1.0 + yi.abs()), "{xi} vs {yi}");
            }
        }
        // A kept pivot that has become small in its column: the
        // diagonally dominant matrix is factorised on its diagonal; with
        // the diagonal shrunk to 1e-3 every kept pivot is below a tenth of
        // the entries beside it, the refactorisation is refused and a full
        // factorisation chooses new pivots.
        let m = 3;
        let full = Pattern::new(m, |_, _| true).expect("analysed");
        let dominant = |r: usize, c: usize| {
            if r == c {
                4.0
            } else {
                1.0 + 0.1 * (r + c) as f64
            }
        };
        let shrunk = |r: usize, c: usize| if r == c { 1e-3 } else { dominant(r, c) };
        let mut f = SparseFactor::<f64>::new();
        f.factor(&full, dominant).expect("nonsingular");
        f.factor(&full, shrunk).expect("nonsingular");
        assert_eq!(f.counts, (2, 1), "the refactorisation was refused");
        let c = [1.0, -2.0, 0.5];
        let mut x = c.to_vec();
        f.solve(&full, &mut x);
        for (r, (ax, cr)) in product(m, shrunk, &x).iter().zip(&c).enumerate() {
            assert!((ax - cr).abs() < 1e-12, "row {r}: {ax} vs {cr}");
        }
        // A complex matrix on the same pattern refactorises too.
        let z = |s: f64| {
            move |r: usize, c: usize| {
                c64::new(entry(r, c) * (1.0 + s), if r == c { 0.5 } else { 0.0 })
            }
        };
        let mut complex = SparseFactor::<c64>::new();
        complex.factor(&p, z(0.0)).expect("nonsingular");
        complex.factor(&p, z(0.01)).expect("nonsingular");
        assert_eq!(complex.counts, (1, 1));
        let bz: Vec<c64> = b.iter().map(|&v| c64::new(v, -v)).collect();
        let mut xz = bz.clone();
        complex.solve(&p, &mut xz);
        for r in 0..n {
            let ax: c64 = (0..n).map(|c| z(0.01)(r, c) * xz[c]).sum();
            assert!((ax - bz[r]).norm() < 1e-13, "row {r}");
        }
    }

    #[test]
    fn a_new_entry_grows_the_pattern_and_a_zero_pivot_is_singular() {
        let n = 4;
        let mut p = Pattern::new(n, |r, c| r == c).expect("analysed");
        assert_eq!((p.nnz(), p.analyses), (4, 1));
        let full = |r: usize, c: usize| if r == c || (r, c) == (3, 0) { 2.0 } else { 0.0 };
        p.cover(|r, c| full(r, c) != 0.0).expect("analysed");
        assert_eq!((p.nnz(), p.analyses), (5, 2));
        p.cover(|r, c| full(r, c) != 0.0).expect("analysed");
        assert_eq!(p.analyses, 2, "a covered matrix makes no new analysis");
        let mut f = SparseFactor::<f64>::new();
        f.factor(&p, full).expect("nonsingular");
        let mut x = vec![2.0, 2.0, 2.0, 4.0];
        f.solve(&p, &mut x);
        assert_eq!(x, [1.0, 1.0, 1.0, 1.0]);
        // Column 1 all zero: singular.
        let singular = |r: usize, c: usize| if c == 1 { 0.0 } else { full(r, c) };
        assert!(f.factor(&p, singular).is_err(), "a zero column is singular");
    }
}

//! Sparse LU factorisation of large square iteration matrices, by faer
//! (COLAMD fill-reducing column ordering, partial pivoting by rows).
//!
//! A [`Pattern`] holds the structural non-zeros (compressed column) and
//! their symbolic analysis, made once per pattern; a [`SparseFactor`]
//! factorises a matrix of that pattern numerically (once per Jacobian) and
//! solves with it. Radau's real and complex systems share one pattern.
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
use faer::linalg::lu::partial_pivoting::factor::PartialPivLuParams;
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Spec};

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
    factorize_symbolic_lu(s, Default::default()).map_err(|_| Singular)
}

/// The numeric LU of one matrix of a [`Pattern`] (`T`: `f64` or `c64`).
pub(crate) struct SparseFactor<T> {
    numeric: NumericLu<usize, T>,
    values: Vec<T>,
    /// The solution of the singularity test.
    probe: Vec<T>,
    stack: MemBuffer,
    /// The analysis the scratch space was sized for.
    sized_for: usize,
}

impl<T: ComplexField + Copy> SparseFactor<T> {
    /// Empty: the first [`SparseFactor::factor`] sizes it.
    pub(crate) fn new() -> Self {
        SparseFactor {
            numeric: NumericLu::new(),
            values: Vec::new(),
            probe: Vec::new(),
            stack: MemBuffer::new(StackReq::EMPTY),
            sized_for: 0,
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
            let params = Spec::<PartialPivLuParams, T>::default();
            let req = p
                .symbolic
                .factorize_numeric_lu_scratch::<T>(Par::Seq, params)
                .or(p.symbolic.solve_in_place_scratch::<T>(1, Par::Seq));
            self.stack = MemBuffer::new(req);
            self.values.resize(p.nnz(), T::zero_impl());
            self.sized_for = p.analyses;
        }
        for c in 0..p.n {
            for k in p.col_ptr[c]..p.col_ptr[c + 1] {
                self.values[k] = value(k, p.row_idx[k], c);
            }
        }
        let a = SparseColMatRef::new(p.structure(), &self.values);
        p.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                a,
                Par::Seq,
                MemStack::new(&mut self.stack),
                Default::default(),
            )
            .map_err(|_| Singular)?;
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

    /// `x ← A⁻¹ x` with the factors of the last [`SparseFactor::factor`].
    pub(crate) fn solve(&mut self, p: &Pattern, x: &mut [T]) {
        let lu = LuRef::new_unchecked(&p.symbolic, &self.numeric);
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x[..p.n], p.n, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
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

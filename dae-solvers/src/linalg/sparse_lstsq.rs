//! Pseudo-inverse solves of consistent initialisation on sparse matrices,
//! without an SVD: [`crate::init`] takes this path for a matrix of at least
//! [`crate::core::matrix::SPARSE_FROM`] rows or columns and falls back to
//! its dense SVD wherever this one answers `None`.
//!
//! Two exact identities do the work. First, a zero row or a zero column of
//! a matrix `A` drops out of its pseudo-inverse: with `A_r` the matrix of
//! the non-zero rows and columns, `A⁺ b` is `A_r⁺ b_r` on the non-zero
//! columns and `0` on the zero ones, whatever `b` holds on the zero rows.
//! Second, for `A_r` of full row rank (`r ≤ c`), the minimum-change step
//!
//! ```text
//!     Δ = −A⁺ g − (I − A⁺A) d     solves     [ I   A_rᵀ ] [ Δ ]   [ −d ]
//!                                             [ A_r  0   ] [ μ ] = [ −g ],
//! ```
//!
//! a square system of `c + r` unknowns with `c + 2 nnz(A_r)` non-zeros,
//! factorised by faer's sparse LU (COLAMD ordering, partial pivoting);
//! for a square `A_r` it is the LU of `A_r` itself (`Δ = −A_r⁻¹ g`).
//!
//! What is not decided here is the numerical rank: the dense path counts a
//! singular value below `10⁻¹²·σ_max` as zero, this one takes every block
//! the LU factorises with finite factors as of full rank. The two differ only
//! for a block whose condition number exceeds `10¹²` (or about `N/ε` for
//! the BDF start): there the dense path drops the smallest directions and
//! this one solves with them. A zero pivot (a singular block) is seen as a
//! non-finite solution and answered `None`, so the dense path decides.

/// A `rows × cols` matrix by its non-zero entries `(row, col, value)`,
/// each `(row, col)` at most once.
pub(crate) struct Entries {
    pub(crate) rows: usize,
    pub(crate) cols: usize,
    pub(crate) entries: Vec<(usize, usize, f64)>,
}

impl Entries {
    /// The non-zero entries of `value(r, c)` over a `rows × cols` matrix
    /// (`rows · cols` calls; for a dense buffer already evaluated).
    pub(crate) fn scan(rows: usize, cols: usize, value: impl Fn(usize, usize) -> f64) -> Self {
        let mut entries = Vec::new();
        for c in 0..cols {
            for r in 0..rows {
                let v = value(r, c);
                if v != 0.0 {
                    entries.push((r, c, v));
                }
            }
        }
        Entries {
            rows,
            cols,
            entries,
        }
    }

    /// The non-zero entries among `values`, given at the entries of
    /// `pattern` in its order ([`dae_core::system::DaeSystem::leading_values`]).
    pub(crate) fn from_pattern(pattern: &dae_core::system::Pattern, values: &[f64]) -> Self {
        let entries = pattern
            .entries()
            .zip(values)
            .filter(|(_, &v)| v != 0.0)
            .map(|((r, c), &v)| (r, c, v))
            .collect();
        Entries {
            rows: pattern.rows,
            cols: pattern.cols,
            entries,
        }
    }

    /// Which rows and which columns hold a non-zero entry.
    fn used(&self) -> (Vec<bool>, Vec<bool>) {
        let mut rows = vec![false; self.rows];
        let mut cols = vec![false; self.cols];
        for &(r, c, _) in &self.entries {
            rows[r] = true;
            cols[c] = true;
        }
        (rows, cols)
    }
}

/// The result of [`min_change`].
pub(crate) struct MinChange {
    /// `Δ = −A⁺ g − (I − A⁺A) d` (length `cols`).
    pub(crate) delta: Vec<f64>,
    /// Rows of `A` with a non-zero entry: its rank, the reduced block being
    /// of full row rank.
    pub(crate) rank: usize,
    /// Columns of `A` with no non-zero entry (`A e_c = 0`: directions of
    /// `ker A` read off the structure), ascending.
    pub(crate) zero_cols: Vec<usize>,
}

/// `Δ = −A⁺ g − (I − A⁺A) d` by the identities of the module docs: the
/// least change from `d = 0` (i.e. `−d` moved back as little as possible)
/// that satisfies `A Δ = −g` in the least-squares sense. `None` when the
/// non-zero rows outnumber the non-zero columns, when the reduced system is
/// singular (a non-finite solution) or when its analysis fails; the caller
/// then takes its dense path.
pub(crate) fn min_change(a: &Entries, g: &[f64], d: &[f64]) -> Option<MinChange> {
    debug_assert_eq!((g.len(), d.len()), (a.rows, a.cols));
    let (row_used, col_used) = a.used();
    // Positions of the reduced rows and columns.
    let index = |used: &[bool]| {
        let mut next = 0;
        used.iter()
            .map(|&u| {
                let at = next;
                next += usize::from(u);
                u.then_some(at)
            })
            .collect::<Vec<Option<usize>>>()
    };
    let (row_at, col_at) = (index(&row_used), index(&col_used));
    let r = row_used.iter().filter(|&&u| u).count();
    let c = col_used.iter().filter(|&&u| u).count();
    if r > c {
        return None;
    }
    let zero_cols: Vec<usize> = (0..a.cols).filter(|&j| !col_used[j]).collect();
    let mut delta: Vec<f64> = d.iter().map(|v| -v).collect();
    if r == 0 {
        return Some(MinChange {
            delta,
            rank: 0,
            zero_cols,
        });
    }
    let reduced = a
        .entries
        .iter()
        .map(|&(i, j, v)| (row_at[i].unwrap_or(0), col_at[j].unwrap_or(0), v));
    let x = if r == c {
        // A_r Δ_r = −g_r.
        let b: Vec<f64> = (0..a.rows)
            .filter(|&i| row_used[i])
            .map(|i| -g[i])
            .collect();
        backend::solve(r, reduced.collect(), b)?
    } else {
        // [I A_rᵀ; A_r 0] [Δ_r; μ] = [−d_r; −g_r]: unknowns 0..c are Δ_r,
        // c..c+r are μ.
        let mut entries: Vec<(usize, usize, f64)> = (0..c).map(|j| (j, j, 1.0)).collect();
        for (i, j, v) in reduced {
            entries.push((c + i, j, v));
            entries.push((j, c + i, v));
        }
        let b: Vec<f64> = (0..a.cols)
            .filter(|&j| col_used[j])
            .map(|j| -d[j])
            .chain((0..a.rows).filter(|&i| row_used[i]).map(|i| -g[i]))
            .collect();
        let mut x = backend::solve(c + r, entries, b)?;
        x.truncate(c);
        x
    };
    for (j, at) in col_at.iter().enumerate() {
        if let Some(at) = *at {
            delta[j] = x[at];
        }
    }
    Some(MinChange {
        delta,
        rank: r,
        zero_cols,
    })
}

#[cfg(feature = "sparse")]
mod backend {
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Mat;

    /// `x = A⁻¹ b` for the `n × n` matrix of `entries` (no repeats) by
    /// faer's sparse LU; `None` when the analysis fails or the solution is
    /// not finite (a zero pivot).
    pub(super) fn solve(
        n: usize,
        entries: Vec<(usize, usize, f64)>,
        b: Vec<f64>,
    ) -> Option<Vec<f64>> {
        let triplets: Vec<Triplet<usize, usize, f64>> = entries
            .into_iter()
            .map(|(row, col, val)| Triplet { row, col, val })
            .collect();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).ok()?;
        let lu = a.sp_lu().ok()?;
        let mut x = Mat::from_fn(n, 1, |i, _| b[i]);
        lu.solve_in_place(x.as_mut());
        let x: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
        super::super::all_finite(&x).then_some(x)
    }
}

#[cfg(not(feature = "sparse"))]
mod backend {
    /// Without the `sparse` feature nothing is solved here (and
    /// `SPARSE_FROM` keeps the callers on their dense path).
    pub(super) fn solve(
        _n: usize,
        _entries: Vec<(usize, usize, f64)>,
        _b: Vec<f64>,
    ) -> Option<Vec<f64>> {
        None
    }
}

#[cfg(all(test, feature = "sparse"))]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// The dense reference: `−A⁺g − (I − A⁺A) d` by nalgebra's SVD.
    fn reference(a: &DMatrix<f64>, g: &[f64], d: &[f64]) -> Vec<f64> {
        let pinv = a.clone().pseudo_inverse(1e-12).expect("svd");
        let g = nalgebra::DVector::from_column_slice(g);
        let d = nalgebra::DVector::from_column_slice(d);
        let p = &pinv * a;
        let id = DMatrix::identity(a.ncols(), a.ncols());
        let delta = -(&pinv * g) - (id - p) * d;
        delta.iter().copied().collect()
    }

    fn check(a: &DMatrix<f64>, g: &[f64], d: &[f64], rank: usize, zero_cols: &[usize]) {
        let e = Entries::scan(a.nrows(), a.ncols(), |r, c| a[(r, c)]);
        let got = min_change(&e, g, d).expect("full row rank");
        assert_eq!(got.rank, rank);
        assert_eq!(got.zero_cols, zero_cols);
        for (x, y) in got.delta.iter().zip(reference(a, g, d)) {
            assert!((x - y).abs() < 1e-12 * (1.0 + y.abs()), "{x} vs {y}");
        }
    }

    #[test]
    fn square_wide_and_padded_blocks_match_the_svd() {
        // Square, with pivoting needed (a zero on the diagonal).
        let sq = DMatrix::from_row_slice(3, 3, &[0.0, 2.0, 1.0, 1.0, 0.5, 0.0, 3.0, 0.0, -1.0]);
        check(&sq, &[1.0, -2.0, 0.5], &[0.3, 0.1, -0.2], 3, &[]);
        // Wide (2×4): the minimum-change step of the projection.
        let wide = DMatrix::from_row_slice(2, 4, &[1.0, 2.0, 0.0, -1.0, 0.0, 1.0, 3.0, 0.5]);
        check(&wide, &[0.2, -0.7], &[1.0, -0.5, 0.25, 2.0], 2, &[]);
        // A zero row (its residual unattainable, ignored) and a zero column
        // (a kernel direction: moved back by −d).
        let padded = DMatrix::from_row_slice(
            3,
            4,
            &[1.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, -1.0, 4.0],
        );
        check(&padded, &[1.0, 9.0, -3.0], &[0.1, 0.2, 0.3, 0.4], 2, &[1]);
    }

    #[test]
    fn singular_or_tall_blocks_are_left_to_the_dense_path() {
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        let e = Entries::scan(2, 2, |r, c| singular[(r, c)]);
        assert!(min_change(&e, &[1.0, 1.0], &[0.0, 0.0]).is_none());
        let tall = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let e = Entries::scan(3, 2, |r, c| tall[(r, c)]);
        assert!(min_change(&e, &[1.0, 1.0, 1.0], &[0.0, 0.0]).is_none());
        // Nothing at all: every column a kernel direction.
        let e = Entries::scan(2, 3, |_, _| 0.0);
        let got = min_change(&e, &[1.0, 2.0], &[1.0, 0.0, -1.0]).expect("empty");
        assert_eq!(
            (got.delta, got.rank, got.zero_cols),
            (vec![-1.0, 0.0, 1.0], 0, vec![0, 1, 2])
        );
    }
}

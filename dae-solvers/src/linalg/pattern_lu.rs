//! LU factors of a small sparse matrix whose pattern is fixed, on a pivot
//! sequence recorded once and replayed (the refactorisation of KLU and
//! MA48, at the size of Radau IIA's coupled stage systems).
//!
//! A dense LU of the sensitivities' `3N × 3N` stage system
//! (`collocation::stagger`) spends most of its work on zeros: on the
//! pendulum (`N = 5`) the matrix has 69 structural non-zeros of 225 and
//! its elimination about 200 non-zero updates of the dense kernel's 1 015.
//! [`PatternLu`] takes the pattern once ([`PatternLu::new`]); its first
//! [`PatternLu::factor`] eliminates with partial pivoting among the
//! structural candidates of each column and records the pivot rows, the
//! rows below each pivot and the columns right of it, fill-in included
//! (the record); later factorisations replay the record — the same
//! operations on the non-zeros alone, no search, no row exchange — as long
//! as each recorded pivot is still the largest of its column's candidates.
//! When it is not, that factorisation is recorded afresh. The factors are
//! therefore always those of partial pivoting (up to the order in which
//! equal candidates are taken), and the arithmetic on each entry is the
//! dense kernel's in the same order: only updates by structural zeros are
//! skipped.
//!
//! Rows are never exchanged in storage: pivot `k` is a row (`Step::pivot`)
//! of the matrix as written (column-major, `n × n`), its multipliers stay in
//! their rows of column `k`, and [`PatternLu::solve`] reads the right-hand
//! side by rows and writes the solution by columns.

use super::{Pivoting, Singular};

/// Entries a [`PatternLu`] can hold (a matrix of at most 45 × 45). The
/// solve's indices are masked by `CAP − 1`, in bounds by construction, so
/// its indexed updates carry no bounds check.
pub(crate) const CAP: usize = 2048;
const MASK: usize = CAP - 1;
/// Entries of the storage: every `u16` position of the replay's record
/// ([`Record::flat`]) is in bounds by its type, so the replay's updates
/// carry neither a bounds check nor a mask (three instructions of about
/// thirteen an update). Only the first `n²` entries are ever touched; the
/// rest (512 KB, allocated zeroed) stays untouched.
const STORE: usize = 1 << 16;
/// Matrices of at most this many entries (2 KB) are cleared whole by
/// [`PatternLu::clear`]: a vector `memset` of about 250 instructions at
/// 15 × 15, where clearing the pendulum's 100-odd touched entries one by
/// one costs more; above it glibc's `memset` turns to `rep stosb`, which
/// callgrind counts byte by byte (2 600 instructions at 18 × 18), and the
/// touched entries alone are cleared.
const CLEAR_WHOLE: usize = 256;
/// Rows of the largest matrix.
const ROWS_CAP: usize = 64;
/// Entries of the solve's scratch: every `u8` row of the record is in
/// bounds by its type.
const ROWS_STORE: usize = 1 << 8;

/// LU factors of an `n × n` matrix with a fixed pattern (see the [module
/// documentation](self)).
pub(crate) struct PatternLu {
    n: usize,
    /// The matrix (column-major, rows as written), then its factors.
    a: Box<[f64; STORE]>,
    /// Structural non-zeros of the matrix (column-major).
    pattern: Vec<bool>,
    /// The elimination last recorded, if any.
    record: Option<Record>,
    /// Scratch for the solution by rows.
    by_rows: Box<[f64; ROWS_STORE]>,
    /// How many factorisations recorded their elimination afresh.
    pub(crate) recorded: usize,
}

/// One elimination's pivot rows and the non-zeros it touches.
struct Record {
    /// Each column's elimination step, in order.
    steps: Vec<Step>,
    /// Every position the elimination reads or writes (the pattern and
    /// its fill): the entries to clear before the next matrix is written.
    touched: Vec<usize>,
    /// The multipliers `l_ik` of each column, step by step
    /// ([`Step::lower`]): their positions, which the replay scales, and
    /// the forward substitution's updates `x_row −= a_at x_from` in order
    /// ([`Solve`]).
    lower: Vec<Solve>,
    /// The replay's updates `(a_ij, l_ik, u_kj)` as positions in the
    /// matrix, in the order the record made them, step by step
    /// ([`Step::flat`]). One flat loop over them costs about half the
    /// nested loops' index arithmetic on the pendulum's 15 × 15 stage
    /// system, where most pivot rows reach two or three columns
    /// (BENCHMARKS.md §21).
    flat: Vec<[u16; 3]>,
    /// The back substitution's updates `(a_at, row)` (the entries of `U`
    /// above its diagonal), step by step ([`Step::back`]).
    back: Vec<(u16, u8)>,
    /// Updates `a_ij −= l_ik u_kj` of one elimination.
    updates: usize,
}

/// A multiplier at `at` (row `row`, pivot row `from`): one update
/// `x_row −= a_at x_from` of the forward substitution.
#[derive(Clone, Copy)]
struct Solve {
    at: u16,
    row: u8,
    from: u8,
}

/// The elimination of column `k`.
struct Step {
    /// Its offset `k n` in the matrix.
    column: usize,
    /// The pivot's row.
    pivot: usize,
    /// Its multipliers in [`Record::lower`] and its updates in
    /// [`Record::flat`].
    lower: std::ops::Range<usize>,
    flat: std::ops::Range<usize>,
    /// The pivot's position, and its row of the back substitution's
    /// updates in [`Record::back`].
    diag: u16,
    back: std::ops::Range<usize>,
}

impl PatternLu {
    /// Storage for an `n × n` matrix whose structural non-zeros are
    /// `pattern(i, j)`; `None` for a matrix of more than [`CAP`] entries.
    pub(crate) fn new(n: usize, pattern: impl Fn(usize, usize) -> bool) -> Option<Self> {
        if n * n > CAP || n > ROWS_CAP {
            return None;
        }
        Some(PatternLu {
            n,
            a: vec![0.0; STORE].into_boxed_slice().try_into().ok()?,
            pattern: (0..n * n).map(|at| pattern(at % n, at / n)).collect(),
            record: None,
            by_rows: Box::new([0.0; ROWS_STORE]),
            recorded: 0,
        })
    }

    /// Factorise the matrix `write` writes (column-major, `n × n`: every
    /// structural non-zero, into zeros: `write` may add) in place, `P A = L U` with partial
    /// pivoting ([`Pivoting::Checked`]): by the record when its pivots are
    /// still the largest, by a new record otherwise (`write` is then
    /// called again: a refused replay has overwritten part of the matrix).
    pub(crate) fn factor(&mut self, write: impl Fn(&mut [f64])) -> Result<(), Singular> {
        let nn = self.n * self.n;
        self.clear();
        write(&mut self.a[..nn]);
        if let Some(rec) = &self.record {
            if replay(rec, &mut self.a) {
                return Ok(());
            }
            self.clear();
            write(&mut self.a[..nn]);
        }
        self.recorded += 1;
        self.record = None;
        self.record = Some(record(&mut self.a[..nn], &self.pattern, self.n)?);
        Ok(())
    }

    /// Zeros over every entry a factorisation may have left non-zero:
    /// the whole matrix up to [`CLEAR_WHOLE`] entries or before the first
    /// record, the record's pattern and fill otherwise (every other entry
    /// is zero already).
    fn clear(&mut self) {
        let nn = self.n * self.n;
        match &self.record {
            Some(rec) if nn > CLEAR_WHOLE => {
                for &at in &rec.touched {
                    self.a[at & MASK] = 0.0;
                }
            }
            _ => self.a[..nn].fill(0.0),
        }
    }

    /// The updates of the recorded elimination (none before the first).
    pub(crate) fn updates(&self) -> usize {
        self.record.as_ref().map_or(0, |rec| rec.updates)
    }

    /// Solve `A x = b`: `b` by rows, overwritten with `x` by columns, with
    /// the factors of a successful [`PatternLu::factor`].
    pub(crate) fn solve(&mut self, b: &mut [f64]) {
        let Some(rec) = &self.record else {
            return;
        };
        let (n, a) = (self.n, &*self.a);
        let b = &mut b[..n];
        let x = &mut *self.by_rows;
        // L y = P b, in place by rows (in `x`).
        x[..n].copy_from_slice(b);
        for op in &rec.lower {
            x[usize::from(op.row)] -= a[usize::from(op.at)] * x[usize::from(op.from)];
        }
        // U x = y, column by column from the last.
        for (step, bk) in rec.steps.iter().zip(b).rev() {
            let xk = x[step.pivot & (ROWS_STORE - 1)] / a[usize::from(step.diag)];
            *bk = xk;
            for &(at, r) in &rec.back[step.back.clone()] {
                x[usize::from(r)] -= a[usize::from(at)] * xk;
            }
        }
    }
}

/// The elimination of `rec` on `a`; `false` (with `a` partly eliminated)
/// when a recorded pivot is no longer the largest of its column's
/// candidates, or is zero or not finite.
fn replay(rec: &Record, a: &mut [f64; STORE]) -> bool {
    for step in &rec.steps {
        let pivot = a[(step.column + step.pivot) & MASK];
        if Pivoting::Checked.singular(pivot.abs()) {
            return false;
        }
        // The multipliers, and whether the pivot is still the largest
        // (checked after scaling: a refused replay is written afresh).
        let inv = 1.0 / pivot;
        let mut largest = 0.0f64;
        for op in &rec.lower[step.lower.clone()] {
            let v = &mut a[usize::from(op.at)];
            if v.abs() > largest {
                largest = v.abs();
            }
            *v *= inv;
        }
        if largest > pivot.abs() {
            return false;
        }
        for &[at, l, u] in &rec.flat[step.flat.clone()] {
            let lu = a[usize::from(l)] * a[usize::from(u)];
            a[usize::from(at)] -= lu;
        }
    }
    true
}

/// Partial pivoting among the structural candidates of each column, on
/// `a` in place, and its record; `Err` at a singular pivot.
fn record(a: &mut [f64], pattern: &[bool], n: usize) -> Result<Record, Singular> {
    let mut nz = pattern.to_vec();
    let mut pivoted = vec![false; n];
    let mut rec = Record {
        steps: Vec::with_capacity(n),
        lower: Vec::new(),
        touched: Vec::new(),
        flat: Vec::new(),
        back: Vec::new(),
        updates: 0,
    };
    for k in 0..n {
        let ck = k * n;
        let mut p = None;
        let mut pmax = 0.0;
        for i in (0..n).filter(|&i| !pivoted[i] && nz[ck + i]) {
            let v = a[ck + i].abs();
            if p.is_none() || v > pmax {
                (p, pmax) = (Some(i), v);
            }
        }
        let Some(p) = p.filter(|_| !Pivoting::Checked.singular(pmax)) else {
            return Err(Singular);
        };
        pivoted[p] = true;
        let lower: Vec<usize> = (0..n).filter(|&i| !pivoted[i] && nz[ck + i]).collect();
        let inv = 1.0 / a[ck + p];
        for &i in &lower {
            a[ck + i] *= inv;
        }
        // Offsets `j n` of the columns `j > k` where the pivot row has a
        // structural non-zero.
        let mut right = Vec::new();
        for j in k + 1..n {
            if !nz[j * n + p] {
                continue;
            }
            let u = a[j * n + p];
            for &i in &lower {
                a[j * n + i] -= a[ck + i] * u;
                nz[j * n + i] = true;
            }
            right.push(j * n);
            rec.updates += lower.len();
        }
        let (lower_from, flat_from) = (rec.lower.len(), rec.flat.len());
        // Positions below `CAP` (at most 45 × 45 entries) fit in `u16`,
        // rows below `ROWS_CAP` in `u8`.
        let at = |pos: usize| pos as u16;
        rec.lower.extend(lower.iter().map(|&i| Solve {
            at: at(ck + i),
            row: i as u8,
            from: p as u8,
        }));
        for &off in &right {
            rec.flat.extend(
                lower
                    .iter()
                    .map(|&i| [at(off + i), at(ck + i), at(off + p)]),
            );
        }
        rec.steps.push(Step {
            column: ck,
            pivot: p,
            lower: lower_from..rec.lower.len(),
            flat: flat_from..rec.flat.len(),
            diag: at(ck + p),
            back: 0..0,
        });
    }
    // U's entries above the diagonal, column by column: the earlier pivot
    // rows with a non-zero in the column (fill included).
    for k in 0..n {
        let (ck, from) = (k * n, rec.back.len());
        for m in 0..k {
            let r = rec.steps[m].pivot;
            if nz[ck + r] {
                rec.back.push(((ck + r) as u16, r as u8));
            }
        }
        rec.steps[k].back = from..rec.back.len();
    }
    rec.touched = (0..n * n).filter(|&at| nz[at]).collect();
    Ok(rec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::DenseLu;

    /// A 9 × 9 matrix with a fixed pattern (about half its entries, the
    /// diagonal but one), its values moved by `s` so that different pivots
    /// win for different `s`.
    fn matrix(s: f64) -> (Vec<f64>, Vec<bool>) {
        let n = 9;
        let mut a = vec![0.0; n * n];
        let mut pattern = vec![false; n * n];
        for j in 0..n {
            for i in 0..n {
                let structural = (i == j || (i + 2 * j) % 5 == 0 || (i % 3 == j % 3 && i != 4))
                    && !(i == 4 && j == 4);
                if structural {
                    pattern[j * n + i] = true;
                    a[j * n + i] = ((i * 7 + j * 3) % 11) as f64 - 5.0 + s * (i as f64 - j as f64);
                }
            }
        }
        (a, pattern)
    }

    fn dense_solution(a: &[f64], b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let mut lu = DenseLu::new(n, Pivoting::Checked);
        lu.matrix_mut().as_mut_slice().copy_from_slice(a);
        lu.factor().unwrap();
        let mut x = b.to_vec();
        lu.solve(&mut x);
        x
    }

    #[test]
    fn replays_and_records_give_the_dense_partial_pivoting_solution() {
        let (a0, pattern) = matrix(0.0);
        let n = 9;
        let mut lu = PatternLu::new(n, |i, j| pattern[j * n + i]).unwrap();
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        for s in [0.0, 0.0, 0.01, 3.0, 3.0, -2.0] {
            let (a, _) = matrix(s);
            lu.factor(|m| m.copy_from_slice(&a)).unwrap();
            let mut x = b.clone();
            lu.solve(&mut x);
            let want = dense_solution(&a, &b);
            assert_eq!(x, want, "s = {s}");
        }
        // The repeated matrices replayed; some of the others re-recorded.
        assert!(lu.recorded >= 2 && lu.recorded < 6, "{}", lu.recorded);
        let _ = a0;
    }

    #[test]
    fn a_singular_matrix_is_refused_and_recorded_again_after() {
        let n = 2;
        let mut lu = PatternLu::new(n, |_, _| true).unwrap();
        assert!(lu
            .factor(|m| m.copy_from_slice(&[1.0, 2.0, 2.0, 4.0]))
            .is_err());
        lu.factor(|m| m.copy_from_slice(&[1.0, 2.0, 3.0, 4.0]))
            .unwrap();
        let mut x = [5.0, 6.0];
        lu.solve(&mut x);
        assert!(
            (x[0] + 1.0).abs() < 1e-15 && (x[1] - 2.0).abs() < 1e-15,
            "{x:?}"
        );
    }
}

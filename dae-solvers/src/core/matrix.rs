//! The linear systems of the Newton iterations, square or least squares.
//!
//! A method builds its iteration matrix from `E` and `J = ∂f/∂y −
//! ∂(E z)/∂y` (both `M × N`) and solves with it; whether `M = N` (an LU
//! factorisation) or `M > N` (a constrained least-squares solve, the
//! overdetermined formulations `ovd1`, `ovd0`) is the business of this
//! module alone. A method is generic over [`Corrector`] (one real system:
//! BDF) or [`StageSystems`] (the real and the complex system of Radau IIA),
//! and is written once for both kinds of formulation.
//!
//! # Least squares (ODASSL, QUALIDAES/GEOMS)
//!
//! For `M > N` the Newton step `δ` of `A δ = b` is the solution of
//!
//! ```text
//!     min ‖S (A_D δ − b_D)‖₂   subject to   A_C δ = b_C ,
//! ```
//!
//! where `A_C` are the constraint rows (held exactly: the iterate stays on
//! every constraint the formulation carries) and `A_D` the differential
//! rows, weighted by [`Rows`]: row `i` is divided by its largest leading
//! coefficient `|E_ij*|` and multiplied by the error weight of that unknown
//! `j*`, so that each differential row measures the defect in the
//! derivative of "its" unknown relative to that unknown's tolerance — the
//! weighting is invariant under scaling of rows and of unknowns. For a
//! square nonsingular matrix the solution is the exact one.
//!
//! # Radau's stage systems for `M > N`: one projection per factorisation
//!
//! Radau IIA's simplified Newton iteration splits, after RADAU5's
//! transformation `T`, into a real system `(γ/h E − J) w = r` and a complex
//! one `((α + iβ)/h E − J) w = r`. Solving each in its own least-squares
//! sense would test the differential rows of the real and of the complex
//! combination of the stages against *different* directions, so the
//! converged stages would satisfy no one square collocation system; the
//! method then loses RADAU5's superconvergence at the step points (measured
//! order 4 instead of 5 on `ovd1`, `ovd0`). [`ProjectedStages`] instead
//! fixes, at each factorisation, one set of test directions — those of the
//! real system's least-squares solve, `Wᵀ = (S D Z)ᵀ S` with `Z` an
//! orthonormal basis of the null space of the real matrix's constraint rows
//! `C` and `D` its differential rows — and solves both systems as the
//! square systems
//!
//! ```text
//!     [ C      ]       [ b_C    ]
//!     [ Wᵀ D   ] w  =  [ Wᵀ b_D ]      (N × N; D = c E_D − J_D, c = γ/h or (α + iβ)/h).
//! ```
//!
//! For the real system this is exactly its constrained least-squares
//! solution (the optimality condition of the LSE problem); for the complex
//! one it is the same projection. Because `Wᵀ` is the same for every stage,
//! the converged stages satisfy every constraint row and `Wᵀ` times the
//! differential rows at every stage: the collocation solution of one
//! square system per step, of order 5 at the step points (see the tests
//! of `odradau`). Each test direction is scaled so that its row of the
//! real matrix has largest entry one: the weights `S` are of the size of
//! the inverse tolerances, and unscaled rows `10²⁶` times larger than the
//! constraint rows defeat partial pivoting (the Newton iteration then
//! diverged on the first step). For a square nonsingular system the
//! projection is the exact solve.
//!
//! # Algebraic conditions among the differential rows
//!
//! Rows that hold derivatives may combine into one that holds none: in a
//! circuit's loop of capacitors and a voltage source (`mna_cv_loop`'s
//! `ovd0`), the loop's rows `(c1 + c2) e2' − c1 e1' = …`,
//! `c1 e1' − c1 e2' = −jv` and the source's derivative `e1' = …` hold
//! derivatives of `e1`, `e2` only, and one combination of the three fixes
//! the loop's current `jv`; likewise a dynamic row beside the derivative of
//! a constraint with the same row of `E`. Such a combination `V` with
//! `Vᵀ E_D = 0` is a condition on `y` alone. In the least-squares test it is
//! mixed with the rows' derivatives, and the unknown it fixes is then
//! determined as in a system of higher index: `odradau(ovd0)` on the CV
//! loop took 5 018 steps at 1e-10 (EXTREMES.md §5, lit9), 654 with it held.
//! (`core::eliminate` forms such rows for a mass-matrix model with a
//! state-dependent `E`; a constant `E` is left as it is there.)
//! [`ProjectedStages`] therefore holds `Vᵀ D` exactly, with `C`, and tests
//! the differential rows only on the null space of both (`V` from an SVD
//! of `E_D` with its rows scaled to largest entry one, found again only
//! when `E_D` changes). When `M = N`, or when `E_D` has full row rank
//! (`ovd1`), `V` is empty and nothing changes. `odbdf`'s corrector
//! ([`LstsqCorrector`]) holds the same `Vᵀ (c E_D − J_D)` exactly beside
//! its constraint rows: without it `odbdf(ovd0)` crawled on the CV loop
//! (111 550 steps at 1e-6; 112 with it, EXTREMES.md §5 "lit10").

use super::block::Part;
use crate::linalg::lstsq::{null_space, split_rows};
use crate::linalg::sparse::{Pattern, SparseFactor};
use crate::linalg::{
    all_finite, mat_vec, ComplexLu, ConstrainedLstsq, DenseLu, Pivoting, Singular,
};
use dae_core::system::{
    Blocks, DaeSystem, FormulationInfo, Pattern as SystemPattern, RowKind, Sparsity,
};
use nalgebra::{Complex, DMatrix};
use std::rc::Rc;

/// Unknowns from which a square iteration matrix is factorised by the
/// sparse LU ([`crate::linalg::sparse`]) rather than the dense one, unless
/// it is denser than [`SPARSE_DENSITY`]. Chosen by measurement
/// (BENCHMARKS.md §14).
pub(crate) const SPARSE_FROM: usize = if cfg!(feature = "sparse") {
    60
} else {
    usize::MAX
};

/// Largest share of structural non-zeros of the first iteration matrix for
/// which a large system stays on the sparse path; a denser one is
/// factorised dense from then on.
pub(crate) const SPARSE_DENSITY: f64 = 0.2;

/// Whether an `n × n` matrix with `nnz` structural non-zeros (the diagonal
/// included) is factorised sparse.
fn sparse_enough(n: usize, nnz: usize) -> bool {
    (nnz as f64) <= SPARSE_DENSITY * (n as f64) * (n as f64)
}

/// The structural non-zeros of one run's matrices on the compressed path:
/// the iteration pattern `U` (`E ∪ ∂f/∂y ∪ ∂(E z)/∂y ∪` the diagonal,
/// `N × N`), on which every [`Matrix::Compressed`] of the run holds its
/// values, and where each entry of the three patterns of
/// [`DaeSystem::sparsity`] sits in `U`. Made once per run, shared by the
/// matrices and read by the factorisations for their one analysis.
pub(crate) struct Structure {
    /// The iteration pattern `U`.
    iteration: SystemPattern,
    /// The system's own patterns (what its `*_values` methods fill).
    sparsity: Sparsity,
    /// Position in `U` of each entry of `E`, `∂f/∂y`, `∂(E z)/∂y`.
    leading_at: Vec<usize>,
    rhs_jacobian_at: Vec<usize>,
    leading_jacobian_at: Vec<usize>,
}

impl Structure {
    /// The structure of `sys` when its matrices are to be held compressed:
    /// square, at least [`SPARSE_FROM`] unknowns, and its iteration
    /// pattern (from the derivation, [`DaeSystem::sparsity`]) at most
    /// [`SPARSE_DENSITY`] full. `None` otherwise (the dense path; a system
    /// that reports no structure reports a full one).
    pub(crate) fn of(sys: &dyn DaeSystem) -> Option<Rc<Structure>> {
        let info = sys.info();
        let (m, n) = (info.equations(), info.unknowns());
        if m != n || n < SPARSE_FROM {
            return None;
        }
        let sparsity = sys.sparsity();
        let parts = [
            &sparsity.leading,
            &sparsity.rhs_jacobian,
            &sparsity.leading_jacobian,
        ];
        // A full part makes a full union: refused before it is formed.
        if parts
            .iter()
            .any(|p| (p.rows, p.cols) != (n, n) || !sparse_enough(n, p.nnz()))
        {
            return None;
        }
        let iteration = SystemPattern::from_entries(
            n,
            n,
            parts
                .iter()
                .flat_map(|p| p.entries())
                .chain((0..n).map(|i| (i, i))),
        );
        if !sparse_enough(n, iteration.nnz()) {
            return None;
        }
        let at = |p: &SystemPattern| -> Vec<usize> {
            p.entries()
                .map(|(r, c)| iteration.position(r, c).expect("U holds every part"))
                .collect()
        };
        Some(Rc::new(Structure {
            leading_at: at(&sparsity.leading),
            rhs_jacobian_at: at(&sparsity.rhs_jacobian),
            leading_jacobian_at: at(&sparsity.leading_jacobian),
            iteration,
            sparsity,
        }))
    }

    /// The pattern and analysis of the sparse LU for matrices on `U`.
    fn lu_pattern(&self) -> Result<Pattern, Singular> {
        let u = &self.iteration;
        Pattern::from_compressed(u.cols, u.col_ptr.clone(), u.row_idx.clone())
    }
}

/// An `M × N` matrix of a step loop (`E`, `J`, `∂(E z)/∂y`): dense, or its
/// values on the run's iteration pattern ([`Structure`]) — no `N × N`
/// buffer on the compressed path. Both forms are read as one slice of
/// values ([`Matrix::values`]), so that the entrywise work of a step loop
/// (`J −= ∂(E z)/∂y`, copies, finiteness) is written once; the
/// factorisations ([`StageSystems::factor`], [`Corrector::assemble`])
/// take either.
pub(crate) enum Matrix {
    /// Column-major `M × N`.
    Dense(DMatrix<f64>),
    /// Values on the iteration pattern, in its order.
    Compressed {
        structure: Rc<Structure>,
        values: Vec<f64>,
        /// The system's own values of one part, before they are placed.
        own: Vec<f64>,
    },
}

impl Matrix {
    /// Zeros: compressed on `structure` when given, else dense `m × n`.
    pub(crate) fn new(m: usize, n: usize, structure: Option<&Rc<Structure>>) -> Self {
        match structure {
            None => Matrix::Dense(DMatrix::zeros(m, n)),
            Some(s) => Matrix::Compressed {
                structure: Rc::clone(s),
                values: vec![0.0; s.iteration.nnz()],
                own: Vec::new(),
            },
        }
    }

    /// The dense matrix (a path that only runs dense: least squares, the
    /// end-point projection).
    pub(crate) fn dense(&self) -> &DMatrix<f64> {
        match self {
            Matrix::Dense(d) => d,
            Matrix::Compressed { .. } => unreachable!("a compressed matrix read as dense"),
        }
    }

    /// Every value: the dense matrix column-major, or the values on the
    /// iteration pattern.
    pub(crate) fn values(&self) -> &[f64] {
        match self {
            Matrix::Dense(d) => d.as_slice(),
            Matrix::Compressed { values, .. } => values,
        }
    }

    /// Every value, to write (see [`Matrix::values`]).
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        match self {
            Matrix::Dense(d) => d.as_mut_slice(),
            Matrix::Compressed { values, .. } => values,
        }
    }

    /// `self ← other` (same form and shape).
    pub(crate) fn copy_from(&mut self, other: &Matrix) {
        self.values_mut().copy_from_slice(other.values());
    }

    /// `E(t, y)`.
    pub(crate) fn leading(&mut self, sys: &dyn DaeSystem, t: f64, y: &[f64]) {
        match self {
            Matrix::Dense(d) => sys.leading(t, y, d),
            Matrix::Compressed {
                structure: s,
                values,
                own,
            } => {
                own.resize(s.sparsity.leading.nnz(), 0.0);
                sys.leading_values(t, y, &s.sparsity.leading, own);
                place(values, own, &s.leading_at);
            }
        }
    }

    /// `∂f/∂y` at `(t, y)`.
    #[inline]
    pub(crate) fn rhs_jacobian(&mut self, sys: &dyn DaeSystem, t: f64, y: &[f64]) {
        match self {
            Matrix::Dense(d) => sys.rhs_jacobian(t, y, d),
            Matrix::Compressed {
                structure: s,
                values,
                own,
            } => {
                own.resize(s.sparsity.rhs_jacobian.nnz(), 0.0);
                sys.rhs_jacobian_values(t, y, &s.sparsity.rhs_jacobian, own);
                place(values, own, &s.rhs_jacobian_at);
            }
        }
    }

    /// `∂(E z)/∂y` at `(t, y)`.
    pub(crate) fn leading_jacobian(&mut self, sys: &dyn DaeSystem, t: f64, y: &[f64], z: &[f64]) {
        match self {
            Matrix::Dense(d) => sys.leading_jacobian(t, y, z, d),
            Matrix::Compressed {
                structure: s,
                values,
                own,
            } => {
                own.resize(s.sparsity.leading_jacobian.nnz(), 0.0);
                sys.leading_jacobian_values(t, y, z, &s.sparsity.leading_jacobian, own);
                place(values, own, &s.leading_jacobian_at);
            }
        }
    }

    /// `out ← A x` (`x` length `N`, `out` length `M`).
    #[inline]
    pub(crate) fn mat_vec(&self, x: &[f64], out: &mut [f64]) {
        match self {
            Matrix::Dense(d) => mat_vec(d, x, out),
            Matrix::Compressed {
                structure: s,
                values,
                ..
            } => {
                // Column by column, like the dense product: the same sums
                // (the dense one adds exact zeros besides).
                out.fill(0.0);
                let u = &s.iteration;
                for (c, &xc) in x.iter().enumerate() {
                    for k in u.col_ptr[c]..u.col_ptr[c + 1] {
                        out[u.row_idx[k]] += values[k] * xc;
                    }
                }
            }
        }
    }
}

/// `values ← 0`, then `values[at[k]] = own[k]`.
fn place(values: &mut [f64], own: &[f64], at: &[usize]) {
    values.fill(0.0);
    for (&v, &k) in own.iter().zip(at) {
        values[k] = v;
    }
}

/// Whether a multistep method's Jacobian (and the iteration matrix formed
/// from it) is current: the reuse policy DASSL and MEBDF share.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum JacState {
    /// Must be evaluated (and factored) before the next Newton iteration.
    Needed,
    /// Evaluated during the current step attempt.
    Fresh,
    /// Evaluated on an earlier step (DASSL's `JCALC = 1`): a Newton failure
    /// with it is retried with a fresh one before the step is reduced.
    Stale,
}

/// Row classes and weights of a least-squares iteration matrix (see the
/// [module documentation](self)).
pub(crate) struct Rows {
    /// `true` for constraint rows (held exactly).
    pub(crate) exact: Vec<bool>,
    /// Weights of the differential rows.
    pub(crate) weight: Vec<f64>,
    /// `true` for the formulation's constraint rows. Those with a non-zero
    /// row of `E` (the acceleration level `G(q) v' + … = 0` of a model with
    /// a mass matrix) are conditions on `y'`, not on `y`: they are weighted
    /// like differential rows, not held exactly.
    constraint: Vec<bool>,
}

impl Rows {
    /// The row classes of a formulation, all weights one.
    pub(crate) fn new(info: &FormulationInfo) -> Self {
        let exact: Vec<bool> = info
            .rows
            .iter()
            .map(|r| matches!(r.kind, RowKind::Constraint { .. }))
            .collect();
        let weight = vec![1.0; exact.len()];
        Rows {
            constraint: exact.clone(),
            exact,
            weight,
        }
    }

    /// No rows: what a square LU reads (nothing).
    pub(crate) fn square() -> Self {
        Rows {
            exact: Vec::new(),
            weight: Vec::new(),
            constraint: Vec::new(),
        }
    }

    /// Weights from the leading matrix `e` (M×N) and the unknowns' error
    /// weights `w` (length N): `w_j* / |E_ij*|`, `j*` the largest entry of
    /// row `i` (`1/|E_ij*|` when `w_j*` is zero, one for a zero row).
    pub(crate) fn update(&mut self, e: &DMatrix<f64>, w: &[f64]) {
        for (i, &constraint) in self.constraint.iter().enumerate() {
            self.exact[i] = constraint && (0..e.ncols()).all(|j| e[(i, j)] == 0.0);
        }
        for (i, (weight, &exact)) in self.weight.iter_mut().zip(&self.exact).enumerate() {
            if exact {
                *weight = 1.0;
                continue;
            }
            let (mut jmax, mut emax) = (0, 0.0_f64);
            for j in 0..e.ncols() {
                let a = e[(i, j)].abs();
                if a > emax {
                    emax = a;
                    jmax = j;
                }
            }
            *weight = if emax > 0.0 && emax.is_finite() {
                let wj = w[jmax];
                if wj > 0.0 && wj.is_finite() {
                    wj / emax
                } else {
                    1.0 / emax
                }
            } else {
                1.0
            };
        }
    }
}

/// Write `c E − J (+ L)` into the dense `a` (all three dense, of `a`'s
/// shape); whether every entry is finite. [`Corrector::assemble`]'s dense
/// form, shared by the correctors that wrap or fall back to it.
pub(crate) fn write_dense(
    a: &mut DMatrix<f64>,
    c: f64,
    e: &Matrix,
    j: &Matrix,
    l: Option<&Matrix>,
) -> bool {
    let a = a.as_mut_slice();
    for (g, (e, j)) in a.iter_mut().zip(e.values().iter().zip(j.values())) {
        *g = c * e - j;
    }
    if let Some(l) = l {
        for (g, l) in a.iter_mut().zip(l.values()) {
            *g += l;
        }
    }
    all_finite(a)
}

/// One real iteration matrix `A` (M×N) and its solver (BDF's corrector).
pub(crate) trait Corrector {
    /// Whether [`Corrector::factor`] reads [`Rows`] (least squares).
    const LEAST_SQUARES: bool;
    /// Storage for an `m × n` system.
    fn new(m: usize, n: usize) -> Self;
    /// Storage for an `m × n` system of these blocks
    /// ([`crate::core::block`]); the plain storage unless overridden.
    fn with_blocks(m: usize, n: usize, blocks: Option<Blocks>) -> Self
    where
        Self: Sized,
    {
        let _ = blocks;
        Self::new(m, n)
    }
    /// The matrix to write before [`Corrector::factor`].
    fn matrix_mut(&mut self) -> &mut DMatrix<f64>;
    /// Write `c E − J (+ L)` as the matrix to factor (`L = ∂(E z)/∂y`
    /// when given; all three of one form); whether every entry is finite.
    /// The default writes the dense matrix.
    fn assemble(&mut self, c: f64, e: &Matrix, j: &Matrix, l: Option<&Matrix>) -> bool {
        write_dense(self.matrix_mut(), c, e, j, l)
    }
    /// Factorise the matrix (least squares: with these row classes).
    fn factor(&mut self, rows: &Rows) -> Result<(), Singular>;
    /// `b[..M]` in, the step `δ` in `b[..N]` out.
    fn solve(&mut self, b: &mut [f64]);
}

/// DASSL's LU (LINPACK conventions) for square systems; from
/// [`SPARSE_FROM`] unknowns on, a sparse LU of the matrix's non-zeros
/// unless the first matrix is denser than [`SPARSE_DENSITY`].
pub(crate) struct SquareLu {
    lu: DenseLu,
    /// The sparse path: the matrix is assembled compressed
    /// ([`Corrector::assemble`] from [`Matrix::Compressed`]), or written
    /// into `a` and gathered.
    sparse: Option<SparseLu>,
}

/// The sparse path of [`SquareLu`].
struct SparseLu {
    n: usize,
    /// The dense matrix of a system without structure (allocated when
    /// first written).
    a: DMatrix<f64>,
    pattern: Option<Pattern>,
    factor: SparseFactor<f64>,
    /// The matrix assembled compressed, on the run's iteration pattern;
    /// empty on the gathered path.
    values: Vec<f64>,
    /// The run's structure, once a compressed matrix was assembled.
    structure: Option<Rc<Structure>>,
}

impl Corrector for SquareLu {
    const LEAST_SQUARES: bool = false;
    fn new(m: usize, n: usize) -> Self {
        debug_assert_eq!(m, n);
        if n >= SPARSE_FROM {
            SquareLu {
                lu: DenseLu::new(0, Pivoting::Linpack),
                sparse: Some(SparseLu {
                    n,
                    a: DMatrix::zeros(0, 0),
                    pattern: None,
                    factor: SparseFactor::new(),
                    values: Vec::new(),
                    structure: None,
                }),
            }
        } else {
            SquareLu {
                lu: DenseLu::new(n, Pivoting::Linpack),
                sparse: None,
            }
        }
    }
    #[inline]
    fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        match &mut self.sparse {
            None => self.lu.matrix_mut(),
            Some(s) => {
                if s.a.nrows() != s.n {
                    s.a = DMatrix::zeros(s.n, s.n);
                }
                &mut s.a
            }
        }
    }
    fn assemble(&mut self, c: f64, e: &Matrix, j: &Matrix, l: Option<&Matrix>) -> bool {
        let (Some(s), Matrix::Compressed { structure, .. }) = (&mut self.sparse, e) else {
            return write_dense(self.matrix_mut(), c, e, j, l);
        };
        if s.structure.is_none() {
            s.structure = Some(Rc::clone(structure));
        }
        s.values.clear();
        s.values
            .extend(e.values().iter().zip(j.values()).map(|(&e, &j)| c * e - j));
        if let Some(l) = l {
            for (g, l) in s.values.iter_mut().zip(l.values()) {
                *g += l;
            }
        }
        all_finite(&s.values)
    }
    fn factor(&mut self, _rows: &Rows) -> Result<(), Singular> {
        let Some(s) = &mut self.sparse else {
            return self.lu.factor();
        };
        if let Some(structure) = &s.structure {
            // Compressed: the pattern is the run's, analysed once.
            if s.pattern.is_none() {
                s.pattern = Some(structure.lu_pattern()?);
            }
            let p = s.pattern.as_ref().expect("the pattern was made above");
            let values = &s.values;
            return s.factor.factor_indexed(p, |k, _, _| values[k]);
        }
        let a = &s.a;
        let nonzero = |r: usize, c: usize| a[(r, c)] != 0.0;
        match &mut s.pattern {
            Some(p) => p.cover(nonzero)?,
            None => {
                let n = a.nrows();
                let p = Pattern::new(n, nonzero)?;
                if !sparse_enough(n, p.nnz()) {
                    // Too dense to gain: the dense LU from now on.
                    let mut lu = DenseLu::new(n, Pivoting::Linpack);
                    lu.matrix_mut().copy_from(a);
                    self.lu = lu;
                    self.sparse = None;
                    return self.lu.factor();
                }
                s.pattern = Some(p);
            }
        }
        let p = s.pattern.as_ref().expect("the pattern was made above");
        s.factor.factor(p, |r, c| a[(r, c)])
    }
    #[inline]
    fn solve(&mut self, b: &mut [f64]) {
        match &mut self.sparse {
            None => self.lu.solve(b),
            Some(s) => {
                let p = s.pattern.as_ref().expect("solve follows a factorisation");
                s.factor.solve(p, b)
            }
        }
    }
}

/// The constrained least-squares corrector of `odbdf` (ODASSL's): the
/// constraint rows exact, the differential rows weighted, and the algebraic
/// combinations of the differential rows held exactly beside the constraint
/// rows, as [`ProjectedStages`] holds them for `odradau` (see the
/// [module documentation](self)).
pub(crate) struct LstsqCorrector {
    ls: ConstrainedLstsq,
    n: usize,
    /// `E` of the last [`Corrector::assemble`] (dense), which the
    /// combinations are found from.
    e: DMatrix<f64>,
    alg: Combinations,
    /// The differential rows of the last factorisation, in order.
    diff_rows: Vec<usize>,
}

impl Corrector for LstsqCorrector {
    const LEAST_SQUARES: bool = true;
    fn new(m: usize, n: usize) -> Self {
        LstsqCorrector {
            ls: ConstrainedLstsq::new(m, n),
            n,
            e: DMatrix::zeros(m, n),
            alg: Combinations::default(),
            diff_rows: Vec::with_capacity(m),
        }
    }
    fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        self.ls.matrix_mut()
    }
    fn assemble(&mut self, c: f64, e: &Matrix, j: &Matrix, l: Option<&Matrix>) -> bool {
        self.e.copy_from(e.dense());
        write_dense(self.ls.matrix_mut(), c, e, j, l)
    }
    fn factor(&mut self, rows: &Rows) -> Result<(), Singular> {
        self.diff_rows.clear();
        self.diff_rows
            .extend((0..rows.exact.len()).filter(|&i| !rows.exact[i]));
        let p = rows.exact.len() - self.diff_rows.len();
        // More differential rows than unknowns left by the constraint rows
        // (else the system is square, and solved exactly whatever its rows).
        let r = if p <= self.n && self.diff_rows.len() > self.n - p {
            self.alg.find(&self.e, &self.diff_rows)?
        } else {
            0
        };
        let q = self.diff_rows.len();
        self.ls
            .factor(&rows.exact, &rows.weight, &self.alg.v()[..r * q])
    }
    fn solve(&mut self, b: &mut [f64]) {
        self.ls.solve(b)
    }
}

/// The real system `γ/h E − J` and the complex system `(α + iβ)/h E − J`
/// of Radau IIA (see the [module documentation](self)).
pub(crate) trait StageSystems {
    /// Whether [`StageSystems::factor`] reads [`Rows`] (least squares).
    const LEAST_SQUARES: bool;
    /// Storage for `m × n` systems.
    fn new(m: usize, n: usize) -> Self;
    /// Storage for `m × n` systems of these blocks
    /// ([`crate::core::block`]); the plain storage unless overridden.
    fn with_blocks(m: usize, n: usize, blocks: Option<Blocks>) -> Self
    where
        Self: Sized,
    {
        let _ = blocks;
        Self::new(m, n)
    }
    /// Factorise `g E − J` and `(a + ib) E − J` (`g = γ/h`, `a = α/h`,
    /// `b = β/h`).
    fn factor(
        &mut self,
        e: &Matrix,
        j: &Matrix,
        g: f64,
        a: f64,
        b: f64,
        rows: &Rows,
    ) -> Result<(), Singular>;
    /// Real system: `x[..M]` in, `x[..N]` out.
    fn solve_real(&mut self, x: &mut [f64]);
    /// Complex system with right-hand side `re[..M] + i im[..M]`; the
    /// solution in `re[..N] + i im[..N]`.
    fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]);
    /// [`StageSystems::solve_real`] of one [`Part`] of a block system
    /// (the staggered corrector, [`crate::core::block`]); without blocks
    /// the whole system is the first part and there is no other.
    fn solve_real_part(&mut self, x: &mut [f64], part: Part) {
        if part == Part::First {
            self.solve_real(x);
        }
    }
    /// [`StageSystems::solve_complex`] of one [`Part`] (see
    /// [`StageSystems::solve_real_part`]).
    fn solve_complex_part(&mut self, re: &mut [f64], im: &mut [f64], part: Part) {
        if part == Part::First {
            self.solve_complex(re, im);
        }
    }
}

/// RADAU5's two LU factorisations (non-finite pivots count as singular):
/// dense, or from [`SPARSE_FROM`] unknowns on sparse (one pattern and
/// analysis for both, unless the first matrix is denser than
/// [`SPARSE_DENSITY`]).
pub(crate) struct SquareStages {
    real: DenseLu,
    complex: ComplexLu,
    sparse: Option<SparseStages>,
}

/// The sparse path of [`SquareStages`].
struct SparseStages {
    n: usize,
    pattern: Option<Pattern>,
    real: SparseFactor<f64>,
    complex: SparseFactor<Complex<f64>>,
    /// The complex right-hand side, then the solution.
    buf: Vec<Complex<f64>>,
}

impl SquareStages {
    /// The dense factorisations for `n` unknowns.
    fn dense(n: usize) -> Self {
        SquareStages {
            real: DenseLu::new(n, Pivoting::Checked),
            complex: ComplexLu::new(n),
            sparse: None,
        }
    }
}

impl SquareStages {
    /// The dense LUs of `g E − J` and `(a + ib) E − J` (`E` and `J`
    /// column-major `N × N`, like the factors).
    #[inline]
    fn factor_dense(
        &mut self,
        e: &DMatrix<f64>,
        j: &DMatrix<f64>,
        g: f64,
        a: f64,
        b: f64,
    ) -> Result<(), Singular> {
        let (e, j) = (e.as_slice(), j.as_slice());
        let len = e.len();
        let (e, j) = (&e[..len], &j[..len]);
        let x = &mut self.real.matrix_mut().as_mut_slice()[..len];
        for i in 0..len {
            x[i] = g * e[i] - j[i];
        }
        self.real.factor()?;
        let (re, im) = self.complex.parts_mut();
        let (re, im) = (&mut re[..len], &mut im[..len]);
        for i in 0..len {
            re[i] = a * e[i] - j[i];
            im[i] = b * e[i];
        }
        self.complex.factor()
    }
}

impl StageSystems for SquareStages {
    const LEAST_SQUARES: bool = false;
    fn new(m: usize, n: usize) -> Self {
        debug_assert_eq!(m, n);
        if n >= SPARSE_FROM {
            SquareStages {
                sparse: Some(SparseStages {
                    n,
                    pattern: None,
                    real: SparseFactor::new(),
                    complex: SparseFactor::new(),
                    buf: vec![Complex::new(0.0, 0.0); n],
                }),
                ..SquareStages::dense(0)
            }
        } else {
            SquareStages::dense(n)
        }
    }
    fn factor(
        &mut self,
        e: &Matrix,
        j: &Matrix,
        g: f64,
        a: f64,
        b: f64,
        _rows: &Rows,
    ) -> Result<(), Singular> {
        if self.sparse.is_none() {
            // The dense path first: no test of the sparse forms per
            // factorisation of a small system.
            if let (Matrix::Dense(e), Matrix::Dense(j)) = (e, j) {
                return self.factor_dense(e, j, g, a, b);
            }
        }
        if let (Some(s), Matrix::Compressed { structure, .. }) = (&mut self.sparse, e) {
            // Compressed: both matrices on the run's pattern, analysed once.
            if s.pattern.is_none() {
                s.pattern = Some(structure.lu_pattern()?);
            }
            let p = s.pattern.as_ref().expect("the pattern was made above");
            let (e, j) = (e.values(), j.values());
            s.real.factor_indexed(p, |k, _, _| g * e[k] - j[k])?;
            return s
                .complex
                .factor_indexed(p, |k, _, _| Complex::new(a * e[k] - j[k], b * e[k]));
        }
        let (e, j) = (e.dense(), j.dense());
        if let Some(s) = &mut self.sparse {
            let nonzero = |r: usize, c: usize| e[(r, c)] != 0.0 || j[(r, c)] != 0.0;
            match &mut s.pattern {
                Some(p) => p.cover(nonzero)?,
                None => {
                    let p = Pattern::new(s.n, nonzero)?;
                    if sparse_enough(s.n, p.nnz()) {
                        s.pattern = Some(p);
                    } else {
                        // Too dense to gain: the dense LUs from now on.
                        *self = SquareStages::dense(s.n);
                    }
                }
            }
        }
        if let Some(s) = &mut self.sparse {
            let p = s.pattern.as_ref().expect("the pattern was made above");
            s.real.factor(p, |r, c| g * e[(r, c)] - j[(r, c)])?;
            return s.complex.factor(p, |r, c| {
                let (e, j) = (e[(r, c)], j[(r, c)]);
                Complex::new(a * e - j, b * e)
            });
        }
        self.factor_dense(e, j, g, a, b)
    }
    #[inline]
    fn solve_real(&mut self, x: &mut [f64]) {
        match &mut self.sparse {
            None => self.real.solve(x),
            Some(s) => {
                let p = s.pattern.as_ref().expect("solve follows a factorisation");
                s.real.solve(p, x)
            }
        }
    }
    #[inline]
    fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]) {
        match &mut self.sparse {
            None => self.complex.solve(re, im),
            Some(s) => {
                let p = s.pattern.as_ref().expect("solve follows a factorisation");
                for (z, (&r, &i)) in s.buf.iter_mut().zip(re.iter().zip(im.iter())) {
                    *z = Complex::new(r, i);
                }
                s.complex.solve(p, &mut s.buf);
                for (z, (r, i)) in s.buf.iter().zip(re.iter_mut().zip(im.iter_mut())) {
                    (*r, *i) = (z.re, z.im);
                }
            }
        }
    }
}

/// The algebraic combinations of `q` rows holding derivatives, `e_d` their
/// rows of `E` (`q × n`, row-major): an orthonormal basis of the left null
/// space of `e_d` with each row scaled to largest entry one (a zero row is
/// one of them), found by an SVD and written to `out` in the rows' own
/// scale (`vᵀ e_d = 0`, `r × q` row-major); returns their number `r`. A
/// singular value counts as zero below `10³ ε max(n, q)`, the tolerance of
/// the rank of `E` elsewhere (`gauss`'s end-point projection).
pub(crate) fn algebraic_combinations(e_d: &[f64], n: usize, q: usize, out: &mut Vec<f64>) -> usize {
    out.clear();
    if q == 0 {
        return 0;
    }
    let scale: Vec<f64> = e_d
        .chunks_exact(n.max(1))
        .map(|row| {
            let big = row.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
            if big > 0.0 {
                1.0 / big
            } else {
                1.0
            }
        })
        .collect();
    // Transposed and padded with zero rows to at least q × q, so that the
    // SVD's Vᵀ is q × q.
    let b = DMatrix::from_fn(n.max(q), q, |c, s| {
        if c < n {
            e_d[s * n + c] * scale[s]
        } else {
            0.0
        }
    });
    let svd = b.svd(false, true);
    let Some(v_t) = svd.v_t else {
        return 0;
    };
    let tol = 1e3 * f64::EPSILON * n.max(q) as f64;
    let mut r = 0;
    for (i, &sigma) in svd.singular_values.iter().enumerate() {
        if sigma <= tol {
            out.extend((0..q).map(|s| v_t[(i, s)] * scale[s]));
            r += 1;
        }
    }
    r
}

/// Radau's stage systems for `M ≥ N`, projected onto one square system per
/// factorisation (see the [module documentation](self)): the constraint
/// rows as they are, and the differential rows tested against the weighted
/// least-squares directions of the real matrix, `Wᵀ = (S D Z)ᵀ S`.
pub(crate) struct ProjectedStages {
    m: usize,
    n: usize,
    /// Number of constraint rows (`p`) and of differential rows (`q`).
    p: usize,
    q: usize,
    /// Row indices of the constraint rows (first `p`), of the differential
    /// rows (first `q`), and the weights of the latter.
    exact_rows: Vec<usize>,
    diff_rows: Vec<usize>,
    weight: Vec<f64>,
    /// `Cᵀ` of the real matrix, then its QR factors (`N × p`).
    ct: Vec<f64>,
    tau: Vec<f64>,
    norms: Vec<f64>,
    /// Null-space basis `Z` of `C` (`N × k`, `k = N − p`).
    z: Vec<f64>,
    /// `Wᵀ` (`k × q`, row-major: row `l` is the test vector `l`).
    wt: Vec<f64>,
    /// `Wᵀ E_D` and `Wᵀ J_D` (`k × N`, row-major).
    we: Vec<f64>,
    wj: Vec<f64>,
    real: DenseLu,
    complex: ComplexLu,
    buf: Vec<f64>,
    cbuf: Vec<Complex<f64>>,
    /// The projected complex right-hand side, split (real, imaginary).
    cre: Vec<f64>,
    cim: Vec<f64>,
    /// The algebraic combinations of the differential rows.
    alg: Combinations,
}

impl ProjectedStages {
    /// `out[..p] = b_C`, `out[p..N] = Wᵀ b_D` (the square right-hand side).
    fn project<T: Copy + Default + std::ops::AddAssign + std::ops::Mul<f64, Output = T>>(
        &self,
        b: impl Fn(usize) -> T,
        out: &mut [T],
    ) {
        let (p, q) = (self.p, self.q);
        for (o, &i) in out.iter_mut().zip(&self.exact_rows[..p]) {
            *o = b(i);
        }
        for (o, wt) in out[p..self.n]
            .iter_mut()
            .zip(self.wt.chunks_exact(q.max(1)))
        {
            let mut sum = T::default();
            for (&w, &i) in wt.iter().zip(&self.diff_rows[..q]) {
                sum += b(i) * w;
            }
            *o = sum;
        }
    }
}

impl ProjectedStages {
    /// The algebraic combinations `V` of the differential rows (see
    /// [`Combinations::find`]), held exactly: the rows `Vᵀ (g E_D −
    /// J_D)` of the real matrix written to `ct` after the `p` constraint
    /// rows, and `Vᵀ` to the first rows of `wt`; returns their number `r`.
    /// Out of line: called only when there are more differential rows than
    /// test directions, and then found afresh only when `E` changes.
    #[inline(never)]
    fn combinations(
        &mut self,
        e: &DMatrix<f64>,
        j: &DMatrix<f64>,
        g: f64,
    ) -> Result<usize, Singular> {
        let (n, p, q) = (self.n, self.p, self.q);
        let r = self.alg.find(e, &self.diff_rows[..q])?;
        if r > n - p {
            return Err(Singular);
        }
        for (col, v) in self.ct[p * n..(p + r) * n]
            .chunks_exact_mut(n)
            .zip(self.alg.v.chunks_exact(q))
        {
            for (c, x) in col.iter_mut().enumerate() {
                *x = v
                    .iter()
                    .zip(&self.diff_rows[..q])
                    .map(|(&v, &i)| v * (g * e[(i, c)] - j[(i, c)]))
                    .sum();
            }
        }
        self.wt[..r * q].copy_from_slice(&self.alg.v[..r * q]);
        Ok(r)
    }
}

/// The algebraic combinations of a system's differential rows (see
/// [`algebraic_combinations`]), with the `E` (column-major) and the row
/// indices they were found for: found afresh only when either changes (a
/// constant `E`: once per run).
#[derive(Default)]
pub(crate) struct Combinations {
    /// Their number `r` and the combinations (`r × q`, row-major).
    r: usize,
    v: Vec<f64>,
    e: Vec<f64>,
    rows: Vec<usize>,
}

impl Combinations {
    /// The algebraic combinations of the differential rows `rows` of `e`:
    /// an orthonormal basis `V` of the left null space of `E_D` with each
    /// row of `E_D` scaled to largest entry one, kept in the original
    /// rows' scale (`vᵀ E_D = 0`, `r × q` row-major, `q = rows.len()`);
    /// returns their number `r`. Found afresh only when `E_D` or its rows
    /// changed since the last call.
    ///
    /// Such a combination is a condition on `y` alone hidden among rows
    /// that hold derivatives (see the [module documentation](self),
    /// "Algebraic conditions among the differential rows").
    pub(crate) fn find(&mut self, e: &DMatrix<f64>, rows: &[usize]) -> Result<usize, Singular> {
        let (n, q) = (e.ncols(), rows.len());
        // The whole of `E` is kept (column-major): one comparison of two
        // slices per factorisation while it stays the same.
        if self.rows.as_slice() == rows && self.e.as_slice() == e.as_slice() {
            return Ok(self.r);
        }
        self.rows.clear();
        self.rows.extend_from_slice(rows);
        self.e.clear();
        self.e.extend_from_slice(e.as_slice());
        let mut e_d = Vec::with_capacity(q * n);
        for &i in rows {
            e_d.extend((0..n).map(|c| e[(i, c)]));
        }
        if !all_finite(&e_d) {
            self.rows.clear();
            return Err(Singular);
        }
        self.r = algebraic_combinations(&e_d, n, q, &mut self.v);
        Ok(self.r)
    }

    /// The combinations of the last [`Combinations::find`] (`r × q`,
    /// row-major).
    pub(crate) fn v(&self) -> &[f64] {
        &self.v
    }
}

impl StageSystems for ProjectedStages {
    const LEAST_SQUARES: bool = true;
    fn new(m: usize, n: usize) -> Self {
        ProjectedStages {
            m,
            n,
            p: 0,
            q: 0,
            exact_rows: vec![0; m],
            diff_rows: vec![0; m],
            weight: vec![0.0; m],
            ct: vec![0.0; n * n],
            tau: vec![0.0; n],
            norms: vec![0.0; n],
            z: vec![0.0; n * n],
            wt: vec![0.0; m * n],
            we: vec![0.0; n * n],
            wj: vec![0.0; n * n],
            real: DenseLu::new(n, Pivoting::Checked),
            complex: ComplexLu::new(n),
            buf: vec![0.0; n],
            cbuf: vec![Complex::new(0.0, 0.0); n],
            cre: vec![0.0; n],
            cim: vec![0.0; n],
            alg: Combinations::default(),
        }
    }
    fn factor(
        &mut self,
        e: &Matrix,
        j: &Matrix,
        g: f64,
        a: f64,
        b: f64,
        rows: &Rows,
    ) -> Result<(), Singular> {
        let (e, j) = (e.dense(), j.dense());
        let (m, n) = (self.m, self.n);
        let (p, q) = split_rows(
            &rows.exact,
            &rows.weight,
            n,
            &mut self.exact_rows,
            &mut self.diff_rows,
            &mut self.weight,
        )?;
        debug_assert_eq!(p + q, m);
        (self.p, self.q) = (p, q);
        let k = n - p;
        let real = |r: usize, c: usize| g * e[(r, c)] - j[(r, c)];
        // The algebraic combinations of the differential rows (more of them
        // than test directions only: a square system is solved exactly
        // whatever its rows), held exactly beside the constraint rows.
        let r = if q > k {
            self.combinations(e, j, g)?
        } else {
            0
        };

        // Z: the null space of the real matrix's constraint rows C and of
        // the algebraic combinations V of its differential rows (written
        // after C by `combinations`).
        for (col, &i) in self.ct.chunks_exact_mut(n).zip(&self.exact_rows[..p]) {
            for (c, v) in col.iter_mut().enumerate() {
                *v = real(i, c);
            }
        }
        null_space(
            &mut self.ct,
            n,
            p + r,
            &mut self.tau,
            &mut self.norms,
            &mut self.z,
        )?;

        // After the r rows V (written by `combinations`), Wᵀ = (S D Z)ᵀ S
        // ((k − r) × q, row-major): entry (l, r) is s_r (D Z)_rl s_r.
        let wt = &mut self.wt[r * q..];
        for (l, zl) in self.z[..n * (k - r)].chunks_exact(n).enumerate() {
            for (r, (&i, &s)) in self.diff_rows[..q]
                .iter()
                .zip(&self.weight[..q])
                .enumerate()
            {
                let dz: f64 = zl.iter().enumerate().map(|(c, &zc)| real(i, c) * zc).sum();
                wt[l * q + r] = (s * dz) * s;
            }
        }
        // Each test vector scaled so that its row of the real matrix has
        // largest entry one: partial pivoting then sees rows of one size.
        for l in 0..k {
            let wt = &mut self.wt[l * q..(l + 1) * q];
            let big = (0..n).fold(0.0_f64, |acc, c| {
                let v: f64 = wt
                    .iter()
                    .zip(&self.diff_rows[..q])
                    .map(|(&w, &i)| w * real(i, c))
                    .sum();
                acc.max(v.abs())
            });
            if !(big > 0.0 && big.is_finite()) {
                return Err(Singular);
            }
            wt.iter_mut().for_each(|w| *w /= big);
        }
        // Wᵀ E_D and Wᵀ J_D (k × N, row-major).
        for l in 0..k {
            let wt = &self.wt[l * q..(l + 1) * q];
            for c in 0..n {
                let (mut se, mut sj) = (0.0, 0.0);
                for (&w, &i) in wt.iter().zip(&self.diff_rows[..q]) {
                    se += w * e[(i, c)];
                    sj += w * j[(i, c)];
                }
                self.we[l * n + c] = se;
                self.wj[l * n + c] = sj;
            }
        }

        let (exact_rows, we, wj) = (&self.exact_rows, &self.we, &self.wj);
        self.real.factor_from(|r, c| {
            if r < p {
                real(exact_rows[r], c)
            } else {
                let o = (r - p) * n + c;
                g * we[o] - wj[o]
            }
        })?;
        let (cre, cim) = self.complex.parts_mut();
        for c in 0..n {
            for r in 0..n {
                (cre[c * n + r], cim[c * n + r]) = if r < p {
                    let i = exact_rows[r];
                    (a * e[(i, c)] - j[(i, c)], b * e[(i, c)])
                } else {
                    let o = (r - p) * n + c;
                    (a * we[o] - wj[o], b * we[o])
                };
            }
        }
        self.complex.factor()
    }
    fn solve_real(&mut self, x: &mut [f64]) {
        let mut buf = std::mem::take(&mut self.buf);
        self.project(|i| x[i], &mut buf);
        self.real.solve(&mut buf);
        x[..self.n].copy_from_slice(&buf);
        self.buf = buf;
    }
    fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]) {
        let mut buf = std::mem::take(&mut self.cbuf);
        self.project(|i| Complex::new(re[i], im[i]), &mut buf);
        for (z, (r, i)) in buf.iter().zip(self.cre.iter_mut().zip(self.cim.iter_mut())) {
            *r = z.re;
            *i = z.im;
        }
        self.complex.solve(&mut self.cre, &mut self.cim);
        re[..self.n].copy_from_slice(&self.cre);
        im[..self.n].copy_from_slice(&self.cim);
        self.cbuf = buf;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::lstsq::lstsq;
    #[cfg(feature = "sparse")]
    use dae_core::interp::InterpretedModel;

    fn rng(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    fn rows(exact: &[bool], next: &mut impl FnMut() -> f64) -> Rows {
        Rows {
            exact: exact.to_vec(),
            weight: exact.iter().map(|_| 0.5 + next().abs()).collect(),
            constraint: exact.to_vec(),
        }
    }

    /// A random `E` with zero constraint rows and a random `J`.
    fn matrices(
        m: usize,
        n: usize,
        exact: &[bool],
        next: &mut impl FnMut() -> f64,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let e = DMatrix::from_fn(m, n, |r, _| if exact[r] { 0.0 } else { next() });
        let e = e + DMatrix::from_fn(m, n, |r, c| if !exact[r] && r % n == c { 2.0 } else { 0.0 });
        let j = DMatrix::from_fn(m, n, |_, _| next());
        (e, j)
    }

    /// Each step-loop matrix of the chain, compressed, holds exactly the
    /// non-zeros of the dense one (none outside the iteration pattern),
    /// and its product is the dense product.
    #[test]
    #[cfg(feature = "sparse")]
    fn compressed_matrices_hold_the_dense_entries() {
        let model =
            InterpretedModel::from_str(&crate::test_models::chain(13)).expect("the chain derives");
        for form in ["rcd0", "ggl1"] {
            let sys = model.system(form).expect("formulation");
            let n = sys.info().unknowns();
            assert!(n >= SPARSE_FROM, "{form}: {n} unknowns");
            let s = Structure::of(&sys).expect("sparse enough");
            let y: Vec<f64> = (0..n).map(|i| 0.3 + 0.01 * i as f64).collect();
            let z: Vec<f64> = (0..n).map(|i| 1.0 - 0.02 * i as f64).collect();
            for part in 0..3 {
                let (mut dense, mut comp) = (Matrix::new(n, n, None), Matrix::new(n, n, Some(&s)));
                for m in [&mut dense, &mut comp] {
                    match part {
                        0 => m.leading(&sys, 0.5, &y),
                        1 => m.rhs_jacobian(&sys, 0.5, &y),
                        _ => m.leading_jacobian(&sys, 0.5, &y, &z),
                    }
                }
                let d = dense.dense();
                for (k, (r, c)) in s.iteration.entries().enumerate() {
                    assert_eq!(comp.values()[k], d[(r, c)], "{form} part {part} ({r}, {c})");
                }
                let nonzero = |v: &[f64]| v.iter().filter(|v| **v != 0.0).count();
                assert_eq!(
                    nonzero(comp.values()),
                    nonzero(d.as_slice()),
                    "{form} part {part}"
                );
                let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
                dense.mat_vec(&z, &mut a);
                comp.mat_vec(&z, &mut b);
                assert_eq!(a, b, "{form} part {part}");
            }
        }
    }

    /// The compressed factorisations solve the systems the dense matrices
    /// make: Radau's real and complex ones, BDF's `c E − J + L`.
    #[test]
    #[cfg(feature = "sparse")]
    #[allow(clippy::needless_range_loop)] // r indexes the rows of a product
    fn compressed_factorisations_solve_the_dense_systems() {
        let model =
            InterpretedModel::from_str(&crate::test_models::chain(13)).expect("the chain derives");
        let sys = model.system("ggl1").expect("formulation");
        let n = sys.info().unknowns();
        let s = Structure::of(&sys).expect("sparse enough");
        let y: Vec<f64> = (0..n).map(|i| 0.3 + 0.01 * i as f64).collect();
        let z: Vec<f64> = (0..n).map(|i| 1.0 - 0.02 * i as f64).collect();
        let eval = |st: Option<&Rc<Structure>>| {
            let (mut e, mut j, mut l) = (
                Matrix::new(n, n, st),
                Matrix::new(n, n, st),
                Matrix::new(n, n, st),
            );
            e.leading(&sys, 0.5, &y);
            j.rhs_jacobian(&sys, 0.5, &y);
            l.leading_jacobian(&sys, 0.5, &y, &z);
            (e, j, l)
        };
        let (e, j, l) = eval(Some(&s));
        let (ed, jd, ld) = eval(None);
        let (ed, jd, ld) = (ed.dense(), jd.dense(), ld.dense());
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
        let check = |x: &[f64], a: &dyn Fn(usize, usize) -> f64, what: &str| {
            for r in 0..n {
                let ax: f64 = (0..n).map(|c| a(r, c) * x[c]).sum();
                assert!(
                    (ax - b[r]).abs() < 1e-9,
                    "{what}, row {r}: {ax} vs {}",
                    b[r]
                );
            }
        };

        let (g, al, be) = (30.0, 25.0, 12.0);
        let mut stages = SquareStages::new(n, n);
        stages
            .factor(&e, &j, g, al, be, &Rows::square())
            .expect("nonsingular");
        let mut x = b.clone();
        stages.solve_real(&mut x);
        check(&x, &|r, c| g * ed[(r, c)] - jd[(r, c)], "real");
        let (mut re, mut im) = (b.clone(), vec![0.0; n]);
        stages.solve_complex(&mut re, &mut im);
        // (a + ib) E − J applied to re + i·im: the real part is b, the
        // imaginary part zero.
        for r in 0..n {
            let (mut pr, mut pi) = (0.0, 0.0);
            for c in 0..n {
                let (ar, ai) = (al * ed[(r, c)] - jd[(r, c)], be * ed[(r, c)]);
                pr += ar * re[c] - ai * im[c];
                pi += ar * im[c] + ai * re[c];
            }
            assert!(
                (pr - b[r]).abs() < 1e-9 && pi.abs() < 1e-9,
                "complex, row {r}"
            );
        }

        let mut lu = SquareLu::new(n, n);
        assert!(lu.assemble(g, &e, &j, Some(&l)));
        lu.factor(&Rows::square()).expect("nonsingular");
        let mut x = b.clone();
        lu.solve(&mut x);
        check(&x, &|r, c| g * ed[(r, c)] - jd[(r, c)] + ld[(r, c)], "bdf");
    }

    #[test]
    fn projected_real_system_is_the_least_squares_solve() {
        let mut next = rng(7);
        for (m, n, exact) in [
            (7, 5, vec![false, false, false, false, true, true, true]),
            (6, 5, vec![false, true, false, false, true, false]),
            (3, 2, vec![false, false, true]),
        ] {
            let (e, j) = matrices(m, n, &exact, &mut next);
            let rows = rows(&exact, &mut next);
            let g = 3.7;
            let mut ps = ProjectedStages::new(m, n);
            ps.factor(
                &Matrix::Dense(e.clone()),
                &Matrix::Dense(j.clone()),
                g,
                2.0,
                3.0,
                &rows,
            )
            .expect("nonsingular");
            let a = DMatrix::from_fn(m, n, |r, c| g * e[(r, c)] - j[(r, c)]);
            let b: Vec<f64> = (0..m).map(|_| next()).collect();
            let want = lstsq(&a, &rows.exact, &rows.weight, &b).expect("lstsq");
            let mut x = b.clone();
            ps.solve_real(&mut x);
            for (u, v) in x[..n].iter().zip(&want) {
                assert!(
                    (u - v).abs() <= 1e-12 * (1.0 + v.abs()),
                    "{m}x{n}: {x:?} vs {want:?}"
                );
            }
        }
    }

    /// Rows holding derivatives whose combination holds none (two rows
    /// with one row of `E`, as a dynamic equation beside the derivative of
    /// a constraint) make a condition on the unknowns alone: the projected
    /// systems hold it exactly, as they hold the constraint rows, and test
    /// only what is left in the least-squares sense.
    /// `(E, J, exact rows, the algebraic combination)` of two systems with
    /// one algebraic combination among their differential rows:
    /// Gear–Hsu–Petzold at t = 0.7, η = 1, with the constraint's derivative
    /// kept as a row holding derivatives (the derivation's ovd0 substitutes
    /// it): the constraint, that row and the dynamic equation; then a 5 × 4
    /// system with a dependent pair of rows beside two independent ones.
    #[allow(clippy::type_complexity)]
    fn combination_systems(
        next: &mut impl FnMut() -> f64,
    ) -> [(DMatrix<f64>, DMatrix<f64>, Vec<bool>, Vec<f64>); 2] {
        let ghp_e = DMatrix::from_row_slice(3, 2, &[0.0, 0.0, 1.0, 0.7, 1.0, 0.7]);
        let ghp_j = DMatrix::from_row_slice(3, 2, &[-1.0, -0.7, 0.0, -1.0, 0.0, -2.0]);
        let mut e5 = DMatrix::from_fn(5, 4, |_, _| next());
        for c in 0..4 {
            e5[(0, c)] = 0.0;
            e5[(4, c)] = -2.5 * e5[(2, c)];
        }
        let j5 = DMatrix::from_fn(5, 4, |_, _| next());
        [
            (ghp_e, ghp_j, vec![true, false, false], vec![0.0, 1.0, -1.0]),
            (
                e5,
                j5,
                vec![true, false, false, false, false],
                vec![0.0, 0.0, 2.5, 0.0, 1.0],
            ),
        ]
    }

    #[test]
    fn algebraic_combinations_of_differential_rows_are_held_exactly() {
        let mut next = rng(5);
        for (e, j, exact, combination) in combination_systems(&mut next) {
            let (m, n) = e.shape();
            let rows = rows(&exact, &mut next);
            let (g, a, b) = (3.7, 2.5, 1.5);
            let mut ps = ProjectedStages::new(m, n);
            ps.factor(
                &Matrix::Dense(e.clone()),
                &Matrix::Dense(j.clone()),
                g,
                a,
                b,
                &rows,
            )
            .expect("nonsingular");
            assert_eq!(ps.alg.r, 1, "{m}x{n}");
            let rhs: Vec<f64> = (0..2 * m).map(|_| next()).collect();
            // The constraint row and the combination hold exactly in the
            // real system and in the complex one.
            let held = |x: &[f64], xi: &[f64], c: f64, d: f64| {
                let row = |w: &[f64], x: &[f64], xi: &[f64], r: &[f64]| {
                    let (mut re, mut im, mut want) = (0.0, 0.0, 0.0);
                    for (i, &wi) in w.iter().enumerate() {
                        for k in 0..n {
                            let (ar, ai) = (c * e[(i, k)] - j[(i, k)], d * e[(i, k)]);
                            re += wi * (ar * x[k] - ai * xi[k]);
                            im += wi * (ar * xi[k] + ai * x[k]);
                        }
                        want += wi * r[i];
                    }
                    (re - want, im)
                };
                let mut first = vec![0.0; m];
                first[0] = 1.0;
                [
                    row(&first, x, xi, &rhs[..m]),
                    row(&combination, x, xi, &rhs[..m]),
                ]
            };
            let mut x = rhs[..m].to_vec();
            ps.solve_real(&mut x);
            for (re, im) in held(&x[..n], &vec![0.0; n], g, 0.0) {
                assert!(re.abs() < 1e-12 && im == 0.0, "{m}x{n} real: {re}");
            }
            let (mut re, mut im) = (rhs[..m].to_vec(), vec![0.0; m]);
            ps.solve_complex(&mut re, &mut im);
            for (r, i) in held(&re[..n], &im[..n], a, b) {
                assert!(
                    r.abs() < 1e-12 && i.abs() < 1e-12,
                    "{m}x{n} complex: {r} {i}"
                );
            }
        }
    }

    /// `odbdf`'s corrector holds the algebraic combination of its
    /// differential rows exactly (the plain least-squares solve does not),
    /// on the two systems of the test above.
    #[test]
    fn lstsq_corrector_holds_algebraic_combinations_exactly() {
        let mut next = rng(7);
        for (e, j, exact, combination) in combination_systems(&mut next) {
            let (m, n) = e.shape();
            let rows = rows(&exact, &mut next);
            let c = 3.7;
            let (e, j) = (Matrix::Dense(e), Matrix::Dense(j));
            let rhs: Vec<f64> = (0..m).map(|_| next()).collect();
            let defect = |w: &[f64], x: &[f64]| {
                let (e, j) = (e.dense(), j.dense());
                let mut d = 0.0;
                for (i, &wi) in w.iter().enumerate() {
                    let ax: f64 = (0..n).map(|k| (c * e[(i, k)] - j[(i, k)]) * x[k]).sum();
                    d += wi * (ax - rhs[i]);
                }
                d
            };
            let mut first = vec![0.0; m];
            first[0] = 1.0;
            let mut lc = LstsqCorrector::new(m, n);
            assert!(lc.assemble(c, &e, &j, None));
            lc.factor(&rows).expect("nonsingular");
            let mut x = rhs.clone();
            lc.solve(&mut x);
            for w in [&first, &combination] {
                let d = defect(w, &x[..n]);
                assert!(d.abs() < 1e-12, "{m}x{n}: {d}");
            }
            let mut plain = ConstrainedLstsq::new(m, n);
            write_dense(plain.matrix_mut(), c, &e, &j, None);
            plain
                .factor(&rows.exact, &rows.weight, &[])
                .expect("nonsingular");
            let mut x = rhs.clone();
            plain.solve(&mut x);
            let d = defect(&combination, &x[..n]);
            assert!(
                d.abs() > 1e-6,
                "{m}x{n}: the plain solve holds it too ({d})"
            );
        }
    }

    #[test]
    fn square_projected_systems_are_the_exact_solves() {
        let mut next = rng(11);
        let (m, n) = (5, 5);
        let exact = [false, false, false, true, true];
        let (e, j) = matrices(m, n, &exact, &mut next);
        let rows = rows(&exact, &mut next);
        let (g, a, b) = (3.7, 2.5, 1.5);
        let (e, j) = (Matrix::Dense(e), Matrix::Dense(j));
        let mut ps = ProjectedStages::new(m, n);
        ps.factor(&e, &j, g, a, b, &rows).expect("nonsingular");
        let mut sq = SquareStages::new(m, n);
        sq.factor(&e, &j, g, a, b, &rows).expect("nonsingular");
        let rhs: Vec<f64> = (0..2 * m).map(|_| next()).collect();
        let (mut x1, mut x2) = (rhs[..m].to_vec(), rhs[..m].to_vec());
        ps.solve_real(&mut x1);
        sq.solve_real(&mut x2);
        let (mut re1, mut im1) = (rhs[..m].to_vec(), rhs[m..].to_vec());
        let (mut re2, mut im2) = (re1.clone(), im1.clone());
        ps.solve_complex(&mut re1, &mut im1);
        sq.solve_complex(&mut re2, &mut im2);
        for (u, v) in x1
            .iter()
            .chain(&re1)
            .chain(&im1)
            .zip(x2.iter().chain(&re2).chain(&im2))
        {
            assert!((u - v).abs() <= 1e-12 * (1.0 + v.abs()), "{u} vs {v}");
        }
    }
}

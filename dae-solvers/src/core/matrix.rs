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
//! Radau's complex system `((α + iβ)/h E − J) w = r` is solved in the least
//! squares case as the real system of twice the size,
//! `[[αE/h − J, −βE/h], [βE/h, αE/h − J]] [Re w; Im w] = [Re r; Im r]`,
//! whose constraint rows are the constraint rows of both parts.

use crate::linalg::{ConstrainedLstsq, DenseLu, Pivoting, Singular};
use dae_core::system::{FormulationInfo, RowKind};
use nalgebra::{Complex, DMatrix};

/// Row classes and weights of a least-squares iteration matrix (see the
/// [module documentation](self)).
pub(crate) struct Rows {
    /// `true` for constraint rows (held exactly).
    pub(crate) exact: Vec<bool>,
    /// Weights of the differential rows.
    pub(crate) weight: Vec<f64>,
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
        Rows { exact, weight }
    }

    /// Weights from the leading matrix `e` (M×N) and the unknowns' error
    /// weights `w` (length N): `w_j* / |E_ij*|`, `j*` the largest entry of
    /// row `i` (`1/|E_ij*|` when `w_j*` is zero, one for a zero row).
    pub(crate) fn update(&mut self, e: &DMatrix<f64>, w: &[f64]) {
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

/// One real iteration matrix `A` (M×N) and its solver (BDF's corrector).
pub(crate) trait Corrector {
    /// Whether [`Corrector::factor`] reads [`Rows`] (least squares).
    const LEAST_SQUARES: bool;
    /// Storage for an `m × n` system.
    fn new(m: usize, n: usize) -> Self;
    /// The matrix to write before [`Corrector::factor`].
    fn matrix_mut(&mut self) -> &mut DMatrix<f64>;
    /// Factorise the matrix (least squares: with these row classes).
    fn factor(&mut self, rows: &Rows) -> Result<(), Singular>;
    /// `b[..M]` in, the step `δ` in `b[..N]` out.
    fn solve(&mut self, b: &mut [f64]);
}

/// DASSL's LU (LINPACK conventions) for square systems.
pub(crate) struct SquareLu(DenseLu<f64>);

impl Corrector for SquareLu {
    const LEAST_SQUARES: bool = false;
    fn new(m: usize, n: usize) -> Self {
        debug_assert_eq!(m, n);
        SquareLu(DenseLu::new(n, Pivoting::Linpack))
    }
    fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        self.0.matrix_mut()
    }
    fn factor(&mut self, _rows: &Rows) -> Result<(), Singular> {
        self.0.factor()
    }
    fn solve(&mut self, b: &mut [f64]) {
        self.0.solve(b)
    }
}

impl Corrector for ConstrainedLstsq {
    const LEAST_SQUARES: bool = true;
    fn new(m: usize, n: usize) -> Self {
        ConstrainedLstsq::new(m, n)
    }
    fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        ConstrainedLstsq::matrix_mut(self)
    }
    fn factor(&mut self, rows: &Rows) -> Result<(), Singular> {
        ConstrainedLstsq::factor(self, &rows.exact, &rows.weight)
    }
    fn solve(&mut self, b: &mut [f64]) {
        ConstrainedLstsq::solve(self, b)
    }
}

/// The real system `γ/h E − J` and the complex system `(α + iβ)/h E − J`
/// of Radau IIA (see the [module documentation](self)).
pub(crate) trait StageSystems {
    /// Whether [`StageSystems::factor`] reads [`Rows`] (least squares).
    const LEAST_SQUARES: bool;
    /// Storage for `m × n` systems.
    fn new(m: usize, n: usize) -> Self;
    /// Factorise `g E − J` and `(a + ib) E − J` (`g = γ/h`, `a = α/h`,
    /// `b = β/h`).
    fn factor(
        &mut self,
        e: &DMatrix<f64>,
        j: &DMatrix<f64>,
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
}

/// RADAU5's two LU factorisations (non-finite pivots count as singular).
pub(crate) struct SquareStages {
    real: DenseLu<f64>,
    complex: DenseLu<Complex<f64>>,
    buf: Vec<Complex<f64>>,
}

impl StageSystems for SquareStages {
    const LEAST_SQUARES: bool = false;
    fn new(m: usize, n: usize) -> Self {
        debug_assert_eq!(m, n);
        SquareStages {
            real: DenseLu::new(n, Pivoting::Checked),
            complex: DenseLu::new(n, Pivoting::Checked),
            buf: vec![Complex::new(0.0, 0.0); n],
        }
    }
    fn factor(
        &mut self,
        e: &DMatrix<f64>,
        j: &DMatrix<f64>,
        g: f64,
        a: f64,
        b: f64,
        _rows: &Rows,
    ) -> Result<(), Singular> {
        self.real.factor_from(|r, c| g * e[(r, c)] - j[(r, c)])?;
        self.complex
            .factor_from(|r, c| Complex::new(a * e[(r, c)] - j[(r, c)], b * e[(r, c)]))
    }
    fn solve_real(&mut self, x: &mut [f64]) {
        self.real.solve(x)
    }
    fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]) {
        for (z, (r, i)) in self.buf.iter_mut().zip(re.iter().zip(im.iter())) {
            *z = Complex::new(*r, *i);
        }
        self.complex.solve(&mut self.buf);
        for (z, (r, i)) in self.buf.iter().zip(re.iter_mut().zip(im.iter_mut())) {
            *r = z.re;
            *i = z.im;
        }
    }
}

/// Constrained least squares for Radau's stage systems, the complex one
/// in its real form of twice the size.
pub(crate) struct LstsqStages {
    m: usize,
    n: usize,
    real: ConstrainedLstsq,
    complex: ConstrainedLstsq,
    exact2: Vec<bool>,
    weight2: Vec<f64>,
    buf: Vec<f64>,
}

impl StageSystems for LstsqStages {
    const LEAST_SQUARES: bool = true;
    fn new(m: usize, n: usize) -> Self {
        LstsqStages {
            m,
            n,
            real: ConstrainedLstsq::new(m, n),
            complex: ConstrainedLstsq::new(2 * m, 2 * n),
            exact2: vec![false; 2 * m],
            weight2: vec![1.0; 2 * m],
            buf: vec![0.0; 2 * m],
        }
    }
    fn factor(
        &mut self,
        e: &DMatrix<f64>,
        j: &DMatrix<f64>,
        g: f64,
        a: f64,
        b: f64,
        rows: &Rows,
    ) -> Result<(), Singular> {
        let (m, n) = (self.m, self.n);
        let ar = self.real.matrix_mut();
        for c in 0..n {
            for r in 0..m {
                ar[(r, c)] = g * e[(r, c)] - j[(r, c)];
            }
        }
        self.real.factor(&rows.exact, &rows.weight)?;
        let ac = self.complex.matrix_mut();
        for c in 0..n {
            for r in 0..m {
                let d = a * e[(r, c)] - j[(r, c)];
                let o = b * e[(r, c)];
                ac[(r, c)] = d;
                ac[(r, n + c)] = -o;
                ac[(m + r, c)] = o;
                ac[(m + r, n + c)] = d;
            }
        }
        for part in 0..2 {
            self.exact2[part * m..(part + 1) * m].copy_from_slice(&rows.exact);
            self.weight2[part * m..(part + 1) * m].copy_from_slice(&rows.weight);
        }
        self.complex.factor(&self.exact2, &self.weight2)
    }
    fn solve_real(&mut self, x: &mut [f64]) {
        self.real.solve(x)
    }
    fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]) {
        let (m, n) = (self.m, self.n);
        self.buf[..m].copy_from_slice(&re[..m]);
        self.buf[m..2 * m].copy_from_slice(&im[..m]);
        self.complex.solve(&mut self.buf);
        re[..n].copy_from_slice(&self.buf[..n]);
        im[..n].copy_from_slice(&self.buf[n..2 * n]);
    }
}

//! The stage solve of the collocation engine, chosen per run: the real
//! system `γ/h E₀ − J` and the complex system `(α + iβ)/h E₀ − J`, square
//! (partial-pivoting LU, dense or sparse, with block forward substitution
//! for a state and its sensitivities) or projected least squares for an
//! overdetermined formulation (`M > N`, [`crate::odradau`]; see
//! `core::matrix`).

use crate::core::block::{Block, Part};
use crate::core::matrix::{Matrix, ProjectedStages, Rows, SquareStages, StageSystems};
use crate::linalg::Singular;
use dae_core::system::Blocks;

/// Which stage solve a run uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StageSolveKind {
    /// `M = N`: the two systems by LU.
    Square,
    /// `M ≥ N`: the two systems projected onto one square system per
    /// factorisation (the constraint rows exact, the differential rows
    /// tested against the real system's weighted least-squares
    /// directions).
    LeastSquares,
}

/// The two factorised stage systems of one run.
// One per run, held by value in the step loop's buffers: the square
// variant's size costs nothing, a box would cost a load per solve.
#[allow(clippy::large_enum_variant)]
pub(crate) enum StageSolve {
    /// [`StageSolveKind::Square`].
    Square(Block<SquareStages>),
    /// [`StageSolveKind::LeastSquares`].
    LeastSquares(ProjectedStages),
}

impl StageSolve {
    /// Storage for `m × n` systems of `kind` (a square one with these
    /// blocks, [`crate::core::block`]).
    pub(crate) fn new(kind: StageSolveKind, m: usize, n: usize, blocks: Option<Blocks>) -> Self {
        match kind {
            StageSolveKind::Square => StageSolve::Square(Block::with_blocks(m, n, blocks)),
            StageSolveKind::LeastSquares => StageSolve::LeastSquares(ProjectedStages::new(m, n)),
        }
    }

    /// Whether [`StageSolve::factor`] reads the row classes ([`Rows`]).
    #[inline]
    pub(crate) fn least_squares(&self) -> bool {
        matches!(self, StageSolve::LeastSquares(_))
    }

    /// Factorise `g E − J` and `(a + ib) E − J` with the shifts
    /// `[g, a, b] = [γ, α, β]/h`.
    // Inlined into the step attempt: left to the inliner it became a call
    // of its own when the attempt grew (the end-point projection of
    // colloc13), +0.3 % of radau5's instructions on the pendulum.
    #[inline(always)]
    pub(crate) fn factor(
        &mut self,
        e: &Matrix,
        j: &Matrix,
        [g, a, b]: [f64; 3],
        rows: &Rows,
    ) -> Result<(), Singular> {
        match self {
            // The plain square systems directly: no call through the block
            // wrapper once per factorisation.
            StageSolve::Square(Block::Plain(s)) => s.factor(e, j, g, a, b, rows),
            StageSolve::Square(s) => s.factor(e, j, g, a, b, rows),
            StageSolve::LeastSquares(s) => s.factor(e, j, g, a, b, rows),
        }
    }

    /// Real system: `x[..M]` in, `x[..N]` out.
    // Always inlined, the plain square solve inline and the others
    // called: in the Newton iteration's loop the square solve is inlined
    // as it was before the stage solve was a value.
    #[inline(always)]
    pub(crate) fn solve_real(&mut self, x: &mut [f64]) {
        match self {
            StageSolve::Square(Block::Plain(s)) => s.solve_real(x),
            StageSolve::Square(s) => s.solve_real(x),
            StageSolve::LeastSquares(s) => projected_real(s, x),
        }
    }

    /// Complex system with right-hand side `re[..M] + i im[..M]`; the
    /// solution in `re[..N] + i im[..N]`.
    #[inline(always)]
    pub(crate) fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]) {
        match self {
            StageSolve::Square(Block::Plain(s)) => s.solve_complex(re, im),
            StageSolve::Square(s) => s.solve_complex(re, im),
            StageSolve::LeastSquares(s) => projected_complex(s, re, im),
        }
    }

    /// [`StageSolve::solve_real`] of one [`Part`] of a block system.
    pub(crate) fn solve_real_part(&mut self, x: &mut [f64], part: Part) {
        match self {
            StageSolve::Square(s) => s.solve_real_part(x, part),
            StageSolve::LeastSquares(s) => s.solve_real_part(x, part),
        }
    }

    /// [`StageSolve::solve_complex`] of one [`Part`] of a block system.
    pub(crate) fn solve_complex_part(&mut self, re: &mut [f64], im: &mut [f64], part: Part) {
        match self {
            StageSolve::Square(s) => s.solve_complex_part(re, im, part),
            StageSolve::LeastSquares(s) => s.solve_complex_part(re, im, part),
        }
    }
}

/// [`StageSolve::solve_real`] of the least-squares solve, not inlined.
#[inline(never)]
fn projected_real(s: &mut ProjectedStages, x: &mut [f64]) {
    s.solve_real(x)
}

/// [`StageSolve::solve_complex`] of the least-squares solve, not inlined.
#[inline(never)]
fn projected_complex(s: &mut ProjectedStages, re: &mut [f64], im: &mut [f64]) {
    s.solve_complex(re, im)
}

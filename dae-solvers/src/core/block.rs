//! The block corrector of forward sensitivities: one factorisation of the
//! state's matrix for the whole block lower-triangular system.
//!
//! A system that is a state and its sensitivities side by side declares
//! [`Blocks`] ([`DaeSystem::blocks`](dae_core::system::DaeSystem::blocks)):
//! its `E` is block diagonal with `1 + P` equal blocks `E₀`, and its
//! Jacobian block lower triangular with `1 + P` equal diagonal blocks `J₀`
//! and the blocks `Bᵢ = ∂(J sᵢ + ∂f/∂pᵢ)/∂y` below them in the first block
//! column. Every iteration matrix a method forms, `c E − J` (BDF's real
//! one, Radau IIA's real `γ/h` and complex `(α + iβ)/h` ones), is then
//!
//! ```text
//!     [ A              ]
//!     [ −B₁   A        ]        A = c E₀ − J₀,
//!     [  ⋮        ⋱    ]
//!     [ −B_P        A  ]
//! ```
//!
//! and [`Block`] solves it by factorising `A` alone (of the size of the
//! state: the dense or the sparse LU the plain run would use) and block
//! forward substitution,
//!
//! ```text
//!     x₀ = A⁻¹ r₀,    xᵢ = A⁻¹ (rᵢ + Bᵢ x₀),
//! ```
//!
//! the exact solution of the same linear system: the Newton iteration is
//! the one of the dense `N (1 + P)` factorisation, at the cost of one `N × N`
//! factorisation and `1 + P` solves. A system without blocks (every other)
//! goes to the plain solver unchanged.
//!
//! A staggered corrector (radau5's, `radau5/stagger.rs`) solves the parts
//! one after the other instead ([`Part`]): the first block alone while it
//! iterates the state, then every later block by `A` alone while it
//! iterates the sensitivities with the state fixed (the state's increment,
//! which `Bᵢ` multiplies, is then zero), and its `J` holds no `Bᵢ`.
//!
//! The sensitivities may leave the error test ([`Blocks::error_control`]
//! false, [`in_error_test`]): they are then also out of the Newton norm,
//! which is safe because their rows are linear in them — the iteration
//! converges them with the state's contraction.

use super::matrix::{write_dense, Corrector, Matrix, Rows, StageSystems};
use crate::linalg::Singular;
use dae_core::system::Blocks;
use nalgebra::DMatrix;

/// Which blocks a staggered corrector solves for
/// ([`StageSystems::solve_real_part`]): the state's first, with its rows
/// alone, then the sensitivities' with the state fixed, whose stage
/// equations are linear and whose matrix is the state's `A` on every
/// block (the sub-diagonal `Bᵢ` multiply the state's increment, zero once
/// the state is fixed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Part {
    /// The first block, `x[..N]` (the rest of `x` untouched).
    First,
    /// Every later block by `A` alone (the first block untouched).
    Rest,
}

/// A square solver `S` (a [`Corrector`] or a [`StageSystems`]) of the whole
/// system, or of the state's block only with block forward substitution.
pub(crate) enum Block<S> {
    /// No block structure: `S` of the whole system.
    Plain(S),
    /// The block solve.
    Lower(Box<Lower<S>>),
}

/// [`Block::Lower`]: the state block's solver and the sub-diagonal blocks.
pub(crate) struct Lower<S> {
    /// Unknowns of a block, `N`.
    size: usize,
    /// Blocks, `1 + P`.
    count: usize,
    /// The solver of `A` (`N × N`).
    inner: S,
    /// [`Corrector`]: the whole matrix as the method writes it.
    full: DMatrix<f64>,
    /// [`StageSystems`]: `E₀` and `J₀`, the diagonal blocks.
    e0: Matrix,
    j0: Matrix,
    /// `Bᵢ` for `i = 1…P`, stacked (`P N × N`): the negated sub-diagonal
    /// blocks of the iteration matrix.
    below: DMatrix<f64>,
}

/// Whether `blocks` describes an `m × n` system a block solve can take.
fn usable(m: usize, n: usize, blocks: Option<Blocks>) -> Option<Blocks> {
    blocks.filter(|b| b.size > 0 && b.count > 1 && m == n && b.unknowns() == n)
}

impl<S> Lower<S> {
    fn new(b: Blocks, inner: S, full: bool) -> Self {
        let (n, p) = (b.size, b.count - 1);
        let whole = if full { b.unknowns() } else { 0 };
        Lower {
            size: n,
            count: b.count,
            inner,
            full: DMatrix::zeros(whole, whole),
            e0: Matrix::Dense(DMatrix::zeros(
                if full { 0 } else { n },
                if full { 0 } else { n },
            )),
            j0: Matrix::Dense(DMatrix::zeros(
                if full { 0 } else { n },
                if full { 0 } else { n },
            )),
            below: DMatrix::zeros(p * n, n),
        }
    }

    /// `x[n i..n (i+1)] += Bᵢ x[..n]` for every `i ≥ 1`, each block then
    /// solved by `solve` (the first one solved before).
    fn substitute(&mut self, x: &mut [f64], mut solve: impl FnMut(&mut S, &mut [f64])) {
        let n = self.size;
        let (first, rest) = x.split_at_mut(n);
        solve(&mut self.inner, first);
        for (i, xi) in rest[..n * (self.count - 1)].chunks_exact_mut(n).enumerate() {
            add_below(&self.below, n, i, first, xi);
            solve(&mut self.inner, xi);
        }
    }
}

/// `xi += B_{i+1} x0`, `B` stacked in `below` (`P n × n`, column-major:
/// column `c` of block `i` is contiguous).
#[inline]
fn add_below(below: &DMatrix<f64>, n: usize, i: usize, x0: &[f64], xi: &mut [f64]) {
    let stride = below.nrows();
    let data = below.as_slice();
    for (c, &x) in x0.iter().enumerate() {
        if x != 0.0 {
            let at = c * stride + n * i;
            for (v, &b) in xi.iter_mut().zip(&data[at..at + n]) {
                *v += b * x;
            }
        }
    }
}

impl<L: Corrector> Corrector for Block<L> {
    const LEAST_SQUARES: bool = L::LEAST_SQUARES;
    fn new(m: usize, n: usize) -> Self {
        Block::Plain(L::new(m, n))
    }
    fn with_blocks(m: usize, n: usize, blocks: Option<Blocks>) -> Self {
        match usable(m, n, blocks).filter(|_| !L::LEAST_SQUARES) {
            Some(b) => Block::Lower(Box::new(Lower::new(b, L::new(b.size, b.size), true))),
            None => Block::Plain(L::new(m, n)),
        }
    }
    #[inline]
    fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        match self {
            Block::Plain(l) => l.matrix_mut(),
            Block::Lower(b) => &mut b.full,
        }
    }
    fn assemble(&mut self, c: f64, e: &Matrix, j: &Matrix, l: Option<&Matrix>) -> bool {
        match self {
            // The wrapped corrector's own (compressed where it is).
            Block::Plain(inner) => inner.assemble(c, e, j, l),
            // A system declaring blocks reports no sparse structure.
            Block::Lower(b) => write_dense(&mut b.full, c, e, j, l),
        }
    }
    fn factor(&mut self, rows: &Rows) -> Result<(), Singular> {
        let b = match self {
            Block::Plain(l) => return l.factor(rows),
            Block::Lower(b) => b,
        };
        let n = b.size;
        b.inner.matrix_mut().copy_from(&b.full.view((0, 0), (n, n)));
        // The iteration matrix holds −Bᵢ below the diagonal.
        for i in 1..b.count {
            let mut dst = b.below.rows_mut(n * (i - 1), n);
            for (d, s) in dst.iter_mut().zip(b.full.view((n * i, 0), (n, n)).iter()) {
                *d = -s;
            }
        }
        b.inner.factor(rows)
    }
    #[inline]
    fn solve(&mut self, x: &mut [f64]) {
        match self {
            Block::Plain(l) => l.solve(x),
            Block::Lower(b) => b.substitute(x, |l, xi| l.solve(xi)),
        }
    }
}

impl<S: StageSystems> StageSystems for Block<S> {
    const LEAST_SQUARES: bool = S::LEAST_SQUARES;
    fn new(m: usize, n: usize) -> Self {
        Block::Plain(S::new(m, n))
    }
    fn with_blocks(m: usize, n: usize, blocks: Option<Blocks>) -> Self {
        match usable(m, n, blocks).filter(|_| !S::LEAST_SQUARES) {
            Some(b) => Block::Lower(Box::new(Lower::new(b, S::new(b.size, b.size), false))),
            None => Block::Plain(S::new(m, n)),
        }
    }
    fn factor(
        &mut self,
        e: &Matrix,
        j: &Matrix,
        g: f64,
        a: f64,
        bi: f64,
        rows: &Rows,
    ) -> Result<(), Singular> {
        let b = match self {
            Block::Plain(s) => return s.factor(e, j, g, a, bi, rows),
            Block::Lower(b) => b,
        };
        let n = b.size;
        // A system declaring blocks reports no sparse structure: its
        // matrices are dense (`Matrix::dense` says so where not).
        let (e, j) = (e.dense(), j.dense());
        if let (Matrix::Dense(e0), Matrix::Dense(j0)) = (&mut b.e0, &mut b.j0) {
            e0.copy_from(&e.view((0, 0), (n, n)));
            j0.copy_from(&j.view((0, 0), (n, n)));
        }
        // E is block diagonal: below the diagonal the real and the
        // complex matrices both hold −J's blocks, −Bᵢ.
        b.below.copy_from(&j.view((n, 0), (n * (b.count - 1), n)));
        b.inner.factor(&b.e0, &b.j0, g, a, bi, rows)
    }
    #[inline]
    fn solve_real(&mut self, x: &mut [f64]) {
        match self {
            Block::Plain(s) => s.solve_real(x),
            Block::Lower(b) => b.substitute(x, |s, xi| s.solve_real(xi)),
        }
    }
    fn solve_real_part(&mut self, x: &mut [f64], part: Part) {
        match (self, part) {
            (Block::Plain(s), Part::First) => s.solve_real(x),
            (Block::Plain(_), Part::Rest) => {}
            (Block::Lower(b), Part::First) => b.inner.solve_real(&mut x[..b.size]),
            (Block::Lower(b), Part::Rest) => {
                let n = b.size;
                for xi in x[n..n * b.count].chunks_exact_mut(n) {
                    b.inner.solve_real(xi);
                }
            }
        }
    }
    fn solve_complex_part(&mut self, re: &mut [f64], im: &mut [f64], part: Part) {
        match (self, part) {
            (Block::Plain(s), Part::First) => s.solve_complex(re, im),
            (Block::Plain(_), Part::Rest) => {}
            (Block::Lower(b), Part::First) => {
                let n = b.size;
                b.inner.solve_complex(&mut re[..n], &mut im[..n]);
            }
            (Block::Lower(b), Part::Rest) => {
                let (n, end) = (b.size, b.size * b.count);
                for (rei, imi) in re[n..end]
                    .chunks_exact_mut(n)
                    .zip(im[n..end].chunks_exact_mut(n))
                {
                    b.inner.solve_complex(rei, imi);
                }
            }
        }
    }
    fn solve_complex(&mut self, re: &mut [f64], im: &mut [f64]) {
        let b = match self {
            Block::Plain(s) => return s.solve_complex(re, im),
            Block::Lower(b) => b,
        };
        let n = b.size;
        let (re0, re_rest) = re.split_at_mut(n);
        let (im0, im_rest) = im.split_at_mut(n);
        b.inner.solve_complex(re0, im0);
        let blocks = n * (b.count - 1);
        for (i, (rei, imi)) in re_rest[..blocks]
            .chunks_exact_mut(n)
            .zip(im_rest[..blocks].chunks_exact_mut(n))
            .enumerate()
        {
            add_below(&b.below, n, i, re0, rei);
            add_below(&b.below, n, i, im0, imi);
            b.inner.solve_complex(rei, imi);
        }
    }
}

/// The components of an `n`-unknown system in its error test: all, or
/// with [`Blocks::error_control`] off the first block's only.
pub(crate) fn in_error_test(n: usize, blocks: Option<Blocks>) -> Vec<bool> {
    let mut mask = vec![true; n];
    restrict_error_test(&mut mask, blocks);
    mask
}

/// Take the blocks after the first out of `mask` when
/// [`Blocks::error_control`] is off.
pub(crate) fn restrict_error_test(mask: &mut [bool], blocks: Option<Blocks>) {
    if let Some(b) = blocks.filter(|b| !b.error_control && b.unknowns() == mask.len()) {
        mask[b.size..].fill(false);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::matrix::{SquareLu, SquareStages};

    fn rng(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// A block system (`n` per block, `count` blocks): `E` block diagonal
    /// with equal blocks, `J` with equal diagonal blocks and random blocks
    /// in the first block column.
    fn system(n: usize, count: usize, next: &mut impl FnMut() -> f64) -> [DMatrix<f64>; 2] {
        let e0 = DMatrix::from_fn(n, n, |r, c| {
            if r == c && r + 1 < n {
                1.0 + 0.5 * next().abs()
            } else {
                0.0
            }
        });
        let j0 = DMatrix::from_fn(n, n, |r, c| next() + if r == c { 3.0 } else { 0.0 });
        let w = n * count;
        let mut e = DMatrix::zeros(w, w);
        let mut j = DMatrix::zeros(w, w);
        for b in 0..count {
            e.view_mut((n * b, n * b), (n, n)).copy_from(&e0);
            j.view_mut((n * b, n * b), (n, n)).copy_from(&j0);
            if b > 0 {
                j.view_mut((n * b, 0), (n, n))
                    .copy_from(&DMatrix::from_fn(n, n, |_, _| next()));
            }
        }
        [e, j]
    }

    fn close(u: &[f64], v: &[f64]) {
        for (a, b) in u.iter().zip(v) {
            assert!((a - b).abs() <= 1e-11 * (1.0 + b.abs()), "{u:?} vs {v:?}");
        }
    }

    /// The block solves are the dense solves of the whole matrix: real,
    /// complex, and BDF's corrector.
    #[test]
    fn block_solves_are_the_dense_solves() {
        let mut next = rng(3);
        let (n, count) = (4, 3);
        let w = n * count;
        let [e, j] = system(n, count, &mut next);
        let blocks = Some(Blocks {
            size: n,
            count,
            error_control: true,
        });
        let rows = Rows::square();
        let (g, a, b) = (3.7, 2.5, 1.5);
        let mut dense = SquareStages::new(w, w);
        let (em, jm) = (Matrix::Dense(e.clone()), Matrix::Dense(j.clone()));
        dense.factor(&em, &jm, g, a, b, &rows).expect("nonsingular");
        let mut block = Block::<SquareStages>::with_blocks(w, w, blocks);
        assert!(matches!(block, Block::Lower(_)));
        block.factor(&em, &jm, g, a, b, &rows).expect("nonsingular");
        let rhs: Vec<f64> = (0..2 * w).map(|_| next()).collect();
        let (mut x1, mut x2) = (rhs[..w].to_vec(), rhs[..w].to_vec());
        dense.solve_real(&mut x1);
        block.solve_real(&mut x2);
        close(&x2, &x1);
        let (mut re1, mut im1) = (rhs[..w].to_vec(), rhs[w..].to_vec());
        let (mut re2, mut im2) = (re1.clone(), im1.clone());
        dense.solve_complex(&mut re1, &mut im1);
        block.solve_complex(&mut re2, &mut im2);
        close(&re2, &re1);
        close(&im2, &im1);

        let cj = 2.0;
        let matrix = DMatrix::from_fn(w, w, |r, c| cj * e[(r, c)] - j[(r, c)]);
        let mut dense = SquareLu::new(w, w);
        dense.matrix_mut().copy_from(&matrix);
        dense.factor(&rows).expect("nonsingular");
        let mut block = Block::<SquareLu>::with_blocks(w, w, blocks);
        block.matrix_mut().copy_from(&matrix);
        block.factor(&rows).expect("nonsingular");
        let (mut x1, mut x2) = (rhs[..w].to_vec(), rhs[..w].to_vec());
        dense.solve(&mut x1);
        block.solve(&mut x2);
        close(&x2, &x1);
    }

    /// The staggered corrector's part solves: the first block by `A`
    /// alone with the rest untouched, and every later block by `A` alone
    /// (no `Bᵢ`) with the first untouched; real and complex.
    #[test]
    fn part_solves_are_the_state_blocks_solves() {
        let mut next = rng(5);
        let (n, count) = (3, 3);
        let w = n * count;
        let [e, j] = system(n, count, &mut next);
        let blocks = Some(Blocks {
            size: n,
            count,
            error_control: false,
        });
        let rows = Rows::square();
        let (g, a, b) = (3.7, 2.5, 1.5);
        let mut block = Block::<SquareStages>::with_blocks(w, w, blocks);
        let (em, jm) = (Matrix::Dense(e.clone()), Matrix::Dense(j.clone()));
        block.factor(&em, &jm, g, a, b, &rows).expect("nonsingular");
        let mut state = SquareStages::new(n, n);
        let e0 = Matrix::Dense(e.view((0, 0), (n, n)).into_owned());
        let j0 = Matrix::Dense(j.view((0, 0), (n, n)).into_owned());
        state.factor(&e0, &j0, g, a, b, &rows).expect("nonsingular");
        let re: Vec<f64> = (0..w).map(|_| next()).collect();
        let im: Vec<f64> = (0..w).map(|_| next()).collect();

        let mut x = re.clone();
        block.solve_real_part(&mut x, Part::First);
        let mut x0 = re[..n].to_vec();
        state.solve_real(&mut x0);
        close(&x[..n], &x0);
        assert_eq!(x[n..], re[n..]);

        let (mut xr, mut xi) = (re.clone(), im.clone());
        block.solve_real_part(&mut x, Part::Rest);
        block.solve_complex_part(&mut xr, &mut xi, Part::Rest);
        assert_eq!(x[..n], x0[..]);
        assert_eq!((&xr[..n], &xi[..n]), (&re[..n], &im[..n]));
        for i in 1..count {
            let at = n * i..n * (i + 1);
            let mut s = re[at.clone()].to_vec();
            state.solve_real(&mut s);
            close(&x[at.clone()], &s);
            let (mut sr, mut si) = (re[at.clone()].to_vec(), im[at.clone()].to_vec());
            state.solve_complex(&mut sr, &mut si);
            close(&xr[at.clone()], &sr);
            close(&xi[at], &si);
        }
    }

    /// Without blocks, or with blocks that do not fit, the plain solver.
    #[test]
    fn plain_without_fitting_blocks() {
        let fit = |m, n, size, count| {
            let b = Blocks {
                size,
                count,
                error_control: true,
            };
            matches!(
                Block::<SquareLu>::with_blocks(m, n, Some(b)),
                Block::Lower(_)
            )
        };
        assert!(fit(6, 6, 2, 3));
        assert!(!fit(6, 6, 3, 3));
        assert!(!fit(6, 6, 6, 1));
        assert!(matches!(
            Block::<SquareLu>::with_blocks(6, 6, None),
            Block::Plain(_)
        ));
        let off = Blocks {
            size: 2,
            count: 3,
            error_control: false,
        };
        assert_eq!(
            in_error_test(6, Some(off)),
            [true, true, false, false, false, false]
        );
        assert_eq!(in_error_test(6, None), [true; 6]);
    }
}

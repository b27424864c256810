//! `mex0`: the square, strangeness-free formulation that keeps every
//! constraint — dummy derivatives (Mattsson & Söderlind 1993) in the form of
//! a minimal extension (Kunkel & Mehrmann 2006, §6.4; Steinbrecher 2006).
//!
//! Every level of every constraint chain is kept as an equation (the rows of
//! `ovd0`). To make the system square again, as many differential unknowns
//! as there are rows below the top level of their chains become **dummies**:
//! their derivatives are no longer integrated but determined by the
//! constraints — new algebraic unknowns in the minimal extension. The rows
//! that define those derivatives (`der(y) = v` for a dummy `y`) then only
//! define the dummy derivative itself, which no other row uses, so they are
//! dropped with it. What remains is `E z' = F(t, z)`, index 1: the dynamics
//! of the states not chosen, and all constraint levels, solved together for
//! the dummies and the algebraic unknowns. Nothing drifts (every constraint
//! holds to Newton's tolerance) and any index-1 solver takes it.
//!
//! **Which unknowns may be dummies** follows the structure of the chain
//! (Pryce's offsets read off the chain): a chain row differentiated `ℓ`
//! times below its top `c` has order `o = c − ℓ`; an unknown has order
//! `d_j`, the largest order of a row below the top that holds it. The rows
//! of order `o ≥ 1` choose their dummies among the differential unknowns of
//! order `o` — for a mechanical system the positions for the position
//! constraints, the velocities for the velocity constraints — and must also
//! determine the algebraic unknowns of that order. Ordered by order, the
//! Jacobian of all chain rows in the dummies and algebraic unknowns is block
//! triangular with these blocks on its diagonal, so the formulation has
//! index 1 exactly where every block is nonsingular.
//!
//! **State selection.** A block whose Jacobian is the same at three probe
//! points (a constant coefficient) or that has no choice (as many candidates
//! as dummies) gets one selection, made once: it never degenerates. The
//! others — the pendulum's `[2x, 2y]` — are chosen numerically: Gaussian
//! elimination with complete pivoting on the block (rows scaled to unit
//! largest entry, the block's algebraic unknowns pivoted first) picks the
//! dummies; the choice is checked whenever the leading matrix is evaluated
//! ([`DaeSystem::leading`], which every solver calls before it forms an
//! iteration matrix and, for a formulation whose `E` is not constant, at the
//! start of each step), and replaced when the determinant of the current
//! choice has fallen below [`RESELECT`] times that of the best one. On the
//! pendulum the dummy is `x` (and `v`) near the horizontal and `y` (and
//! `w`) near the vertical: it switches a few degrees past 45°, where
//! `|x| < 0.9 |y|` or the reverse, twice per swing; the factor is a
//! hysteresis, so the choice does not chatter.
//! Switching changes the equations, not the solution: both sets hold the
//! same constraints, and the dynamics dropped follow from them where the
//! block is nonsingular. A solver's history stays valid across a switch.
//!
//! Not built yet: models whose dynamics rows hold several derivatives (a
//! mass matrix) or whose constraint rows hold derivatives need the dummy
//! derivatives as unknowns of their own, and are refused
//! ([`DummyError::CoupledDerivatives`]).

use crate::system::{DaeSystem, FormulationInfo, RowInfo, RowKind, VarKind};
use nalgebra::DMatrix;
use std::cell::RefCell;

/// A selection is replaced when the determinant of its block has fallen
/// below this factor times the best one's (rows scaled to unit largest
/// entry). The integrated states' errors reach the dummies amplified by the
/// inverse of the selection's conditioning, so the choice is kept close to
/// the best: on S01 at tol 1e-8, `gauss(mex0)` ends with an error of
/// 4.9e-6 at 0.25, 1.8e-7 at 0.5 and 8.1e-9 at 0.9 (`gauss(rcd0)`: 8.1e-9),
/// `radau5` 3.1e-9, 9.6e-10 and 4.7e-10. Switching is cheap (no solver
/// restarts), and the remaining hysteresis keeps it from chattering.
pub const RESELECT: f64 = 0.9;

/// The formulation's name.
pub const NAME: &str = "mex0";

/// Why `mex0` cannot be built from a system.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DummyError {
    /// The system given is not the rows `mex0` selects from.
    #[error(
        "`mex0` is built from the model's `mex0` rows (every constraint level), not from `{given}`"
    )]
    WrongSource {
        /// The formulation given.
        given: String,
    },
    /// The chain or the leading matrix is not finite where the structure is
    /// probed.
    #[error("`mex0` cannot read the model's structure: the constraint chain, its Jacobian or the leading matrix is not finite at the probe points")]
    NotFinite,
    /// A dynamics row with several derivatives, or a constraint row with one.
    #[error("`mex0` needs each dynamics row to hold one derivative and the constraint rows none; row {row} (`{text}`) holds {count}: a mass matrix needs the dummy derivatives as unknowns of their own, which is not built yet (use `rcd0`, `ovd0` or `ggl1`)")]
    CoupledDerivatives {
        /// Row of the source formulation.
        row: usize,
        /// Its text.
        text: String,
        /// How many derivatives it holds.
        count: usize,
    },
    /// The rows of one order cannot choose their dummies: fewer candidates
    /// than rows to satisfy, or more algebraic unknowns than rows.
    #[error("`mex0` cannot choose dummy derivatives for the {rows} constraint rows of order {order}: {candidates} differential unknowns of that order to choose from and {algebraic} algebraic unknowns they must also determine")]
    NoChoice {
        /// Order of the rows (differentiations still below their top).
        order: u8,
        /// Number of rows.
        rows: usize,
        /// Differential unknowns of that order.
        candidates: usize,
        /// Algebraic unknowns of that order.
        algebraic: usize,
    },
    /// The counts do not make a square system.
    #[error("`mex0` would not be square: {equations} equations for {unknowns} unknowns")]
    NotSquare {
        /// Equations.
        equations: usize,
        /// Unknowns.
        unknowns: usize,
    },
}

/// The rows of one order and the unknowns they choose from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Block {
    /// Differentiations still below the top level of the rows' chains.
    pub order: u8,
    /// Members of the constraint chain ([`FormulationInfo::constraints`]).
    pub members: Vec<usize>,
    /// Algebraic unknowns of this order: always solved for here.
    pub algebraic: Vec<usize>,
    /// Differential unknowns of this order: the dummies are chosen among
    /// them.
    pub candidates: Vec<usize>,
}

impl Block {
    /// How many dummies the block chooses.
    pub fn dummies(&self) -> usize {
        self.members.len() - self.algebraic.len()
    }

    /// The algebraic unknowns, then the candidates.
    pub fn columns(&self) -> Vec<usize> {
        self.algebraic
            .iter()
            .chain(&self.candidates)
            .copied()
            .collect()
    }
}

/// The blocks of a formulation's constraint chain, from which unknowns each
/// member holds (`pattern[member][unknown]`), highest order first. Members
/// at the top of their chain have order 0 and are in no block. Shared by
/// the run-time formulation and `dae derive` (which reads the pattern off
/// the symbolic rows).
///
/// ```
/// use dae_core::dummy::blocks;
/// use dae_core::system::{ConstraintInfo, VarKind};
/// // The pendulum x, y, v, w, λ: g, g', g''.
/// let member = |level| ConstraintInfo { level, source: 0, expr: String::new() };
/// let chain = [member(0), member(1), member(2)];
/// let kinds = [VarKind::Differential, VarKind::Differential,
///              VarKind::Differential, VarKind::Differential, VarKind::Algebraic];
/// let pattern = vec![
///     vec![true, true, false, false, false],
///     vec![true, true, true, true, false],
///     vec![true, true, true, true, true],
/// ];
/// let b = blocks(&chain, &kinds, &pattern).unwrap();
/// assert_eq!(b.len(), 2);
/// assert_eq!((b[0].order, b[0].candidates.clone()), (2, vec![0, 1]));
/// assert_eq!((b[1].order, b[1].candidates.clone()), (1, vec![2, 3]));
/// ```
pub fn blocks(
    chain: &[crate::system::ConstraintInfo],
    kinds: &[VarKind],
    pattern: &[Vec<bool>],
) -> Result<Vec<Block>, DummyError> {
    let top = |source: u16| {
        chain
            .iter()
            .filter(|c| c.source == source)
            .map(|c| c.level)
            .max()
            .unwrap_or(0)
    };
    let order: Vec<u8> = chain.iter().map(|c| top(c.source) - c.level).collect();
    let n = kinds.len();
    let d: Vec<u8> = (0..n)
        .map(|j| {
            (0..chain.len())
                .filter(|&r| pattern[r][j])
                .map(|r| order[r])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let highest = order.iter().copied().max().unwrap_or(0);
    let mut out = Vec::new();
    for o in (1..=highest).rev() {
        let members: Vec<usize> = (0..chain.len()).filter(|&r| order[r] == o).collect();
        if members.is_empty() {
            continue;
        }
        let of_kind =
            |k: VarKind| -> Vec<usize> { (0..n).filter(|&j| d[j] == o && kinds[j] == k).collect() };
        let block = Block {
            order: o,
            algebraic: of_kind(VarKind::Algebraic),
            candidates: of_kind(VarKind::Differential),
            members,
        };
        if block.algebraic.len() > block.members.len() || block.candidates.len() < block.dummies() {
            return Err(DummyError::NoChoice {
                order: o,
                rows: block.members.len(),
                candidates: block.candidates.len(),
                algebraic: block.algebraic.len(),
            });
        }
        out.push(block);
    }
    Ok(out)
}

/// A block at run time: its structure, whether its choice is made once,
/// and the current choice.
#[derive(Clone, Debug)]
struct Live {
    block: Block,
    fixed: bool,
    chosen: Vec<usize>,
}

/// The current selection.
#[derive(Debug, Default)]
struct Selection {
    ready: bool,
    /// Output row `i` is inner row `map[i]`.
    map: Vec<usize>,
    /// How many times a choice was replaced after the first.
    switches: usize,
}

#[derive(Debug)]
struct Scratch {
    f: Vec<f64>,
    mat: DMatrix<f64>,
    jac: DMatrix<f64>,
}

/// `mex0` around the model's rows (see the [module documentation](self)).
pub struct DummyDerivatives<S> {
    inner: S,
    info: FormulationInfo,
    /// Inner differential unknowns with the inner row giving `der(y_j)`.
    dynamics: Vec<(usize, usize)>,
    /// Inner constraint rows, in inner order, with their chain member.
    constraint_rows: Vec<usize>,
    blocks: RefCell<Vec<Live>>,
    selection: RefCell<Selection>,
    scratch: RefCell<Scratch>,
}

impl<S: DaeSystem> std::fmt::Debug for DummyDerivatives<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DummyDerivatives")
            .field("model", &self.info.model)
            .field("dummies", &self.dummies())
            .finish_non_exhaustive()
    }
}

impl<S: DaeSystem> DummyDerivatives<S> {
    /// `mex0` around `inner`, the model's `mex0` rows (every level of every
    /// constraint, as in `ovd0`). The structure is probed at `t = 0`, `y = 0`
    /// and perturbed points — or, where `0` is not finite, at `y = 1`, and
    /// where that is not either (a distance `sqrt((x₂ − x₁)² + …)` in a
    /// denominator is zero wherever all unknowns are equal), at a point
    /// whose unknowns all differ; the first selection is made where the
    /// system is first evaluated.
    pub fn new(inner: S) -> Result<Self, DummyError> {
        let src = inner.info().clone();
        if src.name != NAME {
            return Err(DummyError::WrongSource { given: src.name });
        }
        let (m, n, k) = (src.equations(), src.unknowns(), src.constraints.len());
        // Probe points: the chain's pattern and the leading matrix's.
        let mut pattern = None;
        let mut base = vec![0.0; n];
        let starts = [vec![0.0; n], vec![1.0; n], distinct(n)];
        for start in starts {
            base = start;
            pattern = crate::system::chain_pattern(&inner, 0.0, &base);
            if pattern.is_some() {
                break;
            }
        }
        let pattern = pattern.ok_or(DummyError::NotFinite)?;
        let points: Vec<Vec<f64>> = std::iter::once(base.clone())
            .chain((0..2).map(|p| crate::system::perturbed(&base, p)))
            .collect();
        let mut e_pattern = vec![vec![false; n]; m];
        let mut e = DMatrix::zeros(m, n);
        for y in &points {
            inner.leading(0.0, y, &mut e);
            if !e.iter().all(|v| v.is_finite()) {
                return Err(DummyError::NotFinite);
            }
            for (i, row) in e_pattern.iter_mut().enumerate() {
                for (j, p) in row.iter_mut().enumerate() {
                    *p |= e[(i, j)] != 0.0;
                }
            }
        }
        let mut dynamics = Vec::new();
        let mut constraint_rows = Vec::new();
        for (i, row) in src.rows.iter().enumerate() {
            let cols: Vec<usize> = (0..n).filter(|&j| e_pattern[i][j]).collect();
            let expected = usize::from(row.kind == RowKind::Differential);
            if cols.len() != expected {
                return Err(DummyError::CoupledDerivatives {
                    row: i,
                    text: row.text.clone(),
                    count: cols.len(),
                });
            }
            match row.kind {
                RowKind::Differential => dynamics.push((cols[0], i)),
                RowKind::Constraint { .. } => constraint_rows.push(i),
            }
        }
        dynamics.sort_unstable();
        let kinds: Vec<VarKind> = src.variables.iter().map(|v| v.kind).collect();
        let found = blocks(&src.constraints, &kinds, &pattern)?;
        let dummies: usize = found.iter().map(Block::dummies).sum();
        let equations = dynamics.len() - dummies + constraint_rows.len();
        if equations != n || dummies > dynamics.len() {
            return Err(DummyError::NotSquare {
                equations,
                unknowns: n,
            });
        }
        // Blocks with one choice, or a Jacobian that is the same at every
        // probe point, choose once.
        let mut jacs = Vec::new();
        let mut jac = DMatrix::zeros(k, n);
        for y in &points {
            inner.constraints_jacobian(0.0, y, &mut jac);
            jacs.push(jac.clone());
        }
        let live: Vec<Live> = found
            .into_iter()
            .map(|block| {
                let cols: Vec<usize> = block.columns();
                let constant = block.members.iter().all(|&r| {
                    cols.iter().all(|&c| {
                        jacs.iter()
                            .all(|j| j[(r, c)].is_finite() && j[(r, c)] == jacs[0][(r, c)])
                    })
                });
                Live {
                    fixed: constant || block.candidates.len() == block.dummies(),
                    chosen: Vec::new(),
                    block,
                }
            })
            .collect();
        let mut rows: Vec<RowInfo> = (0..dynamics.len() - dummies)
            .map(|s| RowInfo {
                kind: RowKind::Differential,
                text: format!(
                    "the dynamics of selected state {} (the states not chosen as dummies at run time)",
                    s + 1
                ),
            })
            .collect();
        rows.extend(constraint_rows.iter().map(|&i| src.rows[i].clone()));
        let info = FormulationInfo {
            name: NAME.to_string(),
            variables: src
                .variables
                .iter()
                .map(|v| crate::system::VarInfo {
                    index: 1,
                    ..v.clone()
                })
                .collect(),
            rows,
            d_index: Some(1),
            s_index: 0,
            c_level: 0,
            constant_leading: false,
            constant_differential_leading: false,
            ..src
        };
        let sys = DummyDerivatives {
            inner,
            info,
            dynamics,
            constraint_rows,
            blocks: RefCell::new(live),
            selection: RefCell::new(Selection::default()),
            scratch: RefCell::new(Scratch {
                f: vec![0.0; m],
                mat: DMatrix::zeros(m, n),
                jac,
            }),
        };
        // Fixed blocks choose at the first probe point, where the
        // constraints' Jacobian is known to be finite.
        {
            let mut blocks = sys.blocks.borrow_mut();
            for b in blocks.iter_mut().filter(|b| b.fixed) {
                b.chosen = best(&b.block, &jacs[0]).0;
            }
        }
        Ok(sys)
    }

    /// The inner system (the rows `mex0` selects from).
    pub fn inner(&self) -> &S {
        &self.inner
    }

    /// Names of the current dummies (empty before the first evaluation).
    pub fn dummies(&self) -> Vec<String> {
        let mut out: Vec<usize> = self
            .blocks
            .borrow()
            .iter()
            .flat_map(|b| b.chosen.clone())
            .collect();
        out.sort_unstable();
        out.iter()
            .map(|&j| self.info.variables[j].name.clone())
            .collect()
    }

    /// The blocks and whether each is chosen once (`true`) or re-chosen at
    /// run time.
    pub fn blocks(&self) -> Vec<(Block, bool)> {
        self.blocks
            .borrow()
            .iter()
            .map(|b| (b.block.clone(), b.fixed))
            .collect()
    }

    /// How many times the selection changed after the first choice.
    pub fn switches(&self) -> usize {
        self.selection.borrow().switches
    }

    /// Choose the dummies at `(t, y)` if none are chosen yet; with `check`,
    /// re-choose every block whose choice has degenerated.
    fn select(&self, t: f64, y: &[f64], check: bool) {
        let ready = self.selection.borrow().ready;
        if ready && !check {
            return;
        }
        let mut blocks = self.blocks.borrow_mut();
        let mut changed = !ready;
        if blocks.iter().any(|b| !b.fixed) {
            let mut s = self.scratch.borrow_mut();
            self.inner.constraints_jacobian(t, y, &mut s.jac);
            let finite = s.jac.iter().all(|v| v.is_finite());
            for b in blocks.iter_mut().filter(|b| !b.fixed) {
                if !finite {
                    // Keep the choice; choose the first candidates if none.
                    if b.chosen.is_empty() {
                        b.chosen = b.block.candidates[..b.block.dummies()].to_vec();
                    }
                    continue;
                }
                let (choice, quality) = best(&b.block, &s.jac);
                let keep = !b.chosen.is_empty()
                    && determinant(&b.block, &b.chosen, &s.jac) >= RESELECT * quality;
                if !keep && choice != b.chosen {
                    if !b.chosen.is_empty() {
                        changed = true;
                    }
                    b.chosen = choice;
                    changed |= !ready;
                }
            }
        }
        if !changed {
            return;
        }
        let mut sel = self.selection.borrow_mut();
        if sel.ready {
            sel.switches += 1;
        }

        let dummy = |j: usize| blocks.iter().any(|b| b.chosen.contains(&j));
        sel.map = self
            .dynamics
            .iter()
            .filter(|&&(j, _)| !dummy(j))
            .map(|&(_, row)| row)
            .chain(self.constraint_rows.iter().copied())
            .collect();
        sel.ready = true;
    }

    fn rows_of(&self, src: &[f64], out: &mut [f64]) {
        let sel = self.selection.borrow();
        for (o, &r) in out.iter_mut().zip(&sel.map) {
            *o = src[r];
        }
    }

    fn rows_of_matrix(&self, src: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        let sel = self.selection.borrow();
        for (o, &r) in sel.map.iter().enumerate() {
            for j in 0..src.ncols() {
                out[(o, j)] = src[(r, j)];
            }
        }
    }
}

/// A probe point whose `n` unknowns are distinct and in `[0.5, 1.5)`:
/// `0.5 + frac((j + 1) φ)`, φ the golden ratio (no two equal, none zero).
fn distinct(n: usize) -> Vec<f64> {
    let phi = 0.5 * (1.0 + 5f64.sqrt());
    (0..n)
        .map(|j| 0.5 + ((j + 1) as f64 * phi).fract())
        .collect()
}

/// The block's Jacobian (members × `cols`), each row scaled to unit largest
/// entry over the block's columns.
fn scaled(block: &Block, cols: &[usize], jac: &DMatrix<f64>) -> DMatrix<f64> {
    let all: Vec<usize> = block.columns();
    let mut a = DMatrix::zeros(block.members.len(), cols.len());
    for (i, &r) in block.members.iter().enumerate() {
        let norm = all.iter().map(|&c| jac[(r, c)].abs()).fold(0.0, f64::max);
        let scale = if norm > 0.0 { 1.0 / norm } else { 1.0 };
        for (b, &c) in cols.iter().enumerate() {
            a[(i, b)] = jac[(r, c)] * scale;
        }
    }
    a
}

/// The best choice of dummies (Gaussian elimination, the algebraic unknowns
/// pivoted first with row pivoting, then complete pivoting among the
/// candidates) and its |determinant|.
fn best(block: &Block, jac: &DMatrix<f64>) -> (Vec<usize>, f64) {
    let cols: Vec<usize> = block.columns();
    let mut a = scaled(block, &cols, jac);
    let rows = a.nrows();
    let mut free_rows: Vec<usize> = (0..rows).collect();
    let mut free_cols: Vec<usize> = (block.algebraic.len()..cols.len()).collect();
    let mut det = 1.0;
    let mut chosen = Vec::new();
    for step in 0..rows {
        // The pivot: the next algebraic column (row pivoting only), or the
        // largest entry among the free candidate columns.
        let (pr, pc) = if step < block.algebraic.len() {
            let r = *free_rows
                .iter()
                .max_by(|&&x, &&y| a[(x, step)].abs().total_cmp(&a[(y, step)].abs()))
                .unwrap_or(&0);
            (r, step)
        } else {
            let mut at = (free_rows[0], free_cols[0]);
            for &r in &free_rows {
                for &c in &free_cols {
                    if a[(r, c)].abs() > a[at].abs() {
                        at = (r, c);
                    }
                }
            }
            at
        };
        let pivot = a[(pr, pc)];
        det *= pivot.abs();
        free_rows.retain(|&r| r != pr);
        if step >= block.algebraic.len() {
            free_cols.retain(|&c| c != pc);
            chosen.push(cols[pc]);
        }
        if pivot == 0.0 {
            continue;
        }
        for &r in &free_rows {
            let factor = a[(r, pc)] / pivot;
            if factor != 0.0 {
                for c in 0..cols.len() {
                    a[(r, c)] -= factor * a[(pr, c)];
                }
            }
        }
    }
    chosen.sort_unstable();
    (chosen, det)
}

/// |det| of the block restricted to its algebraic unknowns and `chosen`.
fn determinant(block: &Block, chosen: &[usize], jac: &DMatrix<f64>) -> f64 {
    let cols: Vec<usize> = block.algebraic.iter().chain(chosen).copied().collect();
    let a = scaled(block, &cols, jac);
    a.lu().determinant().abs()
}

impl<S: DaeSystem> DaeSystem for DummyDerivatives<S> {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.inner.parameter_values()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        self.select(t, y, false);
        let mut s = self.scratch.borrow_mut();
        self.inner.rhs(t, y, &mut s.f);
        self.rows_of(&s.f, f);
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        self.select(t, y, false);
        let mut s = self.scratch.borrow_mut();
        self.inner.residual(t, y, yp, &mut s.f);
        self.rows_of(&s.f, r);
    }
    fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>) {
        self.select(t, y, true);
        let mut s = self.scratch.borrow_mut();
        self.inner.leading(t, y, &mut s.mat);
        self.rows_of_matrix(&s.mat, e);
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.select(t, y, false);
        let mut s = self.scratch.borrow_mut();
        self.inner.rhs_jacobian(t, y, &mut s.mat);
        self.rows_of_matrix(&s.mat, j);
    }
    fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        self.select(t, y, false);
        let mut s = self.scratch.borrow_mut();
        self.inner.leading_jacobian(t, y, z, &mut s.mat);
        self.rows_of_matrix(&s.mat, j);
    }
    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.inner.constraints(t, y, g)
    }
    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.inner.constraints_jacobian(t, y, j)
    }
    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.inner.invariants(t, y, out)
    }
    fn event_names(&self) -> &[String] {
        self.inner.event_names()
    }
    fn events(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.inner.events(t, y, out)
    }
}

/// The blocks of `model`'s `mex0`, read off the symbolic chain (what
/// `dae derive` reports), or why `mex0` does not apply.
pub fn symbolic_blocks(
    model: &crate::model::Model,
    an: &crate::index::Analysis,
) -> Result<Vec<Block>, String> {
    use crate::expr::Sym;
    if an.max_level() == 0 {
        return Err(
            "`mex0` would repeat `rcd0`: no constraint is differentiated (d-index ≤ 1), so there is nothing to choose dummies for"
                .into(),
        );
    }
    let flat = an.flat();
    if model.has_mass_matrix()
        || !model.implicit.is_empty()
        || !an.implied.is_empty()
        || flat
            .iter()
            .any(|(_, _, e)| e.any_sym(&|s| matches!(s, Sym::Der(_))))
    {
        return Err(
            "`mex0` needs each dynamics row to hold one derivative and the constraints none; with a mass matrix (or an unknown whose derivative only other rows hold) the dummy derivatives must become unknowns of their own, which is not built yet: use `rcd0`, `ovd0` or `ggl1`"
                .into(),
        );
    }
    let chain: Vec<crate::system::ConstraintInfo> = flat
        .iter()
        .map(|&(source, level, _)| crate::system::ConstraintInfo {
            level: level as u8,
            source: source as u16,
            expr: String::new(),
        })
        .collect();
    let kinds: Vec<VarKind> = model.vars.iter().map(|v| v.kind).collect();
    let pattern: Vec<Vec<bool>> = flat
        .iter()
        .map(|(_, _, e)| {
            (0..kinds.len())
                .map(|j| model.involves(e, Sym::Var(j as u32)))
                .collect()
        })
        .collect();
    let found = blocks(&chain, &kinds, &pattern).map_err(|e| e.to_string())?;
    // The dynamics rows of the dummies go, every chain member stays.
    let dummies: usize = found.iter().map(Block::dummies).sum();
    let equations = (model.n_diff + flat.len()).checked_sub(dummies);
    if equations != Some(kinds.len()) {
        return Err(DummyError::NotSquare {
            equations: equations.unwrap_or(0),
            unknowns: kinds.len(),
        }
        .to_string()
            + ": an algebraic unknown whose derivative the chains need (its own equation would have to be differentiated as well) is not handled yet");
    }
    Ok(found)
}

/// `mex0` around `inner` as a boxed system, or the typed refusal of
/// [`crate::system::Model::formulation`] (used by the interpreter and the
/// `dae!` macro's generated models).
pub fn boxed<S: DaeSystem + Send + 'static>(
    inner: S,
    model: &crate::system::ModelInfo,
) -> Result<crate::system::BoxedSystem, crate::system::FormulationError> {
    DummyDerivatives::new(inner)
        .map(|s| Box::new(s) as crate::system::BoxedSystem)
        .map_err(|e| crate::system::FormulationError::NoSelector {
            model: model.name.clone(),
            name: NAME.to_string(),
            reason: e.to_string(),
            available: model.formulations.join(", "),
        })
}

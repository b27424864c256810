//! The runtime trait: what a solver sees of a formulation.
//!
//! A formulation is a quasi-linear DAE
//!
//! ```text
//!     E(t, y) y' = f(t, y),     E: M×N,  y ∈ ℝᴺ,  M ≥ N
//! ```
//!
//! with `M > N` for the overdetermined formulations (`ovd1`, `ovd0`) and `E`
//! depending on `y` for the projected ones (`psi1`, `psi0`); `E` depends on
//! `t` where a model's der() coefficients contain the time. Two
//! implementations exist and share one test suite: straight-line code emitted
//! by the `dae!` macro (fastest, sizes known at compile time, see
//! [`StaticSize`]) and the interpreter in [`crate::interp`] for models read at
//! run time.
//!
//! Every evaluation is in place: the caller owns the output buffers (one
//! allocation before the step loop, none inside it). Matrices are
//! [`nalgebra::DMatrix`] and are overwritten whole, zeros included.
//!
//! Besides the formulation's own rows, every system can evaluate the
//! *model's* constraint chain — the original constraints and all their hidden
//! derivatives, whichever of them the formulation uses — so that consistent
//! initialisation, drift reports and projections work the same for every
//! formulation.

use nalgebra::DMatrix;
use serde::Serialize;

/// Whether an unknown appears differentiated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VarKind {
    /// `der(u)` appears in the model.
    Differential,
    /// Algebraic: a Lagrange multiplier or similar.
    Algebraic,
}

/// One unknown of a formulation.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct VarInfo {
    /// Name as written in the model (`eta` for the GGL multipliers).
    pub name: String,
    /// Differential or algebraic.
    pub kind: VarKind,
    /// Index of the unknown in this formulation (1, 2 or 3): how many
    /// differentiations of the formulation's constraints determine it, plus
    /// one. Radau-type solvers scale the error of index-k components by
    /// `h^(k-1)` (Hairer–Wanner VII.8); BDF codes may leave index ≥ 2
    /// components out of the error test (DASPK).
    pub index: u8,
}

/// What a row of a formulation is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RowKind {
    /// A dynamic equation (possibly a projected combination of several):
    /// the row of `E` is not zero.
    Differential,
    /// `0 = g`, constraint `source` (0-based, in model order) differentiated
    /// `level` times along the model's dynamics.
    Constraint {
        /// Number of total time derivatives taken.
        level: u8,
        /// 0-based index of the original constraint.
        source: u16,
    },
}

impl RowKind {
    /// The constraint level, `None` for differential rows.
    pub fn level(&self) -> Option<u8> {
        match self {
            RowKind::Differential => None,
            RowKind::Constraint { level, .. } => Some(*level),
        }
    }
}

/// One row of a formulation.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RowInfo {
    /// Kind of the row.
    pub kind: RowKind,
    /// The row in the model language, e.g. `m*der(v) = -2*x*lambda`.
    pub text: String,
}

/// One member of the model's constraint chain.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ConstraintInfo {
    /// Number of total time derivatives taken (0 = as written).
    pub level: u8,
    /// 0-based index of the original constraint.
    pub source: u16,
    /// `0 = expr`: the expression in the model language.
    pub expr: String,
}

/// A named model parameter and its default value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamInfo {
    /// Name in the model.
    pub name: String,
    /// Default value from the `parameters { … }` block (of a derived
    /// parameter: its value at the base parameters' defaults).
    pub default: f64,
    /// `Some(expression)` for a derived parameter (`derived { k = …; }`),
    /// computed from the others and not settable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub derived: Option<String>,
}

/// Static description of a formulation: everything a solver or a report
/// needs besides the numbers.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FormulationInfo {
    /// Model name, e.g. `Pendulum`.
    pub model: String,
    /// Formulation name, e.g. `rcd1`.
    pub name: String,
    /// Unknowns in order (`y`).
    pub variables: Vec<VarInfo>,
    /// Rows in order.
    pub rows: Vec<RowInfo>,
    /// Differentiation index; `None` where undefined (overdetermined).
    pub d_index: Option<u8>,
    /// Strangeness index.
    pub s_index: u8,
    /// Maximal constraint level: the highest level of hidden constraint the
    /// formulation leaves out.
    pub c_level: u8,
    /// `true` when `E` depends neither on `y` nor on `t` (a solver may
    /// then evaluate and factor it once).
    pub constant_leading: bool,
    /// `true` when the differential rows' part of `E` depends neither on
    /// `y` nor on `t` (always when `constant_leading`). A model with a constant mass
    /// matrix has it, though its acceleration-level constraint rows keep
    /// `G(q)·v'`: its `E` is constant once those rows are made algebraic,
    /// which the solvers for a constant `E` then do.
    pub constant_differential_leading: bool,
    /// The model's constraint chain evaluated by [`DaeSystem::constraints`].
    pub constraints: Vec<ConstraintInfo>,
    /// Names of the invariants evaluated by [`DaeSystem::invariants`].
    pub invariants: Vec<String>,
    /// Parameter names in the order of the model.
    pub parameters: Vec<String>,
}

impl FormulationInfo {
    /// Number of unknowns `N`.
    pub fn unknowns(&self) -> usize {
        self.variables.len()
    }
    /// Number of equations `M` (`M > N` for overdetermined formulations).
    pub fn equations(&self) -> usize {
        self.rows.len()
    }
    /// Position of the unknown called `name`.
    pub fn variable(&self, name: &str) -> Option<usize> {
        self.variables.iter().position(|v| v.name == name)
    }
    /// Number of differential rows.
    pub fn differential_equations(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.kind == RowKind::Differential)
            .count()
    }
    /// `true` for `M > N`.
    pub fn is_overdetermined(&self) -> bool {
        self.equations() > self.unknowns()
    }
    /// The largest index of any unknown.
    pub fn max_index(&self) -> u8 {
        self.variables.iter().map(|v| v.index).max().unwrap_or(1)
    }
}

/// The structural non-zeros of a `rows × cols` matrix of a formulation,
/// in compressed-column form: the entries of column `c` are at rows
/// `row_idx[col_ptr[c]..col_ptr[c + 1]]`, ascending. An entry outside the
/// pattern is zero wherever the matrix is evaluated; one inside it may be
/// zero at some points.
///
/// ```
/// use dae_core::system::Pattern;
///
/// let p = Pattern::from_entries(3, 2, [(2, 0), (0, 0), (1, 1)]);
/// assert_eq!((p.col_ptr.as_slice(), p.row_idx.as_slice()), ([0, 2, 3].as_slice(), [0, 2, 1].as_slice()));
/// assert!(p.contains(2, 0) && !p.contains(2, 1));
/// assert_eq!(Pattern::dense(2, 2).nnz(), 4);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// Start of each column's entries in `row_idx` (length `cols + 1`).
    pub col_ptr: Vec<usize>,
    /// Row of each entry, column by column, ascending in each.
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Every entry: what a system that knows no structure reports.
    pub fn dense(rows: usize, cols: usize) -> Self {
        Pattern {
            rows,
            cols,
            col_ptr: (0..=cols).map(|c| c * rows).collect(),
            row_idx: (0..cols).flat_map(|_| 0..rows).collect(),
        }
    }

    /// The entries `(row, column)` given in any order (repeats counted
    /// once).
    ///
    /// # Panics
    ///
    /// If an entry is outside `rows × cols` (a programming error).
    pub fn from_entries(
        rows: usize,
        cols: usize,
        entries: impl IntoIterator<Item = (usize, usize)>,
    ) -> Self {
        let mut all: Vec<(usize, usize)> = entries
            .into_iter()
            .inspect(|&(r, c)| {
                assert!(
                    r < rows && c < cols,
                    "entry ({r}, {c}) outside {rows}×{cols}"
                )
            })
            .map(|(r, c)| (c, r))
            .collect();
        all.sort_unstable();
        all.dedup();
        let mut col_ptr = vec![0; cols + 1];
        for &(c, _) in &all {
            col_ptr[c + 1] += 1;
        }
        for c in 0..cols {
            col_ptr[c + 1] += col_ptr[c];
        }
        Pattern {
            rows,
            cols,
            col_ptr,
            row_idx: all.into_iter().map(|(_, r)| r).collect(),
        }
    }

    /// Number of structural non-zeros.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Whether `(row, col)` is a structural non-zero.
    pub fn contains(&self, row: usize, col: usize) -> bool {
        col < self.cols
            && self.row_idx[self.col_ptr[col]..self.col_ptr[col + 1]]
                .binary_search(&row)
                .is_ok()
    }

    /// The position in `row_idx` (and in a value array in this order) of
    /// `(row, col)`, if it is a structural non-zero.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        if col >= self.cols {
            return None;
        }
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[a..b].binary_search(&row).ok().map(|k| a + k)
    }

    /// The entries of `self` or `other` (same shape).
    ///
    /// # Panics
    ///
    /// If the shapes differ (a programming error).
    pub fn union(&self, other: &Pattern) -> Pattern {
        assert_eq!(
            (self.rows, self.cols),
            (other.rows, other.cols),
            "Pattern::union: shapes differ"
        );
        Pattern::from_entries(self.rows, self.cols, self.entries().chain(other.entries()))
    }

    /// The entries `(row, column)`, column by column.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.cols).flat_map(move |c| {
            self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]]
                .iter()
                .map(move |&r| (r, c))
        })
    }
}

/// A system of `count` blocks of `size` unknowns and `size` rows each
/// ([`DaeSystem::blocks`]): `E` is block diagonal with `count` equal
/// blocks, and `∂f/∂y − ∂(E z)/∂y` is block lower triangular with `count`
/// equal diagonal blocks and non-zeros below them in the first block
/// column only:
///
/// ```text
///     [ J    0   …  0 ]
///     [ B₁   J   …  0 ]        the iteration matrix c E − J has the
///     [ ⋮         ⋱   ]        diagonal blocks A = c E₀ − J and
///     [ B_P  0   …  J ]        below them −Bᵢ
/// ```
///
/// so that it is solved by factorising `A` alone: `x₀ = A⁻¹ r₀`,
/// `xᵢ = A⁻¹ (rᵢ + Bᵢ x₀)`.
///
/// ```
/// use dae_core::system::Blocks;
///
/// let b = Blocks { size: 5, count: 3, error_control: true };
/// assert_eq!(b.unknowns(), 15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blocks {
    /// Unknowns (and rows) of one block: the state's.
    pub size: usize,
    /// Blocks: the state's and one per sensitivity parameter.
    pub count: usize,
    /// Whether the blocks after the first are in the error test (and the
    /// Newton norm) of the methods; the first always is.
    pub error_control: bool,
}

impl Blocks {
    /// All unknowns, `size · count`.
    pub fn unknowns(&self) -> usize {
        self.size * self.count
    }
}

/// The structural non-zeros of a formulation's matrices, from its
/// symbolic rows: a Newton iteration matrix `c E − ∂f/∂y + ∂(E z)/∂y` has
/// at most the union of the three ([`Sparsity::iteration`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sparsity {
    /// `E` (M×N).
    pub leading: Pattern,
    /// `∂f/∂y` (M×N).
    pub rhs_jacobian: Pattern,
    /// `∂(E z)/∂y` (M×N; empty when `E` is constant).
    pub leading_jacobian: Pattern,
}

impl Sparsity {
    /// Every entry of every matrix: what a system that knows no structure
    /// reports ([`DaeSystem::sparsity`]'s default).
    pub fn dense(info: &FormulationInfo) -> Self {
        let (m, n) = (info.equations(), info.unknowns());
        Sparsity {
            leading: Pattern::dense(m, n),
            rhs_jacobian: Pattern::dense(m, n),
            leading_jacobian: Pattern::dense(m, n),
        }
    }

    /// The union of the three: the entries an iteration matrix can have.
    pub fn iteration(&self) -> Pattern {
        self.leading
            .union(&self.rhs_jacobian)
            .union(&self.leading_jacobian)
    }
}

/// The entry of a [`DaeSystem::rhs_jacobian_scatter`] map that is not
/// written.
pub const SKIP: usize = usize::MAX;

/// A formulation `E(t, y) y' = f(t, y)` ready to integrate.
///
/// All methods write into caller-owned buffers and never allocate. Slices
/// have length `N` (unknowns), `M` (equations), `K` (the constraint chain,
/// `info().constraints.len()`) or `I` (invariants) as documented; matrices
/// must already have the documented shape. Implementations may panic on
/// wrong buffer sizes (a programming error), never on values: non-finite
/// inputs give non-finite outputs for the solver to detect.
///
/// The `dae!` macro (or the interpreter, for a `.dae` file read at run time)
/// implements it for every formulation a model lists:
///
/// ```
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
/// use nalgebra::DMatrix;
///
/// let sys = Pendulum::default().rcd1(); // E y' = f(t, y), y = (x, y, v, w, lambda)
/// let info = sys.info();
/// assert_eq!((info.unknowns(), info.equations(), info.d_index), (5, 5, Some(2)));
/// let names: Vec<&str> = info.variables.iter().map(|v| v.name.as_str()).collect();
/// assert_eq!(names, ["x", "y", "v", "w", "lambda"]);
///
/// let y = [1.0, 0.0, 0.0, 0.0, 0.0]; // at rest, rod horizontal
/// let mut f = vec![0.0; 5];
/// sys.rhs(0.0, &y, &mut f);
/// assert_eq!(f[3], -Pendulum::default().g); // w' = -2 y lambda / m - g
/// let mut e = DMatrix::zeros(5, 5);
/// sys.leading(0.0, &y, &mut e); // E: identity on x, y, v, w; zero row for the constraint
/// assert_eq!((e[(0, 0)], e[(4, 4)]), (1.0, 0.0));
/// let mut g = vec![0.0; info.constraints.len()];
/// sys.constraints(0.0, &y, &mut g); // the chain: x² + y² − l², 2xv + 2yw, …
/// assert_eq!(&g[..2], [0.0, 0.0]);
/// ```
pub trait DaeSystem {
    /// Static description: variables, rows, structural numbers.
    fn info(&self) -> &FormulationInfo;

    /// Current parameter values, in the order of `info().parameters`.
    fn parameter_values(&self) -> Vec<f64>;

    /// `f(t, y)` into `f` (length M).
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]);

    /// The residual `r = E(t, y) yp − f(t, y)` into `r` (length M).
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]);

    /// `E(t, y)` into `e` (M×N): the leading matrix at the time `t` of the
    /// point `y` (a solver passes the time at which `y` is, e.g. a stage
    /// time). Independent of both when `info().constant_leading`.
    fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>);

    /// `∂f/∂y` into `j` (M×N).
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>);

    /// `∂(E(t, y) z)/∂y` into `j` (M×N) at the time `t` of `y`; all zeros
    /// when `info().constant_leading` (or when `E` depends on `t` only).
    fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>);

    /// The model's constraint chain `g_k(t, y)` into `g` (length K), in the
    /// order of `info().constraints`.
    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]);

    /// `∂g_k/∂y` into `j` (K×N).
    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>);

    /// The model's invariants (e.g. energy) into `out` (length I).
    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]);

    /// Names of the model's event functions (`events { … }`), in the
    /// order of [`DaeSystem::events`]; none unless the model has them.
    ///
    /// ```
    /// use dae::prelude::*;
    ///
    /// dae! {
    ///     /// A falling mass; `ground` crosses zero when it lands.
    ///     pub Fall {
    ///         parameters { g = 9.81 }
    ///         differential { h, v }
    ///         equations { der(h) = v; der(v) = -g; }
    ///         events { ground = h; }
    ///     }
    /// }
    /// let sys = Fall::default().ori2();
    /// assert_eq!(sys.event_names(), ["ground"]);
    /// let mut g = [0.0];
    /// sys.events(0.0, &[2.0, 0.0], &mut g);
    /// assert_eq!(g, [2.0]);
    /// ```
    fn event_names(&self) -> &[String] {
        &[]
    }

    /// The event functions at `(t, y)` into `out` (length
    /// `event_names().len()`): a solver locates their zero crossings
    /// along the solution. Nothing to write unless the model has events.
    fn events(&self, t: f64, y: &[f64], out: &mut [f64]) {
        let _ = (t, y, out);
    }

    /// The structural non-zeros of `E`, `∂f/∂y` and `∂(E z)/∂y`, from the
    /// symbolic rows. The default, for a system that knows no structure
    /// (a wrapper), is dense. Allocates: ask once per run.
    fn sparsity(&self) -> Sparsity {
        Sparsity::dense(self.info())
    }

    /// The block structure of a system that is a state and its forward
    /// sensitivities side by side ([`crate::sensitivity::SensitivitySystem`]),
    /// `None` (the default) for any other: a solver then solves its
    /// iteration matrix by block forward substitution with one
    /// factorisation of the state's block (see [`Blocks`]).
    fn blocks(&self) -> Option<Blocks> {
        None
    }

    /// The first block of a system with [`blocks`](DaeSystem::blocks) as a
    /// system of its own: the state of a state and its sensitivities
    /// ([`crate::sensitivity::SensitivitySystem::state`]), whose rows and
    /// Jacobian are the first block's of this system (up to the order in
    /// which terms are summed). A solver's staggered corrector iterates the
    /// state on it, then the sensitivities, which are linear, with the
    /// state's factorisation. `None` (the default) for a system without
    /// blocks, or one that does not offer its first block alone.
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::DaeSystem;
    ///
    /// let m = InterpretedModel::from_str(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -x * z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// // A formulation of a model has no blocks: it is its own state.
    /// assert!(m.system("rcd0").unwrap().first_block().is_none());
    /// ```
    fn first_block(&self) -> Option<&dyn DaeSystem> {
        None
    }

    /// For a state and its sensitivities: `[∂f/∂y | ∂f/∂p]` of the state's
    /// rows at the state `y` (the first block's unknowns), `N × (N + P)`,
    /// into `out`, the matrix of the sensitivities' rows `J sᵢ + ∂f/∂pᵢ`,
    /// which are linear in `sᵢ`; `false` (the default, `out` untouched)
    /// when the system offers none. A staggered corrector evaluates it once
    /// per stage point and then forms the sensitivities' residuals by
    /// products.
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::DaeSystem;
    ///
    /// let m = InterpretedModel::from_str(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -x * z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// let mut out = nalgebra::DMatrix::zeros(2, 2);
    /// // Not a state with sensitivities: nothing offered, nothing written.
    /// assert!(!m.system("rcd0").unwrap().first_block_linearisation(0.0, &[2.0, 3.0], &mut out));
    /// assert_eq!(out.iter().filter(|v| **v != 0.0).count(), 0);
    /// ```
    fn first_block_linearisation(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>) -> bool {
        let _ = (t, y, out);
        false
    }

    /// [`DaeSystem::first_block_linearisation`] at three points `(t[l],
    /// y[l])` into `out[l]`; `false` when the system offers none. The
    /// default makes three calls; a state with sensitivities evaluates the
    /// three in one pass ([`DaeSystem::rhs_jacobian_scatter3`]).
    fn first_block_linearisations(
        &self,
        t: [f64; 3],
        y: [&[f64]; 3],
        out: &mut [DMatrix<f64>; 3],
    ) -> bool {
        t.into_iter()
            .zip(y)
            .zip(out.iter_mut())
            .all(|((t, y), out)| self.first_block_linearisation(t, y, out))
    }

    /// `f(t, y)` into `f` (length M) and its derivatives along `count`
    /// directions in the unknowns: `df[k M..(k + 1) M] = (∂f/∂y) dy_k`
    /// with `dy_k = dy[k N..(k + 1) N]` — the right-hand sides of forward
    /// sensitivities ([`crate::sensitivity`]), without forming `∂f/∂y`.
    /// The default evaluates `f` and the dense Jacobian (allocates); an
    /// interpreted system makes one forward pass over its tape of `f`
    /// ([`crate::tape::Tape::eval_tangents`]).
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::DaeSystem;
    ///
    /// let m = InterpretedModel::from_str(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -x * z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// let sys = m.system("rcd0").unwrap();
    /// let (mut f, mut df) = ([0.0; 2], [0.0; 2]);
    /// // along (1, 0) at x = 2, z = 3: the derivative of −x z is −z
    /// sys.rhs_tangents(0.0, &[2.0, 3.0], &[1.0, 0.0], 1, &mut f, &mut df);
    /// assert_eq!(f[0], -6.0);
    /// assert_eq!(df[0], -3.0);
    /// ```
    fn rhs_tangents(
        &self,
        t: f64,
        y: &[f64],
        dy: &[f64],
        count: usize,
        f: &mut [f64],
        df: &mut [f64],
    ) {
        let (m, n) = (self.info().equations(), self.info().unknowns());
        self.rhs(t, y, f);
        let mut j = DMatrix::zeros(m, n);
        self.rhs_jacobian(t, y, &mut j);
        for k in 0..count {
            let d = nalgebra::DVectorView::from_slice(&dy[k * n..(k + 1) * n], n);
            df[k * m..(k + 1) * m].copy_from_slice((&j * d).as_slice());
        }
    }

    /// `∂f/∂y` at the entries of `pattern` (this system's
    /// `sparsity().rhs_jacobian`, or any pattern of its shape), in its
    /// order, into `values` (length `pattern.nnz()`). The default
    /// evaluates the dense matrix and picks the entries (allocates).
    fn rhs_jacobian_values(&self, t: f64, y: &[f64], pattern: &Pattern, values: &mut [f64]) {
        gather_dense(pattern, values, |j| self.rhs_jacobian(t, y, j));
    }

    /// `∂f/∂y` on this system's own pattern (`sparsity().rhs_jacobian`):
    /// its value `v` (in the pattern's order) into `out[to[v]]`, and not
    /// written where `to[v]` is [`SKIP`]; `to` has the pattern's `nnz()`
    /// entries. One pass from the evaluation to where a caller keeps the
    /// entries (a staggered corrector's `[∂f/∂y | ∂f/∂p]`, three times a
    /// step), where [`DaeSystem::rhs_jacobian_values`] and a gather make
    /// two and compare the pattern on each call. The default makes them
    /// (allocating).
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::{DaeSystem, SKIP};
    ///
    /// let m = InterpretedModel::from_str(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -x * z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// let sys = m.system("rcd0").unwrap();
    /// // The pattern's entries, column by column: (x', x), (0, x), (x', z), (0, z).
    /// assert_eq!(sys.sparsity().rhs_jacobian.nnz(), 4);
    /// let mut out = [0.0; 2];
    /// // ∂x'/∂x = −z into out[1], ∂x'/∂z = −x into out[0], the rest skipped.
    /// sys.rhs_jacobian_scatter(0.0, &[2.0, 3.0], &[1, SKIP, 0, SKIP], &mut out);
    /// assert_eq!(out, [-2.0, -3.0]);
    /// ```
    fn rhs_jacobian_scatter(&self, t: f64, y: &[f64], to: &[usize], out: &mut [f64]) {
        let pattern = self.sparsity().rhs_jacobian;
        let mut values = vec![0.0; pattern.nnz()];
        self.rhs_jacobian_values(t, y, &pattern, &mut values);
        for (&at, &v) in to.iter().zip(&values) {
            if at != SKIP {
                out[at] = v;
            }
        }
    }

    /// [`DaeSystem::rhs_jacobian_scatter`] at three points `(t[l], y[l])`
    /// into `out[l]` (a three-stage method's stage points). The default
    /// makes three calls; the interpreter evaluates its tape once for the
    /// three (`Tape::eval_outputs_lanes`), the same values bit for bit.
    fn rhs_jacobian_scatter3(
        &self,
        t: [f64; 3],
        y: [&[f64]; 3],
        to: &[usize],
        out: [&mut [f64]; 3],
    ) {
        for ((t, y), out) in t.into_iter().zip(y).zip(out) {
            self.rhs_jacobian_scatter(t, y, to, out);
        }
    }

    /// `E` at the entries of `pattern` (see
    /// [`DaeSystem::rhs_jacobian_values`]).
    fn leading_values(&self, t: f64, y: &[f64], pattern: &Pattern, values: &mut [f64]) {
        gather_dense(pattern, values, |e| self.leading(t, y, e));
    }

    /// `∂(E z)/∂y` at the entries of `pattern` (see
    /// [`DaeSystem::rhs_jacobian_values`]).
    fn leading_jacobian_values(
        &self,
        t: f64,
        y: &[f64],
        z: &[f64],
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        gather_dense(pattern, values, |j| self.leading_jacobian(t, y, z, j));
    }
}

/// The entries at `pattern` of the matrix `eval` writes (into a dense
/// matrix of the pattern's shape), in the pattern's order: the `*_values`
/// of a system without sparse evaluation, or of a pattern not its own.
pub(crate) fn gather_dense(
    pattern: &Pattern,
    values: &mut [f64],
    eval: impl FnOnce(&mut DMatrix<f64>),
) {
    let mut m = DMatrix::zeros(pattern.rows, pattern.cols);
    eval(&mut m);
    for (v, (r, c)) in values.iter_mut().zip(pattern.entries()) {
        *v = m[(r, c)];
    }
}

/// Forward every method through a pointer type.
macro_rules! forward_dae_system {
    ($($ptr:ty),*) => {$(
        impl<T: DaeSystem + ?Sized> DaeSystem for $ptr {
            fn info(&self) -> &FormulationInfo {
                (**self).info()
            }
            fn parameter_values(&self) -> Vec<f64> {
                (**self).parameter_values()
            }
            fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
                (**self).rhs(t, y, f)
            }
            fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
                (**self).residual(t, y, yp, r)
            }
            fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>) {
                (**self).leading(t, y, e)
            }
            fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
                (**self).rhs_jacobian(t, y, j)
            }
            fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
                (**self).leading_jacobian(t, y, z, j)
            }
            fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
                (**self).constraints(t, y, g)
            }
            fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
                (**self).constraints_jacobian(t, y, j)
            }
            fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
                (**self).invariants(t, y, out)
            }
            fn event_names(&self) -> &[String] {
                (**self).event_names()
            }
            fn events(&self, t: f64, y: &[f64], out: &mut [f64]) {
                (**self).events(t, y, out)
            }
            fn sparsity(&self) -> Sparsity {
                (**self).sparsity()
            }
            fn blocks(&self) -> Option<Blocks> {
                (**self).blocks()
            }
            fn first_block(&self) -> Option<&dyn DaeSystem> {
                (**self).first_block()
            }
            fn first_block_linearisation(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>) -> bool {
                (**self).first_block_linearisation(t, y, out)
            }
            fn first_block_linearisations(
                &self,
                t: [f64; 3],
                y: [&[f64]; 3],
                out: &mut [DMatrix<f64>; 3],
            ) -> bool {
                (**self).first_block_linearisations(t, y, out)
            }
            fn rhs_tangents(
                &self,
                t: f64,
                y: &[f64],
                dy: &[f64],
                count: usize,
                f: &mut [f64],
                df: &mut [f64],
            ) {
                (**self).rhs_tangents(t, y, dy, count, f, df)
            }
            fn rhs_jacobian_values(&self, t: f64, y: &[f64], p: &Pattern, v: &mut [f64]) {
                (**self).rhs_jacobian_values(t, y, p, v)
            }
            fn rhs_jacobian_scatter(&self, t: f64, y: &[f64], to: &[usize], out: &mut [f64]) {
                (**self).rhs_jacobian_scatter(t, y, to, out)
            }
            fn rhs_jacobian_scatter3(
                &self,
                t: [f64; 3],
                y: [&[f64]; 3],
                to: &[usize],
                out: [&mut [f64]; 3],
            ) {
                (**self).rhs_jacobian_scatter3(t, y, to, out)
            }
            fn leading_values(&self, t: f64, y: &[f64], p: &Pattern, v: &mut [f64]) {
                (**self).leading_values(t, y, p, v)
            }
            fn leading_jacobian_values(
                &self,
                t: f64,
                y: &[f64],
                z: &[f64],
                p: &Pattern,
                v: &mut [f64],
            ) {
                (**self).leading_jacobian_values(t, y, z, p, v)
            }
        }
    )*};
}

forward_dae_system!(Box<T>, &T);

/// Sizes known at compile time: implemented by macro-generated formulations
/// so that a solver can use stack arrays (`[f64; N]`, `SMatrix`) on its fast
/// path.
pub trait StaticSize {
    /// Number of unknowns `N`.
    const UNKNOWNS: usize;
    /// Number of equations `M`.
    const EQUATIONS: usize;
    /// Length of the constraint chain `K`.
    const CONSTRAINTS: usize;
}

/// A boxed formulation that can move to another thread (parallel sweeps
/// build one per job).
pub type BoxedSystem = Box<dyn DaeSystem + Send>;

/// Static description of a model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelInfo {
    /// Model name.
    pub name: String,
    /// Doc comment, if any.
    pub doc: String,
    /// The model's unknowns (differential first, in declaration order, then
    /// algebraic).
    pub variables: Vec<VarInfo>,
    /// Parameters with defaults.
    pub parameters: Vec<ParamInfo>,
    /// The constraint chain (all levels).
    pub constraints: Vec<ConstraintInfo>,
    /// Invariant names.
    pub invariants: Vec<String>,
    /// Event function names (`events { … }`), in the order of
    /// [`DaeSystem::events`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<String>,
    /// Formulations this model provides.
    pub formulations: Vec<String>,
}

/// Why a parameter could not be set.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParameterError {
    /// No parameter of that name.
    #[error("unknown parameter `{name}` (model `{model}` has: {known})")]
    Unknown {
        /// Model name.
        model: String,
        /// Name asked for.
        name: String,
        /// Comma-separated list of the model's parameters.
        known: String,
    },
    /// NaN or infinite value.
    #[error("parameter `{name}` must be finite, got {value}")]
    NotFinite {
        /// Parameter name.
        name: String,
        /// The offending value.
        value: f64,
    },
    /// A derived parameter: computed from the others, not settable.
    #[error("parameter `{name}` of model `{model}` is derived (`{name} = {expr}`): set the parameters it is computed from instead")]
    Derived {
        /// Model name.
        model: String,
        /// Parameter name.
        name: String,
        /// Its expression, in the model language.
        expr: String,
    },
    /// A value that makes a derived parameter NaN or infinite (nothing was
    /// changed).
    #[error(
        "setting `{name}` to {value} makes derived parameter `{derived}` non-finite ({result})"
    )]
    DerivedNotFinite {
        /// The parameter being set.
        name: String,
        /// Its refused value.
        value: f64,
        /// The derived parameter.
        derived: String,
        /// The derived parameter's value it would have had.
        result: f64,
    },
}

/// Why a formulation could not be built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FormulationError {
    /// The name is not one of the nine formulations.
    #[error(
        "unknown formulation `{name}` (known: ori2, rcd1, rcd0, ovd1, ovd0, ggl1, psi1, psi0, mex0)"
    )]
    Unknown {
        /// Name asked for.
        name: String,
    },
    /// A known formulation the model does not provide (not listed in its
    /// `formulations { … }` block, or not applicable to its structure).
    #[error("model `{model}` does not provide formulation `{name}` (it provides: {available})")]
    NotProvided {
        /// Model name.
        model: String,
        /// Name asked for.
        name: String,
        /// Comma-separated list.
        available: String,
    },
    /// `psi1`/`psi0` the model has no symbolic selector for, and that the
    /// numerical selector cannot build from its `ovd1`/`ovd0`.
    #[error(
        "model `{model}` does not provide formulation `{name}`: {reason} (it provides: {})",
        others(available, name)
    )]
    NoSelector {
        /// Model name.
        model: String,
        /// Name asked for.
        name: String,
        /// Why the numerical selector refused (its [`SelectorError`](crate::selector::SelectorError)).
        reason: String,
        /// Comma-separated list.
        available: String,
    },
}

/// The comma-separated `list` without `name`: what a model provides besides
/// the formulation it could not build.
fn others(list: &str, name: &str) -> String {
    let kept: Vec<&str> = list
        .split(',')
        .map(str::trim)
        .filter(|f| !f.is_empty() && *f != name)
        .collect();
    if kept.is_empty() {
        "no other formulation".to_string()
    } else {
        kept.join(", ")
    }
}

/// A model with parameters: the struct the `dae!` macro generates, or an
/// interpreted model read from a `.dae` file.
pub trait Model {
    /// Static description.
    fn model_info(&self) -> &ModelInfo;
    /// Current value of a parameter.
    fn parameter(&self, name: &str) -> Option<f64>;
    /// Set a parameter by name; rejects unknown names and non-finite values.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), ParameterError>;
    /// Build the named formulation with the current parameter values.
    fn formulation(&self, name: &str) -> Result<BoxedSystem, FormulationError>;
    /// Make ready the formulations `names` (unknown names are skipped):
    /// a model that builds its formulations when first asked for
    /// ([`crate::interp::InterpretedModel::lazy`]) builds these together,
    /// sharing the work they have in common, before a caller that will
    /// ask for each of them (a sweep). Nothing for a model that has them
    /// all already (the default).
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::Model;
    ///
    /// let m = InterpretedModel::lazy(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// m.prepare(&["rcd0", "no such"]);
    /// assert!(m.formulation("rcd0").is_ok());
    /// ```
    fn prepare(&self, names: &[&str]) {
        let _ = names;
    }
}

/// Perturbed points [`chain_pattern`] probes besides the given one.
pub const STRUCTURE_PROBES: usize = 2;

/// Which unknowns each member of the constraint chain contains:
/// `pattern[k][j]` when `∂g_k/∂y_j ≠ 0` at `y` or at one of
/// [`STRUCTURE_PROBES`] perturbed points (deterministic, irregular relative
/// perturbations of ±[0.5, 1.5)·10⁻³, so that an accidental zero such as
/// `∂(x² + y²)/∂x` at `x = 0` is not taken for a structural one; perturbed
/// points where the chain or its Jacobian is not finite are skipped).
/// `None` when the chain or its Jacobian is not finite at `y`. Allocates.
pub fn chain_pattern(sys: &dyn DaeSystem, t: f64, y: &[f64]) -> Option<Vec<Vec<bool>>> {
    let info = sys.info();
    let (k, n) = (info.constraints.len(), info.unknowns());
    let mut g = vec![0.0; k];
    let mut jac = DMatrix::zeros(k, n);
    let mut eval = |y: &[f64], jac: &mut DMatrix<f64>| {
        sys.constraints(t, y, &mut g);
        sys.constraints_jacobian(t, y, jac);
        g.iter().all(|v| v.is_finite()) && jac.iter().all(|v| v.is_finite())
    };
    if !eval(y, &mut jac) {
        return None;
    }
    let mut pattern: Vec<Vec<bool>> = (0..k)
        .map(|r| (0..n).map(|c| jac[(r, c)] != 0.0).collect())
        .collect();
    for p in 0..STRUCTURE_PROBES {
        let probe = perturbed(y, p);
        if eval(&probe, &mut jac) {
            for (r, row) in pattern.iter_mut().enumerate() {
                for (c, e) in row.iter_mut().enumerate() {
                    *e |= jac[(r, c)] != 0.0;
                }
            }
        }
    }
    Some(pattern)
}

/// `y` at [`chain_pattern`]'s probe `p`: deterministic, irregular relative
/// perturbations of ±[0.5, 1.5)·10⁻³ (`y_j + s h 10⁻³ (1 + |y_j|)`).
pub fn perturbed(y: &[f64], p: usize) -> Vec<f64> {
    y.iter()
        .enumerate()
        .map(|(j, &yj)| {
            let h = ((j * 7919 + p * 104_729 + 17) % 1000) as f64 / 1000.0 + 0.5;
            let sign = if (j + p).is_multiple_of(2) { 1.0 } else { -1.0 };
            yj + sign * h * 1e-3 * (1.0 + yj.abs())
        })
        .collect()
}

/// The formulation names: the paper's eight in its order, then `mex0`
/// (dummy derivatives, [`crate::dummy`]).
pub const FORMULATION_NAMES: [&str; 9] = [
    "ori2", "rcd1", "rcd0", "ovd1", "ovd0", "ggl1", "psi1", "psi0", "mex0",
];

/// Check a parameter value (shared by generated and interpreted models).
pub fn check_parameter(name: &str, value: f64) -> Result<(), ParameterError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ParameterError::NotFinite {
            name: name.to_string(),
            value,
        })
    }
}

//! Consistent initial values.
//!
//! A formulation `E(t, y) y' = f(t, y)` can only be started from a point that
//! satisfies every constraint of the model's chain — the original
//! constraints *and* their hidden derivatives — and whose algebraic unknowns
//! (Lagrange multipliers) are the ones these constraints determine. The user
//! gives the differential values (positions, velocities); [`consistent`]
//! completes and, if asked, repairs them.
//!
//! # The constraint chain
//!
//! Every [`DaeSystem`] evaluates the model's chain `g_k(t, y)`, `k = 0..K`
//! (`info().constraints`), where member `k` is constraint `source_k`
//! differentiated `level_k` times along the dynamics, together with its
//! Jacobian `G = ∂g/∂y` (K×N). For a mechanical system with positions `q`,
//! velocities `v` and multipliers `λ`:
//!
//! ```text
//!     level 0:  g(q)                          = 0    positions
//!     level 1:  G(q) v                        = 0    velocities
//!     level 2:  G(q) M⁻¹(f − G(q)ᵀλ) + g_qq(v,v) = 0    accelerations, contains λ
//! ```
//!
//! The rows are split by their structure (which unknowns they contain, see
//! below):
//!
//! * **algebraic rows** — for each source, the member of the highest level
//!   present, provided it contains an algebraic unknown. These determine the
//!   multipliers.
//! * **differential rows** — all other members. They involve differential
//!   unknowns only and are conditions on the user's values.
//!
//! # Step 1: differential rows (check or project)
//!
//! A row is satisfied when `|g_k(y)| ≤ tol · s_k(y)` with the scale
//! `s_k = 1 + Σ_j |∂g_k/∂y_j| |y_j|` (the size of the terms of `g_k`: the
//! test is relative for large terms and absolute near zero).
//!
//! If every differential row is satisfied, the differential values are kept
//! bit for bit. Otherwise [`InitMode::Strict`] returns
//! [`SolveError::InconsistentInitialValues`] with the violated row of the
//! lowest level (the cause: velocities cannot be judged at wrong positions)
//! that has the largest `|g_k| / s_k`, and its residual at the given values;
//! [`InitMode::Project`] (the default) moves the values onto the constraint
//! manifold with the least change, level by level. With `y⁰` the given
//! values, `R_ℓ` the differential rows of level `≤ ℓ` and `C_ℓ` the
//! differential unknowns that first appear at level `ℓ` (positions at level
//! 0, velocities at level 1), stage `ℓ` solves
//!
//! ```text
//!     min ½‖y_C − y⁰_C‖₂²   subject to   g_k(y) = 0,  k ∈ R_ℓ,
//! ```
//!
//! changing only `y_C`. Its optimality conditions are
//! `(y_C − y⁰_C) + Jᵀμ = 0, g_R(y) = 0` with `J = ∂g_R/∂y_C`; each iteration
//! solves their linearisation
//!
//! ```text
//!     [ H  Jᵀ ] [ Δ  ]     [ y_C − y⁰_C ]
//!     [ J  0  ] [ μ⁺ ] = − [ g_R(y)     ],     H = I + Σ_k μ_k ∇²g_k,
//! ```
//!
//! by a pseudo-inverse (SVD, so redundant or zero rows are harmless), with
//! the multipliers `μ` estimated by least squares from the current point and
//! `∇²(μᵀg)` by differences of the analytic Jacobian. With `H = I` this is
//! the Gauss–Newton step `Δ = −J⁺g − (I − J⁺J)(y_C − y⁰_C)` (taken on the
//! first iteration and whenever `J` has full column rank); the curvature
//! term keeps it convergent when the given point is farther from the
//! manifold than the manifold's radius of curvature. A converged point has
//! `g = 0` and `y_C − y⁰_C ∈ range(Jᵀ)`: the closest point. For the pendulum,
//! level 0 moves `(x, y)` radially onto the circle and level 1 replaces
//! `(v, w)` by its orthogonal projection onto the tangent; positions are not
//! touched by the velocity stage, and earlier levels stay satisfied because
//! their rows are part of every later stage. When the new unknowns alone
//! cannot satisfy a level (a model whose hidden constraint introduces no new
//! unknown), the stage is repeated over all differential unknowns of `R_ℓ`
//! jointly (noted in [`InitReport::notes`]). Each changed unknown is listed
//! in [`InitReport::changes`].
//!
//! # Step 2: algebraic rows (Newton)
//!
//! The algebraic rows are solved for the algebraic unknowns `z` they contain,
//! with the given values as first guess: `z ← z − J_z⁺ g` (Newton for a square
//! block, minimum change from the guess otherwise), iterated until the
//! correction is at round-off level. A block without full row rank (no
//! unique multipliers: a singular configuration or redundant constraints) is
//! an [`InitError::Singular`] naming the dependent rows. Algebraic unknowns
//! that appear in no member of the chain — the GGL multipliers `η`, whose
//! exact value is `0` — are set to zero.
//!
//! # Structure
//!
//! Which unknowns a row contains is read off the Jacobian, evaluated at the
//! given point and at two slightly perturbed points, so that an accidental
//! zero (`∂(x² + y²)/∂x = 0` at `x = 0`) is not taken for a structural one.
//!
//! # Given values, guesses and the report
//!
//! [`consistent_from`] takes for each unknown a [`Start`]: a value given
//! ([`Start::Fixed`]: kept if consistent, else projected or refused as
//! above), a guess ([`Start::Guess`]: only where the iteration starts) or
//! nothing ([`Start::Omitted`]: from 0). The values computed depend only on
//! where each unknown starts; [`InitReport::values`] says for every unknown
//! what was given, the guess, the value returned, how far it moved and how
//! it came about ([`How`]). Where the algebraic rows contain an algebraic
//! unknown nonlinearly (its column of their Jacobian changes when the
//! algebraic unknowns move), Newton's answer is one of possibly several
//! solutions, the one nearest its start in the sense of Newton's basins:
//! [`InitValue::nonlinear`] says so, and [`InitValue::root_chosen_by_default`]
//! flags those started from 0 for want of a guess. (In
//! [`InitMode::Strict`], a guessed differential value that violates a
//! constraint is refused like a given one.)
//!
//! # Typed failures
//!
//! A rank-deficient Jacobian of the algebraic rows at the start is
//! [`InitError::Singular`], naming the rows whose pivots vanish in a QR
//! factorisation with column pivoting of its transpose (each a combination
//! of the rows before it, to `10⁻¹²` relative to the first pivot); a Newton
//! iteration that stops with a violated algebraic row is
//! [`InitError::NotConverged`], naming the row with the largest scaled
//! residual; a NaN or ∞ in a row of the chain or its Jacobian at any point
//! the iteration evaluates is [`InitError::NonFinite`], naming the row and
//! every unknown's value there. Nothing non-finite is passed on.
//!
//! # Initial derivative
//!
//! [`initial_derivative`] returns `y'(t0)` for methods that need it (BDF):
//! the least-squares solution of the (possibly rectangular, rank-deficient)
//! system `E(y0) y' = f(t0, y0)`, whose free directions (`ker E`: the
//! algebraic unknowns) are fixed by the differentiated chain
//! `G y' + ∂g/∂t = 0`, and otherwise chosen of minimum norm.
//!
//! # Large systems
//!
//! From 60 unknowns (`core::matrix::SPARSE_FROM`, with the `sparse`
//! feature) neither computation factorises an N×N matrix densely where
//! the structure allows (`linalg::sparse_lstsq`): a least-change
//! step on a block of at least that many rows or columns whose non-zero
//! rows have full rank is one sparse LU (of the block, or of
//! `[I Jᵀ; J 0]` for a wide one), and the initial derivative of a system
//! whose `E(y0)`, without its zero rows and columns, is a square
//! nonsingular block (index-1 and GGL forms: `E` selects the differential
//! unknowns' derivatives) is one sparse LU of that block, with `ker E` the
//! zero columns, plus one of `G` restricted to them. The results are the
//! dense path's to round-off. Everything else — a singular or tall block
//! (the rank and the dependent rows are then named by the SVD), an `E`
//! of another form, the curvature-corrected step of a projection — keeps
//! the dense SVD, whose cost grows like N³; the constraint chain's
//! Jacobian `G` (K×N) is evaluated dense in either case.

use crate::core::matrix::SPARSE_FROM;
use crate::error::{InitError, SolveError};
use crate::linalg::sparse_lstsq::{self, Entries};
use crate::options::Tolerances;
use crate::stats::Stats;
use dae_core::system::{chain_pattern, DaeSystem, VarKind};
use nalgebra::{linalg::SVD, DMatrix, Dyn};
use serde::Serialize;

/// Relative threshold below which a singular value counts as zero
/// ([`Rank::Relative`]).
const RCOND: f64 = 1e-12;
/// Iteration limit handed to the SVD (it never needs more than a few dozen
/// sweeps on finite input; the limit turns a pathology into an error).
const SVD_MAX_ITER: usize = 10_000;
/// The same for [`Rank::RoundOff`] (DASSL's start in the BDF solver).
const SVD_MAX_ITER_ROUND_OFF: usize = 1000;
/// Step halvings tried when a correction leads to non-finite values.
const MAX_HALVINGS: usize = 40;

/// What to do with given values that violate a (hidden) constraint.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InitMode {
    /// Move them onto the constraint manifold with the least change and
    /// report what changed (the default).
    #[default]
    Project,
    /// Refuse them: [`SolveError::InconsistentInitialValues`] with the worst
    /// violated equation and its residual.
    Strict,
}

/// Options of [`consistent`].
#[derive(Clone, Debug, PartialEq)]
pub struct InitOptions {
    /// Project or refuse inconsistent differential values.
    pub mode: InitMode,
    /// A constraint member `g_k` counts as satisfied when
    /// `|g_k| ≤ tol · (1 + Σ_j |∂g_k/∂y_j| |y_j|)`.
    pub tol: f64,
    /// Iteration limit of each Gauss–Newton / Newton solve.
    pub max_iterations: usize,
}

impl Default for InitOptions {
    fn default() -> Self {
        InitOptions {
            mode: InitMode::Project,
            tol: 1e-10,
            max_iterations: 100,
        }
    }
}

impl InitOptions {
    /// The defaults with [`InitMode::Strict`].
    pub fn strict() -> Self {
        InitOptions {
            mode: InitMode::Strict,
            ..InitOptions::default()
        }
    }

    /// `tol` finite and positive, `max_iterations ≥ 1`.
    pub fn validate(&self) -> Result<(), SolveError> {
        if !self.tol.is_finite() || self.tol <= 0.0 {
            return Err(SolveError::invalid(format!(
                "init tol = {} must be finite and positive",
                self.tol
            )));
        }
        if self.max_iterations == 0 {
            return Err(SolveError::invalid(
                "init max_iterations must be at least 1",
            ));
        }
        Ok(())
    }
}

/// One unknown whose value was changed (or computed).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VarChange {
    /// Name of the unknown.
    pub name: String,
    /// Its position in `y`.
    pub index: usize,
    /// Value given.
    pub before: f64,
    /// Value returned.
    pub after: f64,
}

/// Residual of one member of the constraint chain.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConstraintResidual {
    /// Level (number of time derivatives).
    pub level: u8,
    /// 0-based index of the original constraint.
    pub source: u16,
    /// `0 = …` in the model language.
    pub equation: String,
    /// `g_k` at the given values (for algebraic rows: with the given
    /// multipliers).
    pub before: f64,
    /// `g_k` at the returned values.
    pub after: f64,
}

/// Largest residual of the members of one level.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LevelResidual {
    /// Level (number of time derivatives).
    pub level: u8,
    /// `max |g_k|` at the given values.
    pub before: f64,
    /// `max |g_k|` at the returned values.
    pub after: f64,
}

/// Where the value of one unknown starts ([`consistent_from`]).
///
/// ```
/// use dae::dae_solvers::init::Start;
///
/// let start = [Start::Fixed(1.0), Start::Omitted, Start::Guess(-1.0)];
/// assert_eq!(start.map(Start::value), [1.0, 0.0, -1.0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Start {
    /// A value the user gives: kept when it satisfies the constraints,
    /// otherwise projected ([`InitMode::Project`], reported) or refused
    /// ([`InitMode::Strict`]). For an algebraic unknown (determined by the
    /// constraints) it is where Newton starts, and reported as projected
    /// when the constraints move it.
    Fixed(f64),
    /// Only where the iteration starts: the constraints decide the value.
    Guess(f64),
    /// Nothing given: starts from 0.
    Omitted,
}

impl Start {
    /// The value the iteration starts from (`0` for [`Start::Omitted`]).
    pub fn value(self) -> f64 {
        match self {
            Start::Fixed(v) | Start::Guess(v) => v,
            Start::Omitted => 0.0,
        }
    }
}

/// How the initial value of an unknown came about ([`InitValue::how`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum How {
    /// Given ([`Start::Fixed`]) and kept bit for bit.
    Fixed,
    /// Computed from the constraints starting at a guess
    /// ([`Start::Guess`]).
    Guessed,
    /// Nothing given ([`Start::Omitted`]): started from 0 (and moved by the
    /// constraints where they determine it).
    Defaulted,
    /// Given ([`Start::Fixed`]) and moved by the constraints.
    Projected,
}

impl How {
    /// The name used in JSON and text: `fixed`, `guessed`, `defaulted`,
    /// `projected`.
    pub fn as_str(self) -> &'static str {
        match self {
            How::Fixed => "fixed",
            How::Guessed => "guessed",
            How::Defaulted => "defaulted",
            How::Projected => "projected",
        }
    }
}

/// The initial value of one unknown: what was given, where the iteration
/// started, what it returned.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InitValue {
    /// Name of the unknown.
    pub name: String,
    /// The value given ([`Start::Fixed`]).
    pub given: Option<f64>,
    /// The guess given ([`Start::Guess`]).
    pub guess: Option<f64>,
    /// The consistent value returned.
    pub value: f64,
    /// `|value − start|`, the start being the given value, the guess or 0.
    pub moved: f64,
    /// How the value came about.
    pub how: How,
    /// `true` for an algebraic unknown that the rows determining it contain
    /// nonlinearly (its column of their Jacobian changes with the algebraic
    /// unknowns): those rows may have other solutions, and the one found
    /// depends on where Newton started. Always `false` for differential
    /// unknowns.
    pub nonlinear: bool,
}

impl InitValue {
    /// Started from 0 for want of a guess on an unknown the constraints
    /// determine nonlinearly: the consistent value found is one of possibly
    /// several.
    ///
    /// ```
    /// use dae::dae_solvers::init::{How, InitValue};
    ///
    /// let z = InitValue { name: "z".into(), given: None, guess: None, value: 1.0,
    ///                     moved: 1.0, how: How::Defaulted, nonlinear: true };
    /// assert!(z.root_chosen_by_default());
    /// ```
    pub fn root_chosen_by_default(&self) -> bool {
        self.nonlinear && self.how == How::Defaulted
    }
}

/// What [`consistent`] did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InitReport {
    /// Every unknown of the formulation, in its order: given, guess,
    /// returned value, how far it moved and how it came about.
    pub values: Vec<InitValue>,
    /// Mode in force.
    pub mode: InitMode,
    /// `true` when differential values were moved onto the constraints.
    pub projected: bool,
    /// Differential unknowns changed by the projection.
    pub changes: Vec<VarChange>,
    /// Algebraic unknowns computed from the constraints (`before` is the
    /// given guess).
    pub algebraic: Vec<VarChange>,
    /// Algebraic unknowns that appear in no constraint and were set to 0
    /// (the GGL multipliers).
    pub zeroed: Vec<String>,
    /// Every member of the chain, before and after.
    pub constraints: Vec<ConstraintResidual>,
    /// Per level: the largest residual before and after.
    pub levels: Vec<LevelResidual>,
    /// Gauss–Newton iterations of the projection (0 when nothing was
    /// projected).
    pub projection_iterations: usize,
    /// Newton iterations for the algebraic unknowns.
    pub newton_iterations: usize,
    /// Remarks (fallbacks taken, iteration limits met within tolerance).
    pub notes: Vec<String>,
}

/// Consistent initial values and what it took to get them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Consistent {
    /// The consistent `y0` (length N).
    pub y: Vec<f64>,
    /// What was checked, changed and computed.
    pub report: InitReport,
}

/// `0 = expr` for a chain member.
fn equation_text(expr: &str) -> String {
    let e = expr.trim();
    if e.starts_with("0 =") || e.starts_with("0=") {
        e.to_string()
    } else {
        format!("0 = {e}")
    }
}

/// Check `t0` and `y0` against the system: length, finiteness.
fn validate_point(sys: &dyn DaeSystem, t0: f64, y0: &[f64]) -> Result<(), SolveError> {
    let info = sys.info();
    if !t0.is_finite() {
        return Err(SolveError::invalid(format!("t0 = {t0} must be finite")));
    }
    if y0.len() != info.unknowns() {
        return Err(SolveError::invalid(format!(
            "y0 has {} values, formulation `{}` of `{}` has {} unknowns",
            y0.len(),
            info.name,
            info.model,
            info.unknowns()
        )));
    }
    for (i, (&v, var)) in y0.iter().zip(&info.variables).enumerate() {
        if !v.is_finite() {
            return Err(SolveError::invalid(format!(
                "initial value of `{}` (y0[{i}]) is {v}; initial values must be finite",
                var.name
            )));
        }
    }
    Ok(())
}

/// Evaluation buffers for the constraint chain.
struct Chain<'a> {
    sys: &'a dyn DaeSystem,
    t: f64,
    g: Vec<f64>,
    jac: DMatrix<f64>,
}

impl<'a> Chain<'a> {
    fn new(sys: &'a dyn DaeSystem, t: f64) -> Self {
        let info = sys.info();
        let (k, n) = (info.constraints.len(), info.unknowns());
        Chain {
            sys,
            t,
            g: vec![0.0; k],
            jac: DMatrix::zeros(k, n),
        }
    }

    /// Evaluate `g` and `G` at `y`; `false` if anything is not finite.
    fn eval(&mut self, y: &[f64]) -> bool {
        self.sys.constraints(self.t, y, &mut self.g);
        self.sys.constraints_jacobian(self.t, y, &mut self.jac);
        self.g.iter().all(|v| v.is_finite()) && self.jac.iter().all(|v| v.is_finite())
    }

    /// Same as [`Chain::eval`], as a typed error naming the first
    /// non-finite row and the point ([`Chain::non_finite`]).
    fn eval_or_err(&mut self, y: &[f64]) -> Result<(), SolveError> {
        if self.eval(y) {
            Ok(())
        } else {
            Err(self.non_finite(y))
        }
    }

    /// [`InitError::NonFinite`] for the last evaluation at `y`: the first
    /// row whose residual, else whose Jacobian row, is not finite, and
    /// every unknown's value. (A non-finite `y` itself names the first
    /// row, with its residual.)
    fn non_finite(&self, y: &[f64]) -> SolveError {
        let info = self.sys.info();
        let residual = self
            .g
            .iter()
            .position(|v| !v.is_finite())
            .map(|k| (k, "residual", self.g[k]));
        let jacobian = || {
            (0..self.g.len()).find_map(|k| {
                self.jac
                    .row(k)
                    .iter()
                    .find(|v| !v.is_finite())
                    .map(|&v| (k, "Jacobian", v))
            })
        };
        let (k, what, value) = residual.or_else(jacobian).unwrap_or((
            0,
            "residual",
            self.g.first().copied().unwrap_or(f64::NAN),
        ));
        let equation = info
            .constraints
            .get(k)
            .map_or_else(|| format!("constraint {k}"), |m| equation_text(&m.expr));
        SolveError::Init(InitError::NonFinite {
            t: self.t,
            equation,
            what,
            value,
            values: info
                .variables
                .iter()
                .zip(y)
                .map(|(v, &x)| (v.name.clone(), x))
                .collect(),
        })
    }

    /// `s_k = 1 + Σ_j |G_kj| |y_j|` at the last evaluation.
    fn scale(&self, k: usize, y: &[f64]) -> f64 {
        1.0 + self
            .jac
            .row(k)
            .iter()
            .zip(y)
            .map(|(a, b)| (a * b).abs())
            .sum::<f64>()
    }

    /// `|g_k| / s_k` at the last evaluation.
    fn ratio(&self, k: usize, y: &[f64]) -> f64 {
        self.g[k].abs() / self.scale(k, y)
    }

    fn satisfied(&self, k: usize, y: &[f64], tol: f64) -> bool {
        self.ratio(k, y) <= tol
    }

    /// The row of `rows` with the largest scaled residual.
    fn worst(&self, rows: &[usize], y: &[f64]) -> Option<usize> {
        rows.iter().copied().max_by(|&a, &b| {
            self.ratio(a, y)
                .partial_cmp(&self.ratio(b, y))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    }
}

/// Which unknowns each member of the chain contains
/// ([`dae_core::system::chain_pattern`]). Leaves `chain` evaluated at `y`.
fn structure(chain: &mut Chain<'_>, y: &[f64]) -> Result<Vec<Vec<bool>>, SolveError> {
    chain.eval_or_err(y)?;
    let pattern = chain_pattern(chain.sys, chain.t, y).ok_or(SolveError::NonFinite {
        t: chain.t,
        what: "constraint chain near the initial values",
    })?;
    chain.eval_or_err(y)?;
    Ok(pattern)
}

/// How the singular value decompositions of this module decide the rank of
/// a matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Rank {
    /// Singular values up to `RCOND σ_max` (`RCOND = 10⁻¹²`) count as zero;
    /// the SVD converges to `5 ε`. The convention of [`consistent`] and
    /// [`initial_derivative`].
    Relative,
    /// Singular values up to `max(rows, cols) ε σ_max` count as zero, with an
    /// SVD converged to `ε`: the numerical rank at round-off level, so that
    /// any nonsingular matrix, however badly scaled, is inverted (the BDF
    /// solver's start).
    RoundOff,
}

impl Rank {
    /// The SVD of `a` with `U` and `Vᵀ` (singular values descending).
    fn svd(self, a: DMatrix<f64>) -> Option<SVD<f64, Dyn, Dyn>> {
        let (eps, max_iter) = match self {
            Rank::Relative => (f64::EPSILON * 5.0, SVD_MAX_ITER),
            Rank::RoundOff => (f64::EPSILON, SVD_MAX_ITER_ROUND_OFF),
        };
        SVD::try_new(a, true, true, eps, max_iter)
    }

    /// The number of singular values `s` of a `rows × cols` matrix that do
    /// not count as zero.
    fn of(self, s: &[f64], rows: usize, cols: usize) -> usize {
        let smax = s.iter().fold(0.0_f64, |m, &v| m.max(v));
        let cutoff = match self {
            Rank::Relative => smax * RCOND,
            Rank::RoundOff => rows.max(cols) as f64 * f64::EPSILON * smax,
        };
        if smax > 0.0 {
            s.iter().filter(|&&v| v > cutoff).count()
        } else {
            0
        }
    }
}

/// One linearised least-change step.
struct Step {
    /// `Δ = −J⁺g − (I − J⁺J) d`.
    delta: Vec<f64>,
    /// Numerical rank of `J`.
    rank: usize,
    /// Row of `J` carrying most of the left null vector when
    /// `rank < rows`.
    deficient_row: Option<usize>,
}

/// `Δ = −J⁺ g − (I − J⁺J) d` for `J` (r×c) by the SVD: the solution of
/// `min ‖d + Δ‖ s.t. J Δ = −g` (least squares in `J Δ = −g` when that has
/// no solution), with the rank of `J` decided by `rank`. `None` when the
/// SVD does not converge (not seen on finite input).
fn min_change_step(j: &DMatrix<f64>, g: &[f64], d: &[f64], rank: Rank) -> Option<Step> {
    let (r, c) = j.shape();
    if r == 0 {
        return Some(Step {
            delta: d.iter().map(|v| -v).collect(),
            rank: 0,
            deficient_row: None,
        });
    }
    if c == 0 {
        let worst = (0..r).max_by(|&a, &b| {
            g[a].abs()
                .partial_cmp(&g[b].abs())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        return Some(Step {
            delta: Vec::new(),
            rank: 0,
            deficient_row: worst,
        });
    }
    // A large block: the same step without the SVD, when the block's
    // non-zero part has full row rank (the module docs of
    // `linalg::sparse_lstsq`). A zero row or a singular block leaves the
    // rank, and the row that lacks it, to the SVD below.
    if r.max(c) >= SPARSE_FROM {
        let a = Entries::scan(r, c, |i, k| j[(i, k)]);
        if let Some(s) = sparse_lstsq::min_change(&a, g, d) {
            if s.rank == r {
                return Some(Step {
                    delta: s.delta,
                    rank: r,
                    deficient_row: None,
                });
            }
        }
    }
    // Pad with zero columns to at least r columns, so that U is r×r and
    // carries the left null space.
    let cols = c.max(r);
    let mut a = DMatrix::zeros(r, cols);
    a.view_mut((0, 0), (r, c)).copy_from(j);
    let svd = rank.svd(a)?;
    let u = svd.u.as_ref()?;
    let vt = svd.v_t.as_ref()?;
    let s = &svd.singular_values; // descending, length r
    let rank = rank.of(s.as_slice(), r, cols);
    let mut delta: Vec<f64> = d.iter().map(|v| -v).collect();
    for i in 0..rank {
        let ug: f64 = (0..r).map(|k| u[(k, i)] * g[k]).sum();
        let vd: f64 = (0..c).map(|k| vt[(i, k)] * d[k]).sum();
        let coef = vd - ug / s[i];
        for (k, dk) in delta.iter_mut().enumerate() {
            *dk += coef * vt[(i, k)];
        }
    }
    let deficient_row = if rank < r {
        let col = s.len() - 1;
        (0..r).max_by(|&a, &b| {
            u[(a, col)]
                .abs()
                .partial_cmp(&u[(b, col)].abs())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    } else {
        None
    };
    Some(Step {
        delta,
        rank,
        deficient_row,
    })
}

/// The rows of `j` whose pivots vanish in a QR factorisation of `jᵀ` with
/// column pivoting (Businger–Golub), by modified Gram–Schmidt with one
/// re-orthogonalisation: at each step the row with the largest remaining
/// norm is taken (the first of equal ones); the rows left when that norm
/// falls to `RCOND` times the first pivot (or is zero) are, to that
/// accuracy, combinations of the rows taken. Ascending.
fn dependent_rows(j: &DMatrix<f64>) -> Vec<usize> {
    let (r, c) = j.shape();
    let mut rest: Vec<Vec<f64>> = (0..r).map(|i| j.row(i).iter().copied().collect()).collect();
    let mut left: Vec<usize> = (0..r).collect();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut first = None;
    while !left.is_empty() {
        let mut best = 0;
        let mut best_norm = norm(&rest[left[0]]);
        for (pos, &i) in left.iter().enumerate().skip(1) {
            let n = norm(&rest[i]);
            if n > best_norm {
                best = pos;
                best_norm = n;
            }
        }
        let top = *first.get_or_insert(best_norm);
        if !(best_norm > RCOND * top && best_norm > 0.0) {
            break;
        }
        let pivot = left.remove(best);
        let q: Vec<f64> = rest[pivot].iter().map(|x| x / best_norm).collect();
        for &i in &left {
            for _ in 0..2 {
                let dot: f64 = (0..c).map(|k| rest[i][k] * q[k]).sum();
                for (k, qk) in q.iter().enumerate() {
                    rest[i][k] -= dot * qk;
                }
            }
        }
    }
    left.sort_unstable();
    left
}

/// Result of one (Gauss–)Newton solve.
enum Solve {
    /// All rows satisfied; the correction reached round-off level (or the
    /// iteration limit with the rows satisfied: `at_limit`).
    Converged { iterations: usize, at_limit: bool },
    /// Rows still violated after the iteration.
    Failed { iterations: usize },
    /// The Jacobian has no full row rank (only when asked to check).
    Singular { row: usize, rank: usize },
}

/// What a solve works on.
struct Block<'b> {
    /// Rows of the chain.
    rows: &'b [usize],
    /// Unknowns that may change.
    cols: &'b [usize],
    /// Values to stay close to (the given ones).
    anchor: &'b [f64],
    /// Report a rank-deficient Jacobian instead of iterating on.
    need_full_rank: bool,
}

/// One Newton step for the optimality system of the closest point,
///
/// ```text
///     min ½‖y_C − a‖²  s.t.  g_R(y) = 0:
///     (y_C − a) + Jᵀμ = 0,   g_R(y) = 0,
///
///     [ H  Jᵀ ] [ Δ  ]     [ d ]
///     [ J  0  ] [ μ⁺ ] = − [ g ],     H = I + Σ_k μ_k ∇²g_k,
/// ```
///
/// with `d = y_C − a`, the multiplier estimate `μ = argmin ‖d + Jᵀμ‖` and
/// `∇²(μᵀg)` by forward differences of `Jᵀμ`. Without the curvature term
/// (`H = I`) this is the Gauss–Newton step, which diverges when the given
/// point is farther from the manifold than its radius of curvature (the
/// tangential error is multiplied by about `‖d‖ κ` per step). `None` when
/// the multipliers vanish or the model is not finite nearby (the caller
/// keeps the Gauss–Newton step).
fn closest_point_newton_step(
    chain: &Chain<'_>,
    y: &[f64],
    block: &Block<'_>,
    jac: &DMatrix<f64>,
    g: &[f64],
    d: &[f64],
) -> Option<Vec<f64>> {
    let (rows, cols) = (block.rows, block.cols);
    let (r, c) = (rows.len(), cols.len());
    let jt = jac.transpose();
    let mu = min_change_step(&jt, d, &vec![0.0; r], Rank::Relative)?.delta;
    if mu.iter().all(|&m| m == 0.0) {
        return None;
    }
    let jt_mu = |j: &DMatrix<f64>, e: usize| -> f64 {
        rows.iter()
            .zip(&mu)
            .map(|(&row, m)| j[(row, cols[e])] * m)
            .sum()
    };
    let (k, n) = chain.jac.shape();
    let mut jp = DMatrix::zeros(k, n);
    let mut yp = y.to_vec();
    let mut h: DMatrix<f64> = DMatrix::identity(c, c);
    for (b, &col) in cols.iter().enumerate() {
        let step = f64::EPSILON.sqrt() * (1.0 + y[col].abs());
        yp[col] = y[col] + step;
        chain.sys.constraints_jacobian(chain.t, &yp, &mut jp);
        yp[col] = y[col];
        for e in 0..c {
            h[(e, b)] += (jt_mu(&jp, e) - jt_mu(&chain.jac, e)) / step;
        }
    }
    if !h.iter().all(|v: &f64| v.is_finite()) {
        return None;
    }
    let h = (&h + h.transpose()) * 0.5;
    let mut kkt = DMatrix::zeros(c + r, c + r);
    kkt.view_mut((0, 0), (c, c)).copy_from(&h);
    kkt.view_mut((0, c), (c, r)).copy_from(&jt);
    kkt.view_mut((c, 0), (r, c)).copy_from(jac);
    let rhs: Vec<f64> = d.iter().chain(g).copied().collect();
    let sol = min_change_step(&kkt, &rhs, &vec![0.0; c + r], Rank::Relative)?;
    let delta = sol.delta[..c].to_vec();
    delta.iter().all(|v| v.is_finite()).then_some(delta)
}

/// The constrained Gauss–Newton iteration of the module docs on `block`,
/// in place on `y` (with the curvature-corrected Newton step of
/// [`closest_point_newton_step`] where the rows leave freedom). Stops when
/// the rows are satisfied and the correction is at round-off level (zero
/// iterations when the first correction is exactly zero), or stagnates
/// there, or at `max_iterations`.
fn gauss_newton(
    chain: &mut Chain<'_>,
    y: &mut [f64],
    block: &Block<'_>,
    opts: &InitOptions,
) -> Result<Solve, SolveError> {
    let (rows, cols) = (block.rows, block.cols);
    let mut jac = DMatrix::zeros(rows.len(), cols.len());
    let mut g = vec![0.0; rows.len()];
    let mut d = vec![0.0; cols.len()];
    let mut trial = y.to_vec();
    let mut prev_size = f64::INFINITY;
    let mut iterations = 0;
    chain.eval_or_err(y)?;
    loop {
        let within = rows.iter().all(|&r| chain.satisfied(r, y, opts.tol));
        if iterations >= opts.max_iterations {
            return Ok(if within {
                Solve::Converged {
                    iterations,
                    at_limit: true,
                }
            } else {
                Solve::Failed { iterations }
            });
        }
        for (a, &r) in rows.iter().enumerate() {
            g[a] = chain.g[r];
            for (b, &c) in cols.iter().enumerate() {
                jac[(a, b)] = chain.jac[(r, c)];
            }
        }
        for (b, &c) in cols.iter().enumerate() {
            d[b] = y[c] - block.anchor[c];
        }
        let step = min_change_step(&jac, &g, &d, Rank::Relative).ok_or_else(|| {
            SolveError::invalid(
                "singular value decomposition of the constraint Jacobian did not converge",
            )
        })?;
        if block.need_full_rank && step.rank < rows.len() {
            let row = step
                .deficient_row
                .and_then(|a| rows.get(a))
                .or(rows.first())
                .copied();
            if let Some(row) = row {
                return Ok(Solve::Singular {
                    row,
                    rank: step.rank,
                });
            }
        }
        // Where the constraints leave freedom, the curvature of the
        // manifold enters the closest-point problem: take the Newton step
        // of its optimality system instead of the Gauss–Newton one.
        let mut delta = step.delta;
        if step.rank < cols.len() && d.iter().any(|&v| v != 0.0) {
            if let Some(newton) = closest_point_newton_step(chain, y, block, &jac, &g, &d) {
                delta = newton;
            }
        }
        let size = delta.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let ymax = cols.iter().fold(0.0_f64, |m, &c| m.max(y[c].abs()));
        let roundoff = f64::EPSILON * (1.0 + ymax);
        if iterations > 0
            && within
            && (size <= 16.0 * roundoff || (size <= 1e4 * roundoff && size >= 0.5 * prev_size))
        {
            return Ok(Solve::Converged {
                iterations,
                at_limit: false,
            });
        }
        if size == 0.0 {
            return Ok(if within {
                Solve::Converged {
                    iterations,
                    at_limit: false,
                }
            } else {
                Solve::Failed { iterations }
            });
        }
        // Apply the correction, halving it while the model is not finite
        // at the new point.
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..=MAX_HALVINGS {
            trial.copy_from_slice(y);
            for (b, &c) in cols.iter().enumerate() {
                trial[c] = y[c] + alpha * delta[b];
            }
            if trial.iter().all(|v| v.is_finite()) && chain.eval(&trial) {
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            // Name the row at the full step (the first point tried).
            for (b, &c) in cols.iter().enumerate() {
                trial[c] = y[c] + delta[b];
            }
            chain.eval(&trial);
            return Err(chain.non_finite(&trial));
        }
        y.copy_from_slice(&trial);
        iterations += 1;
        prev_size = alpha * size;
    }
}

/// Which of the unknowns `cols` the rows `rows` contain (indexed by unknown,
/// length `n`).
fn touched(
    pattern: &[Vec<bool>],
    n: usize,
    rows: impl Iterator<Item = usize>,
    cols: &[usize],
) -> Vec<bool> {
    let mut t = vec![false; n];
    for r in rows {
        for &c in cols {
            t[c] |= pattern[r][c];
        }
    }
    t
}

/// Bookkeeping of the projection stages.
#[derive(Default)]
struct Progress {
    notes: Vec<String>,
    projection_iterations: usize,
}

/// One attempt at a projection stage; `true` when its rows are satisfied.
fn projection_stage(
    chain: &mut Chain<'_>,
    y: &mut [f64],
    block: &Block<'_>,
    opts: &InitOptions,
    level: u8,
    progress: &mut Progress,
) -> Result<bool, SolveError> {
    match gauss_newton(chain, y, block, opts)? {
        Solve::Converged {
            iterations,
            at_limit,
        } => {
            progress.projection_iterations += iterations;
            if at_limit {
                progress.notes.push(format!(
                    "level {level}: iteration limit reached with the constraints satisfied; \
                     the projection may not be the closest point"
                ));
            }
            Ok(true)
        }
        Solve::Failed { iterations } => {
            progress.projection_iterations += iterations;
            Ok(false)
        }
        Solve::Singular { .. } => Ok(false),
    }
}

/// Compute consistent initial values from the given ones.
///
/// `y0` holds every unknown of the formulation: the differential values
/// (positions, velocities) are the data, the algebraic values are a first
/// guess (any finite value will do, `0` is fine). See the module
/// documentation for the algorithm. Returns the consistent `y` with a
/// report, or
///
/// * [`SolveError::InvalidInput`] — wrong length, a non-finite value (named),
///   invalid options;
/// * [`SolveError::InconsistentInitialValues`] — in [`InitMode::Strict`] a
///   violated constraint of the lowest violated level (the worst of that
///   level) and its residual at the given values; in [`InitMode::Project`] a
///   constraint that cannot be satisfied (e.g. a rank-zero Jacobian at the
///   given point);
/// * [`SolveError::Init`] — [`InitError::Singular`]: multipliers the
///   constraints do not determine, naming the dependent rows;
///   [`InitError::NotConverged`]: Newton for the algebraic unknowns did not
///   converge, naming the worst row; [`InitError::NonFinite`]: a row of the
///   chain is NaN or ∞ at a point reached, naming it and the point;
/// * [`SolveError::NonFinite`] — the model is not finite near the initial
///   values (while its structure is read).
///
/// Every value of `y0` counts as given: the differential ones are
/// [`Start::Fixed`], the algebraic ones [`Start::Guess`]
/// ([`InitReport::values`]); [`consistent_from`] says which is which.
///
/// ```
/// use dae::dae_solvers::init::{consistent, InitMode, InitOptions};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd1(); // x, y, v, w, lambda
/// // Off the circle and with a radial velocity: projected with least change.
/// let start = consistent(&sys, 0.0, &[1.1, 0.0, 0.3, 0.0, 0.0], &InitOptions::default())?;
/// let [x, y, v, w, lambda] = start.y[..] else { unreachable!() };
/// assert!((x * x + y * y - 1.0).abs() < 1e-12 && (x * v + y * w).abs() < 1e-12);
/// assert!(start.report.projected && lambda.is_finite());
/// // Refused instead of projected:
/// let strict = InitOptions { mode: InitMode::Strict, ..InitOptions::default() };
/// let err = consistent(&sys, 0.0, &[1.1, 0.0, 0.0, 0.0, 0.0], &strict).unwrap_err();
/// assert_eq!(err.kind(), "inconsistent_initial_values");
/// # Ok::<(), SolveError>(())
/// ```
pub fn consistent(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    opts: &InitOptions,
) -> Result<Consistent, SolveError> {
    opts.validate()?;
    validate_point(sys, t0, y0)?;
    let start: Vec<Start> = sys
        .info()
        .variables
        .iter()
        .zip(y0)
        .map(|(v, &x)| match v.kind {
            VarKind::Differential => Start::Fixed(x),
            VarKind::Algebraic => Start::Guess(x),
        })
        .collect();
    consistent_checked(sys, t0, y0, &start, opts)
}

/// [`consistent`] with each unknown's start said: a value given
/// ([`Start::Fixed`]: kept, or projected and reported), a guess
/// ([`Start::Guess`]: only where the iteration starts) or nothing
/// ([`Start::Omitted`]: starts from 0). The values computed are those of
/// [`consistent`] from `y0 = start.map(Start::value)`; the report's
/// [`InitReport::values`] says for each unknown how its value came about,
/// and flags an algebraic unknown started from 0 that its rows contain
/// nonlinearly ([`InitValue::root_chosen_by_default`]): the constraints
/// may have other solutions there, and a guess chooses among them.
///
/// ```
/// use dae::dae_solvers::init::{consistent_from, How, InitOptions, Start};
/// use dae::prelude::*;
///
/// dae! {
///     /// `x = exp(t)` held by a multiplier `z` with two consistent values.
///     pub TwoRoots {
///         differential { x, y }
///         algebraic { z }
///         equations {
///             der(x) = y * z * (z + 1) / 2;
///             der(y) = x;
///             0 = x - exp(t);
///         }
///         formulations { ori2 }
///     }
/// }
/// let sys = TwoRoots::default().ori2();
/// let opts = InitOptions::default();
/// let start = [Start::Fixed(1.0), Start::Fixed(1.0), Start::Omitted];
/// let first = consistent_from(&sys, 0.0, &start, &opts)?;
/// let z = &first.report.values[2];
/// assert!((z.value - 1.0).abs() < 1e-12);
/// assert!(z.how == How::Defaulted && z.root_chosen_by_default());
/// let guessed = [Start::Fixed(1.0), Start::Fixed(1.0), Start::Guess(-1.0)];
/// let other = consistent_from(&sys, 0.0, &guessed, &opts)?;
/// assert!((other.y[2] + 2.0).abs() < 1e-12);
/// assert_eq!(other.report.values[2].how, How::Guessed);
/// # Ok::<(), SolveError>(())
/// ```
pub fn consistent_from(
    sys: &dyn DaeSystem,
    t0: f64,
    start: &[Start],
    opts: &InitOptions,
) -> Result<Consistent, SolveError> {
    opts.validate()?;
    let y0: Vec<f64> = start.iter().map(|s| s.value()).collect();
    validate_point(sys, t0, &y0)?;
    consistent_checked(sys, t0, &y0, start, opts)
}

/// Which of the unknowns `cols` the rows `rows` contain nonlinearly: their
/// column of the chain's Jacobian at `y` differs from the one at two points
/// where every unknown of `cols` is moved (by `0.37 (1 + |y_c|)` and
/// `−0.61 (1 + |y_c|)`), or is not finite there. A column that does not
/// depend on these unknowns is evaluated from the same expression at every
/// point and compares equal to round-off.
fn nonlinear_columns(chain: &Chain<'_>, y: &[f64], rows: &[usize], cols: &[usize]) -> Vec<bool> {
    let (k, n) = chain.jac.shape();
    let mut base = DMatrix::zeros(k, n);
    chain.sys.constraints_jacobian(chain.t, y, &mut base);
    let mut moved = DMatrix::zeros(k, n);
    let mut nonlinear = vec![false; cols.len()];
    for factor in [0.37, -0.61] {
        let mut yp = y.to_vec();
        for &c in cols {
            yp[c] = y[c] + factor * (1.0 + y[c].abs());
        }
        chain.sys.constraints_jacobian(chain.t, &yp, &mut moved);
        for (b, &c) in cols.iter().enumerate() {
            nonlinear[b] |= rows.iter().any(|&r| {
                let (u, v) = (base[(r, c)], moved[(r, c)]);
                !v.is_finite() || (u - v).abs() > 1e-9 * (u.abs() + v.abs())
            });
        }
    }
    nonlinear
}

/// [`consistent`] on a checked `y0 = start.map(Start::value)`.
fn consistent_checked(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    start: &[Start],
    opts: &InitOptions,
) -> Result<Consistent, SolveError> {
    let info = sys.info();
    let n = info.unknowns();
    let members = &info.constraints;
    let k = members.len();

    let diff_cols: Vec<usize> = (0..n)
        .filter(|&j| info.variables[j].kind == VarKind::Differential)
        .collect();
    let alg_cols: Vec<usize> = (0..n)
        .filter(|&j| info.variables[j].kind == VarKind::Algebraic)
        .collect();

    let mut y = y0.to_vec();
    let mut chain = Chain::new(sys, t0);
    let pattern = structure(&mut chain, &y)?;
    let mut progress = Progress::default();

    // Algebraic unknowns in no member of the chain (GGL's η): exactly 0.
    let mut zeroed = Vec::new();
    for &a in &alg_cols {
        if !(0..k).any(|r| pattern[r][a]) {
            y[a] = 0.0;
            zeroed.push(info.variables[a].name.clone());
        }
    }
    // The anchor of every least-change problem: the values as given.
    let given = y.clone();
    chain.eval_or_err(&y)?;
    let before = chain.g.clone();

    // Classify the rows: top level per source, containing an algebraic
    // unknown → algebraic row; everything else → differential row.
    let top_level = |source: u16| {
        members
            .iter()
            .filter(|m| m.source == source)
            .map(|m| m.level)
            .max()
            .unwrap_or(0)
    };
    let is_alg_row = |r: usize| {
        members[r].level == top_level(members[r].source) && alg_cols.iter().any(|&a| pattern[r][a])
    };
    let mut alg_rows: Vec<usize> = (0..k).filter(|&r| is_alg_row(r)).collect();
    let mut diff_rows: Vec<usize> = (0..k).filter(|&r| !is_alg_row(r)).collect();
    // An algebraic unknown that a differential row contains is a function
    // of the state, fixed by an algebraic row of its own (the reaction rate
    // of a CSTR, `0 = r − k(T)·c`, whose derivative the prescribed output's
    // chain holds). It is corrected with the differential unknowns in step
    // 1, and the algebraic rows that hold no other algebraic unknown move
    // there with it; step 2 solves the rest.
    // (Ascending, as `alg_cols` is. One pass suffices: a row that moves
    // holds no algebraic unknown outside `with_state`, so none joins it.)
    let with_state: Vec<usize> = alg_cols
        .iter()
        .copied()
        .filter(|&a| diff_rows.iter().any(|&r| pattern[r][a]))
        .collect();
    if !with_state.is_empty() {
        let (moving, staying): (Vec<usize>, Vec<usize>) = alg_rows.iter().partition(|&&r| {
            alg_cols
                .iter()
                .all(|&a| !pattern[r][a] || with_state.contains(&a))
        });
        alg_rows = staying;
        diff_rows.extend(moving);
        diff_rows.sort_unstable();
    }
    let diff_cols: Vec<usize> = {
        let mut c = diff_cols;
        c.extend(with_state.iter().copied());
        c.sort_unstable();
        c
    };
    let alg_cols: Vec<usize> = alg_cols
        .iter()
        .copied()
        .filter(|a| !with_state.contains(a))
        .collect();
    let alg_touched = touched(&pattern, n, alg_rows.iter().copied(), &alg_cols);
    let alg_solve_cols: Vec<usize> = alg_cols
        .iter()
        .copied()
        .filter(|&a| alg_touched[a])
        .collect();

    // Step 1: the differential rows.
    let violated: Vec<usize> = diff_rows
        .iter()
        .copied()
        .filter(|&r| !chain.satisfied(r, &y, opts.tol))
        .collect();
    if !violated.is_empty() {
        if opts.mode == InitMode::Strict {
            // The lowest violated level is the cause (a velocity residual
            // at a wrong position means little); the worst row within it.
            let lowest = violated
                .iter()
                .map(|&r| members[r].level)
                .min()
                .unwrap_or(0);
            let candidates: Vec<usize> = violated
                .iter()
                .copied()
                .filter(|&r| members[r].level == lowest)
                .collect();
            let r = chain.worst(&candidates, &y).unwrap_or(violated[0]);
            return Err(SolveError::InconsistentInitialValues {
                equation: equation_text(&members[r].expr),
                residual: before[r],
            });
        }
        let mut levels: Vec<u8> = diff_rows.iter().map(|&r| members[r].level).collect();
        levels.sort_unstable();
        levels.dedup();
        for &level in &levels {
            let rows: Vec<usize> = diff_rows
                .iter()
                .copied()
                .filter(|&r| members[r].level <= level)
                .collect();
            chain.eval_or_err(&y)?;
            if rows.iter().all(|&r| chain.satisfied(r, &y, opts.tol)) {
                continue;
            }
            let earlier = touched(
                &pattern,
                n,
                diff_rows
                    .iter()
                    .copied()
                    .filter(|&r| members[r].level < level),
                &diff_cols,
            );
            let here = touched(
                &pattern,
                n,
                diff_rows
                    .iter()
                    .copied()
                    .filter(|&r| members[r].level == level),
                &diff_cols,
            );
            let all = touched(&pattern, n, rows.iter().copied(), &diff_cols);
            let new_cols: Vec<usize> = diff_cols
                .iter()
                .copied()
                .filter(|&c| here[c] && !earlier[c])
                .collect();
            let all_cols: Vec<usize> = diff_cols.iter().copied().filter(|&c| all[c]).collect();
            let start = y.clone();
            let mut done = false;
            if !new_cols.is_empty() {
                let block = Block {
                    rows: &rows,
                    cols: &new_cols,
                    anchor: &given,
                    need_full_rank: false,
                };
                done = projection_stage(&mut chain, &mut y, &block, opts, level, &mut progress)?;
            }
            if !done && all_cols.len() > new_cols.len() {
                y.copy_from_slice(&start);
                progress.notes.push(format!(
                    "level {level}: the unknowns new at this level could not satisfy it; \
                     corrected all differential unknowns of levels ≤ {level} jointly"
                ));
                let block = Block {
                    rows: &rows,
                    cols: &all_cols,
                    anchor: &given,
                    need_full_rank: false,
                };
                done = projection_stage(&mut chain, &mut y, &block, opts, level, &mut progress)?;
            }
            if !done {
                chain.eval_or_err(&y)?;
                let failing: Vec<usize> = rows
                    .iter()
                    .copied()
                    .filter(|&r| !chain.satisfied(r, &y, opts.tol))
                    .collect();
                let pool = if failing.is_empty() { &rows } else { &failing };
                let r = chain.worst(pool, &y).unwrap_or(rows[0]);
                let residual = if violated.contains(&r) {
                    before[r]
                } else {
                    chain.g[r]
                };
                return Err(SolveError::InconsistentInitialValues {
                    equation: equation_text(&members[r].expr),
                    residual,
                });
            }
        }
    }

    // Step 2: the algebraic rows, for the algebraic unknowns they contain.
    let mut newton_iterations = 0;
    if !alg_rows.is_empty() {
        let block = Block {
            rows: &alg_rows,
            cols: &alg_solve_cols,
            anchor: &given,
            need_full_rank: true,
        };
        match gauss_newton(&mut chain, &mut y, &block, opts)? {
            Solve::Converged {
                iterations,
                at_limit,
            } => {
                newton_iterations = iterations;
                if at_limit {
                    progress.notes.push(
                        "algebraic unknowns: iteration limit reached with the constraints satisfied"
                            .to_string(),
                    );
                }
            }
            Solve::Failed { iterations } => {
                chain.eval_or_err(&y)?;
                let r = chain.worst(&alg_rows, &y).unwrap_or(alg_rows[0]);
                return Err(SolveError::Init(InitError::NotConverged {
                    t: t0,
                    equation: equation_text(&members[r].expr),
                    residual: chain.g[r],
                    iterations,
                }));
            }
            Solve::Singular { row, rank } => {
                // The point where the rank fell is in `y` (the start, unless
                // it fell during the iteration).
                chain.eval_or_err(&y)?;
                let mut jac = DMatrix::zeros(alg_rows.len(), alg_solve_cols.len());
                for (a, &r) in alg_rows.iter().enumerate() {
                    for (b, &c) in alg_solve_cols.iter().enumerate() {
                        jac[(a, b)] = chain.jac[(r, c)];
                    }
                }
                let mut dependent: Vec<usize> = dependent_rows(&jac)
                    .into_iter()
                    .map(|a| alg_rows[a])
                    .collect();
                if dependent.is_empty() {
                    // The QR pivots stayed above the threshold where the
                    // singular values did not: the SVD's row.
                    dependent.push(row);
                }
                return Err(SolveError::Init(InitError::Singular {
                    t: t0,
                    equations: dependent
                        .iter()
                        .map(|&r| equation_text(&members[r].expr))
                        .collect(),
                    unknowns: alg_solve_cols
                        .iter()
                        .map(|&a| info.variables[a].name.clone())
                        .collect(),
                    rank,
                    rows: alg_rows.len(),
                }));
            }
        }
    }

    // Final check of the whole chain.
    chain.eval_or_err(&y)?;
    let after = chain.g.clone();
    let unsatisfied: Vec<usize> = (0..k)
        .filter(|&r| !chain.satisfied(r, &y, opts.tol))
        .collect();
    if let Some(r) = chain.worst(&unsatisfied, &y) {
        return Err(SolveError::InconsistentInitialValues {
            equation: equation_text(&members[r].expr),
            residual: after[r],
        });
    }

    let changes: Vec<VarChange> = diff_cols
        .iter()
        .copied()
        .filter(|&j| y[j].to_bits() != y0[j].to_bits())
        .map(|j| VarChange {
            name: info.variables[j].name.clone(),
            index: j,
            before: y0[j],
            after: y[j],
        })
        .collect();
    let algebraic: Vec<VarChange> = alg_solve_cols
        .iter()
        .map(|&j| VarChange {
            name: info.variables[j].name.clone(),
            index: j,
            before: y0[j],
            after: y[j],
        })
        .collect();
    let constraints: Vec<ConstraintResidual> = members
        .iter()
        .enumerate()
        .map(|(r, m)| ConstraintResidual {
            level: m.level,
            source: m.source,
            equation: equation_text(&m.expr),
            before: before[r],
            after: after[r],
        })
        .collect();
    let mut level_list: Vec<u8> = members.iter().map(|m| m.level).collect();
    level_list.sort_unstable();
    level_list.dedup();
    let levels = level_list
        .into_iter()
        .map(|level| {
            let max = |v: &[f64]| {
                (0..k)
                    .filter(|&r| members[r].level == level)
                    .fold(0.0_f64, |m, r| m.max(v[r].abs()))
            };
            LevelResidual {
                level,
                before: max(&before),
                after: max(&after),
            }
        })
        .collect();

    let nonlinear = nonlinear_columns(&chain, &y, &alg_rows, &alg_solve_cols);
    let values = (0..n)
        .map(|j| {
            let (given, guess, how) = match start[j] {
                Start::Fixed(v) if v.to_bits() == y[j].to_bits() => (Some(v), None, How::Fixed),
                Start::Fixed(v) => (Some(v), None, How::Projected),
                Start::Guess(v) => (None, Some(v), How::Guessed),
                Start::Omitted => (None, None, How::Defaulted),
            };
            InitValue {
                name: info.variables[j].name.clone(),
                given,
                guess,
                value: y[j],
                moved: (y[j] - start[j].value()).abs(),
                how,
                nonlinear: alg_solve_cols
                    .iter()
                    .position(|&a| a == j)
                    .is_some_and(|b| nonlinear[b]),
            }
        })
        .collect();

    Ok(Consistent {
        report: InitReport {
            values,
            mode: opts.mode,
            projected: !changes.is_empty(),
            changes,
            algebraic,
            zeroed,
            constraints,
            levels,
            projection_iterations: progress.projection_iterations,
            newton_iterations,
            notes: progress.notes,
        },
        y,
    })
}

/// `y'(t0)` at (consistent) initial values `y0`.
///
/// Among the least-squares solutions of `E(y0) y' = f(t0, y0)` — the affine
/// set `E⁺f + ker E`, `E` of size M×N, possibly rectangular (`M > N` for
/// overdetermined formulations) and rank-deficient (zero algebraic columns
/// and constraint rows) — return the one that best satisfies the
/// differentiated constraint chain `G(y0) y' + ∂g/∂t = 0`, and among those
/// the one of minimum norm:
///
/// ```text
///     y' = E⁺f + Z ζ,   ζ = −(G Z)⁺ (G E⁺f + g_t),   Z: orthonormal basis of ker E.
/// ```
///
/// On differential rows `E y' = f` holds to round-off whenever it is
/// solvable; the kernel directions (multipliers) get the derivative the
/// chain implies (`λ'` from the derivative of the acceleration constraint,
/// `η' = 0` for GGL multipliers, which appear in no constraint). `g_t` is a
/// central difference in `t` (exactly 0 for autonomous models).
///
/// Errors: [`SolveError::InvalidInput`] for a wrong length or non-finite
/// value, [`SolveError::NonFinite`] when the model produces NaN or ∞.
pub fn initial_derivative(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
) -> Result<Vec<f64>, SolveError> {
    validate_point(sys, t0, y0)?;
    initial_derivative_with(sys, t0, y0, &DerivativeRule::STRICT)
}

/// The choices in which the users of [`initial_derivative_with`] differ.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DerivativeRule {
    /// Rank of `E` and of `G Z`.
    rank: Rank,
    /// `true`: a constraint chain that cannot fix the kernel directions (a
    /// non-finite value, an SVD that does not converge) leaves them at their
    /// least-squares value and `y'` unchecked, for the caller to judge;
    /// `false`: either is an error.
    lenient: bool,
    /// `what` of the [`SolveError::NonFinite`] for a non-finite `E(y0)` and
    /// `f(t0, y0)`.
    non_finite: [&'static str; 2],
}

impl DerivativeRule {
    /// [`initial_derivative`].
    pub(crate) const STRICT: DerivativeRule = DerivativeRule {
        rank: Rank::Relative,
        lenient: false,
        non_finite: [
            "leading matrix at the initial values",
            "right-hand side at the initial values",
        ],
    };
    /// The start of the BDF solver (DASSL): every nonsingular `E` is solved
    /// exactly, and the solver's consistency test judges the result.
    pub(crate) const SOLVER: DerivativeRule = DerivativeRule {
        rank: Rank::RoundOff,
        lenient: true,
        non_finite: ["leading matrix", "right-hand side"],
    };
}

impl DerivativeRule {
    /// The typed error naming `E` (its values) or `f` at `t0` when either
    /// holds a non-finite entry.
    fn check_finite(&self, e: &[f64], f: &[f64], t0: f64) -> Result<(), SolveError> {
        for (values, what) in [(e, self.non_finite[0]), (f, self.non_finite[1])] {
            if !values.iter().all(|v| v.is_finite()) {
                return Err(SolveError::NonFinite { t: t0, what });
            }
        }
        Ok(())
    }
}

/// [`initial_derivative`] by `rule`, for `y0` of the system's length and
/// finite (not checked here).
pub(crate) fn initial_derivative_with(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    rule: &DerivativeRule,
) -> Result<Vec<f64>, SolveError> {
    let n = sys.info().unknowns();
    if n == 0 {
        return Ok(Vec::new());
    }
    if n >= SPARSE_FROM {
        if let Some(yp) = initial_derivative_sparse(sys, t0, y0, rule)? {
            return Ok(yp);
        }
    }
    initial_derivative_dense(sys, t0, y0, rule)
}

/// [`initial_derivative_with`] by the SVD of the dense `E` (every system
/// below [`SPARSE_FROM`] unknowns, and the larger ones whose `E` has no
/// square non-zero block).
fn initial_derivative_dense(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    rule: &DerivativeRule,
) -> Result<Vec<f64>, SolveError> {
    let info = sys.info();
    let (m, n) = (info.equations(), info.unknowns());
    let mut e = DMatrix::zeros(m, n);
    sys.leading(t0, y0, &mut e);
    let mut f = vec![0.0; m];
    sys.rhs(t0, y0, &mut f);
    rule.check_finite(e.as_slice(), &f, t0)?;
    // Zero rows padded below so that V is N×N and carries ker E.
    let rows = m.max(n);
    let mut a = DMatrix::zeros(rows, n);
    a.view_mut((0, 0), (m, n)).copy_from(&e);
    let svd_failed = || {
        SolveError::invalid("singular value decomposition of the leading matrix did not converge")
    };
    let svd = rule.rank.svd(a).ok_or_else(svd_failed)?;
    let (u, vt) = match (svd.u.as_ref(), svd.v_t.as_ref()) {
        (Some(u), Some(vt)) => (u, vt),
        _ => return Err(svd_failed()),
    };
    let s = &svd.singular_values; // descending, length n
    let rank = rule.rank.of(s.as_slice(), rows, n);
    let mut yp = vec![0.0; n];
    for i in 0..rank {
        let uf: f64 = (0..m).map(|r| u[(r, i)] * f[r]).sum();
        let coef = uf / s[i];
        for (c, ypc) in yp.iter_mut().enumerate() {
            *ypc += coef * vt[(i, c)];
        }
    }

    let nz = n - rank;
    if nz > 0 && !info.constraints.is_empty() {
        let z = vt.rows(rank, nz).transpose();
        if let Some(zeta) = kernel_from_chain(sys, t0, y0, &yp, Kernel::Basis(&z), rule)? {
            for (k, zeta_k) in zeta.iter().enumerate() {
                for (c, ypc) in yp.iter_mut().enumerate() {
                    *ypc += zeta_k * z[(c, k)];
                }
            }
        }
    }
    if !rule.lenient && !yp.iter().all(|v| v.is_finite()) {
        return Err(SolveError::NonFinite {
            t: t0,
            what: "initial derivative",
        });
    }
    Ok(yp)
}

/// `y'(t0)` without the SVD of `E`, for a large system whose `E(y0)` has,
/// once its zero rows and zero columns are set aside, a square nonsingular
/// block: the structure of the index-1 and GGL formulations (`E` selects
/// the differential unknowns' derivatives, its rows of algebraic equations
/// and its columns of algebraic unknowns are zero). Then `ker E` is spanned
/// by the zero columns, `E⁺f` is the block's solution on the others and
/// `0` on them, and `y'` is the dense path's to round-off: one sparse LU of
/// the block, and for the kernel part one of `G Z`, `Z` the zero columns
/// (`G Z` is `G` restricted to them; [`crate::linalg::sparse_lstsq`]).
/// `E` is read at its structural non-zeros (`DaeSystem::leading_values`).
///
/// `Ok(None)` — the caller takes the dense path — where `E` has another
/// form (a kernel that no zero column spans, more non-zero rows than
/// columns, a singular block); the errors are the dense path's.
fn initial_derivative_sparse(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    rule: &DerivativeRule,
) -> Result<Option<Vec<f64>>, SolveError> {
    let info = sys.info();
    let (m, n) = (info.equations(), info.unknowns());
    let pattern = sys.sparsity().leading;
    let mut values = vec![0.0; pattern.nnz()];
    sys.leading_values(t0, y0, &pattern, &mut values);
    let mut f = vec![0.0; m];
    sys.rhs(t0, y0, &mut f);
    rule.check_finite(&values, &f, t0)?;
    let e = Entries::from_pattern(&pattern, &values);
    let neg_f: Vec<f64> = f.iter().map(|v| -v).collect();
    // Δ = −E⁺(−f) = E⁺f; only a square non-zero block makes the zero
    // columns the whole kernel.
    let Some(step) = sparse_lstsq::min_change(&e, &neg_f, &vec![0.0; n]) else {
        return Ok(None);
    };
    if step.rank + step.zero_cols.len() != n {
        return Ok(None);
    }
    let mut yp = step.delta;
    if !step.zero_cols.is_empty() && !info.constraints.is_empty() {
        let z = Kernel::Columns(&step.zero_cols);
        if let Some(zeta) = kernel_from_chain(sys, t0, y0, &yp, z, rule)? {
            for (&c, zeta_c) in step.zero_cols.iter().zip(zeta) {
                yp[c] += zeta_c;
            }
        }
    }
    if !rule.lenient && !yp.iter().all(|v| v.is_finite()) {
        return Err(SolveError::NonFinite {
            t: t0,
            what: "initial derivative",
        });
    }
    Ok(Some(yp))
}

/// A basis of `ker E` for [`kernel_from_chain`].
#[derive(Clone, Copy)]
enum Kernel<'z> {
    /// Orthonormal columns (N × dim), from the SVD of `E`.
    Basis(&'z DMatrix<f64>),
    /// The unit vectors of these unknowns (zero columns of `E`).
    Columns(&'z [usize]),
}

/// `ζ = −(G Z)⁺ (G y'_E + g_t)`: the kernel part of `y' = y'_E + Z ζ` (`Z`
/// an orthonormal basis of `ker E` as columns, `y'_E = E⁺f`) that the
/// differentiated constraint chain implies. `Ok(None)` where the chain
/// cannot give it and `rule.lenient`.
fn kernel_from_chain(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    yp: &[f64],
    z: Kernel<'_>,
    rule: &DerivativeRule,
) -> Result<Option<Vec<f64>>, SolveError> {
    let give_up = |err: SolveError| if rule.lenient { Ok(None) } else { Err(err) };
    let n = yp.len();
    let nz = match z {
        Kernel::Basis(b) => b.ncols(),
        Kernel::Columns(c) => c.len(),
    };
    let mut chain = Chain::new(sys, t0);
    // Only G enters: a lenient caller does without a finite g(t0, y0).
    let finite = chain.eval(y0);
    if !(finite || rule.lenient && chain.jac.iter().all(|v| v.is_finite())) {
        return give_up(SolveError::NonFinite {
            t: t0,
            what: "constraint chain at the initial values",
        });
    }
    let k = chain.g.len();
    // g_t by a central difference in t.
    let dt = f64::EPSILON.cbrt() * t0.abs().max(1.0);
    let mut gp = vec![0.0; k];
    let mut gm = vec![0.0; k];
    sys.constraints(t0 + dt, y0, &mut gp);
    sys.constraints(t0 - dt, y0, &mut gm);
    // rhs of the kernel problem: (G Z) ζ = −(G E⁺f + g_t); passed to
    // `min_change_step` as the residual g = G E⁺f + g_t.
    let mut resid = vec![0.0; k];
    for (r, res) in resid.iter_mut().enumerate() {
        let gy: f64 = (0..n).map(|c| chain.jac[(r, c)] * yp[c]).sum();
        *res = gy + (gp[r] - gm[r]) / (2.0 * dt);
    }
    if !resid.iter().all(|v| v.is_finite()) {
        return give_up(SolveError::NonFinite {
            t: t0,
            what: "time derivative of the constraint chain",
        });
    }
    let mut gz: DMatrix<f64> = DMatrix::zeros(k, nz);
    match z {
        Kernel::Basis(z) => {
            for r in 0..k {
                for c in 0..nz {
                    gz[(r, c)] = (0..n).map(|j| chain.jac[(r, j)] * z[(j, c)]).sum();
                }
            }
        }
        Kernel::Columns(cols) => {
            let finite = cols
                .iter()
                .all(|&c| chain.jac.column(c).iter().all(|v| v.is_finite()));
            if finite {
                // `G Z` is G's columns of the kernel unknowns: its zero
                // rows (members without them) drop out of the
                // pseudo-inverse, the rest is one sparse solve.
                let a = Entries::scan(k, nz, |r, c| chain.jac[(r, cols[c])]);
                let zeros = vec![0.0; nz];
                if let Some(step) = sparse_lstsq::min_change(&a, &resid, &zeros) {
                    return Ok(Some(step.delta));
                }
            }
            for (c, &col) in cols.iter().enumerate() {
                gz.set_column(c, &chain.jac.column(col));
            }
        }
    }
    if !gz.iter().all(|v| v.is_finite()) {
        return give_up(SolveError::NonFinite {
            t: t0,
            what: "constraint chain at the initial values",
        });
    }
    match min_change_step(&gz, &resid, &vec![0.0; nz], rule.rank) {
        Some(step) => Ok(Some(step.delta)),
        None => give_up(SolveError::invalid(
            "singular value decomposition of the constraint Jacobian did not converge",
        )),
    }
}

/// Reject initial values `(y0, yp0)` that violate a row of `E y' = f` by more
/// than a perturbation of every unknown by its tolerance could explain:
/// `|F_i| > Σ_j |∂F_i/∂y_j| (atol_j + rtol_j |y_j|)`, beyond round-off.
pub(crate) fn check_residuals(
    sys: &dyn DaeSystem,
    tol: &Tolerances,
    t0: f64,
    y0: &[f64],
    yp0: &[f64],
    stats: &mut Stats,
) -> Result<(), SolveError> {
    let n = y0.len();
    let info = sys.info();
    let m = info.equations();
    let mut r = vec![0.0; m];
    sys.residual(t0, y0, yp0, &mut r);
    let mut f = vec![0.0; m];
    sys.rhs(t0, y0, &mut f);
    stats.residual_evals += 2;
    if !r.iter().all(|v| v.is_finite()) {
        return Err(SolveError::NonFinite {
            t: t0,
            what: "residual",
        });
    }
    stats.jacobian_evals += 1;
    let scale: Vec<f64> = (0..n)
        .map(|j| tol.atol(j) + tol.rtol(j) * y0[j].abs())
        .collect();
    // Per row: `Σ_j |E_ij y'_j|` and `Σ_j |∂F_i/∂y_j| scale_j`.
    let (ey, allowed) = row_sums(sys, t0, y0, yp0, &scale);
    let mut worst: Option<(usize, f64)> = None;
    for i in 0..m {
        let ri = r[i].abs();
        if ri <= 100.0 * f64::EPSILON * (f[i].abs() + ey[i]) {
            continue;
        }
        let allowed = allowed[i];
        let ratio = if allowed > 0.0 {
            ri / allowed
        } else {
            f64::INFINITY
        };
        let worse = match worst {
            Some((_, w)) => ratio > w,
            None => true,
        };
        if ratio > 1.0 && worse {
            worst = Some((i, ratio));
        }
    }
    match worst {
        Some((i, _)) => Err(SolveError::InconsistentInitialValues {
            equation: info
                .rows
                .get(i)
                .map(|row| row.text.clone())
                .unwrap_or_else(|| format!("row {i}")),
            residual: r[i],
        }),
        None => Ok(()),
    }
}

/// [`check_residuals`]' row sums: `Σ_j |E_ij y'_j|` and
/// `Σ_j |(∂(E y')/∂y − ∂f/∂y)_ij| scale_j` for every row `i`. From
/// [`SPARSE_FROM`] unknowns on, a square system with a constant `E` is
/// evaluated on its structural non-zeros ([`DaeSystem::sparsity`]): no
/// `N × N` matrix (at 1 000 unknowns the dense form was 59 M instructions,
/// a tenth of bdf's whole run on the 200-link chain, BENCHMARKS.md §16c).
/// The sums are the dense ones bit for bit: the same terms in the same
/// order (ascending `j`), without the exact zeros.
fn row_sums(
    sys: &dyn DaeSystem,
    t0: f64,
    y0: &[f64],
    yp0: &[f64],
    scale: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let info = sys.info();
    let (m, n) = (info.equations(), y0.len());
    let (mut ey, mut allowed) = (vec![0.0; m], vec![0.0; m]);
    if n >= SPARSE_FROM && m == n && info.constant_leading {
        let sparsity = sys.sparsity();
        let (e, j) = (&sparsity.leading, &sparsity.rhs_jacobian);
        if (e.rows, e.cols, j.rows, j.cols) == (m, n, m, n) {
            let mut values = vec![0.0; e.nnz()];
            sys.leading_values(t0, y0, e, &mut values);
            for ((r, c), v) in e.entries().zip(&values) {
                ey[r] += (v * yp0[c]).abs();
            }
            values.clear();
            values.resize(j.nnz(), 0.0);
            sys.rhs_jacobian_values(t0, y0, j, &mut values);
            for ((r, c), v) in j.entries().zip(&values) {
                allowed[r] += (v * scale[c]).abs();
            }
            return (ey, allowed);
        }
    }
    let mut jac = DMatrix::zeros(m, n);
    sys.rhs_jacobian(t0, y0, &mut jac);
    jac.neg_mut();
    if !info.constant_leading {
        let mut lj = DMatrix::zeros(m, n);
        sys.leading_jacobian(t0, y0, yp0, &mut lj);
        jac += lj;
    }
    let mut lead = DMatrix::zeros(m, n);
    sys.leading(t0, y0, &mut lead);
    for i in 0..m {
        ey[i] = (0..n).map(|j| (lead[(i, j)] * yp0[j]).abs()).sum();
        allowed[i] = (0..n).map(|j| (jac[(i, j)] * scale[j]).abs()).sum();
    }
    (ey, allowed)
}

#[cfg(all(test, feature = "sparse"))]
mod tests {
    use super::*;
    use dae_core::interp::InterpretedModel;
    use dae_core::system::Model;

    /// The planar chain of `n` links of `scripts/chain.py`, 5n unknowns.
    fn chain_model(n: usize) -> String {
        crate::test_models::chain(n)
    }

    /// The chain bent into a zig-zag, moving: no accidental zeros.
    fn chain_start(n: usize) -> Vec<f64> {
        let (mut x, mut y) = (0.0, 0.0);
        let mut q = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            let a = 0.3 + 0.4 * (i % 3) as f64 - 0.2 * (i % 2) as f64;
            let (px, py) = (x, y);
            x += a.cos();
            y -= a.sin();
            let w = 0.1 + 0.05 * (i % 4) as f64;
            q.0.push(x);
            q.1.push(y);
            // Velocity along the link's normal, plus the previous mass's.
            let (du, dv) = (w * (y - py), -w * (x - px));
            let (pu, pv) = (
                q.2.last().copied().unwrap_or(0.0),
                q.3.last().copied().unwrap_or(0.0),
            );
            q.2.push(pu + du);
            q.3.push(pv + dv);
        }
        let mut y0: Vec<f64> = [q.0, q.1, q.2, q.3].concat();
        y0.extend((0..n).map(|i| 0.5 * i as f64));
        y0
    }

    /// `check_residuals`' row sums over the structural non-zeros are the
    /// dense sums bit for bit (the chain's `rcd0`, 65 unknowns, constant
    /// `E`), and an initial value off its row is still refused.
    #[test]
    fn row_sums_on_the_structure_are_the_dense_ones() {
        let model = InterpretedModel::from_str(&chain_model(13)).expect("the chain derives");
        let sys = model.system("rcd0").expect("formulation");
        let info = sys.info();
        let (m, n) = (info.equations(), info.unknowns());
        assert!(n >= SPARSE_FROM && info.constant_leading, "the sparse sums");
        let y0 = chain_start(13);
        let yp0: Vec<f64> = (0..n).map(|i| 0.7 - 0.03 * i as f64).collect();
        let scale: Vec<f64> = (0..n).map(|j| 1e-6 * (1.0 + y0[j].abs())).collect();
        let (ey, allowed) = row_sums(&sys, 0.0, &y0, &yp0, &scale);
        let (mut jac, mut lead) = (DMatrix::zeros(m, n), DMatrix::zeros(m, n));
        sys.rhs_jacobian(0.0, &y0, &mut jac);
        sys.leading(0.0, &y0, &mut lead);
        for i in 0..m {
            let e: f64 = (0..n).map(|j| (lead[(i, j)] * yp0[j]).abs()).sum();
            let a: f64 = (0..n).map(|j| (-jac[(i, j)] * scale[j]).abs()).sum();
            assert_eq!((ey[i], allowed[i]), (e, a), "row {i}");
        }
        assert!(allowed.iter().any(|&a| a > 0.0));
        let tol = Tolerances::uniform(1e-6);
        let err = check_residuals(&sys, &tol, 0.0, &y0, &yp0, &mut Stats::default());
        assert!(
            matches!(err, Err(SolveError::InconsistentInitialValues { .. })),
            "an arbitrary y'0 violates the dynamics: {err:?}"
        );
    }

    /// Sparse and dense initial derivatives of the chain's index-1 and GGL
    /// forms agree to round-off, under both rules; 15 links are 75 (rcd0)
    /// and 90 (ggl1) unknowns, above `SPARSE_FROM`.
    #[test]
    fn sparse_initial_derivative_is_the_dense_one() {
        let n = 15;
        let model = InterpretedModel::from_str(&chain_model(n)).expect("chain parses");
        for form in ["rcd0", "ggl1"] {
            let sys = model.formulation(form).expect("formulation");
            let sys: &dyn DaeSystem = &*sys;
            assert!(sys.info().unknowns() >= SPARSE_FROM);
            let mut y0 = chain_start(n);
            y0.resize(sys.info().unknowns(), 0.0);
            let y = consistent(sys, 0.0, &y0, &InitOptions::default())
                .expect("consistent")
                .y;
            for rule in [DerivativeRule::STRICT, DerivativeRule::SOLVER] {
                let sparse = initial_derivative_sparse(sys, 0.0, &y, &rule)
                    .expect("finite")
                    .expect("the chain's E has a square non-zero block");
                let dense = initial_derivative_dense(sys, 0.0, &y, &rule).expect("finite");
                let scale = dense.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
                for (j, (a, b)) in sparse.iter().zip(&dense).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-10 * scale,
                        "{form} {rule:?}: y'[{j}] sparse {a} dense {b}"
                    );
                }
                // And the multipliers' derivatives are not trivially zero.
                assert!(sparse[4 * n..5 * n].iter().any(|v| v.abs() > 1e-3));
            }
        }
    }
}

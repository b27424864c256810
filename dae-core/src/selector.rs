//! The projected formulations with a selector computed numerically at run
//! time.
//!
//! `psi1` and `psi0` multiply the kinematic rows `q' = v` (and, for `psi0`,
//! the dynamic rows of the velocities) by a selector `S` with `S Gᵀ = 0`,
//! `G = ∂g/∂q`. The symbolic selector of [`crate::formulation`] is built from
//! a pivot block of `G` and loses rank where that block is singular — the
//! spherical pendulum's `[[z, 0, −x], [0, z, −y]]` at `z = 0` — and does not
//! exist for a time-dependent constraint (it would make `E` depend on `t`).
//!
//! [`NumericSelector`] builds the same formulation from the overdetermined
//! one it projects (`ovd1` for `psi1`, `ovd0` for `psi0`): its rows are the
//! overdetermined system's, with the kinematic rows (and for `psi0` the
//! velocity rows) replaced by `σ` times them, `σ` an orthonormal basis of the
//! null space of `G_q` (of `∂ġ/∂v` for the velocities), computed by an SVD.
//! `σ` is constant between updates, so `E` stays independent of `t` and the
//! Jacobians are exact linear combinations of the overdetermined system's.
//! It is recomputed when the leading matrix is evaluated (`leading`, which a
//! solver calls before it forms an iteration matrix and, with a
//! state-dependent `E`, at the start of a step) and the current `σ` has
//! degraded: the smallest singular value of `[σ; Ĝ]` (`Ĝ`
//! the rows of `G_q` normalised) below [`DEGRADED`]. Changing `σ` does not
//! change the solution: `σ (q' − v) = 0` together with `G (q' − v) = 0` (the
//! velocity constraint) is `q' = v` for any `σ` with `[σ; G]` nonsingular.
//!
//! The positions `q` and velocities `v` are read off the constraint chain's
//! structure ([`crate::system::chain_pattern`], which consistent
//! initialisation uses too): the differential unknowns whose column of the
//! level-0 (level-1) Jacobian is non-zero at the given point or at perturbed
//! ones, so that an accidental zero is not taken for a structural one.
//! `leading` allocates (the test of `σ` is an SVD of size `|q|`), as does
//! construction; the other evaluations do not.

use crate::system::{DaeSystem, FormulationInfo, RowInfo, RowKind, VarKind};
use nalgebra::DMatrix;
use std::cell::RefCell;

/// Smallest singular value of `[σ; Ĝ]` below which `σ` is recomputed.
pub const DEGRADED: f64 = 0.25;

/// Which projected formulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projected {
    /// `psi1`, from `ovd1`: kinematic rows projected.
    Psi1,
    /// `psi0`, from `ovd0`: kinematic and velocity rows projected.
    Psi0,
}

impl Projected {
    /// The formulation's name.
    pub fn name(self) -> &'static str {
        match self {
            Projected::Psi1 => "psi1",
            Projected::Psi0 => "psi0",
        }
    }
    /// The overdetermined formulation it projects.
    pub fn source(self) -> &'static str {
        match self {
            Projected::Psi1 => "ovd1",
            Projected::Psi0 => "ovd0",
        }
    }
}

/// One projected block: rows `cols` of the inner system (row `j` gives
/// `der(y_j)`) combined by `σ` ((|cols| − m) × |cols|).
#[derive(Clone, Debug)]
struct Block {
    cols: Vec<usize>,
    /// Chain rows whose Jacobian in `cols` is `G`.
    chain_rows: Vec<usize>,
    sigma: DMatrix<f64>,
    ready: bool,
}

impl Block {
    /// Recompute `σ` if it is not ready or has degraded at `jac` (K×N).
    fn update(&mut self, jac: &DMatrix<f64>) {
        let m = self.chain_rows.len();
        let n = self.cols.len();
        let mut g = DMatrix::zeros(m, n);
        for (a, &r) in self.chain_rows.iter().enumerate() {
            for (b, &c) in self.cols.iter().enumerate() {
                g[(a, b)] = jac[(r, c)];
            }
            let norm = g.row(a).norm();
            if norm > 0.0 && norm.is_finite() {
                g.row_mut(a).scale_mut(1.0 / norm);
            }
        }
        if !g.iter().all(|v| v.is_finite()) {
            return;
        }
        if self.ready {
            let mut stacked = DMatrix::zeros(n, n);
            stacked.rows_mut(0, n - m).copy_from(&self.sigma);
            stacked.rows_mut(n - m, m).copy_from(&g);
            let smallest = stacked.singular_values().min();
            if smallest >= DEGRADED {
                return;
            }
        }
        // The null space of G: the right singular vectors beyond its rank.
        // A full SVD of the square [G; 0] gives all n of them.
        let mut square = DMatrix::zeros(n, n);
        square.rows_mut(0, m).copy_from(&g);
        let svd = square.svd(false, true);
        let Some(vt) = svd.v_t else { return };
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        for (k, &i) in order[m..].iter().enumerate() {
            self.sigma.row_mut(k).copy_from(&vt.row(i));
        }
        self.ready = true;
    }
}

/// Scratch buffers of the inner system's size.
#[derive(Debug)]
struct Scratch {
    f: Vec<f64>,
    mat: DMatrix<f64>,
    jac: DMatrix<f64>,
}

/// `psi1`/`psi0` with a numerical selector (see the [module
/// documentation](self)).
pub struct NumericSelector<S> {
    inner: S,
    info: FormulationInfo,
    /// Inner rows copied as they are, in output order after the blocks.
    kept: Vec<usize>,
    blocks: RefCell<Vec<Block>>,
    scratch: RefCell<Scratch>,
}

impl<S: DaeSystem> std::fmt::Debug for NumericSelector<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NumericSelector")
            .field("name", &self.info.name)
            .field("kept", &self.kept)
            .finish_non_exhaustive()
    }
}

/// Why a numerical selector cannot be built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SelectorError {
    /// The system given is not the overdetermined formulation projected.
    #[error("the numerical `{name}` is built from `{source_name}`, not from `{given}`")]
    WrongSource {
        /// The projected formulation.
        name: &'static str,
        /// What it needs.
        source_name: &'static str,
        /// What was given.
        given: String,
    },
    /// The constraint chain is not finite where its structure is probed.
    #[error("the numerical `{name}` cannot read the constraints' structure: the chain or its Jacobian is not finite at the probe point")]
    NotFinite {
        /// The projected formulation.
        name: &'static str,
    },
    /// A model with a mass matrix has no `psi0`.
    #[error("`psi0` does not apply to a model with a mass matrix: its acceleration level holds `v'`, not the multipliers")]
    MassMatrix,
    /// Not a mechanical system (position constraints differentiated twice),
    /// or no positions with more unknowns than constraints.
    #[error("`{name}` needs positions and velocities with more unknowns than constraints ({positions} positions, {velocities} velocities, {constraints} constraints)")]
    NotMechanical {
        /// The projected formulation.
        name: &'static str,
        /// Positions found.
        positions: usize,
        /// Velocities found.
        velocities: usize,
        /// Position-level constraints.
        constraints: usize,
    },
}

impl<S: DaeSystem> NumericSelector<S> {
    /// Project `inner` (the model's `ovd1` for `psi1`, `ovd0` for `psi0`);
    /// `t0, y0` is where the structure is probed (any point will do).
    pub fn new(inner: S, which: Projected, t0: f64, y0: &[f64]) -> Result<Self, SelectorError> {
        let src = inner.info();
        if src.name != which.source() {
            return Err(SelectorError::WrongSource {
                name: which.name(),
                source_name: which.source(),
                given: src.name.clone(),
            });
        }
        let n = src.unknowns();
        let k = src.constraints.len();
        let level_rows =
            |l: u8| -> Vec<usize> { (0..k).filter(|&r| src.constraints[r].level == l).collect() };
        let (rows0, rows1) = (level_rows(0), level_rows(1));
        // A mechanical system: every constraint's chain ends at level 2.
        let sources: std::collections::BTreeSet<u16> =
            src.constraints.iter().map(|c| c.source).collect();
        let mechanical = !sources.is_empty()
            && sources.iter().all(|&s| {
                src.constraints
                    .iter()
                    .filter(|c| c.source == s)
                    .map(|c| c.level)
                    .max()
                    == Some(2)
            });
        if !mechanical {
            return Err(SelectorError::NotMechanical {
                name: which.name(),
                positions: 0,
                velocities: 0,
                constraints: rows0.len(),
            });
        }
        // Structure: non-zero columns at y0 and perturbed points.
        let seen = crate::system::chain_pattern(&inner, t0, y0)
            .ok_or(SelectorError::NotFinite { name: which.name() })?;
        let differential = |j: usize| src.variables[j].kind == VarKind::Differential;
        let in_rows = |rows: &[usize], j: usize| rows.iter().any(|&r| seen[r][j]);
        let q: Vec<usize> = (0..n)
            .filter(|&j| differential(j) && in_rows(&rows0, j))
            .collect();
        let v: Vec<usize> = (0..n)
            .filter(|&j| differential(j) && !q.contains(&j) && in_rows(&rows1, j))
            .collect();
        // psi0 finds the multipliers in the acceleration level; with a mass
        // matrix (a dynamics row of E with several entries among the
        // unknowns that are not positions) that level holds v', not λ (see
        // `formulation::applicable`). The coupling may be with a velocity
        // that no constraint holds (the cart pendulum's cart), so every
        // dynamics row and every such column is looked at.
        if which == Projected::Psi0 {
            let mut e = DMatrix::zeros(src.equations(), n);
            inner.leading(t0, y0, &mut e);
            let free: Vec<usize> = (0..n)
                .filter(|&j| differential(j) && !q.contains(&j))
                .collect();
            let coupled = (0..src.equations())
                .filter(|&r| src.rows[r].kind == RowKind::Differential)
                .any(|r| free.iter().filter(|&&c| e[(r, c)] != 0.0).count() > 1);
            if coupled {
                return Err(SelectorError::MassMatrix);
            }
        }
        let m = rows0.len();
        if q.len() <= m
            || v.len() < rows1.len()
            || (which == Projected::Psi0 && v.len() <= rows1.len())
        {
            return Err(SelectorError::NotMechanical {
                name: which.name(),
                positions: q.len(),
                velocities: v.len(),
                constraints: m,
            });
        }
        let block = |cols: Vec<usize>, chain_rows: Vec<usize>| Block {
            sigma: DMatrix::zeros(cols.len() - chain_rows.len(), cols.len()),
            cols,
            chain_rows,
            ready: false,
        };
        let mut blocks = vec![block(q.clone(), rows0)];
        if which == Projected::Psi0 {
            blocks.push(block(v.clone(), rows1));
        }
        let projected: Vec<usize> = blocks.iter().flat_map(|b| b.cols.clone()).collect();
        // The inner system's differential rows are in unknown order: row j
        // gives der(y_j).
        let kept: Vec<usize> = (0..src.equations())
            .filter(|&r| !(src.rows[r].kind == RowKind::Differential && projected.contains(&r)))
            .collect();
        let mut rows = Vec::new();
        for b in &blocks {
            let names: Vec<&str> = b
                .cols
                .iter()
                .map(|&c| src.variables[c].name.as_str())
                .collect();
            for i in 0..b.sigma.nrows() {
                rows.push(RowInfo {
                    kind: RowKind::Differential,
                    text: format!(
                        "σ{} · (rows of der({})): numerical selector row {}",
                        i + 1,
                        names.join(", "),
                        i + 1
                    ),
                });
            }
        }
        rows.extend(kept.iter().map(|&r| src.rows[r].clone()));
        let info = FormulationInfo {
            name: which.name().to_string(),
            rows,
            d_index: Some(src.c_level + 1),
            s_index: src.c_level,
            constant_leading: false,
            constant_differential_leading: false,
            ..src.clone()
        };
        let m_in = src.equations();
        let scratch = Scratch {
            f: vec![0.0; m_in],
            mat: DMatrix::zeros(m_in, n),
            jac: DMatrix::zeros(k, n),
        };
        let sys = NumericSelector {
            inner,
            info,
            kept,
            blocks: RefCell::new(blocks),
            scratch: RefCell::new(scratch),
        };
        sys.refresh(t0, y0);
        Ok(sys)
    }

    /// Update every block's `σ` at `(t, y)` if it has degraded.
    fn refresh(&self, t: f64, y: &[f64]) {
        let mut s = self.scratch.borrow_mut();
        self.inner.constraints_jacobian(t, y, &mut s.jac);
        for b in self.blocks.borrow_mut().iter_mut() {
            b.update(&s.jac);
        }
    }

    /// Combine the inner rows `src` (length M_in) into `out` (length N).
    fn combine_vec(&self, src: &[f64], out: &mut [f64]) {
        let mut o = 0;
        for b in self.blocks.borrow().iter() {
            for i in 0..b.sigma.nrows() {
                out[o] = b
                    .cols
                    .iter()
                    .enumerate()
                    .map(|(c, &r)| b.sigma[(i, c)] * src[r])
                    .sum();
                o += 1;
            }
        }
        for &r in &self.kept {
            out[o] = src[r];
            o += 1;
        }
    }

    /// Combine the inner matrix rows `src` (M_in × N) into `out` (N × N).
    fn combine_mat(&self, src: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        out.fill(0.0);
        let mut o = 0;
        for b in self.blocks.borrow().iter() {
            for i in 0..b.sigma.nrows() {
                for (c, &r) in b.cols.iter().enumerate() {
                    let w = b.sigma[(i, c)];
                    if w != 0.0 {
                        for j in 0..src.ncols() {
                            out[(o, j)] += w * src[(r, j)];
                        }
                    }
                }
                o += 1;
            }
        }
        for &r in &self.kept {
            for j in 0..src.ncols() {
                out[(o, j)] = src[(r, j)];
            }
            o += 1;
        }
    }
}

impl<S: DaeSystem> DaeSystem for NumericSelector<S> {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.inner.parameter_values()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        let mut s = self.scratch.borrow_mut();
        self.inner.rhs(t, y, &mut s.f);
        self.combine_vec(&s.f, f);
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let mut s = self.scratch.borrow_mut();
        self.inner.residual(t, y, yp, &mut s.f);
        self.combine_vec(&s.f, r);
    }
    fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>) {
        self.refresh(t, y);
        let mut s = self.scratch.borrow_mut();
        self.inner.leading(t, y, &mut s.mat);
        self.combine_mat(&s.mat, e);
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let mut s = self.scratch.borrow_mut();
        self.inner.rhs_jacobian(t, y, &mut s.mat);
        self.combine_mat(&s.mat, j);
    }
    fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        let mut s = self.scratch.borrow_mut();
        self.inner.leading_jacobian(t, y, z, &mut s.mat);
        self.combine_mat(&s.mat, j);
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

/// Which selector a projected formulation runs with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SelectorKind {
    /// Derived symbolically (`S(q)`, see [`crate::formulation`]).
    Symbolic,
    /// Computed at run time ([`NumericSelector`]).
    Numerical,
}

impl SelectorKind {
    /// `"symbolic"` or `"numerical"`.
    pub fn as_str(self) -> &'static str {
        match self {
            SelectorKind::Symbolic => "symbolic",
            SelectorKind::Numerical => "numerical",
        }
    }
}

/// Formulation `name` of `model`: the model's own, or — for `psi1`/`psi0`
/// when the model has no symbolic selector for them (a time-dependent
/// constraint, too many constraints) or when `numerical` is asked — the
/// projection of its `ovd1`/`ovd0` by a [`NumericSelector`], its structure
/// probed at `(t0, y0)`. The selector's kind is `None` for the other
/// formulations.
pub fn formulation(
    model: &dyn crate::system::Model,
    name: &str,
    numerical: bool,
    t0: f64,
    y0: &[f64],
) -> Result<(crate::system::BoxedSystem, Option<SelectorKind>), crate::system::FormulationError> {
    let which = match name {
        "psi1" => Some(Projected::Psi1),
        "psi0" => Some(Projected::Psi0),
        _ => None,
    };
    let own = model.formulation(name);
    let Some(which) = which else {
        return own.map(|s| (s, None));
    };
    match own {
        Ok(sys) if !numerical => return Ok((sys, Some(SelectorKind::Symbolic))),
        Err(e @ crate::system::FormulationError::Unknown { .. }) => return Err(e),
        _ => {}
    }
    let not_provided = || crate::system::FormulationError::NotProvided {
        model: model.model_info().name.clone(),
        name: name.to_string(),
        available: model.model_info().formulations.join(", "),
    };
    let inner = model
        .formulation(which.source())
        .map_err(|_| not_provided())?;
    let mut y = y0.to_vec();
    y.resize(inner.info().unknowns(), 0.0);
    let sys = NumericSelector::new(inner, which, t0, &y).map_err(|e| {
        crate::system::FormulationError::NoSelector {
            model: model.model_info().name.clone(),
            name: name.to_string(),
            reason: e.to_string(),
            available: model.model_info().formulations.join(", "),
        }
    })?;
    Ok((Box::new(sys), Some(SelectorKind::Numerical)))
}

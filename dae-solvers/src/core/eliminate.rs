//! Constraint rows that carry derivatives, made algebraic at run time.
//!
//! A model written with a mass matrix, `M(q) v' = f − G(q)ᵀλ`, cannot have
//! `v'` substituted into the acceleration level of its constraints without
//! inverting `M`, which the derivation never does symbolically. Its rcd0
//! and ovd0 therefore carry rows `G(q) v' + ∂(G v)/∂q v = 0`: constraint
//! rows with a non-zero row of `E`. The multipliers are then fixed by a
//! combination of those rows and the dynamics rows whose coefficients
//! depend on `q`, and a simplified Newton iteration that freezes `E` at the
//! start of the step stops contracting once the step has grown a little:
//! radau5(rcd0) on Andrews' squeezer in natural form rejected 894 of 1 774
//! attempts at tol 1e-4, 891 of them for the Newton iteration.
//!
//! [`Eliminated`] presents the same formulation with those rows replaced by
//! `row − L(y)·(dynamics rows)`, `L = E_C E_D⁻¹` (`E_C` the constraint rows'
//! part of `E`, `E_D` the square part of the dynamics rows): the new rows
//! have a zero row of `E` identically in `y`, and vanish exactly where the
//! old ones and the dynamics rows do, so the solutions are the same. They
//! are the algebraic rows `G M⁻¹(f − Gᵀλ) + ∂(G v)/∂q v = 0` of a
//! semi-explicit index-1 system, computed numerically.
//!
//! Jacobians: the solvers form `∂f/∂y − ∂(E z)/∂y` with `z ≈ y'`. For a
//! transformed row that is `(J_C − L J_D) − (Λ_C − L Λ_D)` with `Λ =
//! ∂(E z)/∂y`, and `Λ_C − L Λ_D = (∂L/∂y)(E_D z)` by differentiating
//! `E_C = L E_D`: the term `(∂L/∂y) f_D` of the exact Jacobian of
//! `f_C − L f_D`, at `E_D z = f_D`. So [`Eliminated`] passes on `J_C − L J_D`
//! as the right-hand side's Jacobian and `Λ_C − L Λ_D` as the leading
//! matrix's, and reports the inner system's `constant_leading` (false: the
//! rows had a state-dependent `E`).
//!
//! **A constant mass matrix.** When only the constraint rows' part of `E`
//! depends on `y` (`constant_differential_leading`: the cart pendulum's
//! `M` is constant, its acceleration row is not), the eliminated `E` is
//! constant. [`Eliminated::constant`] presents it so to the methods that
//! need a constant `E` (mebdf, idec): `constant_leading` set, a zero
//! leading-matrix Jacobian, and the `(∂L/∂y) f_D` term moved into the
//! right-hand side's Jacobian, which is then exact. There every constraint
//! row is transformed, not only those with a non-zero row of `E` at the
//! start (a row whose `E_C` vanishes there has a zero row of `L` there), so
//! that `E` stays constant wherever the solution goes.

use crate::linalg::{DenseLu, Pivoting};
use crate::{NotApplicable, Problem, SolveError};
use dae_core::system::{DaeSystem, FormulationInfo, RowKind};
use nalgebra::DMatrix;
use std::cell::RefCell;
use std::ops::Deref;
use std::rc::Rc;

/// A formulation whose constraint rows with a non-zero row of `E` have been
/// made algebraic (see the [module documentation](self)).
pub(crate) struct Eliminated<'a> {
    inner: &'a dyn DaeSystem,
    /// The dynamics rows (`RowKind::Differential`).
    dyn_rows: Vec<usize>,
    /// The columns of `E` the dynamics rows occupy (as many as rows).
    dyn_cols: Vec<usize>,
    /// The constraint rows with a non-zero row of `E`.
    rows: Vec<usize>,
    work: RefCell<Work>,
    /// The constant-`E` presentation ([`Eliminated::constant`]): the inner
    /// information with `constant_leading` set.
    constant: Option<FormulationInfo>,
}

struct Work {
    /// `E(t, y)` of the inner system.
    e: DMatrix<f64>,
    /// `E_Dᵀ` factored (once in the constant presentation, where `E_D` is
    /// constant; at every evaluation otherwise).
    lu: DenseLu,
    /// `L`, one row per transformed row (`rows.len() × dyn_rows.len()`).
    l: DMatrix<f64>,
    /// Scratch of length `dyn_rows.len()`.
    col: Vec<f64>,
    /// The constant presentation's scratch (empty otherwise): `f` (length
    /// M), `z` with `E_D z = f_D` (length N) and `∂(E z)/∂y` (M × N).
    f: Vec<f64>,
    z: Vec<f64>,
    lam: DMatrix<f64>,
}

impl<'a> Eliminated<'a> {
    /// The adapter for `inner` at the consistent start `(t0, y0)`, or
    /// `None` when there is nothing to eliminate or the structure does not
    /// allow it (constraint rows with `E` outside the dynamics' columns, or
    /// a singular `E_D` at the start).
    pub(crate) fn new(inner: &'a dyn DaeSystem, t0: f64, y0: &[f64]) -> Option<Self> {
        Self::build(inner, t0, y0, false)
    }

    /// The constant-`E` presentation of `inner` at `y0` (see the [module
    /// documentation](self)), or `None` when its differential rows' `E`
    /// depends on `y` or `t`, or as for [`Eliminated::new`].
    pub(crate) fn constant(inner: &'a dyn DaeSystem, t0: f64, y0: &[f64]) -> Option<Self> {
        if !inner.info().constant_differential_leading {
            return None;
        }
        Self::build(inner, t0, y0, true)
    }

    fn build(inner: &'a dyn DaeSystem, t0: f64, y0: &[f64], constant: bool) -> Option<Self> {
        let info: &FormulationInfo = inner.info();
        if info.constant_leading {
            return None;
        }
        let (m, n) = (info.equations(), info.unknowns());
        let mut e = DMatrix::zeros(m, n);
        inner.leading(t0, y0, &mut e);
        let nonzero_row = |e: &DMatrix<f64>, i: usize| (0..n).any(|j| e[(i, j)] != 0.0);
        let rows: Vec<usize> = (0..m)
            .filter(|&i| matches!(info.rows[i].kind, RowKind::Constraint { .. }))
            .filter(|&i| constant || nonzero_row(&e, i))
            .collect();
        if rows.is_empty() {
            return None;
        }
        let dyn_rows: Vec<usize> = (0..m)
            .filter(|&i| matches!(info.rows[i].kind, RowKind::Differential))
            .collect();
        let dyn_cols: Vec<usize> = (0..n)
            .filter(|&j| dyn_rows.iter().any(|&i| e[(i, j)] != 0.0))
            .collect();
        if dyn_cols.len() != dyn_rows.len()
            || rows
                .iter()
                .any(|&i| (0..n).any(|j| e[(i, j)] != 0.0 && !dyn_cols.contains(&j)))
        {
            return None;
        }
        let k = dyn_rows.len();
        let adapter = Eliminated {
            inner,
            work: RefCell::new(Work {
                e,
                lu: DenseLu::new(k, Pivoting::Checked),
                l: DMatrix::zeros(rows.len(), k),
                col: vec![0.0; k],
                f: vec![0.0; if constant { m } else { 0 }],
                z: vec![0.0; if constant { n } else { 0 }],
                lam: if constant {
                    DMatrix::zeros(m, n)
                } else {
                    DMatrix::zeros(0, 0)
                },
            }),
            dyn_rows,
            dyn_cols,
            rows,
            constant: constant.then(|| FormulationInfo {
                constant_leading: true,
                ..info.clone()
            }),
        };
        // The constant presentation factors `E_D` here, once.
        if constant && !adapter.factor_e_d() {
            return None;
        }
        adapter.update(t0, y0).then_some(adapter)
    }

    /// `E(t, y)` and the factors of `E_Dᵀ` (kept from the start in the
    /// constant presentation); false if `E_D` is singular.
    fn factor(&self, t: f64, y: &[f64]) -> bool {
        self.inner.leading(t, y, &mut self.work.borrow_mut().e);
        self.constant.is_some() || self.factor_e_d()
    }

    /// Factor `E_Dᵀ` from the `E` in the work space: `Lᵀ` solves
    /// `E_Dᵀ Lᵀ = E_Cᵀ`, and `E_D x = b` is its transposed solve.
    fn factor_e_d(&self) -> bool {
        let w = &mut *self.work.borrow_mut();
        let (dr, dc) = (&self.dyn_rows, &self.dyn_cols);
        w.lu.factor_from(|i, j| w.e[(dr[j], dc[i])]).is_ok()
    }

    /// `L(t, y) = E_C E_D⁻¹`; false if `E_D` is singular.
    fn update(&self, t: f64, y: &[f64]) -> bool {
        if !self.factor(t, y) {
            return false;
        }
        let w = &mut *self.work.borrow_mut();
        let dc = &self.dyn_cols;
        for (r, &i) in self.rows.iter().enumerate() {
            for (c, &j) in dc.iter().enumerate() {
                w.col[c] = w.e[(i, j)];
            }
            w.lu.solve(&mut w.col);
            for c in 0..self.dyn_rows.len() {
                w.l[(r, c)] = w.col[c];
            }
        }
        true
    }

    /// `v[rows] −= L(t, y) v[dyn_rows]`, as `E_C (E_D⁻¹ v[dyn_rows])`: one
    /// solve instead of one per row of `L`. NaN everywhere if `E_D(t, y)`
    /// is singular (the solvers then retry with a smaller step).
    fn transform(&self, t: f64, y: &[f64], v: &mut [f64]) {
        if !self.factor(t, y) {
            v.fill(f64::NAN);
            return;
        }
        let w = &mut *self.work.borrow_mut();
        let (dr, dc) = (&self.dyn_rows, &self.dyn_cols);
        for (c, &d) in dr.iter().enumerate() {
            w.col[c] = v[d];
        }
        w.lu.solve_transposed(&mut w.col);
        for &i in &self.rows {
            let s: f64 = dc.iter().zip(&w.col).map(|(&j, x)| w.e[(i, j)] * x).sum();
            v[i] -= s;
        }
    }

    /// The same for the rows of an `M × N` matrix.
    fn transform_rows(&self, t: f64, y: &[f64], a: &mut DMatrix<f64>) {
        if self.update(t, y) {
            self.combine_rows(a);
        } else {
            a.fill(f64::NAN);
        }
    }

    /// `j −= ∂(E z)/∂y` with `E_D z = f_D` at `(t, y)`: after the rows are
    /// combined, the `(∂L/∂y) f_D` term of the new rows' Jacobian (the
    /// dynamics rows' part of `∂(E z)/∂y` is zero, their `E` constant).
    fn subtract_leading_term(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let w = &mut *self.work.borrow_mut();
        self.inner.rhs(t, y, &mut w.f);
        let (dr, dc) = (&self.dyn_rows, &self.dyn_cols);
        for (c, &i) in dr.iter().enumerate() {
            w.col[c] = w.f[i];
        }
        w.lu.solve_transposed(&mut w.col);
        w.z.fill(0.0);
        for (c, &k) in dc.iter().enumerate() {
            w.z[k] = w.col[c];
        }
        self.inner.leading_jacobian(t, y, &w.z, &mut w.lam);
        *j -= &w.lam;
    }

    /// `a[rows, :] −= L a[dyn_rows, :]` for an `M × N` matrix.
    fn combine_rows(&self, a: &mut DMatrix<f64>) {
        let w = self.work.borrow();
        for j in 0..a.ncols() {
            for (r, &i) in self.rows.iter().enumerate() {
                let s: f64 = self
                    .dyn_rows
                    .iter()
                    .enumerate()
                    .map(|(c, &d)| w.l[(r, c)] * a[(d, j)])
                    .sum();
                a[(i, j)] -= s;
            }
        }
    }
}

impl DaeSystem for Eliminated<'_> {
    fn info(&self) -> &FormulationInfo {
        self.constant.as_ref().unwrap_or_else(|| self.inner.info())
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.inner.parameter_values()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        self.inner.rhs(t, y, f);
        self.transform(t, y, f);
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        self.inner.residual(t, y, yp, r);
        self.transform(t, y, r);
    }
    fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>) {
        self.inner.leading(t, y, e);
        for &i in &self.rows {
            for j in 0..e.ncols() {
                e[(i, j)] = 0.0;
            }
        }
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.inner.rhs_jacobian(t, y, j);
        if self.constant.is_some() {
            self.subtract_leading_term(t, y, j);
        }
        self.transform_rows(t, y, j);
    }
    fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        if self.constant.is_some() {
            j.fill(0.0);
            return;
        }
        self.inner.leading_jacobian(t, y, z, j);
        self.transform_rows(t, y, j);
    }
    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.inner.constraints(t, y, g);
    }
    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.inner.constraints_jacobian(t, y, j);
    }
    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.inner.invariants(t, y, out);
    }
    fn event_names(&self) -> &[String] {
        self.inner.event_names()
    }
    fn events(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.inner.events(t, y, out)
    }
}

/// The formulation an integrator runs on: the caller's, or an
/// [`Eliminated`] presentation of it that the integration owns (shared by
/// the runs of one integration, e.g. a start-up run and the run it feeds).
#[derive(Clone)]
pub(crate) enum Formulation<'a> {
    /// The caller's formulation.
    Given(&'a dyn DaeSystem),
    /// Its derivative-carrying constraint rows made algebraic.
    Eliminated(Rc<Eliminated<'a>>),
}

impl<'a> Deref for Formulation<'a> {
    type Target = dyn DaeSystem + 'a;
    fn deref(&self) -> &Self::Target {
        match self {
            Formulation::Given(sys) => *sys,
            Formulation::Eliminated(e) => &**e,
        }
    }
}

/// `problem`'s formulation with its derivative-carrying constraint rows
/// made algebraic ([`Eliminated`]), or itself when there are none.
pub(crate) fn algebraic_rows<'a>(problem: &Problem<'a>) -> Formulation<'a> {
    match Eliminated::new(problem.system, problem.t0, problem.y0) {
        Some(e) => Formulation::Eliminated(Rc::new(e)),
        None => Formulation::Given(problem.system),
    }
}

/// `problem`'s formulation with a constant `E`: itself when its `E` is
/// constant, else its constant presentation ([`Eliminated::constant`]);
/// [`NotApplicable::LeadingMatrixNotConstant`] when it has none.
pub(crate) fn constant_leading<'a>(problem: &Problem<'a>) -> Result<Formulation<'a>, SolveError> {
    if problem.system.info().constant_leading {
        return Ok(Formulation::Given(problem.system));
    }
    match Eliminated::constant(problem.system, problem.t0, problem.y0) {
        Some(e) => Ok(Formulation::Eliminated(Rc::new(e))),
        None => Err(NotApplicable::LeadingMatrixNotConstant.into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::init::{consistent, InitOptions};
    use dae_core::interp::InterpretedModel;

    /// The cart pendulum (constant coupled mass matrix; its acceleration row
    /// keeps `2u·der(vu)`) in rcd0 and ovd0, at its consistent start and at
    /// a point off it.
    fn cart(name: &str) -> (dae_core::interp::InterpretedSystem, Vec<Vec<f64>>) {
        let model = InterpretedModel::from_str(include_str!("../../../scenes/cart_pendulum.dae"))
            .expect("the cart pendulum derives");
        let sys = model.system(name).expect("formulation");
        let guess = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let y0 = consistent(&sys, 0.0, &guess, &InitOptions::default())
            .expect("consistent start")
            .y;
        let off = vec![0.1, 0.6, -0.7, 0.4, -1.3, 0.8, 2.5];
        (sys, vec![y0, off])
    }

    #[test]
    fn transformed_rows_have_no_derivative_and_the_same_zeros() {
        for name in ["rcd0", "ovd0"] {
            let (sys, points) = cart(name);
            let el = Eliminated::new(&sys, 0.0, &points[0]).expect("rows to eliminate");
            assert!(!el.rows.is_empty());
            let (m, n) = (sys.info().equations(), sys.info().unknowns());
            for y in &points {
                let mut e = DMatrix::zeros(m, n);
                el.leading(0.0, y, &mut e);
                for &i in &el.rows {
                    assert!((0..n).all(|j| e[(i, j)] == 0.0), "{name}: row {i} of E");
                }
                // r_new = r − L r_D: zero wherever the rows it combines are.
                let yp = [0.3, -0.2, 0.5, 1.1, -0.4, 0.7, 0.0];
                let (mut r, mut r_new) = (vec![0.0; m], vec![0.0; m]);
                sys.residual(0.0, y, &yp, &mut r);
                el.residual(0.0, y, &yp, &mut r_new);
                for i in (0..m).filter(|i| !el.rows.contains(i)) {
                    assert_eq!(r[i], r_new[i], "{name}: row {i} untouched");
                }
                // With E z = f on the dynamics rows the new rows are f_new.
                let mut f = vec![0.0; m];
                el.rhs(0.0, y, &mut f);
                for &i in &el.rows {
                    assert!(
                        (r_new[i] + f[i]).abs() <= 1e-12 * (1.0 + f[i].abs()),
                        "{name}"
                    );
                }
            }
        }
    }

    /// The iteration matrix the solvers form, `∂f/∂y − ∂(E z)/∂y`, is the
    /// Jacobian of the new right-hand side `f_C − L(y) f_D` when `E_D z = f_D`
    /// (the `(∂L/∂y) f_D` term comes through the leading matrix's part).
    #[test]
    fn iteration_matrix_is_the_jacobian_of_the_new_rows() {
        let (sys, points) = cart("rcd0");
        let el = Eliminated::new(&sys, 0.0, &points[0]).expect("rows to eliminate");
        let (m, n) = (sys.info().equations(), sys.info().unknowns());
        let y = &points[1];
        // z with E_D z = f_D: the dynamics rows solved for the derivative.
        let mut e = DMatrix::zeros(m, n);
        sys.leading(0.0, y, &mut e);
        let mut f = vec![0.0; m];
        sys.rhs(0.0, y, &mut f);
        let (dr, dc) = (&el.dyn_rows, &el.dyn_cols);
        let ed = DMatrix::from_fn(dr.len(), dc.len(), |i, j| e[(dr[i], dc[j])]);
        let fd = nalgebra::DVector::from_fn(dr.len(), |i, _| f[dr[i]]);
        let zd = ed.lu().solve(&fd).expect("E_D invertible");
        let mut z = vec![0.0; n];
        for (c, &j) in dc.iter().enumerate() {
            z[j] = zd[c];
        }
        let (mut jac, mut ljac) = (DMatrix::zeros(m, n), DMatrix::zeros(m, n));
        el.rhs_jacobian(0.0, y, &mut jac);
        el.leading_jacobian(0.0, y, &z, &mut ljac);
        let formed = &jac - &ljac;
        assert_jacobian_of_rhs(&el, y, &formed, &el.rows);
    }

    /// `jac`'s rows `rows` are the Jacobian of `sys`'s right-hand side at
    /// `y`, against central differences.
    fn assert_jacobian_of_rhs(sys: &dyn DaeSystem, y: &[f64], jac: &DMatrix<f64>, rows: &[usize]) {
        let m = sys.info().equations();
        for j in 0..y.len() {
            let d = 1e-6 * (1.0 + y[j].abs());
            let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
            yp[j] += d;
            ym[j] -= d;
            let (mut fp, mut fm) = (vec![0.0; m], vec![0.0; m]);
            sys.rhs(0.0, &yp, &mut fp);
            sys.rhs(0.0, &ym, &mut fm);
            for &i in rows {
                let fd = (fp[i] - fm[i]) / (2.0 * d);
                assert!(
                    (jac[(i, j)] - fd).abs() <= 1e-6 * (1.0 + fd.abs()),
                    "row {i}, column {j}: {} against {fd}",
                    jac[(i, j)]
                );
            }
        }
    }

    /// The constant presentation of the cart pendulum's rcd0 (its mass
    /// matrix is constant): `E` constant and equal at two points, a zero
    /// leading-matrix Jacobian, and the right-hand side's Jacobian the exact
    /// one of the new rows (every row, against central differences).
    #[test]
    fn a_constant_mass_matrix_gives_a_constant_e_and_the_exact_jacobian() {
        let (sys, points) = cart("rcd0");
        assert!(!sys.info().constant_leading && sys.info().constant_differential_leading);
        let el = Eliminated::constant(&sys, 0.0, &points[0]).expect("a constant presentation");
        assert!(el.info().constant_leading);
        let (m, n) = (sys.info().equations(), sys.info().unknowns());
        let (mut e0, mut e1) = (DMatrix::zeros(m, n), DMatrix::zeros(m, n));
        el.leading(0.0, &points[0], &mut e0);
        el.leading(1.0, &points[1], &mut e1);
        assert_eq!(e0, e1);
        let y = &points[1];
        let mut lj = DMatrix::from_element(m, n, 1.0);
        el.leading_jacobian(0.0, y, &[0.3; 7], &mut lj);
        assert!(lj.iter().all(|&v| v == 0.0));
        let mut jac = DMatrix::zeros(m, n);
        el.rhs_jacobian(0.0, y, &mut jac);
        assert_jacobian_of_rhs(&el, y, &jac, &(0..m).collect::<Vec<_>>());
        // A state-dependent mass matrix has none.
        let model = InterpretedModel::from_str(include_str!("../../../scenes/andrews_natural.dae"))
            .expect("the squeezer derives");
        let rcd0 = model.system("rcd0").expect("rcd0");
        assert!(!rcd0.info().constant_differential_leading);
        assert!(Eliminated::constant(&rcd0, 0.0, &vec![0.0; rcd0.info().unknowns()]).is_none());
    }
}

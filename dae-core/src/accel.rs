//! The constraint chain of a model with a mass matrix.
//!
//! For `M(q) v' = f(t, q, v, λ)` the acceleration-level member of the chain
//! holds der() (`G(q) v' + g_qq(v, v) = 0`): the accelerations `M⁻¹ f` are
//! never formed symbolically. [`DaeSystem::constraints`](crate::system::DaeSystem::constraints)
//! must still be a function of `(t, y)` alone — consistent initialisation
//! solves its top level for the multipliers, reports evaluate its drift — so
//! the accelerations are eliminated here, numerically:
//!
//! ```text
//!     a   = E_d(t, y)⁻¹ f_d(t, y)                     (the model's dynamic rows)
//!     g   = L(t, y, a)                              (the chain, der() → a)
//!     ∂g/∂y = ∂L/∂y + ∂L/∂a · E_d⁻¹ (∂f_d/∂y − ∂(E_d a)/∂y)
//! ```
//!
//! `E_d` is square (one dynamic row per differential unknown) and, for a
//! model that passed the structural check, nonsingular wherever `M` is; a
//! singular `E_d` at some point gives NaN values for the solver to report.
//! Unlike the rest of [`DaeSystem`](crate::system::DaeSystem) these two
//! evaluations allocate (a few vectors and one LU of size `n_diff`): they
//! serve initialisation and reports, not the step loop.

use nalgebra::{DMatrix, DVector};

/// What the elimination needs from a formulation of a model with a mass
/// matrix. Implemented by the `dae!` macro's generated systems and by the
/// interpreter; not meant to be implemented by hand.
pub trait AccelParts {
    /// Number of differential unknowns `n_d` (the first `n_d` of `y`).
    fn accel_dim(&self) -> usize;
    /// `E_d(t, y)` (n_d × n_d): the model's dynamic rows' der() coefficients.
    fn accel_leading(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>);
    /// `f_d(t, y)` (length n_d): the model's dynamic rows' right-hand sides.
    fn accel_rhs(&self, t: f64, y: &[f64], out: &mut [f64]);
    /// `∂f_d/∂y` (n_d × N).
    fn accel_rhs_jacobian(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>);
    /// `∂(E_d(t, y) z)/∂y` (n_d × N).
    fn accel_leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], out: &mut DMatrix<f64>);
    /// The chain `L(t, y, y')` with der() read from `yp` (length K).
    fn chain_at(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]);
    /// `∂L/∂y` at fixed `y'` (K × N).
    fn chain_jacobian_at(&self, t: f64, y: &[f64], yp: &[f64], out: &mut DMatrix<f64>);
    /// `∂L/∂y'` restricted to the differential unknowns (K × n_d); `L` is
    /// linear in der(), so this does not depend on `y'`.
    fn chain_der(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>);
}

/// `y'` of the differential unknowns from the dynamic rows, padded with
/// zeros to length `N`, and the factorisation used; `None` if `E_d` is
/// singular or the values are not finite.
fn accelerations<S: AccelParts + ?Sized>(
    s: &S,
    t: f64,
    y: &[f64],
) -> Option<(Vec<f64>, nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>)> {
    let nd = s.accel_dim();
    let mut e = DMatrix::zeros(nd, nd);
    s.accel_leading(t, y, &mut e);
    let mut f = vec![0.0; nd];
    s.accel_rhs(t, y, &mut f);
    let lu = e.lu();
    let a = lu.solve(&DVector::from_vec(f))?;
    if !a.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mut yp = vec![0.0; y.len()];
    yp[..nd].copy_from_slice(a.as_slice());
    Some((yp, lu))
}

/// The chain `g(t, y)` with the accelerations eliminated (NaN where `E_d`
/// is singular).
pub fn constraints<S: AccelParts + ?Sized>(s: &S, t: f64, y: &[f64], g: &mut [f64]) {
    match accelerations(s, t, y) {
        Some((yp, _)) => s.chain_at(t, y, &yp, g),
        None => g.fill(f64::NAN),
    }
}

/// `∂g/∂y` of [`constraints`] (K × N; NaN where `E_d` is singular).
pub fn constraints_jacobian<S: AccelParts + ?Sized>(
    s: &S,
    t: f64,
    y: &[f64],
    j: &mut DMatrix<f64>,
) {
    let Some((yp, lu)) = accelerations(s, t, y) else {
        j.fill(f64::NAN);
        return;
    };
    let (nd, n, k) = (s.accel_dim(), y.len(), j.nrows());
    s.chain_jacobian_at(t, y, &yp, j);
    let mut fy = DMatrix::zeros(nd, n);
    s.accel_rhs_jacobian(t, y, &mut fy);
    let mut ez = DMatrix::zeros(nd, n);
    s.accel_leading_jacobian(t, y, &yp, &mut ez);
    fy -= ez;
    // ∂a/∂y = E_d⁻¹ (∂f_d/∂y − ∂(E_d a)/∂y).
    if !lu.solve_mut(&mut fy) {
        j.fill(f64::NAN);
        return;
    }
    let mut c = DMatrix::zeros(k, nd);
    s.chain_der(t, y, &mut c);
    j.gemm(1.0, &c, &fy, 1.0);
}

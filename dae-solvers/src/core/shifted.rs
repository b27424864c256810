//! The iteration matrix `a E − b J` of a method on a constant leading
//! matrix `E` (`J = ∂f/∂y`, dense): MEBDF's `E/(hβ) − J` (`a = 1/(hβ)`,
//! `b = 1`) and IDeC's `E − hJ` (`a = 1`, `b = h`). `E` is evaluated once;
//! the Jacobian when the family says so, counted and checked; the matrix
//! is formed, checked, counted and factored only when `J`, `a` or `b` has
//! changed since the last factorisation (the same `a`, `b` and `J` are
//! the same matrix, bit for bit).

use super::control::Failure;
use super::matrix::{Corrector, Rows, SquareLu};
use crate::linalg::all_finite;
use crate::{SolveError, Stats};
use dae_core::system::DaeSystem;
use nalgebra::DMatrix;

/// `E`, `J` and the factorisation of `a E − b J` (see the
/// [module documentation](self)).
pub(crate) struct Shifted {
    /// The constant leading matrix `E`.
    pub(crate) lead: DMatrix<f64>,
    /// The Jacobian `J = ∂f/∂y` of the last [`Shifted::jacobian`].
    pub(crate) jac: DMatrix<f64>,
    /// `a E − b J`, factored.
    lu: SquareLu,
    /// `(a, b)` of the factored matrix (none before the first, after a
    /// new `J` or a failed factorisation).
    factored: Option<(f64, f64)>,
}

impl Shifted {
    /// Storage for `n` unknowns; `E` is set by the caller
    /// ([`Shifted::lead`]).
    pub(crate) fn new(n: usize) -> Self {
        Shifted {
            lead: DMatrix::zeros(n, n),
            jac: DMatrix::zeros(n, n),
            lu: SquareLu::new(n, n),
            factored: None,
        }
    }

    /// `E` at `(t, y)`, once (it is constant); a non-finite entry is
    /// [`SolveError::NonFinite`] naming the leading matrix.
    pub(crate) fn leading(
        &mut self,
        sys: &dyn DaeSystem,
        t: f64,
        y: &[f64],
    ) -> Result<(), SolveError> {
        sys.leading(t, y, &mut self.lead);
        if !all_finite(self.lead.as_slice()) {
            return Err(SolveError::NonFinite {
                t,
                what: "leading matrix",
            });
        }
        Ok(())
    }

    /// [`Shifted::jacobian`], a non-finite entry the failure naming the
    /// Jacobian.
    pub(crate) fn checked_jacobian(
        &mut self,
        sys: &dyn DaeSystem,
        stats: &mut Stats,
        t: f64,
        y: &[f64],
    ) -> Result<(), Failure> {
        if self.jacobian(sys, stats, t, y) {
            Ok(())
        } else {
            Err(Failure::NonFinite("Jacobian"))
        }
    }

    /// `J = ∂f/∂y` at `(t, y)`, counted; the factorisation is then due.
    /// Whether every entry is finite.
    pub(crate) fn jacobian(
        &mut self,
        sys: &dyn DaeSystem,
        stats: &mut Stats,
        t: f64,
        y: &[f64],
    ) -> bool {
        sys.rhs_jacobian(t, y, &mut self.jac);
        stats.jacobian_evals += 1;
        self.factored = None;
        all_finite(self.jac.as_slice())
    }

    /// Factor `a E − b J` unless it is the factored matrix; `true` when it
    /// was factored now (counted). A non-finite entry is
    /// [`Failure::NonFinite`] naming the iteration matrix, a singular
    /// matrix [`Failure::Singular`].
    pub(crate) fn factor(&mut self, a: f64, b: f64, stats: &mut Stats) -> Result<bool, Failure> {
        if self.factored == Some((a, b)) {
            return Ok(false);
        }
        self.factored = None;
        let m = self.lu.matrix_mut().as_mut_slice();
        for ((g, e), j) in m
            .iter_mut()
            .zip(self.lead.as_slice())
            .zip(self.jac.as_slice())
        {
            *g = a * e - b * j;
        }
        if !all_finite(m) {
            return Err(Failure::NonFinite("iteration matrix"));
        }
        stats.factorizations += 1;
        self.lu
            .factor(&Rows::square())
            .map_err(|_| Failure::Singular)?;
        self.factored = Some((a, b));
        Ok(true)
    }

    /// `(a, b)` of the factored matrix, if one is factored.
    pub(crate) fn factored(&self) -> Option<(f64, f64)> {
        self.factored
    }

    /// `x ← (a E − b J)⁻¹ x` with the factored matrix.
    pub(crate) fn solve(&mut self, x: &mut [f64]) {
        self.lu.solve(x)
    }
}

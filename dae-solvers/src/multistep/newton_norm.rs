//! The Newton norm of a corrector whose error test leaves unknowns out
//! that its convergence test must keep (DASPK's `INFO(16)`: the index-2
//! unknowns are zeroed in the error test's weights `VT`, and the corrector
//! is measured with every weight, `WT`).
//!
//! An index-2 unknown's iteration error is not seen in the other
//! components: on a linear index-2 circuit (`scenes/mna_cv_loop.dae`,
//! `ori2`) with the source current out of the Newton norm too, iterations
//! that converged in the node potentials left the current with errors up to
//! 3e-2 at tol 1e-6 (EXTREMES.md "ix2bdf13"). Kept at its full weight, the
//! round-off its rows carry into an index-2 unknown grows like `ε/h`: on
//! S02 at tol 1e-12 (pendulum, `rcd1` and `ggl1`) the full-weight test alone
//! failed near t ≈ 1 200, the step collapsing to 3e-12. So an update at the
//! round-off floor of the index-scaled norm (an index-`k` unknown weighted
//! by `h^(k−1)`, Hairer & Wanner VII.8) also counts as converged.

use crate::core::weights::{index_powers, Weights};
use crate::options::Tolerances;
use dae_core::system::FormulationInfo;

/// The Newton norm where it differs from the error test's (see the
/// [module documentation](self)).
pub(crate) struct NewtonNorm {
    /// Weights of every unknown in the Newton norm, unscaled.
    full: Weights,
    /// The same scaled by `h^(k−1)` for an unknown of index `k`.
    scaled: Weights,
    /// `100 ε ‖y⁽⁰⁾‖` in the scaled norm: an update below it (scaled) is
    /// round-off.
    floor: f64,
}

impl NewtonNorm {
    /// The Newton norm over the unknowns `in_newton` of a corrector whose
    /// error test holds `in_test`; `None` where the two are the same (the
    /// error test's weights are then the Newton norm's).
    pub(crate) fn of(
        tol: &Tolerances,
        info: &FormulationInfo,
        in_test: &[bool],
        in_newton: &[bool],
    ) -> Option<Self> {
        let weights = |powers| Weights::new(tol, |_| 1.0, in_newton.to_vec(), powers);
        (in_newton != in_test).then(|| NewtonNorm {
            full: weights(vec![0; in_newton.len()]),
            scaled: weights(index_powers(info)),
            floor: 0.0,
        })
    }

    /// At every attempt, from the step point `y_n` and the step `h` (the
    /// scaled weights follow `h`): the weights of `y_n`, as the error
    /// test's, the round-off floor of the prediction `predicted`, and the
    /// prediction's norm.
    pub(crate) fn start(&mut self, y_n: &[f64], h: f64, predicted: &[f64]) -> f64 {
        self.full.update(y_n);
        self.scaled.update_scaled(y_n, h);
        self.floor = 100.0 * f64::EPSILON * self.scaled.norm(predicted);
        self.full.norm(predicted)
    }

    /// The norm of a Newton update; zero (below any bound of the
    /// convergence test) at the round-off floor of the scaled norm.
    pub(crate) fn norm(&self, delta: &[f64]) -> f64 {
        let norm = self.full.norm(delta);
        if norm > 0.0 && self.scaled.norm(delta) <= self.floor {
            0.0
        } else {
            norm
        }
    }
}

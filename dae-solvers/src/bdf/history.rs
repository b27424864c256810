//! The step's history and coefficients: the engine's modified divided
//! differences ([`Divided`](crate::multistep::divided::Divided)) started
//! and rescaled for the step, and the corrector's leading coefficient
//! `c_J`, error constant `C_k` and whether the iteration matrix is still
//! good for it (DDASTP's block 1).

use super::step::Integrator;
use crate::core::matrix::{Corrector, JacState};
use crate::multistep::UNKNOWN_RATE;

/// Re-evaluate the iteration matrix when `c_J/c_J^old` leaves
/// `[(1−XRATE)/(1+XRATE), (1+XRATE)/(1−XRATE)]`.
const XRATE: f64 = 0.25;

impl<L: Corrector> Integrator<'_, L> {
    /// Start at `(t0, y0, y'0)` with order one and step `h`.
    pub(super) fn start(&mut self, t0: f64, y0: &[f64], yp0: &[f64], h: f64) {
        self.ms.ramp = !self.ms.cfg.fixed_step;
        self.k = 1;
        self.hist.start(y0, yp0, h);
        self.restart_at(t0, h);
    }

    /// Start a constant-step run of order `k = values.len()` at `t` from the
    /// values at `t − (k−1)h, …, t` (oldest first): the classical BDF-`k`.
    pub(super) fn start_from_history(&mut self, t: f64, values: &[&[f64]], h: f64) {
        self.ms.ramp = false;
        self.k = values.len();
        self.hist.start_from_values(values, h);
        self.restart_at(t, h);
    }

    /// The step point `t` and step `h` of a start: `c_J = 1/h`, the rate
    /// unknown, the iteration matrix due.
    fn restart_at(&mut self, t: f64, h: f64) {
        self.ms.t = t;
        self.ms.h = h;
        self.cj = 1.0 / h;
        self.cjold = self.cj;
        self.ms.rate = UNKNOWN_RATE;
        self.ms.jac = JacState::Needed;
    }

    /// Block 1: the history's coefficients for the step and `φ → φ*`;
    /// `c_J = −α_s/h`, `C_k = max(|α_{k+1} + α_s − α⁰|, α_{k+1})`, and a
    /// new iteration matrix when `c_J` has moved too far.
    #[inline(always)]
    pub(super) fn set_coefficients(&mut self) {
        let k = self.k;
        let h = self.ms.h;
        let (alphas, alpha0) = self.hist.set_coefficients(h, k);
        let cjlast = self.cj;
        self.cj = -alphas / h;
        let alpha = self.hist.alpha[k];
        self.ck = (alpha + alphas - alpha0).abs().max(alpha);
        let ratio = self.cj / self.cjold;
        let lo = (1.0 - XRATE) / (1.0 + XRATE);
        if !(lo..=1.0 / lo).contains(&ratio) {
            self.ms.jac = JacState::Needed;
        }
        if self.cj != cjlast {
            self.ms.rate = UNKNOWN_RATE;
        }
    }

    /// Block 2: the predictor `y⁽⁰⁾`, `y'⁽⁰⁾` into the iterate.
    pub(super) fn predict(&mut self) {
        self.hist.predict(self.k, &mut self.y, &mut self.yp);
    }
}

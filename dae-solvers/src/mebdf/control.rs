//! The error estimate and the choice of the next order and step, in the
//! manner of Cash's MEBDF code (itself after Gear's and Hindmarsh's codes).
//!
//! *Error estimate*: the local error of the order-`p` step is
//! `|C_p| ‖y_{n+1} − P_p(t_{n+1})‖`, the predictor `P_p` being the polynomial
//! of degree `p` through `y_n, …, y_{n−p}`: the difference is
//! `∇^(p+1) y_{n+1} ≈ h^(p+1) y^(p+1)`, `C_p` the error constant of the
//! formula ([`super::coeffs`]). The same with `p ∓ 1` estimates the errors
//! the neighbouring orders would have made. The norm is the root mean
//! square over the unknowns of index at most one and the differential ones
//! of index two; the algebraic index-2 unknowns and every index-3 unknown
//! are left out (`core::policy::index_scaled_error_test` and the module
//! documentation of [`super`] give the measurements).
//!
//! *Step and order*: after `p + 1` steps at the same order and step size,
//! the ratios `r_q = 1/(c_q est_q^(1/(q+1)) + 10⁻⁶)` of orders
//! `q = p − 1, p, p + 1` (biases `c = 1.3, 1.2, 1.4` favouring the current
//! order) are compared and the largest wins; before, the step is kept. A
//! ratio below 1.1 at the same order keeps the step; increases are at most
//! ×10 until the first rejection, ×2 after; decreases at least ×0.2. After a
//! rejected error test: `r_p` clamped to `[0.1, 0.9]`, or the lower order if
//! it promises a larger step; from the third failure on one step, order one
//! and `r = 1/4` (the engine's fall-back, `multistep::Common::fall_back`).

use super::coeffs::MAX_ORDER;
use super::step::Integrator;
use crate::core::control;
use crate::multistep::propagate;

/// Step ratio `1/(bias · est^(1/(q+1)) + 10⁻⁶ bias)` for an error `est` at
/// order `q`.
fn ratio(est: f64, q: usize, bias: f64) -> f64 {
    1.0 / (bias * est.powf(1.0 / (q + 1) as f64) + 1e-6 * bias)
}

impl Integrator<'_> {
    /// The stage whose value is the solution of the current attempt.
    pub(super) fn solution(&self) -> usize {
        if self.p == 1 {
            0
        } else {
            2
        }
    }

    /// `|C_q| ‖y_{n+1} − P_q(t_{n+1})‖` for the current attempt (at `q = p`
    /// its error norm, accepted when at most one), the family's norm or
    /// the propagated one ([`crate::multistep::propagate`]: carried through
    /// `E/(hβ) − J` as factored, the left-out unknowns zeroed in it too);
    /// `q = p` is the error test, where [`Estimate::Checked`] checks at
    /// the first test after a new Jacobian *or a rejected step* (the key
    /// counts both): MEBDF keeps `J` over many steps, and on the test
    /// suite's `amplified_circle` at 1e-7 a check at new Jacobians alone
    /// came after 9 000 error tests of the accept-`h`/reject-`2h` cycle
    /// (6 335 steps, `|z|` 2.0e-3), with rejections after 4 (191 steps,
    /// 1.7e-6).
    ///
    /// [`Estimate::Checked`]: crate::options::Estimate::Checked
    pub(super) fn estimate_at(&mut self, q: usize) -> f64 {
        let mut d = std::mem::take(&mut self.delta);
        self.hist
            .difference_to(&self.stage[self.solution()], q, &mut d);
        propagate::keep(&mut d, &self.estimated);
        let test = (q == self.p).then_some(&mut self.ms.stats);
        let carry = propagate::through_shifted(&mut self.matrix, &self.estimated);
        let norm = self.estimate.term_norm(&d, &self.ms.weights, test, carry);
        let est = self.coef.error_constant[q] * self.estimate_scale * norm;
        self.delta = d;
        control::error_norm(est)
    }

    /// Order and step ratio after an accepted step with error `err`.
    pub(super) fn propose(&mut self, err: f64) -> (usize, f64) {
        let p = self.p;
        self.same += 1;
        let max_order = self.ms.cfg.max_order;
        let r_same = ratio(err, p, 1.2);
        let (mut p_new, mut r) = (p, 1.0);
        if self.same > p {
            r = r_same;
            if self.ms.cfg.fixed_order {
                if p < max_order {
                    let r_up = ratio(self.estimate_at(p + 1), p + 1, 1.4);
                    p_new = p + 1;
                    r = r_up.min(r_same);
                }
            } else {
                if p > 1 {
                    let r_down = ratio(self.estimate_at(p - 1), p - 1, 1.3);
                    if r_down > r {
                        (p_new, r) = (p - 1, r_down);
                    }
                }
                if p < max_order.min(MAX_ORDER) {
                    let r_up = ratio(self.estimate_at(p + 1), p + 1, 1.4);
                    if r_up > r {
                        (p_new, r) = (p + 1, r_up);
                    }
                }
            }
            if p_new == p && (1.0..1.1).contains(&r) {
                r = 1.0;
            }
        }
        let r_max = if self.ms.ramp { 10.0 } else { 2.0 };
        r = r.clamp(0.2, r_max);
        if r > 1.0 && self.ms.h * r > self.ms.cfg.hmax {
            r = (self.ms.cfg.hmax / self.ms.h).max(1.0);
        }
        (p_new, r)
    }

    /// After the first or second rejected error test (error `err`) on
    /// this step: the new order, and the step of the retry.
    pub(super) fn reject(&mut self, err: f64) -> f64 {
        let p = self.p;
        let mut r = ratio(err, p, 1.2).clamp(0.1, 0.9);
        if p > 1 && !self.ms.cfg.fixed_order {
            let r_down = ratio(self.estimate_at(p - 1), p - 1, 1.3).clamp(0.1, 0.9);
            if r_down > r {
                self.p = p - 1;
                r = r_down;
            }
        }
        self.ms.h * r
    }
}

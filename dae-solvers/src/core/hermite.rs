//! Dense output of the step points' order for a method whose own
//! polynomial between the step points is of lower order: the Hermite
//! polynomial through the values and slopes of the last three step points.
//!
//! A method of order `p` whose continuous extension is of a lower order
//! `q` (Gauss–Legendre collocation: `p = 6` at the step points, `q = 4`
//! for its collocation polynomial, the stage order plus one) reports
//! between the step points errors of `O(h^q)`. The step points' values
//! `y_{n−1}, y_n, y_{n+1}` and slopes `y'_{n−1}, y'_n, y'_{n+1}` (each
//! slope from the equations at its own step point, so of the step points'
//! order) determine the polynomial of degree 5 through them; on the last
//! step `[t_n, t_{n+1}]` its error is
//!
//! ```text
//!     y⁽⁶⁾(ξ)/6! · (t − t_{n−1})² (t − t_n)² (t − t_{n+1})²  ≤  2.1·10⁻⁴ h⁶ |y⁽⁶⁾|
//! ```
//!
//! at a constant step (the maximum of `s(1 − s)(1 + s)` on `[0, 1]` is
//! `2/(3√3)`), plus the data's own errors, `O(h⁶)` for the values and
//! `h · O(h⁵)` for the slopes: the order of the step points, with a
//! constant small against that of the method's local error over a few
//! steps. The grid may be variable: the divided differences are taken on
//! the step points as they are. Before the second step (two points) it is
//! the cubic Hermite polynomial of the first step, `O(h⁴)`; a method uses
//! its own polynomial where it has fewer than two points.
//!
//! The polynomial is kept in Newton form on the nodes `t_{n+1}, t_{n+1},
//! t_n, t_n, t_{n−1}, t_{n−1}` (newest first), its coefficients computed
//! once per step ([`StepHermite::push`]), so that each evaluation costs a
//! Horner sweep of five products per unknown.

/// The values and slopes of the last three step points of some unknowns,
/// and the Newton form of their Hermite polynomial (see the
/// [module documentation](self)).
#[derive(Clone, Debug)]
pub(crate) struct StepHermite {
    /// The unknowns interpolated (positions in the method's `y`).
    unknowns: Vec<usize>,
    /// Step points, newest first (`len` of them valid).
    t: [f64; 3],
    /// Values at the step points, point-major, newest first (`3 k`).
    y: Vec<f64>,
    /// Slopes at the step points, likewise.
    yp: Vec<f64>,
    /// Step points held (0 … 3).
    len: usize,
    /// Divided differences `f[z₀ … z_i]`, `i = 1 … 5`, unknown-major (`5 k`).
    coef: Vec<f64>,
}

impl StepHermite {
    /// No step point yet, for the `unknowns` (positions in `y`).
    pub(crate) fn new(unknowns: Vec<usize>) -> Self {
        let k = unknowns.len();
        StepHermite {
            unknowns,
            t: [0.0; 3],
            y: vec![0.0; 3 * k],
            yp: vec![0.0; 3 * k],
            len: 0,
            coef: vec![0.0; 5 * k],
        }
    }

    /// The unknowns interpolated.
    pub(crate) fn unknowns(&self) -> &[usize] {
        &self.unknowns
    }

    /// Whether the polynomial is defined (two step points or more).
    pub(crate) fn ready(&self) -> bool {
        self.len >= 2
    }

    /// Forget every step point (the slopes could not be had at one: the
    /// method's own polynomial serves until two points are held again).
    pub(crate) fn clear(&mut self) {
        self.len = 0;
    }

    /// A new step point `t` (after the others) with the full vector `y`
    /// and the slopes `yp` of the unknowns (in the order of
    /// [`StepHermite::unknowns`]); the polynomial is then the one on the
    /// step that ends at `t`.
    pub(crate) fn push(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        let k = self.unknowns.len();
        self.y.copy_within(0..2 * k, k);
        self.yp.copy_within(0..2 * k, k);
        self.t.copy_within(0..2, 1);
        self.t[0] = t;
        for (i, &j) in self.unknowns.iter().enumerate() {
            self.y[i] = y[j];
        }
        self.yp[..k].copy_from_slice(&yp[..k]);
        self.len = (self.len + 1).min(3);
        if self.len >= 2 {
            self.coefficients();
        }
    }

    /// The divided differences on the doubled nodes.
    fn coefficients(&mut self) {
        let k = self.unknowns.len();
        let (a, b) = (self.t[0], self.t[1]);
        let ab = 1.0 / (b - a);
        if self.len == 2 {
            for i in 0..k {
                let (ya, yb) = (self.y[i], self.y[k + i]);
                let (pa, pb) = (self.yp[i], self.yp[k + i]);
                let sab = (yb - ya) * ab;
                let d2 = (sab - pa) * ab;
                let d3 = ((pb - sab) * ab - d2) * ab;
                self.coef[5 * i..5 * i + 5].copy_from_slice(&[pa, d2, d3, 0.0, 0.0]);
            }
            return;
        }
        let c = self.t[2];
        let (bc, ac) = (1.0 / (c - b), 1.0 / (c - a));
        for i in 0..k {
            let (ya, yb, yc) = (self.y[i], self.y[k + i], self.y[2 * k + i]);
            let (pa, pb, pc) = (self.yp[i], self.yp[k + i], self.yp[2 * k + i]);
            // First differences on z = a, a, b, b, c, c.
            let (sab, sbc) = ((yb - ya) * ab, (yc - yb) * bc);
            // Second.
            let (q0, q1) = ((sab - pa) * ab, (pb - sab) * ab);
            let (q2, q3) = ((sbc - pb) * bc, (pc - sbc) * bc);
            // Third: z₃ − z₀ = b − a, z₄ − z₁ = c − a, z₅ − z₂ = c − b.
            let (r0, r1, r2) = ((q1 - q0) * ab, (q2 - q1) * ac, (q3 - q2) * bc);
            // Fourth and fifth: spans c − a.
            let (u0, u1) = ((r1 - r0) * ac, (r2 - r1) * ac);
            let v0 = (u1 - u0) * ac;
            self.coef[5 * i..5 * i + 5].copy_from_slice(&[pa, q0, r0, u0, v0]);
        }
    }

    /// The polynomial at `tau` (on the last step) into the interpolated
    /// unknowns of `out`; the others are left as they are. Only when
    /// [`StepHermite::ready`].
    pub(crate) fn eval(&self, tau: f64, out: &mut [f64]) {
        debug_assert!(self.ready());
        let x = tau - self.t[0];
        let xb = tau - self.t[1];
        let xc = if self.len == 3 { tau - self.t[2] } else { 0.0 };
        for (i, &j) in self.unknowns.iter().enumerate() {
            let c = &self.coef[5 * i..5 * i + 5];
            let p = c[2] + xb * (c[3] + xc * c[4]);
            out[j] = self.y[i] + x * (c[0] + x * (c[1] + xb * p));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values and slopes of `y(t)` at `t` into a point of two unknowns
    /// (the second interpolated, the first not).
    fn push(h: &mut StepHermite, t: f64, y: impl Fn(f64) -> f64, yp: impl Fn(f64) -> f64) {
        h.push(t, &[f64::NAN, y(t)], &[yp(t)]);
    }

    #[test]
    fn reproduces_quintics_on_a_variable_grid_and_cubics_from_two_points() {
        let q = |t: f64| 0.3 - t * (1.1 - t * (0.7 + t * (0.2 - t * (0.05 + 0.4 * t))));
        let qp = |t: f64| -1.1 + t * (1.4 + t * (-0.6 + t * (0.2 + 2.0 * t)));
        let c = |t: f64| 2.0 + t * (0.5 - t * (1.5 + 0.25 * t));
        let cp = |t: f64| 0.5 - t * (3.0 + 0.75 * t);
        let mut h = StepHermite::new(vec![1]);
        assert!(!h.ready());
        push(&mut h, 0.1, c, cp);
        push(&mut h, 0.35, c, cp);
        assert!(h.ready());
        let mut out = [7.0, 0.0];
        for tau in [0.1, 0.2, 0.3, 0.35] {
            h.eval(tau, &mut out);
            assert!((out[1] - c(tau)).abs() < 1e-14, "cubic at {tau}");
            assert_eq!(out[0], 7.0, "not interpolated");
        }
        let mut h = StepHermite::new(vec![1]);
        for t in [-0.4, 0.1, 0.35, 1.2] {
            push(&mut h, t, q, qp);
        }
        for tau in [0.35, 0.5, 0.9, 1.2] {
            h.eval(tau, &mut out);
            assert!((out[1] - q(tau)).abs() < 1e-13, "quintic at {tau}");
        }
        // Cleared: not ready until two points again.
        h.clear();
        push(&mut h, 1.5, q, qp);
        assert!(!h.ready());
    }

    #[test]
    fn error_on_the_last_step_is_of_order_six() {
        // exp on the steps …, 1 − 2h, 1 − h, 1: the largest error on
        // [1 − h, 1] falls 2⁶-fold as h halves.
        let max_error = |step: f64| {
            let mut h = StepHermite::new(vec![1]);
            for k in [2.0, 1.0, 0.0] {
                push(&mut h, 1.0 - k * step, f64::exp, f64::exp);
            }
            let mut out = [0.0; 2];
            (1..20)
                .map(|i| {
                    let tau = 1.0 - step + step * f64::from(i) / 20.0;
                    h.eval(tau, &mut out);
                    (out[1] - tau.exp()).abs()
                })
                .fold(0.0, f64::max)
        };
        let (e1, e2) = (max_error(0.1), max_error(0.05));
        let ratio = e1 / e2;
        assert!((55.0..73.0).contains(&ratio), "{e1:e} / {e2:e} = {ratio}");
        // The bound 2.1e-4 h⁶ max|y⁽⁶⁾| (e on [0.8, 1]).
        assert!(e1 < 2.1e-4 * 0.1f64.powi(6) * 1f64.exp(), "{e1:e}");
    }
}

//! Dense output of the step points' order for a method whose own
//! polynomial between the step points is of lower order: the Hermite
//! polynomial through the values and slopes of the last four step points.
//!
//! A method of order `p` whose continuous extension is of a lower order
//! `q` (Gauss–Legendre collocation: `p = 6` at the step points, `q = 4`
//! for its collocation polynomial, the stage order plus one) reports
//! between the step points errors of `O(h^q)`. The values and slopes of
//! the last `k` step points (each slope from the equations at its own step
//! point, so of the step points' order) determine the Hermite polynomial
//! of degree `2k − 1` through them; on the last step its interpolation
//! error is `y⁽²ᵏ⁾(ξ)/(2k)! · Π (t − t_i)²`, at a constant step at most
//!
//! ```text
//!     k = 3:  2.1·10⁻⁴ h⁶ |y⁽⁶⁾|      k = 4:  2.5·10⁻⁵ h⁸ |y⁽⁸⁾|
//! ```
//!
//! (the maxima of `s(1 − s)(1 + s)` and `s(1 − s)(1 + s)(2 + s)` on
//! `[0, 1]`, squared, over `6!` and `8!`), plus the data's own errors,
//! `O(h⁶)` for the values and `h · O(h⁵)` for the slopes, carried smoothly
//! between the step points. With `k = 4` ([`POINTS`]) the interpolation
//! error vanishes against the step points' own as `h → 0`: the output
//! between the step points is then as accurate as at them. The grid may be
//! variable: the divided differences are taken on the step points as they
//! are. With two or three points held (the first steps of a run) the
//! degree is 3 or 5; a method uses its own polynomial where it holds fewer
//! than two.
//!
//! The polynomial is kept in Newton form on the doubled nodes `t_{n+1},
//! t_{n+1}, t_n, t_n, …` (newest first); its divided differences are
//! computed at the first evaluation after a step, so that a run that asks
//! for no value between its step points pays only for the data, and each
//! evaluation is a Horner sweep of `2k − 1` products per unknown.

use std::cell::RefCell;

/// Step points held at most: the polynomial is of degree `2 POINTS − 1`.
pub(crate) const POINTS: usize = 4;

/// The values and slopes of the last [`POINTS`] step points of some
/// unknowns, and the Newton form of their Hermite polynomial (see the
/// [module documentation](self)).
#[derive(Debug)]
pub(crate) struct StepHermite {
    /// The unknowns interpolated (positions in the method's `y`).
    unknowns: Vec<usize>,
    /// Step points, a ring: the newest at `head`, the one before it at
    /// `head − 1` (mod [`POINTS`]), … (`len` of them valid).
    t: [f64; POINTS],
    /// Values at the step points, slot-major (`POINTS k`).
    y: Vec<f64>,
    /// Slopes at the step points, likewise.
    yp: Vec<f64>,
    /// Slot of the newest step point.
    head: usize,
    /// Step points held (0 … `POINTS`).
    len: usize,
    /// The divided differences `f[z₀ … z_l]`, `l = 0 … 2 len − 1`,
    /// unknown-major (`2 POINTS k`), computed at the first evaluation
    /// after a new step point (none where no output is asked for).
    coef: RefCell<(bool, Vec<f64>)>,
}

impl StepHermite {
    /// No step point yet, for the `unknowns` (positions in `y`).
    pub(crate) fn new(unknowns: Vec<usize>) -> Self {
        let k = unknowns.len();
        StepHermite {
            unknowns,
            t: [0.0; POINTS],
            y: vec![0.0; POINTS * k],
            yp: vec![0.0; POINTS * k],
            head: 0,
            len: 0,
            coef: RefCell::new((false, vec![0.0; 2 * POINTS * k])),
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
        self.head = (self.head + 1) % POINTS;
        let at = self.head * k;
        self.t[self.head] = t;
        for (v, &j) in self.y[at..at + k].iter_mut().zip(&self.unknowns) {
            *v = y[j];
        }
        self.yp[at..at + k].copy_from_slice(&yp[..k]);
        self.len = (self.len + 1).min(POINTS);
        self.coef.get_mut().0 = false;
    }

    /// The slot of the step point `age` steps before the newest.
    fn slot(&self, age: usize) -> usize {
        (self.head + POINTS - age) % POINTS
    }

    /// The divided differences on the doubled nodes `z = t₀, t₀, t₁, t₁,
    /// …` (newest first) of every unknown, into `coef`.
    fn coefficients(&self, coef: &mut [f64]) {
        let (k, nodes) = (self.unknowns.len(), 2 * self.len);
        let z = |i: usize| self.t[self.slot(i / 2)];
        for u in 0..k {
            let d = &mut coef[2 * POINTS * u..2 * POINTS * u + nodes];
            for (i, di) in d.iter_mut().enumerate() {
                *di = self.y[self.slot(i / 2) * k + u];
            }
            for level in 1..nodes {
                for i in (level..nodes).rev() {
                    d[i] = if level == 1 && i % 2 == 1 {
                        // A doubled node: the slope.
                        self.yp[self.slot(i / 2) * k + u]
                    } else {
                        (d[i] - d[i - 1]) / (z(i) - z(i - level))
                    };
                }
            }
        }
    }

    /// The polynomial at `tau` (on the last step) into the interpolated
    /// unknowns of `out`; the others are left as they are. Only when
    /// [`StepHermite::ready`].
    pub(crate) fn eval(&self, tau: f64, out: &mut [f64]) {
        debug_assert!(self.ready());
        let mut cache = self.coef.borrow_mut();
        let (valid, coef) = &mut *cache;
        if !*valid {
            self.coefficients(coef);
            *valid = true;
        }
        let nodes = 2 * self.len;
        let mut x = [0.0; POINTS];
        for (age, x) in x.iter_mut().enumerate().take(self.len) {
            *x = tau - self.t[self.slot(age)];
        }
        for (u, &j) in self.unknowns.iter().enumerate() {
            let c = &coef[2 * POINTS * u..2 * POINTS * u + nodes];
            let mut p = c[nodes - 1];
            for l in (0..nodes - 1).rev() {
                p = c[l] + x[l / 2] * p;
            }
            out[j] = p;
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
    fn reproduces_polynomials_of_degree_2k_minus_1_on_a_variable_grid() {
        let c = |t: f64| 2.0 + t * (0.5 - t * (1.5 + 0.25 * t));
        let cp = |t: f64| 0.5 - t * (3.0 + 0.75 * t);
        let q = |t: f64| 0.3 - t * (1.1 - t * (0.7 + t * (0.2 - t * (0.05 + 0.4 * t))));
        let qp = |t: f64| -1.1 + t * (1.4 + t * (0.6 - t * (0.2 + 2.0 * t)));
        let s = |t: f64| q(t) + t.powi(7) * 0.3 - t.powi(6) * 0.2;
        let sp = |t: f64| qp(t) + 2.1 * t.powi(6) - 1.2 * t.powi(5);
        let mut out = [7.0, 0.0];
        // Two points: cubics.
        let mut h = StepHermite::new(vec![1]);
        assert!(!h.ready());
        push(&mut h, 0.1, c, cp);
        push(&mut h, 0.35, c, cp);
        assert!(h.ready());
        for tau in [0.1, 0.2, 0.3, 0.35] {
            h.eval(tau, &mut out);
            assert!((out[1] - c(tau)).abs() < 1e-14, "cubic at {tau}");
            assert_eq!(out[0], 7.0, "not interpolated");
        }
        // Three points: quintics; four (and on): degree 7.
        type F<'a> = &'a dyn Fn(f64) -> f64;
        let cases: [(F, F, usize); 2] = [(&q, &qp, 3), (&s, &sp, 4)];
        for (f, fp, points) in cases {
            let mut h = StepHermite::new(vec![1]);
            let grid = [-0.4, 0.1, 0.35, 1.2, 1.3];
            for &t in &grid[grid.len() - points - 1..] {
                push(&mut h, t, f, fp);
            }
            for tau in [1.2, 1.22, 1.27, 1.3] {
                h.eval(tau, &mut out);
                assert!((out[1] - f(tau)).abs() < 1e-13, "{points} points at {tau}");
            }
        }
        // Cleared: not ready until two points again.
        let mut h = StepHermite::new(vec![1]);
        push(&mut h, 1.0, q, qp);
        push(&mut h, 1.5, q, qp);
        h.clear();
        push(&mut h, 2.0, q, qp);
        assert!(!h.ready());
    }

    #[test]
    fn error_on_the_last_step_is_of_order_2k() {
        // exp on the steps …, 1 − 2h, 1 − h, 1: the largest error on
        // [1 − h, 1] falls 2⁶-fold as h halves with three points, 2⁸-fold
        // with four.
        let max_error = |step: f64, points: usize| {
            let mut h = StepHermite::new(vec![1]);
            for k in (0..points).rev() {
                push(&mut h, 1.0 - k as f64 * step, f64::exp, f64::exp);
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
        // (Four points at longer steps: at 0.05 the error is round-off.)
        for (points, order, h) in [(3, 6, 0.1), (4, 8, 0.2)] {
            let (e1, e2) = (max_error(h, points), max_error(h / 2.0, points));
            let ratio = (e1 / e2).log2();
            assert!(
                (ratio - f64::from(order)).abs() < 0.3,
                "{points} points: {e1:e} / {e2:e}: order {ratio}"
            );
        }
        // The bound 2.1e-4 h⁶ max|y⁽⁶⁾| of three points (e on [0.8, 1]).
        assert!(max_error(0.1, 3) < 2.1e-4 * 0.1f64.powi(6) * 1f64.exp());
    }
}

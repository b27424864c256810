//! The slopes at the step points of a method that is not stiffly accurate
//! (`gauss`), for its dense output of the step points' order
//! ([`crate::core::hermite`]): between the step points the collocation
//! polynomial is `O(h⁴)` (stage order 3), the step points `O(h⁶)`.
//!
//! The Hermite polynomial needs `y'` at each step point to `O(h⁵)`. The
//! collocation polynomial's end slope is only `O(h³)`; the equations at the
//! (projected) end point give more:
//!
//! - **Split** — the usual case (`rcd0`, `psi0` of mechanical systems, the
//!   reactor, Jay's problem): the columns of `E` that are zero are the
//!   algebraic unknowns `a`, and the rows of `E` that are not zero (`R`)
//!   are as many as the other unknowns `d`. Then `E_Rd y'_d = f_R(t, y)`
//!   gives the slopes of `d` exactly from the step point's own `f`, at no
//!   evaluation beyond the projection's. The algebraic unknowns keep the
//!   collocation polynomial: at the output times the projection solves
//!   them from the interpolated `d` (their stored dense output stays
//!   `O(h⁴)`).
//! - **Coupled** — a row of `E` holds the derivative of an algebraic
//!   unknown (Gear–Hsu–Petzold's `rcd0`: `y1' + ηt y2'`, `y2` fixed by an
//!   algebraic row). The slope of every unknown then solves `E_R y' = f_R`
//!   with the differentiated algebraic rows `∂f_a/∂t + J_a y' = 0`, the
//!   projection's matrix. Its `J_a` may be a few steps old, so it is
//!   applied to a correction only: from the collocation polynomial's end
//!   slope `w`, `P c = [f_R − E_R w ; −D_w f_a]`, `y' = w + c`, with the
//!   directional derivative `D_w f_a` of `f_a` along `(1, w)` by a central
//!   difference (two evaluations of `f` per step, counted). An `O(h)`
//!   error of `J_a` then costs `O(h · h³)` in the slope, `O(h⁵)` in the
//!   output.
//!
//! A split found at `t₀` (from the values of `E` there, for an `E` that is
//! not constant) is checked at every step point; where `E` fills one of
//! its zero columns the run goes on coupled. Where a slope cannot be had
//! (a singular block, a non-finite value) the history is cleared and the
//! collocation polynomial serves until two step points are held again.

use super::stages::zero_columns;
use super::step::Integrator;
use super::tableau::Collocation;
use crate::core::hermite::StepHermite;
use crate::linalg::{all_finite, mat_vec, DenseLu, Pivoting};

/// `∛ε`, the relative step of a central difference.
const CBRT_EPS: f64 = 6.055454452393343e-6;

/// How the slopes at the step points are had (see the
/// [module documentation](self)).
pub(super) enum Kind {
    /// None: the collocation polynomial is the dense output (a stiffly
    /// accurate method, least-squares stages, or no slope to be had).
    None,
    /// `E_Rd y'_d = f_R` on the rows `R` and the columns `d`; the
    /// block factorised (once, where `E` is constant).
    Split {
        rows: Vec<usize>,
        /// The zero columns of `E` (the algebraic unknowns).
        zero: Vec<usize>,
        lu: DenseLu,
        /// With a constant `E`: `E_Rd⁻¹`, column-major, applied as a
        /// product (cheaper per step than the solve).
        inverse: Vec<f64>,
    },
    /// `y' = w + P⁻¹ [f_R − E_R w ; −D_w f_a]` with the projection's
    /// matrix `P`.
    Coupled,
}

/// The slopes' way, their buffers and the step points' Hermite data.
pub(super) struct Slopes {
    pub(super) kind: Kind,
    /// The step points' values and slopes and their polynomial.
    pub(super) hermite: StepHermite,
    /// Slopes of the interpolated unknowns (`N`).
    v: Vec<f64>,
    /// `f` at the two points of the central difference (`M` each).
    f_plus: Vec<f64>,
    f_minus: Vec<f64>,
    /// The perturbed points (`N`).
    y_step: Vec<f64>,
}

impl Slopes {
    /// No Hermite output.
    pub(super) fn none() -> Self {
        Slopes {
            kind: Kind::None,
            hermite: StepHermite::new(Vec::new()),
            v: Vec::new(),
            f_plus: Vec::new(),
            f_minus: Vec::new(),
            y_step: Vec::new(),
        }
    }

    /// Whether the dense output is the Hermite polynomial where it is
    /// ready (degree 7 from four step points on).
    pub(super) fn active(&self) -> bool {
        !matches!(self.kind, Kind::None)
    }
}

impl<K: Collocation> Integrator<'_, K> {
    /// Choose how the slopes are had, from `E(t₀, y₀)` and the algebraic
    /// rows (after [`Integrator::find_algebraic_rows`]), and take the
    /// first step point's where the split applies.
    pub(super) fn setup_slopes(&mut self) {
        if !self.interpolate
            || !K::TABLEAU.end.projected()
            || self.w.stages.least_squares()
            || self.m != self.n
        {
            return;
        }
        let (m, n) = (self.m, self.n);
        let e = self.w.e_n.dense();
        let zero = zero_columns(e);
        let rows: Vec<usize> = (0..m).filter(|i| !self.w.algebraic.contains(i)).collect();
        let cols: Vec<usize> = (0..n).filter(|j| !zero.contains(j)).collect();
        let buffers = |kind: Kind, unknowns: Vec<usize>| Slopes {
            kind,
            hermite: StepHermite::new(unknowns),
            v: vec![0.0; n],
            f_plus: vec![0.0; m],
            f_minus: vec![0.0; m],
            y_step: vec![0.0; n],
        };
        if cols.is_empty() {
            // `E = 0`: no unknown has a derivative to interpolate with.
            return;
        }
        if rows.len() == cols.len() {
            let mut lu = DenseLu::new(cols.len(), Pivoting::Checked);
            if lu.factor_from(|a, b| e[(rows[a], cols[b])]).is_ok() {
                let k = cols.len();
                let mut inverse = Vec::new();
                if self.constant_leading {
                    inverse = vec![0.0; k * k];
                    for (j, col) in inverse.chunks_exact_mut(k).enumerate() {
                        col[j] = 1.0;
                        lu.solve(col);
                    }
                }
                let kind = Kind::Split {
                    rows,
                    zero,
                    lu,
                    inverse,
                };
                self.slopes = buffers(kind, cols);
                let t = self.c.one.t;
                self.push_split(t);
                return;
            }
        }
        if !self.w.algebraic.is_empty() && self.w.algebraic_unknowns.is_empty() {
            self.slopes = buffers(Kind::Coupled, (0..n).collect());
        }
    }

    /// After the end point of an accepted step is projected: its slopes
    /// and a new step point of the Hermite polynomial.
    pub(super) fn push_slopes(&mut self) {
        let t = self.c.one.t;
        if let Kind::Split { zero, .. } = &self.slopes.kind {
            if !self.constant_leading {
                // `E` filled a zero column: coupled from here on.
                let e = self.w.e_n.dense();
                if zero.iter().any(|&j| e.column(j).iter().any(|&x| x != 0.0)) {
                    self.slopes.kind = Kind::Coupled;
                    self.slopes.hermite = StepHermite::new((0..self.n).collect());
                }
            }
        }
        match self.slopes.kind {
            Kind::None => {}
            Kind::Split { .. } => self.push_split(t),
            Kind::Coupled => self.push_coupled(t),
        }
    }

    /// `E_Rd y'_d = f_R` at the step point `t` (`E` and `f` evaluated
    /// there).
    fn push_split(&mut self, t: f64) {
        let Slopes {
            kind: Kind::Split {
                rows, lu, inverse, ..
            },
            hermite,
            v,
            ..
        } = &mut self.slopes
        else {
            return;
        };
        let cols = hermite.unknowns();
        let k = cols.len();
        let v = &mut v[..k];
        if self.constant_leading {
            v.fill(0.0);
            for (col, &i) in inverse.chunks_exact(k).zip(rows.iter()) {
                let f = self.w.f0[i];
                for (x, a) in v.iter_mut().zip(col) {
                    *x += a * f;
                }
            }
        } else {
            let e = self.w.e_n.dense();
            if lu.factor_from(|a, b| e[(rows[a], cols[b])]).is_err() {
                hermite.clear();
                return;
            }
            for (x, &i) in v.iter_mut().zip(rows.iter()) {
                *x = self.w.f0[i];
            }
            lu.solve(v);
        }
        if all_finite(v) {
            hermite.push(t, &self.w.y, v);
        } else {
            hermite.clear();
        }
    }

    /// The coupled slopes at the step point `t`: the correction of the
    /// collocation polynomial's end slope with the projection's matrix.
    fn push_coupled(&mut self, t: f64) {
        let (m, n) = (self.m, self.n);
        let w = &self.w;
        let s = &mut self.slopes;
        // The step of the central difference: `δ ≤ ∛u max(1, |t|)` and
        // `δ |w| ≤ ∛u max(1, |y|)`.
        let y_max = w.y.iter().fold(1.0f64, |a, x| a.max(x.abs()));
        let w_max = w.yp.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let delta = CBRT_EPS / (1.0 / t.abs().max(1.0)).max(w_max / y_max);
        for (sign, f) in [(1.0, &mut s.f_plus), (-1.0, &mut s.f_minus)] {
            for k in 0..n {
                s.y_step[k] = w.y[k] + sign * delta * w.yp[k];
            }
            self.sys.rhs(t + sign * delta, &s.y_step, f);
        }
        self.stats.residual_evals += 2;
        // The directional derivative on the algebraic rows (kept in
        // `y_step`, free now) before `f_plus` takes `E w`.
        for (d, &i) in s.y_step.iter_mut().zip(&w.algebraic) {
            *d = (s.f_plus[i] - s.f_minus[i]) / (2.0 * delta);
        }
        // r = [f_R − E_R w ; −D_w f_a] into `v`, then `c = P⁻¹ r`.
        mat_vec(w.e_n.dense(), &w.yp, &mut s.f_plus[..m]);
        let c = &mut s.v;
        for ((ci, f), ew) in c.iter_mut().zip(&w.f0).zip(&s.f_plus) {
            *ci = f - ew;
        }
        for (&i, d) in w.algebraic.iter().zip(&s.y_step) {
            c[i] = -d;
        }
        w.projection.solve(c);
        for (ci, wi) in c.iter_mut().zip(&w.yp) {
            *ci += wi;
        }
        if all_finite(c) {
            s.hermite.push(t, &w.y, c);
        } else {
            s.hermite.clear();
        }
    }
}

//! The stage equations of one step attempt: the buffers of the step loop,
//! the Jacobian and the two factorised iteration matrices, the starting
//! values, the simplified Newton iteration in the transformed unknowns, the
//! embedded error estimate, and the new collocation polynomial of an
//! accepted step.

use super::step::Integrator;
use super::tableau::{
    divided_differences, polynomial_increment, AINV, ALPHA, BETA, C, DD, GAMMA, T, TI,
};
use super::{tolerance_factor, NIT, NIT_FIXED, THET, UROUND};
use crate::core::matrix::{Rows, StageSystems};
use crate::core::newton::Verdict;
use crate::core::weights::Weights;
use crate::linalg::{mat_vec, Singular};
use crate::options::Options;
use crate::SolveError;
use dae_core::system::FormulationInfo;
use nalgebra::DMatrix;

/// Every buffer the step loop touches, allocated once (`N` unknowns, `M`
/// equations).
pub(super) struct Work<S> {
    /// `y_n`.
    pub(super) y: Vec<f64>,
    /// Stage increments `Z_1, Z_2, Z_3` (stage-major, `3N`).
    pub(super) z: Vec<f64>,
    /// Transformed Newton right-hand sides (stride `M`), then increments
    /// `ΔW` (the first `N` of each block).
    pub(super) dw: Vec<f64>,
    /// Stage residuals `G_i(Z)` (stride `M`).
    pub(super) res: Vec<f64>,
    /// A stage value `Y_i`.
    pub(super) ys: Vec<f64>,
    /// A stage derivative `Y'_i`.
    pub(super) yd: Vec<f64>,
    /// `f(t_n, y_n)` (`M`).
    pub(super) f0: Vec<f64>,
    /// `y'(t_n)` from the last collocation polynomial (for `∂(E z)/∂y`).
    pub(super) yp: Vec<f64>,
    /// Error weights, index-scaled.
    pub(super) weights: Weights,
    /// Row classes of the least-squares systems.
    pub(super) rows: Rows,
    /// Collocation polynomial of the last accepted step (`4N`).
    pub(super) cont: Vec<f64>,
    /// Error estimate (`M` in, `N` out).
    pub(super) err: Vec<f64>,
    /// `(1/h) Σ d_i Z_i` (`N`).
    pub(super) tmp: Vec<f64>,
    /// `f(t_n, y_n + err)` of the refined estimate (`M`).
    pub(super) fm: Vec<f64>,
    /// `E(y_n) (1/h) Σ d_i Z_i` (`M`).
    pub(super) ez: Vec<f64>,
    /// `J = ∂f/∂y − ∂(E z)/∂y` at the Jacobian point.
    pub(super) jac: DMatrix<f64>,
    /// `∂(E z)/∂y`.
    pub(super) ljac: DMatrix<f64>,
    /// `E` at the Jacobian point (`E₀` of the iteration matrices).
    pub(super) e_jac: DMatrix<f64>,
    /// `E(y_n)`.
    pub(super) e_n: DMatrix<f64>,
    /// `γ/h E₀ − J` and `(α + iβ)/h E₀ − J`, factorised.
    pub(super) stages: S,
}

impl<S: StageSystems> Work<S> {
    /// The buffers for `info`, with the error weights of `options` (the
    /// tolerance map, and the index of each unknown for the scaling).
    pub(super) fn new(info: &FormulationInfo, options: &Options) -> Self {
        let (m, n) = (info.equations(), info.unknowns());
        let v = |len: usize| vec![0.0; len];
        let mat = || DMatrix::zeros(m, n);
        Work {
            y: v(n),
            z: v(3 * n),
            dw: v(3 * m),
            res: v(3 * m),
            ys: v(n),
            yd: v(n),
            f0: v(m),
            yp: v(n),
            weights: Weights::new(
                &options.tol,
                |i| tolerance_factor(options, i),
                vec![true; n],
                info.variables
                    .iter()
                    .map(|var| i32::from(var.index.max(1)) - 1)
                    .collect(),
            ),
            rows: Rows::new(info),
            cont: v(4 * n),
            err: v(m),
            tmp: v(n),
            fm: v(m),
            ez: v(m),
            jac: mat(),
            ljac: mat(),
            e_jac: mat(),
            e_n: mat(),
            stages: S::new(m, n),
        }
    }
}

/// Outcome of one simplified Newton iteration.
pub(super) enum Newton {
    /// Converged after this many iterations.
    Converged(usize),
    /// Converging too slowly: retry with the step multiplied by `factor`.
    TooSlow { iterations: usize, factor: f64 },
    /// Diverged or did not converge within `NIT` iterations.
    Diverged(usize),
    /// A residual or an increment was not finite.
    NonFinite(usize),
}

impl<S: StageSystems> Integrator<'_, S> {
    /// `J = ∂f/∂y − ∂(E z)/∂y` and `E₀` at `(t, y_n)`.
    pub(super) fn jacobian(&mut self, t: f64) -> Result<(), SolveError> {
        let w = &mut self.w;
        self.sys.rhs_jacobian(t, &w.y, &mut w.jac);
        if !self.constant_leading {
            self.sys.leading_jacobian(&w.y, &w.yp, &mut w.ljac);
            for (j, l) in w.jac.as_mut_slice().iter_mut().zip(w.ljac.as_slice()) {
                *j -= l;
            }
        }
        w.e_jac.as_mut_slice().copy_from_slice(w.e_n.as_slice());
        self.stats.jacobian_evals += 1;
        if w.jac.as_slice().iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                t,
                what: "jacobian",
            });
        }
        Ok(())
    }

    /// Factorise `γ/h E₀ − J` and `(α + iβ)/h E₀ − J`.
    pub(super) fn factor(&mut self, h: f64) -> Result<(), Singular> {
        let w = &mut self.w;
        if S::LEAST_SQUARES {
            w.weights.update_scaled(&w.y, h);
            w.rows.update(&w.e_jac, w.weights.get());
        }
        w.stages
            .factor(&w.e_jac, &w.jac, GAMMA / h, ALPHA / h, BETA / h, &w.rows)
    }

    /// Zero on the first step, otherwise the last collocation polynomial
    /// extrapolated to the new nodes (`ratio = h / h_old`).
    pub(super) fn starting_values(&mut self, first: bool, ratio: f64) {
        let n = self.n;
        let w = &mut self.w;
        if first {
            w.z.fill(0.0);
            return;
        }
        // Slices of exactly `n` entries, indexed by `k < n`: no bounds checks.
        let (d1, d2, d3) = (
            &w.cont[n..2 * n],
            &w.cont[2 * n..3 * n],
            &w.cont[3 * n..4 * n],
        );
        for (i, &ci) in C.iter().enumerate() {
            let s = ci * ratio;
            let zi = &mut w.z[i * n..(i + 1) * n];
            for k in 0..n {
                zi[k] = polynomial_increment(&[d1[k], d2[k], d3[k]], s);
            }
        }
    }

    /// Stage residuals `G_i(Z) = E(Y_i) Y'_i − f(t + c_i h, Y_i)` into `res`.
    fn stage_residuals(&mut self, t: f64, h: f64) {
        let (n, m) = (self.n, self.m);
        let w = &mut self.w;
        let (z1, z2, z3) = (&w.z[..n], &w.z[n..2 * n], &w.z[2 * n..3 * n]);
        let (y, ys, yd) = (&w.y[..n], &mut w.ys[..n], &mut w.yd[..n]);
        for (i, &ci) in C.iter().enumerate() {
            let zi = &w.z[i * n..(i + 1) * n];
            let a = AINV[i];
            for k in 0..n {
                ys[k] = y[k] + zi[k];
                yd[k] = (a[0] * z1[k] + a[1] * z2[k] + a[2] * z3[k]) / h;
            }
            self.sys
                .residual(t + ci * h, ys, yd, &mut w.res[i * m..(i + 1) * m]);
        }
        self.stats.residual_evals += 3;
    }

    /// Simplified Newton iteration for the stage increments (RADAU5's loop
    /// at label 40). `may_shorten` allows the early exit on slow
    /// convergence; without it (fixed-step mode) up to `NIT_FIXED`
    /// iterations are made.
    pub(super) fn newton(&mut self, t: f64, h: f64, may_shorten: bool) -> Newton {
        let (n, m) = (self.n, self.m);
        let max_iter = if may_shorten { NIT } else { NIT_FIXED };
        let eta = self.newton.eta.max(UROUND).powf(0.8);
        self.newton.restart(max_iter, eta, THET);
        loop {
            self.stage_residuals(t, h);
            let w = &mut self.w;
            if w.res.iter().any(|v| !v.is_finite()) {
                return Newton::NonFinite(self.newton.iterations());
            }
            // R = −(T⁻¹ ⊗ I) G.
            {
                let (g1, g2, g3) = (&w.res[..m], &w.res[m..2 * m], &w.res[2 * m..3 * m]);
                let (r1, r) = w.dw.split_at_mut(m);
                let (r2, r3) = r.split_at_mut(m);
                let (r2, r3) = (&mut r2[..m], &mut r3[..m]);
                for k in 0..m {
                    let (g1, g2, g3) = (g1[k], g2[k], g3[k]);
                    r1[k] = -(TI[0][0] * g1 + TI[0][1] * g2 + TI[0][2] * g3);
                    r2[k] = -(TI[1][0] * g1 + TI[1][1] * g2 + TI[1][2] * g3);
                    r3[k] = -(TI[2][0] * g1 + TI[2][1] * g2 + TI[2][2] * g3);
                }
            }
            w.stages.solve_real(&mut w.dw[..m]);
            let (re, im) = w.dw[m..].split_at_mut(m);
            w.stages.solve_complex(re, im);

            let dyno = w.weights.norm_blocks(&w.dw, m, 3);
            if !dyno.is_finite() {
                return Newton::NonFinite(self.newton.iterations() + 1);
            }
            let verdict = self.newton.observe(dyno, 0.0);
            let iterations = self.newton.iterations();
            match verdict {
                Verdict::Diverged => return Newton::Diverged(iterations),
                Verdict::TooSlow { factor } => {
                    return Newton::TooSlow { iterations, factor };
                }
                Verdict::Continue | Verdict::Converged => {}
            }

            // Z += (T ⊗ I) ΔW   (T₃₂ = 1, T₃₃ = 0).
            let w = &mut self.w;
            let (a1, a2, a3) = (&w.dw[..n], &w.dw[m..m + n], &w.dw[2 * m..2 * m + n]);
            let (z1, z) = w.z.split_at_mut(n);
            let (z2, z3) = z.split_at_mut(n);
            let (z2, z3) = (&mut z2[..n], &mut z3[..n]);
            for k in 0..n {
                let (a1, a2, a3) = (a1[k], a2[k], a3[k]);
                z1[k] += T[0][0] * a1 + T[0][1] * a2 + T[0][2] * a3;
                z2[k] += T[1][0] * a1 + T[1][1] * a2 + T[1][2] * a3;
                z3[k] += T[2][0] * a1 + a2;
            }
            if verdict == Verdict::Converged {
                return Newton::Converged(iterations);
            }
        }
    }

    /// Scaled norm of the embedded error estimate; NaN if it is not finite.
    pub(super) fn error_norm(&mut self, t: f64, h: f64, refine: bool) -> f64 {
        let (n, m) = (self.n, self.m);
        let w = &mut self.w;
        // tmp = (1/h) Σ d_i Z_i,  ez = E(y_n) tmp.
        {
            let (z1, z2, z3) = (&w.z[..n], &w.z[n..2 * n], &w.z[2 * n..3 * n]);
            let tmp = &mut w.tmp[..n];
            for k in 0..n {
                tmp[k] = (DD[0] * z1[k] + DD[1] * z2[k] + DD[2] * z3[k]) / h;
            }
        }
        mat_vec(&w.e_n, &w.tmp, &mut w.ez);
        for k in 0..m {
            w.err[k] = w.f0[k] + w.ez[k];
        }
        w.stages.solve_real(&mut w.err);
        let mut err = w.weights.norm(&w.err[..n]);
        if err >= 1.0 && refine {
            for k in 0..n {
                w.ys[k] = w.y[k] + w.err[k];
            }
            self.sys.rhs(t, &w.ys, &mut w.fm);
            self.stats.residual_evals += 1;
            for k in 0..m {
                w.err[k] = w.fm[k] + w.ez[k];
            }
            w.stages.solve_real(&mut w.err);
            err = w.weights.norm(&w.err[..n]);
        }
        if err.is_nan() {
            f64::NAN
        } else {
            err.max(1e-10)
        }
    }

    /// Accept the step: `y_{n+1} = y_n + Z_3`, the new collocation
    /// polynomial (Newton form on `s = 0, c₂ − 1, c₁ − 1, −1`) and
    /// `y'_{n+1} = Y'_3`.
    pub(super) fn advance(&mut self, h: f64) {
        let n = self.n;
        let w = &mut self.w;
        let (z1, z2, z3) = (&w.z[..n], &w.z[n..2 * n], &w.z[2 * n..3 * n]);
        let (y, yp) = (&mut w.y[..n], &mut w.yp[..n]);
        let (c0, c) = w.cont.split_at_mut(n);
        let (c1, c) = c.split_at_mut(n);
        let (c2, c3) = c.split_at_mut(n);
        let (c0, c1, c2, c3) = (&mut c0[..n], &mut c1[..n], &mut c2[..n], &mut c3[..n]);
        for k in 0..n {
            let (z1, z2, z3) = (z1[k], z2[k], z3[k]);
            y[k] += z3;
            let d = divided_differences(z1, z2, z3);
            c0[k] = y[k];
            c1[k] = d[0];
            c2[k] = d[1];
            c3[k] = d[2];
            yp[k] = (AINV[2][0] * z1 + AINV[2][1] * z2 + AINV[2][2] * z3) / h;
        }
    }
}

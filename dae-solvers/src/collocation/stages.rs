//! The stage equations of one step attempt: the buffers of the step loop,
//! the Jacobian and the two factorised iteration matrices, the starting
//! values, the simplified Newton iteration in the transformed unknowns, the
//! embedded error estimate, and the new collocation polynomial of an
//! accepted step.

use super::kernels;
use super::solve::{StageSolve, StageSolveKind};
use super::stagger::{rhs_for_error, Phase, Stagger};
use super::step::Integrator;
use super::tableau::Collocation;
use crate::core::block::Part;
use crate::core::matrix::{Matrix, Rows, Structure};
use crate::core::weights::{self, Plain, Weights};
use crate::linalg::{all_finite, mat_vec, two_sum, DenseLu, Pivoting, Singular};
use crate::options::Options;
use crate::NotApplicable;
use crate::SolveError;
use dae_core::system::{DaeSystem, FormulationInfo, RowKind};
use nalgebra::DMatrix;
use std::cell::RefCell;

/// Most simplified Newton steps of the projected dense output
/// ([`Integrator::project_output`]).
const OUTPUT_PROJECTION_STEPS: usize = 3;

/// The projected dense output stops at a correction of this weighted norm
/// (a thousandth of the tolerance).
const OUTPUT_PROJECTION_FLOOR: f64 = 1e-3;

/// Every buffer the step loop touches, allocated once (`N` unknowns, `M`
/// equations).
pub(super) struct Work {
    /// `y_n`.
    pub(super) y: Vec<f64>,
    /// Rounding error of `y_n` (compensated summation at tight
    /// tolerances, see [`super::TIGHT_TOL`]).
    pub(super) y_lo: Vec<f64>,
    /// Stage increments `Z_1, Z_2, Z_3` (stage-major, `3N`).
    pub(super) z: Vec<f64>,
    /// Transformed Newton right-hand sides (stride `M`), then increments
    /// `ΔW` (the first `N` of each block).
    pub(super) dw: Vec<f64>,
    /// Stage residuals `G_i(Z)` (stride `M`).
    pub(super) res: Vec<f64>,
    /// Stage values `Y_i` (stage-major, `3N`).
    pub(super) ys: Vec<f64>,
    /// Stage derivatives `Y'_i` (stage-major, `3N`).
    pub(super) yd: Vec<f64>,
    /// `f(t_n, y_n)` (`M`).
    pub(super) f0: Vec<f64>,
    /// `y'(t_n)` from the last collocation polynomial (for `∂(E z)/∂y`).
    pub(super) yp: Vec<f64>,
    /// Error weights, index-scaled.
    pub(super) weights: Weights<Plain>,
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
    /// `J = ∂f/∂y − ∂(E z)/∂y` at the Jacobian point. Like `ljac`,
    /// `e_jac` and `e_n`, compressed on the run's iteration pattern for a
    /// large sparse square system of a stiffly accurate method
    /// ([`Structure::of`]), dense otherwise.
    pub(super) jac: Matrix,
    /// `∂(E z)/∂y`.
    pub(super) ljac: Matrix,
    /// `E` at the Jacobian point (`E₀` of the iteration matrices); unused
    /// when `E` is constant (then `E₀ = E(y_n)`).
    pub(super) e_jac: Matrix,
    /// `E(y_n)`.
    pub(super) e_n: Matrix,
    /// `E(t_n, y_n)` of the step just taken (a method that is not stiffly
    /// accurate, whose end-point projection keeps that step's differential
    /// part; unused with a constant `E`).
    pub(super) e_step: DMatrix<f64>,
    /// `γ/h E₀ − J` and `(α + iβ)/h E₀ − J`, factorised.
    pub(super) stages: StageSolve,
    /// The algebraic rows (constraint rows whose row of `E` is zero at
    /// `t₀`), for the end-point projection of a method that is not
    /// stiffly accurate; empty when there is none to make.
    pub(super) algebraic: Vec<usize>,
    /// The matrix of the projection: rows of `E(y_{n+1})` and of `J`.
    pub(super) projection: DenseLu,
    /// With a constant `E` whose zero columns are as many as the algebraic
    /// rows: those columns, the algebraic unknowns. The projection then
    /// moves only them, and its matrix is the `k × k` block of `J`
    /// (`projection_small`); empty otherwise.
    pub(super) algebraic_unknowns: Vec<usize>,
    /// That block, factorised.
    pub(super) projection_small: DenseLu,
    /// Its right-hand side, then the correction.
    pub(super) delta: Vec<f64>,
    /// The staggered corrector of a state and its sensitivities
    /// ([`super::stagger`]); `None` for every other system.
    pub(super) stagger: Option<Stagger>,
    /// Scratch of the projected dense output ([`Integrator::project_output`]),
    /// which runs through `&self`: `f` at the output point, the correction,
    /// and the residual evaluations made (added to the statistics).
    pub(super) output: RefCell<OutputScratch>,
}

/// Buffers of [`Integrator::project_output`].
pub(super) struct OutputScratch {
    f: Vec<f64>,
    delta: Vec<f64>,
    pub(super) residual_evals: usize,
}

impl Work {
    /// The buffers for `sys` with the stage solve `solve`, with the error
    /// weights of `options` (the tolerance map, and the index of each
    /// unknown for the scaling).
    pub(super) fn new<K: Collocation>(
        sys: &dyn DaeSystem,
        options: &Options,
        solve: StageSolveKind,
    ) -> Self {
        let info = sys.info();
        let blocks = sys.blocks();
        let (m, n) = (info.equations(), info.unknowns());
        let v = |len: usize| vec![0.0; len];
        let mat = || DMatrix::zeros(m, n);
        // Compressed `J` and `E` for square stage systems of a stiffly
        // accurate method (the end-point projection of the others, and
        // the least-squares systems, read them dense).
        let structure = if solve == StageSolveKind::LeastSquares || K::TABLEAU.end.projected() {
            None
        } else {
            Structure::of(sys)
        };
        let matrix = || Matrix::new(m, n, structure.as_ref());
        Work {
            y: v(n),
            y_lo: v(n),
            z: v(3 * n),
            dw: v(3 * m),
            res: v(3 * m),
            ys: v(3 * n),
            yd: v(3 * n),
            f0: v(m),
            yp: v(n),
            weights: Weights::new(
                &options.tol,
                |i| (K::POLICY.tolerance_factor)(options.tol.rtol(i), options.tol.atol(i)),
                crate::core::policy::collocation_error_test(info, blocks, options),
                weights::index_powers(info),
            ),
            rows: Rows::new(info),
            cont: v(4 * n),
            err: v(m),
            tmp: v(n),
            fm: v(m),
            ez: v(m),
            jac: matrix(),
            ljac: matrix(),
            e_jac: matrix(),
            e_n: matrix(),
            e_step: if K::TABLEAU.end.projected() {
                mat()
            } else {
                DMatrix::zeros(0, 0)
            },
            stages: StageSolve::new(solve, m, n, blocks),
            stagger: Stagger::of::<K>(sys, options, solve, structure.is_none()),
            algebraic: Vec::new(),
            projection: DenseLu::new(
                if K::TABLEAU.end.projected() { n } else { 0 },
                Pivoting::Checked,
            ),
            algebraic_unknowns: Vec::new(),
            projection_small: DenseLu::new(0, Pivoting::Checked),
            delta: v(if K::TABLEAU.end.projected() { n } else { 0 }),
            output: RefCell::new(OutputScratch {
                f: v(if K::TABLEAU.end.projected() { m } else { 0 }),
                delta: v(if K::TABLEAU.end.projected() { n } else { 0 }),
                residual_evals: 0,
            }),
        }
    }
}

impl Work {
    /// Add the end-point correction `d` to `y_k` (with compensation at
    /// tight tolerances); the dense output ends at the corrected value.
    fn correct(&mut self, k: usize, d: f64, compensated: bool) {
        if compensated {
            (self.y[k], self.y_lo[k]) = two_sum(self.y[k], d + self.y_lo[k]);
        } else {
            self.y[k] += d;
        }
        self.cont[k] = self.y[k];
    }
}

/// A non-finite end-point correction is a typed error.
fn check_projection(delta: &[f64], t: f64) -> Result<(), SolveError> {
    if all_finite(delta) {
        Ok(())
    } else {
        Err(SolveError::NonFinite {
            t,
            what: "end-point projection",
        })
    }
}

/// The error estimate's real solve: every block, or one part of them
/// ([`Integrator::error_part`]).
fn solve_error(stages: &mut StageSolve, err: &mut [f64], part: Option<Part>) {
    match part {
        None => stages.solve_real(err),
        Some(part) => stages.solve_real_part(err, part),
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

impl<K: Collocation> Integrator<'_, K> {
    /// `J = ∂f/∂y − ∂(E z)/∂y` and `E₀` at `(t, y_n)` (`E₀` is `E(t_n, y_n)`
    /// from the step point's evaluation).
    pub(super) fn jacobian(&mut self, t: f64) -> Result<(), SolveError> {
        let staggered = self.staggered_jacobian(t);
        let w = &mut self.w;
        if !staggered {
            w.jac.rhs_jacobian(&*self.sys, t, &w.y);
        }
        if !self.constant_leading {
            w.ljac.leading_jacobian(&*self.sys, t, &w.y, &w.yp);
            for (j, l) in w.jac.values_mut().iter_mut().zip(w.ljac.values()) {
                *j -= l;
            }
        }
        if !self.constant_leading {
            w.e_jac.copy_from(&w.e_n);
        }
        self.stats.jacobian_evals += 1;
        if !all_finite(w.jac.values()) {
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
        // A constant `E` is `E(y_n)` at every point; it is not copied.
        let e0 = if self.constant_leading {
            &w.e_n
        } else {
            &w.e_jac
        };
        if w.stages.least_squares() {
            w.weights.update_scaled(&w.y, h);
            w.rows.update(e0.dense(), w.weights.get());
        }
        let k = &K::TABLEAU;
        let shifts = [k.gamma / h, k.alpha / h, k.beta / h];
        w.stages.factor(e0, &w.jac, shifts, &w.rows)
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
        kernels::extrapolate::<K>(&w.cont, ratio, &mut w.z, n);
    }

    /// Stage residuals `G_i(Z) = E(Y_i) Y'_i − f(t + c_i h, Y_i)` into `res`.
    #[inline]
    pub(super) fn stage_residuals(&mut self, t: f64, h: f64) {
        let m = self.m;
        let w = &mut self.w;
        let n = self.n;
        kernels::stage_points::<K>(&w.y, &w.z, h, &mut w.ys, &mut w.yd);
        // The formulation resolved once, not at each of the three calls.
        let sys: &dyn DaeSystem = &*self.sys;
        for (i, &ci) in K::TABLEAU.c.iter().enumerate() {
            sys.residual(
                t + ci * h,
                &w.ys[i * n..(i + 1) * n],
                &w.yd[i * n..(i + 1) * n],
                &mut w.res[i * m..(i + 1) * m],
            );
        }
        self.stats.residual_evals += 3;
    }

    /// Simplified Newton iteration for the stage increments (RADAU5's loop
    /// at label 40, [`Integrator::iterate`]), staggered for a state and its
    /// sensitivities ([`super::stagger`]). `may_shorten` allows the early
    /// exit on slow convergence; without it (fixed-step mode) up to
    /// `NIT_FIXED` iterations are made.
    pub(super) fn newton(&mut self, t: f64, h: f64, may_shorten: bool) -> Newton {
        if self.w.stagger.is_some() {
            self.newton_staggered(t, h, may_shorten)
        } else {
            self.iterate(t, h, may_shorten, Phase::Whole)
        }
    }

    /// Scaled norm of the embedded error estimate; NaN if it is not finite.
    pub(super) fn error_norm(&mut self, t: f64, h: f64, refine: bool) -> f64 {
        let part = self.error_part();
        let (n, m) = (self.n, self.m);
        let w = &mut self.w;
        // tmp = (1/h) Σ d_i Z_i,  ez = E(y_n) tmp.
        kernels::error_combination::<K>(&w.z, h, &mut w.tmp, n);
        // With the sensitivities out of the error test, the state's rows
        // alone (`E` of a state and its sensitivities is block diagonal, its
        // first block the state's `E₀`; the sensitivities' weights are zero
        // in the norm, so leaving their rows out adds no term but `+0`).
        let (n, m) = match (part, &w.stagger) {
            (Some(Part::First), Some(st)) => {
                let (size, e) = (st.size, w.e_n.dense().as_slice());
                w.ez[..size].fill(0.0);
                for (j, &v) in w.tmp[..size].iter().enumerate() {
                    for (ez, &ej) in w.ez[..size].iter_mut().zip(&e[j * m..j * m + size]) {
                        *ez += ej * v;
                    }
                }
                (size, size)
            }
            _ => {
                w.e_n.mat_vec(&w.tmp, &mut w.ez);
                (n, m)
            }
        };
        for k in 0..m {
            w.err[k] = w.f0[k] + w.ez[k];
        }
        solve_error(&mut w.stages, &mut w.err, part);
        let mut err = w.weights.norm(&w.err[..n]);
        if err >= 1.0 && refine {
            for k in 0..n {
                w.ys[k] = w.y[k] + w.err[k];
            }
            rhs_for_error(&*self.sys, w.stagger.as_ref(), t, &w.ys[..n], &mut w.fm);
            self.stats.residual_evals += 1;
            for k in 0..m {
                w.err[k] = w.fm[k] + w.ez[k];
            }
            solve_error(&mut w.stages, &mut w.err, part);
            err = w.weights.norm(&w.err[..n]);
        }
        if err.is_nan() {
            f64::NAN
        } else {
            err.max(1e-10)
        }
    }

    /// The algebraic rows of the end-point projection, from `E(y₀)`
    /// (evaluated by the start); only for a method that is not stiffly
    /// accurate.
    ///
    /// The projection makes the end point satisfy the rows of `E` that are
    /// zero: it needs every algebraic condition of the system to be such a
    /// row, i.e. as many zero rows as `E` has null directions
    /// (`m − rank E`). Where an algebraic condition is a combination of
    /// rows that hold derivatives — a loop of capacitors and a voltage
    /// source in a circuit, whose current is fixed only by the sum of the
    /// loop's rows — there are fewer, the projection's matrix is singular,
    /// and the method is refused with that reason
    /// ([`NotApplicable::AlgebraicConditionsNotRows`]) rather than failing
    /// at its first step.
    pub(super) fn find_algebraic_rows(&mut self, info: &FormulationInfo) -> Result<(), SolveError> {
        if !K::TABLEAU.end.projected() || self.w.stages.least_squares() {
            return Ok(());
        }
        let e = self.w.e_n.dense();
        self.w.algebraic = (0..self.m)
            .filter(|&i| {
                matches!(info.rows[i].kind, RowKind::Constraint { .. })
                    && (0..self.n).all(|j| e[(i, j)] == 0.0)
            })
            .collect();
        let scale = e.amax();
        let rank = if scale > 0.0 {
            let tol = 1e3 * f64::EPSILON * scale * self.m.max(self.n) as f64;
            e.clone().svd(false, false).rank(tol)
        } else {
            0
        };
        let null = self.m - rank;
        if self.w.algebraic.len() < null {
            return Err(SolveError::NotApplicable(
                NotApplicable::AlgebraicConditionsNotRows {
                    zero_rows: self.w.algebraic.len(),
                    conditions: null,
                },
            ));
        }
        if self.constant_leading && !self.w.algebraic.is_empty() {
            let zero_columns = zero_columns(e);
            if zero_columns.len() == self.w.algebraic.len() {
                self.w.projection_small = DenseLu::new(zero_columns.len(), Pivoting::Checked);
                self.w.algebraic_unknowns = zero_columns;
            }
        }
        Ok(())
    }

    /// One simplified Newton step that makes the end point of an accepted
    /// step more consistent (a method that is not stiffly accurate, see
    /// [`crate::gauss`]): with `f` and `E` evaluated at the current end
    /// point, `δ` with `E(y_{n+1}) δ = 0` (the differential part kept) and
    /// `f_a(t, y_{n+1}) + J_a δ = 0` on the algebraic rows `a`, `J` the
    /// iteration's Jacobian; `first` says it is the step's first
    /// projection (the matrix is factorised then and kept), `sized` that
    /// the caller needs the size of the correction. With a constant
    /// `E`, `f(t, y_{n+1})` is updated to `f + J δ`, exact where `f` is
    /// linear in the algebraic unknowns and `J` is current; the caller
    /// evaluates `f` again at the new point unless `δ` was negligible.
    ///
    /// Returns the weighted norm of `δ` (0 unless `sized` where `E` is
    /// constant and its zero columns are the algebraic unknowns), by which
    /// the caller iterates to convergence: the iteration's `J` may be the
    /// one of the step's start (or older), and the algebraic rows may be
    /// nonlinear in the unknowns, so one step is not exact in general (the
    /// reactor's `rcd0`, whose coefficient of `TC` changes by a tenth over
    /// a step, and Jay's, with `z²` in its constraint; see
    /// [`crate::gauss`]).
    pub(super) fn project(
        &mut self,
        t: f64,
        h: f64,
        first: bool,
        sized: bool,
    ) -> Result<f64, SolveError> {
        let w = &mut self.w;
        if w.algebraic.is_empty() {
            return Ok(0.0);
        }
        if !w.algebraic_unknowns.is_empty() {
            return self.project_algebraic_unknowns(t, h, first, sized);
        }
        // Column-major: the rows of `E`, then the algebraic rows of `J`.
        let n = self.n;
        // Where the formulation chose other rows over the step (`mex0`'s
        // dummies: the zero pattern of `E` changed), the step's own `E`;
        // otherwise `E(y_{n+1})`, whose null space is the constraints'
        // normal at the new point (`psi0`).
        let chose_other_rows = !self.constant_leading
            && w.e_step
                .iter()
                .zip(w.e_n.values())
                .any(|(a, b)| (*a == 0.0) != (*b == 0.0));
        let e = if chose_other_rows {
            &w.e_step
        } else {
            w.e_n.dense()
        };
        if first || !self.constant_leading {
            w.projection
                .matrix_mut()
                .as_mut_slice()
                .copy_from_slice(e.as_slice());
            let p = w.projection.matrix_mut().as_mut_slice();
            let jac = w.jac.values();
            for &i in &w.algebraic {
                for j in 0..n {
                    p[i + j * n] = jac[i + j * n];
                }
            }
            w.projection
                .factor()
                .map_err(|_| SolveError::SingularMatrix { t, h })?;
        }
        w.delta.fill(0.0);
        for &i in &w.algebraic {
            w.delta[i] = -w.f0[i];
        }
        w.projection.solve(&mut w.delta);
        check_projection(&w.delta, t)?;
        for k in 0..self.n {
            w.correct(k, w.delta[k], self.c.one.compensated);
        }
        let size = w.weights.norm(&w.delta[..self.n]);
        if self.constant_leading {
            mat_vec(w.jac.dense(), &w.delta, &mut w.fm);
            for (f, d) in w.f0.iter_mut().zip(&w.fm) {
                *f += d;
            }
        }
        Ok(size)
    }

    /// Project a value `u` of the dense output at `tau` (inside the step
    /// just accepted) as the end point was projected
    /// ([`Integrator::project`]): the differential part kept, the algebraic
    /// rows `f_a(tau, u) = 0` solved by simplified Newton steps with the
    /// end-point projection's factorised matrix (rows of `E` and of the
    /// iteration's `J`), at most [`OUTPUT_PROJECTION_STEPS`], until the
    /// correction is below the Newton floor. Only for a method that is not
    /// stiffly accurate and has algebraic rows (`gauss` on `rcd0`, `psi0`,
    /// `mex0`): its collocation polynomial meets the constraints at the
    /// nodes only, and between them misses them by its interpolation error,
    /// `O(h⁴)` — 100 times the tolerance on Andrews' squeezer, where the
    /// order-6 step points allow long steps.
    pub(super) fn project_output(&self, tau: f64, u: &mut [f64]) {
        let w = &self.w;
        if w.algebraic.is_empty() {
            return;
        }
        let mut scratch = w.output.borrow_mut();
        let OutputScratch {
            f,
            delta,
            residual_evals,
        } = &mut *scratch;
        for _ in 0..OUTPUT_PROJECTION_STEPS {
            self.sys.rhs(tau, u, f);
            *residual_evals += 1;
            if w.algebraic_unknowns.is_empty() {
                delta.fill(0.0);
                for &i in &w.algebraic {
                    delta[i] = -f[i];
                }
                w.projection.solve(delta);
            } else {
                let k = w.algebraic.len();
                for (m, &i) in delta.iter_mut().zip(&w.algebraic) {
                    *m = -f[i];
                }
                w.projection_small.solve(&mut delta[..k]);
                // Scattered to the algebraic unknowns (`f` is free until
                // the next evaluation).
                f[..k].copy_from_slice(&delta[..k]);
                delta.fill(0.0);
                for (&j, &d) in w.algebraic_unknowns.iter().zip(&f[..k]) {
                    delta[j] = d;
                }
            }
            if !all_finite(delta) {
                return;
            }
            for (x, d) in u.iter_mut().zip(delta.iter()) {
                *x += d;
            }
            // The factorised matrix holds `J` of the step's end (or older),
            // not at `tau`: even where the rows are linear in the
            // algebraic unknowns one step is not exact (the reactor's
            // `rcd0`: a tenth of the correction left over a whole step).
            if w.weights.norm(&delta[..self.n]) <= OUTPUT_PROJECTION_FLOOR {
                return;
            }
        }
    }

    /// [`Integrator::project`] when `E` is constant and its zero columns
    /// are the algebraic unknowns `a` (as `λ` in `rcd0`): `E δ = 0` is
    /// `δ` zero outside `a`, and the algebraic rows `r` give the `k × k`
    /// system `J_ra δ_a = −f_r`; then `f += J_·a δ_a`.
    fn project_algebraic_unknowns(
        &mut self,
        t: f64,
        h: f64,
        first: bool,
        sized: bool,
    ) -> Result<f64, SolveError> {
        let w = &mut self.w;
        let (rows, cols, jac) = (&w.algebraic, &w.algebraic_unknowns, w.jac.dense());
        if first {
            w.projection_small
                .factor_from(|a, b| jac[(rows[a], cols[b])])
                .map_err(|_| SolveError::SingularMatrix { t, h })?;
        }
        let k = rows.len();
        let mu = &mut w.delta[..k];
        for (m, &i) in mu.iter_mut().zip(rows) {
            *m = -w.f0[i];
        }
        w.projection_small.solve(mu);
        check_projection(mu, t)?;
        for a in 0..k {
            let (d, j) = (w.delta[a], w.algebraic_unknowns[a]);
            w.correct(j, d, self.c.one.compensated);
            let col = &w.jac.values()[j * self.m..(j + 1) * self.m];
            for (f, &jij) in w.f0.iter_mut().zip(col) {
                *f += jij * d;
            }
        }
        if !sized {
            return Ok(0.0);
        }
        // The correction's weighted norm, on all `N` unknowns (`tmp` is
        // free after the step's error estimate).
        w.tmp.fill(0.0);
        for (&j, &d) in w.algebraic_unknowns.iter().zip(&w.delta[..k]) {
            w.tmp[j] = d;
        }
        Ok(w.weights.norm(&w.tmp[..self.n]))
    }

    /// Accept the step: `y_{n+1} = y_n + Z_3` (or `Σ END_i Z_i`), the new
    /// collocation polynomial (Newton form, see [`Collocation`]) and
    /// `y'_{n+1}`.
    pub(super) fn advance(&mut self, h: f64) {
        let w = &mut self.w;
        let y_lo = self.c.one.compensated.then_some(&mut w.y_lo[..]);
        kernels::advance::<K>(&w.z, h, &mut w.y, y_lo, &mut w.yp, &mut w.cont);
    }
}

/// The columns of `e` that are zero (at its point, for an `E` that is not
/// constant): the unknowns whose derivative no equation holds.
pub(super) fn zero_columns(e: &DMatrix<f64>) -> Vec<usize> {
    (0..e.ncols())
        .filter(|&j| e.column(j).iter().all(|&x| x == 0.0))
        .collect()
}

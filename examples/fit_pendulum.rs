//! Fitting the pendulum's g and l to noisy observations of its position,
//! with the forward sensitivities (issue 25, done-when 4).
//!
//! The data (`data/fit_pendulum.csv`, written by `scripts/fit_data.py`):
//! the pendulum of `scenes/pendulum.dae` with g = 9.81, l = 1, released at
//! rest from the horizontal, its position (x, y) at t = 0.1, 0.2, …, 4
//! from the Jacobi-elliptic closed form (mpmath), plus Gaussian noise of
//! σ = 0.01 m (seed 25). Nothing here comes from a `dae` run.
//!
//! The fit: Levenberg–Marquardt on the 80 residuals `obs − model(g, l)`.
//! The model and its Jacobian come from one run of the sensitivity system
//! (`dae_core::sensitivity`, radau5 on `ggl1`, tol 1e-10): the residual
//! Jacobian *is* the sensitivities ∂x/∂g, ∂x/∂l, ∂y/∂g, ∂y/∂l at the
//! observation times, read from the dense output with `Solution::at`. The
//! release is given as x = 1, y = 0 at every trial l and projected onto the
//! circle of radius l (the consistent start): x(0) = l, as in the data.
//!
//! Standard errors from `σ² (JᵀJ)⁻¹` with the known σ (and, beside them,
//! from the residual variance `s² = SSR / (m − 2)`), 95 % intervals
//! `±1.96 se`.
//!
//! ```sh
//! cargo run --example fit_pendulum -- [--start G L]
//! ```

use dae::dae_core::sensitivity::{Sensitivities, SensitivityError};
use dae::dae_solvers::{radau5::Radau5, sensitivity::consistent_start, InitOptions};
use dae::prelude::*;

/// The observations: `t, x_exact, y_exact, x_obs, y_obs`.
pub const DATA: &str = include_str!("../data/fit_pendulum.csv");
/// The model (its own g and l are replaced by the fit's).
pub const MODEL: &str = include_str!("../scenes/pendulum.dae");
/// The noise's standard deviation (`scripts/fit_data.py`).
pub const SIGMA: f64 = 0.01;
/// The values the data were made with.
pub const TRUTH: [f64; 2] = [9.81, 1.0];
/// The normal quantile of a two-sided 95 % interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// One observation.
#[derive(Clone, Copy, Debug)]
pub struct Observation {
    /// Time.
    pub t: f64,
    /// Observed x (with noise).
    pub x: f64,
    /// Observed y (with noise).
    pub y: f64,
}

/// Why the fit failed.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The data file is malformed.
    #[error("data/fit_pendulum.csv line {line}: {what}")]
    Data {
        /// 1-based line.
        line: usize,
        /// What is wrong.
        what: String,
    },
    /// The sensitivity system could not be built.
    #[error(transparent)]
    Sensitivity(#[from] SensitivityError),
    /// A run failed.
    #[error("at g = {g}, l = {l}: {source}")]
    Solve {
        /// Gravity tried.
        g: f64,
        /// Length tried.
        l: f64,
        /// The solver's error.
        source: SolveError,
    },
    /// The solution could not be read at an observation time.
    #[error(transparent)]
    Solution(#[from] SolutionError),
    /// No step decreased the sum of squares, however damped.
    #[error("no descent from g = {g}, l = {l} after {iterations} iterations (damping {mu:e})")]
    NoDescent {
        /// Gravity reached.
        g: f64,
        /// Length reached.
        l: f64,
        /// Iterations done.
        iterations: usize,
        /// The damping reached.
        mu: f64,
    },
    /// `JᵀJ` is singular: g and l are not identifiable from these data.
    #[error("JᵀJ is singular at g = {g}, l = {l}")]
    Singular {
        /// Gravity.
        g: f64,
        /// Length.
        l: f64,
    },
}

/// The result of a fit.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The estimates `[g, l]`.
    pub estimate: [f64; 2],
    /// Standard errors from `σ² (JᵀJ)⁻¹`, the known σ.
    pub se: [f64; 2],
    /// Standard errors from `s² (JᵀJ)⁻¹`, `s² = SSR / (m − 2)`.
    pub se_residual: [f64; 2],
    /// Correlation of the two estimates.
    pub correlation: f64,
    /// The sum of squared residuals at the estimate.
    pub ssr: f64,
    /// Accepted Levenberg–Marquardt iterations.
    pub iterations: usize,
    /// Sensitivity runs made (each trial point is one).
    pub runs: usize,
    /// `(g, l, SSR)` at the start and after each accepted iteration.
    pub path: Vec<(f64, f64, f64)>,
}

/// The observations of `data/fit_pendulum.csv`.
pub fn observations(src: &str) -> Result<Vec<Observation>, FitError> {
    let mut out = Vec::new();
    for (i, line) in src.lines().enumerate() {
        if line.starts_with('#') || line.starts_with("t,") || line.trim().is_empty() {
            continue;
        }
        let bad = |what: String| FitError::Data { line: i + 1, what };
        let f: Vec<f64> = line
            .split(',')
            .map(|s| {
                s.trim()
                    .parse::<f64>()
                    .map_err(|e| bad(format!("`{s}`: {e}")))
            })
            .collect::<Result<_, _>>()?;
        if f.len() != 5 {
            return Err(bad(format!("{} fields, expected 5", f.len())));
        }
        out.push(Observation {
            t: f[0],
            x: f[3],
            y: f[4],
        });
    }
    Ok(out)
}

/// The residuals `obs − model` (x then y at each time) and their Jacobian
/// with respect to `[g, l]` (`−∂model/∂p`), from one sensitivity run.
fn residuals(
    model: &mut Sensitivities,
    p: [f64; 2],
    obs: &[Observation],
) -> Result<(Vec<f64>, Vec<[f64; 2]>), FitError> {
    let [g, l] = p;
    model.set_parameter("g", g)?;
    model.set_parameter("l", l)?;
    let sys = model.formulation("ggl1")?;
    let solve_error = |source| FitError::Solve { g, l, source };
    // Released at rest from the horizontal: x = 1 is projected onto the
    // circle of radius l, the sensitivities onto the linearised constraints.
    let mut y0 = vec![0.0; sys.info().unknowns()];
    y0[0] = 1.0;
    let start = consistent_start(&sys, 0.0, &y0, &InitOptions::default()).map_err(solve_error)?;
    let t_end = obs.iter().map(|o| o.t).fold(0.0, f64::max);
    let problem = Problem {
        system: &sys,
        t0: 0.0,
        y0: &start.y,
        t_end,
    };
    let sol = Radau5
        .solve(&problem, &Options::with_tol(1e-10))
        .map_err(solve_error)?;
    let ix = |n: &str| sol.index_of(n);
    let (x, y) = (ix("x")?, ix("y")?);
    let (xg, xl, yg, yl) = (ix("dx/dg")?, ix("dx/dl")?, ix("dy/dg")?, ix("dy/dl")?);
    let mut r = Vec::with_capacity(2 * obs.len());
    let mut jac = Vec::with_capacity(2 * obs.len());
    for o in obs {
        let u = sol.at(o.t)?;
        r.push(o.x - u[x]);
        jac.push([-u[xg], -u[xl]]);
        r.push(o.y - u[y]);
        jac.push([-u[yg], -u[yl]]);
    }
    Ok((r, jac))
}

/// `JᵀJ` and `Jᵀr`.
fn normal_equations(r: &[f64], jac: &[[f64; 2]]) -> ([[f64; 2]; 2], [f64; 2]) {
    let mut a = [[0.0; 2]; 2];
    let mut b = [0.0; 2];
    for (ri, ji) in r.iter().zip(jac) {
        for i in 0..2 {
            b[i] += ji[i] * ri;
            for j in 0..2 {
                a[i][j] += ji[i] * ji[j];
            }
        }
    }
    (a, b)
}

/// The inverse of a symmetric 2×2 matrix, `None` when singular to
/// round-off.
fn inverse(a: [[f64; 2]; 2]) -> Option<[[f64; 2]; 2]> {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let scale = a[0][0].abs() * a[1][1].abs();
    if !(det.is_finite() && det.abs() > 1e-14 * scale) {
        return None;
    }
    Some([
        [a[1][1] / det, -a[0][1] / det],
        [-a[1][0] / det, a[0][0] / det],
    ])
}

fn sum_sq(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Levenberg–Marquardt (Marquardt's scaling, `JᵀJ + μ diag(JᵀJ)`) from
/// `start = [g, l]`, until a step changes neither parameter by more than
/// `1e-9` relative; then the standard errors at the estimate.
pub fn fit(obs: &[Observation], start: [f64; 2], sigma: f64) -> Result<Fit, FitError> {
    let mut model = Sensitivities::from_str(MODEL, &["g", "l"])?;
    let mut p = start;
    let (mut r, mut jac) = residuals(&mut model, p, obs)?;
    let mut ssr = sum_sq(&r);
    let mut path = vec![(p[0], p[1], ssr)];
    let mut mu = 1e-3;
    let mut runs = 1;
    let mut iterations = 0;
    let max_iterations = 100;
    // `jac` is ∂r/∂p: the Gauss–Newton step is −(JᵀJ)⁻¹Jᵀr, damped by μ.
    let step_of = |a: [[f64; 2]; 2], b: [f64; 2], mu: f64| {
        let damped = [
            [a[0][0] * (1.0 + mu), a[0][1]],
            [a[1][0], a[1][1] * (1.0 + mu)],
        ];
        inverse(damped).map(|inv| {
            [
                -(inv[0][0] * b[0] + inv[0][1] * b[1]),
                -(inv[1][0] * b[0] + inv[1][1] * b[1]),
            ]
        })
    };
    loop {
        let (a, b) = normal_equations(&r, &jac);
        // Converged when the undamped step moves neither parameter by more
        // than 1e-9 relative.
        let gn = step_of(a, b, 0.0).ok_or(FitError::Singular { g: p[0], l: p[1] })?;
        if gn.iter().zip(&p).all(|(s, v)| s.abs() <= 1e-9 * v.abs()) {
            break;
        }
        let no_descent = |p: [f64; 2], mu: f64| FitError::NoDescent {
            g: p[0],
            l: p[1],
            iterations,
            mu,
        };
        if iterations >= max_iterations {
            return Err(no_descent(p, mu));
        }
        loop {
            if mu > 1e12 {
                return Err(no_descent(p, mu));
            }
            let Some(step) = step_of(a, b, mu) else {
                mu *= 10.0;
                continue;
            };
            let trial = [p[0] + step[0], p[1] + step[1]];
            if trial.iter().all(|v| *v > 0.0) {
                runs += 1;
                // A trial that cannot be integrated is a step too long.
                if let Ok((r_new, jac_new)) = residuals(&mut model, trial, obs) {
                    let ssr_new = sum_sq(&r_new);
                    if ssr_new <= ssr {
                        (p, r, jac, ssr) = (trial, r_new, jac_new, ssr_new);
                        mu = (mu / 10.0).max(1e-12);
                        break;
                    }
                }
            }
            mu *= 10.0;
        }
        iterations += 1;
        path.push((p[0], p[1], ssr));
    }
    let (a, _) = normal_equations(&r, &jac);
    let cov = inverse(a).ok_or(FitError::Singular { g: p[0], l: p[1] })?;
    let s2 = ssr / (r.len() as f64 - 2.0);
    let se = [cov[0][0].sqrt() * sigma, cov[1][1].sqrt() * sigma];
    Ok(Fit {
        estimate: p,
        se,
        se_residual: [(cov[0][0] * s2).sqrt(), (cov[1][1] * s2).sqrt()],
        correlation: cov[0][1] / (cov[0][0] * cov[1][1]).sqrt(),
        ssr,
        iterations,
        runs,
        path,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut start = [8.0, 1.3];
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.as_slice() {
        [] => {}
        [flag, g, l] if flag == "--start" => start = [g.parse()?, l.parse()?],
        _ => return Err("usage: fit_pendulum [--start G L]".into()),
    }
    let obs = observations(DATA)?;
    println!(
        "{} observations of (x, y) at t = {} … {} s, σ = {SIGMA} m; start g = {}, l = {}",
        obs.len(),
        obs[0].t,
        obs[obs.len() - 1].t,
        start[0],
        start[1]
    );
    let fit = fit(&obs, start, SIGMA)?;
    println!("iteration        g              l          sum of squares");
    for (k, (g, l, ssr)) in fit.path.iter().enumerate() {
        println!("{k:>9}  {g:>13.9}  {l:>13.10}  {ssr:>14.6e}");
    }
    println!(
        "{} iterations, {} sensitivity runs (radau5, ggl1, tol 1e-10)",
        fit.iterations, fit.runs
    );
    println!(
        "residual s = {:.5} m (σ = {SIGMA}); correlation of the estimates {:.3}",
        (fit.ssr / (2.0 * obs.len() as f64 - 2.0)).sqrt(),
        fit.correlation
    );
    println!(
        "param   estimate      std. error  (from s)     95 % interval               true    inside"
    );
    for (k, name) in ["g", "l"].iter().enumerate() {
        let (est, se) = (fit.estimate[k], fit.se[k]);
        let (lo, hi) = (est - Z95 * se, est + Z95 * se);
        let inside = (lo..=hi).contains(&TRUTH[k]);
        println!(
            "{name:<5} {est:>11.6}  {se:>11.2e}  ({:>9.2e})  [{lo:.6}, {hi:.6}]  {:>6}  {}",
            fit.se_residual[k],
            TRUTH[k],
            if inside { "yes" } else { "NO" }
        );
    }
    Ok(())
}

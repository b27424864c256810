//! Fitting the pendulum's g and l to 50 noisy samples of x(t), with the
//! forward sensitivities and the `levenberg-marquardt` crate (issue 25,
//! item 4 and done-when 4).
//!
//! The data (`data/fit_pendulum.csv`, written by `scripts/fit_data.py`):
//! the pendulum of `scenes/pendulum.dae` with g = 9.81, l = 1, released at
//! rest from the horizontal, its horizontal position x at t = 0.1, 0.2, …,
//! 5 (about two periods) from the Jacobi-elliptic closed form (mpmath),
//! plus Gaussian noise of σ = 0.01 m (seed 25). Only x is observed; y is in
//! the file beside the exact x as a check. Nothing here comes from a `dae`
//! run.
//!
//! **Why x(t) alone determines both g and l.** The release is at rest from
//! the horizontal, x(0) = l, y(0) = 0, at every trial l: the amplitude of
//! x is l, and the angle swept, π/2 either side, is fixed by the release,
//! so the motion is θ(t) = Θ(t √(g/l)) with one dimensionless function Θ.
//! The amplitude of x(t) = l sin Θ(t √(g/l)) gives l, its period
//! T = 4 √(l/g) K(1/2) gives g/l; together g and l. (Released from rest at
//! an angle that scaled with l, or observed through the angle alone, only
//! g/l would be identifiable and `JᵀJ` singular.) The fit below reports the
//! correlation of the two estimates: large, as l enters both, but below 1.
//!
//! The fit: `levenberg_marquardt::LevenbergMarquardt` (rust-cv, MINPACK's
//! `lmder` in Rust, on nalgebra) on the 50 residuals `x_obs − x(t; g, l)`.
//! The model and its Jacobian come from one run of the sensitivity system
//! (`dae_core::sensitivity`, radau5 on `ggl1`, tol 1e-10) per trial point:
//! the residual Jacobian *is* −∂x/∂g, −∂x/∂l at the observation times, read
//! from the dense output with `Solution::at`. The release is given as
//! x = 1, y = 0 at every trial l and projected onto the circle of radius l
//! (the consistent start): x(0) = l, as in the data.
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
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DVector, Dyn, OMatrix, Vector2, U2};

/// The observations: `t, x_exact, y_exact, x_obs`.
pub const DATA: &str = include_str!("../data/fit_pendulum.csv");
/// The model (its own g and l are replaced by the fit's).
pub const MODEL: &str = include_str!("../scenes/pendulum.dae");
/// The noise's standard deviation (`scripts/fit_data.py`).
pub const SIGMA: f64 = 0.01;
/// The values the data were made with.
pub const TRUTH: [f64; 2] = [9.81, 1.0];
/// The normal quantile of a two-sided 95 % interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// One observation of x.
#[derive(Clone, Copy, Debug)]
pub struct Observation {
    /// Time.
    pub t: f64,
    /// Observed x (with noise).
    pub x: f64,
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
    /// A trial point left the physical region (g ≤ 0 or l ≤ 0).
    #[error("trial point g = {g}, l = {l} is not physical")]
    NotPhysical {
        /// Gravity tried.
        g: f64,
        /// Length tried.
        l: f64,
    },
    /// Levenberg–Marquardt stopped without converging.
    #[error(
        "Levenberg–Marquardt stopped at g = {g}, l = {l} after {evaluations} evaluations: {reason}"
    )]
    NotConverged {
        /// Gravity reached.
        g: f64,
        /// Length reached.
        l: f64,
        /// Residual evaluations made.
        evaluations: usize,
        /// The crate's termination reason.
        reason: String,
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
    /// Residual evaluations counted by the crate.
    pub evaluations: usize,
    /// The crate's termination reason.
    pub termination: String,
    /// Sensitivity runs made (each trial point and each reset is one).
    pub runs: usize,
    /// `(g, l, SSR)` at every point run, in order (the first is the start).
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
        if f.len() != 4 {
            return Err(bad(format!("{} fields, expected 4", f.len())));
        }
        out.push(Observation { t: f[0], x: f[3] });
    }
    Ok(out)
}

/// The residuals and their Jacobian with respect to `[g, l]`.
type Linearised = (DVector<f64>, OMatrix<f64, Dyn, U2>);

/// The residuals `obs − x(t; g, l)` and their Jacobian with respect to
/// `[g, l]` (`−∂x/∂p`), from one sensitivity run.
fn residuals(
    model: &mut Sensitivities,
    p: [f64; 2],
    obs: &[Observation],
) -> Result<Linearised, FitError> {
    let [g, l] = p;
    if !(g > 0.0 && l > 0.0) {
        return Err(FitError::NotPhysical { g, l });
    }
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
    let (x, xg, xl) = (
        sol.index_of("x")?,
        sol.index_of("dx/dg")?,
        sol.index_of("dx/dl")?,
    );
    let mut r = DVector::zeros(obs.len());
    let mut jac = OMatrix::<f64, Dyn, U2>::zeros(obs.len());
    for (i, o) in obs.iter().enumerate() {
        let u = sol.at(o.t)?;
        r[i] = o.x - u[x];
        jac[(i, 0)] = -u[xg];
        jac[(i, 1)] = -u[xl];
    }
    Ok((r, jac))
}

/// The least-squares problem as the crate sees it: `set_params` runs the
/// sensitivity system once and keeps the residuals and their Jacobian.
/// The crate's parameters are `(ln g, ln l)`: every trial point is
/// physical (a step in g itself from a far start can cross zero), and the
/// Jacobian is the sensitivities times g and l. The estimate and its
/// covariance are reported in g and l (at the minimum, `JᵀJ` in g, l is
/// the one in ln g, ln l scaled by `diag(1/g, 1/l)`: the same linearised
/// intervals).
struct PendulumFit<'a> {
    model: Sensitivities,
    obs: &'a [Observation],
    p: Vector2<f64>,
    /// The last run's residuals and Jacobian, or why it failed.
    last: Result<Linearised, FitError>,
    /// The first failure (the crate stops at a `None`), kept for the report.
    failure: Option<FitError>,
    runs: usize,
    path: Vec<(f64, f64, f64)>,
}

impl PendulumFit<'_> {
    /// Takes the last run's result out, leaving a placeholder.
    fn take_last(&mut self) -> Result<Linearised, FitError> {
        let placeholder = FitError::NotPhysical {
            g: self.p[0],
            l: self.p[1],
        };
        std::mem::replace(&mut self.last, Err(placeholder))
    }

    fn run(&mut self) {
        let p = [self.p[0], self.p[1]];
        self.runs += 1;
        self.last = residuals(&mut self.model, p, self.obs);
        match &self.last {
            Ok((r, _)) => self.path.push((p[0], p[1], r.norm_squared())),
            Err(e) => {
                if self.failure.is_none() {
                    self.failure = Some(FitError::NotConverged {
                        g: p[0],
                        l: p[1],
                        evaluations: self.runs,
                        reason: e.to_string(),
                    });
                }
            }
        }
    }
}

impl LeastSquaresProblem<f64, Dyn, U2> for PendulumFit<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, U2>;
    type ParameterStorage = Owned<f64, U2>;

    fn set_params(&mut self, q: &Vector2<f64>) {
        self.p = q.map(f64::exp);
        self.run();
    }

    fn params(&self) -> Vector2<f64> {
        self.p.map(f64::ln)
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.last.as_ref().ok().map(|(r, _)| r.clone())
    }

    /// `∂r/∂(ln g, ln l) = (g ∂r/∂g, l ∂r/∂l)`.
    fn jacobian(&self) -> Option<OMatrix<f64, Dyn, U2>> {
        let p = self.p;
        self.last.as_ref().ok().map(|(_, j)| {
            let mut j = j.clone();
            j.column_mut(0).scale_mut(p[0]);
            j.column_mut(1).scale_mut(p[1]);
            j
        })
    }
}

/// Levenberg–Marquardt (the `levenberg-marquardt` crate, Moré's trust-region
/// form with scaled diagonal) in `(ln g, ln l)` from `start = [g, l]`;
/// `xtol = 1e-8`, `ftol = 1e-10` (the runs are accurate to about 1e-10;
/// tighter tolerances only make the crate wander in the integration's
/// error, about 1e-8 relative in g and l, far inside a standard error of
/// 2e-3 relative); then the standard errors at the estimate.
pub fn fit(obs: &[Observation], start: [f64; 2], sigma: f64) -> Result<Fit, FitError> {
    let model = Sensitivities::from_str(MODEL, &["g", "l"])?;
    let mut problem = PendulumFit {
        model,
        obs,
        p: Vector2::new(start[0], start[1]),
        last: Err(FitError::NotPhysical {
            g: start[0],
            l: start[1],
        }),
        failure: None,
        runs: 0,
        path: Vec::new(),
    };
    problem.run();
    // The start itself cannot be run: say why, not the crate's "residuals".
    let first = problem.take_last()?;
    problem.last = Ok(first);
    let (mut problem, report) = LevenbergMarquardt::new()
        .with_xtol(1e-8)
        .with_ftol(1e-10)
        .minimize(problem);
    let p = [problem.p[0], problem.p[1]];
    if !report.termination.was_successful() {
        return Err(problem.failure.take().unwrap_or(FitError::NotConverged {
            g: p[0],
            l: p[1],
            evaluations: report.number_of_evaluations,
            reason: format!("{:?}", report.termination),
        }));
    }
    // The crate leaves the problem at its best point, last run there.
    let (r, jac) = problem.take_last()?;
    let ssr = r.norm_squared();
    let cov = (jac.transpose() * &jac)
        .try_inverse()
        .filter(|c| c.iter().all(|v| v.is_finite()))
        .ok_or(FitError::Singular { g: p[0], l: p[1] })?;
    let s2 = ssr / (r.len() as f64 - 2.0);
    Ok(Fit {
        estimate: p,
        se: [cov[(0, 0)].sqrt() * sigma, cov[(1, 1)].sqrt() * sigma],
        se_residual: [(cov[(0, 0)] * s2).sqrt(), (cov[(1, 1)] * s2).sqrt()],
        correlation: cov[(0, 1)] / (cov[(0, 0)] * cov[(1, 1)]).sqrt(),
        ssr,
        evaluations: report.number_of_evaluations,
        termination: format!("{:?}", report.termination),
        runs: problem.runs,
        path: problem.path,
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
        "{} observations of x at t = {} … {} s, σ = {SIGMA} m; start g = {}, l = {}",
        obs.len(),
        obs[0].t,
        obs[obs.len() - 1].t,
        start[0],
        start[1]
    );
    let fit = fit(&obs, start, SIGMA)?;
    println!("      run        g              l          sum of squares");
    for (k, (g, l, ssr)) in fit.path.iter().enumerate() {
        println!("{k:>9}  {g:>13.9}  {l:>13.10}  {ssr:>14.6e}");
    }
    println!(
        "levenberg-marquardt: {}, {} evaluations; {} sensitivity runs (radau5, ggl1, tol 1e-10)",
        fit.termination, fit.evaluations, fit.runs
    );
    println!(
        "residual s = {:.5} m (σ = {SIGMA}); correlation of the estimates {:.3}",
        (fit.ssr / (obs.len() as f64 - 2.0)).sqrt(),
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

//! DAE integrators over the [`dae_core::system::DaeSystem`] trait.
//!
//! Shared pieces live in their own modules — [`options`] (tolerances and
//! error weights), [`stats`], [`solution`], [`error`], and the dense LU
//! factorisation both solvers use (`linalg`, crate-private) — and each
//! method family in one module: [`radau5`] (Radau IIA, order 5, after RADAU5
//! of Hairer & Wanner) and [`bdf`] (variable order BDF in fixed-leading-
//! coefficient form, after DASSL/DASPK). [`init`] computes consistent initial
//! values from the model's constraint chain, and the initial derivative the
//! BDF solver starts from.
//!
//! Every solver returns `Result<Solution, SolveError>` and never panics on a
//! user's problem; no allocation happens inside the step loop.

pub mod bdf;
pub mod error;
pub mod init;
mod linalg;
pub mod options;
pub mod radau5;
pub mod solution;
pub mod stats;

pub use error::SolveError;
pub use init::{consistent, initial_derivative, InitMode, InitOptions};
pub use options::{Options, Tolerances};
pub use solution::Solution;
pub use stats::Stats;

use dae_core::system::{DaeSystem, FormulationInfo};

/// An initial value problem: a formulation, a consistent start, a horizon.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    /// The formulation to integrate.
    pub system: &'a dyn DaeSystem,
    /// Initial time.
    pub t0: f64,
    /// Consistent initial values (length N), e.g. from [`init::consistent`].
    pub y0: &'a [f64],
    /// End of the horizon (`t_end > t0`).
    pub t_end: f64,
}

impl Problem<'_> {
    /// `options` valid for `n` unknowns over this horizon, and `y0` `n`
    /// finite values.
    pub(crate) fn check(&self, n: usize, options: &Options) -> Result<(), SolveError> {
        options.validate(n, self.t0, self.t_end)?;
        if self.y0.len() != n {
            return Err(SolveError::invalid(format!(
                "y0 has {} components, the system has {n} unknowns",
                self.y0.len()
            )));
        }
        if self.y0.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                t: self.t0,
                what: "initial values",
            });
        }
        Ok(())
    }
}

/// [`Solver::accepts`] of a solver for square systems only (all of this
/// crate's).
fn accepts_square(info: &FormulationInfo) -> Result<(), String> {
    if info.is_overdetermined() {
        return Err("overdetermined: solver needs a square system".into());
    }
    Ok(())
}

/// A DAE integrator.
pub trait Solver {
    /// Short name used on the command line (`radau5`, `bdf`, …).
    fn name(&self) -> &'static str;
    /// `Ok` when the solver can integrate this formulation at all; otherwise
    /// the reason, e.g. "overdetermined: solver needs a square system".
    fn accepts(&self, info: &FormulationInfo) -> Result<(), String>;
    /// Integrate from `t0` to `t_end`, reporting the solution at
    /// `options.output_times` (dense output, not step-size clipping).
    fn solve(&self, problem: &Problem<'_>, options: &Options) -> Result<Solution, SolveError>;
}

/// All solvers of this crate, by name.
pub fn solver_by_name(name: &str) -> Option<Box<dyn Solver + Send + Sync>> {
    match name {
        "radau5" => Some(Box::new(radau5::Radau5)),
        "bdf" => Some(Box::new(bdf::Bdf)),
        _ => None,
    }
}

/// Names of all solvers, in report order.
pub const SOLVER_NAMES: [&str; 2] = ["radau5", "bdf"];

//! DAE integrators over the [`dae_core::system::DaeSystem`] trait.
//!
//! One integrator [`core`] — error weights and the one norm, the Newton
//! contraction monitor, square and least-squares linear algebra behind one
//! interface, step-size limits and failure budgets, the output grid, the
//! defaults a formulation implies ([`core::policy`]) — and one module per
//! method family, holding only what is particular to it:
//!
//! | solver | method | formulations |
//! |---|---|---|
//! | [`radau5`] | Radau IIA order 5 (RADAU5, Hairer & Wanner) | square, index ≤ 3 |
//! | [`bdf`] | BDF orders 1–5, fixed leading coefficient (DASSL/DASPK) | square |
//! | [`odradau`] | Radau IIA 5 with least-squares stage equations (QUALIDAES/GEOMS) | `M ≥ N`, c-level ≤ 1 |
//! | [`odbdf`] | BDF 1–5 with a least-squares corrector (ODASSL/OVDBDF) | `M ≥ N`, c-level 0 |
//! | [`mebdf`] | modified extended BDF orders 1–8 (Cash's MEBDF/MEBDFDAE) | square, constant `E` |
//! | [`idec`] | linearly implicit Euler + iterated defect correction (Somali) | square, constant `E`, index ≤ 2 |
//! | [`gauss`] | Gauss–Legendre order 6, symmetric, quasi-constant step | square, index ≤ 1 |
//!
//! [`init`] computes consistent initial values from the model's constraint
//! chain, and the initial derivative BDF starts from. A model written with a
//! mass matrix keeps `der(v)` in the acceleration level of its constraints;
//! radau5, bdf, odradau, odbdf and gauss integrate such a formulation with
//! those rows made algebraic (`core/eliminate.rs`: `v'` eliminated with the
//! dynamics rows, numerically, at every evaluation), which is the same
//! solution of a semi-explicit index-1 system. Every solver returns
//! `Result<Solution, SolveError>` and never panics on a user's problem; no
//! allocation happens inside the step loop but the records asked for (step
//! points, the dense output: amortised pushes). [`Solver::accepts`] says, typed,
//! why a solver cannot take a formulation.
//!
//! A [`Solution`] keeps the dense output of every accepted step
//! ([`Options::dense_output`]): [`Solution::at`] answers at any time of the
//! horizon, [`Solution::value`] and [`Solution::component`] by the
//! unknowns' names. [`Solver::integrator`] is the same integration step by
//! step ([`Integrator::step`], [`Integrator::advance_to`]); `solve` is that
//! stepper run to the end.

#![warn(missing_docs)]

pub mod bdf;
pub(crate) mod collocation;
pub mod core;
pub mod error;
pub mod gauss;
pub mod idec;
pub mod init;
pub mod integrator;
mod linalg;
pub mod mebdf;
pub(crate) mod multistep;
pub mod odbdf;
pub mod odradau;
pub mod options;
pub mod radau5;
pub mod sensitivity;
pub mod solution;
pub mod stats;
#[cfg(test)]
pub(crate) mod test_models;

pub use core::events::{Crossing, Direction, Event, EventAction, EventSpec, Reset, ResetReport};
pub use error::{InitError, NotApplicable, SolutionError, SolveError, Stopped};
pub use init::{consistent, consistent_from, initial_derivative, InitMode, InitOptions, Start};
pub use integrator::{Integrator, StepOutcome};
pub use options::{Options, Tol, Tolerances};
pub use solution::{DenseOutput, Solution};
pub use stats::Stats;

use dae_core::system::{DaeSystem, FormulationInfo};

/// An initial value problem: a formulation, a consistent start, a horizon.
///
/// ```
/// use dae::dae_solvers::init;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd1();
/// // The start must be consistent: computed from the positions.
/// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
/// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 20.0 };
/// assert_eq!(problem.y0.len(), sys.info().unknowns());
/// # Ok::<(), SolveError>(())
/// ```
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
        // The event rules name the model's events and unknowns.
        core::events::Events::new(self.system, options, self.t0, self.y0)?;
        Ok(())
    }
}

/// A DAE integrator.
///
/// Solvers are also found by name, and say (typed) which formulations they
/// cannot take:
///
/// ```
/// use dae::dae_solvers::{solver_by_name, NotApplicable, SOLVER_NAMES};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let ovd0 = Pendulum::default().ovd0(); // overdetermined: 8 equations, 5 unknowns
/// for name in SOLVER_NAMES {
///     let solver = solver_by_name(name).unwrap();
///     match solver.accepts(ovd0.info()) {
///         Ok(()) => println!("{name} integrates ovd0"),
///         Err(why) => println!("{name}: {why}"),
///     }
/// }
/// let radau5 = solver_by_name("radau5").unwrap();
/// assert!(matches!(radau5.accepts(ovd0.info()), Err(NotApplicable::Overdetermined { .. })));
/// assert!(solver_by_name("odradau").unwrap().accepts(ovd0.info()).is_ok());
/// ```
pub trait Solver {
    /// Short name used on the command line (`radau5`, `bdf`, …).
    fn name(&self) -> &'static str;
    /// `Ok` when the solver can integrate this formulation at all; otherwise
    /// the typed reason, e.g. [`NotApplicable::Overdetermined`].
    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable>;
    /// The integration of `problem` as a stepper, started at `t0` (the
    /// checks done, the first step chosen): advance it one accepted step at
    /// a time or up to a time, read `t`, `y` and the statistics between
    /// steps (see [`Integrator`]). Running it to the end is
    /// [`Solver::solve`].
    ///
    /// Every solver supports it, also with a constant step
    /// ([`Options::fixed_step`]), where bdf, odbdf and mebdf step through
    /// their adaptive start-up run first.
    fn integrator<'a>(
        &self,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<Integrator<'a>, SolveError>;

    /// Integrate from `t0` to `t_end`, reporting the solution at
    /// `options.output_times` (dense output, not step-size clipping), and
    /// keeping the dense output of every step for [`Solution::at`] when
    /// [`Options::dense_output`] is on. This is [`Solver::integrator`] run
    /// to the end ([`Integrator::finish`]).
    ///
    /// A reset event ([`EventAction::Reset`]) restarts the integration
    /// at the event with a fresh stepper, as [`Solver::run`] does.
    fn solve(&self, problem: &Problem<'_>, options: &Options) -> Result<Solution, SolveError> {
        self.run(problem, options).map_err(|stopped| stopped.error)
    }

    /// [`Solver::solve`], and when the run stops before `t_end`, the error
    /// with the work done until then ([`Stopped`]: the work counters, the
    /// time and values of the last accepted step). A run refused before
    /// its first step (invalid input, a start that cannot be evaluated)
    /// reports no work, at `t0` with `y0`.
    ///
    /// ```
    /// use dae::dae_solvers::bdf::Bdf;
    /// use dae::models::builtin::Pendulum;
    /// use dae::prelude::*;
    ///
    /// let sys = Pendulum::default().rcd0();
    /// let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
    /// let problem = Problem { system: &sys, t0: 0.0, y0: &y0, t_end: 20.0 };
    /// let options = Options { max_steps: 40, ..Options::with_tol(1e-6) };
    /// let stopped = Bdf.run(&problem, &options).unwrap_err();
    /// assert_eq!(stopped.error.kind(), "step_limit");
    /// assert!(stopped.stats.steps > 0 && stopped.stats.residual_evals > 0);
    /// assert!(stopped.t > 0.0);
    /// ```
    ///
    /// After a reset event ([`EventAction::Reset`]) the integration
    /// restarts at the event from the consistent values the reset made
    /// ([`Event::reset`]), with a fresh stepper of this solver
    /// ([`Solver::integrator`]): the solution is the runs joined (output
    /// times, step points, dense output, events; the work counters
    /// summed). Each run has the budget [`Options::max_steps`]; more than
    /// [`core::events::MAX_RESETS`] restarts is
    /// [`SolveError::TooManyResets`].
    fn run(&self, problem: &Problem<'_>, options: &Options) -> Result<Solution, Box<Stopped>> {
        let refused = |error: SolveError, t: f64, y: &[f64], stats: Stats| {
            Box::new(Stopped {
                error,
                stats,
                t,
                y: y.to_vec(),
            })
        };
        let (mut solution, mut restart) = match self.integrator(problem, options) {
            Ok(integrator) => integrator.run_segment()?,
            Err(error) => return Err(refused(error, problem.t0, problem.y0, Stats::default())),
        };
        let mut resets = 0;
        while let Some((t0, y0, fired)) = restart.take() {
            resets += 1;
            if resets > core::events::MAX_RESETS {
                let error = SolveError::TooManyResets { t: t0, resets };
                return Err(refused(error, t0, &y0, solution.stats));
            }
            let later = Problem {
                t0,
                y0: &y0,
                ..*problem
            };
            let mut integrator = match self.integrator(&later, options) {
                Ok(integrator) => integrator,
                Err(error) => return Err(refused(error, t0, &y0, solution.stats)),
            };
            integrator.mask_events(&fired);
            match integrator.run_segment() {
                Ok((next, again)) => {
                    solution.append(next);
                    restart = again;
                }
                Err(mut stopped) => {
                    stopped.stats += solution.stats;
                    return Err(stopped);
                }
            }
        }
        Ok(solution)
    }
}

/// All solvers of this crate, by name.
pub fn solver_by_name(name: &str) -> Option<Box<dyn Solver + Send + Sync>> {
    match name {
        "radau5" => Some(Box::new(radau5::Radau5)),
        "bdf" => Some(Box::new(bdf::Bdf)),
        "odradau" => Some(Box::new(odradau::OdRadau)),
        "odbdf" => Some(Box::new(odbdf::OdBdf)),
        "mebdf" => Some(Box::new(mebdf::Mebdf)),
        "idec" => Some(Box::new(idec::Idec::default())),
        "gauss" => Some(Box::new(gauss::Gauss)),
        _ => None,
    }
}

/// Names of all solvers, in report order.
pub const SOLVER_NAMES: [&str; 7] = [
    "radau5", "bdf", "odradau", "odbdf", "mebdf", "idec", "gauss",
];

//! Typed solver errors.

use serde::Serialize;

/// Why an integration stopped.
///
/// Every solver returns these instead of panicking; [`SolveError::kind`]
/// and [`SolveError::t`] are the machine-readable parts:
///
/// ```
/// use dae::dae_solvers::radau5::Radau5;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd0();
/// let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
/// let problem = Problem { system: &sys, t0: 0.0, y0: &y0, t_end: 20.0 };
/// // Too few steps allowed for the horizon: a typed error, not a panic.
/// let options = Options { max_steps: 10, ..Options::with_tol(1e-8) };
/// let err = Radau5.solve(&problem, &options).unwrap_err();
/// assert!(matches!(err, SolveError::StepLimit { max_steps: 10, .. }));
/// assert_eq!(err.kind(), "step_limit");
/// assert!(err.t().unwrap() < 20.0);
/// // A negative tolerance is refused before any work, naming it.
/// let err = Radau5.solve(&problem, &Options::with_tol(-1e-6)).unwrap_err();
/// assert_eq!(err.kind(), "invalid_input");
/// assert_eq!(err.t(), None);
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SolveError {
    /// The step size fell below the round-off limit at `t`.
    #[error("step size too small at t = {t:e}: h = {h:e}")]
    StepSizeTooSmall {
        /// Time reached.
        t: f64,
        /// Step size tried last.
        h: f64,
    },
    /// Newton iteration failed repeatedly (divergence or too slow
    /// convergence) even after step-size reductions.
    #[error("Newton iteration failed at t = {t:e} with h = {h:e} after {iterations} iterations")]
    NewtonFailure {
        /// Time reached.
        t: f64,
        /// Step size tried last.
        h: f64,
        /// Iterations in the last attempt.
        iterations: usize,
    },
    /// The Newton iterations of one step failed with increments that did
    /// not shrink as the step was cut from `h_from` to `h`: the arithmetic
    /// cannot determine `unknown` to its tolerance there — the round-off of
    /// its residual is of the tolerance's size or larger (or an
    /// inconsistency that no step resolves) — so a shorter step cannot help
    /// ([`crate::Options`]: loosen that unknown's tolerance, or choose a
    /// formulation that keeps it out of the error test).
    #[error(
        "at t = {t:e} the Newton increments of `{unknown}` stall at {level:.2} of its tolerance for every step from h = {h_from:e} down to {h:e}: round-off in its equations is at the tolerance's size, so no step size can meet it; loosen that unknown's tolerance"
    )]
    RoundOffFloor {
        /// Time reached.
        t: f64,
        /// Step size tried last.
        h: f64,
        /// Step size of the first stalled attempt.
        h_from: f64,
        /// The unknown with the largest weighted increment of the last
        /// attempt.
        unknown: String,
        /// That attempt's last increment, weighted (1 = the tolerance).
        level: f64,
    },
    /// The iteration matrix is singular and stays so after step-size
    /// reductions.
    #[error("singular iteration matrix at t = {t:e} (h = {h:e})")]
    SingularMatrix {
        /// Time reached.
        t: f64,
        /// Step size tried last.
        h: f64,
    },
    /// A NaN or infinity appeared in the solution or the residual.
    #[error("non-finite value in {what} at t = {t:e}")]
    NonFinite {
        /// Time reached.
        t: f64,
        /// Where it appeared (`residual`, `solution`, …).
        what: &'static str,
    },
    /// The maximum number of steps was reached before `t_end`.
    #[error("step limit of {max_steps} reached at t = {t:e}")]
    StepLimit {
        /// Time reached.
        t: f64,
        /// The limit in force.
        max_steps: usize,
    },
    /// The initial values violate an equation and may not be projected.
    #[error("inconsistent initial values: {equation} has residual {residual:e}")]
    InconsistentInitialValues {
        /// The violated equation (in the model language).
        equation: String,
        /// Its residual.
        residual: f64,
    },
    /// Consistent initialisation failed in a way the values cannot repair:
    /// the constraints do not determine the algebraic unknowns, Newton did
    /// not converge, or the model is not finite at a point it visited
    /// ([`crate::init::consistent`]).
    #[error("initialisation: {0}")]
    Init(#[from] InitError),
    /// The solver cannot integrate this formulation at all
    /// ([`crate::Solver::accepts`]).
    #[error("not applicable: {0}")]
    NotApplicable(#[from] NotApplicable),
    /// A well-formed tolerance the method cannot honour: a relative
    /// tolerance below `100 ε` or not below 1 (the rule is on
    /// [`crate::Options`]).
    #[error(
        "{name}{} = {value:e} {issue}; relative tolerances must be 0 or in [{min:.1e}, {max})",
        index.map_or_else(String::new, |i| format!("[{i}]")),
        min = crate::options::RTOL_MIN,
        max = crate::options::RTOL_MAX
    )]
    ToleranceOutOfRange {
        /// `"rtol"`.
        name: &'static str,
        /// The component, for per-component tolerances.
        index: Option<usize>,
        /// The value given.
        value: f64,
        /// What is wrong with it.
        issue: crate::options::ToleranceIssue,
    },
    /// The problem or the options are invalid (negative tolerance, wrong
    /// length, `t_end <= t0`, a formulation the solver cannot take, …).
    #[error("invalid input: {what}")]
    InvalidInput {
        /// What is wrong, naming the field.
        what: String,
    },
    /// [`crate::Integrator::advance_to`] was asked for a time it cannot
    /// report: outside the horizon, or before the last accepted step when
    /// no dense output is recorded ([`crate::Options::dense_output`]).
    #[error("t = {t:e} is out of reach: the integrator can report [{from:e}, {to:e}]")]
    OutOfReach {
        /// The time asked for.
        t: f64,
        /// The earliest time that can still be reported.
        from: f64,
        /// The end of the horizon.
        to: f64,
    },
    /// [`crate::Options::events`] names an event the model does not have.
    #[error(
        "no event named `{name}`{}; {}",
        suggestion.as_ref().map(|s| format!(" (did you mean `{s}`?)")).unwrap_or_default(),
        if known.is_empty() { "the model has no events".to_string() } else { format!("the model's events are {}", known.join(", ")) }
    )]
    UnknownEvent {
        /// The name given.
        name: String,
        /// The closest event name, if one is close.
        suggestion: Option<String>,
        /// The model's event names.
        known: Vec<String>,
    },
    /// An event's reset names an unknown the formulation does not have.
    #[error(
        "the reset of event `{event}` names `{name}`, which is not an unknown{}; the unknowns are {}",
        suggestion.as_ref().map(|s| format!(" (did you mean `{s}`?)")).unwrap_or_default(),
        known.join(", ")
    )]
    UnknownResetTarget {
        /// The event.
        event: String,
        /// The name given.
        name: String,
        /// The closest unknown's name, if one is close.
        suggestion: Option<String>,
        /// The formulation's unknowns.
        known: Vec<String>,
    },
    /// The values an event's reset made could not be made consistent
    /// again: the projection onto the constraints failed (the reset left
    /// them violated beyond repair), or gave non-finite values.
    #[error("the reset of event `{event}` at t = {t:e} leaves the constraints violated beyond repair: {source}")]
    ResetInconsistent {
        /// The event.
        event: String,
        /// Time of the event.
        t: f64,
        /// Why the projection failed.
        source: Box<SolveError>,
    },
    /// A run restarted after resets more often than
    /// [`crate::core::events::MAX_RESETS`] allows: a chattering or Zeno
    /// reset (a bouncing ball coming to rest).
    #[error("{resets} restarts after event resets by t = {t:e}: a chattering or Zeno reset")]
    TooManyResets {
        /// Time of the last reset.
        t: f64,
        /// Restarts made.
        resets: usize,
    },
}

impl SolveError {
    /// Short machine-readable name of the variant (`step_size_too_small`, …).
    pub fn kind(&self) -> &'static str {
        match self {
            SolveError::StepSizeTooSmall { .. } => "step_size_too_small",
            SolveError::NewtonFailure { .. } => "newton_failure",
            SolveError::RoundOffFloor { .. } => "round_off_floor",
            SolveError::SingularMatrix { .. } => "singular_matrix",
            SolveError::NonFinite { .. } => "non_finite",
            SolveError::StepLimit { .. } => "step_limit",
            SolveError::InconsistentInitialValues { .. } => "inconsistent_initial_values",
            SolveError::NotApplicable(_) => "not_applicable",
            SolveError::Init(e) => e.kind(),
            SolveError::ToleranceOutOfRange { .. } => "tolerance_out_of_range",
            SolveError::InvalidInput { .. } => "invalid_input",
            SolveError::OutOfReach { .. } => "out_of_reach",
            SolveError::UnknownEvent { .. } => "unknown_event",
            SolveError::UnknownResetTarget { .. } => "unknown_reset_target",
            SolveError::ResetInconsistent { .. } => "reset_inconsistent",
            SolveError::TooManyResets { .. } => "too_many_resets",
        }
    }

    /// Time at which the failure happened, where there is one.
    pub fn t(&self) -> Option<f64> {
        match self {
            SolveError::StepSizeTooSmall { t, .. }
            | SolveError::NewtonFailure { t, .. }
            | SolveError::RoundOffFloor { t, .. }
            | SolveError::SingularMatrix { t, .. }
            | SolveError::NonFinite { t, .. }
            | SolveError::StepLimit { t, .. } => Some(*t),
            SolveError::Init(e) => Some(e.t()),
            SolveError::ResetInconsistent { t, .. } | SolveError::TooManyResets { t, .. } => {
                Some(*t)
            }
            _ => None,
        }
    }

    /// What the failure says about the run ([`Failure`]): whether it was
    /// refused before any step, whether the iteration broke down, ran out of
    /// budget, met a non-finite value, or could not start.
    ///
    /// ```
    /// use dae::dae_solvers::error::Failure;
    /// use dae::dae_solvers::SolveError;
    ///
    /// let e = SolveError::SingularMatrix { t: 0.5, h: 1e-3 };
    /// assert_eq!(e.failure(), Failure::Breakdown);
    /// let e = SolveError::StepLimit { t: 0.5, max_steps: 10 };
    /// assert_eq!(e.failure(), Failure::Budget);
    /// ```
    pub fn failure(&self) -> Failure {
        match self {
            SolveError::StepSizeTooSmall { .. }
            | SolveError::NewtonFailure { .. }
            | SolveError::RoundOffFloor { .. }
            | SolveError::SingularMatrix { .. } => Failure::Breakdown,
            SolveError::StepLimit { .. } | SolveError::TooManyResets { .. } => Failure::Budget,
            SolveError::NonFinite { .. } => Failure::NonFinite,
            SolveError::InconsistentInitialValues { .. }
            | SolveError::Init(_)
            | SolveError::ResetInconsistent { .. } => Failure::Initialisation,
            SolveError::NotApplicable(_)
            | SolveError::UnknownEvent { .. }
            | SolveError::UnknownResetTarget { .. }
            | SolveError::ToleranceOutOfRange { .. }
            | SolveError::InvalidInput { .. }
            | SolveError::OutOfReach { .. } => Failure::Refused,
        }
    }

    pub(crate) fn invalid(what: impl Into<String>) -> Self {
        SolveError::InvalidInput { what: what.into() }
    }
}

/// The classes of [`SolveError`] ([`SolveError::failure`]): what a caller
/// deciding what to do next needs to know of a failure, without matching
/// its kind by name.
///
/// ```
/// use dae::dae_solvers::error::Failure;
/// use dae::dae_solvers::radau5::Radau5;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd0();
/// let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
/// let problem = Problem { system: &sys, t0: 0.0, y0: &y0, t_end: 20.0 };
/// let options = Options { max_steps: 10, ..Options::with_tol(1e-8) };
/// let err = Radau5.solve(&problem, &options).unwrap_err();
/// assert_eq!(err.failure(), Failure::Budget);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Failure {
    /// Refused before any step: invalid input, a tolerance out of range, a
    /// formulation the solver cannot take, a time out of reach.
    Refused,
    /// Consistent initialisation failed, or the values given are
    /// inconsistent.
    Initialisation,
    /// The iteration broke down: a singular iteration matrix, Newton
    /// failures or a step size collapsing below round-off, each after the
    /// retries of its budget — how a rank-deficient formulation (a selector
    /// that loses rank) or a singularity of the problem shows.
    Breakdown,
    /// The step budget ([`crate::Options::max_steps`]) ran out.
    Budget,
    /// A NaN or infinity in the residual, the solution or a matrix.
    NonFinite,
}

/// A run that stopped before the end of its horizon: why, and the work it
/// did until then — what [`crate::Solver::run`] and
/// [`crate::Integrator::run`] return, so that a failed run reports its cost
/// and where it got to, not only its error.
///
/// ```
/// use dae::dae_solvers::radau5::Radau5;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd0();
/// let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
/// let problem = Problem { system: &sys, t0: 0.0, y0: &y0, t_end: 20.0 };
/// let options = Options { max_steps: 10, ..Options::with_tol(1e-8) };
/// let stopped = Radau5.run(&problem, &options).unwrap_err();
/// assert_eq!(stopped.error.kind(), "step_limit");
/// assert!(stopped.stats.steps > 0);
/// // The values of the last accepted step, at its time.
/// assert!(stopped.t > 0.0 && stopped.t < 20.0);
/// assert!(stopped.y.iter().all(|v| v.is_finite()));
/// assert!(stopped.to_string().starts_with("step limit of 10"));
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error, Serialize)]
#[error("{error}")]
pub struct Stopped {
    /// Why the run stopped.
    pub error: SolveError,
    /// The work done until then, the failed attempts included.
    pub stats: crate::Stats,
    /// Time of the last accepted step (`t0` when none was accepted).
    pub t: f64,
    /// The solution there.
    pub y: Vec<f64>,
}

/// Why consistent initialisation ([`crate::init::consistent`]) stopped:
/// the typed failures that name the rows of the constraint chain (in the
/// model language, `0 = …`) and the unknowns involved.
///
/// ```
/// use dae::dae_solvers::init::{consistent, InitOptions};
/// use dae::dae_solvers::InitError;
/// use dae::prelude::*;
///
/// dae! {
///     /// A point on a circle, held by the same constraint written twice.
///     pub Twice {
///         differential { x, y, v, w }
///         algebraic { a, b }
///         equations {
///             der(x) = v;
///             der(y) = w;
///             der(v) = -2 * x * (a + b);
///             der(w) = -2 * y * (a + b) - 9.81;
///             0 = x^2 + y^2 - 1;
///             0 = 2 * x^2 + 2 * y^2 - 2;
///         }
///         formulations { rcd0 }
///     }
/// }
/// let sys = Twice::default().rcd0();
/// let err = consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0], &InitOptions::default())
///     .unwrap_err();
/// let SolveError::Init(InitError::Singular { equations, unknowns, rank, .. }) = &err else {
///     panic!("{err}");
/// };
/// assert_eq!((equations.len(), unknowns.len(), *rank), (1, 2, 1));
/// assert_eq!(err.kind(), "init_singular");
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error, Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum InitError {
    /// The Jacobian of the rows that determine the algebraic unknowns, with
    /// respect to those unknowns, is rank deficient at the start: the
    /// unknowns are not determined (a singular configuration, redundant
    /// constraints). A column-pivoted QR factorisation of the rows names
    /// those whose pivots vanished: each is, to `10⁻¹²` relative to the
    /// largest pivot, a combination of the rows chosen before it.
    #[error(
        "the constraints do not determine the algebraic unknowns ({}) at t = {t:e}: the \
         Jacobian of their {rows} rows with respect to them has rank {rank}; dependent on \
         the others: {}",
        unknowns.join(", "),
        equations.join("; ")
    )]
    Singular {
        /// Start time.
        t: f64,
        /// The dependent rows (`0 = …`), in the order of the chain.
        equations: Vec<String>,
        /// The algebraic unknowns being solved for.
        unknowns: Vec<String>,
        /// Numerical rank of the Jacobian.
        rank: usize,
        /// Number of rows solved.
        rows: usize,
    },
    /// Newton's iteration for the algebraic unknowns stopped with a row
    /// still violated: the largest (scaled) residual row and its value.
    #[error(
        "Newton's iteration for the algebraic unknowns did not converge in {iterations} \
         iterations at t = {t:e}: {equation} has residual {residual:e}"
    )]
    NotConverged {
        /// Start time.
        t: f64,
        /// The row with the largest scaled residual (`0 = …`).
        equation: String,
        /// Its residual at the last iterate.
        residual: f64,
        /// Iterations made.
        iterations: usize,
    },
    /// A row of the constraint chain, or its Jacobian, is NaN or infinite
    /// at a point initialisation reached.
    #[error(
        "{equation} has a non-finite {what} ({value}) at t = {t:e} during initialisation, at {}",
        values.iter().map(|(n, v)| format!("{n} = {v:e}")).collect::<Vec<_>>().join(", ")
    )]
    NonFinite {
        /// Time.
        t: f64,
        /// The first such row (`0 = …`).
        equation: String,
        /// `residual` or `Jacobian`.
        what: &'static str,
        /// The non-finite value (the residual, or the first non-finite
        /// entry of the Jacobian row).
        value: f64,
        /// Every unknown at that point, by name, in the formulation's order.
        values: Vec<(String, f64)>,
    },
}

impl InitError {
    /// Machine-readable name: `init_singular`, `init_not_converged`,
    /// `init_non_finite` (what [`SolveError::kind`] returns for it).
    pub fn kind(&self) -> &'static str {
        match self {
            InitError::Singular { .. } => "init_singular",
            InitError::NotConverged { .. } => "init_not_converged",
            InitError::NonFinite { .. } => "init_non_finite",
        }
    }

    /// The time of the failure.
    pub fn t(&self) -> f64 {
        match self {
            InitError::Singular { t, .. }
            | InitError::NotConverged { t, .. }
            | InitError::NonFinite { t, .. } => *t,
        }
    }
}

/// Why a solver cannot integrate a formulation at all: the typed refusal of
/// [`crate::Solver::accepts`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error, Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum NotApplicable {
    /// The formulation has no unknowns.
    #[error("the system has no unknowns")]
    NoUnknowns,
    /// More equations than unknowns, for a solver of square systems.
    #[error("overdetermined: solver needs a square system")]
    Overdetermined {
        /// Equations `M`.
        equations: usize,
        /// Unknowns `N`.
        unknowns: usize,
    },
    /// Fewer equations than unknowns.
    #[error("underdetermined: {equations} equations for {unknowns} unknowns")]
    Underdetermined {
        /// Equations `M`.
        equations: usize,
        /// Unknowns `N`.
        unknowns: usize,
    },
    /// The formulation leaves out hidden constraints above the level the
    /// method can integrate (its constraint level `c_level` exceeds `max`).
    #[error("constraint level {c_level}: solver needs c-level at most {max}")]
    ConstraintLevel {
        /// The formulation's constraint level.
        c_level: u8,
        /// The highest level the solver takes.
        max: u8,
    },
    /// The leading matrix `E(t, y)` depends on the unknowns or on time, for
    /// a method whose formulas need a constant one (MEBDF, the linearly
    /// implicit Euler). The message names the state (it is recorded in the
    /// harness snapshot); a time-dependent `E` gets the same reason.
    #[error("state-dependent leading matrix E(y): solver needs a constant one")]
    LeadingMatrixNotConstant,
    /// A method that makes its end point consistent on the rows of `E`
    /// that are zero (`gauss`), on a system with more algebraic conditions
    /// than such rows: some are combinations of rows holding derivatives
    /// (a loop of capacitors and a voltage source).
    #[error(
        "E has {conditions} null directions (algebraic conditions) but only {zero_rows} zero rows: the other conditions are combinations of rows holding derivatives, onto which this solver cannot project its end point; use radau5 or bdf"
    )]
    AlgebraicConditionsNotRows {
        /// Rows of `E` that are zero (constraint rows).
        zero_rows: usize,
        /// `m − rank E`.
        conditions: usize,
    },
    /// A formulation of index 2 or 3 whose constraints are not in
    /// Hessenberg form, for a method that leaves unknowns of index ≥ 2 out
    /// of its error test (the BDF family): a level of a constraint below
    /// its top one already depends on an algebraic unknown (see
    /// [`crate::core::policy::hessenberg`]). The unknowns left out of the
    /// test are then states that nothing controls.
    #[error(
        "constraint {constraint} at level {level} (below its top level {top}) depends on the algebraic unknown `{unknown}`: this index-{d_index} formulation is not in Hessenberg form, outside BDF's convergence theory, and the unknowns its error test leaves out would be controlled by nothing; use an index-1 formulation (rcd0) or radau5"
    )]
    NotHessenberg {
        /// 0-based index of the model's constraint.
        constraint: u16,
        /// The level (number of differentiations) that depends on it.
        level: u8,
        /// The chain's top level.
        top: u8,
        /// The algebraic unknown.
        unknown: String,
        /// The formulation's largest index.
        d_index: u8,
    },
    /// `bdf`, `radau5` or `odradau` on a formulation of index 2 or 3 whose
    /// leading matrix `E` depends on `t` (see
    /// [`crate::core::policy::leading_constant_in_time`]).
    #[error(
        "E depends on t in this index-{d_index} formulation, where {solver}'s simplified Newton iteration, its matrix taken at one time for a whole step or several, does not converge (Gear, Hsu & Petzold's y1' + ηt y2': failures at every tolerance); use an index-1 formulation (rcd0)"
    )]
    TimeDependentLeading {
        /// The solver that refuses.
        solver: &'static str,
        /// The formulation's largest index.
        d_index: u8,
    },
    /// A variable-step BDF method (`bdf`) on a formulation with unknowns of
    /// index 3 (see [`crate::core::policy::variable_step_index3`]): BDF's
    /// convergence results for index 3 are for a constant step, and after a
    /// change of step size its index-3 unknowns are O(1) wrong (Petzold
    /// 1982; Brenan, Campbell & Petzold 1996, §3.2).
    #[error(
        "{solver} is a variable-step BDF method and this formulation has index {d_index}: BDF converges at index 3 only with a constant step (Brenan, Campbell & Petzold 1996, §3.2; Petzold 1982: after a change of step size the index-3 unknowns are O(1) wrong) and its error test leaves the index-2/3 unknowns out (DASSL-type codes take index ≤ 1); measured on the IVP Test Set's car axis: -1.5 to 2.6 correct digits at tol 1e-4 to 1e-10; use an index-1 or stabilised formulation (rcd0, ggl1, psi0), radau5, mebdf, or a fixed step"
    )]
    VariableStepIndexThree {
        /// The solver that refuses.
        solver: &'static str,
        /// The formulation's largest index.
        d_index: u8,
    },
    /// An overdetermined formulation whose constraint rows and the
    /// algebraic combinations of its rows holding derivatives fix every
    /// unknown, for a least-squares method whose error estimate measures
    /// the differential rows on the directions the constraints leave free
    /// (`odradau`, see [`crate::core::policy::free_directions`]).
    #[error(
        "the {constraints} constraint rows and {combinations} algebraic combinations of the rows holding derivatives fix all {unknowns} unknowns: no direction is left free, so {solver}'s error estimate (the differential rows measured on the free directions) sees nothing and neither the step size nor the solution between steps is controlled (Gear, Hsu & Petzold's ovd0: 2.2 digits at 1e-8); use an index-1 formulation (rcd0)"
    )]
    NoFreeDirection {
        /// The solver that refuses.
        solver: &'static str,
        /// Constraint rows with a zero row of `E`.
        constraints: usize,
        /// Algebraic combinations of the other rows.
        combinations: usize,
        /// Unknowns `N`.
        unknowns: usize,
    },
    /// `idec` with error control on a formulation with unknowns of index 2
    /// (see [`crate::idec`], "Known limitation"): every interval restarts
    /// from the accepted value, which costs the index-2 unknowns the order
    /// the corrections should give, so the steps grow like `tol^(−1/2)` to
    /// `tol^(−1)` and the run crawls to the step limit. The seed's
    /// constant-step scheme ([`crate::Options::fixed_step`]) keeps the
    /// global connection its theory needs and takes these formulations.
    #[error(
        "index-2 unknowns with error control: idec restarts every interval from the accepted value, which costs the index-2 unknowns the order of the corrections (steps grow like tol^(-1/2) to tol^(-1), a crawl to the step limit); use an index-1 formulation (rcd0), a fixed step, or radau5"
    )]
    RestartedIndexTwo,
    /// An unknown has a higher index than the method integrates.
    #[error("index {index}: solver takes unknowns of index at most {max}")]
    IndexTooHigh {
        /// The largest index of any unknown of the formulation.
        index: u8,
        /// The highest index the solver takes.
        max: u8,
    },
}

/// Why a [`crate::Solution`] cannot answer a question about its values:
/// the typed failure of [`crate::Solution::at`] and of access by name.
///
/// ```
/// use dae::dae_solvers::{init, radau5::Radau5, SolutionError};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd0();
/// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
/// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 1.0 };
/// let sol = Radau5.solve(&problem, &Options::with_tol(1e-6))?;
/// assert!(matches!(sol.at(2.0), Err(SolutionError::OutsideHorizon { .. })));
/// let err = sol.value(0.5, "lamda").unwrap_err();
/// assert!(matches!(&err, SolutionError::UnknownName { suggestion: Some(s), .. } if s == "lambda"));
/// assert!(err.to_string().contains("did you mean `lambda`?"));
/// # Ok::<(), SolveError>(())
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SolutionError {
    /// The time lies outside the integrated horizon `[t0, t_end]`.
    #[error("t = {t:e} is outside the horizon [{t0:e}, {t_end:e}]")]
    OutsideHorizon {
        /// The time asked for.
        t: f64,
        /// Start of the horizon.
        t0: f64,
        /// End of the horizon.
        t_end: f64,
    },
    /// The solve ran with [`crate::Options::dense_output`] off, so only the
    /// output times ([`crate::Solution::t`]) are known.
    #[error(
        "no dense output was recorded (Options::dense_output was off); \
         only the output times are known"
    )]
    NoDenseOutput,
    /// No unknown of the formulation has this name.
    #[error(
        "no unknown named `{name}`{}; the unknowns are {}",
        suggestion.as_ref().map_or_else(String::new, |s| format!(" (did you mean `{s}`?)")),
        known.join(", ")
    )]
    UnknownName {
        /// The name asked for.
        name: String,
        /// The closest known name, when one is close.
        suggestion: Option<String>,
        /// Every unknown, in the formulation's order.
        known: Vec<String>,
    },
    /// The output buffer of [`crate::Solution::at_into`] has the wrong
    /// length.
    #[error("output buffer has {got} components, the solution has {expected}")]
    LengthMismatch {
        /// Unknowns of the solution.
        expected: usize,
        /// Length of the buffer given.
        got: usize,
    },
}

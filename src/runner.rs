//! One run: a model, a start, a horizon, one solver, one formulation, one
//! tolerance → a [`RunRecord`] with errors against the reference, work
//! counters, constraint residuals per level and invariant drift. Shared by
//! `dae run` and `dae sweep`.

use crate::reference::data::{Reference, Scaling, UseError};
use dae_core::selector::SelectorKind;
use dae_core::system::{DaeSystem, FormulationInfo, Model, VarKind};
use dae_solvers::error::Failure;
use dae_solvers::init::{self, InitMode, InitOptions, InitValue, Start};
use dae_solvers::options::{check_relative, Tol, ToleranceIssue};
use dae_solvers::{Options, Problem, SolveError, Stats, Tolerances};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use std::time::Instant;

/// Everything that defines one run.
pub struct RunSpec<'a> {
    /// Scene name (reported).
    pub scene: &'a str,
    /// The model with its parameters set.
    pub model: &'a dyn Model,
    /// Given values of unknowns by name (differential ones; algebraic ones
    /// are computed).
    pub initial: &'a [(String, f64)],
    /// Guesses by name (a scene's `[guess]`): where the computation of an
    /// unknown not in [`RunSpec::initial`] starts
    /// ([`dae_solvers::init::Start::Guess`]); an unknown in neither starts
    /// from 0.
    pub guess: &'a [(String, f64)],
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t_end: f64,
    /// Check times (residuals and drift are measured there, and errors
    /// against a reference that gives no times of its own).
    pub check: &'a [f64],
    /// Reference, if any (see [`crate::reference::data`]).
    pub reference: Option<&'a Reference>,
    /// Solver name.
    pub solver: &'a str,
    /// Formulation name.
    pub formulation: &'a str,
    /// Tolerance (`RTOL = ATOL`), in `[100 ε, 1)`
    /// ([`dae_solvers::options::check_uniform`]; [`RunError::Tolerance`]
    /// otherwise). Not used when [`RunSpec::tolerances`] is given.
    pub tol: f64,
    /// Separate and per-unknown tolerances (`dae run --rtol/--atol`, a
    /// scene's `[tolerance]`), instead of the uniform [`RunSpec::tol`].
    pub tolerances: Option<&'a RunTolerances>,
    /// Keep every accepted step in [`Trajectory::steps`] (`dae run
    /// --trajectory`).
    pub record_steps: bool,
    /// Project inconsistent initial values (default) or refuse them.
    pub init_mode: InitMode,
    /// Extra output times for figures (solution sampled there too).
    pub samples: &'a [f64],
    /// Repeat the timed integration this many times (the minimum is
    /// reported: interference only adds time, see [`RunRecord::tsim_s`]).
    pub repeats: usize,
    /// Bound on the accepted steps of each integration (`None`: the
    /// library's [`Options::max_steps`]); a run stopped there is a
    /// `step_limit` error record, not a hang.
    pub max_steps: Option<usize>,
    /// How the model's events are treated (a scene's `[events]`;
    /// [`Options::events`]): each located event is listed in
    /// [`RunRecord::events`].
    pub events: &'a [dae_solvers::EventSpec],
    /// The BDF methods' error estimate (`dae run --estimate`;
    /// [`Options::estimate`]).
    pub estimate: dae_solvers::options::Estimate,
}

/// Error information of a failed run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ErrorInfo {
    /// Machine-readable kind (`step_size_too_small`, …).
    pub kind: String,
    /// Human-readable message.
    pub message: String,
    /// Time reached, where known.
    pub t: Option<f64>,
}

/// Named values in a fixed order, serialised as a JSON object.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Named(pub Vec<(String, f64)>);

impl Serialize for Named {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl Named {
    /// Value of `name`.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(k, _)| k == name).map(|(_, v)| *v)
    }
}

/// Largest constraint violations over the check times, per level of the
/// model's constraint chain: entry `k` is the largest `|g|` of the level-`k`
/// constraints (`None` for a level without any). Serialised as
/// `{"level0": …, "level1": …}`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Residuals(pub Vec<Option<f64>>);

impl Residuals {
    /// Residual of level `k`.
    pub fn level(&self, k: usize) -> Option<f64> {
        self.0.get(k).copied().flatten()
    }

    /// Number of levels of the chain.
    pub fn levels(&self) -> usize {
        self.0.len()
    }
}

impl Serialize for Residuals {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0.iter().enumerate() {
            m.serialize_entry(&format!("level{k}"), v)?;
        }
        m.end()
    }
}

/// The result of one run (the JSON contract of `dae run`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunRecord {
    /// Scene name.
    pub scene: String,
    /// Solver.
    pub solver: String,
    /// Formulation.
    pub formulation: String,
    /// Tolerance.
    pub tol: f64,
    /// `ok` or `error`.
    pub status: &'static str,
    /// Why it failed.
    pub error: Option<ErrorInfo>,
    /// Time reached: the end of the horizon on success; for a run that
    /// stopped, the time of its last accepted step (`t0` when it accepted
    /// none; the error names where it failed).
    pub t_end: f64,
    /// Values at `t_end` by unknown name (for a run that stopped, those of
    /// its last accepted step; empty when initialisation failed).
    #[serde(rename = "final")]
    pub final_values: Named,
    /// Max over the reference's times of the largest error of the
    /// differential unknowns it gives (of all it gives, if none is
    /// differential); `null` without a reference. The times are the check
    /// times, or a `values` reference's own. Each error is scaled as the
    /// reference says ([`Scaling`]).
    pub err: Option<f64>,
    /// Sum over those times of the errors of every unknown the reference
    /// gives.
    pub err_sum: Option<f64>,
    /// Euclidean norm of the same errors: the square root of the sum over
    /// those times of the squared errors of every unknown the reference
    /// gives. On S02 this is the reading of the paper's ERR under which the
    /// classic codes' measured errors reproduce it (BENCHMARKS.md §3c);
    /// `err_sum` is SPEC's stricter reading.
    pub err_l2: Option<f64>,
    /// Max over those times of the errors of the algebraic unknowns the
    /// reference gives (the multipliers of a mechanical system); `null`
    /// if it gives none.
    pub err_algebraic: Option<f64>,
    /// Significant correct digits, as the IVP Test Set reports them:
    /// `−log₁₀` of the largest scaled error of any unknown the reference
    /// gives over those times (with relative scaling, the IVP Test Set's
    /// `scd`); `null` without a reference or for an exact answer.
    pub scd: Option<f64>,
    /// Does the answer deserve the tolerance? (See [`Accuracy`].) `null`
    /// for a run that did not reach the end.
    pub accuracy: Option<Accuracy>,
    /// What the verdict rests on, in one line (`null` with it).
    pub accuracy_note: Option<String>,
    /// Integration time in seconds: the CPU time of the thread that ran
    /// the integration, the **minimum** over the repeats: the integration is
    /// deterministic, so what varies between repeats is interference, and
    /// interference only ever adds time. CPU time, not wall time, so that it
    /// does not grow when other processes compete for the cores
    /// (BENCHMARKS.md §8: a sweep's CPU times moved 0.98× in the median
    /// where wall times moved 2.66× with both cores loaded). It does not
    /// count time spent waiting, e.g. for pages;
    /// [`wall_s`](RunRecord::wall_s) is the elapsed time beside it.
    pub tsim_s: f64,
    /// Wall-clock time of the same integration(s) in seconds (minimum over
    /// the repeats): what a user waits, and what grows with the machine's
    /// load.
    pub wall_s: f64,
    /// Work counters; for a run that stopped, the work done until then,
    /// its failed attempts included (zero when it stopped before its first
    /// step).
    pub stats: Stats,
    /// Constraint residuals per level: the largest over the solution (every
    /// output time, and [`VERIFY_SAMPLES`] equidistant points of the
    /// horizon), not only at the check times.
    pub residuals: Residuals,
    /// Largest `|I(t) − I(t0)|` per invariant, over the same points as
    /// [`RunRecord::residuals`].
    pub invariant_drift: Named,
    /// What consistent initialisation did (projected values), if anything.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init: Option<InitSummary>,
    /// Every unknown of the formulation at the start: the value given, the
    /// guess, the consistent value used, how far it moved from where it
    /// started, and how it came about
    /// ([`dae_solvers::init::InitReport::values`]). Empty when
    /// initialisation failed.
    pub initialisation: Vec<InitValue>,
    /// Solution at the sample times (for figures; not serialised).
    #[serde(skip)]
    pub trajectory: Trajectory,
    /// For `psi1`/`psi0`: `"symbolic"` or `"numerical"`, the selector the
    /// run used (see [`run`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selector: Option<&'static str>,
    /// The located events in time order: name, time, direction, action
    /// and, for a reset, the values it assigned and the consistent ones
    /// the run restarted from ([`dae_solvers::Event`]). Omitted when the
    /// model has no events.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<Vec<dae_solvers::Event>>,
}

/// The accuracy verdict of a run that reached the end of its horizon.
///
/// Reaching the end (`status = "ok"`) says nothing about the answer: a BDF
/// run released at 179.99° ends with an error of 4.9–11 at tolerances where
/// 1e-4 would be honest, and used to be reported as plain "ok". The
/// verdict says whether the tolerance bought the accuracy it names.
///
/// * With a reference: [`Accurate`](Accuracy::Accurate) iff at every check
///   time the error of the differential unknowns is at most
///   [`ACCURATE_FACTOR`]` · tol · max(1, |y*|)`, `|y*|` the largest of those
///   unknowns in the exact solution there (the scale the error weights
///   `atol + rtol |y|` use with `RTOL = ATOL = tol`; for a solution of
///   order one — the paper's pendulum at a check time — the rule reads
///   `err ≤ 100 · tol`). Otherwise [`Inaccurate`](Accuracy::Inaccurate).
///   Why 100: the tolerance bounds the error made in each step, and the
///   global error is what the steps' errors accumulate to over the horizon;
///   a good method on a well-conditioned problem keeps it within one or two
///   orders of magnitude of the tolerance over the horizons measured here
///   (RADAU5 on the paper's S01: within 75 · tol on every formulation but
///   the index-3 `ori2`). Beyond 100 · tol the tolerance no longer describes
///   the answer.
/// * Without a reference: [`Unverified`](Accuracy::Unverified), or
///   [`Suspect`](Accuracy::Suspect) when the position- or velocity-level
///   constraint residual reaches [`SUSPECT_FACTOR`]` · tol`, or an
///   invariant drifts by `SUSPECT_FACTOR · tol · max(1, |I(t0)|)` —
///   orders of magnitude beyond what the tolerance allows, so the answer
///   is very likely wrong even though nothing checks it. (The
///   acceleration level is left out: it carries the multipliers, whose
///   scale can be huge for stiff parameters.)
///
/// The verdict never changes the exit code of `dae run` (0 for a run that
/// reached the end); the text output and the sweep's tables flag it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Accuracy {
    /// Error within `100 · tol · max(1, |y*|)` at every check time.
    Accurate,
    /// Error beyond it somewhere.
    Inaccurate,
    /// No reference; residuals and drift unremarkable.
    Unverified,
    /// No reference, and residuals or drift ≥ `1e4 · tol` (scaled).
    Suspect,
}

impl Accuracy {
    /// The name used in JSON and CSV.
    pub fn as_str(self) -> &'static str {
        match self {
            Accuracy::Accurate => "accurate",
            Accuracy::Inaccurate => "inaccurate",
            Accuracy::Unverified => "unverified",
            Accuracy::Suspect => "suspect",
        }
    }

    /// Whether the verdict is a warning (inaccurate or suspect).
    pub fn is_warning(self) -> bool {
        matches!(self, Accuracy::Inaccurate | Accuracy::Suspect)
    }
}

/// A run with a reference is accurate iff its scaled error is at most
/// `ACCURATE_FACTOR · tol` (see [`Accuracy`]).
pub const ACCURATE_FACTOR: f64 = 100.0;

/// A run without a reference is suspect when a constraint residual or an
/// invariant drift reaches `SUSPECT_FACTOR · tol` (scaled; see
/// [`Accuracy`]).
pub const SUSPECT_FACTOR: f64 = 1e4;

/// What initialisation changed, in short: initial values the scene did not
/// give, and given values moved onto the constraints. Present in a record
/// only when there is something to say.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InitSummary {
    /// Differential values moved onto the constraints: the values after
    /// the projection, by name.
    pub projected: Named,
    /// The same moves with the value given: `from` → `to`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub changes: Vec<InitChange>,
    /// Differential unknowns given no initial value: started from 0 (then
    /// projected, if 0 was inconsistent).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub defaulted: Vec<String>,
}

/// One initial value moved by the projection.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InitChange {
    /// The unknown.
    pub name: String,
    /// Its value before the projection (given, or 0 if not given).
    pub from: f64,
    /// Its value after.
    pub to: f64,
}

/// The tolerances of one run by unknown name: a value of each kind for
/// every unknown, and per-unknown values that replace it for the unknowns
/// they name (`dae run --rtol/--atol`, a scene's `[tolerance]`). The error
/// weight of unknown `i` is `1 / (atol_i + rtol_i |y_i|)`
/// ([`dae_solvers::Tolerances`]); unknowns a formulation adds (GGL's
/// multipliers) take the uniform values.
///
/// ```
/// use dae::runner::{Named, RunTolerances};
///
/// let tol = RunTolerances {
///     atol_of: Named(vec![("lambda".into(), 1e-6)]),
///     ..RunTolerances::uniform(1e-8)
/// };
/// assert!(!tol.is_uniform() && tol.check().is_ok());
/// assert_eq!(tol.atol_for("lambda"), 1e-6);
/// assert_eq!(tol.atol_for("x"), 1e-8);
/// assert!(RunTolerances { rtol: 2.0, ..RunTolerances::uniform(1e-8) }.check().is_err());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunTolerances {
    /// Relative tolerance of every unknown not in `rtol_of`: `0` or in
    /// `[100 ε, 1)` ([`dae_solvers::options::check_relative`]).
    pub rtol: f64,
    /// Absolute tolerance of every unknown not in `atol_of`: finite, `≥ 0`.
    pub atol: f64,
    /// Relative tolerances by unknown name.
    pub rtol_of: Named,
    /// Absolute tolerances by unknown name.
    pub atol_of: Named,
}

impl RunTolerances {
    /// `RTOL = ATOL = tol` for every unknown.
    pub fn uniform(tol: f64) -> Self {
        RunTolerances {
            rtol: tol,
            atol: tol,
            rtol_of: Named::default(),
            atol_of: Named::default(),
        }
    }

    /// Whether every unknown has `RTOL = ATOL` = the same value.
    pub fn is_uniform(&self) -> bool {
        self.rtol == self.atol && self.rtol_of.0.is_empty() && self.atol_of.0.is_empty()
    }

    /// Relative tolerance of unknown `name`.
    pub fn rtol_for(&self, name: &str) -> f64 {
        self.rtol_of.get(name).unwrap_or(self.rtol)
    }

    /// Absolute tolerance of unknown `name`.
    pub fn atol_for(&self, name: &str) -> f64 {
        self.atol_of.get(name).unwrap_or(self.atol)
    }

    /// Every value by the library's rule ([`dae_solvers::Options`]): a
    /// relative tolerance `0` or in `[100 ε, 1)`, an absolute one finite
    /// and not negative; and the uniform pair not both 0.
    pub fn check(&self) -> Result<(), RunError> {
        let bad = |kind: &'static str, unknown: Option<&str>, value: f64, issue| {
            RunError::ToleranceValue {
                kind,
                unknown: unknown.map(str::to_string),
                value,
                issue,
            }
        };
        let absolute = |v: f64| {
            if !v.is_finite() {
                Err(ToleranceIssue::NotFinite)
            } else if v < 0.0 {
                Err(ToleranceIssue::Negative)
            } else {
                Ok(())
            }
        };
        check_relative(self.rtol).map_err(|i| bad("rtol", None, self.rtol, i))?;
        absolute(self.atol).map_err(|i| bad("atol", None, self.atol, i))?;
        for (name, v) in &self.rtol_of.0 {
            check_relative(*v).map_err(|i| bad("rtol", Some(name), *v, i))?;
        }
        for (name, v) in &self.atol_of.0 {
            absolute(*v).map_err(|i| bad("atol", Some(name), *v, i))?;
        }
        if self.rtol == 0.0 && self.atol == 0.0 {
            return Err(bad("atol", None, 0.0, ToleranceIssue::Zero));
        }
        Ok(())
    }

    /// The library's per-component tolerances for a formulation's
    /// unknowns; a name the formulation lacks is
    /// [`RunError::UnknownVariable`], an unknown left with `rtol = atol =
    /// 0` is [`RunError::ToleranceValue`].
    pub fn for_system(
        &self,
        info: &dae_core::system::FormulationInfo,
    ) -> Result<Tolerances, RunError> {
        for (name, _) in self.rtol_of.0.iter().chain(&self.atol_of.0) {
            if info.variable(name).is_none() {
                return Err(RunError::UnknownVariable(name.clone()));
            }
        }
        let rtol: Vec<f64> = info
            .variables
            .iter()
            .map(|v| self.rtol_for(&v.name))
            .collect();
        let atol: Vec<f64> = info
            .variables
            .iter()
            .map(|v| self.atol_for(&v.name))
            .collect();
        if let Some((v, _)) = info
            .variables
            .iter()
            .zip(rtol.iter().zip(&atol))
            .find(|(_, (r, a))| **r + **a <= 0.0)
        {
            return Err(RunError::ToleranceValue {
                kind: "atol",
                unknown: Some(v.name.clone()),
                value: 0.0,
                issue: ToleranceIssue::Zero,
            });
        }
        Ok(Tolerances {
            rtol: Tol::PerComponent(rtol),
            atol: Tol::PerComponent(atol),
        })
    }

    /// The tolerance the accuracy verdict holds a run to ([`Accuracy`]):
    /// the loosest of the relative and absolute tolerances of the
    /// differential unknowns (what [`RunRecord::err`] measures) — with
    /// `RTOL = ATOL = tol`, `tol`.
    pub fn verdict_tol(&self, info: &dae_core::system::FormulationInfo) -> f64 {
        let loosest = info
            .variables
            .iter()
            .filter(|v| v.kind == VarKind::Differential)
            .map(|v| self.rtol_for(&v.name).max(self.atol_for(&v.name)))
            .fold(0.0f64, f64::max);
        if loosest > 0.0 {
            loosest
        } else {
            self.rtol.max(self.atol)
        }
    }
}

/// Sampled solution with errors, residuals and drift per sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Unknown names.
    pub names: Vec<String>,
    /// Sample times.
    pub t: Vec<f64>,
    /// Values at the sample times.
    pub y: Vec<Vec<f64>>,
    /// `(t, error)` at each sample where the reference gives a value: the
    /// largest error of the unknowns [`RunRecord::err`] measures (empty
    /// without a reference).
    pub err: Vec<(f64, f64)>,
    /// `|g|` per level of the constraint chain (max over sources) at each
    /// sample.
    pub residuals: Vec<Vec<f64>>,
    /// Drift of the first invariant at each sample.
    pub drift: Vec<f64>,
    /// Every accepted step `(t, y)`, from the consistent start at `t0`,
    /// when [`RunSpec::record_steps`] asks for them (empty otherwise).
    pub steps: Vec<(f64, Vec<f64>)>,
}

/// Why a run could not even start (bad input): exit code 2.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Unknown solver.
    #[error("unknown solver `{0}` (known: {known})", known = dae_solvers::SOLVER_NAMES.join(", "))]
    UnknownSolver(String),
    /// A tolerance outside [`dae_solvers::options::check_uniform`].
    #[error(
        "tolerance {tol:e} {issue}; tolerances (RTOL = ATOL) must be in {}",
        crate::runner::tolerance_range()
    )]
    Tolerance {
        /// The value given.
        tol: f64,
        /// What is wrong with it.
        issue: dae_solvers::options::ToleranceIssue,
    },
    /// Formulation problem.
    #[error(transparent)]
    Formulation(#[from] dae_core::system::FormulationError),
    /// The solver cannot take this formulation.
    #[error("solver `{solver}` cannot integrate `{formulation}`: {why}")]
    NotApplicable {
        /// Solver.
        solver: String,
        /// Formulation.
        formulation: String,
        /// Reason.
        why: String,
    },
    /// An `[initial]`, `[guess]` or per-unknown tolerance name that is not
    /// an unknown.
    #[error("`{0}` is not an unknown of the model")]
    UnknownVariable(String),
    /// A separate or per-unknown tolerance outside the library's rule
    /// ([`RunTolerances::check`]).
    #[error(
        "{kind}{} = {value:e} {issue}",
        unknown.as_ref().map_or_else(String::new, |u| format!(" of `{u}`"))
    )]
    ToleranceValue {
        /// `rtol` or `atol`.
        kind: &'static str,
        /// The unknown it is given for (`None`: every unknown).
        unknown: Option<String>,
        /// The value.
        value: f64,
        /// What is wrong with it.
        issue: ToleranceIssue,
    },
    /// A reference that cannot serve this run.
    #[error("reference: {0}")]
    Reference(#[from] UseError),
}

/// The accepted range of a uniform tolerance, for messages, with its
/// lower bound `100 ε` written in full: `[2.220446049250313e-14, 1)`. A
/// rounded bound (`2.2e-14`) would name a value that is itself refused.
///
/// The library's [`dae_solvers::options::uniform_range`].
///
/// ```
/// assert_eq!(dae::runner::tolerance_range(), "[2.220446049250313e-14, 1)");
/// ```
pub fn tolerance_range() -> String {
    dae_solvers::options::uniform_range()
}

/// Run one integration. `Err` only for bad input; solver failures are an
/// `Ok` record with `status = "error"`.
///
/// `psi1` and `psi0` run with the model's symbolic selector where it has
/// one; where it has none (a time-dependent constraint), or where a run with
/// the symbolic selector stops with a singular iteration matrix, a Newton
/// failure or a collapsed step (how a selector that loses rank, at the
/// start or where the motion takes it, shows), the run is made again with a
/// selector computed numerically ([`dae_core::selector`]). The record's
/// `selector` says which.
pub fn run(spec: &RunSpec<'_>) -> Result<RunRecord, RunError> {
    let (first, failure) = run_with(spec, false)?;
    match Retry::after(&first, failure) {
        // A second attempt only: where the numerical selector cannot be
        // built (the model lists no ovd1/ovd0, or its rank fails at t0),
        // the answer is the first run's solver failure, not bad input.
        Retry::NumericalSelector => Ok(run_with(spec, true).map_or(first, |(r, _)| r)),
        Retry::No => Ok(first),
    }
}

/// Whether a run is made again, and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Retry {
    /// The record stands.
    No,
    /// Again with a selector computed numerically.
    NumericalSelector,
}

impl Retry {
    /// After `record`, which stopped with `failure` (or finished: `None`):
    /// a run with the symbolic selector whose iteration broke down is made
    /// again with the numerical one.
    fn after(record: &RunRecord, failure: Option<Failure>) -> Self {
        let symbolic = record.selector == Some(SelectorKind::Symbolic.as_str());
        if symbolic && failure == Some(Failure::Breakdown) {
            Retry::NumericalSelector
        } else {
            Retry::No
        }
    }
}

/// One run with the symbolic selector, or the numerical one when
/// `numerical`: its record, and the class of its failure when it stopped.
fn run_with(spec: &RunSpec<'_>, numerical: bool) -> Result<(RunRecord, Option<Failure>), RunError> {
    let solver = dae_solvers::solver_by_name(spec.solver)
        .ok_or_else(|| RunError::UnknownSolver(spec.solver.into()))?;
    match spec.tolerances {
        Some(t) => t.check()?,
        None => {
            dae_solvers::options::check_uniform(spec.tol).map_err(|issue| RunError::Tolerance {
                tol: spec.tol,
                issue,
            })?
        }
    }
    if let Some(r) = spec.reference {
        let info = spec.model.model_info();
        let unknowns: Vec<&str> = info.variables.iter().map(|v| v.name.as_str()).collect();
        r.check_use(&unknowns, spec.t0, spec.t_end, spec.check)?;
    }
    let (sys, selector) =
        dae_core::selector::formulation(spec.model, spec.formulation, numerical, spec.t0, &[])?;
    let info = sys.info().clone();
    solver
        .accepts(&info)
        .map_err(|why| RunError::NotApplicable {
            solver: spec.solver.into(),
            formulation: spec.formulation.into(),
            why: why.to_string(),
        })?;
    let (tolerances, tol) = match spec.tolerances {
        Some(t) => (t.for_system(&info)?, t.verdict_tol(&info)),
        None => (Tolerances::uniform(spec.tol), spec.tol),
    };
    let n = info.unknowns();
    let mut start = vec![Start::Omitted; n];
    for (name, v) in spec.guess {
        let i = info
            .variable(name)
            .ok_or_else(|| RunError::UnknownVariable(name.clone()))?;
        start[i] = Start::Guess(*v);
    }
    // A value given fixes it, whatever the guesses say (a scene refuses
    // both for one name).
    for (name, v) in spec.initial {
        let i = info
            .variable(name)
            .ok_or_else(|| RunError::UnknownVariable(name.clone()))?;
        start[i] = Start::Fixed(*v);
    }
    // Differential unknowns of the model the scene gives no value or
    // guess: 0.
    let defaulted: Vec<String> = spec
        .model
        .model_info()
        .variables
        .iter()
        .filter(|v| v.kind == VarKind::Differential)
        .filter(|v| {
            !spec
                .initial
                .iter()
                .chain(spec.guess)
                .any(|(name, _)| *name == v.name)
        })
        .map(|v| v.name.clone())
        .collect();
    let mut record = RunRecord {
        scene: spec.scene.to_string(),
        solver: spec.solver.to_string(),
        formulation: spec.formulation.to_string(),
        tol,
        status: "ok",
        error: None,
        t_end: spec.t0,
        final_values: Named::default(),
        err: None,
        err_sum: None,
        err_l2: None,
        err_algebraic: None,
        scd: None,
        accuracy: None,
        accuracy_note: None,
        tsim_s: 0.0,
        wall_s: 0.0,
        stats: Stats::default(),
        residuals: Residuals::default(),
        invariant_drift: Named::default(),
        init: None,
        initialisation: Vec::new(),
        trajectory: Trajectory::default(),
        selector: selector.map(SelectorKind::as_str),
        events: (!sys.event_names().is_empty()).then(Vec::new),
    };
    let fail = |mut record: RunRecord, e: SolveError| {
        record.status = "error";
        record.t_end = e.t().unwrap_or(spec.t0);
        record.error = Some(ErrorInfo {
            kind: e.kind().to_string(),
            message: e.to_string(),
            t: e.t(),
        });
        (record, Some(e.failure()))
    };
    let init_opts = InitOptions {
        mode: spec.init_mode,
        ..InitOptions::default()
    };
    let consistent = match init::consistent_from(&sys, spec.t0, &start, &init_opts) {
        Ok(c) => c,
        Err(e) => return Ok(fail(record, e)),
    };
    let changes = if consistent.report.projected {
        consistent.report.changes.as_slice()
    } else {
        &[]
    };
    if !changes.is_empty() || !defaulted.is_empty() {
        record.init = Some(InitSummary {
            projected: Named(changes.iter().map(|c| (c.name.clone(), c.after)).collect()),
            changes: changes
                .iter()
                .map(|c| InitChange {
                    name: c.name.clone(),
                    from: c.before,
                    to: c.after,
                })
                .collect(),
            defaulted,
        });
    }
    record.initialisation = consistent.report.values;
    let y0 = consistent.y;
    let reference_times = spec.reference.and_then(Reference::times).unwrap_or(&[]);
    let mut output_times: Vec<f64> = spec
        .check
        .iter()
        .chain(spec.samples)
        .chain(reference_times)
        .copied()
        .collect();
    output_times.sort_by(f64::total_cmp);
    output_times.dedup();
    // What the record's trajectory shows; the residuals and the drift are
    // measured at the verification samples as well (dense output: output
    // times never shorten a step, so the statistics do not move).
    let shown = output_times.clone();
    output_times.extend(verification_samples(spec.t0, spec.t_end));
    output_times.sort_by(f64::total_cmp);
    output_times.dedup();
    let defaults = Options::default();
    let options = Options {
        tol: tolerances,
        output_times,
        max_steps: spec.max_steps.unwrap_or(defaults.max_steps),
        record_steps: spec.record_steps,
        // The record needs the check times (and, for --trajectory, the
        // step points) only: a sweep's long runs should not keep every
        // step's dense output.
        dense_output: false,
        events: spec.events.to_vec(),
        estimate: spec.estimate,
        ..defaults
    };
    let problem = Problem {
        system: &sys,
        t0: spec.t0,
        y0: &y0,
        t_end: spec.t_end,
    };
    let mut times = Vec::new();
    let mut walls = Vec::new();
    let mut solution = None;
    for _ in 0..spec.repeats.max(1) {
        let (result, cpu, wall) = timed(|| solver.run(&problem, &options));
        times.push(cpu);
        walls.push(wall);
        match result {
            Ok(s) => solution = Some(s),
            Err(stopped) => {
                record.tsim_s = cpu;
                record.wall_s = wall;
                // The work done and where it got to: the last accepted
                // step's time and values (the error keeps its own time).
                record.stats = stopped.stats;
                record.final_values = named(&info, &stopped.y);
                let (mut record, failure) = fail(record, stopped.error);
                record.t_end = stopped.t;
                return Ok((record, failure));
            }
        }
    }
    let Some(sol) = solution else {
        return Ok(fail(
            record,
            SolveError::InvalidInput {
                what: "no run".into(),
            },
        ));
    };
    // Interference only adds time to a deterministic computation: the
    // minimum is the stable statistic.
    record.tsim_s = minimum(&times);
    record.wall_s = minimum(&walls);
    record.stats = sol.stats;
    if let Some(events) = &mut record.events {
        events.clone_from(&sol.events);
    }
    record.t_end = sol.t.last().copied().unwrap_or(spec.t_end);
    if let Some(last) = sol.last() {
        record.final_values = named(&info, last);
    }
    if spec.record_steps {
        let first = sol.steps.first().map(|(t, _)| *t);
        if !matches!(first, Some(t) if t <= spec.t0) {
            record.trajectory.steps.push((spec.t0, y0.clone()));
        }
    }
    measure(spec, &*sys, &y0, &sol, &shown, &mut record);
    if spec.record_steps {
        record.trajectory.steps.extend(sol.steps);
    }
    Ok((record, None))
}

/// The values `y` of the unknowns of `info`, by name.
fn named(info: &FormulationInfo, y: &[f64]) -> Named {
    Named(
        info.variables
            .iter()
            .zip(y)
            .map(|(v, x)| (v.name.clone(), *x))
            .collect(),
    )
}

/// Run `f` on this thread and measure it: its result, the CPU time this
/// thread spent in it, and the wall-clock time it took, both in seconds.
///
/// The CPU time is the thread's (`CLOCK_THREAD_CPUTIME_ID` on Unix, via
/// the `cpu-time` crate), so work of other threads and processes does not
/// count; where the platform offers no thread clock it falls back to the
/// wall-clock time.
///
/// ```
/// let (sum, cpu, wall) = dae::runner::timed(|| (0..100_000u64).sum::<u64>());
/// assert_eq!(sum, 4_999_950_000);
/// assert!(cpu >= 0.0 && wall >= 0.0);
/// ```
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let cpu = cpu_time::ThreadTime::try_now().ok();
    let wall = Instant::now();
    let out = f();
    let wall = wall.elapsed().as_secs_f64();
    let cpu = cpu
        .and_then(|c| c.try_elapsed().ok())
        .map_or(wall, |d| d.as_secs_f64());
    (out, cpu, wall)
}

/// Smallest value of a list; 0 for an empty one.
///
/// ```
/// assert_eq!(dae::runner::minimum(&[3.0, 1.5, 2.0]), 1.5);
/// assert_eq!(dae::runner::minimum(&[]), 0.0);
/// ```
pub fn minimum(values: &[f64]) -> f64 {
    values.iter().copied().reduce(f64::min).unwrap_or(0.0)
}

/// Whether each output time is a check time (within `10⁻¹²(1 + |t|)`), by
/// one merge of the two lists: `times` in increasing order (as a
/// [`dae_solvers::Solution`] reports them), `checks` in any order (sorted
/// here; a scene's are already strictly increasing). `O(n + m)` after the
/// sort, where scanning the check list per output time was `O(n·m)`: 10⁵
/// check times took 6.5 s, 5·10⁵ over two minutes.
///
/// ```
/// use dae::runner::check_flags;
///
/// let times = [0.0, 0.5, 1.0, 1.5, 2.0];
/// assert_eq!(
///     check_flags(&times, &[2.0, 1.0 + 1e-13]),
///     [false, false, true, false, true]
/// );
/// ```
pub fn check_flags(times: &[f64], checks: &[f64]) -> Vec<bool> {
    let mut sorted;
    let checks = if checks.windows(2).all(|w| w[0] <= w[1]) {
        checks
    } else {
        sorted = checks.to_vec();
        sorted.sort_by(f64::total_cmp);
        &sorted[..]
    };
    let mut next = 0;
    times
        .iter()
        .map(|&t| {
            let slack = 1e-12 * (1.0 + t.abs());
            // Check times below the window of t cannot match t or any
            // later (larger) output time.
            while next < checks.len() && checks[next] < t - slack {
                next += 1;
            }
            next < checks.len() && checks[next] <= t + slack
        })
        .collect()
}

/// The reference's components in a formulation: position in `y`, scaling,
/// and whether [`RunRecord::err`] measures it (a differential unknown, or
/// every one if the reference gives no differential unknown).
struct Components {
    /// `(j, i)`: component `j` of the reference is unknown `i`.
    index: Vec<(usize, usize)>,
    scaling: Vec<Scaling>,
    main: Vec<bool>,
}

impl Components {
    fn new(reference: &Reference, info: &dae_core::system::FormulationInfo) -> Components {
        // Names are checked against the model before the run; a name the
        // formulation lacks could only be left out.
        let index: Vec<(usize, usize)> = reference
            .names()
            .iter()
            .enumerate()
            .filter_map(|(j, n)| info.variable(n).map(|i| (j, i)))
            .collect();
        let differential: Vec<bool> = index
            .iter()
            .map(|&(_, i)| info.variables[i].kind == VarKind::Differential)
            .collect();
        let any = differential.iter().any(|&d| d);
        Components {
            scaling: index.iter().map(|&(j, _)| reference.scaling()[j]).collect(),
            main: differential.iter().map(|&d| d || !any).collect(),
            index,
        }
    }

    /// The errors against `exact` (the reference's values) of `y`.
    fn errors(&self, y: &[f64], exact: &[f64]) -> Errors {
        let scale = self
            .index
            .iter()
            .zip(self.main.iter().zip(&self.scaling))
            .filter(|(_, (&main, &s))| main && s == Scaling::Absolute)
            .fold(1.0f64, |m, (&(j, _), _)| m.max(exact[j].abs()));
        let mut e = Errors {
            main: 0.0,
            sum: 0.0,
            squares: 0.0,
            other: None,
            all: 0.0,
            verdict: 0.0,
        };
        for (c, &(j, i)) in self.index.iter().enumerate() {
            let d = self.scaling[c].error(y[i], exact[j]);
            e.sum += d;
            e.squares += d * d;
            e.all = max_or_nan(e.all, d);
            if self.main[c] {
                e.main = max_or_nan(e.main, d);
                let v = if self.scaling[c] == Scaling::Absolute {
                    d / scale
                } else {
                    d
                };
                e.verdict = max_or_nan(e.verdict, v);
            } else {
                e.other = Some(max_or_nan(e.other.unwrap_or(0.0), d));
            }
        }
        e
    }
}

/// `max(m, d)`, but NaN when `d` is NaN (`f64::max` would drop it): a NaN
/// error must not pass for a small one.
fn max_or_nan(m: f64, d: f64) -> f64 {
    if d.is_nan() {
        d
    } else {
        m.max(d)
    }
}

/// Errors against the reference at one time.
struct Errors {
    /// Largest error of the main components.
    main: f64,
    /// Sum over all components.
    sum: f64,
    /// Sum of squares over all components.
    squares: f64,
    /// Largest error of the other (algebraic) components.
    other: Option<f64>,
    /// Largest error over all components.
    all: f64,
    /// The accuracy verdict's measure: the main components' errors,
    /// absolute ones divided by `max(1, |y*|)` over the absolute main
    /// components.
    verdict: f64,
}

/// Errors, residuals and drift from the solution at the output times.
/// Equidistant points strictly inside the horizon at which every run's
/// constraint residuals and invariant drift are measured besides its output
/// times ([`verification_samples`]).
pub const VERIFY_SAMPLES: usize = 100;

/// The [`VERIFY_SAMPLES`] points `t0 + k (t_end − t0) / (VERIFY_SAMPLES +
/// 1)`, `k = 1 …`: a run whose check times say little (only `t_end`, or
/// only the start) is still measured along its whole solution.
///
/// ```
/// let s = dae::runner::verification_samples(0.0, 1.0);
/// assert_eq!(s.len(), dae::runner::VERIFY_SAMPLES);
/// assert!(s.iter().all(|&t| 0.0 < t && t < 1.0));
/// ```
pub fn verification_samples(t0: f64, t_end: f64) -> Vec<f64> {
    let n = VERIFY_SAMPLES;
    (1..=n)
        .map(|k| t0 + (t_end - t0) * (k as f64 / (n + 1) as f64))
        .filter(|t| t.is_finite() && *t > t0 && *t < t_end)
        .collect()
}

/// Errors, residuals and drift of `sol`: the errors at the reference's
/// (or the check) times, the residuals and the drift at every output time;
/// the trajectory keeps the output times in `shown` and the last.
fn measure(
    spec: &RunSpec<'_>,
    sys: &dyn DaeSystem,
    y0: &[f64],
    sol: &dae_solvers::Solution,
    shown: &[f64],
    record: &mut RunRecord,
) {
    let info = sys.info();
    let k = info.constraints.len();
    let levels = info
        .constraints
        .iter()
        .map(|c| usize::from(c.level) + 1)
        .max()
        .unwrap_or(0);
    let n_inv = info.invariants.len();
    let mut g = vec![0.0; k];
    let mut inv0 = vec![0.0; n_inv];
    let mut inv = vec![0.0; n_inv];
    sys.invariants(spec.t0, y0, &mut inv0);
    let is_check = check_flags(&sol.t, spec.check);
    let mut is_shown = check_flags(&sol.t, shown);
    if let Some(last) = is_shown.last_mut() {
        *last = true;
    }
    let reference = spec.reference.map(|r| (r, Components::new(r, info)));
    let is_ref_time = match spec.reference.and_then(Reference::times) {
        Some(times) => check_flags(&sol.t, times),
        None => is_check,
    };
    let mut exact = vec![0.0; spec.reference.map_or(0, |r| r.names().len())];
    let (mut err, mut err_sum, mut err_sq, mut err_alg, mut worst) =
        (0.0f64, 0.0f64, 0.0f64, None::<f64>, 0.0f64);
    let mut compared = false;
    // A comparison after the start: one at t0 only verifies nothing.
    let mut compared_later = false;
    // Largest verdict measure over the reference's times, and where.
    let (mut err_scaled, mut worst_t) = (0.0f64, spec.t0);
    let mut res = vec![None::<f64>; levels];
    let mut drift = vec![0.0f64; n_inv];
    let traj = &mut record.trajectory;
    traj.names = info.variables.iter().map(|v| v.name.clone()).collect();
    for (((t, y), &is_shown), &is_ref_time) in
        sol.t.iter().zip(&sol.y).zip(&is_shown).zip(&is_ref_time)
    {
        sys.constraints(*t, y, &mut g);
        let mut lev = vec![0.0f64; levels];
        for (c, gi) in info.constraints.iter().zip(&g) {
            let l = usize::from(c.level);
            lev[l] = lev[l].max(gi.abs());
        }
        sys.invariants(*t, y, &mut inv);
        if let Some((r, comps)) = &reference {
            if r.at(*t, &mut exact) {
                let e = comps.errors(y, &exact);
                if is_shown {
                    traj.err.push((*t, e.main));
                }
                if is_ref_time {
                    compared = true;
                    compared_later |= *t > spec.t0;
                    if e.verdict > err_scaled || e.verdict.is_nan() {
                        err_scaled = e.verdict;
                        worst_t = *t;
                    }
                    err = max_or_nan(err, e.main);
                    err_sum += e.sum;
                    err_sq += e.squares;
                    if let Some(o) = e.other {
                        err_alg = Some(err_alg.unwrap_or(0.0).max(o));
                    }
                    worst = max_or_nan(worst, e.all);
                }
            }
        }
        // Along the whole solution, not only at the check times (a scene
        // checked at t0 alone measured nothing).
        for (l, slot) in res.iter_mut().enumerate() {
            if info.constraints.iter().any(|c| usize::from(c.level) == l) {
                *slot = Some(max_or_nan(slot.unwrap_or(0.0), lev[l]));
            }
        }
        for (d, (a, b)) in drift.iter_mut().zip(inv.iter().zip(&inv0)) {
            *d = max_or_nan(*d, (a - b).abs());
        }
        if !is_shown {
            continue;
        }
        traj.t.push(*t);
        traj.y.push(y.clone());
        traj.residuals.push(lev);
        traj.drift.push(
            inv.first()
                .zip(inv0.first())
                .map_or(0.0, |(a, b)| (a - b).abs()),
        );
    }
    if compared {
        record.err = Some(err);
        record.err_sum = Some(err_sum);
        record.err_l2 = Some(err_sq.sqrt());
        record.err_algebraic = err_alg;
        record.scd = (worst > 0.0 && worst.is_finite()).then(|| -worst.log10());
    }
    record.residuals = Residuals(res);
    record.invariant_drift = Named(info.invariants.iter().cloned().zip(drift).collect());
    let inv_scale: Vec<f64> = inv0.iter().map(|v| v.abs().max(1.0)).collect();
    let (accuracy, note) = verdict(
        spec,
        record,
        compared_later.then_some((err_scaled, worst_t)),
        &inv_scale,
    );
    record.accuracy = Some(accuracy);
    record.accuracy_note = Some(note);
}

/// The accuracy verdict and its one-line reason (see [`Accuracy`]).
/// `compared`: the largest scaled error and where, if the reference was
/// compared after the start (a comparison at `t0` alone verifies nothing:
/// the verdict is then the one without a reference).
fn verdict(
    spec: &RunSpec<'_>,
    record: &RunRecord,
    compared: Option<(f64, f64)>,
    inv_scale: &[f64],
) -> (Accuracy, String) {
    let tol = record.tol;
    let unused = if spec.reference.is_some() && compared.is_none() {
        "the reference is compared at no time after the start"
    } else {
        "no reference"
    };
    if let Some((err_scaled, worst_t)) = compared {
        let bound = ACCURATE_FACTOR * tol;
        // NaN compares false: a NaN error is not accurate.
        return if err_scaled <= bound {
            (
                Accuracy::Accurate,
                format!("err within {ACCURATE_FACTOR}·tol·max(1, |y*|) at every check time"),
            )
        } else {
            (
                Accuracy::Inaccurate,
                format!(
                    "err/max(1, |y*|) = {err_scaled:.2e} at t = {worst_t} is {:.0}·tol, beyond the \
                     {ACCURATE_FACTOR}·tol an accurate run keeps to",
                    err_scaled / tol
                ),
            )
        };
    }
    let bound = SUSPECT_FACTOR * tol;
    let mut excess: Vec<String> = Vec::new();
    for level in 0..2 {
        if let Some(r) = record.residuals.level(level) {
            if r >= bound || r.is_nan() {
                excess.push(format!("level-{level} constraint residual {r:.2e}"));
            }
        }
    }
    for ((name, d), scale) in record.invariant_drift.0.iter().zip(inv_scale) {
        if *d >= bound * scale || d.is_nan() {
            excess.push(format!("drift of {name} {d:.2e} (scale {scale:.2e})"));
        }
    }
    if excess.is_empty() {
        (
            Accuracy::Unverified,
            format!(
                "{unused}; constraint residuals and invariant drift below {SUSPECT_FACTOR:.0e}·tol"
            ),
        )
    } else {
        (
            Accuracy::Suspect,
            format!(
                "{unused}, but {} at or above {SUSPECT_FACTOR:.0e}·tol (scaled)",
                excess.join(", ")
            ),
        )
    }
}

/// The forward sensitivities of a run (`dae run --sensitivities g,l`, a
/// scene's `[sensitivities]`; `docs/design_sensitivities.md`): `∂y/∂p` of
/// every unknown with respect to each named parameter, at the check times
/// and at the end, from a second integration of the state and its
/// sensitivities together ([`dae_core::sensitivity::SensitivitySystem`]),
/// from the run's consistent start.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SensitivityRecord {
    /// The check times the values are given at.
    pub times: Vec<f64>,
    /// Per parameter, per unknown: the sensitivity at each check time
    /// (`{"g": {"x": [...], …}, …}`).
    #[serde(serialize_with = "per_parameter")]
    pub values: Vec<(String, Series)>,
    /// Per parameter, per unknown: the sensitivity at the end.
    #[serde(rename = "final", serialize_with = "per_parameter")]
    pub final_values: Vec<(String, Named)>,
    /// Whether the sensitivities were in the error test.
    pub error_control: bool,
    /// The work of the combined integration.
    pub stats: Stats,
    /// Why the combined integration stopped (`None`: it reached the end).
    pub error: Option<ErrorInfo>,
}

/// Why sensitivities cannot be computed (bad input: exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum SensitivityRunError {
    /// The model text could not be read.
    #[error("sensitivities: {0}")]
    Model(#[from] crate::models::ModelError),
    /// A parameter that does not exist, a derived one, a formulation that
    /// cannot carry sensitivities ([`dae_core::sensitivity::SensitivityError`]).
    #[error("sensitivities: {0}")]
    Sensitivity(#[from] dae_core::sensitivity::SensitivityError),
    /// The solver cannot take the sensitivity system.
    #[error("sensitivities: solver `{solver}` cannot integrate them: {why}")]
    NotApplicable {
        /// Solver.
        solver: String,
        /// Reason.
        why: String,
    },
}

/// The sensitivities with respect to `parameters` of the run `spec` that
/// produced `record` (a run that reached its end), the model read from
/// its text `source`: the model's parameters as `spec.model` has them, the
/// state started from the record's consistent start, the sensitivities
/// from their consistent start (zero given values projected onto the
/// linearised constraints), the uniform tolerance `record.tol`.
///
/// ```
/// use dae::inputs::inputs;
/// use dae::runner::{run, sensitivities};
/// use dae::scene::Scene;
///
/// let scene = Scene::builtin("s01").unwrap();
/// let inputs = inputs(&scene).unwrap();
/// let spec = inputs.spec(&scene, "radau5", "rcd0", 1e-8);
/// let record = run(&spec).unwrap();
/// let s = sensitivities(&spec, &record, dae::models::PENDULUM_SOURCE, &["g".into()], true).unwrap();
/// let (name, dg) = &s.values[0];
/// assert_eq!(name, "g");
/// assert_eq!(dg.0.len(), 5); // x, y, v, w, lambda
/// assert_eq!(dg.0[0].1.len(), scene.time.checks.len());
/// assert!(s.error.is_none());
/// ```
pub fn sensitivities(
    spec: &RunSpec<'_>,
    record: &RunRecord,
    source: &str,
    parameters: &[String],
    error_control: bool,
) -> Result<SensitivityRecord, SensitivityRunError> {
    use dae_core::sensitivity::Sensitivities;
    let names: Vec<&str> = parameters.iter().map(String::as_str).collect();
    let mut model = Sensitivities::from_str(source, &names)?;
    for p in &spec.model.model_info().parameters {
        if p.derived.is_none() {
            if let Some(v) = spec.model.parameter(&p.name) {
                model.set_parameter(&p.name, v)?;
            }
        }
    }
    let mut sys = model.formulation(spec.formulation)?;
    sys.set_error_control(error_control);
    let solver = dae_solvers::solver_by_name(spec.solver).ok_or_else(|| {
        SensitivityRunError::NotApplicable {
            solver: spec.solver.into(),
            why: "unknown solver".into(),
        }
    })?;
    let info = sys.info().clone();
    solver
        .accepts(&info)
        .map_err(|why| SensitivityRunError::NotApplicable {
            solver: spec.solver.into(),
            why: why.to_string(),
        })?;
    let n = sys.state_unknowns();
    let mut y0 = vec![0.0; info.unknowns()];
    for (k, v) in record.initialisation.iter().enumerate().take(n) {
        y0[k] = v.value;
    }
    let mut out = SensitivityRecord {
        times: spec.check.to_vec(),
        values: Vec::new(),
        final_values: Vec::new(),
        error_control,
        stats: Stats::default(),
        error: None,
    };
    let error = |e: &SolveError| ErrorInfo {
        kind: e.kind().to_string(),
        message: e.to_string(),
        t: e.t(),
    };
    let start = match dae_solvers::sensitivity::consistent_start(
        &sys,
        spec.t0,
        &y0,
        &InitOptions::default(),
    ) {
        Ok(s) => s,
        Err(e) => {
            out.error = Some(error(&e));
            return Ok(out);
        }
    };
    let options = Options {
        tol: Tolerances::uniform(record.tol),
        output_times: spec.check.to_vec(),
        max_steps: spec.max_steps.unwrap_or(Options::default().max_steps),
        dense_output: false,
        ..Options::default()
    };
    let problem = Problem {
        system: &sys,
        t0: spec.t0,
        y0: &start.y,
        t_end: spec.t_end,
    };
    let sol = match solver.run(&problem, &options) {
        Ok(sol) => sol,
        Err(stopped) => {
            out.stats = stopped.stats;
            out.error = Some(error(&stopped.error));
            return Ok(out);
        }
    };
    out.stats = sol.stats;
    let rows: Vec<Option<&Vec<f64>>> = spec
        .check
        .iter()
        .map(|t| sol.t.iter().position(|s| s == t).map(|k| &sol.y[k]))
        .collect();
    for (i, p) in parameters.iter().enumerate() {
        let series = (0..n)
            .map(|j| {
                let values = rows
                    .iter()
                    .map(|y| y.map_or(f64::NAN, |y| y[n * (i + 1) + j]))
                    .collect();
                (info.variables[j].name.clone(), values)
            })
            .collect();
        out.values.push((p.clone(), Series(series)));
        if let Some(last) = sol.last() {
            out.final_values
                .push((p.clone(), named(&info, &last[n * (i + 1)..n * (i + 2)])));
        }
    }
    Ok(out)
}

/// Values of each unknown by name, one per check time (a JSON object).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series(pub Vec<(String, Vec<f64>)>);

impl Serialize for Series {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// `(parameter, T)` pairs written as a JSON object in their order.
fn per_parameter<T: Serialize, S: Serializer>(v: &[(String, T)], s: S) -> Result<S::Ok, S::Error> {
    let mut m = s.serialize_map(Some(v.len()))?;
    for (k, x) in v {
        m.serialize_entry(k, x)?;
    }
    m.end()
}

//! One run: a model, a start, a horizon, one solver, one formulation, one
//! tolerance → a [`RunRecord`] with errors against the reference, work
//! counters, constraint residuals per level and invariant drift. Shared by
//! `dae run` and `dae sweep`.

use crate::reference::{PendulumExact, ReferenceError};
use dae_core::system::{DaeSystem, Model};
use dae_solvers::init::{self, InitMode, InitOptions};
use dae_solvers::{Options, Problem, SolveError, Stats};
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
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t_end: f64,
    /// Check times (errors and residuals are measured there).
    pub check: &'a [f64],
    /// Exact reference, if any.
    pub reference: Option<&'a PendulumExact>,
    /// Solver name.
    pub solver: &'a str,
    /// Formulation name.
    pub formulation: &'a str,
    /// Tolerance (`RTOL = ATOL`), in `[100 ε, 1)`
    /// ([`dae_solvers::options::check_uniform`]; [`RunError::Tolerance`]
    /// otherwise).
    pub tol: f64,
    /// Project inconsistent initial values (default) or refuse them.
    pub init_mode: InitMode,
    /// Extra output times for figures (solution sampled there too).
    pub samples: &'a [f64],
    /// Repeat the timed integration this many times (median reported).
    pub repeats: usize,
    /// Bound on the accepted steps of each integration (`None`: the
    /// library's [`Options::max_steps`]); a run stopped there is a
    /// `step_limit` error record, not a hang.
    pub max_steps: Option<usize>,
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

/// Largest constraint violations over the check times, per level.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Residuals {
    /// Position level.
    pub level0: Option<f64>,
    /// Velocity level.
    pub level1: Option<f64>,
    /// Acceleration level.
    pub level2: Option<f64>,
}

impl Residuals {
    /// Residual of level `k`.
    pub fn level(&self, k: usize) -> Option<f64> {
        match k {
            0 => self.level0,
            1 => self.level1,
            2 => self.level2,
            _ => None,
        }
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
    /// Time reached (the end of the horizon on success).
    pub t_end: f64,
    /// Values at `t_end` by unknown name.
    #[serde(rename = "final")]
    pub final_values: Named,
    /// Max over check times of the largest error of the model's differential
    /// unknowns (`null` without a reference).
    pub err: Option<f64>,
    /// Sum over check times of the errors of every unknown.
    pub err_sum: Option<f64>,
    /// Max over check times of the multiplier's error.
    pub err_lambda: Option<f64>,
    /// Does the answer deserve the tolerance? (See [`Accuracy`].) `null`
    /// for a run that did not reach the end.
    pub accuracy: Option<Accuracy>,
    /// What the verdict rests on, in one line (`null` with it).
    pub accuracy_note: Option<String>,
    /// Integration time in seconds (median of the repeats).
    pub tsim_s: f64,
    /// Work counters.
    pub stats: Stats,
    /// Constraint residuals per level.
    pub residuals: Residuals,
    /// Largest `|I(t) − I(t0)|` over the check times per invariant.
    pub invariant_drift: Named,
    /// What consistent initialisation did (projected values), if anything.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init: Option<InitSummary>,
    /// Solution at the sample times (for figures; not serialised).
    #[serde(skip)]
    pub trajectory: Trajectory,
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

/// What initialisation changed, in short.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InitSummary {
    /// Differential values moved onto the constraints.
    pub projected: Named,
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
    /// Largest error of any reference component at each sample (empty
    /// without a reference).
    pub err: Vec<f64>,
    /// `|g|` per level (max over sources) at each sample.
    pub residuals: Vec<[f64; 3]>,
    /// Drift of the first invariant at each sample.
    pub drift: Vec<f64>,
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
        dae_solvers::options::uniform_range()
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
    /// An `[initial]` name that is not an unknown.
    #[error("`{0}` in [initial] is not an unknown of the model")]
    UnknownVariable(String),
    /// A reference the model cannot have.
    #[error("reference: {0}")]
    Reference(String),
    /// The exact reference cannot be built from the scene's values: the
    /// field to blame (`initial.x`, `parameters.g`, `time.end`, …) and why.
    #[error("`{field}`: pendulum-exact reference: {source}")]
    ReferenceInput {
        /// The scene field, as `section.key`.
        field: String,
        /// What the reference refused.
        source: ReferenceError,
    },
}

impl RunError {
    /// The scene field a bad-input error is about, where there is one.
    pub fn field(&self) -> Option<&str> {
        match self {
            RunError::ReferenceInput { field, .. } => Some(field),
            _ => None,
        }
    }
}

/// The scene field (`initial.x`, `parameters.g`, `time.end`) of the input a
/// reference error blames.
fn reference_field(e: &ReferenceError) -> String {
    match e.input() {
        "theta0" | "x0" => "initial.x".into(),
        "y0" => "initial.y".into(),
        "v0" => "initial.v".into(),
        "w0" => "initial.w".into(),
        "t" => "time.end".into(),
        p => format!("parameters.{p}"),
    }
}

/// Variables compared against the pendulum reference, in its order.
const REF_NAMES: [&str; 5] = ["x", "y", "v", "w", "lambda"];

/// Check that the reference can be used for this model and scene.
pub fn pendulum_reference(
    model: &dyn Model,
    initial: &[(String, f64)],
) -> Result<PendulumExact, RunError> {
    let info = model.model_info();
    for n in REF_NAMES {
        if !info.variables.iter().any(|v| v.name == n) {
            return Err(RunError::Reference(format!(
                "pendulum-exact needs unknowns x, y, v, w, lambda; model `{}` has no `{n}`",
                info.name
            )));
        }
    }
    let param = |n: &str| {
        model
            .parameter(n)
            .ok_or_else(|| RunError::Reference(format!("pendulum-exact needs parameter `{n}`")))
    };
    let value = |n: &str| {
        initial
            .iter()
            .find(|(k, _)| k == n)
            .map(|(_, v)| *v)
            .unwrap_or(0.0)
    };
    PendulumExact::from_state(
        value("x"),
        value("y"),
        value("v"),
        value("w"),
        param("l")?,
        param("g")?,
        param("m")?,
    )
    .map_err(|source| RunError::ReferenceInput {
        field: reference_field(&source),
        source,
    })
}

/// The reference must be defined over the whole horizon (the state is NaN
/// beyond 2⁵¹ periods): checked once at `t_end − t0`, the furthest time.
fn check_reference_horizon(reference: &PendulumExact, t0: f64, t_end: f64) -> Result<(), RunError> {
    let t = t_end - t0;
    if reference.state(t).iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        let source = ReferenceError::PhaseLost { t };
        Err(RunError::ReferenceInput {
            field: reference_field(&source),
            source,
        })
    }
}

/// Run one integration. `Err` only for bad input; solver failures are an
/// `Ok` record with `status = "error"`.
pub fn run(spec: &RunSpec<'_>) -> Result<RunRecord, RunError> {
    let solver = dae_solvers::solver_by_name(spec.solver)
        .ok_or_else(|| RunError::UnknownSolver(spec.solver.into()))?;
    dae_solvers::options::check_uniform(spec.tol).map_err(|issue| RunError::Tolerance {
        tol: spec.tol,
        issue,
    })?;
    if let Some(r) = spec.reference {
        check_reference_horizon(r, spec.t0, spec.t_end)?;
    }
    let sys = spec.model.formulation(spec.formulation)?;
    let info = sys.info().clone();
    solver
        .accepts(&info)
        .map_err(|why| RunError::NotApplicable {
            solver: spec.solver.into(),
            formulation: spec.formulation.into(),
            why: why.to_string(),
        })?;
    let n = info.unknowns();
    let mut y0 = vec![0.0; n];
    for (name, v) in spec.initial {
        let i = info
            .variable(name)
            .ok_or_else(|| RunError::UnknownVariable(name.clone()))?;
        y0[i] = *v;
    }
    let mut record = RunRecord {
        scene: spec.scene.to_string(),
        solver: spec.solver.to_string(),
        formulation: spec.formulation.to_string(),
        tol: spec.tol,
        status: "ok",
        error: None,
        t_end: spec.t0,
        final_values: Named::default(),
        err: None,
        err_sum: None,
        err_lambda: None,
        accuracy: None,
        accuracy_note: None,
        tsim_s: 0.0,
        stats: Stats::default(),
        residuals: Residuals::default(),
        invariant_drift: Named::default(),
        init: None,
        trajectory: Trajectory::default(),
    };
    let fail = |mut record: RunRecord, e: SolveError| {
        record.status = "error";
        record.t_end = e.t().unwrap_or(spec.t0);
        record.error = Some(ErrorInfo {
            kind: e.kind().to_string(),
            message: e.to_string(),
            t: e.t(),
        });
        record
    };
    let init_opts = InitOptions {
        mode: spec.init_mode,
        ..InitOptions::default()
    };
    let consistent = match init::consistent(&sys, spec.t0, &y0, &init_opts) {
        Ok(c) => c,
        Err(e) => return Ok(fail(record, e)),
    };
    if consistent.report.projected {
        record.init = Some(InitSummary {
            projected: Named(
                consistent
                    .report
                    .changes
                    .iter()
                    .map(|c| (c.name.clone(), c.after))
                    .collect(),
            ),
        });
    }
    let y0 = consistent.y;
    let mut output_times: Vec<f64> = spec.check.iter().chain(spec.samples).copied().collect();
    output_times.sort_by(f64::total_cmp);
    output_times.dedup();
    let defaults = Options::with_tol(spec.tol);
    let options = Options {
        output_times,
        max_steps: spec.max_steps.unwrap_or(defaults.max_steps),
        ..defaults
    };
    let problem = Problem {
        system: &sys,
        t0: spec.t0,
        y0: &y0,
        t_end: spec.t_end,
    };
    let mut times = Vec::new();
    let mut solution = None;
    for _ in 0..spec.repeats.max(1) {
        let start = Instant::now();
        let result = solver.solve(&problem, &options);
        times.push(start.elapsed().as_secs_f64());
        match result {
            Ok(s) => solution = Some(s),
            Err(e) => {
                record.tsim_s = times[times.len() - 1];
                return Ok(fail(record, e));
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
    times.sort_by(f64::total_cmp);
    record.tsim_s = times[times.len() / 2];
    record.stats = sol.stats;
    record.t_end = sol.t.last().copied().unwrap_or(spec.t_end);
    if let Some(last) = sol.last() {
        record.final_values = Named(
            info.variables
                .iter()
                .zip(last)
                .map(|(v, x)| (v.name.clone(), *x))
                .collect(),
        );
    }
    measure(spec, &*sys, &y0, &sol, &mut record);
    Ok(record)
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

/// Errors, residuals and drift from the solution at the output times.
fn measure(
    spec: &RunSpec<'_>,
    sys: &dyn DaeSystem,
    y0: &[f64],
    sol: &dae_solvers::Solution,
    record: &mut RunRecord,
) {
    let info = sys.info();
    let k = info.constraints.len();
    let n_inv = info.invariants.len();
    let mut g = vec![0.0; k];
    let mut inv0 = vec![0.0; n_inv];
    let mut inv = vec![0.0; n_inv];
    sys.invariants(spec.t0, y0, &mut inv0);
    let ref_idx: Vec<Option<usize>> = REF_NAMES.iter().map(|n| info.variable(n)).collect();
    let is_check = check_flags(&sol.t, spec.check);
    let (mut err, mut err_sum, mut err_lambda) = (0.0f64, 0.0f64, 0.0f64);
    // Largest error relative to max(1, |y*|) over the check times, and
    // where: the accuracy verdict's measure.
    let (mut err_scaled, mut worst_t) = (0.0f64, spec.t0);
    let mut res = [None::<f64>; 3];
    let mut drift = vec![0.0f64; n_inv];
    let traj = &mut record.trajectory;
    traj.names = info.variables.iter().map(|v| v.name.clone()).collect();
    for ((t, y), &is_check) in sol.t.iter().zip(&sol.y).zip(&is_check) {
        sys.constraints(*t, y, &mut g);
        let mut lev = [0.0f64; 3];
        for (c, gi) in info.constraints.iter().zip(&g) {
            if (c.level as usize) < 3 {
                lev[c.level as usize] = lev[c.level as usize].max(gi.abs());
            }
        }
        sys.invariants(*t, y, &mut inv);
        let mut e_here = 0.0f64;
        if let Some(r) = spec.reference {
            // The reference starts at its own t = 0: the scene's t0.
            let exact = r.state(*t - spec.t0);
            let mut sum = 0.0;
            for (j, idx) in ref_idx.iter().enumerate() {
                if let Some(i) = idx {
                    let d = (y[*i] - exact[j]).abs();
                    sum += d;
                    if j < 4 {
                        e_here = e_here.max(d);
                    }
                }
            }
            if is_check {
                let scale = exact[..4].iter().fold(1.0f64, |m, v| m.max(v.abs()));
                if e_here / scale > err_scaled || e_here.is_nan() {
                    err_scaled = e_here / scale;
                    worst_t = *t;
                }
                err = err.max(e_here);
                err_sum += sum;
                if let Some(i) = ref_idx[4] {
                    err_lambda = err_lambda.max((y[i] - exact[4]).abs());
                }
            }
        }
        if is_check {
            for (l, slot) in res.iter_mut().enumerate() {
                if info.constraints.iter().any(|c| c.level as usize == l) {
                    *slot = Some(slot.unwrap_or(0.0).max(lev[l]));
                }
            }
            for (d, (a, b)) in drift.iter_mut().zip(inv.iter().zip(&inv0)) {
                *d = d.max((a - b).abs());
            }
        }
        traj.t.push(*t);
        traj.y.push(y.clone());
        if spec.reference.is_some() {
            traj.err.push(e_here);
        }
        traj.residuals.push(lev);
        traj.drift.push(
            inv.first()
                .zip(inv0.first())
                .map_or(0.0, |(a, b)| (a - b).abs()),
        );
    }
    if spec.reference.is_some() {
        record.err = Some(err);
        record.err_sum = Some(err_sum);
        record.err_lambda = ref_idx[4].map(|_| err_lambda);
    }
    record.residuals = Residuals {
        level0: res[0],
        level1: res[1],
        level2: res[2],
    };
    record.invariant_drift = Named(info.invariants.iter().cloned().zip(drift).collect());
    let inv_scale: Vec<f64> = inv0.iter().map(|v| v.abs().max(1.0)).collect();
    let (accuracy, note) = verdict(spec, record, err_scaled, worst_t, &inv_scale);
    record.accuracy = Some(accuracy);
    record.accuracy_note = Some(note);
}

/// The accuracy verdict and its one-line reason (see [`Accuracy`]).
fn verdict(
    spec: &RunSpec<'_>,
    record: &RunRecord,
    err_scaled: f64,
    worst_t: f64,
    inv_scale: &[f64],
) -> (Accuracy, String) {
    let tol = spec.tol;
    if spec.reference.is_some() {
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
                "no reference; constraint residuals and invariant drift below {SUSPECT_FACTOR:.0e}·tol"
            ),
        )
    } else {
        (
            Accuracy::Suspect,
            format!(
                "no reference, but {} at or above {SUSPECT_FACTOR:.0e}·tol (scaled)",
                excess.join(", ")
            ),
        )
    }
}

//! `dae sweep`: every solver × formulation × tolerance of a scene, and the
//! paper's report of the speed/accuracy trade — success matrix, efficiency
//! table, Pareto front, fastest pair per target error, comparison with the
//! paper's tables, figures (on S01/S02 the work-precision diagram carries
//! the Fortran codes' curves as reference lines, [`fortran`]) and an
//! `index.html` that shows them together.
//!
//! # Flow
//! [`run`] loads the scene's model, decides for every pair whether it is
//! applicable ([`Pair::not_applicable`] gives the reason otherwise: the
//! model does not provide the formulation, or [`Solver::accepts`] refuses
//! it), runs every applicable pair at every tolerance with
//! [`crate::runner::run`] and returns a [`SweepReport`]. [`Summary::of`]
//! derives the tables; [`write_outputs`] writes `results.csv`,
//! `results.json`, the figures and `index.html` as one set
//! ([`write::publish_dir`]: a staging directory renamed into place).
//!
//! # Timing
//! `tsim_s` is the **minimum** over the timed integrations of the same run
//! (integration only: no model loading, no consistent initialisation, output
//! only at the check times), each measured as the **CPU time of the thread
//! that integrated** ([`crate::runner::timed`]). The computation is
//! deterministic, so what varies between its integrations is interference
//! (preemption, lost caches, a shared core's frequency), and interference
//! only ever adds time: the minimum is the statistic other work on the
//! machine moves least, as benchmark harnesses take it. The Pareto front and
//! the fastest pair per target use it, with runs closer in time than
//! [`pareto::TIME_RESOLUTION`] (5 %) tied and ordered by their error, step
//! and evaluation counts and name, which do not depend on the machine
//! ([`pareto`]; BENCHMARKS.md §8 measures how far their order holds between
//! an idle and a loaded machine, §8c describes the tie rule). The wall-clock
//! time of the same integrations is kept beside it (`wall_s`, their
//! minimum, and [`SweepRun::wall_runs`]).
//!
//! How often a run is timed: at least `repeats` times, and more while the
//! timings total less than [`SweepOptions::min_timed_cpu_s`] of CPU time
//! (default [`MIN_TIMED_CPU_S`]) or their minimum is not settled (fewer
//! than [`FLOOR_HITS`] timings within [`FLOOR_WIDTH`] of it), up to
//! [`MAX_TIMED`] integrations, so that a millisecond-long run, whose minimum
//! needs many samples, is timed tens of times, and a busy machine gets the
//! timings its noise needs; but never again once they
//! total [`REPEAT_BUDGET_S`], so a slow run (seconds each, where timing
//! noise is relatively small) is timed fewer than `repeats` times. Every
//! individual time is kept in [`SweepRun::tsim_runs`].
//!
//! The timings are taken in **rounds**: each round times once, in grid
//! order, every successful run that needs another timing
//! ([`more_timings`]). A run's timings are thus spread over the whole timing
//! pass, not taken in a row: a slow phase of the machine (another job's
//! burst, a lower clock) then reaches every run alike, instead of all the
//! timings of the few runs that happened to be timed during it, which a
//! minimum cannot undo. Timed integrations never overlap with other work
//! of the sweep:
//! - `jobs = 1` (default): a sequential accuracy pass, whose integration
//!   of a run (unless it also sampled the figures) is that run's first
//!   timing, then the timing rounds.
//! - `jobs > 1`: an accuracy pass runs the runs in parallel on a rayon
//!   pool of `jobs` threads (each thread loads its own model once), then
//!   the timing rounds, sequentially.
//!   Failed runs are not re-timed: their `tsim_s` is the time to failure of
//!   the one (parallel) attempt. The results are in grid order whatever
//!   the threads' schedule.
//!
//! # Progress
//! With `progress` set, a bar is drawn on stderr when it is a terminal;
//! otherwise (a pipe, a CI log) plain lines are printed to stderr every 5 %
//! of the runs or every 10 s, whichever comes first ([`progress`]).
//!
//! At the figure tolerance (1e-7 like the paper, else the sweep's nearest
//! in `log10`) one further, untimed integration samples the solution for the
//! figures: 801 equidistant times, or only the check times when a scene has
//! 100 or more of them (as the paper plots S02 "every 2 s only").
//!
//! [`Solver::accepts`]: dae_solvers::Solver::accepts

pub mod fortran;
pub mod html;
pub mod paper;
pub mod pareto;
pub mod plot;
pub mod progress;
pub mod table;
pub mod write;

use crate::inputs::{inputs, InputError};
use crate::runner::{self, RunError, RunRecord, RunSpec, Trajectory};
use crate::scene::{ModelSource, Scene};
use dae_core::system::{FormulationError, Model};
use dae_solvers::init::InitMode;
use progress::Progress;
use rayon::prelude::*;
use serde::Serialize;
use std::borrow::Borrow;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

/// The tolerance the paper's figures use.
pub const FIGURE_TOL: f64 = 1e-7;
/// Equidistant samples for the figures of scenes with few check times.
pub const FIGURE_SAMPLES: usize = 801;
/// From this many check times on, figures use the check times only.
pub const CHECKS_AS_SAMPLES: usize = 100;
/// A run is timed again only while its timed integrations took less than
/// this in total (seconds): a slow run is timed fewer than `repeats` times.
pub const REPEAT_BUDGET_S: f64 = 1.0;
/// A run is timed at least `repeats` times and then again while its timed
/// integrations took less than this CPU time in total (seconds), up to
/// [`MAX_TIMED`] times: short runs need more samples for a stable minimum
/// (the default of [`SweepOptions::min_timed_cpu_s`]).
pub const MIN_TIMED_CPU_S: f64 = 0.25;
/// At most this many timed integrations per run, unless `repeats` asks
/// for more.
pub const MAX_TIMED: usize = 50;
/// A run's minimum time counts as settled once this many of its timings
/// lie within [`FLOOR_WIDTH`] of it ([`more_timings`]).
pub const FLOOR_HITS: usize = 3;
/// How close to the minimum (relative) a timing must be to count as a hit
/// of the floor: a fifth of the ranking's 5 % resolution
/// ([`pareto::TIME_RESOLUTION`]), 1 %.
pub const FLOOR_WIDTH: f64 = pareto::TIME_RESOLUTION / 5.0;

/// What to sweep and how.
#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// Solver names (each known to [`dae_solvers::solver_by_name`]).
    pub solvers: Vec<String>,
    /// Formulation names (each one of the eight).
    pub formulations: Vec<String>,
    /// Tolerances, `RTOL = ATOL`, each in `[100 ε, 1)`.
    pub tolerances: Vec<f64>,
    /// Timed integrations per run, at least (fewer only once they took
    /// [`REPEAT_BUDGET_S`]; more while they took under `min_timed_cpu_s`,
    /// up to [`MAX_TIMED`]); the minimum is reported. At least 1.
    pub repeats: usize,
    /// Time a run again, beyond `repeats`, while its timings total less
    /// than this CPU time in seconds ([`more_timings`]); 0: exactly
    /// `repeats` timings (e.g. a map that does not rank by time).
    pub min_timed_cpu_s: f64,
    /// Threads of the accuracy pass; 1 = one sequential pass.
    pub jobs: usize,
    /// Project inconsistent initial values (default) or refuse them.
    pub init_mode: InitMode,
    /// Report progress on stderr: a bar on a terminal, plain lines
    /// otherwise ([`progress::Progress`]).
    pub progress: bool,
    /// Bound on the accepted steps of each run (`None`: the library's).
    pub max_steps: Option<usize>,
    /// Sample the solution at the figure tolerance for the figures
    /// (`false`: no figure samples, e.g. for the stability map).
    pub figures: bool,
}

impl SweepOptions {
    /// The scene's own `[sweep]` grid, 3 repeats and more for runs under
    /// [`MIN_TIMED_CPU_S`], sequential.
    pub fn from_scene(scene: &Scene) -> Self {
        SweepOptions {
            solvers: scene.sweep.solvers.clone(),
            formulations: scene.sweep.formulations.clone(),
            tolerances: scene.sweep.tolerances.clone(),
            repeats: 3,
            min_timed_cpu_s: MIN_TIMED_CPU_S,
            jobs: 1,
            init_mode: InitMode::Project,
            progress: true,
            max_steps: scene.sweep.max_steps,
            figures: true,
        }
    }
}

/// `; did you mean `NAME`?` when a known name is close to `name`
/// ([`dae_core::names::did_you_mean`]), or nothing.
fn suggest(name: &str, known: &[&str]) -> String {
    dae_core::names::did_you_mean(name, known)
        .map_or_else(String::new, |k| format!("; did you mean `{k}`?"))
}

/// Why a sweep could not run or its results could not be written.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A solver name that is not known.
    #[error(
        "unknown solver `{name}`{hint} (known: {known})",
        hint = suggest(name, &dae_solvers::SOLVER_NAMES),
        known = dae_solvers::SOLVER_NAMES.join(", ")
    )]
    UnknownSolver {
        /// The name given.
        name: String,
    },
    /// A formulation name that is not one of the eight.
    #[error(
        "unknown formulation `{name}`{hint} (known: {known})",
        hint = suggest(name, &dae_core::system::FORMULATION_NAMES),
        known = dae_core::system::FORMULATION_NAMES.join(", ")
    )]
    UnknownFormulation {
        /// The name given.
        name: String,
    },
    /// A tolerance outside [`dae_solvers::options::check_uniform`].
    #[error(
        "tolerance {tol:e} {issue}; tolerances (RTOL = ATOL) must be in {}",
        crate::runner::tolerance_range()
    )]
    BadTolerance {
        /// The value given.
        tol: f64,
        /// What is wrong with it.
        issue: dae_solvers::options::ToleranceIssue,
    },
    /// Nothing to sweep.
    #[error("nothing to sweep: no {what} given")]
    Empty {
        /// `solvers`, `formulations` or `tolerances`.
        what: &'static str,
    },
    /// The scene's model, parameters or reference could not be used.
    #[error(transparent)]
    Inputs(#[from] InputError),
    /// A run could not start (bad scene input, e.g. an unusable reference).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A worker thread panicked.
    #[error("a sweep worker thread panicked")]
    WorkerPanicked,
    /// The pool of worker threads could not be started.
    #[error("cannot start {threads} sweep worker thread(s): {source}")]
    ThreadPool {
        /// Threads asked for (`--jobs`).
        threads: usize,
        /// Rayon's error.
        source: rayon::ThreadPoolBuildError,
    },
    /// The output directory holds something a sweep did not write, so it
    /// is not replaced (see [`write_outputs`]).
    #[error(
        "will not replace {}: {}; a sweep replaces its output directory as a whole, so give a new or \
         empty directory, or one that holds only a sweep's outputs",
        dir.display(),
        if entry.is_empty() { "it is not a directory".to_string() } else { format!("it holds `{entry}`, which dae sweep does not write") }
    )]
    NotOurs {
        /// The output directory.
        dir: PathBuf,
        /// The first entry that is not a sweep output (empty: `dir` is not a
        /// directory).
        entry: String,
    },
    /// A file or directory could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// What was read.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The output set could not be published: another process holds the
    /// destination, it is a mount point, or the file system refused.
    #[error(transparent)]
    Publish(#[from] write::PublishError),
    /// A figure could not be drawn or written (a full disk shows here as
    /// the PNG encoder's error): the set is incomplete, so not published.
    #[error("cannot draw figure {file}: {source}")]
    Figure {
        /// The figure's file name, without extension.
        file: String,
        /// Why.
        source: plot::PlotError,
    },
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The destination.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// One solver × formulation pair of the grid.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pair {
    /// Solver.
    pub solver: String,
    /// Formulation.
    pub formulation: String,
    /// Why the pair is not run: "not provided by the model" or the
    /// solver's reason from `Solver::accepts`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_applicable: Option<String>,
}

/// One run of the sweep: the runner's record (serialised flat, exactly as
/// `dae run` prints it) plus every timed integration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepRun {
    /// The record; `tsim_s` is the minimum of `tsim_runs`, `wall_s` the
    /// minimum of `wall_runs`.
    #[serde(flatten)]
    pub record: RunRecord,
    /// Every timed integration in seconds: CPU time of the integrating
    /// thread ([`crate::runner::timed`]).
    pub tsim_runs: Vec<f64>,
    /// The wall-clock times of the same integrations, in the same order.
    pub wall_runs: Vec<f64>,
}

impl Borrow<RunRecord> for SweepRun {
    fn borrow(&self) -> &RunRecord {
        &self.record
    }
}

/// What was swept, in short.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneInfo {
    /// Scene name.
    pub name: String,
    /// Where it came from.
    pub origin: String,
    /// Model (built-in name or path).
    pub model: String,
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t_end: f64,
    /// Number of check times.
    pub checks: usize,
    /// Reference kind.
    pub reference: &'static str,
}

/// Everything a sweep measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepReport {
    /// The scene.
    pub scene: SceneInfo,
    /// Solvers, in row order.
    pub solvers: Vec<String>,
    /// Formulations, in column order.
    pub formulations: Vec<String>,
    /// Tolerances, in sweep order.
    pub tolerances: Vec<f64>,
    /// Timed integrations per run, at least (see [`SweepOptions::repeats`]).
    pub repeats: usize,
    /// See [`SweepOptions::min_timed_cpu_s`].
    pub min_timed_cpu_s: f64,
    /// Threads of the accuracy pass.
    pub jobs: usize,
    /// Bound on each run's steps (`None`: the library's).
    pub max_steps: Option<usize>,
    /// Tolerance of the solution, error and residual figures.
    pub figure_tol: f64,
    /// Every pair, applicable or not.
    pub pairs: Vec<Pair>,
    /// Every run, in pair × tolerance order.
    pub runs: Vec<SweepRun>,
    /// Wall-clock time of the whole sweep in seconds.
    pub wall_s: f64,
    /// Unknowns of the model, in order.
    pub variables: Vec<String>,
    /// Invariants of the model.
    pub invariants: Vec<String>,
    /// Constraint levels present in the model's chain, with their
    /// expressions (`level`, `0 = expr`).
    pub constraints: Vec<(u8, String)>,
    /// `true` when the scene is the paper's setup of S01 or S02
    /// ([`crate::scene::Scene::is_paper_setup`]; enables the paper
    /// comparison and the Fortran reference lines).
    #[serde(skip)]
    pub paper_setup: bool,
}

impl SweepReport {
    /// One line on the size of the sweep and how it was timed (shared by the
    /// terminal report and index.html).
    pub fn scale_line(&self) -> String {
        format!(
            "{} solver(s) × {} formulation(s) × {} tolerance(s): {} runs in {:.1} s (tsim = CPU time of the \
             integrating thread, minimum of at least {} timed integration(s) (more, up to {}, while they took under {} s; \
             fewer once they took {} s); wall time \
             beside it in results.csv; {}{})",
            self.solvers.len(),
            self.formulations.len(),
            self.tolerances.len(),
            self.runs.len(),
            self.wall_s,
            self.repeats,
            MAX_TIMED.max(self.repeats),
            self.min_timed_cpu_s,
            REPEAT_BUDGET_S,
            if self.jobs > 1 {
                format!("accuracy pass on {} threads, timing pass sequential", self.jobs)
            } else {
                "one sequential pass".to_string()
            },
            self.max_steps
                .map_or_else(String::new, |n| format!("; at most {n} steps per run"))
        )
    }

    /// Whether the scene has a reference (errors are measured).
    pub fn has_reference(&self) -> bool {
        self.scene.reference != "none"
    }

    /// The runs at the figure tolerance that succeeded, in pair order.
    pub fn figure_runs(&self) -> Vec<&SweepRun> {
        self.runs
            .iter()
            .filter(|r| r.record.status == "ok" && paper::same_tol(r.record.tol, self.figure_tol))
            .collect()
    }
}

/// The tables derived from a report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// X / x / o / - per pair.
    pub success: table::SuccessMatrix,
    /// The Pareto front at [`pareto::TIME_RESOLUTION`] ([`pareto::pareto_front`]).
    pub pareto: Vec<pareto::Point>,
    /// Fastest run per target error, ties in time going to the more
    /// accurate ([`pareto::targets`]).
    pub targets: Vec<pareto::Target>,
    /// Comparison with the paper under `err_sum` (scenes S01 and S02 only).
    pub paper: Option<paper::Comparison>,
    /// The same under `err_l2`, the reading of the paper's ERR under which
    /// the classic codes' measured errors reproduce it.
    pub paper_l2: Option<paper::Comparison>,
    /// The Fortran reference lines of the work-precision diagram (scenes
    /// S01 and S02 only; `None` also when the shipped data cannot be read,
    /// which the figures report as a note).
    pub reference_lines: Option<fortran::ReferenceLines>,
}

impl Summary {
    /// Derive the tables.
    pub fn of(report: &SweepReport) -> Summary {
        let table = paper::PaperTable::for_scene(
            &report.scene.name,
            report.paper_setup,
            report.scene.t_end,
        )
        .filter(|_| report.has_reference());
        let [paper, paper_l2] =
            paper::Measure::ALL.map(|m| table.as_ref().map(|t| paper::compare(t, report, m)));
        Summary {
            success: table::success_matrix(
                &report.solvers,
                &report.formulations,
                &report.pairs,
                &report.runs,
            ),
            pareto: pareto::pareto_front(&report.runs),
            targets: pareto::targets(&report.runs, &pareto::TARGETS),
            paper,
            paper_l2,
            reference_lines: fortran::ReferenceLines::for_report(report).ok().flatten(),
        }
    }
}

/// Median of a non-empty list (mean of the two middle values for an even
/// count); 0 for an empty one.
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The tolerance of the figures: 1e-7 if swept, else the nearest in log10
/// (the first of equally near ones).
pub fn figure_tol(tolerances: &[f64]) -> f64 {
    let dist = |t: f64| (t.log10() - FIGURE_TOL.log10()).abs();
    tolerances
        .iter()
        .copied()
        .fold(None::<f64>, |best, t| match best {
            Some(b) if dist(b) <= dist(t) => Some(b),
            _ => Some(t),
        })
        .unwrap_or(FIGURE_TOL)
}

/// Sample times of the figures (empty: the check times are used).
pub fn sample_times(scene: &Scene) -> Vec<f64> {
    if scene.time.checks.len() >= CHECKS_AS_SAMPLES {
        return Vec::new();
    }
    let (a, b) = (scene.time.start, scene.time.end);
    let n = FIGURE_SAMPLES - 1;
    (0..=n).map(|i| a + (b - a) * i as f64 / n as f64).collect()
}

/// Check the grid before anything runs.
pub fn validate(opts: &SweepOptions) -> Result<(), SweepError> {
    for (what, empty) in [
        ("solvers", opts.solvers.is_empty()),
        ("formulations", opts.formulations.is_empty()),
        ("tolerances", opts.tolerances.is_empty()),
    ] {
        if empty {
            return Err(SweepError::Empty { what });
        }
    }
    if let Some(s) = opts
        .solvers
        .iter()
        .find(|s| dae_solvers::solver_by_name(s).is_none())
    {
        return Err(SweepError::UnknownSolver { name: s.clone() });
    }
    if let Some(f) = opts
        .formulations
        .iter()
        .find(|f| !dae_core::system::FORMULATION_NAMES.contains(&f.as_str()))
    {
        return Err(SweepError::UnknownFormulation { name: f.clone() });
    }
    for &tol in &opts.tolerances {
        dae_solvers::options::check_uniform(tol)
            .map_err(|issue| SweepError::BadTolerance { tol, issue })?;
    }
    Ok(())
}

/// Every pair of the grid with its applicability.
pub fn pairs(
    model: &dyn Model,
    solvers: &[String],
    formulations: &[String],
) -> Result<Vec<Pair>, SweepError> {
    prepare(model, formulations);
    let mut out = Vec::new();
    for s in solvers {
        let solver = dae_solvers::solver_by_name(s)
            .ok_or_else(|| SweepError::UnknownSolver { name: s.clone() })?;
        for f in formulations {
            let not_applicable = match dae_core::selector::formulation(model, f, false, 0.0, &[]) {
                Ok((sys, _)) => solver.accepts(sys.info()).err().map(|why| why.to_string()),
                Err(FormulationError::NotProvided { .. }) => {
                    Some("not provided by the model".to_string())
                }
                Err(FormulationError::NoSelector { reason, .. }) => {
                    Some(format!("not provided by the model: {reason}"))
                }
                Err(FormulationError::Unknown { .. }) => {
                    return Err(SweepError::UnknownFormulation { name: f.clone() })
                }
            };
            out.push(Pair {
                solver: s.clone(),
                formulation: f.clone(),
                not_applicable,
            });
        }
    }
    Ok(out)
}

/// Have `model` build the grid's formulations together (a model read at
/// run time lowers them when first asked for, sharing the rows they have
/// in common only when asked together), with the `ovd1`/`ovd0` a
/// numerical selector builds `psi1`/`psi0` from.
fn prepare(model: &dyn Model, formulations: &[String]) {
    let mut names: Vec<&str> = formulations.iter().map(String::as_str).collect();
    for (psi, source) in [("psi1", "ovd1"), ("psi0", "ovd0")] {
        if names.contains(&psi) && !names.contains(&source) {
            names.push(source);
        }
    }
    model.prepare(&names);
}

/// One run of the grid.
#[derive(Clone, Debug)]
struct Job {
    solver: String,
    formulation: String,
    tol: f64,
    /// Sample the solution for the figures (an untimed integration).
    figure: bool,
}

/// What every run shares.
struct Ctx<'a> {
    scene: &'a Scene,
    inputs: crate::inputs::Inputs,
    init_mode: InitMode,
    samples: Vec<f64>,
    repeats: usize,
    min_timed_cpu_s: f64,
    max_steps: Option<usize>,
}

impl Ctx<'_> {
    /// `sweep S01` + `phase`: the prefix of the progress lines.
    fn label(&self, phase: &str) -> String {
        format!("sweep {}{phase}", self.scene.name)
    }

    fn run(&self, model: &dyn Model, job: &Job, samples: &[f64]) -> Result<RunRecord, RunError> {
        runner::run(&RunSpec {
            model,
            init_mode: self.init_mode,
            samples,
            max_steps: self.max_steps,
            ..self
                .inputs
                .spec(self.scene, &job.solver, &job.formulation, job.tol)
        })
    }

    /// The accuracy run: errors, statistics and (at the figure tolerance)
    /// the sampled trajectory. Its time counts as a timed integration only
    /// when it carried no extra samples.
    fn accuracy(&self, model: &dyn Model, job: &Job) -> Result<(RunRecord, bool), RunError> {
        let sampled = job.figure && !self.samples.is_empty();
        let mut rec = self.run(model, job, if sampled { &self.samples } else { &[] })?;
        if !job.figure {
            rec.trajectory = Trajectory::default();
        }
        Ok((rec, !sampled))
    }

    /// Does this run need another timing?
    fn needs_timing(&self, times: &Timings) -> bool {
        more_timings(&times.cpu, self.repeats, self.min_timed_cpu_s)
    }

    /// The timing rounds: each round adds one timed integration (output at
    /// the check times only) to every successful run that
    /// [`needs_timing`](Ctx::needs_timing), in grid order, until none does.
    /// Progress counts the runs whose timings are complete.
    fn timing_rounds(
        &self,
        model: &dyn Model,
        jobs: &[Job],
        runs: &mut [(RunRecord, Timings)],
        progress: bool,
    ) -> Result<(), RunError> {
        let mut pending: Vec<usize> = (0..runs.len())
            .filter(|&i| runs[i].0.status == "ok")
            .collect();
        let bar = Progress::new(&self.label(" timing"), pending.len(), progress);
        while !pending.is_empty() {
            let mut next = Vec::with_capacity(pending.len());
            for i in pending {
                let times = &mut runs[i].1;
                if self.needs_timing(times) {
                    bar.set_message(job_label(&jobs[i]));
                    times.push(&self.run(model, &jobs[i], &[])?);
                }
                if self.needs_timing(times) {
                    next.push(i);
                } else {
                    bar.inc();
                }
            }
            pending = next;
        }
        bar.finish();
        Ok(())
    }
}

/// Does a run whose timed integrations took `cpu` (seconds of CPU time
/// each) need another, when `repeats` were asked for and `min_cpu_s`
/// ([`SweepOptions::min_timed_cpu_s`])? Yes for the first; then no once
/// they total [`REPEAT_BUDGET_S`]; else yes below `repeats`; beyond that,
/// up to [`MAX_TIMED`] and unless `min_cpu_s` is 0, while they total under
/// `min_cpu_s` **or their floor is not yet reached**: fewer than
/// [`FLOOR_HITS`] timings lie within [`FLOOR_WIDTH`] of their minimum.
///
/// Why the floor: the minimum of a few timings of a run of tens of
/// milliseconds, each preempted several times on a busy machine, can sit
/// 20–50 % above the run's cost (BENCHMARKS.md §8d), while its minimum over
/// enough timings does not; the timings needed grow with the load, so the
/// rule asks the timings themselves whether the minimum is settled, rather
/// than fixing their number.
///
/// ```
/// use dae::sweep::{more_timings, MIN_TIMED_CPU_S};
/// assert!(more_timings(&[], 3, MIN_TIMED_CPU_S));
/// let ms = |t: &[f64]| t.iter().map(|x| x * 1e-3).collect::<Vec<_>>();
/// assert!(more_timings(&ms(&[1.0; 3]), 3, MIN_TIMED_CPU_S)); // 1 ms runs: more samples
/// assert!(!more_timings(&ms(&[1.0; 50]), 3, MIN_TIMED_CPU_S)); // ... up to 50
/// assert!(!more_timings(&[0.1; 3], 3, MIN_TIMED_CPU_S)); // 0.1 s runs: 3 at one floor suffice
/// assert!(more_timings(&[0.1, 0.13, 0.12], 3, MIN_TIMED_CPU_S)); // ... a scattered 3 do not
/// assert!(!more_timings(&[0.1, 0.13, 0.12, 0.2, 0.14, 0.15, 0.13, 0.11], 3, MIN_TIMED_CPU_S)); // 1 s: no more
/// assert!(!more_timings(&[2.0], 3, MIN_TIMED_CPU_S)); // a 2 s run: once
/// assert!(!more_timings(&[0.001], 1, 0.0)); // exactly `repeats`
/// ```
pub fn more_timings(cpu: &[f64], repeats: usize, min_cpu_s: f64) -> bool {
    let count = cpu.len();
    let total: f64 = cpu.iter().sum();
    if count == 0 {
        return true;
    }
    if total >= REPEAT_BUDGET_S {
        return false;
    }
    if count < repeats {
        return true;
    }
    if count >= MAX_TIMED || min_cpu_s <= 0.0 {
        return false;
    }
    let floor = minimum(cpu) * (1.0 + FLOOR_WIDTH);
    total < min_cpu_s || cpu.iter().filter(|&&t| t <= floor).count() < FLOOR_HITS
}

pub use crate::runner::minimum;

/// The timed integrations of one run: CPU and wall-clock seconds.
#[derive(Default)]
struct Timings {
    cpu: Vec<f64>,
    wall: Vec<f64>,
}

impl Timings {
    fn push(&mut self, rec: &RunRecord) {
        self.cpu.push(rec.tsim_s);
        self.wall.push(rec.wall_s);
    }

    /// The run with its minima and every time.
    fn into_run(self, mut record: RunRecord) -> SweepRun {
        record.tsim_s = minimum(&self.cpu);
        record.wall_s = minimum(&self.wall);
        SweepRun {
            record,
            tsim_runs: self.cpu,
            wall_runs: self.wall,
        }
    }
}

fn job_label(job: &Job) -> String {
    format!("{}({}) tol {:e}", job.solver, job.formulation, job.tol)
}

/// Run the sweep.
pub fn run(scene: &Scene, opts: &SweepOptions) -> Result<SweepReport, SweepError> {
    let start = Instant::now();
    validate(opts)?;
    let inputs = inputs(scene)?;
    let info = inputs.model.model_info().clone();
    let pairs = pairs(&*inputs.model, &opts.solvers, &opts.formulations)?;
    let fig_tol = figure_tol(&opts.tolerances);
    let jobs: Vec<Job> = pairs
        .iter()
        .filter(|p| p.not_applicable.is_none())
        .flat_map(|p| {
            opts.tolerances.iter().map(move |&tol| Job {
                solver: p.solver.clone(),
                formulation: p.formulation.clone(),
                tol,
                figure: opts.figures && paper::same_tol(tol, fig_tol),
            })
        })
        .collect();
    let ctx = Ctx {
        scene,
        inputs,
        init_mode: opts.init_mode,
        samples: sample_times(scene),
        repeats: opts.repeats.max(1),
        min_timed_cpu_s: opts.min_timed_cpu_s,
        max_steps: opts.max_steps,
    };
    let runs = if opts.jobs <= 1 {
        sequential(&ctx, &*ctx.inputs.model, &jobs, opts.progress)?
    } else {
        parallel(&ctx, &*ctx.inputs.model, &jobs, opts.jobs, opts.progress)?
    };
    let mut levels: Vec<(u8, String)> = info
        .constraints
        .iter()
        .map(|c| (c.level, c.expr.clone()))
        .collect();
    levels.sort_by_key(|(l, _)| *l);
    let paper_setup = scene.is_paper_setup();
    Ok(SweepReport {
        scene: SceneInfo {
            name: scene.name.clone(),
            origin: scene.origin.clone(),
            model: match &scene.model {
                ModelSource::Builtin(n) => n.clone(),
                ModelSource::File(p) => p.display().to_string(),
            },
            t0: scene.time.start,
            t_end: scene.time.end,
            checks: scene.time.checks.len(),
            reference: scene.reference.as_str(),
        },
        solvers: opts.solvers.clone(),
        formulations: opts.formulations.clone(),
        tolerances: opts.tolerances.clone(),
        repeats: ctx.repeats,
        min_timed_cpu_s: ctx.min_timed_cpu_s,
        jobs: opts.jobs.max(1),
        max_steps: opts.max_steps,
        figure_tol: fig_tol,
        pairs,
        runs,
        wall_s: start.elapsed().as_secs_f64(),
        variables: info.variables.iter().map(|v| v.name.clone()).collect(),
        invariants: info.invariants.clone(),
        constraints: levels,
        paper_setup,
    })
}

/// `jobs = 1`: a sequential accuracy pass (its integrations are the first
/// timings), then the timing rounds.
fn sequential(
    ctx: &Ctx<'_>,
    model: &dyn Model,
    jobs: &[Job],
    progress: bool,
) -> Result<Vec<SweepRun>, SweepError> {
    let bar = Progress::new(&ctx.label(""), jobs.len(), progress);
    let mut runs = Vec::with_capacity(jobs.len());
    for job in jobs {
        bar.set_message(job_label(job));
        let (record, timed) = ctx.accuracy(model, job)?;
        let mut times = Timings::default();
        if timed || record.status != "ok" {
            times.push(&record);
        }
        runs.push((record, times));
        bar.inc();
    }
    bar.finish();
    ctx.timing_rounds(model, jobs, &mut runs, progress)?;
    Ok(runs
        .into_iter()
        .map(|(record, times)| times.into_run(record))
        .collect())
}

/// `jobs > 1`: a parallel accuracy pass on a rayon pool of `threads`
/// threads, then the (sequential) timing rounds.
fn parallel(
    ctx: &Ctx<'_>,
    model: &dyn Model,
    jobs: &[Job],
    threads: usize,
    progress: bool,
) -> Result<Vec<SweepRun>, SweepError> {
    let threads = threads.min(jobs.len().max(1));
    let mut formulations: Vec<String> = jobs.iter().map(|j| j.formulation.clone()).collect();
    formulations.sort();
    formulations.dedup();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("dae-sweep-{i}"))
        .build()
        .map_err(|source| SweepError::ThreadPool { threads, source })?;
    // One model per worker thread, loaded by the thread on its first run
    // (one model instance is never integrated by two threads at once). A
    // model that fails to load leaves its slot empty and its error in
    // `load_error`, returned once the pass stops.
    let models: Vec<OnceLock<Option<Box<dyn Model + Send + Sync>>>> =
        (0..threads).map(|_| OnceLock::new()).collect();
    let load_error: Mutex<Option<InputError>> = Mutex::new(None);
    let bar = Progress::new(&ctx.label(" accuracy"), jobs.len(), progress);
    let records: Result<Vec<RunRecord>, SweepError> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let slot = rayon::current_thread_index()
                    .and_then(|i| models.get(i))
                    .ok_or(SweepError::WorkerPanicked)?;
                let model = slot.get_or_init(|| match crate::inputs::model(ctx.scene) {
                    Ok(m) => {
                        prepare(&*m, &formulations);
                        Some(m)
                    }
                    Err(e) => {
                        if let Ok(mut first) = load_error.lock() {
                            first.get_or_insert(e);
                        }
                        None
                    }
                });
                let Some(model) = model else {
                    return Err(SweepError::WorkerPanicked);
                };
                bar.set_message(job_label(job));
                let (rec, _) = ctx.accuracy(&**model, job)?;
                bar.inc();
                Ok(rec)
            })
            .collect()
    });
    if let Some(e) = load_error.into_inner().ok().flatten() {
        return Err(SweepError::Inputs(e));
    }
    let records = records?;
    bar.finish();
    // A failed run keeps the time to failure of its one attempt.
    let mut runs: Vec<(RunRecord, Timings)> = records
        .into_iter()
        .map(|record| {
            let mut times = Timings::default();
            if record.status != "ok" {
                times.push(&record);
            }
            (record, times)
        })
        .collect();
    ctx.timing_rounds(model, jobs, &mut runs, progress)?;
    Ok(runs
        .into_iter()
        .map(|(record, times)| times.into_run(record))
        .collect())
}

/// The JSON document `results.json`:
///
/// ```text
/// { "scene":   {name, origin, model, t0, t_end, checks, reference},
///   "sweep":   {solvers, formulations, tolerances, repeats, min_timed_cpu_s, jobs, max_steps, figure_tol, wall_s, pairs: [...]},
///   "runs":    [ RunRecord fields (as `dae run` prints them) + "tsim_runs": [...] ],
///   "success": {legend, formulations, rows: [{solver, cells: [{formulation, mark, ok, runs, reason?}]}]},
///   "pareto":  {error: "err", time_resolution: 0.05, definition,
///               rows: [{solver, formulation, tol, tsim_s, err, steps, evals}]},
///   "targets": {error: "err", time_resolution: 0.05, definition,
///               rows: [{target, best: {solver, formulation, tol, tsim_s, err, steps, evals} | null,
///                       tied: [the same, the runs best was tied with in time]}]},
///   "paper":   {table, measure: "err_sum", note, rows: [...], counts: [...]} | null,
///   "paper_l2": the same with measure "err_l2" | null,
///   "reference_lines": {scenario, note, header, calibration,
///                       curves: [{label, code, formulation, time_column, files,
///                                 points: [{tol, err, time_s, steps}], failed}]} | null }
/// ```
///
/// `reference_lines` are the Fortran curves drawn as reference lines in the
/// work-precision diagram (measured elsewhere, not by this sweep; see
/// [`fortran`]).
pub fn results_json(report: &SweepReport, summary: &Summary) -> serde_json::Value {
    serde_json::to_value(ResultsDoc::new(report, summary)).unwrap_or(serde_json::Value::Null)
}

/// `results.json`, field by field in document order.
#[derive(Serialize)]
struct ResultsDoc<'a> {
    scene: &'a SceneInfo,
    sweep: SweepDoc<'a>,
    runs: &'a [SweepRun],
    success: &'a table::SuccessMatrix,
    pareto: Explained<&'a [pareto::Point]>,
    targets: Explained<&'a [pareto::Target]>,
    paper: Option<&'a paper::Comparison>,
    paper_l2: Option<&'a paper::Comparison>,
    reference_lines: Option<&'a fortran::ReferenceLines>,
}

#[derive(Serialize)]
struct SweepDoc<'a> {
    solvers: &'a [String],
    formulations: &'a [String],
    tolerances: &'a [f64],
    repeats: usize,
    min_timed_cpu_s: f64,
    jobs: usize,
    max_steps: Option<usize>,
    figure_tol: f64,
    wall_s: f64,
    pairs: &'a [Pair],
}

#[derive(Serialize)]
struct Explained<T> {
    error: &'static str,
    time_resolution: f64,
    definition: &'static str,
    rows: T,
}

impl<'a> ResultsDoc<'a> {
    fn new(report: &'a SweepReport, summary: &'a Summary) -> Self {
        ResultsDoc {
            scene: &report.scene,
            sweep: SweepDoc {
                solvers: &report.solvers,
                formulations: &report.formulations,
                tolerances: &report.tolerances,
                repeats: report.repeats,
                min_timed_cpu_s: report.min_timed_cpu_s,
                jobs: report.jobs,
                max_steps: report.max_steps,
                figure_tol: report.figure_tol,
                wall_s: report.wall_s,
                pairs: &report.pairs,
            },
            runs: &report.runs,
            success: &summary.success,
            pareto: Explained {
                error: "err",
                time_resolution: pareto::TIME_RESOLUTION,
                definition: pareto::FRONT_RULE,
                rows: &summary.pareto,
            },
            targets: Explained {
                error: "err",
                time_resolution: pareto::TIME_RESOLUTION,
                definition: pareto::TARGET_RULE,
                rows: &summary.targets,
            },
            paper: summary.paper.as_ref(),
            paper_l2: summary.paper_l2.as_ref(),
            reference_lines: summary.reference_lines.as_ref(),
        }
    }
}

/// Serialise `results.json` (pretty, with a final newline).
pub fn results_json_string(report: &SweepReport, summary: &Summary) -> String {
    serde_json::to_string_pretty(&ResultsDoc::new(report, summary)).unwrap_or_default() + "\n"
}

/// What [`write_outputs`] wrote.
#[derive(Clone, Debug, Default)]
pub struct Outputs {
    /// Files written, in order.
    pub files: Vec<PathBuf>,
    /// Figures left out (nothing to draw), and why.
    pub notes: Vec<String>,
}

fn write_file(dir: &Path, name: &str, bytes: &[u8], out: &mut Outputs) -> Result<(), SweepError> {
    let path = dir.join(name);
    write::atomic_write(&path, bytes).map_err(|source| SweepError::Write {
        path: path.clone(),
        source,
    })?;
    out.files.push(path);
    Ok(())
}

/// Whether `name` is a file `dae sweep` writes into its output directory
/// (`results.csv`, `results.json`, `index.html`, figures as `.svg` and
/// `.png`), or a temporary file of an older version of it (`.NAME.tmp-…`).
pub fn is_output_name(name: &str) -> bool {
    matches!(
        name,
        "results.csv" | "results.json" | "index.html" | "map.txt" | "map.json"
    ) || name.ends_with(".svg")
        || name.ends_with(".png")
        || (name.starts_with('.') && name.contains(".tmp-"))
}

/// `Ok` when `dir` may be replaced by a sweep's output: it does not exist,
/// or it is a directory holding only files a sweep writes
/// ([`is_output_name`]). Anything else — a subdirectory, a file of the
/// user's — is [`SweepError::NotOurs`], so a sweep never deletes what it
/// did not write.
pub fn check_replaceable(dir: &Path) -> Result<(), SweepError> {
    let io = |source| SweepError::Write {
        path: dir.to_path_buf(),
        source,
    };
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(_) if dir.exists() && !dir.is_dir() => {
            return Err(SweepError::NotOurs {
                dir: dir.to_path_buf(),
                entry: String::new(),
            })
        }
        Err(e) => return Err(io(e)),
    };
    for entry in entries {
        let entry = entry.map_err(io)?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_file = entry.file_type().map_err(io)?.is_file();
        if !(is_file && is_output_name(&name)) {
            return Err(SweepError::NotOurs {
                dir: dir.to_path_buf(),
                entry: name,
            });
        }
    }
    Ok(())
}

/// Produce the output directory `dir` as one set: refuse a `dir` that holds
/// anything but sweep outputs ([`check_replaceable`]), then let `fill`
/// write every file into a staging directory that replaces `dir` only when
/// complete ([`write::publish_dir`], under `lock` or, if `None`, a lock
/// taken here). Shared by [`write_outputs`] and the stability map.
pub fn publish<T>(
    dir: &Path,
    lock: Option<&write::OutputLock>,
    fill: impl FnOnce(&Path) -> Result<T, SweepError>,
) -> Result<T, SweepError> {
    check_replaceable(dir)?;
    write::publish_dir(dir, lock, fill)
}

/// Write `results.csv`, `results.json`, the figures (SVG and PNG) and
/// `index.html` as one set into `dir`. A figure that cannot be drawn or
/// written is an error ([`SweepError::Figure`]): the set would be
/// incomplete, so the previous one stays. `lock`: the destination's lock if
/// the caller took it before the work (the command line does), else `None`.
///
/// The set is atomic ([`write::publish_dir`]): everything is written into a
/// staging directory `.<dir name>.dae-sweep-new-…` beside `dir` and renamed
/// to `dir` only when complete, so a failed or killed sweep leaves the
/// previous output whole and nothing partial in `dir`. An existing `dir` is
/// replaced as a whole — files of an earlier sweep that this one does not
/// write (a figure of a solver no longer swept) are gone — and only if it
/// holds nothing but sweep outputs ([`check_replaceable`]); otherwise the
/// sweep refuses before writing. Leftovers of a killed run beside `dir`
/// are removed by the next one.
pub fn write_outputs(
    report: &SweepReport,
    summary: &Summary,
    dir: &Path,
    lock: Option<&write::OutputLock>,
) -> Result<Outputs, SweepError> {
    let mut out = publish(dir, lock, |staging| fill_outputs(report, summary, staging))?;
    // The files were written in the staging directory: report them where
    // they are now.
    for f in &mut out.files {
        if let Some(name) = f.file_name() {
            *f = dir.join(name);
        }
    }
    Ok(out)
}

/// Every output file into `dir` (an empty staging directory).
fn fill_outputs(
    report: &SweepReport,
    summary: &Summary,
    dir: &Path,
) -> Result<Outputs, SweepError> {
    let mut out = Outputs::default();
    let csv = table::results_csv(report).map_err(|source| SweepError::Write {
        path: dir.join("results.csv"),
        source,
    })?;
    write_file(dir, "results.csv", &csv, &mut out)?;
    let json = results_json_string(report, summary);
    write_file(dir, "results.json", json.as_bytes(), &mut out)?;
    let figures = plot::figures(report);
    for fig in &figures.figures {
        let files = plot::render(fig, dir).map_err(|source| SweepError::Figure {
            file: fig.file.clone(),
            source,
        })?;
        out.files.extend(files);
    }
    out.notes.extend(figures.notes.iter().cloned());
    let drawn: Vec<&plot::Figure> = figures
        .figures
        .iter()
        .filter(|f| {
            out.files
                .iter()
                .any(|p| p.ends_with(format!("{}.svg", f.file)))
        })
        .collect();
    let page = html::index(report, summary, &drawn, &out.notes);
    write_file(dir, "index.html", page.as_bytes(), &mut out)?;
    Ok(out)
}

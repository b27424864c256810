//! The stability map: every extreme case × solver × formulation ×
//! tolerance → what happened.
//!
//! A *case* is a scene file (the shipped ones are `scenes/extremes/*.toml`:
//! loose and tight tolerances, a long horizon, releases up to 179.99°, a
//! pendulum looping over the top, g/l, m and l over many decades,
//! inconsistent starts, bad values). Each case is swept with its own
//! `[sweep]` grid, every run bounded by a step limit, and every run lands in
//! one [`Class`]: accurate, inaccurate, unverified, suspect, failed with a
//! typed error (and where), or stopped at the step limit. A case that
//! cannot even start (a scene or model error, an unusable reference) is
//! one row saying so, at the stage where it was refused.
//!
//! The output is a text table ([`text`]), a JSON document ([`json`]) and a
//! heat map ([`draw_heat_map`]: rows case × tolerance, columns solver ×
//! formulation, colour log₁₀(err / tol) for finished runs with a reference,
//! a fixed colour per failure class otherwise). `dae sweep --extremes`
//! writes all three.

use crate::runner::{Accuracy, RunRecord, ACCURATE_FACTOR, SUSPECT_FACTOR};
use crate::scene::Scene;
use crate::sweep::plot::PlotError;
use crate::sweep::{self, SweepError, SweepOptions, SweepReport};
use dae_solvers::init::InitMode;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Step limit of every run of the map (each run is bounded and says so when
/// it stops there): 5·10⁶ accepted steps, twice what the slowest applicable
/// pair needs on S02 at 1e-12 (odbdf, 2.3·10⁶), and room for radau5 over the
/// 2·10⁴ s horizon case at 1e-6 (≈ 2.7·10⁶).
pub const MAP_MAX_STEPS: usize = 5_000_000;

/// What makes a finished run with a reference accurate.
///
/// ```
/// use dae::stability::Verdict;
///
/// // At tol 1e-8 the literature map wants 6 significant correct digits.
/// assert!(Verdict::Digits.accepts(6.0, 1e-8));
/// assert!(!Verdict::Digits.accepts(5.9, 1e-8));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The run's own verdict ([`crate::runner::Accuracy`]): the error within
    /// [`ACCURATE_FACTOR`]·tol·max(1, |y*|) at every check time (the
    /// stability map of the extremes).
    #[default]
    Accuracy,
    /// Significant correct digits against the published reference, as the
    /// IVP Test Set defines them (`scd` = −log₁₀ of the largest error,
    /// relative where the scene says so): accurate when
    /// `scd ≥ −log₁₀(tol) − 2` (the literature map, issue 26).
    Digits,
}

impl Verdict {
    /// Digits a run at `tol` needs under [`Verdict::Digits`].
    pub fn digits_needed(tol: f64) -> f64 {
        -tol.log10() - 2.0
    }

    /// Whether `scd` digits are enough at `tol` (always under
    /// [`Verdict::Accuracy`], which does not look at digits).
    pub fn accepts(self, scd: f64, tol: f64) -> bool {
        match self {
            Verdict::Accuracy => true,
            // A small slack for the printing of tol (1e-8 is not exactly
            // 10⁻⁸): 6 digits at 1e-8 are 6 digits.
            Verdict::Digits => scd >= Self::digits_needed(tol) - 1e-9,
        }
    }
}

/// How to build a map.
#[derive(Clone, Debug)]
pub struct MapOptions {
    /// Threads of each case's sweep.
    pub jobs: usize,
    /// Step limit per run.
    pub max_steps: usize,
    /// Only these solvers (all of each case's when `None`).
    pub solvers: Option<Vec<String>>,
    /// Only these tolerances (each case's own when `None`).
    pub tolerances: Option<Vec<f64>>,
    /// Progress bars on stderr.
    pub progress: bool,
    /// What makes a finished run accurate.
    pub verdict: Verdict,
}

impl Default for MapOptions {
    fn default() -> Self {
        MapOptions {
            jobs: 1,
            max_steps: MAP_MAX_STEPS,
            solvers: None,
            tolerances: None,
            progress: false,
            verdict: Verdict::Accuracy,
        }
    }
}

/// What one run of the map came to.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "class")]
pub enum Class {
    /// Reached the end; error against the reference within the threshold.
    Accurate,
    /// Reached the end; error against the reference above the threshold.
    Inaccurate,
    /// Reached the end; no reference, residuals and drift unremarkable.
    Unverified,
    /// Reached the end; no reference, residuals or drift far above tol.
    Suspect,
    /// Stopped at the step limit.
    StepLimit {
        /// Time reached.
        t: f64,
    },
    /// Failed with a typed solver error (`kind` as in `dae run`'s JSON).
    Failed {
        /// The error's kind.
        kind: String,
        /// Where it happened, if known.
        t: Option<f64>,
        /// The message.
        message: String,
    },
    /// The solver does not take this formulation (or the model has none).
    NotApplicable {
        /// Why.
        why: String,
    },
}

impl Class {
    fn of(rec: &RunRecord) -> Class {
        if let Some(e) = &rec.error {
            if e.kind == "step_limit" {
                return Class::StepLimit {
                    t: e.t.unwrap_or(rec.t_end),
                };
            }
            return Class::Failed {
                kind: e.kind.clone(),
                t: e.t,
                message: e.message.clone(),
            };
        }
        match rec.accuracy {
            Some(Accuracy::Accurate) => Class::Accurate,
            Some(Accuracy::Inaccurate) => Class::Inaccurate,
            Some(Accuracy::Suspect) => Class::Suspect,
            Some(Accuracy::Unverified) | None => Class::Unverified,
        }
    }

    /// One character for the text map.
    pub fn symbol(&self) -> char {
        match self {
            Class::Accurate => 'A',
            Class::Inaccurate => 'i',
            Class::Unverified => 'u',
            Class::Suspect => 's',
            Class::StepLimit { .. } => 'L',
            Class::Failed { .. } => 'F',
            Class::NotApplicable { .. } => '-',
        }
    }

    fn is_failure(&self) -> bool {
        matches!(self, Class::StepLimit { .. } | Class::Failed { .. })
    }
}

/// One cell of the map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// Solver.
    pub solver: String,
    /// Formulation.
    pub formulation: String,
    /// Tolerance (`None` for a pair that was not run).
    pub tol: Option<f64>,
    /// What happened.
    #[serde(flatten)]
    pub class: Class,
    /// Error against the reference (if any).
    pub err: Option<f64>,
    /// Significant correct digits against the reference (if any; see
    /// [`crate::runner::RunRecord::scd`]).
    pub scd: Option<f64>,
    /// Largest invariant drift over the check times.
    pub drift: Option<f64>,
    /// Largest position-level constraint residual.
    pub g0: Option<f64>,
    /// Accepted steps.
    pub steps: usize,
    /// What the accuracy verdict rests on (see [`crate::runner::Accuracy`]).
    pub note: Option<String>,
}

/// Where a case that could not start was refused.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Refusal {
    /// `scene` (loading the file), `model` or `run` (the reference or
    /// another input of every run).
    pub stage: &'static str,
    /// The typed error, rendered.
    pub message: String,
}

/// One case of the map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Case {
    /// The scene file.
    pub file: String,
    /// The scene's name, when it loaded.
    pub scene: Option<String>,
    /// Why the case could not start, if it could not.
    pub refused: Option<Refusal>,
    /// Tolerances of its grid.
    pub tolerances: Vec<f64>,
    /// Every cell, in solver × formulation × tolerance order.
    pub cells: Vec<Cell>,
    /// Wall-clock seconds of the case.
    pub wall_s: f64,
}

/// The whole map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StabilityMap {
    /// What makes a finished run with a reference accurate.
    pub verdict: Verdict,
    /// The accuracy threshold: a run with a reference is accurate when
    /// `err ≤ threshold · tol`.
    pub threshold: f64,
    /// Step limit per run.
    pub max_steps: usize,
    /// Every case, in file-name order.
    pub cases: Vec<Case>,
}

/// Counts over the map.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Counts {
    /// Runs made.
    pub runs: usize,
    /// Per class symbol: accurate, inaccurate, unverified, suspect.
    pub accurate: usize,
    /// Finished above the threshold.
    pub inaccurate: usize,
    /// Finished without a reference.
    pub unverified: usize,
    /// Finished without a reference, flagged.
    pub suspect: usize,
    /// Stopped at the step limit.
    pub step_limit: usize,
    /// Typed solver errors.
    pub failed: usize,
    /// Cases refused before any run.
    pub refused_cases: usize,
}

impl StabilityMap {
    /// Count the cells by class.
    pub fn counts(&self) -> Counts {
        let mut c = Counts::default();
        for case in &self.cases {
            if case.refused.is_some() {
                c.refused_cases += 1;
            }
            for cell in &case.cells {
                match cell.class {
                    Class::NotApplicable { .. } => continue,
                    Class::Accurate => c.accurate += 1,
                    Class::Inaccurate => c.inaccurate += 1,
                    Class::Unverified => c.unverified += 1,
                    Class::Suspect => c.suspect += 1,
                    Class::StepLimit { .. } => c.step_limit += 1,
                    Class::Failed { .. } => c.failed += 1,
                }
                c.runs += 1;
            }
        }
        c
    }
}

/// The case files of a directory: every `*.toml`, sorted by name.
pub fn case_files(dir: &Path) -> Result<Vec<PathBuf>, SweepError> {
    let entries = std::fs::read_dir(dir).map_err(|source| SweepError::Read {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    Ok(files)
}

/// Build the map over `files`. Never fails on a case: a case that cannot
/// run is a refused row. Fails only on bad options (an unknown solver or a
/// bad tolerance given to every case).
pub fn build(files: &[PathBuf], opts: &MapOptions) -> Result<StabilityMap, SweepError> {
    let mut cases = Vec::with_capacity(files.len());
    for file in files {
        cases.push(case(file, opts)?);
    }
    Ok(StabilityMap {
        verdict: opts.verdict,
        threshold: ACCURATE_FACTOR,
        max_steps: opts.max_steps,
        cases,
    })
}

fn case(file: &Path, opts: &MapOptions) -> Result<Case, SweepError> {
    let start = std::time::Instant::now();
    let label = file.display().to_string();
    let refused = |stage, message: String, scene: Option<String>| Case {
        file: label.clone(),
        scene,
        refused: Some(Refusal { stage, message }),
        tolerances: Vec::new(),
        cells: Vec::new(),
        wall_s: start.elapsed().as_secs_f64(),
    };
    let scene = match Scene::load(file) {
        Ok(s) => s,
        Err(e) => return Ok(refused("scene", e.to_string(), None)),
    };
    let mut sweep_opts = SweepOptions::from_scene(&scene);
    // The map does not rank by time: one timing per run.
    sweep_opts.repeats = 1;
    sweep_opts.min_timed_cpu_s = 0.0;
    sweep_opts.jobs = opts.jobs.max(1);
    sweep_opts.progress = opts.progress;
    sweep_opts.init_mode = InitMode::Project;
    sweep_opts.max_steps = Some(opts.max_steps);
    sweep_opts.figures = false;
    if let Some(s) = &opts.solvers {
        sweep_opts.solvers = s.clone();
    }
    if let Some(t) = &opts.tolerances {
        sweep_opts.tolerances = t.clone();
    }
    sweep::validate(&sweep_opts)?;
    let report = match sweep::run(&scene, &sweep_opts) {
        Ok(r) => r,
        Err(e @ SweepError::Inputs(_)) => {
            return Ok(refused("model", e.to_string(), Some(scene.name)))
        }
        Err(e @ SweepError::Run(_)) => return Ok(refused("run", e.to_string(), Some(scene.name))),
        Err(e) => return Err(e),
    };
    Ok(Case {
        file: label,
        scene: Some(scene.name.clone()),
        refused: None,
        tolerances: sweep_opts.tolerances.clone(),
        cells: cells(&report, opts.verdict),
        wall_s: start.elapsed().as_secs_f64(),
    })
}

fn cells(report: &SweepReport, verdict: Verdict) -> Vec<Cell> {
    let mut out = Vec::new();
    for p in &report.pairs {
        if let Some(why) = &p.not_applicable {
            out.push(Cell {
                solver: p.solver.clone(),
                formulation: p.formulation.clone(),
                tol: None,
                class: Class::NotApplicable { why: why.clone() },
                err: None,
                scd: None,
                drift: None,
                g0: None,
                steps: 0,
                note: None,
            });
            continue;
        }
        for run in report
            .runs
            .iter()
            .filter(|r| r.record.solver == p.solver && r.record.formulation == p.formulation)
        {
            let rec = &run.record;
            let mut note = rec.accuracy_note.clone();
            let class = match (Class::of(rec), rec.scd) {
                (Class::Accurate | Class::Inaccurate, Some(scd)) if verdict == Verdict::Digits => {
                    let needed = Verdict::digits_needed(rec.tol);
                    if verdict.accepts(scd, rec.tol) {
                        note = Some(format!("scd {scd:.2} >= {needed:.0} needed at this tol"));
                        Class::Accurate
                    } else {
                        note = Some(format!("scd {scd:.2} < {needed:.0} needed at this tol"));
                        Class::Inaccurate
                    }
                }
                (class, _) => class,
            };
            out.push(Cell {
                solver: rec.solver.clone(),
                formulation: rec.formulation.clone(),
                tol: Some(rec.tol),
                class,
                err: rec.err,
                scd: rec.scd,
                drift: rec
                    .invariant_drift
                    .0
                    .iter()
                    .map(|(_, d)| *d)
                    .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.max(d)))),
                g0: rec.residuals.level(0),
                steps: rec.stats.steps,
                note,
            });
        }
    }
    out
}

fn short(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.1e}"))
}

/// The map as text: per case, one row per solver, one column per
/// formulation, one symbol per tolerance (`A` accurate, `i` inaccurate,
/// `u` unverified, `s` suspect, `L` step limit, `F` failed, `-` not
/// applicable); then every failure with its typed error and time.
pub fn text(map: &StabilityMap) -> String {
    let mut s = String::new();
    let accurate = match map.verdict {
        Verdict::Accuracy => format!("err <= {}·tol·max(1,|y*|)", map.threshold),
        Verdict::Digits => "scd >= -log10(tol) - 2 against the published reference".into(),
    };
    let _ = writeln!(
        s,
        "Stability map: A accurate ({accurate}), i inaccurate, u unverified (no reference), \
         s suspect (residual or drift >= {:e}·tol), L step limit ({} steps), F failed, - not applicable; \
         one symbol per tolerance",
        SUSPECT_FACTOR, map.max_steps
    );
    for case in &map.cases {
        let name = case.scene.as_deref().unwrap_or("?");
        let _ = writeln!(s, "\n{}  ({name}, {:.1} s)", case.file, case.wall_s);
        if let Some(r) = &case.refused {
            let _ = writeln!(s, "  refused at {}: {}", r.stage, r.message);
            continue;
        }
        let tols: Vec<String> = case.tolerances.iter().map(|t| format!("{t:e}")).collect();
        let _ = writeln!(s, "  tolerances: {}", tols.join(", "));
        let (solvers, formulations) = axes(&case.cells);
        let width = case.tolerances.len().max(4);
        let _ = write!(s, "  {:<8}", "");
        for f in &formulations {
            let _ = write!(s, " {f:<width$}");
        }
        s.push('\n');
        for sv in &solvers {
            let _ = write!(s, "  {sv:<8}");
            for f in &formulations {
                let sym: String = case
                    .cells
                    .iter()
                    .filter(|c| &c.solver == sv && &c.formulation == f)
                    .map(|c| c.class.symbol())
                    .collect();
                let _ = write!(s, " {sym:<width$}");
            }
            s.push('\n');
        }
        if map.verdict == Verdict::Digits {
            digits_table(&mut s, case, &solvers, &formulations);
        }
        for c in case.cells.iter().filter(|c| c.class.is_failure()) {
            let what = match &c.class {
                Class::StepLimit { t } => format!("step limit at t = {t:.6e}"),
                Class::Failed { kind, t, message } => match t {
                    Some(t) => format!("{kind} at t = {t:.6e}: {message}"),
                    None => format!("{kind}: {message}"),
                },
                _ => unreachable!("filtered to failures"),
            };
            let _ = writeln!(
                s,
                "  {}({}) tol {:e}: {what}",
                c.solver,
                c.formulation,
                c.tol.unwrap_or(f64::NAN)
            );
        }
        for c in case
            .cells
            .iter()
            .filter(|c| matches!(c.class, Class::Inaccurate | Class::Suspect))
        {
            let _ = writeln!(
                s,
                "  {}({}) tol {:e}: {} (err {}{}, |g0| {}, drift {}){}",
                c.solver,
                c.formulation,
                c.tol.unwrap_or(f64::NAN),
                if c.class == Class::Inaccurate {
                    "inaccurate"
                } else {
                    "suspect"
                },
                short(c.err),
                c.scd.map_or(String::new(), |d| format!(", scd {d:.2}")),
                short(c.g0),
                short(c.drift),
                c.note
                    .as_deref()
                    .map_or(String::new(), |n| format!(": {n}"))
            );
        }
    }
    let c = map.counts();
    let _ = writeln!(
        s,
        "\n{} runs: {} accurate, {} inaccurate, {} unverified, {} suspect, {} at the step limit, {} failed; \
         {} case(s) refused before any run",
        c.runs, c.accurate, c.inaccurate, c.unverified, c.suspect, c.step_limit, c.failed, c.refused_cases
    );
    s
}

/// Per solver(formulation), one column per tolerance: the significant
/// correct digits and the accepted steps of the run (`A9.6/2768`: the
/// class symbol, scd, steps), or only the class symbol where the run did
/// not finish (`F`, `L`) or has no digits.
fn digits_table(s: &mut String, case: &Case, solvers: &[String], formulations: &[String]) {
    let _ = write!(s, "  scd/steps {:<12}", "");
    for t in &case.tolerances {
        let _ = write!(s, " {:>12}", format!("{t:.0e}"));
    }
    s.push('\n');
    for sv in solvers {
        for f in formulations {
            let row: Vec<&Cell> = case
                .cells
                .iter()
                .filter(|c| &c.solver == sv && &c.formulation == f && c.tol.is_some())
                .collect();
            if row.is_empty() {
                continue;
            }
            let _ = write!(s, "  {:<22}", format!("{sv}({f})"));
            for t in &case.tolerances {
                let entry = row
                    .iter()
                    .find(|c| c.tol == Some(*t))
                    .map_or_else(String::new, |c| match (&c.class, c.scd) {
                        (Class::Accurate | Class::Inaccurate, Some(d)) => {
                            format!("{}{d:.1}/{}", c.class.symbol(), c.steps)
                        }
                        // A run that did not finish has no digits (and a
                        // failed one no step count): its symbol; the failure
                        // lines below say what and where.
                        (class, _) => class.symbol().to_string(),
                    });
                let _ = write!(s, " {entry:>12}");
            }
            s.push('\n');
        }
    }
}

/// Solvers and formulations of a case's cells, in first-seen order.
fn axes(cells: &[Cell]) -> (Vec<String>, Vec<String>) {
    let mut solvers: Vec<String> = Vec::new();
    let mut formulations: Vec<String> = Vec::new();
    for c in cells {
        if !solvers.contains(&c.solver) {
            solvers.push(c.solver.clone());
        }
        if !formulations.contains(&c.formulation) {
            formulations.push(c.formulation.clone());
        }
    }
    (solvers, formulations)
}

/// The map as JSON (pretty, final newline): `{threshold, max_steps,
/// counts, cases: [{file, scene, refused, tolerances, cells: [{solver,
/// formulation, tol, class, …, err, drift, g0, steps}], wall_s}]}`.
pub fn json(map: &StabilityMap) -> String {
    #[derive(Serialize)]
    struct Doc<'a> {
        #[serde(flatten)]
        map: &'a StabilityMap,
        counts: Counts,
    }
    serde_json::to_string_pretty(&Doc {
        map,
        counts: map.counts(),
    })
    .unwrap_or_default()
        + "\n"
}

/// Colour of a cell in the heat map.
fn colour(cell: &Cell) -> RGBColor {
    match &cell.class {
        Class::NotApplicable { .. } => RGBColor(255, 255, 255),
        Class::StepLimit { .. } => RGBColor(120, 60, 160),
        Class::Failed { .. } => RGBColor(40, 40, 40),
        Class::Unverified => RGBColor(170, 200, 230),
        Class::Suspect => RGBColor(230, 140, 40),
        Class::Accurate | Class::Inaccurate => {
            // log10(err / tol): ≤ −2 deep green, 0 pale, ≥ log10(threshold)
            // amber, ≥ 6 deep red.
            let ratio = match (cell.err, cell.tol) {
                (Some(e), Some(t)) if e > 0.0 => (e / t).log10(),
                _ => -2.0,
            };
            let x = ((ratio + 2.0) / 8.0).clamp(0.0, 1.0);
            let lerp = |a: f64, b: f64, u: f64| (a + (b - a) * u).round() as u8;
            if x < 0.5 {
                let u = x / 0.5;
                RGBColor(
                    lerp(30.0, 245.0, u),
                    lerp(140.0, 240.0, u),
                    lerp(60.0, 200.0, u),
                )
            } else {
                let u = (x - 0.5) / 0.5;
                RGBColor(
                    lerp(245.0, 190.0, u),
                    lerp(240.0, 20.0, u),
                    lerp(200.0, 20.0, u),
                )
            }
        }
    }
}

fn draw_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

const CELL_W: u32 = 26;
const CELL_H: u32 = 16;
const LEFT: u32 = 230;
const TOP: u32 = 150;
const LEGEND_H: u32 = 120;

/// A row of the heat map: the case's index and the tolerance (`None` for a
/// refused case).
type Row = (usize, Option<f64>);
/// A column of the heat map: solver and formulation.
type Column = (String, String);

/// Rows (case, tolerance) and columns (solver, formulation).
fn grid(map: &StabilityMap) -> (Vec<Row>, Vec<Column>) {
    let mut cols: Vec<Column> = Vec::new();
    let mut rows = Vec::new();
    for (i, case) in map.cases.iter().enumerate() {
        if case.refused.is_some() {
            rows.push((i, None));
            continue;
        }
        for &t in &case.tolerances {
            rows.push((i, Some(t)));
        }
        for c in &case.cells {
            let key = (c.solver.clone(), c.formulation.clone());
            if !cols.contains(&key) {
                cols.push(key);
            }
        }
    }
    (rows, cols)
}

/// Pixel size of the heat map.
pub fn heat_map_size(map: &StabilityMap) -> (u32, u32) {
    let (rows, cols) = grid(map);
    (
        LEFT + CELL_W * cols.len().max(1) as u32 + 20,
        TOP + CELL_H * rows.len().max(1) as u32 + LEGEND_H,
    )
}

/// Draw the heat map on any backend.
pub fn draw_heat_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &StabilityMap,
) -> Result<(), PlotError> {
    crate::font::register()?;
    root.fill(&WHITE).map_err(draw_err)?;
    let (rows, cols) = grid(map);
    let font = ("sans-serif", 12).into_font();
    let bold = ("sans-serif", 18).into_font().style(FontStyle::Bold);
    root.draw(&Text::new(
        "Stability map: case × tolerance (rows) by solver(formulation) (columns)",
        (10, 8),
        bold,
    ))
    .map_err(draw_err)?;
    // Column labels, rotated.
    let vertical = font.clone().transform(FontTransform::Rotate270);
    for (j, (s, f)) in cols.iter().enumerate() {
        let x = (LEFT + CELL_W * j as u32 + CELL_W / 2 - 6) as i32;
        root.draw(&Text::new(
            format!("{s}({f})"),
            (x, TOP as i32 - 6),
            vertical.clone(),
        ))
        .map_err(draw_err)?;
    }
    for (i, (ci, tol)) in rows.iter().enumerate() {
        let case = &map.cases[*ci];
        let y = (TOP + CELL_H * i as u32) as i32;
        let stem = Path::new(&case.file)
            .file_stem()
            .map_or(case.file.clone(), |s| s.to_string_lossy().into_owned());
        let name = case.scene.as_deref().unwrap_or(&stem);
        let label = match tol {
            Some(t) => format!("{name}  {t:.0e}"),
            None => format!(
                "{name}  refused ({})",
                case.refused.as_ref().map_or("", |r| r.stage)
            ),
        };
        root.draw(&Text::new(label, (8, y + 2), font.clone()))
            .map_err(draw_err)?;
        for (j, key) in cols.iter().enumerate() {
            let x = (LEFT + CELL_W * j as u32) as i32;
            let fill = match tol {
                None => RGBColor(200, 200, 200),
                Some(t) => case
                    .cells
                    .iter()
                    .find(|c| {
                        c.solver == key.0
                            && c.formulation == key.1
                            && c.tol.is_none_or(|ct| ct == *t)
                    })
                    .map_or(RGBColor(255, 255, 255), colour),
            };
            root.draw(&Rectangle::new(
                [(x, y), (x + CELL_W as i32 - 1, y + CELL_H as i32 - 1)],
                fill.filled(),
            ))
            .map_err(draw_err)?;
        }
    }
    // Legend.
    let y0 = (TOP + CELL_H * rows.len() as u32 + 16) as i32;
    let swatches: [(&str, RGBColor); 9] = [
        ("err ≤ 0.01·tol", colour(&legend_cell(1e-2))),
        ("err = tol", colour(&legend_cell(1.0))),
        ("err = 100·tol", colour(&legend_cell(1e2))),
        ("err ≥ 1e6·tol", colour(&legend_cell(1e6))),
        ("no reference", colour_of(Class::Unverified)),
        ("suspect", colour_of(Class::Suspect)),
        ("step limit", colour_of(Class::StepLimit { t: 0.0 })),
        (
            "typed error",
            colour_of(Class::Failed {
                kind: String::new(),
                t: None,
                message: String::new(),
            }),
        ),
        ("case refused", RGBColor(200, 200, 200)),
    ];
    for (k, (label, c)) in swatches.iter().enumerate() {
        let x = 10 + (k as i32 % 5) * 170;
        let y = y0 + (k as i32 / 5) * 24;
        root.draw(&Rectangle::new([(x, y), (x + 18, y + 14)], c.filled()))
            .map_err(draw_err)?;
        root.draw(&Rectangle::new(
            [(x, y), (x + 18, y + 14)],
            BLACK.stroke_width(1),
        ))
        .map_err(draw_err)?;
        root.draw(&Text::new(*label, (x + 24, y + 1), font.clone()))
            .map_err(draw_err)?;
    }
    root.draw(&Text::new(
        "white: not applicable (the solver does not take the formulation)",
        (10, y0 + 52),
        font,
    ))
    .map_err(draw_err)?;
    Ok(())
}

fn legend_cell(ratio: f64) -> Cell {
    Cell {
        solver: String::new(),
        formulation: String::new(),
        tol: Some(1.0),
        class: Class::Accurate,
        err: Some(ratio),
        scd: None,
        drift: None,
        g0: None,
        steps: 0,
        note: None,
    }
}

fn colour_of(class: Class) -> RGBColor {
    colour(&Cell {
        class,
        ..legend_cell(1.0)
    })
}

/// Write `map.txt`, `map.json`, `map.svg` and `map.png` into `dir` as one
/// set ([`crate::sweep::publish`]: `dir` is replaced only when every file is
/// written, and only if it holds nothing but sweep outputs). `lock`: the
/// destination's lock if the caller took it before the work, else `None`.
pub fn write(
    map: &StabilityMap,
    dir: &Path,
    lock: Option<&sweep::write::OutputLock>,
) -> Result<Vec<PathBuf>, SweepError> {
    let names = sweep::publish(dir, lock, |staging| {
        let io = |name: &str| {
            let path = dir.join(name);
            move |source| SweepError::Write { path, source }
        };
        let plot = |name: &str| {
            let path = dir.join(name);
            move |e: PlotError| SweepError::Write {
                path,
                source: std::io::Error::other(e.to_string()),
            }
        };
        for (name, body) in [("map.txt", text(map)), ("map.json", json(map))] {
            std::fs::write(staging.join(name), body).map_err(io(name))?;
        }
        let size = heat_map_size(map);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
            draw_heat_map(&root, map)
                .and_then(|()| root.present().map_err(draw_err))
                .map_err(plot("map.svg"))?;
        }
        std::fs::write(staging.join("map.svg"), svg).map_err(io("map.svg"))?;
        let png = staging.join("map.png");
        {
            let root = BitMapBackend::new(&png, size).into_drawing_area();
            draw_heat_map(&root, map)
                .and_then(|()| root.present().map_err(draw_err))
                .map_err(plot("map.png"))?;
        }
        Ok(["map.txt", "map.json", "map.svg", "map.png"])
    })?;
    Ok(names.iter().map(|n| dir.join(n)).collect())
}

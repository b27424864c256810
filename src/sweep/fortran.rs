//! The classic Fortran codes on the paper's scenarios, measured on a machine
//! of the class this project develops on: their work-precision curves are
//! the reference lines of the S01/S02 work-precision diagram, so that a
//! sweep shows where its runs stand against the frontier the Fortran codes
//! draw.
//!
//! Shipped in `data/` (copies of `shared/reference/`) and embedded:
//! - `side_by_side_2026-11-23.csv` and
//!   `side_by_side_extended_tols_2026-11-23.csv`: Fortran RADAU5 (rcd1,
//!   rcd0, ggl1) and DASSL (rcd0), tolerances 1e-3 … 1e-14, timed in one
//!   session together with our own radau5 and bdf (the `dae-*` rows); time
//!   column `time_median_s`, the median of `n_timings` timed integrations.
//! - `fortran_anchors.csv`: RADAU5, DASSL, DASPK, ODASSL, MEBDF and MEBDF
//!   with maximum order 5 (`mebdf-maxder5`), tolerances 1e-5 … 1e-12; time
//!   column `cpu_s`, the median CPU seconds of an integration (its header
//!   comments give the build and the machine).
//!
//! Both files measure `err_true`, the largest pointwise error of the
//! differential unknowns over the check times against the exact solution,
//! max(|x−x*|, |y−y*|, |v−v*|, |w−w*|) — exactly our `err` (SPEC §3), so a
//! reference line and a line of ours share both axes. Where a code and
//! formulation are in both files, the side-by-side rows are used (same
//! binaries: the errors and step counts agree; they were timed alongside our
//! own solvers, which gives the timing [`Calibration`]).
//!
//! Which scenes get the lines is [`paper::scenario`]'s rule, the one that
//! decides whether the paper's tables apply; only formulations the sweep
//! ran get lines, and only successful Fortran runs are points.

use super::paper::{self, Scenario};
use super::{SweepReport, SweepRun};
use serde::{Deserialize, Serialize};

/// Fortran RADAU5 and DASSL timed beside our solvers (2026-11-23).
pub const SIDE_BY_SIDE_CSV: &str = include_str!("../../data/side_by_side_2026-11-23.csv");
/// The same session at the tolerances 1e-3, 1e-4, 1e-13, 1e-14.
pub const SIDE_BY_SIDE_EXTENDED_CSV: &str =
    include_str!("../../data/side_by_side_extended_tols_2026-11-23.csv");
/// Every Fortran code at 1e-5 … 1e-12, with `#` header comments.
pub const ANCHORS_CSV: &str = include_str!("../../data/fortran_anchors.csv");

/// File names of the shipped copies (as in `shared/reference/`).
pub const SIDE_BY_SIDE_FILE: &str = "side_by_side_2026-11-23.csv";
/// See [`SIDE_BY_SIDE_FILE`].
pub const SIDE_BY_SIDE_EXTENDED_FILE: &str = "side_by_side_extended_tols_2026-11-23.csv";
/// See [`SIDE_BY_SIDE_FILE`].
pub const ANCHORS_FILE: &str = "fortran_anchors.csv";

/// Time column of the side-by-side files.
pub const SIDE_BY_SIDE_TIME: &str = "time_median_s";
/// Time column of the anchors.
pub const ANCHORS_TIME: &str = "cpu_s";

/// Why the shipped Fortran measurements could not be read (a bug in the
/// shipped copies; a test parses them).
#[derive(Debug, thiserror::Error)]
pub enum FortranError {
    /// A malformed row or header.
    #[error("data/{file}: {source}")]
    Csv {
        /// Which file.
        file: &'static str,
        /// The parser's error (with its position).
        source: csv::Error,
    },
}

/// One integration of a shipped file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// Code as in the file without the `fortran-`/`dae-` prefix
    /// (`radau5`, `dassl`, `mebdf-maxder5`, …).
    pub code: String,
    /// Formulation.
    pub formulation: String,
    /// `S01` or `S02`.
    pub scenario: String,
    /// RTOL = ATOL.
    pub tol: f64,
    /// The run reached the end of the horizon (`status` is `ok`).
    pub ok: bool,
    /// `err_true` (NaN where the file has none).
    pub err: f64,
    /// Seconds per integration from [`Measurement::time_column`].
    pub time_s: f64,
    /// Accepted steps.
    pub steps: u64,
    /// File it came from.
    pub file: &'static str,
    /// Column `time_s` came from.
    pub time_column: &'static str,
}

impl Measurement {
    /// A point for a work-precision line: a successful run with a finite
    /// error and a positive, finite time.
    fn point(&self) -> Option<CurvePoint> {
        let usable = self.ok
            && self.err.is_finite()
            && self.err >= 0.0
            && self.time_s.is_finite()
            && self.time_s > 0.0;
        usable.then_some(CurvePoint {
            tol: self.tol,
            err: self.err,
            time_s: self.time_s,
            steps: self.steps,
        })
    }
}

/// Every row of the shipped files: the Fortran codes, and our own solvers
/// as that session measured them.
#[derive(Clone, Debug, PartialEq)]
pub struct Shipped {
    /// Fortran rows, side-by-side files first, in file order.
    pub fortran: Vec<Measurement>,
    /// The `dae-*` rows of the side-by-side files.
    pub ours: Vec<Measurement>,
    /// The `#` header comments of the anchors (build and machine).
    pub anchors_header: Vec<String>,
}

#[derive(Deserialize)]
struct SideRow {
    code: String,
    formulation: String,
    scenario: String,
    tol: f64,
    err_true: f64,
    steps: u64,
    time_median_s: f64,
    status: String,
}

#[derive(Deserialize)]
struct AnchorRow {
    solver: String,
    formulation: String,
    scenario: String,
    tol: f64,
    status: String,
    err_true: f64,
    cpu_s: f64,
    steps: u64,
}

fn rows<T: for<'de> Deserialize<'de>>(
    file: &'static str,
    text: &str,
) -> Result<Vec<T>, FortranError> {
    csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes())
        .deserialize()
        .collect::<Result<Vec<T>, _>>()
        .map_err(|source| FortranError::Csv { file, source })
}

impl Shipped {
    /// Parse the embedded copies.
    pub fn load() -> Result<Shipped, FortranError> {
        Shipped::parse(SIDE_BY_SIDE_CSV, SIDE_BY_SIDE_EXTENDED_CSV, ANCHORS_CSV)
    }

    /// Parse the three files' text (the side-by-side shape: `code,
    /// formulation,scenario,tol,err_true,steps,…,time_median_s,status,…`; the
    /// anchors' shape: `solver,formulation,scenario,tol,status,err_true,
    /// …,cpu_s,steps,…` after `#` comments). Columns are found by name.
    pub fn parse(side: &str, extended: &str, anchors: &str) -> Result<Shipped, FortranError> {
        let mut fortran = Vec::new();
        let mut ours = Vec::new();
        for (file, text) in [
            (SIDE_BY_SIDE_FILE, side),
            (SIDE_BY_SIDE_EXTENDED_FILE, extended),
        ] {
            for r in rows::<SideRow>(file, text)? {
                let (code, into) = if let Some(c) = r.code.strip_prefix("fortran-") {
                    (c, &mut fortran)
                } else if let Some(c) = r.code.strip_prefix("dae-") {
                    (c, &mut ours)
                } else {
                    continue;
                };
                into.push(Measurement {
                    code: code.to_string(),
                    formulation: r.formulation,
                    scenario: r.scenario,
                    tol: r.tol,
                    ok: r.status == "ok",
                    err: r.err_true,
                    time_s: r.time_median_s,
                    steps: r.steps,
                    file,
                    time_column: SIDE_BY_SIDE_TIME,
                });
            }
        }
        for r in rows::<AnchorRow>(ANCHORS_FILE, anchors)? {
            fortran.push(Measurement {
                code: r.solver,
                formulation: r.formulation,
                scenario: r.scenario,
                tol: r.tol,
                ok: r.status == "ok",
                err: r.err_true,
                time_s: r.cpu_s,
                steps: r.steps,
                file: ANCHORS_FILE,
                time_column: ANCHORS_TIME,
            });
        }
        let anchors_header = anchors
            .lines()
            .filter_map(|l| l.strip_prefix('#'))
            .map(|l| l.trim().to_string())
            .collect();
        Ok(Shipped {
            fortran,
            ours,
            anchors_header,
        })
    }

    /// The reference curves of a scenario on the given formulations: one
    /// per code and formulation, formulations in the order given, codes in
    /// the order of first appearance (side-by-side files first). A code and
    /// formulation with side-by-side rows takes only those; curves without
    /// a successful run are left out.
    pub fn curves(&self, scenario: Scenario, formulations: &[String]) -> Vec<Curve> {
        let rows: Vec<&Measurement> = self
            .fortran
            .iter()
            .filter(|m| m.scenario == scenario.name())
            .collect();
        let mut codes: Vec<&str> = Vec::new();
        for m in &rows {
            if !codes.contains(&m.code.as_str()) {
                codes.push(&m.code);
            }
        }
        let mut out = Vec::new();
        for f in formulations {
            for code in &codes {
                let of_pair: Vec<&&Measurement> = rows
                    .iter()
                    .filter(|m| m.code == *code && &m.formulation == f)
                    .collect();
                let side_by_side = of_pair.iter().any(|m| m.file != ANCHORS_FILE);
                let mut chosen: Vec<&Measurement> = Vec::new();
                for m in of_pair {
                    let wanted = !side_by_side || m.file != ANCHORS_FILE;
                    if wanted && !chosen.iter().any(|c| paper::same_tol(c.tol, m.tol)) {
                        chosen.push(m);
                    }
                }
                let mut files: Vec<&'static str> = Vec::new();
                for m in &chosen {
                    if !files.contains(&m.file) {
                        files.push(m.file);
                    }
                }
                // Loose to tight, as our lines run.
                chosen.sort_by(|a, b| b.tol.total_cmp(&a.tol));
                let points: Vec<CurvePoint> = chosen.iter().filter_map(|m| m.point()).collect();
                if points.is_empty() {
                    continue;
                }
                out.push(Curve {
                    label: format!("{} (Fortran, {f})", code_name(code)),
                    code: (*code).to_string(),
                    formulation: f.clone(),
                    time_column: chosen[0].time_column,
                    files,
                    failed: chosen
                        .iter()
                        .filter(|m| m.point().is_none())
                        .map(|m| m.tol)
                        .collect(),
                    points,
                });
            }
        }
        out
    }

    /// How this sweep's timings compare with the side-by-side session's:
    /// for every successful run of ours that the session also measured
    /// (same solver, formulation, scenario and tolerance, `dae-*` rows),
    /// the ratio of the time per accepted step here to there. Per step, so
    /// that a change of our step counts since then does not enter.
    pub fn calibration(&self, scenario: Scenario, runs: &[SweepRun]) -> Option<Calibration> {
        let mut ratios: Vec<f64> = Vec::new();
        for r in runs.iter().map(|r| &r.record).filter(|r| r.status == "ok") {
            let Some(there) = self.ours.iter().find(|m| {
                m.scenario == scenario.name()
                    && m.code == r.solver
                    && m.formulation == r.formulation
                    && paper::same_tol(m.tol, r.tol)
                    && m.ok
            }) else {
                continue;
            };
            let here = r.tsim_s / r.stats.steps as f64;
            let then = there.time_s / there.steps as f64;
            let ratio = here / then;
            if ratio.is_finite() && ratio > 0.0 {
                ratios.push(ratio);
            }
        }
        let min = ratios.iter().copied().fold(f64::INFINITY, f64::min);
        let max = ratios.iter().copied().fold(0.0, f64::max);
        (!ratios.is_empty()).then(|| Calibration {
            runs: ratios.len(),
            median: super::median(&ratios),
            min,
            max,
        })
    }
}

/// The name of a code in labels: `RADAU5`, `MEBDF maxder5`.
pub fn code_name(code: &str) -> String {
    match code.split_once('-') {
        Some((base, variant)) => format!("{} {variant}", base.to_ascii_uppercase()),
        None => code.to_ascii_uppercase(),
    }
}

/// One point of a reference line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CurvePoint {
    /// RTOL = ATOL of the Fortran run (not comparable across codes: RADAU5
    /// maps it to 0.1·RTOL^(2/3) internally).
    pub tol: f64,
    /// `err_true`, our `err`.
    pub err: f64,
    /// Seconds per integration (the curve's time column).
    pub time_s: f64,
    /// Accepted steps.
    pub steps: u64,
}

/// One Fortran code on one formulation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Curve {
    /// Legend label, `RADAU5 (Fortran, rcd1)`.
    pub label: String,
    /// Code as in the file, without `fortran-`.
    pub code: String,
    /// Formulation.
    pub formulation: String,
    /// Which time column the points' `time_s` is.
    pub time_column: &'static str,
    /// Files the points came from.
    pub files: Vec<&'static str>,
    /// Successful runs, loose to tight tolerance.
    pub points: Vec<CurvePoint>,
    /// Tolerances at which the code failed (no point).
    pub failed: Vec<f64>,
}

/// Our time per step here against the side-by-side session's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Calibration {
    /// Runs compared.
    pub runs: usize,
    /// Median ratio here / there.
    pub median: f64,
    /// Smallest ratio.
    pub min: f64,
    /// Largest ratio.
    pub max: f64,
}

/// The reference lines of a sweep's work-precision diagram.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceLines {
    /// The scenario.
    pub scenario: Scenario,
    /// What the lines are, where they were measured and which columns
    /// are plotted.
    pub note: String,
    /// The anchors' header comments, verbatim.
    pub header: Vec<String>,
    /// One curve per code and formulation.
    pub curves: Vec<Curve>,
    /// Our timings here against the side-by-side session (`None`: no run
    /// of this sweep was measured there).
    pub calibration: Option<Calibration>,
}

impl ReferenceLines {
    /// The lines for a sweep: for a scene that is S01 or S02
    /// ([`paper::scenario`]) with a reference (errors are measured), one
    /// curve per Fortran code on each formulation with an applicable pair.
    /// `Ok(None)` for any other scene or when no curve is left.
    pub fn for_report(report: &SweepReport) -> Result<Option<ReferenceLines>, FortranError> {
        let Some(scenario) =
            paper::scenario(&report.scene.name, report.paper_setup, report.scene.t_end)
        else {
            return Ok(None);
        };
        if !report.has_reference() {
            return Ok(None);
        }
        let shipped = Shipped::load()?;
        let formulations: Vec<String> = report
            .formulations
            .iter()
            .filter(|f| {
                report
                    .pairs
                    .iter()
                    .any(|p| &p.formulation == *f && p.not_applicable.is_none())
            })
            .cloned()
            .collect();
        Ok(ReferenceLines::of(
            &shipped,
            scenario,
            &formulations,
            &report.runs,
        ))
    }

    /// [`ReferenceLines::for_report`] on plain inputs (`None`: no curve).
    pub fn of(
        shipped: &Shipped,
        scenario: Scenario,
        formulations: &[String],
        runs: &[SweepRun],
    ) -> Option<ReferenceLines> {
        let curves = shipped.curves(scenario, formulations);
        if curves.is_empty() {
            return None;
        }
        let mut columns: Vec<String> = Vec::new();
        for (column, meaning) in [
            (SIDE_BY_SIDE_TIME, "median time of the timed integrations"),
            (
                ANCHORS_TIME,
                "median CPU seconds, noisy: another job shared that machine",
            ),
        ] {
            let of_column: Vec<&Curve> =
                curves.iter().filter(|c| c.time_column == column).collect();
            let mut files: Vec<&str> = Vec::new();
            for f in of_column.iter().flat_map(|c| &c.files) {
                if !files.contains(f) {
                    files.push(f);
                }
            }
            let codes: Vec<String> = of_column
                .iter()
                .map(|c| format!("{}({})", code_name(&c.code), c.formulation))
                .collect();
            if !codes.is_empty() {
                columns.push(format!(
                    "{column} ({meaning}, data/{}) for {}",
                    files.join(" and data/"),
                    codes.join(", ")
                ));
            }
        }
        let calibration = shipped.calibration(scenario, runs);
        let calibration_text = match calibration {
            Some(c) if c.runs > 1 => format!(
                " Our radau5/bdf runs that the side-by-side session also timed ({} runs) took {:.2}× (median; \
                 {:.2}–{:.2}×) their time per step there.",
                c.runs, c.median, c.min, c.max
            ),
            Some(c) => format!(
                " Our run that the side-by-side session also timed took {:.2}× its time per step there.",
                c.median
            ),
            None => String::new(),
        };
        let note = format!(
            "Fortran reference lines (dotted grey, hollow markers in the formulation's colour, one shape per \
             code; {scenario}): err_true of the shipped \
             Fortran measurements, the same err as ours (max over the check times of max(|x−x*|, |y−y*|, |v−v*|, \
             |w−w*|)), against {}. Built with gfortran 12 -O2 and run on a 2-core machine of the class this \
             project develops on, in another session than this sweep: errors compare exactly, times only \
             roughly. Successful Fortran runs only; their nominal tolerances do not compare across codes (RADAU5 \
             maps RTOL to 0.1·RTOL^(2/3)).{calibration_text}",
            columns.join("; "),
            scenario = scenario.name(),
        );
        Some(ReferenceLines {
            scenario,
            note,
            header: shipped.anchors_header.clone(),
            curves,
            calibration,
        })
    }
}

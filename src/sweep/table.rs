//! The paper's tables: the success matrix (Tables 5 and 8) and the
//! efficiency table (Tables 6 and 9), as data, as terminal text and as CSV.

use super::paper::{Comparison, PaperCell};
use super::pareto::{Point, Target};
use super::{Pair, Summary, SweepReport};
use crate::runner::{Accuracy, RunRecord, ACCURATE_FACTOR, SUSPECT_FACTOR};
use serde::Serialize;
use std::borrow::Borrow;
use std::fmt::Write;

/// A cell of the success matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Mark {
    /// Successful at every tolerance.
    #[serde(rename = "X")]
    Every,
    /// Successful at some tolerances.
    #[serde(rename = "x")]
    Some,
    /// Successful at none.
    #[serde(rename = "o")]
    None,
    /// Not applicable (see the cell's reason).
    #[serde(rename = "-")]
    NotApplicable,
}

impl Mark {
    /// The paper's symbol.
    pub fn symbol(self) -> &'static str {
        match self {
            Mark::Every => "X",
            Mark::Some => "x",
            Mark::None => "o",
            Mark::NotApplicable => "-",
        }
    }

    /// Classify a pair from its successful and total run counts.
    pub fn classify(ok: usize, runs: usize) -> Mark {
        if runs > 0 && ok == runs {
            Mark::Every
        } else if ok > 0 {
            Mark::Some
        } else {
            Mark::None
        }
    }
}

/// One cell: a formulation for one solver.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SuccessCell {
    /// Formulation.
    pub formulation: String,
    /// The mark.
    pub mark: Mark,
    /// Successful runs.
    pub ok: usize,
    /// Runs (tolerances).
    pub runs: usize,
    /// Runs judged accurate (see [`crate::runner::Accuracy`]).
    pub accurate: usize,
    /// Runs judged inaccurate.
    pub inaccurate: usize,
    /// Runs without a reference, unremarkable.
    pub unverified: usize,
    /// Runs without a reference whose residuals or drift are suspect.
    pub suspect: usize,
    /// Why the pair is not applicable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The runs that did not reach the end: tolerance and error kind, in
    /// sweep order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub failed: Vec<(f64, String)>,
}

/// One row of the matrix.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SuccessRow {
    /// Solver.
    pub solver: String,
    /// One cell per formulation, in column order.
    pub cells: Vec<SuccessCell>,
}

/// The success matrix: solver rows × formulation columns.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SuccessMatrix {
    /// What the marks mean.
    pub legend: &'static str,
    /// Column order.
    pub formulations: Vec<String>,
    /// Rows.
    pub rows: Vec<SuccessRow>,
}

/// The legend of the success matrix.
pub const SUCCESS_LEGEND: &str = "X: successful at every tolerance, x: at some, o: at none, -: not applicable \
                                  (reason given); successful = the integration reached the end of the horizon. \
                                  After the mark, the accuracy of the runs that did: n/m = n of m tolerances \
                                  accurate (err <= 100·tol·max(1, |y*|) at every check time), ? = no reference \
                                  to verify against, !k = k runs suspect (constraint residual or invariant drift \
                                  >= 1e4·tol)";

/// The colour class of a success-matrix cell: how many of its tolerances
/// gave a usable answer — one that reached the end of the horizon and is
/// accurate (or, without a reference, unverified and not suspect). So a
/// pair that reached the end at every tolerance but was accurate at none
/// is not green.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Usable {
    /// Every tolerance: green.
    All,
    /// Some tolerances: amber.
    Some,
    /// None: red.
    None,
    /// The pair is not applicable: grey.
    NotApplicable,
}

impl Usable {
    /// The CSS class of `index.html` (`acc-all`, `acc-some`, `acc-none`,
    /// `na`).
    pub fn class(self) -> &'static str {
        match self {
            Usable::All => "acc-all",
            Usable::Some => "acc-some",
            Usable::None => "acc-none",
            Usable::NotApplicable => "na",
        }
    }
}

/// The rule of the success matrix's colours, for the legend under it.
pub const USABLE_LEGEND: &str = "Colour: how many tolerances gave a usable answer (reached the end and accurate; \
                                 without a reference: reached the end and not suspect) — green: every one, amber: \
                                 some, red: none, grey: not applicable. A pair that reached the end at every \
                                 tolerance but is accurate at none is red.";

impl SuccessCell {
    /// How many of the cell's tolerances gave a usable answer (see
    /// [`Usable`]).
    ///
    /// ```
    /// use dae::sweep::table::{Mark, SuccessCell, Usable};
    ///
    /// let cell = SuccessCell {
    ///     formulation: "ori2".into(),
    ///     mark: Mark::Every,
    ///     ok: 8,
    ///     runs: 8,
    ///     accurate: 0,
    ///     inaccurate: 8,
    ///     unverified: 0,
    ///     suspect: 0,
    ///     reason: None,
    ///     failed: Vec::new(),
    /// };
    /// // Finished at 8/8 tolerances, accurate at 0/8: not green.
    /// assert_eq!(cell.usable(), Usable::None);
    /// assert_eq!(SuccessCell { accurate: 5, inaccurate: 3, ..cell.clone() }.usable(), Usable::Some);
    /// assert_eq!(SuccessCell { accurate: 8, inaccurate: 0, ..cell }.usable(), Usable::All);
    /// ```
    pub fn usable(&self) -> Usable {
        if self.reason.is_some() {
            return Usable::NotApplicable;
        }
        let good = self.accurate + self.unverified;
        if self.runs > 0 && good == self.runs {
            Usable::All
        } else if good > 0 {
            Usable::Some
        } else {
            Usable::None
        }
    }

    /// The accuracy after the mark (see [`SUCCESS_LEGEND`]): `n/m`, `?`,
    /// `!k`; empty for a not-applicable cell or when no run finished.
    pub fn accuracy_label(&self) -> String {
        let finished = self.accurate + self.inaccurate + self.unverified + self.suspect;
        if self.reason.is_some() || finished == 0 {
            String::new()
        } else if self.accurate + self.inaccurate > 0 {
            format!("{}/{}", self.accurate, self.runs)
        } else if self.suspect > 0 {
            format!("!{}", self.suspect)
        } else {
            "?".into()
        }
    }

    /// Why runs of the cell failed, grouped by error kind: `failed at
    /// 1e-11, 1e-12 (newton_failure)`; `None` if none did.
    pub fn failure_note(&self) -> Option<String> {
        if self.failed.is_empty() {
            return None;
        }
        let mut kinds: Vec<(&str, Vec<String>)> = Vec::new();
        for (tol, kind) in &self.failed {
            match kinds.iter_mut().find(|(k, _)| k == kind) {
                Some((_, tols)) => tols.push(tol_label(*tol)),
                None => kinds.push((kind, vec![tol_label(*tol)])),
            }
        }
        let parts: Vec<String> = kinds
            .iter()
            .map(|(k, tols)| format!("{} ({k})", tols.join(", ")))
            .collect();
        Some(format!("failed at {}", parts.join("; ")))
    }

    /// The mark and the accuracy, as the text matrix shows them (`X 6/8`).
    pub fn label(&self) -> String {
        let acc = self.accuracy_label();
        if acc.is_empty() {
            self.mark.symbol().into()
        } else {
            format!("{} {acc}", self.mark.symbol())
        }
    }
}

impl SuccessMatrix {
    /// The cell of a solver and formulation.
    pub fn cell(&self, solver: &str, formulation: &str) -> Option<&SuccessCell> {
        self.rows
            .iter()
            .find(|r| r.solver == solver)?
            .cells
            .iter()
            .find(|c| c.formulation == formulation)
    }

    /// Distinct reasons of not-applicable cells, in order of appearance.
    pub fn reasons(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for c in self.rows.iter().flat_map(|r| &r.cells) {
            if let Some(r) = c.reason.as_deref() {
                if !out.contains(&r) {
                    out.push(r);
                }
            }
        }
        out
    }
}

/// Build the success matrix from the pairs and the runs.
pub fn success_matrix<R: Borrow<RunRecord>>(
    solvers: &[String],
    formulations: &[String],
    pairs: &[Pair],
    runs: &[R],
) -> SuccessMatrix {
    let rows = solvers
        .iter()
        .map(|s| SuccessRow {
            solver: s.clone(),
            cells: formulations
                .iter()
                .map(|f| {
                    let reason = pairs
                        .iter()
                        .find(|p| &p.solver == s && &p.formulation == f)
                        .and_then(|p| p.not_applicable.clone());
                    let mine = runs
                        .iter()
                        .map(Borrow::borrow)
                        .filter(|r| &r.solver == s && &r.formulation == f);
                    let mut verdicts = [0usize; 4];
                    let mut failed = Vec::new();
                    let (ok, n) = mine.fold((0, 0), |(ok, n), r| {
                        if let Some(a) = r.accuracy {
                            verdicts[a as usize] += 1;
                        }
                        if r.status != "ok" {
                            let kind = r.error.as_ref().map_or("error", |e| e.kind.as_str());
                            failed.push((r.tol, kind.to_string()));
                        }
                        (ok + usize::from(r.status == "ok"), n + 1)
                    });
                    let mark = if reason.is_some() {
                        Mark::NotApplicable
                    } else {
                        Mark::classify(ok, n)
                    };
                    SuccessCell {
                        formulation: f.clone(),
                        mark,
                        ok,
                        runs: n,
                        accurate: verdicts[Accuracy::Accurate as usize],
                        inaccurate: verdicts[Accuracy::Inaccurate as usize],
                        unverified: verdicts[Accuracy::Unverified as usize],
                        suspect: verdicts[Accuracy::Suspect as usize],
                        reason,
                        failed,
                    }
                })
                .collect(),
        })
        .collect();
    SuccessMatrix {
        legend: SUCCESS_LEGEND,
        formulations: formulations.to_vec(),
        rows,
    }
}

/// `1.2e-05` (the paper's style); `-` for `None`.
pub fn sci(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(v) if !v.is_finite() => format!("{v}"),
        Some(0.0) => "0".into(),
        Some(v) => {
            let s = format!("{v:.1e}");
            match s.split_once('e') {
                Some((m, e)) => {
                    let e: i32 = e.parse().unwrap_or(0);
                    format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
                }
                None => s,
            }
        }
    }
}

/// A tolerance as `1e-7`.
pub fn tol_label(t: f64) -> String {
    let e = t.log10().round();
    if (10f64.powf(e) - t).abs() <= 1e-9 * t {
        format!("1e{}", e as i32)
    } else {
        format!("{t:e}")
    }
}

/// Render rows of cells as an aligned text table (comfy-table, no
/// borders): the first column left-aligned, the others right-aligned two
/// spaces apart; trailing blanks trimmed, one line per row.
///
/// ```
/// use dae::sweep::table::align;
///
/// let rows = vec![
///     vec!["pair".to_string(), "tol".into(), "err".into()],
///     vec!["radau5(rcd0)".into(), "1e-7".into(), "3.1e-07".into()],
///     vec!["bdf(ggl1)".into(), "1e-10".into()],
/// ];
/// assert_eq!(
///     align(&rows),
///     "pair            tol      err\n\
///      radau5(rcd0)   1e-7  3.1e-07\n\
///      bdf(ggl1)     1e-10\n"
/// );
/// ```
pub fn align(rows: &[Vec<String>]) -> String {
    use comfy_table::{CellAlignment, ContentArrangement, Table};
    let cols = rows.iter().map(Vec::len).max().unwrap_or(0);
    let mut table = Table::new();
    table
        .load_preset(comfy_table::presets::NOTHING)
        .set_content_arrangement(ContentArrangement::Disabled);
    for r in rows {
        table.add_row(r.iter().map(String::as_str));
    }
    for (c, column) in table.column_iter_mut().enumerate().take(cols) {
        if c == 0 {
            column.set_padding((0, 0));
        } else {
            column
                .set_padding((2, 0))
                .set_cell_alignment(CellAlignment::Right);
        }
    }
    let mut s = String::new();
    for line in table.lines() {
        s.push_str(line.trim_end());
        s.push('\n');
    }
    s
}

/// The success matrix as text, with numbered reasons below: `-k` for a
/// pair that is not applicable, `*k` after the mark of a pair with failed
/// runs.
pub fn success_text(m: &SuccessMatrix) -> String {
    let reasons = m.reasons();
    let mut failures: Vec<String> = Vec::new();
    let mut rows = vec![std::iter::once(String::new())
        .chain(m.formulations.iter().cloned())
        .collect::<Vec<_>>()];
    for r in &m.rows {
        let mut row = vec![r.solver.clone()];
        for c in &r.cells {
            row.push(match &c.reason {
                Some(why) => format!(
                    "-{}",
                    reasons.iter().position(|x| x == why).map_or(0, |i| i + 1)
                ),
                None => match c.failure_note() {
                    Some(note) => {
                        failures.push(format!("{}({}) {note}", r.solver, c.formulation));
                        format!("{} *{}", c.label(), failures.len())
                    }
                    None => c.label(),
                },
            });
        }
        rows.push(row);
    }
    let mut s = align(&rows);
    for (i, r) in reasons.iter().enumerate() {
        let _ = writeln!(s, "  -{}: {r}", i + 1);
    }
    for (i, f) in failures.iter().enumerate() {
        let _ = writeln!(s, "  *{}: {f}", i + 1);
    }
    let _ = writeln!(s, "  {}", m.legend);
    s
}

/// Column headers of the efficiency table for a constraint chain of
/// `levels` levels (one `|gk|` column each).
pub fn efficiency_header(levels: usize) -> Vec<String> {
    let head = [
        "pair", "tol", "status", "accuracy", "tsim_s", "wall_s", "err", "err_sum", "err_alg",
        "steps", "rejected", "evals", "jac", "LU",
    ];
    let mut h: Vec<String> = head.iter().map(|s| s.to_string()).collect();
    h.extend((0..levels).map(|k| format!("|g{k}|")));
    h.push("drift".into());
    h
}

/// Levels of the constraint chain the runs report (the most any run has).
pub fn residual_levels<R: Borrow<RunRecord>>(runs: &[R]) -> usize {
    runs.iter()
        .map(|r| r.borrow().residuals.levels())
        .max()
        .unwrap_or(0)
}

/// The efficiency table: one row per run (pairs in sweep order, tolerances
/// within), with the time, the errors, the work counters, the largest
/// constraint residual per level and the drift of the first invariant
/// (energy).
pub fn efficiency_rows<R: Borrow<RunRecord>>(runs: &[R]) -> Vec<Vec<String>> {
    let levels = residual_levels(runs);
    let mut rows = vec![efficiency_header(levels)];
    for r in runs.iter().map(Borrow::borrow) {
        let ok = r.status == "ok";
        let status = match (&r.error, ok) {
            (_, true) => "ok".to_string(),
            (Some(e), false) => match e.t {
                Some(t) => format!("{} at t={t:.4}", e.kind),
                None => e.kind.clone(),
            },
            (None, false) => r.status.to_string(),
        };
        // A run that stopped shows the work it did until then.
        let num = |v: usize| v.to_string();
        let val = |v: Option<f64>| if ok { sci(v) } else { "-".into() };
        let mut row = vec![
            format!("{}({})", r.solver, r.formulation),
            tol_label(r.tol),
            status,
            match r.accuracy {
                Some(a) if a.is_warning() => a.as_str().to_uppercase(),
                Some(a) => a.as_str().to_string(),
                None => "-".into(),
            },
            if ok { sci(Some(r.tsim_s)) } else { "-".into() },
            if ok { sci(Some(r.wall_s)) } else { "-".into() },
            val(r.err),
            val(r.err_sum),
            val(r.err_algebraic),
            num(r.stats.steps),
            num(r.stats.rejected),
            num(r.stats.residual_evals),
            num(r.stats.jacobian_evals),
            num(r.stats.factorizations),
        ];
        row.extend((0..levels).map(|k| val(r.residuals.level(k))));
        row.push(val(r.invariant_drift.0.first().map(|(_, v)| *v)));
        rows.push(row);
    }
    rows
}

fn point_row(p: &Point) -> Vec<String> {
    vec![
        p.pair(),
        tol_label(p.tol),
        sci(Some(p.tsim_s)),
        sci(Some(p.err)),
    ]
}

/// The `≈` column of the Pareto front, one entry per run: `≈` when the run
/// is tied in time with the one before it (within
/// [`TIME_RESOLUTION`](super::pareto::TIME_RESOLUTION); the front's order
/// then rests on the error, not on the clock), else empty.
///
/// ```
/// use dae::sweep::pareto::Point;
/// use dae::sweep::table::front_ties;
/// let p = |t: f64, err: f64| Point { solver: "s".into(), formulation: "f".into(),
///     tol: 1e-6, tsim_s: t, err, steps: 1, evals: 1 };
/// let front = [p(1.00, 1e-3), p(1.04, 1e-4), p(2.0, 1e-6)];
/// assert_eq!(front_ties(&front), ["", "≈", ""]);
/// ```
pub fn front_ties(front: &[Point]) -> Vec<&'static str> {
    let mut marks = vec![""; front.len()];
    for (i, w) in front.windows(2).enumerate() {
        if super::pareto::tied(w[0].tsim_s, w[1].tsim_s, super::pareto::TIME_RESOLUTION) {
            marks[i + 1] = "≈";
        }
    }
    marks
}

/// The runs a target's pick was tied with, as `label; label` (empty for
/// none).
///
/// ```
/// use dae::sweep::pareto::{Point, Target};
/// use dae::sweep::table::tied_text;
/// let p = Point { solver: "bdf".into(), formulation: "rcd1".into(), tol: 1e-6,
///     tsim_s: 1.97e-3, err: 5.4e-3, steps: 4816, evals: 9000 };
/// let t = Target { target: 1e-2, best: None, tied: vec![p] };
/// assert_eq!(tied_text(&t), "bdf(rcd1) 1e-6");
/// ```
pub fn tied_text(t: &Target) -> String {
    t.tied
        .iter()
        .map(Point::label)
        .collect::<Vec<_>>()
        .join("; ")
}

/// The Pareto front as text, with the `≈` column of [`front_ties`].
pub fn pareto_text(front: &[Point]) -> String {
    let mut rows = vec![vec![
        "pair".into(),
        "tol".into(),
        "tsim_s".into(),
        "err".into(),
        "≈".into(),
    ]];
    rows.extend(front.iter().zip(front_ties(front)).map(|(p, m)| {
        let mut r = point_row(p);
        r.push(m.into());
        r
    }));
    align(&rows)
}

/// The target table as text, with the runs each pick was tied with.
pub fn targets_text(targets: &[Target]) -> String {
    let mut rows = vec![vec![
        "target err".into(),
        "fastest pair".into(),
        "tol".into(),
        "tsim_s".into(),
        "err".into(),
        format!(
            "tied with (time within {} %)",
            100.0 * super::pareto::TIME_RESOLUTION
        ),
    ]];
    for t in targets {
        match &t.best {
            Some(p) => {
                let mut r = vec![format!("≤ {}", sci(Some(t.target)))];
                r.extend(point_row(p));
                r.push(tied_text(t));
                rows.push(r);
            }
            None => rows.push(vec![
                format!("≤ {}", sci(Some(t.target))),
                "none met it".into(),
            ]),
        }
    }
    align(&rows)
}

/// A paper cell as text.
pub fn paper_cell(c: PaperCell) -> String {
    match c {
        PaperCell::Value(v) => sci(Some(v)),
        PaperCell::Failed => "failed".into(),
        PaperCell::Illegible => "?".into(),
    }
}

/// The comparison with the paper as text: one line per row and tolerance
/// set, `ours / paper verdict`.
pub fn paper_text(c: &Comparison) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}: {}", c.table, c.note);
    let tols: Vec<f64> = {
        let mut t: Vec<f64> = Vec::new();
        for cell in c.rows.iter().flat_map(|r| &r.cells) {
            if !t.iter().any(|x| super::paper::same_tol(*x, cell.tol)) {
                t.push(cell.tol);
            }
        }
        t
    };
    let mut rows = vec![std::iter::once("ours vs paper".to_string())
        .chain(tols.iter().map(|t| tol_label(*t)))
        .collect()];
    for r in &c.rows {
        let mut ours = vec![format!(
            "{}({}) {}",
            r.solver,
            r.formulation,
            c.measure.field()
        )];
        let mut theirs = vec![format!("  {}({}) ERR", r.paper_solver, r.formulation)];
        let mut verdict = vec!["  →".to_string()];
        for t in &tols {
            match r.cells.iter().find(|c| super::paper::same_tol(c.tol, *t)) {
                Some(cell) => {
                    ours.push(cell.ours.map_or_else(|| "failed".into(), |v| sci(Some(v))));
                    theirs.push(paper_cell(cell.paper));
                    verdict.push(cell.verdict.label().into());
                }
                None => {
                    ours.push(String::new());
                    theirs.push(String::new());
                    verdict.push(String::new());
                }
            }
        }
        rows.extend([ours, theirs, verdict]);
    }
    s.push_str(&align(&rows));
    let counts: Vec<String> = c
        .counts
        .iter()
        .filter(|k| k.cells > 0)
        .map(|k| format!("{} {}", k.cells, k.verdict.label()))
        .collect();
    let _ = writeln!(s, "  cells: {}", counts.join(", "));
    if !c.illegible.is_empty() {
        let _ = writeln!(
            s,
            "  illegible in the seed, not compared: {}",
            c.illegible.join(", ")
        );
    }
    s
}

/// The whole terminal report.
pub fn text_report(report: &SweepReport, summary: &Summary) -> String {
    let mut s = String::new();
    let sc = &report.scene;
    let _ = writeln!(
        s,
        "Sweep {} ({}): model {}, t in [{}, {}], {} check time(s), reference {}",
        sc.name, sc.origin, sc.model, sc.t0, sc.t_end, sc.checks, sc.reference
    );
    let _ = writeln!(s, "{}\n", report.scale_line());
    let _ = writeln!(s, "Success matrix");
    s.push_str(&success_text(&summary.success));
    let _ = writeln!(s, "{}", accuracy_line(report));
    let _ = writeln!(s, "\nEfficiency (err: max pointwise error of the differential unknowns over the check times; err_sum: sum over check times of all unknowns' errors; |gk|: largest constraint residual of level k; drift: |{}(t) - {}(t0)|)",
        report.invariants.first().map_or("I", String::as_str),
        report.invariants.first().map_or("I", String::as_str));
    s.push_str(&align(&efficiency_rows(&report.runs)));
    if report.has_reference() {
        let _ = writeln!(
            s,
            "\nPareto front (by tsim and err; times within {} % are tied, ≈: tied with the run above)",
            100.0 * super::pareto::TIME_RESOLUTION
        );
        s.push_str(&pareto_text(&summary.pareto));
        let _ = writeln!(
            s,
            "\nFastest run per target error (err; of runs tied in time, the more accurate)"
        );
        s.push_str(&targets_text(&summary.targets));
    } else {
        let _ = writeln!(
            s,
            "\nNo reference: errors, Pareto front and target table are not available."
        );
    }
    match &summary.paper {
        Some(c) => {
            let _ = writeln!(s, "\nAgainst the paper");
            s.push_str(&paper_text(c));
            if let Some(c) = &summary.paper_l2 {
                let _ = writeln!(s, "\nAgainst the paper, like for like");
                s.push_str(&paper_text(c));
            }
        }
        None => {
            let _ = writeln!(
                s,
                "\nAgainst the paper: only for the paper's scenes S01 and S02 (Tables 6 and 9) with the built-in pendulum."
            );
        }
    }
    if let Some(lines) = &summary.reference_lines {
        let labels: Vec<&str> = lines.curves.iter().map(|c| c.label.as_str()).collect();
        let _ = writeln!(
            s,
            "\nReference lines in the work-precision diagram: {}.\n{}",
            labels.join(", "),
            lines.note
        );
    }
    s
}

/// One line on the accuracy verdicts of the finished runs (shared by the
/// terminal report and index.html).
pub fn accuracy_line(report: &SweepReport) -> String {
    let finished: Vec<Accuracy> = report
        .runs
        .iter()
        .filter_map(|r| r.record.accuracy)
        .collect();
    let count = |a: Accuracy| finished.iter().filter(|v| **v == a).count();
    if report.has_reference() {
        format!(
            "Accuracy: {} of {} finished runs accurate (err <= {ACCURATE_FACTOR}·tol·max(1, |y*|) at every check \
             time), {} INACCURATE: reaching the end is not being right.",
            count(Accuracy::Accurate),
            finished.len(),
            count(Accuracy::Inaccurate)
        )
    } else {
        format!(
            "Accuracy: no reference, {} of {} finished runs unverified, {} SUSPECT (constraint residual or invariant \
             drift >= {SUSPECT_FACTOR:.0e}·tol).",
            count(Accuracy::Unverified),
            finished.len(),
            count(Accuracy::Suspect)
        )
    }
}

/// `results.csv`: one row per run.
pub fn results_csv(report: &SweepReport) -> std::io::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> = [
        "scene",
        "solver",
        "formulation",
        "tol",
        "status",
        "accuracy",
        "accuracy_note",
        "error_kind",
        "error_message",
        "t_end",
        "tsim_s",
        "tsim_runs",
        "wall_s",
        "wall_runs",
        "err",
        "err_sum",
        "err_l2",
        "err_algebraic",
        "scd",
        "steps",
        "rejected",
        "residual_evals",
        "jacobian_evals",
        "factorizations",
        "newton_iterations",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let levels = residual_levels(&report.runs);
    head.extend((0..levels).map(|k| format!("residual_level{k}")));
    head.extend(report.invariants.iter().map(|n| format!("drift_{n}")));
    head.extend(report.variables.iter().map(|n| format!("final_{n}")));
    w.write_record(&head)?;
    let opt = |v: Option<f64>| v.map_or_else(String::new, |v| format!("{v:e}"));
    for run in &report.runs {
        let r = &run.record;
        let mut row = vec![
            r.scene.clone(),
            r.solver.clone(),
            r.formulation.clone(),
            format!("{:e}", r.tol),
            r.status.to_string(),
            r.accuracy
                .map_or_else(String::new, |a| a.as_str().to_string()),
            r.accuracy_note.clone().unwrap_or_default(),
            r.error
                .as_ref()
                .map_or_else(String::new, |e| e.kind.clone()),
            r.error
                .as_ref()
                .map_or_else(String::new, |e| e.message.clone()),
            format!("{:e}", r.t_end),
            format!("{:e}", r.tsim_s),
            run.tsim_runs
                .iter()
                .map(|t| format!("{t:e}"))
                .collect::<Vec<_>>()
                .join(";"),
            format!("{:e}", r.wall_s),
            run.wall_runs
                .iter()
                .map(|t| format!("{t:e}"))
                .collect::<Vec<_>>()
                .join(";"),
            opt(r.err),
            opt(r.err_sum),
            opt(r.err_l2),
            opt(r.err_algebraic),
            opt(r.scd),
            r.stats.steps.to_string(),
            r.stats.rejected.to_string(),
            r.stats.residual_evals.to_string(),
            r.stats.jacobian_evals.to_string(),
            r.stats.factorizations.to_string(),
            r.stats.newton_iterations.to_string(),
        ];
        row.extend((0..levels).map(|k| opt(r.residuals.level(k))));
        row.extend(
            report
                .invariants
                .iter()
                .map(|n| opt(r.invariant_drift.get(n))),
        );
        row.extend(report.variables.iter().map(|n| opt(r.final_values.get(n))));
        w.write_record(&row)?;
    }
    w.into_inner()
        .map_err(|e| std::io::Error::other(e.to_string()))
}

//! The paper's efficiency tables (Steinbrecher 2015, Table 6 for S01 and
//! Table 9 for S02), shipped in `data/` and embedded, and the comparison of
//! our errors with the paper's ERR.
//!
//! The paper does not define ERR. Two readings are compared ([`Measure`]):
//! SPEC's `err_sum` (the sum of the errors over the check times, the most
//! demanding reading, and the one the acceptance criteria use), and
//! `err_l2` (their Euclidean norm), the reading under which our faithful
//! ports of DASSL and ODASSL, which take those codes' steps, reproduce the
//! paper's DASSL, DASPK and ODASSL values on S02 to within small factors,
//! as the Fortran RADAU5's measured errors reproduce the paper's RADAU5
//! (BENCHMARKS.md §3c). Under `err_sum` the same runs sit 18–38× above
//! them.
//!
//! Families: our `radau5` is compared with RADAU5, our `bdf` with DASSL and
//! with DASPK, our `odradau` with QUALIDAES and GEOMS, our `odbdf` with
//! ODASSL and OVDBDF (one comparison row per paper code). A cell is labelled by
//! the ratio `ours / paper`: below 1/2 **more accurate**, within a factor
//! 2 either way **equal**, above 2 **behind**. Where only one side
//! succeeded the cell says so.

use super::{SweepReport, SweepRun};
use crate::runner::RunRecord;
use serde::Serialize;

/// Table 9 of the paper (S02), as shipped in `shared/reference/`.
pub const TABLE9_S02_CSV: &str = include_str!("../../data/paper_table9_s02.csv");
/// Table 6 of the paper (S01), transcribed from the seed text; `?` marks
/// cells the seed's OCR makes illegible.
pub const TABLE6_S01_CSV: &str = include_str!("../../data/paper_table6_s01.csv");

/// Factor within which two errors count as equal.
pub const EQUAL_FACTOR: f64 = 2.0;

/// One cell of a paper table.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum PaperCell {
    /// A value.
    Value(f64),
    /// The integration was not successful (`-` in the paper).
    Failed,
    /// The seed text is illegible here.
    Illegible,
}

/// One row: a code, a formulation, a quantity over the tolerances.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PaperRow {
    /// Paper code (`RADAU5`, `DASSL`, …).
    pub solver: String,
    /// Formulation.
    pub formulation: String,
    /// `tsim_s` or `err`.
    pub quantity: String,
    /// One cell per tolerance of the table.
    pub cells: Vec<PaperCell>,
}

/// A parsed paper table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PaperTable {
    /// Which table (`Table 6 (S01)` …).
    pub label: String,
    /// Tolerances of the columns.
    pub tolerances: Vec<f64>,
    /// Rows in file order.
    pub rows: Vec<PaperRow>,
}

/// Why a paper table could not be parsed.
#[derive(Debug, thiserror::Error)]
pub enum PaperError {
    /// Missing or malformed header.
    #[error("{label}: bad header: {why}")]
    Header {
        /// Table.
        label: String,
        /// What is wrong.
        why: String,
    },
    /// A malformed row.
    #[error("{label}: line {line}: {why}")]
    Row {
        /// Table.
        label: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        why: String,
    },
}

impl PaperTable {
    /// Parse the CSV shape of `data/paper_table*.csv` (read with the `csv`
    /// crate): `#` comment lines, a header `solver,formulation,quantity,TOL…`,
    /// then rows; an empty cell is a failed run, `?` an illegible one.
    ///
    /// ```
    /// use dae::sweep::paper::{PaperCell, PaperTable};
    ///
    /// let t = PaperTable::parse("T", "# a note\nsolver,formulation,quantity,1e-5,1e-6\nDASSL,rcd0,err,3.1e2,\n")?;
    /// assert_eq!(t.cell("DASSL", "rcd0", "err", 1e-5), Some(PaperCell::Value(310.0)));
    /// assert_eq!(t.cell("DASSL", "rcd0", "err", 1e-6), Some(PaperCell::Failed));
    /// # Ok::<(), dae::sweep::paper::PaperError>(())
    /// ```
    pub fn parse(label: &str, text: &str) -> Result<PaperTable, PaperError> {
        let mut reader = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .flexible(true)
            .from_reader(text.as_bytes());
        let header_err = |why: String| PaperError::Header {
            label: label.into(),
            why,
        };
        let head = reader
            .headers()
            .map_err(|e| header_err(e.to_string()))?
            .clone();
        if head.is_empty() {
            return Err(header_err("no header".into()));
        }
        let names: Vec<&str> = head.iter().collect();
        if names.len() < 4 || names[..3] != ["solver", "formulation", "quantity"] {
            return Err(header_err(format!(
                "expected solver,formulation,quantity,… got `{}`",
                names.join(",")
            )));
        }
        let tolerances = names[3..]
            .iter()
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|_| header_err(format!("tolerance `{t}` is not a number")))
            })
            .collect::<Result<Vec<f64>, _>>()?;
        let mut rows = Vec::new();
        for record in reader.records() {
            let row_err = |line: u64, why: String| PaperError::Row {
                label: label.into(),
                line: usize::try_from(line).unwrap_or(usize::MAX),
                why,
            };
            let f = record
                .map_err(|e| row_err(e.position().map_or(0, csv::Position::line), e.to_string()))?;
            let line = f.position().map_or(0, csv::Position::line);
            if f.len() != 3 + tolerances.len() {
                return Err(row_err(
                    line,
                    format!("{} fields, expected {}", f.len(), 3 + tolerances.len()),
                ));
            }
            let cells = f
                .iter()
                .skip(3)
                .map(|c| match c {
                    "" => Ok(PaperCell::Failed),
                    "?" => Ok(PaperCell::Illegible),
                    v => v
                        .parse::<f64>()
                        .map(PaperCell::Value)
                        .map_err(|_| row_err(line, format!("`{v}` is not a number"))),
                })
                .collect::<Result<Vec<_>, _>>()?;
            rows.push(PaperRow {
                solver: f[0].into(),
                formulation: f[1].into(),
                quantity: f[2].into(),
                cells,
            });
        }
        Ok(PaperTable {
            label: label.into(),
            tolerances,
            rows,
        })
    }

    /// The paper table for a scene, when the scene is one of the paper's
    /// ([`scenario`]: name `S01`/`S02`, the built-in pendulum, the paper's
    /// horizon).
    pub fn for_scene(name: &str, paper_setup: bool, t_end: f64) -> Option<PaperTable> {
        let (label, text) = match scenario(name, paper_setup, t_end)? {
            Scenario::S01 => ("Table 6 (S01)", TABLE6_S01_CSV),
            Scenario::S02 => ("Table 9 (S02)", TABLE9_S02_CSV),
        };
        PaperTable::parse(label, text).ok()
    }

    /// The cell of `quantity` for a code, formulation and tolerance.
    pub fn cell(
        &self,
        solver: &str,
        formulation: &str,
        quantity: &str,
        tol: f64,
    ) -> Option<PaperCell> {
        let col = self.tolerances.iter().position(|t| same_tol(*t, tol))?;
        self.rows
            .iter()
            .find(|r| r.solver == solver && r.formulation == formulation && r.quantity == quantity)
            .map(|r| r.cells[col])
    }

    /// Whether the paper ran this code on this formulation at all.
    pub fn has(&self, solver: &str, formulation: &str) -> bool {
        self.rows
            .iter()
            .any(|r| r.solver == solver && r.formulation == formulation)
    }
}

/// One of the paper's two scenarios (SPEC §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Scenario {
    /// The pendulum on [0, 20], checked at t = 20.
    S01,
    /// The pendulum on [0, 2000], checked every 2 s.
    S02,
}

impl Scenario {
    /// `S01` or `S02`, as the reference files name it.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::S01 => "S01",
            Scenario::S02 => "S02",
        }
    }
}

/// Which of the paper's scenarios a scene is, if any: its name is
/// `S01`/`S02` (any case), it is the paper's setup of that scenario
/// (`paper_setup`: [`crate::scene::Scene::is_paper_setup`], the built-in
/// pendulum with the scenario's parameters, initial values and check times)
/// and its horizon is the scenario's (20 or 2000). The one rule for everything
/// measured elsewhere on the paper's scenarios: the paper's tables and the
/// Fortran reference lines ([`super::fortran`]).
pub fn scenario(name: &str, paper_setup: bool, t_end: f64) -> Option<Scenario> {
    if !paper_setup {
        return None;
    }
    match name.to_ascii_uppercase().as_str() {
        "S01" if t_end == 20.0 => Some(Scenario::S01),
        "S02" if t_end == 2000.0 => Some(Scenario::S02),
        _ => None,
    }
}

/// Tolerances equal up to rounding of their decimal form.
pub fn same_tol(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// The paper codes of our solver's family.
pub fn family(solver: &str) -> &'static [&'static str] {
    match solver {
        "radau5" => &["RADAU5"],
        "bdf" => &["DASSL", "DASPK"],
        "odradau" => &["QUALIDAES", "GEOMS"],
        "odbdf" => &["ODASSL", "OVDBDF"],
        "mebdf" => &["MEBDF"],
        _ => &[],
    }
}

/// Which of our errors is set against the paper's ERR.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// `err_sum`: the sum over the check times of the errors of every
    /// unknown (SPEC §3, the most demanding reading).
    ErrSum,
    /// `err_l2`: the Euclidean norm of the same errors, the reading under
    /// which the classic codes' measured errors reproduce the paper's.
    ErrL2,
}

impl Measure {
    /// Both, SPEC's first.
    pub const ALL: [Measure; 2] = [Measure::ErrSum, Measure::ErrL2];

    /// The run record's field.
    pub fn field(self) -> &'static str {
        match self {
            Measure::ErrSum => "err_sum",
            Measure::ErrL2 => "err_l2",
        }
    }

    /// Our value in `record`.
    pub fn of(self, record: &RunRecord) -> Option<f64> {
        match self {
            Measure::ErrSum => record.err_sum,
            Measure::ErrL2 => record.err_l2,
        }
    }

    fn definition(self) -> &'static str {
        match self {
            Measure::ErrSum => {
                "sum over the check times of the errors of the five unknowns, positions, velocities and \
                 multiplier, against the exact solution; SPEC's reading, the most demanding"
            }
            Measure::ErrL2 => {
                "Euclidean norm over the check times and the five unknowns of the same errors; the reading \
                 under which the classic codes' measured errors reproduce the paper's values (BENCHMARKS.md §3c)"
            }
        }
    }
}

/// How our error compares with the paper's in one cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// `ours < paper / 2`.
    MoreAccurate,
    /// Within a factor 2.
    Equal,
    /// `ours > 2 · paper`.
    Behind,
    /// We succeeded where the paper's code failed.
    PaperFailed,
    /// The paper's code succeeded where we failed.
    WeFailed,
    /// Both failed.
    BothFailed,
    /// The paper's cell is illegible in the seed.
    Illegible,
}

impl Verdict {
    /// Short label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Verdict::MoreAccurate => "more accurate",
            Verdict::Equal => "equal",
            Verdict::Behind => "behind",
            Verdict::PaperFailed => "paper failed",
            Verdict::WeFailed => "we failed",
            Verdict::BothFailed => "both failed",
            Verdict::Illegible => "illegible",
        }
    }

    /// Compare our error (`None`: our run failed) with the paper's cell.
    pub fn of(ours: Option<f64>, paper: PaperCell) -> Verdict {
        match (ours, paper) {
            (_, PaperCell::Illegible) => Verdict::Illegible,
            (Some(_), PaperCell::Failed) => Verdict::PaperFailed,
            (None, PaperCell::Failed) => Verdict::BothFailed,
            (None, PaperCell::Value(_)) => Verdict::WeFailed,
            (Some(o), PaperCell::Value(p)) => {
                if o * EQUAL_FACTOR < p {
                    Verdict::MoreAccurate
                } else if o > p * EQUAL_FACTOR {
                    Verdict::Behind
                } else {
                    Verdict::Equal
                }
            }
        }
    }
}

/// One cell of the comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareCell {
    /// Tolerance.
    pub tol: f64,
    /// Our error in the comparison's [`Measure`] (`None` when our run
    /// failed).
    pub ours: Option<f64>,
    /// The paper's ERR.
    pub paper: PaperCell,
    /// The label.
    pub verdict: Verdict,
}

/// One row: our pair against one paper code on the same formulation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareRow {
    /// Our solver.
    pub solver: String,
    /// Formulation.
    pub formulation: String,
    /// The paper code.
    pub paper_solver: String,
    /// One cell per tolerance of ours that the paper table has.
    pub cells: Vec<CompareCell>,
}

/// The comparison with the paper for one scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Which table.
    pub table: String,
    /// Which of our errors is compared.
    pub measure: Measure,
    /// What is compared.
    pub note: String,
    /// Rows.
    pub rows: Vec<CompareRow>,
    /// Paper rows (`CODE(formulation)`) we ran against but whose every
    /// cell is illegible in the seed: left out of `rows`.
    pub illegible: Vec<String>,
    /// How many cells got each verdict, in [`Verdict`] order.
    pub counts: Vec<VerdictCount>,
}

/// How many cells got one verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct VerdictCount {
    /// The verdict.
    pub verdict: Verdict,
    /// Number of cells.
    pub cells: usize,
}

/// Compare our runs with a paper table under `measure`: every pair of ours
/// whose family code the paper ran on the same formulation.
pub fn compare(table: &PaperTable, report: &SweepReport, measure: Measure) -> Comparison {
    compare_runs(
        table,
        &report.solvers,
        &report.formulations,
        &report.tolerances,
        &report.runs,
        measure,
    )
}

/// [`compare`] on plain lists (used by tests).
pub fn compare_runs(
    table: &PaperTable,
    solvers: &[String],
    formulations: &[String],
    tolerances: &[f64],
    runs: &[SweepRun],
    measure: Measure,
) -> Comparison {
    let mut rows = Vec::new();
    let mut illegible = Vec::new();
    for s in solvers {
        for f in formulations {
            let ours: Vec<&SweepRun> = runs
                .iter()
                .filter(|r| &r.record.solver == s && &r.record.formulation == f)
                .collect();
            if ours.is_empty() {
                continue;
            }
            for code in family(s) {
                if !table.has(code, f) {
                    continue;
                }
                let mut cells = Vec::new();
                for &tol in tolerances {
                    let Some(paper) = table.cell(code, f, "err", tol) else {
                        continue;
                    };
                    let Some(run) = ours.iter().find(|r| same_tol(r.record.tol, tol)) else {
                        continue;
                    };
                    let mine = if run.record.status == "ok" {
                        measure.of(&run.record)
                    } else {
                        None
                    };
                    cells.push(CompareCell {
                        tol,
                        ours: mine,
                        paper,
                        verdict: Verdict::of(mine, paper),
                    });
                }
                if !cells.is_empty() && cells.iter().all(|c| c.verdict == Verdict::Illegible) {
                    illegible.push(format!("{code}({f})"));
                } else if !cells.is_empty() {
                    rows.push(CompareRow {
                        solver: s.clone(),
                        formulation: f.clone(),
                        paper_solver: (*code).to_string(),
                        cells,
                    });
                }
            }
        }
    }
    let all = [
        Verdict::MoreAccurate,
        Verdict::Equal,
        Verdict::Behind,
        Verdict::PaperFailed,
        Verdict::WeFailed,
        Verdict::BothFailed,
        Verdict::Illegible,
    ];
    let counts = all
        .iter()
        .map(|v| VerdictCount {
            verdict: *v,
            cells: rows
                .iter()
                .flat_map(|r| &r.cells)
                .filter(|c| c.verdict == *v)
                .count(),
        })
        .collect();
    Comparison {
        table: table.label.clone(),
        measure,
        note: format!(
            "our {} ({}) next to the paper's ERR; more accurate: ours < paper/{EQUAL_FACTOR}, equal: within a factor \
             {EQUAL_FACTOR}, behind: ours > {EQUAL_FACTOR}·paper. radau5 ↔ RADAU5, bdf ↔ DASSL and DASPK, odradau ↔ QUALIDAES and GEOMS, odbdf ↔ ODASSL and OVDBDF, mebdf ↔ MEBDF.",
            measure.field(),
            measure.definition()
        ),
        rows,
        illegible,
        counts,
    }
}

//! Statistics snapshot of every registered solver on shared reference
//! models.
//!
//! Every solver of [`dae_solvers::SOLVER_NAMES`] (looked up with
//! [`dae_solvers::solver_by_name`], so a solver added there is covered
//! without touching this file) runs every case of [`cases`] that it
//! [`accepts`](dae_solvers::Solver::accepts) at the tolerances of [`TOLS`].
//! Each run is pinned in `tests/snapshots/harness.json`:
//!
//! * a success by its [`Stats`](dae_solvers::Stats) (steps, rejected,
//!   residual and Jacobian evaluations, factorisations, Newton iterations),
//!   its output times and the solution at each of them (the last is
//!   `y(t_end)`);
//! * a failure by the typed error's `kind()` and `t()`;
//! * a case the solver refuses by the refusal's text, once per solver and
//!   case ("not applicable").
//!
//! The comparison is strict where the code is deterministic: counts must be
//! equal, values and times agree to `|a − b| ≤ 1e-9 · max(1, |b|)` (`b` the
//! snapshot's). A record of the snapshot with no current run, or a run with
//! no record, is a difference too, so a new solver or case is noticed. The
//! test lists every differing record, not only the first.
//!
//! To rewrite the snapshot from the current code (after checking the diff
//! the failing test prints):
//!
//! ```text
//! DAE_BLESS=1 cargo test -p dae-solvers --test harness
//! ```
//!
//! When [`Options`] change, adapt [`options`] only: every run is built
//! there.

mod common;

use common::*;
use dae_core::system::DaeSystem;
use dae_solvers::init::{consistent, InitOptions};
use dae_solvers::{solver_by_name, Options, Problem, SOLVER_NAMES};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::time::Instant;

/// Tolerances (`rtol = atol`) every applicable case runs at.
const TOLS: [f64; 3] = [1e-4, 1e-7, 1e-10];

/// Relative agreement required of values and times.
const REL: f64 = 1e-9;

/// The environment variable that rewrites the snapshot.
const BLESS: &str = "DAE_BLESS";

/// The snapshot, beside this file.
fn snapshot_path() -> String {
    format!(
        "{}/tests/snapshots/harness.json",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// The options of every run: uniform tolerance `tol`, dense output at
/// `output_times`, and index-2 unknowns out of BDF's error test, as the
/// `dae run` command line uses them (the library default includes them).
/// `solver` is there for the day a solver needs its own settings.
fn options(solver: &str, tol: f64, output_times: Vec<f64>) -> Options {
    let _ = solver;
    Options {
        output_times,
        index2_in_error_test: Some(false),
        ..Options::with_tol(tol)
    }
}

/// The text of a refusal of [`dae_solvers::Solver::accepts`], whatever its
/// type.
fn refusal_text<E: std::fmt::Display>(e: E) -> String {
    format!("{e}")
}

// ---------------------------------------------------------------------------
// The cases
// ---------------------------------------------------------------------------

/// Where a case's initial values come from.
enum Start {
    /// These values, as they are (exact or deliberately inconsistent).
    Given(Vec<f64>),
    /// [`consistent`] from this guess (default [`InitOptions`]).
    Consistent(Vec<f64>),
}

/// One initial value problem.
struct Case {
    name: &'static str,
    system: Box<dyn DaeSystem>,
    t0: f64,
    t_end: f64,
    start: Start,
}

fn case(
    name: &'static str,
    system: impl DaeSystem + 'static,
    t0: f64,
    t_end: f64,
    start: Start,
) -> Case {
    Case {
        name,
        system: Box::new(system),
        t0,
        t_end,
        start,
    }
}

/// The reference problems, in snapshot order: every square model family of
/// `common/`, the overdetermined pendulum (refused by square solvers), and
/// problems that end in each typed error.
fn cases() -> Vec<Case> {
    use Start::{Consistent, Given};
    let mut cases = Vec::new();
    // The paper's pendulum (S01 start, one period) in every formulation.
    for form in Form::SQUARE.into_iter().chain([Form::Ovd1]) {
        let name = match form {
            Form::Ori2 => "pendulum_ori2",
            Form::Rcd1 => "pendulum_rcd1",
            Form::Rcd0 => "pendulum_rcd0",
            Form::Ggl1 => "pendulum_ggl1",
            Form::Psi1 => "pendulum_psi1",
            Form::Psi0 => "pendulum_psi0",
            Form::Ovd1 => "pendulum_ovd1",
        };
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        cases.push(case(name, sys, 0.0, 2.0, Consistent(y0)));
    }
    // The overdetermined pendulum with every constraint level (the
    // least-squares solvers' main formulation).
    let ovd0 = PendulumOvd0::new();
    let y0 = ovd0.y0();
    cases.push(case("pendulum_ovd0", ovd0, 0.0, 2.0, Consistent(y0)));
    // Other constrained mechanical and index-2 models.
    let dp = DoublePendulum::new(1.3, 0.7, 1.1, 0.8, G);
    let dp_start = dp.state(0.9, -0.4, 0.5, -1.0);
    cases.push(case(
        "double_pendulum_rcd0",
        Sys(dp),
        0.0,
        2.0,
        Consistent(dp_start),
    ));
    // A constant mass matrix whose acceleration row keeps `der(vu)` (the
    // cart pendulum of `scenes/`): rcd0 is integrated through the
    // elimination of `core/eliminate.rs`, by the constant-`E` solvers too.
    let cart = dae_core::interp::InterpretedModel::from_str(include_str!(
        "../../scenes/cart_pendulum.dae"
    ))
    .expect("the cart pendulum derives")
    .system("rcd0")
    .expect("its rcd0");
    cases.push(case(
        "cart_pendulum_rcd0",
        cart,
        0.0,
        2.0,
        Consistent(vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
    ));
    cases.push(case(
        "idec_ori1",
        Sys(Idec::new()),
        0.0,
        1.0,
        Consistent(Idec::exact(0.0)),
    ));
    cases.push(case(
        "toy_ode",
        Sys(Toy::new()),
        0.0,
        1.0,
        Consistent(vec![0.7, 0.2]),
    ));
    cases.push(case(
        "toy_free",
        Sys(Toy::unconstrained()),
        0.0,
        1.0,
        Consistent(vec![0.3, -0.2, 0.5]),
    ));
    // Small systems with closed-form solutions, started exactly.
    cases.push(case("ode", ode(), 0.0, 2.0, Given(ode_exact(0.0))));
    cases.push(case("ode_from_1", ode(), 1.0, 3.0, Given(ode_exact(1.0))));
    cases.push(case(
        "index1",
        index1(),
        0.0,
        2.0,
        Given(index1_exact(0.0).to_vec()),
    ));
    cases.push(case("dae1", dae1(), 0.0, 1.4, Given(dae1_exact(0.0))));
    // Failures: each should end in a typed error.
    cases.push(case(
        "pendulum_rcd0_inconsistent",
        Pendulum::new(Form::Rcd0),
        0.0,
        1.0,
        Given(vec![1.0, 0.0, 0.0, 0.0, 1.0]),
    ));
    cases.push(case(
        "ode_empty_horizon",
        ode(),
        1.0,
        1.0,
        Given(ode_exact(1.0)),
    ));
    cases.push(case("blow_up", blow_up(), 0.0, 2.0, Given(vec![1.0])));
    cases.push(case("nan_rhs", nan_rhs(), 0.0, 1.0, Given(vec![1.0])));
    cases.push(case(
        "nan_beyond_half",
        nan_beyond_half(),
        0.0,
        2.0,
        Given(vec![1.0]),
    ));
    cases.push(case(
        "no_real_root",
        no_real_root(),
        0.0,
        1.0,
        Given(vec![1.0]),
    ));
    cases.push(case(
        "zero_equals_one",
        zero_equals_one(),
        0.0,
        1.0,
        Given(vec![0.0]),
    ));
    cases.push(case(
        "structurally_singular",
        structurally_singular(),
        0.0,
        1.0,
        Given(vec![1.0, 0.0]),
    ));
    cases
}

/// Output times of a case: a quarter, half way, the end.
fn output_times(t0: f64, t_end: f64) -> Vec<f64> {
    let span = t_end - t0;
    vec![t0 + 0.25 * span, t0 + 0.5 * span, t_end]
}

// ---------------------------------------------------------------------------
// The snapshot
// ---------------------------------------------------------------------------

/// The whole snapshot file.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Snapshot {
    /// What the file is (not compared).
    about: String,
    /// The problems, as run.
    cases: Vec<CaseRecord>,
    /// One record per solver, case and tolerance (per solver and case when
    /// not applicable).
    runs: Vec<Run>,
}

/// A problem as it was posed.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct CaseRecord {
    name: String,
    model: String,
    formulation: String,
    t0: f64,
    t_end: f64,
    output_times: Vec<f64>,
    /// The initial values handed to the solvers.
    y0: Vec<f64>,
}

/// One solver on one case at one tolerance.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Run {
    solver: String,
    case: String,
    /// `None` for a case the solver does not accept.
    tol: Option<f64>,
    #[serde(flatten)]
    outcome: Outcome,
}

/// How a run ended.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
enum Outcome {
    /// Reached `t_end`.
    Ok {
        stats: StatsRecord,
        /// Output times reported.
        t: Vec<f64>,
        /// The solution at each of them.
        y: Vec<Vec<f64>>,
    },
    /// A typed error.
    Error {
        kind: String,
        /// `SolveError::t()`.
        t: Option<f64>,
    },
    /// `accepts` refused the case.
    NotApplicable { reason: String },
}

/// The counters of [`dae_solvers::Stats`] that are pinned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
struct StatsRecord {
    steps: usize,
    rejected: usize,
    residual_evals: usize,
    jacobian_evals: usize,
    factorizations: usize,
    newton_iterations: usize,
}

impl StatsRecord {
    fn of(s: &dae_solvers::Stats) -> Self {
        StatsRecord {
            steps: s.steps,
            rejected: s.rejected,
            residual_evals: s.residual_evals,
            jacobian_evals: s.jacobian_evals,
            factorizations: s.factorizations,
            newton_iterations: s.newton_iterations,
        }
    }

    fn fields(&self) -> [(&'static str, usize); 6] {
        [
            ("steps", self.steps),
            ("rejected", self.rejected),
            ("residual_evals", self.residual_evals),
            ("jacobian_evals", self.jacobian_evals),
            ("factorizations", self.factorizations),
            ("newton_iterations", self.newton_iterations),
        ]
    }
}

impl Run {
    /// Identity of the record: solver, case, tolerance.
    fn key(&self) -> String {
        match self.tol {
            Some(tol) => format!("{} / {} / tol {tol:e}", self.solver, self.case),
            None => format!("{} / {} / (any tol)", self.solver, self.case),
        }
    }
}

impl Outcome {
    /// One line describing the outcome.
    fn summary(&self) -> String {
        match self {
            Outcome::Ok { stats, y, .. } => format!(
                "ok, {} steps, {} rejected, y(t_end) = {:?}",
                stats.steps,
                stats.rejected,
                y.last().map(Vec::as_slice).unwrap_or(&[])
            ),
            Outcome::Error { kind, t } => format!("error {kind} at t = {}", show_t(*t)),
            Outcome::NotApplicable { reason } => format!("not applicable: {reason}"),
        }
    }
}

fn show_t(t: Option<f64>) -> String {
    match t {
        Some(t) => format!("{t:e}"),
        None => "(none)".into(),
    }
}

// ---------------------------------------------------------------------------
// Running
// ---------------------------------------------------------------------------

/// Pose every case and run every solver on it.
fn run_all() -> Snapshot {
    let mut case_records = Vec::new();
    let mut runs = Vec::new();
    let cases = cases();
    let mut posed = Vec::new();
    for c in &cases {
        let y0 = match &c.start {
            Start::Given(y) => y.clone(),
            Start::Consistent(guess) => {
                consistent(c.system.as_ref(), c.t0, guess, &InitOptions::default())
                    .unwrap_or_else(|e| panic!("case {}: consistent initial values: {e}", c.name))
                    .y
            }
        };
        let info = c.system.info();
        case_records.push(CaseRecord {
            name: c.name.into(),
            model: info.model.clone(),
            formulation: info.name.clone(),
            t0: c.t0,
            t_end: c.t_end,
            output_times: output_times(c.t0, c.t_end),
            y0: y0.clone(),
        });
        posed.push(y0);
    }
    for name in SOLVER_NAMES {
        let solver =
            solver_by_name(name).unwrap_or_else(|| panic!("{name} is in SOLVER_NAMES only"));
        for (c, y0) in cases.iter().zip(&posed) {
            if let Err(reason) = solver.accepts(c.system.info()) {
                runs.push(Run {
                    solver: name.into(),
                    case: c.name.into(),
                    tol: None,
                    outcome: Outcome::NotApplicable {
                        reason: refusal_text(reason),
                    },
                });
                continue;
            }
            let problem = Problem {
                system: c.system.as_ref(),
                t0: c.t0,
                y0,
                t_end: c.t_end,
            };
            for tol in TOLS {
                let opts = options(name, tol, output_times(c.t0, c.t_end));
                let outcome = match solver.solve(&problem, &opts) {
                    Ok(sol) => {
                        let finite = sol
                            .t
                            .iter()
                            .chain(sol.y.iter().flatten())
                            .all(|v| v.is_finite());
                        assert!(
                            finite,
                            "{name} / {} / tol {tol:e}: a successful run returned non-finite output",
                            c.name
                        );
                        Outcome::Ok {
                            stats: StatsRecord::of(&sol.stats),
                            t: sol.t,
                            y: sol.y,
                        }
                    }
                    Err(err) => Outcome::Error {
                        kind: err.kind().into(),
                        t: err.t(),
                    },
                };
                runs.push(Run {
                    solver: name.into(),
                    case: c.name.into(),
                    tol: Some(tol),
                    outcome,
                });
            }
        }
    }
    Snapshot {
        about: format!(
            "Statistics of every solver on the reference cases of dae-solvers/tests/harness.rs. \
             Do not edit: `{BLESS}=1 cargo test -p dae-solvers --test harness` rewrites it."
        ),
        cases: case_records,
        runs,
    }
}

// ---------------------------------------------------------------------------
// Comparing
// ---------------------------------------------------------------------------

/// `new` agrees with the snapshot's `old`.
fn close(new: f64, old: f64) -> bool {
    (new - old).abs() <= REL * old.abs().max(1.0)
}

/// Differences of two value lists, one line each, into `out`.
fn diff_values(what: &str, old: &[f64], new: &[f64], out: &mut Vec<String>) {
    if old.len() != new.len() {
        out.push(format!(
            "{what}: {} values -> {} values ({old:?} -> {new:?})",
            old.len(),
            new.len()
        ));
        return;
    }
    for (i, (o, n)) in old.iter().zip(new).enumerate() {
        if !close(*n, *o) {
            out.push(format!("{what}[{i}]: {o:e} -> {n:e} (diff {:.3e})", n - o));
        }
    }
}

/// What differs between a snapshot record and a current run.
fn diff_outcome(old: &Outcome, new: &Outcome) -> Vec<String> {
    let mut out = Vec::new();
    match (old, new) {
        (
            Outcome::Ok {
                stats: so,
                t: to,
                y: yo,
            },
            Outcome::Ok {
                stats: sn,
                t: tn,
                y: yn,
            },
        ) => {
            for ((name, o), (_, n)) in so.fields().into_iter().zip(sn.fields()) {
                if o != n {
                    out.push(format!("stats.{name}: {o} -> {n}"));
                }
            }
            diff_values("t", to, tn, &mut out);
            if yo.len() != yn.len() {
                out.push(format!("y: {} outputs -> {}", yo.len(), yn.len()));
            } else {
                for (k, (o, n)) in yo.iter().zip(yn).enumerate() {
                    let at = to.get(k).map_or(String::new(), |t| format!(" (t = {t})"));
                    diff_values(&format!("y[{k}]{at}"), o, n, &mut out);
                }
            }
        }
        (Outcome::Error { kind: ko, t: to }, Outcome::Error { kind: kn, t: tn }) => {
            if ko != kn {
                out.push(format!("error kind: {ko} -> {kn}"));
            }
            let same_t = match (to, tn) {
                (Some(o), Some(n)) => close(*n, *o),
                (None, None) => true,
                _ => false,
            };
            if !same_t {
                out.push(format!("error t: {} -> {}", show_t(*to), show_t(*tn)));
            }
        }
        (Outcome::NotApplicable { reason: ro }, Outcome::NotApplicable { reason: rn }) => {
            if ro != rn {
                out.push(format!("refusal: {ro:?} -> {rn:?}"));
            }
        }
        _ => out.push(format!("outcome: {} -> {}", old.summary(), new.summary())),
    }
    out
}

/// Every difference between the snapshot `old` and the current `new`, one
/// entry per differing case or run record (with its detail lines).
fn diff(old: &Snapshot, new: &Snapshot) -> Vec<String> {
    let mut entries = Vec::new();

    let new_cases: HashMap<&str, &CaseRecord> =
        new.cases.iter().map(|c| (c.name.as_str(), c)).collect();
    let old_case_names: Vec<&str> = old.cases.iter().map(|c| c.name.as_str()).collect();
    for o in &old.cases {
        let Some(n) = new_cases.get(o.name.as_str()) else {
            entries.push(format!(
                "case {}: in the snapshot, no longer defined",
                o.name
            ));
            continue;
        };
        let mut lines = Vec::new();
        for (what, a, b) in [
            ("model", &o.model, &n.model),
            ("formulation", &o.formulation, &n.formulation),
        ] {
            if a != b {
                lines.push(format!("{what}: {a} -> {b}"));
            }
        }
        diff_values("t0", &[o.t0], &[n.t0], &mut lines);
        diff_values("t_end", &[o.t_end], &[n.t_end], &mut lines);
        diff_values("output_times", &o.output_times, &n.output_times, &mut lines);
        diff_values("y0", &o.y0, &n.y0, &mut lines);
        if !lines.is_empty() {
            entries.push(entry(&format!("case {}", o.name), &lines));
        }
    }
    for n in &new.cases {
        if !old_case_names.contains(&n.name.as_str()) {
            entries.push(format!("case {}: new, not in the snapshot", n.name));
        }
    }

    let new_runs: HashMap<String, &Run> = new.runs.iter().map(|r| (r.key(), r)).collect();
    let mut seen = std::collections::HashSet::new();
    for o in &old.runs {
        let key = o.key();
        seen.insert(key.clone());
        match new_runs.get(&key) {
            None => entries.push(format!(
                "{key}: in the snapshot ({}), no current run",
                o.outcome.summary()
            )),
            Some(n) => {
                let lines = diff_outcome(&o.outcome, &n.outcome);
                if !lines.is_empty() {
                    entries.push(entry(&key, &lines));
                }
            }
        }
    }
    for n in &new.runs {
        let key = n.key();
        if !seen.contains(&key) {
            entries.push(format!(
                "{key}: new run ({}), not in the snapshot",
                n.outcome.summary()
            ));
        }
    }
    entries
}

/// A header and indented detail lines.
fn entry(header: &str, lines: &[String]) -> String {
    let mut s = format!("{header}:");
    for l in lines {
        let _ = write!(s, "\n    {l}");
    }
    s
}

fn to_json(s: &Snapshot) -> String {
    let mut text = serde_json::to_string_pretty(s).expect("snapshot serialises");
    text.push('\n');
    text
}

// ---------------------------------------------------------------------------
// The tests
// ---------------------------------------------------------------------------

#[test]
fn every_solver_matches_the_statistics_snapshot() {
    let start = Instant::now();
    let current = run_all();
    let elapsed = start.elapsed().as_secs_f64();
    eprintln!(
        "harness: {} cases, {} run records in {elapsed:.1} s",
        current.cases.len(),
        current.runs.len()
    );
    let path = snapshot_path();
    if std::env::var_os(BLESS).is_some_and(|v| !v.is_empty() && v != "0") {
        if let Some(dir) = std::path::Path::new(&path).parent() {
            std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        }
        std::fs::write(&path, to_json(&current)).unwrap_or_else(|e| panic!("{path}: {e}"));
        eprintln!("harness: wrote {path}");
        return;
    }
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{path}: {e}\nGenerate it with `{BLESS}=1 cargo test -p dae-solvers --test harness`."
        )
    });
    let snapshot: Snapshot =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path} is not a snapshot: {e}"));
    let entries = diff(&snapshot, &current);
    if !entries.is_empty() {
        let mut report = format!(
            "{} record(s) differ from {path} (old -> new; counts exact, values to {REL:e} relative):\n",
            entries.len()
        );
        for e in &entries {
            let _ = writeln!(report, "  {}", e.replace('\n', "\n  "));
        }
        let _ = write!(
            report,
            "If every change is intended, rewrite the snapshot with \
             `{BLESS}=1 cargo test -p dae-solvers --test harness`."
        );
        panic!("{report}");
    }
}

/// The comparison itself: it reports every differing record, missing and
/// new ones included, and tolerates differences below [`REL`].
#[test]
fn the_comparison_reports_every_difference() {
    let ok = |steps: usize, y: f64| Outcome::Ok {
        stats: StatsRecord {
            steps,
            rejected: 1,
            residual_evals: 10,
            jacobian_evals: 2,
            factorizations: 3,
            newton_iterations: 12,
        },
        t: vec![0.5, 1.0],
        y: vec![vec![0.25, y], vec![0.5, y]],
    };
    let run = |solver: &str, case: &str, tol: Option<f64>, outcome: Outcome| Run {
        solver: solver.into(),
        case: case.into(),
        tol,
        outcome,
    };
    let old = Snapshot {
        about: String::new(),
        cases: vec![],
        runs: vec![
            run("a", "c1", Some(1e-4), ok(10, 2.0)),
            run("a", "c1", Some(1e-7), ok(20, 2.0)),
            run("a", "c2", Some(1e-4), ok(30, 2.0)),
            run(
                "a",
                "c3",
                Some(1e-4),
                Outcome::Error {
                    kind: "step_size_too_small".into(),
                    t: Some(0.99),
                },
            ),
            run(
                "b",
                "c1",
                None,
                Outcome::NotApplicable {
                    reason: "overdetermined".into(),
                },
            ),
        ],
    };
    let mut new = old.clone();
    assert!(diff(&old, &new).is_empty());
    // Below the relative tolerance: no difference.
    new.runs[0].outcome = ok(10, 2.0 * (1.0 + 1e-11));
    assert!(diff(&old, &new).is_empty());
    // A count, a value, an error time; a removed and an added record.
    new.runs[0].outcome = ok(11, 2.0);
    new.runs[1].outcome = ok(20, 2.0 + 1e-6);
    new.runs[3].outcome = Outcome::Error {
        kind: "step_size_too_small".into(),
        t: Some(0.98),
    };
    new.runs.remove(2);
    new.runs.push(run("c", "c1", Some(1e-4), ok(5, 1.0)));
    let entries = diff(&old, &new);
    assert_eq!(entries.len(), 5, "{entries:#?}");
    assert!(
        entries[0].contains("a / c1 / tol 1e-4") && entries[0].contains("stats.steps: 10 -> 11")
    );
    assert!(entries[1].contains("y[0] (t = 0.5)[1]") && entries[1].contains("y[1] (t = 1)[1]"));
    assert!(entries[2].contains("a / c2 / tol 1e-4") && entries[2].contains("no current run"));
    assert!(entries[3].contains("error t: 9.9e-1 -> 9.8e-1"));
    assert!(entries[4].contains("c / c1 / tol 1e-4") && entries[4].contains("new run"));
    // The snapshot survives a round trip through its JSON.
    let back: Snapshot = serde_json::from_str(&to_json(&old)).expect("round trip");
    assert!(diff(&old, &back).is_empty());
    assert_eq!(to_json(&back), to_json(&old));
}

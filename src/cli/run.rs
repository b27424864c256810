//! `dae run [SCENE] [--solver NAME] [--formulation NAME] [--tol T | --rtol R
//! --atol A] [--trajectory FILE.csv] [--format json|text] [--strict-init]`.
//!
//! Exit codes ([`super::Failure`]): 0 for a run that reached the end of its
//! horizon (accurate or not: the output says which); 2 for bad input — the
//! flags, the scene, the model, a formulation the solver cannot take,
//! initial values `--strict-init` refuses, a `--trajectory` file that
//! cannot be written — with a message on stderr and nothing on stdout; 3
//! for a solver that stopped before the end, with the run record on stdout.

use super::Failure;
use crate::inputs::{choose_formulation, inputs, run_tolerances, FormulationChoice};
use crate::runner::{self, RunRecord, RunSpec, RunTolerances, SensitivityRecord};
use crate::scene::{did_you_mean, ModelSource, Scene, KNOWN_FORMULATIONS, KNOWN_SOLVERS};
use dae_solvers::init::{InitMode, InitValue};
use serde::Serialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Output format of `dae run`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// JSON (the contract shape).
    Json,
    /// A short human-readable summary.
    Text,
}

/// Flags of `dae run`.
#[derive(Clone, Debug, clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML) or built-in scene name (`s01`, `s02`).
    #[arg(default_value = "s01")]
    pub scene: String,
    /// Solver (default: the scene's first).
    #[arg(long)]
    pub solver: Option<String>,
    /// Formulation (default: the solver's preferred one that the model
    /// provides, see `dae_solvers::core::policy::preferred_formulations`;
    /// the output says which and why).
    #[arg(long)]
    pub formulation: Option<String>,
    /// Tolerance RTOL = ATOL for every unknown, in [100 ε, 1) = [2.220446049250313e-14, 1) like scene
    /// tolerances: the same as `--rtol T --atol T`, and refused beside
    /// either. Default: the scene's `[tolerance]`, else 1e-8.
    #[arg(long, allow_negative_numbers = true, conflicts_with_all = ["rtol", "atol"])]
    pub tol: Option<f64>,
    /// Relative tolerance of every unknown (0, or in [100 ε, 1) = [2.220446049250313e-14, 1)); a
    /// scene's per-unknown `[tolerance] rtol` entries stay.
    #[arg(long, allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance of every unknown (finite, ≥ 0); a scene's
    /// per-unknown `[tolerance] atol` entries stay.
    #[arg(long, allow_negative_numbers = true)]
    pub atol: Option<f64>,
    /// Output format.
    #[arg(long, value_enum, default_value = "json")]
    pub format: Format,
    /// Refuse inconsistent initial values (exit code 2) instead of
    /// projecting them.
    #[arg(long)]
    pub strict_init: bool,
    /// Write every accepted step as CSV: a header `t,<unknown>,…` (the
    /// formulation's unknowns), then one row per step from the consistent
    /// start. Written whole or not at all (a temporary file in the same
    /// directory, renamed into place); not written when the solver fails.
    #[arg(long, value_name = "FILE.csv")]
    pub trajectory: Option<PathBuf>,
    /// Forward sensitivities with respect to these base parameters
    /// (comma-separated, e.g. `g,l`; replaces a scene's `[sensitivities]`):
    /// `∂y/∂p` of every unknown at the check times and at the end, from a
    /// second integration of the state and its sensitivities together.
    #[arg(long, value_delimiter = ',', value_name = "P,…")]
    pub sensitivities: Option<Vec<String>>,
    /// With sensitivities: leave them out of the error test (the step sizes
    /// are then the state's; in the error test by default).
    #[arg(long)]
    pub no_sensitivity_error_control: bool,
    /// The BDF methods' (`bdf`, `odbdf`, `mebdf`) error estimate: `checked`
    /// (the default: the method's own, switched to the propagated one once
    /// that is found ten times larger), `propagated` (always) or `dassl`
    /// (the method's own: DASSL's step counts). Other solvers ignore it.
    #[arg(long, value_enum, default_value = "checked")]
    pub estimate: EstimateArg,
}

/// `dae run --estimate` ([`dae_solvers::options::Estimate`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EstimateArg {
    /// The method's own estimate, checked against the propagated one.
    Checked,
    /// The propagated estimate at every step.
    Propagated,
    /// The method's own estimate (DASSL's).
    Dassl,
}

impl From<EstimateArg> for dae_solvers::options::Estimate {
    fn from(e: EstimateArg) -> Self {
        match e {
            EstimateArg::Checked => Self::Checked,
            EstimateArg::Propagated => Self::Propagated,
            EstimateArg::Dassl => Self::Dassl,
        }
    }
}

/// Check a tolerance given on the command line: the rule of the library
/// and of scene files, [`dae_solvers::options::check_uniform`] (`RTOL =
/// ATOL = tol` in `[100 ε, 1)`).
pub fn check_tol(tol: f64, flag: &str) -> Result<(), Failure> {
    dae_solvers::options::check_uniform(tol).map_err(|issue| {
        Failure::input(format!(
            "{flag} {tol:e}: the tolerance {issue}; tolerances (RTOL = ATOL) must be in {}",
            crate::runner::tolerance_range()
        ))
    })
}

/// `unknown {what} `{name}`; did you mean `…`? (known: …)`.
fn unknown_name(flag: &str, what: &str, name: &str, known: &[&str]) -> Failure {
    let hint =
        did_you_mean(name, known).map_or_else(String::new, |s| format!("; did you mean `{s}`?"));
    Failure::input(format!(
        "{flag} {name}: unknown {what} `{name}`{hint} (known: {})",
        known.join(", ")
    ))
}

/// What `dae run` prints in JSON: the run record, and what `dae run`
/// decided around it.
#[derive(Serialize)]
struct Output<'a> {
    #[serde(flatten)]
    record: &'a RunRecord,
    /// How the formulation was chosen.
    formulation_choice: &'a FormulationChoice,
    /// Separate or per-unknown tolerances (absent for `RTOL = ATOL = tol`).
    #[serde(skip_serializing_if = "Option::is_none")]
    tolerances: Option<&'a RunTolerances>,
    /// The `--trajectory` file written.
    #[serde(skip_serializing_if = "Option::is_none")]
    trajectory_file: Option<TrajectoryFile>,
    /// The forward sensitivities asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    sensitivities: Option<SensitivityRecord>,
}

/// The `--trajectory` file: where, and how many rows.
#[derive(Serialize)]
struct TrajectoryFile {
    path: String,
    rows: usize,
}

/// Run one scene; `Ok((output, exit code))`.
pub fn run(args: &RunArgs) -> Result<(String, i32), Failure> {
    for (flag, value) in [("--tol", args.tol), ("--rtol", args.rtol)] {
        match value {
            // A relative tolerance may be 0 only beside a positive --atol.
            Some(v) if flag == "--rtol" && v == 0.0 => {}
            Some(v) => check_tol(v, flag)?,
            None => {}
        }
    }
    if let Some(a) = args.atol {
        if !a.is_finite() || a < 0.0 {
            return Err(Failure::input(format!(
                "--atol {a:e}: an absolute tolerance must be finite and not negative"
            )));
        }
    }
    if let Some(s) = &args.solver {
        if !KNOWN_SOLVERS.contains(&s.as_str()) {
            return Err(unknown_name("--solver", "solver", s, KNOWN_SOLVERS));
        }
    }
    if let Some(f) = &args.formulation {
        if !KNOWN_FORMULATIONS.contains(&f.as_str()) {
            return Err(unknown_name(
                "--formulation",
                "formulation",
                f,
                KNOWN_FORMULATIONS,
            ));
        }
    }
    let scene = Scene::load(&args.scene).map_err(|e| Failure::input(e.to_string()))?;
    let inputs = inputs(&scene).map_err(|e| Failure::input(e.to_string()))?;
    let solver = args
        .solver
        .clone()
        .or_else(|| scene.sweep.solvers.first().cloned())
        .unwrap_or_else(|| "radau5".into());
    let Some(s) = dae_solvers::solver_by_name(&solver) else {
        return Err(unknown_name("--solver", "solver", &solver, KNOWN_SOLVERS));
    };
    let (formulation, choice) = match &args.formulation {
        Some(f) => (f.clone(), FormulationChoice::Flag),
        None => choose_formulation(&*inputs.model, &scene, &*s)
            .map_err(|e| Failure::input(format!("{}: {e}", scene.origin)))?,
    };
    let (rtol, atol) = match args.tol {
        Some(t) => (Some(t), Some(t)),
        None => (args.rtol, args.atol),
    };
    let tolerances = run_tolerances(&scene, rtol, atol);
    tolerances
        .check()
        .map_err(|e| Failure::input(format!("{}: tolerances: {e}", scene.origin)))?;
    let uniform = tolerances.is_uniform();
    let spec = RunSpec {
        init_mode: if args.strict_init {
            InitMode::Strict
        } else {
            InitMode::Project
        },
        tolerances: (!uniform).then_some(&tolerances),
        record_steps: args.trajectory.is_some(),
        estimate: args.estimate.into(),
        ..inputs.spec(&scene, &solver, &formulation, tolerances.rtol)
    };
    let record =
        runner::run(&spec).map_err(|e| Failure::input(format!("{}: {e}", scene.origin)))?;
    if let Some(e) = &record.error {
        // Initial values --strict-init refuses are bad input, not a
        // failure of the solver.
        if e.kind == "inconsistent_initial_values" {
            return Err(Failure::input(format!(
                "{}: {} (--strict-init refuses them; without it they are projected onto the \
                 constraints and reported)",
                scene.origin, e.message
            )));
        }
    }
    let sensitivities = match sensitivity_request(args, &scene) {
        Some((parameters, control)) => {
            let source = match &scene.model {
                ModelSource::Builtin(name) => crate::models::source(name),
                ModelSource::File(path) => crate::models::source(&path.display().to_string()),
            }
            .map_err(|e| Failure::input(format!("{}: {e}", scene.origin)))?;
            let s = runner::sensitivities(&spec, &record, &source.text, &parameters, control)
                .map_err(|e| Failure::input(format!("{}: {e}", scene.origin)))?;
            Some(s)
        }
        None => None,
    };
    let code = if record.status == "ok" { 0 } else { 3 };
    let trajectory_file = match (&args.trajectory, code) {
        (Some(path), 0) => {
            let rows = write_trajectory(path, &record)?;
            Some(TrajectoryFile {
                path: path.display().to_string(),
                rows,
            })
        }
        _ => None,
    };
    let output = Output {
        record: &record,
        formulation_choice: &choice,
        tolerances: (!uniform).then_some(&tolerances),
        trajectory_file,
        sensitivities,
    };
    let out = match args.format {
        Format::Json => {
            serde_json::to_string_pretty(&output)
                .map_err(|e| Failure::input(format!("cannot render the run as JSON: {e}")))?
                + "\n"
        }
        Format::Text => text_output(&output),
    };
    Ok((out, code))
}

/// The sensitivities asked for: `--sensitivities` (with
/// `--no-sensitivity-error-control`), else the scene's `[sensitivities]`.
fn sensitivity_request(args: &RunArgs, scene: &Scene) -> Option<(Vec<String>, bool)> {
    match (&args.sensitivities, &scene.sensitivities) {
        (Some(p), _) => Some((p.clone(), !args.no_sensitivity_error_control)),
        (None, Some(s)) => Some((
            s.parameters.clone(),
            s.error_control && !args.no_sensitivity_error_control,
        )),
        (None, None) => None,
    }
}

/// Write the accepted steps of `record` to `path` as CSV, atomically;
/// the number of rows.
fn write_trajectory(path: &Path, record: &RunRecord) -> Result<usize, Failure> {
    let traj = &record.trajectory;
    let fail = |e: std::io::Error| {
        Failure::input(format!(
            "--trajectory {}: cannot write the file: {e}",
            path.display()
        ))
    };
    if path.is_dir() {
        return Err(fail(std::io::Error::other("it is a directory")));
    }
    crate::sweep::write::atomic_write_with(path, |w| {
        let mut csv = csv::Writer::from_writer(w);
        let header = std::iter::once("t").chain(traj.names.iter().map(String::as_str));
        csv.write_record(header)?;
        for (t, y) in &traj.steps {
            // `{:e}` is the shortest text that reads back to the same f64.
            let row = std::iter::once(format!("{t:e}")).chain(y.iter().map(|v| format!("{v:e}")));
            csv.write_record(row)?;
        }
        csv.flush()
    })
    .map_err(fail)?;
    Ok(traj.steps.len())
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.3e}"))
}

/// Human-readable summary of one run.
pub fn text(r: &RunRecord) -> String {
    let mut s = String::new();
    // A finished run whose answer is wrong says so on its first line.
    let flag = match r.accuracy {
        Some(a) if a.is_warning() => format!(" — {}", a.as_str().to_uppercase()),
        _ => String::new(),
    };
    let _ = writeln!(
        s,
        "{} {}({}) tol {:e}: {}{flag}",
        r.scene, r.solver, r.formulation, r.tol, r.status
    );
    if let Some(e) = &r.error {
        let _ = writeln!(s, "  error: {} ({})", e.message, e.kind);
    }
    if let (Some(a), Some(note)) = (r.accuracy, &r.accuracy_note) {
        let label = if a.is_warning() {
            format!("WARNING: {}", a.as_str().to_uppercase())
        } else {
            a.as_str().to_string()
        };
        let _ = writeln!(s, "  accuracy: {label} ({note})");
    }
    if let Some(init) = &r.init {
        if !init.defaulted.is_empty() {
            let _ = writeln!(
                s,
                "  initial values: not given, started from 0: {}",
                init.defaulted.join(", ")
            );
        }
        if !init.changes.is_empty() {
            let moves: Vec<String> = init
                .changes
                .iter()
                .map(|c| format!("{} {:e} -> {:e}", c.name, c.from, c.to))
                .collect();
            let _ = writeln!(
                s,
                "  initial values: projected onto the constraints: {}",
                moves.join(", ")
            );
        }
    }
    initialisation_table(&mut s, &r.initialisation);
    let _ = writeln!(s, "  t_end {}  tsim {:.3e} s", r.t_end, r.tsim_s);
    let vals: Vec<String> = r
        .final_values
        .0
        .iter()
        .map(|(k, v)| format!("{k} = {v:.12e}"))
        .collect();
    let _ = writeln!(s, "  final: {}", vals.join(", "));
    let _ = writeln!(
        s,
        "  err {}  err_sum {}  err_l2 {}  err_algebraic {}  scd {}",
        opt(r.err),
        opt(r.err_sum),
        opt(r.err_l2),
        opt(r.err_algebraic),
        r.scd.map_or_else(|| "-".into(), |v| format!("{v:.2}"))
    );
    let st = &r.stats;
    let _ = writeln!(
        s,
        "  steps {} rejected {} residual evals {} jacobians {} factorizations {} newton {}",
        st.steps,
        st.rejected,
        st.residual_evals,
        st.jacobian_evals,
        st.factorizations,
        st.newton_iterations
    );
    if let Some(step) = st.propagated_from {
        let _ = writeln!(
            s,
            "  estimate: propagated from accepted step {step} on (the check found the method's \
             own estimate missing the error of its algebraic unknowns; see --estimate)"
        );
    }
    let levels: Vec<String> = (0..r.residuals.levels())
        .map(|k| format!("level{k} {}", opt(r.residuals.level(k))))
        .collect();
    let _ = writeln!(s, "  residuals: {}", levels.join(" "));
    for (k, v) in &r.invariant_drift.0 {
        let _ = writeln!(s, "  drift of {k}: {v:.3e}");
    }
    if let Some(events) = &r.events {
        let _ = writeln!(s, "  events: {}", events.len());
        for e in events {
            let moved = e
                .reset
                .as_ref()
                .map(|r| format!(" (projection moved {:.1e})", r.moved))
                .unwrap_or_default();
            let _ = writeln!(
                s,
                "    t = {:<22} {} {} {}{moved}",
                format!("{:.15e}", e.t),
                e.name,
                e.direction.name(),
                e.action
            );
        }
    }
    s
}

/// The start of every unknown as a short table (given, guess, value used,
/// how far it moved, how), then a warning for each algebraic unknown that
/// started from 0 for want of a guess although its rows contain it
/// nonlinearly.
fn initialisation_table(s: &mut String, values: &[InitValue]) {
    if values.is_empty() {
        return;
    }
    let width = values
        .iter()
        .map(|v| v.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(4);
    let _ = writeln!(
        s,
        "  initialisation:\n    {:<width$}  {:>10}  {:>10}  {:>10}  {:>9}  how",
        "name", "given", "guess", "value", "moved"
    );
    for v in values {
        let num = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |x| format!("{x:.3e}"));
        let _ = writeln!(
            s,
            "    {:<width$}  {:>10}  {:>10}  {:>10}  {:>9}  {}",
            v.name,
            num(v.given),
            num(v.guess),
            num(Some(v.value)),
            format!("{:.2e}", v.moved),
            v.how.as_str()
        );
    }
    for v in values.iter().filter(|v| v.root_chosen_by_default()) {
        let _ = writeln!(
            s,
            "  WARNING: {} started from 0 (no [guess]); the DAE may have other consistent values",
            v.name
        );
    }
}

/// [`text`], with what `dae run` decided: the formulation's choice, the
/// tolerances when they are not one `tol`, the trajectory file.
fn text_output(o: &Output<'_>) -> String {
    let r = o.record;
    let mut s = text(r);
    let mut extra = String::new();
    match o.formulation_choice {
        FormulationChoice::Flag => {}
        FormulationChoice::Policy { preference, .. } => {
            let _ = writeln!(
                extra,
                "  formulation {}: the default for {} (its preference: {}; --formulation to choose)",
                r.formulation,
                r.solver,
                preference.join(" > ")
            );
        }
        FormulationChoice::Scene { .. } => {
            let _ = writeln!(
                extra,
                "  formulation {}: the scene's first that {} takes (none of its preferred ones \
                 would do; --formulation to choose)",
                r.formulation, r.solver
            );
        }
    }
    if let Some(t) = o.tolerances {
        let per = |named: &runner::Named| {
            if named.0.is_empty() {
                String::new()
            } else {
                let v: Vec<String> = named.0.iter().map(|(k, v)| format!("{k} {v:e}")).collect();
                format!(" ({})", v.join(", "))
            }
        };
        let _ = writeln!(
            extra,
            "  tolerances: rtol {:e}{}  atol {:e}{}  (the verdict's tol is the loosest of the \
             differential unknowns')",
            t.rtol,
            per(&t.rtol_of),
            t.atol,
            per(&t.atol_of)
        );
    }
    if let Some(f) = &o.trajectory_file {
        let _ = writeln!(extra, "  trajectory: {} ({} rows)", f.path, f.rows);
    }
    if let Some(sens) = &o.sensitivities {
        let control = if sens.error_control { "in" } else { "out of" };
        let _ = writeln!(
            extra,
            "  sensitivities ({control} the error test; steps {}, jacobians {}, factorizations {}):",
            sens.stats.steps, sens.stats.jacobian_evals, sens.stats.factorizations
        );
        if let Some(e) = &sens.error {
            let _ = writeln!(extra, "    error: {} ({})", e.message, e.kind);
        }
        for (p, finals) in &sens.final_values {
            let v: Vec<String> = finals
                .0
                .iter()
                .map(|(k, v)| format!("d{k}/d{p} = {v:.6e}"))
                .collect();
            let _ = writeln!(extra, "    final: {}", v.join(", "));
        }
    }
    // After the first line (and the error/accuracy lines that belong to it).
    let at = s
        .match_indices('\n')
        .map(|(i, _)| i + 1)
        .find(|&i| !(s[i..].starts_with("  error:") || s[i..].starts_with("  accuracy:")))
        .unwrap_or(s.len());
    s.insert_str(at, &extra);
    s
}

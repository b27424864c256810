//! `dae run [SCENE] [--solver NAME] [--formulation NAME] [--tol T] [--format json|text]`.

use super::Failure;
use crate::inputs::inputs;
use crate::runner::{self, RunRecord, RunSpec};
use crate::scene::Scene;
use dae_solvers::init::InitMode;
use std::fmt::Write;

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
    /// Formulation (default: the scene's first that the solver accepts).
    #[arg(long)]
    pub formulation: Option<String>,
    /// Tolerance, RTOL = ATOL (default 1e-8), in [2.2e-14, 1) like scene
    /// tolerances.
    #[arg(long, default_value_t = 1e-8, allow_negative_numbers = true)]
    pub tol: f64,
    /// Output format.
    #[arg(long, value_enum, default_value = "json")]
    pub format: Format,
    /// Refuse inconsistent initial values instead of projecting them.
    #[arg(long)]
    pub strict_init: bool,
}

/// Check a tolerance given on the command line: the rule of the library
/// and of scene files, [`dae_solvers::options::check_uniform`] (`RTOL =
/// ATOL = tol` in `[100 ε, 1)`).
pub fn check_tol(tol: f64, flag: &str) -> Result<(), Failure> {
    dae_solvers::options::check_uniform(tol).map_err(|issue| {
        Failure::input(format!(
            "{flag} {tol:e}: the tolerance {issue}; tolerances (RTOL = ATOL) must be in {}",
            dae_solvers::options::uniform_range()
        ))
    })
}

/// Run one scene; `Ok((output, exit code))`.
pub fn run(args: &RunArgs) -> Result<(String, i32), Failure> {
    check_tol(args.tol, "--tol")?;
    let scene = Scene::load(&args.scene).map_err(|e| Failure::input(e.to_string()))?;
    let inputs = inputs(&scene).map_err(|e| Failure::input(e.to_string()))?;
    let model = &inputs.model;
    let solver = args
        .solver
        .clone()
        .or_else(|| scene.sweep.solvers.first().cloned())
        .unwrap_or_else(|| "radau5".into());
    let Some(s) = dae_solvers::solver_by_name(&solver) else {
        return Err(Failure::input(format!(
            "--solver {solver}: unknown solver (known: {})",
            dae_solvers::SOLVER_NAMES.join(", ")
        )));
    };
    let formulation = match &args.formulation {
        Some(f) => f.clone(),
        None => scene
            .sweep
            .formulations
            .iter()
            .find(|f| {
                model
                    .formulation(f)
                    .is_ok_and(|sys| s.accepts(sys.info()).is_ok())
            })
            .cloned()
            .ok_or_else(|| {
                Failure::input(format!(
                    "no formulation of the scene is accepted by `{solver}`"
                ))
            })?,
    };
    let spec = RunSpec {
        init_mode: if args.strict_init {
            InitMode::Strict
        } else {
            InitMode::Project
        },
        ..inputs.spec(&scene, &solver, &formulation, args.tol)
    };
    let record =
        runner::run(&spec).map_err(|e| Failure::input(format!("{}: {e}", scene.origin)))?;
    let code = if record.status == "ok" { 0 } else { 3 };
    let out = match args.format {
        Format::Json => serde_json::to_string_pretty(&record).unwrap_or_default() + "\n",
        Format::Text => text(&record),
    };
    Ok((out, code))
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
    let levels: Vec<String> = (0..r.residuals.levels())
        .map(|k| format!("level{k} {}", opt(r.residuals.level(k))))
        .collect();
    let _ = writeln!(s, "  residuals: {}", levels.join(" "));
    for (k, v) in &r.invariant_drift.0 {
        let _ = writeln!(s, "  drift of {k}: {v:.3e}");
    }
    s
}

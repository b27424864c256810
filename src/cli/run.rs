//! `dae run [SCENE] [--solver NAME] [--formulation NAME] [--tol T] [--format json|text]`.

use super::Failure;
use crate::runner::{self, RunError, RunRecord, RunSpec};
use crate::scene::{ReferenceKind, Scene};
use dae_core::system::Model;
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

/// Load a scene's model with the scene's parameters applied and names
/// checked.
pub fn load_model(scene: &Scene) -> Result<Box<dyn Model + Send + Sync>, Failure> {
    let spec = match &scene.model {
        crate::scene::ModelSource::Builtin(name) => name.clone(),
        crate::scene::ModelSource::File(path) => path.display().to_string(),
    };
    let mut model = crate::models::load(&spec).map_err(|e| Failure::input(e.to_string()))?;
    let info = model.model_info().clone();
    let vars: Vec<&str> = info.variables.iter().map(|v| v.name.as_str()).collect();
    let params: Vec<&str> = info.parameters.iter().map(|p| p.name.as_str()).collect();
    scene
        .check_names(&vars, &params)
        .map_err(|e| Failure::input(e.to_string()))?;
    for p in &scene.parameters {
        model.set_parameter(&p.name, p.value).map_err(|e| {
            Failure::input(format!(
                "{}:{}:{}: [parameters] {e}",
                scene.origin, p.line, p.column
            ))
        })?;
    }
    Ok(model)
}

/// A run that could not start, as a bad-input failure: errors about a
/// scene field (an exact reference that cannot be built from the start,
/// say) are prefixed with the field's place in the scene file.
pub fn located(scene: &Scene, e: &RunError) -> Failure {
    match e.field() {
        Some(field) => Failure::input(format!("{}: {e}", scene.locate(field))),
        None => Failure::input(format!("{}: {e}", scene.origin)),
    }
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
    let model = load_model(&scene)?;
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
    let initial = scene.initial_values();
    let reference = match scene.reference {
        ReferenceKind::PendulumExact => {
            Some(runner::pendulum_reference(&*model, &initial).map_err(|e| located(&scene, &e))?)
        }
        ReferenceKind::None => None,
    };
    let spec = RunSpec {
        scene: &scene.name,
        model: &*model,
        initial: &initial,
        t0: scene.time.start,
        t_end: scene.time.end,
        check: &scene.time.checks,
        reference: reference.as_ref(),
        solver: &solver,
        formulation: &formulation,
        tol: args.tol,
        init_mode: if args.strict_init {
            InitMode::Strict
        } else {
            InitMode::Project
        },
        samples: &[],
        repeats: 1,
        max_steps: None,
    };
    let record = runner::run(&spec).map_err(|e| located(&scene, &e))?;
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
        "  err {}  err_sum {}  err_lambda {}",
        opt(r.err),
        opt(r.err_sum),
        opt(r.err_lambda)
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
    let _ = writeln!(
        s,
        "  residuals: level0 {} level1 {} level2 {}",
        opt(r.residuals.level0),
        opt(r.residuals.level1),
        opt(r.residuals.level2)
    );
    for (k, v) in &r.invariant_drift.0 {
        let _ = writeln!(s, "  drift of {k}: {v:.3e}");
    }
    s
}

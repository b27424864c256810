//! One way from a scene to the inputs of its runs — the model with the
//! scene's parameters, the initial values, the reference — shared by
//! `dae run`, `dae sweep` and the library.
//!
//! ```
//! use dae::inputs::inputs;
//! use dae::scene::Scene;
//!
//! let scene = Scene::builtin("s01").unwrap();
//! let inputs = inputs(&scene).unwrap();
//! assert_eq!(inputs.model.parameter("g"), Some(13.7503716373294544));
//! assert_eq!(inputs.initial[0], ("x".to_string(), 1.0));
//! let reference = inputs.reference.unwrap();
//! assert_eq!((reference.kind(), reference.names().len()), ("exact", 5));
//! ```

use crate::models::{self, ModelError};
use crate::reference::data::{Reference, UseError};
use crate::reference::{PendulumExact, ReferenceError};
use crate::runner::{Named, RunSpec, RunTolerances};
use crate::scene::{Location, ReferenceSpec, Scene, SceneError, TolSpec};
use dae_core::system::{Model, ParameterError};
use dae_solvers::core::policy::preferred_formulations;
use dae_solvers::init::InitMode;
use dae_solvers::Solver;
use serde::Serialize;

/// What every run of a scene shares.
pub struct Inputs {
    /// The model, the scene's parameters set.
    pub model: Box<dyn Model + Send + Sync>,
    /// The scene's initial values, by name.
    pub initial: Vec<(String, f64)>,
    /// The scene's guesses (`[guess]`), by name.
    pub guess: Vec<(String, f64)>,
    /// The reference, checked against the model and the horizon.
    pub reference: Option<Reference>,
}

impl Inputs {
    /// The run of `solver` on `formulation` at `tol` over the scene's
    /// horizon, checked at its check times against its reference, with the
    /// defaults of `dae run`: inconsistent initial values projected, no
    /// extra samples, one integration, the library's step bound. Change
    /// any of them with struct update syntax:
    ///
    /// ```
    /// use dae::inputs::inputs;
    /// use dae::runner::{run, RunSpec};
    /// use dae::scene::Scene;
    ///
    /// let scene = Scene::builtin("s01").unwrap();
    /// let inputs = inputs(&scene).unwrap();
    /// let record = run(&RunSpec { repeats: 3, ..inputs.spec(&scene, "radau5", "ggl1", 1e-6) }).unwrap();
    /// assert_eq!(record.status, "ok");
    /// assert!(record.err.unwrap() < 1e-4);
    /// ```
    pub fn spec<'a>(
        &'a self,
        scene: &'a Scene,
        solver: &'a str,
        formulation: &'a str,
        tol: f64,
    ) -> RunSpec<'a> {
        RunSpec {
            scene: &scene.name,
            model: &*self.model,
            initial: &self.initial,
            guess: &self.guess,
            t0: scene.time.start,
            t_end: scene.time.end,
            check: &scene.time.checks,
            reference: self.reference.as_ref(),
            solver,
            formulation,
            tol,
            tolerances: None,
            record_steps: false,
            init_mode: InitMode::Project,
            samples: &[],
            repeats: 1,
            max_steps: None,
            events: &scene.events,
            estimate: Default::default(),
        }
    }
}

/// The tolerance of `dae run` when neither the command line nor the scene
/// gives one: `RTOL = ATOL = 1e-8`.
pub const DEFAULT_TOL: f64 = 1e-8;

/// The tolerances of `dae run` on `scene` with the command line's `rtol`
/// and `atol` (`--tol T` gives both). For each unknown and each kind the
/// value is, first found: the scene's per-unknown entry (`[tolerance] atol
/// = { lambda = 1e-6 }`), the command line, the scene's number, then
/// [`DEFAULT_TOL`]. A per-unknown entry is the most specific statement, so
/// it stays when the command line changes the others.
///
/// ```
/// use dae::inputs::run_tolerances;
/// use dae::scene::Scene;
///
/// let text = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\nend = 1\n\
///             [tolerance]\nrtol = 1e-6\natol = { lambda = 1e-4 }\n";
/// let scene = Scene::parse(text, "t.toml", None).unwrap();
/// let t = run_tolerances(&scene, None, None);
/// assert_eq!((t.rtol, t.atol, t.atol_for("lambda")), (1e-6, 1e-8, 1e-4));
/// let t = run_tolerances(&scene, Some(1e-9), Some(1e-12));
/// assert_eq!((t.rtol, t.atol, t.atol_for("lambda")), (1e-9, 1e-12, 1e-4));
/// ```
pub fn run_tolerances(scene: &Scene, rtol: Option<f64>, atol: Option<f64>) -> RunTolerances {
    let resolve = |flag: Option<f64>, spec: &Option<TolSpec>| {
        let (uniform, named) = match spec {
            Some(TolSpec::Uniform(v)) => (Some(*v), Named::default()),
            Some(TolSpec::PerUnknown(list)) => (
                None,
                Named(list.iter().map(|e| (e.name.clone(), e.value)).collect()),
            ),
            None => (None, Named::default()),
        };
        (flag.or(uniform).unwrap_or(DEFAULT_TOL), named)
    };
    let (rtol, rtol_of) = resolve(rtol, &scene.tolerance.rtol);
    let (atol, atol_of) = resolve(atol, &scene.tolerance.atol);
    RunTolerances {
        rtol,
        atol,
        rtol_of,
        atol_of,
    }
}

/// How `dae run` came to integrate the formulation it did (the `dae run`
/// JSON's `formulation_choice`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "by", rename_all = "snake_case")]
pub enum FormulationChoice {
    /// Named with `--formulation`.
    Flag,
    /// The first of the solver's preferred formulations
    /// ([`preferred_formulations`]) that the scene lists, the model
    /// provides and the solver accepts.
    Policy {
        /// The solver's order, best first.
        preference: Vec<&'static str>,
        /// The better ones passed over, and why.
        skipped: Vec<Skipped>,
    },
    /// None of the preferred ones would do: the scene's first formulation
    /// (in its `[sweep] formulations` order) that the model provides and
    /// the solver accepts.
    Scene {
        /// The preferred ones passed over, and why.
        skipped: Vec<Skipped>,
    },
}

/// A formulation passed over by the default choice.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Skipped {
    /// Its name.
    pub formulation: String,
    /// Why: not in the scene's list, not provided by the model, or refused
    /// by the solver.
    pub why: String,
}

/// No formulation of the scene can be integrated by the solver.
#[derive(Debug, thiserror::Error)]
#[error(
    "no formulation of the scene can be integrated by `{solver}`: {}",
    skipped.iter().map(|s| format!("{} ({})", s.formulation, s.why)).collect::<Vec<_>>().join("; ")
)]
pub struct NoFormulation {
    /// The solver.
    pub solver: String,
    /// Every formulation tried, and why it would not do.
    pub skipped: Vec<Skipped>,
}

/// The formulation `dae run` integrates with `solver` when none is named:
/// the first of the solver's [`preferred_formulations`] that the scene's
/// `[sweep] formulations` list (every formulation unless the scene
/// restricts them), the model provides and the solver accepts; failing
/// that, the first in the scene's order that the model provides and the
/// solver accepts. The order is decided, with the measurements behind it,
/// in [`preferred_formulations`].
///
/// ```
/// use dae::inputs::{choose_formulation, inputs, FormulationChoice};
/// use dae::scene::Scene;
///
/// let scene = Scene::builtin("s01").unwrap();
/// let inputs = inputs(&scene).unwrap();
/// let radau5 = dae::dae_solvers::solver_by_name("radau5").unwrap();
/// let (name, why) = choose_formulation(&*inputs.model, &scene, &*radau5).unwrap();
/// assert_eq!(name, "ggl1");
/// assert!(matches!(why, FormulationChoice::Policy { .. }));
/// ```
pub fn choose_formulation(
    model: &dyn Model,
    scene: &Scene,
    solver: &dyn Solver,
) -> Result<(String, FormulationChoice), NoFormulation> {
    let preference: Vec<&'static str> = preferred_formulations(solver.name())
        .unwrap_or_default()
        .to_vec();
    let mut skipped = Vec::new();
    let usable = |f: &str| -> Result<(), String> {
        let sys = model.formulation(f).map_err(|e| e.to_string())?;
        solver.accepts(sys.info()).map_err(|e| e.to_string())
    };
    for f in &preference {
        if !scene.sweep.formulations.iter().any(|s| s == f) {
            skipped.push(Skipped {
                formulation: f.to_string(),
                why: "not in the scene's [sweep] formulations".into(),
            });
            continue;
        }
        match usable(f) {
            Ok(()) => {
                return Ok((
                    f.to_string(),
                    FormulationChoice::Policy {
                        preference,
                        skipped,
                    },
                ))
            }
            Err(why) => skipped.push(Skipped {
                formulation: f.to_string(),
                why,
            }),
        }
    }
    for f in &scene.sweep.formulations {
        if preference.contains(&f.as_str()) {
            continue;
        }
        match usable(f) {
            Ok(()) => return Ok((f.clone(), FormulationChoice::Scene { skipped })),
            Err(why) => skipped.push(Skipped {
                formulation: f.clone(),
                why,
            }),
        }
    }
    Err(NoFormulation {
        solver: solver.name().to_string(),
        skipped,
    })
}

/// Why a scene's inputs could not be built.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The model could not be loaded.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A name in `[initial]` or `[parameters]` the model does not have.
    #[error(transparent)]
    Names(#[from] SceneError),
    /// A parameter value the model refuses.
    #[error("{at}: [parameters] {source}")]
    Parameter {
        /// Where the value is.
        at: Location,
        /// Why it was refused.
        source: ParameterError,
    },
    /// The reference cannot serve this model and scene.
    #[error("{at}: {message}")]
    Reference {
        /// The scene field to blame.
        at: Location,
        /// What is wrong.
        message: String,
    },
}

/// Build the inputs of `scene`'s runs.
pub fn inputs(scene: &Scene) -> Result<Inputs, InputError> {
    let model = model(scene)?;
    let info = model.model_info().clone();
    let vars: Vec<&str> = info.variables.iter().map(|v| v.name.as_str()).collect();
    let initial = scene.initial_values();
    let reference = match &scene.reference {
        ReferenceSpec::None => None,
        ReferenceSpec::Exact { .. } => Some(Reference::pendulum(
            pendulum(scene, &*model, &initial)?,
            scene.time.start,
        )),
        ReferenceSpec::Values { table, scaling } => {
            Some(Reference::values(table.clone(), scaling.clone()))
        }
        ReferenceSpec::Trajectory { table, scaling } => {
            Some(Reference::trajectory(table.clone(), scaling.clone()))
        }
    };
    if let Some(r) = &reference {
        r.check_use(&vars, scene.time.start, scene.time.end, &scene.time.checks)
            .map_err(|e| {
                let field = match e {
                    UseError::Undefined { .. } => "time.end",
                    _ => "reference.kind",
                };
                InputError::Reference {
                    at: scene.locate(field),
                    message: format!("reference: {e}"),
                }
            })?;
    }
    Ok(Inputs {
        model,
        initial,
        guess: scene.guess_values(),
        reference,
    })
}

/// The model of `scene`'s runs alone, its names checked and the scene's
/// parameters set: what [`inputs`] builds first, for a caller that needs
/// one more model instance (a sweep's worker thread).
pub fn model(scene: &Scene) -> Result<Box<dyn Model + Send + Sync>, InputError> {
    let mut model = models::load_source(&scene.model)?;
    let info = model.model_info();
    let vars: Vec<&str> = info.variables.iter().map(|v| v.name.as_str()).collect();
    let params: Vec<&str> = info.parameters.iter().map(|p| p.name.as_str()).collect();
    scene.check_names(&vars, &params)?;
    scene.check_events(&info.events, &vars)?;
    for p in &scene.parameters {
        model
            .set_parameter(&p.name, p.value)
            .map_err(|source| InputError::Parameter {
                at: Location {
                    origin: scene.origin.clone(),
                    line: p.line,
                    column: p.column,
                },
                source,
            })?;
    }
    Ok(model)
}

/// The pendulum's closed form from the scene's start and the model's
/// parameters `l`, `g`, `m`; a refusal blames the scene field it comes
/// from.
fn pendulum(
    scene: &Scene,
    model: &dyn Model,
    initial: &[(String, f64)],
) -> Result<PendulumExact, InputError> {
    let refuse = |field: &str, message: String| InputError::Reference {
        at: scene.locate(field),
        message,
    };
    let info = model.model_info();
    if let Some(n) = PendulumExact::COMPONENTS
        .iter()
        .find(|n| !info.variables.iter().any(|v| v.name == **n))
    {
        return Err(refuse(
            "reference.kind",
            format!(
                "reference: the pendulum's closed form needs unknowns {}; model `{}` has no `{n}`",
                PendulumExact::COMPONENTS.join(", "),
                info.name
            ),
        ));
    }
    let param = |n: &str| {
        model.parameter(n).ok_or_else(|| {
            refuse(
                "reference.kind",
                format!("reference: the pendulum's closed form needs parameter `{n}`"),
            )
        })
    };
    let value = |n: &str| {
        initial
            .iter()
            .find(|(k, _)| k == n)
            .map_or(0.0, |(_, v)| *v)
    };
    let exact = PendulumExact::from_state(
        value("x"),
        value("y"),
        value("v"),
        value("w"),
        param("l")?,
        param("g")?,
        param("m")?,
    )
    .map_err(|e| pendulum_refusal(scene, &e))?;
    // The closed form is NaN beyond 2⁵¹ periods: checked at the furthest
    // time of the horizon.
    if exact
        .state(scene.time.end - scene.time.start)
        .iter()
        .any(|v| !v.is_finite())
    {
        let e = ReferenceError::PhaseLost {
            t: scene.time.end - scene.time.start,
        };
        return Err(pendulum_refusal(scene, &e));
    }
    Ok(exact)
}

/// A refusal of the pendulum's closed form, at the scene field (`initial.x`,
/// `parameters.g`, `time.end`) of the input it blames.
fn pendulum_refusal(scene: &Scene, e: &ReferenceError) -> InputError {
    let field = match e.input() {
        "theta0" | "x0" => "initial.x".to_string(),
        "y0" => "initial.y".into(),
        "v0" => "initial.v".into(),
        "w0" => "initial.w".into(),
        "t" => "time.end".into(),
        p => format!("parameters.{p}"),
    };
    InputError::Reference {
        at: scene.locate(&field),
        message: format!("`{field}`: pendulum-exact reference: {e}"),
    }
}

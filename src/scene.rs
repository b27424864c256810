//! Scene files: what to integrate, how long, what to compare against, and
//! which solvers × formulations × tolerances to sweep.
//!
//! A scene is a small TOML file:
//!
//! ```toml
//! name = "S01"
//! model = "pendulum"          # built-in name, or a path to a .dae file
//! [parameters]                # optional overrides of the model defaults
//! g = 13.7503716373294544
//! [initial]                   # differential unknowns; algebraic ones are computed
//! x = 1.0
//! y = 0.0
//! v = 0.0
//! w = 0.0
//! [guess]                     # optional: where the computation of an unknown
//! lambda = 0.0                # not in [initial] starts (see below)
//! [time]
//! end = 20.0                  # start = 0.0 unless given
//! check = [20.0]              # or: check_every = 2.0; neither: check at end
//! [reference]
//! kind = "exact"              # the pendulum's closed form; see below
//! [sweep]                     # optional; defaults: every solver, formulation,
//! solvers = ["radau5", "bdf", "odradau", "odbdf", "mebdf", "idec", "gauss"] # and the tolerances 1e-5 … 1e-12
//! formulations = ["ori2", "rcd1", "rcd0", "ovd1", "ovd0", "ggl1", "psi1", "psi0", "mex0"]
//! tolerances = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
//! max_steps = 2000000         # optional: steps (accepted + rejected) per run
//! [tolerance]                 # optional, `dae run` only (the sweep takes its list)
//! rtol = 1e-8                 # every unknown; default 1e-8
//! atol = { x = 1e-10, lambda = 1e-6 }   # or per unknown (the others: 1e-8)
//! ```
//!
//! # Initial values and guesses
//!
//! `[initial]` fixes values: the differential unknowns' (positions,
//! velocities, …) are kept when they satisfy the constraints and otherwise
//! projected onto them with the least change (reported), or refused with
//! `--strict-init`. Algebraic unknowns (multipliers) are computed from the
//! constraints by Newton's method, starting from 0. `[guess]` gives, for
//! any unknown `[initial]` does not name, only where that computation
//! starts: where the constraints determine an unknown nonlinearly they may
//! have several solutions (a multiplier entering as `z²`), and the guess
//! chooses the one nearest to it. `dae run` reports for every unknown the
//! value given, the guess, the value used, how far it moved and how it came
//! about (`fixed`, `guessed`, `defaulted`, `projected`), and warns when an
//! unknown that enters nonlinearly started from 0 for want of a guess. A
//! name in `[guess]` that is not an unknown of the model, or that
//! `[initial]` also gives, is an error with its line.
//!
//! # Tolerances of `dae run`
//!
//! `[tolerance]` gives `rtol` and `atol`, each one number for every unknown
//! or a table `{ name = value, … }` by unknown name. For each unknown and
//! each kind the value is, first found: its entry in the scene's table,
//! the command line's `--rtol`/`--atol` (`--tol T` is both), the scene's
//! number, `1e-8`. Relative tolerances are `0` or in `[100 ε, 1)`,
//! absolute ones finite and not negative; a name that is not an unknown of
//! the model is an error with its line (and a suggestion when one is close).
//! `dae sweep` ignores the section: it sweeps `[sweep] tolerances`, each
//! `RTOL = ATOL`.
//!
//! Everything that can be checked without the model is checked when the
//! scene is parsed, and every problem is a [`SceneError`] that names the
//! field and its place in the file as `file:line:column`. Names of
//! variables and parameters need the model: [`Scene::check_names`].
//!
//! A model path is relative to the directory of the scene file; the
//! resolved path is stored in [`ModelSource::File`].
//!
//! # References
//!
//! `[reference]` says what the runs are compared against
//! ([`crate::reference::data`]); without it, nothing (`kind = "none"`):
//!
//! ```toml
//! [reference]
//! kind = "exact"                # a built-in closed form: closed_form = "pendulum"
//! # kind = "values"             # published values at given times, errors there:
//! # file = "andrews_ref.csv"    #   a CSV `t,<unknown>,…` beside the scene, or inline:
//! # times = [0.03]
//! # values = { x1 = [15.81], x2 = [-15.7] }
//! # kind = "trajectory"         # a sampled solution (CSV), interpolated at the checks
//! # columns = ["x1", "x2"]      # the columns to compare (default: all)
//! # scaling = "relative"        # absolute (default) or relative, for every
//! #                             # component, or per component: { x1 = "relative" }
//! ```
//!
//! `kind = "pendulum-exact"` is the older name of `kind = "exact"` and still
//! accepted.
//!
//! ```
//! use dae::scene::{ModelSource, Scene};
//!
//! let s = Scene::builtin("s02").unwrap();
//! assert_eq!(s.model, ModelSource::Builtin("pendulum".into()));
//! assert_eq!(s.time.checks.len(), 1000);
//! assert_eq!(s.parameter("g"), Some(13.7503716373294544));
//! assert_eq!(s.sweep.tolerances.len(), 8);
//! ```

use crate::reference::data::{Scaling, Table, SCALINGS};
use serde::de::{Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Solver names a scene may sweep ([`dae_solvers::SOLVER_NAMES`]).
pub const KNOWN_SOLVERS: &[&str] = &dae_solvers::SOLVER_NAMES;

/// Formulation names a scene may sweep
/// ([`dae_core::system::FORMULATION_NAMES`], the paper's eight).
pub const KNOWN_FORMULATIONS: &[&str] = &dae_core::system::FORMULATION_NAMES;

/// Tolerances swept when a scene gives none: `RTOL = ATOL = 10⁻ⁱ`,
/// `i = 5, …, 12` (paper §2.2).
pub const DEFAULT_TOLERANCES: [f64; 8] = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12];

/// Names of the built-in scenes.
pub const BUILTIN_SCENES: [&str; 2] = ["s01", "s02"];

/// Upper bound on the number of check times a scene may ask for.
pub const MAX_CHECK_TIMES: usize = 10_000_000;

/// Largest magnitude of a number in `[parameters]`, `[initial]` and
/// `[time]`: `1e150`, so that squares and pairwise products of scene values
/// (`x² + y²`, `L²`, `m·g·y`, `end − start`) stay finite. A larger value is
/// refused naming its field ([`SceneError::TooLarge`]); it could only
/// overflow somewhere downstream (an `x = 1e308` start once hung the exact
/// reference).
pub const MAX_ABS_VALUE: f64 = 1e150;

const S01_TOML: &str = include_str!("../scenes/s01.toml");
const S02_TOML: &str = include_str!("../scenes/s02.toml");

/// Reference kinds a scene may name (`pendulum-exact` is also accepted, as
/// the older name of `exact`).
pub const REFERENCE_KINDS: [&str; 4] = ["exact", "values", "trajectory", "none"];

/// Largest reference CSV file a scene may name (256 MiB).
pub const MAX_REFERENCE_BYTES: u64 = 256 << 20;

/// Closed forms a reference of kind `exact` may name.
pub const CLOSED_FORMS: [&str; 1] = ["pendulum"];

pub use dae_core::names::did_you_mean;

/// `; did you mean `NAME`?` for an error message, or nothing.
fn hint<S: AsRef<str>>(name: &str, known: &[S]) -> String {
    let known: Vec<&str> = known.iter().map(AsRef::as_ref).collect();
    did_you_mean(name, &known).map_or_else(String::new, |s| format!("; did you mean `{s}`?"))
}

/// A place in a scene: the file (or `<built-in NAME>`, or the origin given to
/// [`Scene::parse`]) and a 1-based line and column (in characters).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Location {
    /// File path or other origin of the text.
    pub origin: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, counted in characters.
    pub column: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.origin, self.line, self.column)
    }
}

/// Everything that can be wrong with a scene. Each variant that stems from
/// the text carries its [`Location`]; the messages read
/// `file:line:column: ` followed by the field (as `section.key`) and the
/// problem.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene file `{}`: {source}", path.display())]
    Io {
        /// The path as given or resolved.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Neither an existing file nor a built-in scene.
    #[error(
        "no scene file `{}` and no built-in scene of that name (built-in scenes: {})",
        path.display(),
        BUILTIN_SCENES.join(", ")
    )]
    NotFound {
        /// The argument given.
        path: PathBuf,
    },
    /// Not valid TOML.
    #[error("{at}: invalid TOML: {message}")]
    Syntax {
        /// Where the parser stopped.
        at: Location,
        /// The parser's message.
        message: String,
    },
    /// A value of the wrong type (a string for a number, …).
    #[error("{at}: `{field}`: {message}")]
    InvalidType {
        /// Where.
        at: Location,
        /// `section.key`.
        field: String,
        /// What was expected and found.
        message: String,
    },
    /// A required field is absent.
    #[error("{at}: missing field `{field}`")]
    MissingField {
        /// The enclosing table (line 1 for top-level fields).
        at: Location,
        /// `section.key`.
        field: String,
    },
    /// A field the scene format does not have (often a typo).
    #[error("{at}: unknown field `{field}`, expected one of: {expected}")]
    UnknownField {
        /// Where.
        at: Location,
        /// `section.key`.
        field: String,
        /// The fields allowed there.
        expected: String,
    },
    /// NaN or infinite where a finite number is needed.
    #[error("{at}: `{field}` = {value} is not a finite number")]
    NotFinite {
        /// Where.
        at: Location,
        /// `section.key`.
        field: String,
        /// The value.
        value: f64,
    },
    /// A literal that is not zero but rounds to 0 in double precision
    /// (`1e-400`), refused like one that rounds to infinity.
    #[error(
        "{at}: `{field}` = {literal} underflows to 0 in double precision (the smallest positive \
         value is 4.9e-324); write 0 if 0 is meant"
    )]
    Underflow {
        /// Where.
        at: Location,
        /// `section.key`.
        field: String,
        /// The literal as written.
        literal: String,
    },
    /// A finite number too large to be used ([`MAX_ABS_VALUE`]).
    #[error(
        "{at}: `{field}` = {value:e} is too large: scene values must have magnitude at most {max:e} so that \
         their squares and products stay finite"
    )]
    TooLarge {
        /// Where.
        at: Location,
        /// `section.key`.
        field: String,
        /// The value.
        value: f64,
        /// [`MAX_ABS_VALUE`].
        max: f64,
    },
    /// A value that is well-typed but unusable.
    #[error("{at}: `{field}` {reason}")]
    InvalidValue {
        /// Where.
        at: Location,
        /// `section.key`.
        field: String,
        /// Why.
        reason: String,
    },
    /// A tolerance outside the library's rule
    /// ([`dae_solvers::options::check_uniform`]): NaN, infinite, not
    /// positive, below `100 ε` or not below 1.
    #[error(
        "{at}: `sweep.tolerances`: tolerance {value:e} {issue}; tolerances (RTOL = ATOL) must be in {}",
        crate::runner::tolerance_range()
    )]
    InvalidTolerance {
        /// Where.
        at: Location,
        /// The value.
        value: f64,
        /// What is wrong with it.
        issue: dae_solvers::options::ToleranceIssue,
    },
    /// `time.end` not after `time.start`.
    #[error("{at}: `time.end` = {end} must be greater than `time.start` = {start}")]
    EmptyHorizon {
        /// Where `end` is.
        at: Location,
        /// Start time.
        start: f64,
        /// End time.
        end: f64,
    },
    /// A check time outside `[start, end]`.
    #[error("{at}: `time.check`: check time {time} is outside the horizon [{start}, {end}]")]
    CheckOutsideHorizon {
        /// Where.
        at: Location,
        /// The check time.
        time: f64,
        /// Start time.
        start: f64,
        /// End time.
        end: f64,
    },
    /// Check times must increase strictly.
    #[error("{at}: `time.check`: check time {time} does not come after {previous}; list check times in increasing order")]
    CheckNotIncreasing {
        /// Where.
        at: Location,
        /// The check time.
        time: f64,
        /// The one before it.
        previous: f64,
    },
    /// A reference table (`reference.file`, or `reference.times` with
    /// `reference.values`) that cannot be read or is malformed.
    #[error("{at}: `{field}`: {reason}")]
    ReferenceTable {
        /// Where.
        at: Location,
        /// The field (`reference.file`, `reference.values`, …).
        field: String,
        /// What is wrong (with the CSV line where there is one).
        reason: String,
    },
    /// Check times that are all the start: a verdict there verifies
    /// nothing (the solution is the initial values).
    #[error(
        "{at}: `time.check`: the only check time is the start {start}, where the solution is the \
         initial values and a verdict verifies nothing; give a check time after it, or leave \
         `check` out to check at the end"
    )]
    VacuousChecks {
        /// Where (the list).
        at: Location,
        /// The start of the horizon.
        start: f64,
    },
    /// Both `check` and `check_every`.
    #[error("{at}: `time.check` and `time.check_every` are exclusive; give one of them")]
    CheckConflict {
        /// Where the second one is.
        at: Location,
    },
    /// More check times than [`MAX_CHECK_TIMES`].
    #[error("{at}: `time.check_every` gives {count} check times, more than the limit {max}")]
    TooManyCheckTimes {
        /// Where.
        at: Location,
        /// How many it would give (saturated).
        count: f64,
        /// [`MAX_CHECK_TIMES`].
        max: usize,
    },
    /// `reference.kind` not one of [`REFERENCE_KINDS`].
    #[error("{at}: `reference.kind` = \"{kind}\" is unknown (known: {})", REFERENCE_KINDS.join(", "))]
    UnknownReference {
        /// Where.
        at: Location,
        /// The kind given.
        kind: String,
    },
    /// A solver not in [`KNOWN_SOLVERS`].
    #[error(
        "{at}: `sweep.solvers`: unknown solver \"{name}\"{} (known: {})",
        hint(name, KNOWN_SOLVERS),
        KNOWN_SOLVERS.join(", ")
    )]
    UnknownSolver {
        /// Where.
        at: Location,
        /// The name given.
        name: String,
    },
    /// A formulation not in [`KNOWN_FORMULATIONS`].
    #[error(
        "{at}: `sweep.formulations`: unknown formulation \"{name}\"{} (known: {})",
        hint(name, KNOWN_FORMULATIONS),
        KNOWN_FORMULATIONS.join(", ")
    )]
    UnknownFormulation {
        /// Where.
        at: Location,
        /// The name given.
        name: String,
    },
    /// The same name twice in a sweep list.
    #[error("{at}: `{field}`: \"{name}\" is listed twice")]
    Duplicate {
        /// Where the second one is.
        at: Location,
        /// `sweep.solvers`, …
        field: String,
        /// The repeated entry.
        name: String,
    },
    /// The model a scene names is a directory, not a model file.
    #[error("{at}: `model`: `{}` is a directory, not a model file", path.display())]
    ModelIsDirectory {
        /// Where.
        at: Location,
        /// The resolved path.
        path: PathBuf,
    },
    /// The model a scene names is neither a built-in model nor a file.
    #[error(
        "{at}: `model`: \"{name}\" is neither a built-in model (built-in: {}) nor a model file \
         (a path to a .dae file, relative to the scene file)",
        crate::models::BUILTIN_MODELS.join(", ")
    )]
    UnknownModel {
        /// Where.
        at: Location,
        /// The value given.
        name: String,
    },
    /// The model file a scene names does not exist.
    #[error("{at}: `model`: model file `{}` does not exist", path.display())]
    ModelNotFound {
        /// Where.
        at: Location,
        /// The resolved path.
        path: PathBuf,
    },
    /// An `[initial]`, `[guess]` or per-unknown `[tolerance]` entry the
    /// model does not have.
    #[error(
        "{at}: `{section}.{name}`: the model has no variable `{name}`{} (variables: {})",
        hint(name, known),
        known.join(", ")
    )]
    UnknownVariable {
        /// Where.
        at: Location,
        /// `initial`, `guess`, `tolerance.rtol` or `tolerance.atol`.
        section: &'static str,
        /// The name given.
        name: String,
        /// The model's variables.
        known: Vec<String>,
    },
    /// An `[events.NAME]` table for an event the model does not have.
    #[error(
        "{at}: `events.{name}`: the model has no event `{name}`{} ({})",
        hint(name, known),
        if known.is_empty() { "it has no `events { … }` section".to_string() } else { format!("events: {}", known.join(", ")) }
    )]
    UnknownEvent {
        /// Where.
        at: Location,
        /// The name given.
        name: String,
        /// The model's events.
        known: Vec<String>,
    },
    /// A `[parameters]` entry the model does not have.
    #[error(
        "{at}: `parameters.{name}`: the model has no parameter `{name}`{} (parameters: {})",
        hint(name, known),
        known.join(", ")
    )]
    UnknownParameter {
        /// Where.
        at: Location,
        /// The name given.
        name: String,
        /// The model's parameters.
        known: Vec<String>,
    },
    /// A `[tolerance]` value outside the library's rule: a relative
    /// tolerance `0` or in `[100 ε, 1)`, an absolute one finite and not
    /// negative.
    #[error("{at}: `{field}` = {value:e} {issue}")]
    InvalidToleranceValue {
        /// Where.
        at: Location,
        /// `tolerance.rtol`, `tolerance.atol.x`, …
        field: String,
        /// The value.
        value: f64,
        /// What is wrong with it.
        issue: dae_solvers::options::ToleranceIssue,
    },
}

impl SceneError {
    /// For a name that is not known (a solver, formulation, variable or
    /// parameter), the known name closest to it ([`did_you_mean`]), which
    /// the message suggests.
    ///
    /// ```
    /// use dae::scene::Scene;
    ///
    /// let text = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\nend = 1\n\
    ///             [sweep]\nsolvers = [\"radua5\"]\n";
    /// let err = Scene::parse(text, "t.toml", None).unwrap_err();
    /// assert_eq!(err.suggestion().as_deref(), Some("radau5"));
    /// assert!(err.to_string().contains("did you mean `radau5`?"));
    /// ```
    pub fn suggestion(&self) -> Option<String> {
        let (name, known): (&str, Vec<&str>) = match self {
            SceneError::UnknownSolver { name, .. } => (name, KNOWN_SOLVERS.to_vec()),
            SceneError::UnknownFormulation { name, .. } => (name, KNOWN_FORMULATIONS.to_vec()),
            SceneError::UnknownVariable { name, known, .. }
            | SceneError::UnknownParameter { name, known, .. } => {
                (name, known.iter().map(String::as_str).collect())
            }
            _ => return None,
        };
        did_you_mean(name, &known).map(str::to_string)
    }
}

/// Which model a scene integrates.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub enum ModelSource {
    /// A model compiled into the tool, by name (e.g. `pendulum`).
    Builtin(String),
    /// A `.dae` model file, resolved against the scene file's directory.
    File(PathBuf),
}

/// `[sensitivities]`: `parameters = ["g", "l"]` (base parameters of the
/// model, checked when the sensitivities are built) and `error_control`
/// (default `true`: the sensitivities in the error test, see
/// `dae_core::sensitivity::SensitivitySystem::set_error_control`).
///
/// ```
/// let text = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\nend = 1\n\
///             [sensitivities]\nparameters = [\"g\", \"l\"]\n";
/// let s = dae::scene::Scene::parse(text, "t.toml", None).unwrap();
/// let sens = s.sensitivities.unwrap();
/// assert_eq!(sens.parameters, ["g", "l"]);
/// assert!(sens.error_control);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensitivitySpec {
    /// The parameters, in order.
    pub parameters: Vec<String>,
    /// Whether the sensitivities are in the error test.
    pub error_control: bool,
}

/// `name = value` from `[parameters]` or `[initial]`, with its place.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedValue {
    /// The key.
    pub name: String,
    /// The value (finite).
    pub value: f64,
    /// 1-based line of the key.
    pub line: usize,
    /// 1-based column of the key.
    pub column: usize,
}

/// How the check times were specified.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum CheckRule {
    /// Explicit `check = [...]`.
    List,
    /// `check_every = step`.
    Every(f64),
    /// Neither: the end of the horizon only.
    EndOnly,
}

/// The horizon and the check times.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimeSpec {
    /// Initial time (default 0).
    pub start: f64,
    /// Final time (`> start`).
    pub end: f64,
    /// Check times: strictly increasing, within `[start, end]`, not empty.
    pub checks: Vec<f64>,
    /// How they were given.
    pub rule: CheckRule,
}

/// What the numerical solution is compared against, as the scene gives it
/// (built into a [`crate::reference::data::Reference`] with the model, by
/// [`crate::inputs`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ReferenceSpec {
    /// A built-in closed form ([`CLOSED_FORMS`]), from the scene's start and
    /// parameters.
    Exact {
        /// Its name (`pendulum`).
        closed_form: String,
    },
    /// Published values at their times.
    Values {
        /// The values.
        table: Table,
        /// Per column of the table.
        scaling: Vec<Scaling>,
    },
    /// A sampled solution, interpolated at the check times.
    Trajectory {
        /// The samples.
        table: Table,
        /// Per column of the table.
        scaling: Vec<Scaling>,
    },
    /// No reference: errors are not computed.
    None,
}

impl ReferenceSpec {
    /// The kind, as scene files name it.
    pub fn as_str(&self) -> &'static str {
        match self {
            ReferenceSpec::Exact { .. } => "exact",
            ReferenceSpec::Values { .. } => "values",
            ReferenceSpec::Trajectory { .. } => "trajectory",
            ReferenceSpec::None => "none",
        }
    }
}

/// What `dae sweep` runs: every solver × formulation × tolerance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sweep {
    /// Solver names, each in [`KNOWN_SOLVERS`].
    pub solvers: Vec<String>,
    /// Formulation names, each in [`KNOWN_FORMULATIONS`].
    pub formulations: Vec<String>,
    /// Tolerances (`RTOL = ATOL`), each in `[100 ε, 1)`
    /// ([`dae_solvers::options::check_uniform`]).
    pub tolerances: Vec<f64>,
    /// Steps (accepted and rejected) each run may take before it stops
    /// with a step-limit failure; `None`: the library's
    /// ([`dae_solvers::Options::max_steps`]). Bounds the time of a sweep
    /// whose slow pairs would otherwise dominate it.
    pub max_steps: Option<usize>,
}

impl Default for Sweep {
    fn default() -> Self {
        Sweep {
            solvers: KNOWN_SOLVERS.iter().map(|s| s.to_string()).collect(),
            formulations: KNOWN_FORMULATIONS.iter().map(|s| s.to_string()).collect(),
            tolerances: DEFAULT_TOLERANCES.to_vec(),
            max_steps: None,
        }
    }
}

/// One kind of tolerance in a scene's `[tolerance]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum TolSpec {
    /// One value for every unknown.
    Uniform(f64),
    /// Values by unknown name (with their places); the unknowns not named
    /// take the command line's or the default value.
    PerUnknown(Vec<NamedValue>),
}

/// A scene's `[tolerance]`: what `dae run` integrates with (see the
/// [module documentation](self#tolerances-of-dae-run)). Both `None` when
/// the scene has no such section.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ToleranceSpec {
    /// Relative tolerance.
    pub rtol: Option<TolSpec>,
    /// Absolute tolerance.
    pub atol: Option<TolSpec>,
}

/// A parsed and validated scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Where the scene came from: a file path, `<built-in NAME>`, or the origin
    /// passed to [`Scene::parse`]. Used in error messages.
    pub origin: String,
    /// Display name.
    pub name: String,
    /// The model.
    pub model: ModelSource,
    /// Parameter overrides, in file order.
    pub parameters: Vec<NamedValue>,
    /// Initial values of differential unknowns, in file order.
    pub initial: Vec<NamedValue>,
    /// Guesses (`[guess]`): where the computation of unknowns `[initial]`
    /// does not give starts, in file order.
    pub guess: Vec<NamedValue>,
    /// Horizon and check times.
    pub time: TimeSpec,
    /// Reference solution.
    pub reference: ReferenceSpec,
    /// Sweep grid.
    pub sweep: Sweep,
    /// Tolerances of `dae run` (`[tolerance]`; the sweep uses
    /// [`Sweep::tolerances`]).
    pub tolerance: ToleranceSpec,
    /// How the model's events are treated (`[events.NAME]`), in file
    /// order: which crossings count, and whether one stops the run or
    /// resets unknowns ([`dae_solvers::EventSpec`]). The names are checked
    /// against the model by [`Scene::check_events`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<dae_solvers::EventSpec>,
    /// Forward sensitivities to compute beside a run (`[sensitivities]`;
    /// `dae run --sensitivities` replaces them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensitivities: Option<SensitivitySpec>,
    /// Where `model`, `time`, `time.start`, `time.end` and `reference.kind`
    /// are in the text, for problems found after parsing ([`Scene::locate`]).
    /// Entries are `(field, line, column)`; the file is [`Scene::origin`].
    #[serde(skip)]
    pub places: Vec<(String, usize, usize)>,
}

impl Scene {
    /// The initial values as `(name, value)` pairs, in the scene's order:
    /// what [`crate::runner::RunSpec::initial`] and the reference take.
    pub fn initial_values(&self) -> Vec<(String, f64)> {
        self.initial
            .iter()
            .map(|v| (v.name.clone(), v.value))
            .collect()
    }

    /// The guesses as `(name, value)` pairs, in the scene's order: what
    /// [`crate::runner::RunSpec::guess`] takes.
    ///
    /// ```
    /// let text = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[guess]\nlambda = 2\n\
    ///             [time]\nend = 1\n";
    /// let s = dae::scene::Scene::parse(text, "t.toml", None).unwrap();
    /// assert_eq!(s.guess_values(), [("lambda".to_string(), 2.0)]);
    /// assert_eq!(s.locate("guess.lambda").to_string(), "t.toml:6:1");
    /// ```
    pub fn guess_values(&self) -> Vec<(String, f64)> {
        self.guess
            .iter()
            .map(|v| (v.name.clone(), v.value))
            .collect()
    }

    /// A built-in scene by name (`s01`, `s02`; case-insensitive): the paper's
    /// scenarios, identical to `scenes/s01.toml` and `scenes/s02.toml`.
    ///
    /// ```
    /// let s = dae::scene::Scene::builtin("s01").unwrap();
    /// assert_eq!((s.time.end, s.time.checks.clone()), (20.0, vec![20.0]));
    /// assert!(dae::scene::Scene::builtin("s03").is_none());
    /// ```
    pub fn builtin(name: &str) -> Option<Scene> {
        let key = name.to_ascii_lowercase();
        let text = match key.as_str() {
            "s01" => S01_TOML,
            "s02" => S02_TOML,
            _ => return None,
        };
        // The embedded files are tested to parse; fall back to None rather
        // than panic should that ever fail.
        Scene::parse(text, &format!("<built-in {key}>"), None).ok()
    }

    /// Whether this scene is the paper's setup of the scenario it is named
    /// after (`S01`/`S02`, any case): the built-in pendulum with the
    /// parameters, initial values, start and check times of the built-in
    /// scene of that name. Only then do the paper's tables and the Fortran
    /// measurements apply; a scene named `S02` with another `g`, other
    /// initial values or other check times is compared with neither.
    ///
    /// ```
    /// use dae::scene::Scene;
    /// let paper = Scene::builtin("s02").unwrap();
    /// assert!(paper.is_paper_setup());
    /// let mut other_g = paper.clone();
    /// other_g.parameters.iter_mut().find(|p| p.name == "g").unwrap().value = 9.81;
    /// assert!(!other_g.is_paper_setup());
    /// let mut other_start = paper.clone();
    /// other_start.initial.iter_mut().find(|p| p.name == "x").unwrap().value = 0.5;
    /// assert!(!other_start.is_paper_setup());
    /// let mut fewer_checks = paper.clone();
    /// fewer_checks.time.checks.retain(|t| t % 20.0 == 0.0);
    /// assert!(!fewer_checks.is_paper_setup());
    /// let mut renamed = paper.clone();
    /// renamed.name = "my run".into();
    /// assert!(!renamed.is_paper_setup());
    /// ```
    pub fn is_paper_setup(&self) -> bool {
        if self.model != ModelSource::Builtin("pendulum".into()) {
            return false;
        }
        let Some(paper) = Scene::builtin(&self.name) else {
            return false;
        };
        let values = |v: &[NamedValue]| {
            let mut v: Vec<(String, f64)> = v.iter().map(|x| (x.name.clone(), x.value)).collect();
            v.sort_by(|a, b| a.0.cmp(&b.0));
            v
        };
        values(&self.parameters) == values(&paper.parameters)
            && values(&self.initial) == values(&paper.initial)
            && self.time.start == paper.time.start
            && self.time.end == paper.time.end
            && self.time.checks == paper.time.checks
    }

    /// Read a scene file, or a built-in scene by name when no file of that
    /// name exists. Model paths in the file are resolved against its
    /// directory.
    pub fn load(path_or_builtin: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path_or_builtin.as_ref();
        // A built-in name is a file only if a file of that name exists: a
        // directory called `s01` in the working directory does not hide the
        // built-in scene.
        if !path.is_file() {
            if let Some(scene) = path.to_str().and_then(Scene::builtin) {
                return Ok(scene);
            }
        }
        if !path.exists() {
            return Err(SceneError::NotFound {
                path: path.to_path_buf(),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(&text, &path.display().to_string(), Some(&base))
    }

    /// Parse and validate scene text. `origin` names the text in error
    /// messages; a relative model path is resolved against `base_dir` (the
    /// current directory when `None`).
    ///
    /// ```
    /// use dae::scene::{Scene, SceneError};
    ///
    /// let text = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\nend = 0\n";
    /// let err = Scene::parse(text, "t.toml", None).unwrap_err();
    /// assert!(matches!(err, SceneError::EmptyHorizon { .. }));
    /// assert_eq!(
    ///     err.to_string(),
    ///     "t.toml:6:7: `time.end` = 0 must be greater than `time.start` = 0"
    /// );
    /// ```
    pub fn parse(text: &str, origin: &str, base_dir: Option<&Path>) -> Result<Scene, SceneError> {
        let src = Source { text, origin };
        let raw: RawScene = toml::from_str(text).map_err(|e| src.toml_error(&e))?;
        src.validate(raw, base_dir)
    }

    /// Value of a parameter override, if the scene gives one.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.value)
    }

    /// Initial value the scene gives for a variable, if any.
    pub fn initial_value(&self, name: &str) -> Option<f64> {
        self.initial
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.value)
    }

    /// Check the names in `[initial]`, `[guess]` and in `[tolerance]`'s
    /// per-unknown tables against the model's `variables` and those in `[parameters]`
    /// against its `parameters`; the first unknown one is reported with
    /// its line and, when a known name is close, a suggestion.
    ///
    /// ```
    /// let s = dae::scene::Scene::builtin("s01").unwrap();
    /// assert!(s.check_names(&["x", "y", "v", "w", "lambda"], &["m", "l", "g"]).is_ok());
    /// let err = s.check_names(&["x", "y", "v", "w"], &["m", "l"]).unwrap_err();
    /// assert!(err.to_string().contains("`parameters.g`"));
    /// ```
    pub fn check_names(&self, variables: &[&str], parameters: &[&str]) -> Result<(), SceneError> {
        let known = |list: &[&str]| list.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        for entry in &self.parameters {
            if !parameters.contains(&entry.name.as_str()) {
                return Err(SceneError::UnknownParameter {
                    at: self.location(entry),
                    name: entry.name.clone(),
                    known: known(parameters),
                });
            }
        }
        fn per_unknown(spec: &Option<TolSpec>) -> &[NamedValue] {
            match spec {
                Some(TolSpec::PerUnknown(list)) => list,
                _ => &[],
            }
        }
        let sections = [
            ("initial", self.initial.as_slice()),
            ("guess", self.guess.as_slice()),
            ("tolerance.rtol", per_unknown(&self.tolerance.rtol)),
            ("tolerance.atol", per_unknown(&self.tolerance.atol)),
        ];
        for (section, entries) in sections {
            for entry in entries {
                if !variables.contains(&entry.name.as_str()) {
                    return Err(SceneError::UnknownVariable {
                        at: self.location(entry),
                        section,
                        name: entry.name.clone(),
                        known: known(variables),
                    });
                }
            }
        }
        Ok(())
    }

    /// Check `[events.NAME]` against the model: each `NAME` one of its
    /// `events` (the model's `events { … }` section), each unknown a reset
    /// names one of its `variables`. The first unknown name is reported
    /// with its line and, when a known name is close, a suggestion.
    ///
    /// ```
    /// let text = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\nend = 1\n\
    ///             [events.wall]\ndirection = \"falling\"\nscale = { v = -0.8, w = -0.8 }\n";
    /// let s = dae::scene::Scene::parse(text, "t.toml", None).unwrap();
    /// let vars = ["x", "y", "v", "w", "lambda"];
    /// assert!(s.check_events(&["wall".to_string()], &vars).is_ok());
    /// let err = s.check_events(&["wal".to_string()], &vars).unwrap_err();
    /// assert_eq!(
    ///     err.to_string(),
    ///     "t.toml:7:9: `events.wall`: the model has no event `wall`; did you mean `wal`? (events: wal)"
    /// );
    /// let err = s.check_events(&["wall".to_string()], &["x", "y", "v"]).unwrap_err();
    /// let msg = err.to_string();
    /// assert!(msg.starts_with("t.toml:9:") && msg.contains("`events.wall.scale.w`"), "{msg}");
    /// ```
    pub fn check_events(&self, events: &[String], variables: &[&str]) -> Result<(), SceneError> {
        for e in &self.events {
            if !events.contains(&e.name) {
                return Err(SceneError::UnknownEvent {
                    at: self.locate(&format!("events.{}", e.name)),
                    name: e.name.clone(),
                    known: events.to_vec(),
                });
            }
            if let dae_solvers::EventAction::Reset(rules) = &e.action {
                for (u, r) in rules {
                    if !variables.contains(&u.as_str()) {
                        let kind = match r {
                            dae_solvers::Reset::Scale(_) => "scale",
                            dae_solvers::Reset::Value(_) => "set",
                        };
                        return Err(SceneError::UnknownVariable {
                            at: self.locate(&format!("events.{}.{kind}.{u}", e.name)),
                            section: "events",
                            name: format!("{}.{kind}.{u}", e.name),
                            known: variables.iter().map(|s| s.to_string()).collect(),
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// Where a field (`initial.x`, `parameters.g`, `time.end`, `model`,
    /// `reference.kind`, …) is in the scene text, for problems found after
    /// parsing (an exact reference that cannot be built from the start, …).
    /// A field the scene does not give (a model default, say) is located at
    /// its table (`time`) or at `reference.kind`, else at the file's first
    /// line.
    ///
    /// ```
    /// let s = dae::scene::Scene::builtin("s01").unwrap();
    /// assert_eq!(s.locate("initial.x").to_string(), "<built-in s01>:12:1");
    /// assert_eq!(s.locate("time.end").to_string(), "<built-in s01>:18:7");
    /// ```
    pub fn locate(&self, field: &str) -> Location {
        let named = |list: &[NamedValue], name: &str| {
            list.iter()
                .find(|e| e.name == name)
                .map(|e| self.location(e))
        };
        let place = |f: &str| {
            self.places
                .iter()
                .find(|(k, ..)| k == f)
                .map(|&(_, line, column)| Location {
                    origin: self.origin.clone(),
                    line,
                    column,
                })
        };
        let found = if let Some(name) = field.strip_prefix("initial.") {
            named(&self.initial, name)
        } else if let Some(name) = field.strip_prefix("guess.") {
            named(&self.guess, name)
        } else if let Some(name) = field.strip_prefix("parameters.") {
            named(&self.parameters, name)
        } else {
            place(field).or_else(|| field.split_once('.').and_then(|(table, _)| place(table)))
        };
        found
            .or_else(|| place("reference.kind"))
            .unwrap_or_else(|| Location {
                origin: self.origin.clone(),
                line: 1,
                column: 1,
            })
    }

    fn location(&self, entry: &NamedValue) -> Location {
        Location {
            origin: self.origin.clone(),
            line: entry.line,
            column: entry.column,
        }
    }
}

// ---------------------------------------------------------------------------
// The raw serde layer: everything optional and spanned, validated afterwards.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<Spanned<String>>,
    model: Option<Spanned<String>>,
    parameters: Option<RawNamed>,
    initial: Option<Spanned<RawNamed>>,
    guess: Option<RawNamed>,
    time: Option<Spanned<RawTime>>,
    reference: Option<Spanned<RawReference>>,
    sweep: Option<RawSweep>,
    tolerance: Option<RawTolerance>,
    events: Option<RawEvents>,
    sensitivities: Option<RawSensitivities>,
}

/// `[sensitivities]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSensitivities {
    parameters: Vec<String>,
    error_control: Option<bool>,
}

/// `[events.NAME]`: `direction = "both" | "rising" | "falling"`, and
/// `stop = true`, or a reset: `scale = { w = -0.8 }` (`w = −0.8 w`) and/or
/// `set = { lambda = 0 }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEvent {
    direction: Option<Spanned<String>>,
    stop: Option<Spanned<bool>>,
    scale: Option<RawNamed>,
    set: Option<RawNamed>,
}

/// The `[events.NAME]` tables, in file order, with spans.
struct RawEvents(Vec<(Spanned<String>, Spanned<RawEvent>)>);

impl<'de> Deserialize<'de> for RawEvents {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct EventsVisitor;
        impl<'de> Visitor<'de> for EventsVisitor {
            type Value = RawEvents;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a table of `[events.NAME]` tables")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawEvents, A::Error> {
                let mut entries = Vec::new();
                while let Some(key) = map.next_key::<Spanned<String>>()? {
                    entries.push((key, map.next_value::<Spanned<RawEvent>>()?));
                }
                Ok(RawEvents(entries))
            }
        }
        deserializer.deserialize_map(EventsVisitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTolerance {
    rtol: Option<Spanned<RawTol>>,
    atol: Option<Spanned<RawTol>>,
}

/// `rtol`/`atol`: a number, or a table of `name = number`.
enum RawTol {
    Uniform(f64),
    PerUnknown(RawNamed),
}

impl<'de> Deserialize<'de> for RawTol {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct TolVisitor;
        impl<'de> Visitor<'de> for TolVisitor {
            type Value = RawTol;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number, or a table of `unknown = number` entries")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<RawTol, E> {
                Ok(RawTol::Uniform(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<RawTol, E> {
                Ok(RawTol::Uniform(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<RawTol, E> {
                Ok(RawTol::Uniform(v as f64))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawTol, A::Error> {
                Ok(RawTol::PerUnknown(RawNamed(named_entries(map)?)))
            }
        }
        deserializer.deserialize_any(TolVisitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    start: Option<Spanned<f64>>,
    end: Option<Spanned<f64>>,
    check: Option<Spanned<Vec<Spanned<f64>>>>,
    check_every: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawReference {
    kind: Option<Spanned<String>>,
    closed_form: Option<Spanned<String>>,
    file: Option<Spanned<String>>,
    times: Option<Spanned<Vec<Spanned<f64>>>>,
    values: Option<Spanned<RawSeries>>,
    columns: Option<Spanned<Vec<Spanned<String>>>>,
    scaling: Option<Spanned<toml::Value>>,
}

/// A table of `name = [numbers]`, in file order, with spans.
struct RawSeries(Vec<(Spanned<String>, Spanned<Vec<f64>>)>);

impl<'de> Deserialize<'de> for RawSeries {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct SeriesVisitor;
        impl<'de> Visitor<'de> for SeriesVisitor {
            type Value = RawSeries;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a table of `name = [numbers]` entries")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawSeries, A::Error> {
                let mut entries = Vec::new();
                while let Some(key) = map.next_key::<Spanned<String>>()? {
                    entries.push((key, map.next_value::<Spanned<Vec<f64>>>()?));
                }
                Ok(RawSeries(entries))
            }
        }
        deserializer.deserialize_map(SeriesVisitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSweep {
    solvers: Option<Spanned<Vec<Spanned<String>>>>,
    formulations: Option<Spanned<Vec<Spanned<String>>>>,
    tolerances: Option<Spanned<Vec<Spanned<f64>>>>,
    max_steps: Option<Spanned<i64>>,
}

/// A table of `name = number`, in file order, with spans.
struct RawNamed(Vec<(Spanned<String>, Spanned<f64>)>);

impl<'de> Deserialize<'de> for RawNamed {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NamedVisitor;
        impl<'de> Visitor<'de> for NamedVisitor {
            type Value = RawNamed;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a table of `name = number` entries")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawNamed, A::Error> {
                Ok(RawNamed(named_entries(map)?))
            }
        }
        deserializer.deserialize_map(NamedVisitor)
    }
}

/// `name = number` entries with their spans.
type Entries = Vec<(Spanned<String>, Spanned<f64>)>;

/// The `name = number` entries of a table, in file order, with spans.
fn named_entries<'de, A: MapAccess<'de>>(mut map: A) -> Result<Entries, A::Error> {
    let mut entries = Vec::new();
    while let Some(key) = map.next_key::<Spanned<String>>()? {
        let value = map.next_value::<Spanned<f64>>()?;
        entries.push((key, value));
    }
    Ok(entries)
}

/// The scene text with its origin, for locating errors.
struct Source<'a> {
    text: &'a str,
    origin: &'a str,
}

impl Source<'_> {
    /// 1-based line and column (in characters) of a byte offset.
    fn location(&self, offset: usize) -> Location {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        Location {
            origin: self.origin.to_string(),
            line,
            column,
        }
    }

    fn at(&self, span: &Range<usize>) -> Location {
        self.location(span.start)
    }

    /// `section.key` for the text at `offset`: the closest `[section]`
    /// header above and the key on that line, as far as they can be found.
    fn field_at(&self, offset: usize) -> String {
        let offset = offset.min(self.text.len());
        let mut section = String::new();
        let mut key = String::new();
        let mut pos = 0;
        for line in self.text.split_inclusive('\n') {
            let trimmed = line.trim();
            if pos > offset {
                break;
            }
            if trimmed.starts_with('[') {
                let header = trimmed.trim_start_matches('[');
                let end = header.find(']').unwrap_or(header.len());
                section = header[..end].trim().to_string();
                key.clear();
            } else if let Some(eq) = line.find('=') {
                let candidate = line[..eq].trim();
                if !candidate.is_empty() && !candidate.starts_with('#') {
                    key = candidate.trim_matches('"').to_string();
                }
            }
            pos += line.len();
        }
        match (section.is_empty(), key.is_empty()) {
            (true, _) => key,
            (false, true) => section,
            (false, false) => format!("{section}.{key}"),
        }
    }

    /// Turn a TOML/serde error into a located [`SceneError`].
    fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let span = e.span().unwrap_or(0..0);
        let at = self.at(&span);
        let message = e.message().trim().replace('\n', ": ");
        if let Some(rest) = message.strip_prefix("unknown field `") {
            let name = rest.split('`').next().unwrap_or_default().to_string();
            let expected = rest
                .split_once("expected ")
                .map_or_else(String::new, |(_, x)| x.replace("one of ", ""));
            let section = self.field_at(span.start);
            let section = section.split('.').next().unwrap_or_default();
            let field = if section.is_empty() || section == name {
                name
            } else {
                format!("{section}.{name}")
            };
            return SceneError::UnknownField {
                at,
                field,
                expected,
            };
        }
        if message.starts_with("invalid type")
            || message.starts_with("invalid value")
            || message.starts_with("invalid length")
        {
            return SceneError::InvalidType {
                at,
                field: self.field_at(span.start),
                message,
            };
        }
        SceneError::Syntax { at, message }
    }

    fn missing(&self, field: &str, table: Option<&Range<usize>>) -> SceneError {
        SceneError::MissingField {
            at: table.map_or_else(|| self.location(0), |s| self.at(s)),
            field: field.to_string(),
        }
    }

    /// Whether the number literal at `span` has a non-zero digit before
    /// its exponent (so that a value of 0 is an underflow).
    fn nonzero_literal(&self, span: &Range<usize>) -> bool {
        let literal = self.text.get(span.clone()).unwrap_or_default();
        let mantissa = literal.split(['e', 'E']).next().unwrap_or_default();
        // Hexadecimal, octal and binary integers are exact: no underflow.
        !mantissa.contains(['x', 'o', 'b']) && mantissa.chars().any(|c| ('1'..='9').contains(&c))
    }

    /// A finite number of magnitude at most [`MAX_ABS_VALUE`].
    fn finite(&self, field: &str, v: &Spanned<f64>) -> Result<f64, SceneError> {
        let value = *v.get_ref();
        if !value.is_finite() {
            Err(SceneError::NotFinite {
                at: self.at(&v.span()),
                field: field.to_string(),
                value,
            })
        } else if value == 0.0 && self.nonzero_literal(&v.span()) {
            Err(SceneError::Underflow {
                at: self.at(&v.span()),
                field: field.to_string(),
                literal: self
                    .text
                    .get(v.span())
                    .unwrap_or_default()
                    .trim()
                    .to_string(),
            })
        } else if value.abs() > MAX_ABS_VALUE {
            Err(SceneError::TooLarge {
                at: self.at(&v.span()),
                field: field.to_string(),
                value,
                max: MAX_ABS_VALUE,
            })
        } else {
            Ok(value)
        }
    }

    fn named(&self, section: &str, raw: RawNamed) -> Result<Vec<NamedValue>, SceneError> {
        raw.0
            .into_iter()
            .map(|(key, value)| {
                let name = key.get_ref().clone();
                let v = self.finite(&format!("{section}.{name}"), &value)?;
                let at = self.at(&key.span());
                Ok(NamedValue {
                    name,
                    value: v,
                    line: at.line,
                    column: at.column,
                })
            })
            .collect()
    }

    fn validate(&self, raw: RawScene, base_dir: Option<&Path>) -> Result<Scene, SceneError> {
        let name = raw.name.ok_or_else(|| self.missing("name", None))?;
        if name.get_ref().trim().is_empty() {
            return Err(SceneError::InvalidValue {
                at: self.at(&name.span()),
                field: "name".into(),
                reason: "must not be empty".into(),
            });
        }
        let model_raw = raw.model.ok_or_else(|| self.missing("model", None))?;
        let model = self.model(&model_raw, base_dir)?;
        let mut places = Vec::new();
        let mut place = |field: &str, span: Range<usize>| {
            let at = self.at(&span);
            places.push((field.to_string(), at.line, at.column));
        };
        place("model", model_raw.span());
        let parameters = match raw.parameters {
            Some(p) => self.named("parameters", p)?,
            None => Vec::new(),
        };
        let initial_raw = raw.initial.ok_or_else(|| self.missing("initial", None))?;
        let initial_span = initial_raw.span();
        let initial = self.named("initial", initial_raw.into_inner())?;
        if initial.is_empty() {
            return Err(SceneError::InvalidValue {
                at: self.at(&initial_span),
                field: "initial".into(),
                reason: "must give at least one initial value".into(),
            });
        }
        let guess = match raw.guess {
            Some(g) => self.named("guess", g)?,
            None => Vec::new(),
        };
        if let Some(g) = guess
            .iter()
            .find(|g| initial.iter().any(|i| i.name == g.name))
        {
            return Err(SceneError::InvalidValue {
                at: Location {
                    origin: self.origin.to_string(),
                    line: g.line,
                    column: g.column,
                },
                field: format!("guess.{}", g.name),
                reason: "is fixed by [initial]; a guess is only for unknowns [initial] does \
                         not give"
                    .into(),
            });
        }
        let time_raw = raw.time.ok_or_else(|| self.missing("time", None))?;
        place("time", time_raw.span());
        for (field, value) in [
            ("time.start", &time_raw.get_ref().start),
            ("time.end", &time_raw.get_ref().end),
        ] {
            if let Some(v) = value {
                place(field, v.span());
            }
        }
        let time = self.time(time_raw)?;
        let reference = match raw.reference {
            None => ReferenceSpec::None,
            Some(r) => {
                let span = r.span();
                place("reference", span.clone());
                let r = r.into_inner();
                if let Some(kind) = &r.kind {
                    place("reference.kind", kind.span());
                }
                self.reference(r, &span, base_dir)?
            }
        };
        let sweep = match raw.sweep {
            None => Sweep::default(),
            Some(s) => self.sweep(s)?,
        };
        let tolerance = match raw.tolerance {
            None => ToleranceSpec::default(),
            Some(t) => ToleranceSpec {
                rtol: self.tol_spec("tolerance.rtol", t.rtol)?,
                atol: self.tol_spec("tolerance.atol", t.atol)?,
            },
        };
        let mut events = Vec::new();
        let mut reset_places = Vec::new();
        for (key, raw) in raw.events.map(|e| e.0).unwrap_or_default() {
            let name = key.get_ref().clone();
            place(&format!("events.{name}"), key.span());
            events.push(self.event(&name, raw, &mut reset_places)?);
        }
        places.extend(reset_places);
        Ok(Scene {
            origin: self.origin.to_string(),
            name: name.into_inner(),
            model,
            parameters,
            initial,
            guess,
            time,
            reference,
            sweep,
            tolerance,
            events,
            sensitivities: raw.sensitivities.map(|s| SensitivitySpec {
                parameters: s.parameters,
                error_control: s.error_control.unwrap_or(true),
            }),
            places,
        })
    }

    /// One `[events.NAME]` table; the reset entries' places are recorded
    /// as `events.NAME.scale.UNKNOWN` (`set` likewise).
    fn event(
        &self,
        name: &str,
        raw: Spanned<RawEvent>,
        places: &mut Vec<(String, usize, usize)>,
    ) -> Result<dae_solvers::EventSpec, SceneError> {
        use dae_solvers::{Direction, EventAction, EventSpec, Reset};
        let span = raw.span();
        let raw = raw.into_inner();
        let direction = match &raw.direction {
            None => Direction::Both,
            Some(d) => match d.get_ref().as_str() {
                "both" => Direction::Both,
                "rising" => Direction::Rising,
                "falling" => Direction::Falling,
                other => {
                    return Err(SceneError::InvalidValue {
                        at: self.at(&d.span()),
                        field: format!("events.{name}.direction"),
                        reason: format!(
                            "= \"{other}\" is not a direction (\"both\", \"rising\" or \"falling\")"
                        ),
                    })
                }
            },
        };
        let mut rules = Vec::new();
        for (kind, table) in [("scale", raw.scale), ("set", raw.set)] {
            let Some(table) = table else { continue };
            let field = format!("events.{name}.{kind}");
            for v in self.named(&field, table)? {
                places.push((format!("{field}.{}", v.name), v.line, v.column));
                let rule = if kind == "scale" {
                    Reset::Scale(v.value)
                } else {
                    Reset::Value(v.value)
                };
                rules.push((v.name, rule));
            }
        }
        let stop = raw.stop.as_ref().is_some_and(|s| *s.get_ref());
        let action = match (stop, rules.is_empty()) {
            (false, true) => EventAction::Record,
            (true, true) => EventAction::Stop,
            (false, false) => EventAction::Reset(rules),
            (true, false) => {
                return Err(SceneError::InvalidValue {
                    at: self.at(&span),
                    field: format!("events.{name}"),
                    reason: "both stops the run (`stop = true`) and resets unknowns \
                             (`scale`/`set`): choose one"
                        .into(),
                })
            }
        };
        Ok(EventSpec {
            name: name.to_string(),
            direction,
            action,
        })
    }

    /// `tolerance.rtol` or `tolerance.atol`: each value by the library's
    /// rule for its kind; no name twice; a table not empty.
    fn tol_spec(
        &self,
        field: &str,
        raw: Option<Spanned<RawTol>>,
    ) -> Result<Option<TolSpec>, SceneError> {
        let Some(raw) = raw else { return Ok(None) };
        let span = raw.span();
        let relative = field.ends_with("rtol");
        let check = |field: String, value: f64, at: Location| {
            let rule = if relative {
                dae_solvers::options::check_relative(value)
            } else if !value.is_finite() {
                Err(dae_solvers::options::ToleranceIssue::NotFinite)
            } else if value < 0.0 {
                Err(dae_solvers::options::ToleranceIssue::Negative)
            } else {
                Ok(())
            };
            rule.map_err(|issue| SceneError::InvalidToleranceValue {
                at,
                field,
                value,
                issue,
            })
        };
        Ok(Some(match raw.into_inner() {
            RawTol::Uniform(v) => {
                check(field.to_string(), v, self.at(&span))?;
                TolSpec::Uniform(v)
            }
            RawTol::PerUnknown(entries) => {
                let mut out: Vec<NamedValue> = Vec::with_capacity(entries.0.len());
                for (key, value) in entries.0 {
                    let name = key.get_ref().clone();
                    let at = self.at(&key.span());
                    check(format!("{field}.{name}"), *value.get_ref(), at.clone())?;
                    if out.iter().any(|e| e.name == name) {
                        return Err(SceneError::Duplicate {
                            at,
                            field: field.into(),
                            name,
                        });
                    }
                    out.push(NamedValue {
                        name,
                        value: *value.get_ref(),
                        line: at.line,
                        column: at.column,
                    });
                }
                if out.is_empty() {
                    return Err(SceneError::InvalidValue {
                        at: self.at(&span),
                        field: field.into(),
                        reason: "is an empty table: name at least one unknown, or give a number"
                            .into(),
                    });
                }
                TolSpec::PerUnknown(out)
            }
        }))
    }

    /// `[reference]`: its kind and, for `values` and `trajectory`, the
    /// table (read from `file`, relative to `base_dir`, or inline) and the
    /// scaling of each column.
    fn reference(
        &self,
        r: RawReference,
        table_span: &Range<usize>,
        base_dir: Option<&Path>,
    ) -> Result<ReferenceSpec, SceneError> {
        let kind = r
            .kind
            .as_ref()
            .ok_or_else(|| self.missing("reference.kind", Some(table_span)))?;
        let invalid = |span: &Range<usize>, field: &str, reason: String| SceneError::InvalidValue {
            at: self.at(span),
            field: field.into(),
            reason,
        };
        let kind_name = kind.get_ref().as_str();
        // Fields that do not belong to the kind are refused, not ignored.
        let given: [(&str, Option<Range<usize>>); 6] = [
            ("closed_form", r.closed_form.as_ref().map(Spanned::span)),
            ("file", r.file.as_ref().map(Spanned::span)),
            ("times", r.times.as_ref().map(Spanned::span)),
            ("values", r.values.as_ref().map(Spanned::span)),
            ("columns", r.columns.as_ref().map(Spanned::span)),
            ("scaling", r.scaling.as_ref().map(Spanned::span)),
        ];
        let allowed: &[&str] = match kind_name {
            "exact" | "pendulum-exact" => &["closed_form"],
            "values" | "trajectory" => &["file", "times", "values", "columns", "scaling"],
            "none" => &[],
            other => {
                return Err(SceneError::UnknownReference {
                    at: self.at(&kind.span()),
                    kind: other.to_string(),
                })
            }
        };
        if let Some((field, Some(span))) = given
            .iter()
            .find(|(f, span)| span.is_some() && !allowed.contains(f))
        {
            return Err(invalid(
                span,
                &format!("reference.{field}"),
                format!("does not apply to a reference of kind \"{kind_name}\""),
            ));
        }
        let table = match kind_name {
            "none" => return Ok(ReferenceSpec::None),
            "exact" | "pendulum-exact" => {
                let closed_form = match &r.closed_form {
                    None => CLOSED_FORMS[0].to_string(),
                    Some(c) if CLOSED_FORMS.contains(&c.get_ref().as_str()) => c.get_ref().clone(),
                    Some(c) => {
                        return Err(invalid(
                            &c.span(),
                            "reference.closed_form",
                            format!(
                                "\"{}\" is unknown (known: {})",
                                c.get_ref(),
                                CLOSED_FORMS.join(", ")
                            ),
                        ))
                    }
                };
                return Ok(ReferenceSpec::Exact { closed_form });
            }
            _ => self.reference_table(&r, table_span, base_dir)?,
        };
        let table = match &r.columns {
            None => table,
            Some(columns) => self.select_columns(table, columns)?,
        };
        let scaling = self.scaling(r.scaling.as_ref(), &table)?;
        Ok(if kind_name == "values" {
            ReferenceSpec::Values { table, scaling }
        } else {
            ReferenceSpec::Trajectory { table, scaling }
        })
    }

    /// The table of a `values` or `trajectory` reference: `file` or
    /// `times` with `values`, not both.
    fn reference_table(
        &self,
        r: &RawReference,
        table_span: &Range<usize>,
        base_dir: Option<&Path>,
    ) -> Result<Table, SceneError> {
        let located =
            |span: &Range<usize>, field: &str, reason: String| SceneError::ReferenceTable {
                at: self.at(span),
                field: field.into(),
                reason,
            };
        match (&r.file, &r.times, &r.values) {
            (Some(file), None, None) => {
                let given = Path::new(file.get_ref());
                let path = match base_dir {
                    Some(base) if given.is_relative() => base.join(given),
                    _ => given.to_path_buf(),
                };
                let cannot = |why: String| {
                    located(
                        &file.span(),
                        "reference.file",
                        format!("cannot read `{}`: {why}", path.display()),
                    )
                };
                // A regular file of bounded size: `/dev/zero` or a FIFO
                // would never end.
                let meta = std::fs::metadata(&path).map_err(|e| cannot(e.to_string()))?;
                if !meta.is_file() {
                    return Err(cannot("not a regular file".into()));
                }
                if meta.len() > MAX_REFERENCE_BYTES {
                    return Err(cannot(format!(
                        "{} bytes, more than the limit of {MAX_REFERENCE_BYTES}",
                        meta.len()
                    )));
                }
                let text = std::fs::read_to_string(&path).map_err(|e| cannot(e.to_string()))?;
                Table::from_csv(&text).map_err(|e| {
                    located(
                        &file.span(),
                        "reference.file",
                        format!("`{}`: {e}", path.display()),
                    )
                })
            }
            (None, Some(times), Some(values)) => {
                let t: Vec<f64> = times.get_ref().iter().map(|v| *v.get_ref()).collect();
                let mut names = Vec::new();
                let mut columns = Vec::new();
                for (name, series) in &values.get_ref().0 {
                    if series.get_ref().len() != t.len() {
                        return Err(located(
                            &series.span(),
                            &format!("reference.values.{}", name.get_ref()),
                            format!(
                                "{} values for the {} times of `reference.times`",
                                series.get_ref().len(),
                                t.len()
                            ),
                        ));
                    }
                    names.push(name.get_ref().clone());
                    columns.push(series.get_ref().clone());
                }
                let rows = (0..t.len())
                    .map(|i| columns.iter().map(|c| c[i]).collect())
                    .collect();
                Table::new(names, t, rows)
                    .map_err(|e| located(&values.span(), "reference.values", e.to_string()))
            }
            (Some(file), _, _) => Err(located(
                &file.span(),
                "reference.file",
                "give either `file` or `times` with `values`, not both".into(),
            )),
            (None, None, None) => Err(self.missing("reference.file", Some(table_span))),
            (None, Some(times), None) => Err(self.missing("reference.values", Some(&times.span()))),
            (None, None, Some(values)) => {
                Err(self.missing("reference.times", Some(&values.span())))
            }
        }
    }

    /// `columns`: the columns of the table to compare, in that order.
    fn select_columns(
        &self,
        table: Table,
        columns: &Spanned<Vec<Spanned<String>>>,
    ) -> Result<Table, SceneError> {
        let mut index = Vec::new();
        for c in columns.get_ref() {
            let name = c.get_ref();
            let j = table.names.iter().position(|n| n == name).ok_or_else(|| {
                SceneError::InvalidValue {
                    at: self.at(&c.span()),
                    field: "reference.columns".into(),
                    reason: format!(
                        "`{name}` is not a column of the table (columns: {})",
                        table.names.join(", ")
                    ),
                }
            })?;
            if index.contains(&j) {
                return Err(SceneError::Duplicate {
                    at: self.at(&c.span()),
                    field: "reference.columns".into(),
                    name: name.clone(),
                });
            }
            index.push(j);
        }
        if index.is_empty() {
            return Err(SceneError::InvalidValue {
                at: self.at(&columns.span()),
                field: "reference.columns".into(),
                reason: "must name at least one column".into(),
            });
        }
        let names = index.iter().map(|&j| table.names[j].clone()).collect();
        let rows = table
            .rows
            .iter()
            .map(|row| index.iter().map(|&j| row[j]).collect())
            .collect();
        Ok(Table {
            names,
            times: table.times,
            rows,
        })
    }

    /// `scaling`: one name for every column, or a table of names per
    /// column (the others absolute).
    fn scaling(
        &self,
        raw: Option<&Spanned<toml::Value>>,
        table: &Table,
    ) -> Result<Vec<Scaling>, SceneError> {
        let mut out = vec![Scaling::Absolute; table.names.len()];
        let Some(raw) = raw else { return Ok(out) };
        let invalid = |field: String, reason: String| SceneError::InvalidValue {
            at: self.at(&raw.span()),
            field,
            reason,
        };
        let parse = |field: &str, v: &toml::Value| {
            v.as_str().and_then(Scaling::parse).ok_or_else(|| {
                invalid(
                    field.into(),
                    format!("must be one of {} (got {v})", SCALINGS.join(", ")),
                )
            })
        };
        match raw.get_ref() {
            toml::Value::Table(per) => {
                for (name, v) in per {
                    let field = format!("reference.scaling.{name}");
                    let j = table.names.iter().position(|n| n == name).ok_or_else(|| {
                        invalid(
                            field.clone(),
                            format!("`{name}` is not a column of the reference"),
                        )
                    })?;
                    out[j] = parse(&field, v)?;
                }
            }
            v => out.fill(parse("reference.scaling", v)?),
        }
        Ok(out)
    }

    fn model(
        &self,
        raw: &Spanned<String>,
        base_dir: Option<&Path>,
    ) -> Result<ModelSource, SceneError> {
        let value = raw.get_ref().trim();
        if value.is_empty() {
            return Err(SceneError::InvalidValue {
                at: self.at(&raw.span()),
                field: "model".into(),
                reason: "must name a built-in model or a .dae file".into(),
            });
        }
        if crate::models::BUILTIN_MODELS.contains(&value) {
            return Ok(ModelSource::Builtin(value.to_string()));
        }
        let given = Path::new(value);
        let path = match base_dir {
            Some(base) if given.is_relative() => base.join(given),
            _ => given.to_path_buf(),
        };
        let at = self.at(&raw.span());
        if path.is_dir() {
            return Err(SceneError::ModelIsDirectory { at, path });
        }
        if path.is_file() {
            return Ok(ModelSource::File(path));
        }
        let looks_like_path =
            value.ends_with(".dae") || value.contains('/') || value.contains('\\');
        if looks_like_path {
            Err(SceneError::ModelNotFound { at, path })
        } else {
            Err(SceneError::UnknownModel {
                at,
                name: value.to_string(),
            })
        }
    }

    fn time(&self, raw: Spanned<RawTime>) -> Result<TimeSpec, SceneError> {
        let table = raw.span();
        let raw = raw.into_inner();
        let start = match &raw.start {
            Some(s) => self.finite("time.start", s)?,
            None => 0.0,
        };
        let end_raw = raw
            .end
            .as_ref()
            .ok_or_else(|| self.missing("time.end", Some(&table)))?;
        let end = self.finite("time.end", end_raw)?;
        if end <= start {
            return Err(SceneError::EmptyHorizon {
                at: self.at(&end_raw.span()),
                start,
                end,
            });
        }
        let (checks, rule) = match (raw.check, raw.check_every) {
            (Some(_), Some(every)) => {
                return Err(SceneError::CheckConflict {
                    at: self.at(&every.span()),
                })
            }
            (Some(list), None) => (self.check_list(list, start, end)?, CheckRule::List),
            (None, Some(every)) => {
                let step = self.finite("time.check_every", &every)?;
                (
                    self.check_every(&every, step, start, end)?,
                    CheckRule::Every(step),
                )
            }
            (None, None) => (vec![end], CheckRule::EndOnly),
        };
        Ok(TimeSpec {
            start,
            end,
            checks,
            rule,
        })
    }

    fn check_list(
        &self,
        list: Spanned<Vec<Spanned<f64>>>,
        start: f64,
        end: f64,
    ) -> Result<Vec<f64>, SceneError> {
        let list_span = list.span();
        let list = list.into_inner();
        if list.is_empty() {
            return Err(SceneError::InvalidValue {
                at: self.at(&list_span),
                field: "time.check".into(),
                reason:
                    "is empty: give at least one check time, or leave it out to check at the end"
                        .into(),
            });
        }
        let mut out: Vec<f64> = Vec::with_capacity(list.len());
        for item in &list {
            let t = self.finite("time.check", item)?;
            let at = self.at(&item.span());
            if !(start..=end).contains(&t) {
                return Err(SceneError::CheckOutsideHorizon {
                    at,
                    time: t,
                    start,
                    end,
                });
            }
            if let Some(&previous) = out.last() {
                if t <= previous {
                    return Err(SceneError::CheckNotIncreasing {
                        at,
                        time: t,
                        previous,
                    });
                }
            }
            out.push(t);
        }
        if out.iter().all(|&t| t <= start) {
            return Err(SceneError::VacuousChecks {
                at: self.at(&list_span),
                start,
            });
        }
        Ok(out)
    }

    /// `start + k·every`, `k = 1, 2, …` while `≤ end` (with a slack of
    /// 10⁻⁹·every for rounding; a time within the slack beyond `end` is
    /// clamped to `end`). Each time is computed from `k` directly, not by
    /// accumulation.
    fn check_every(
        &self,
        raw: &Spanned<f64>,
        every: f64,
        start: f64,
        end: f64,
    ) -> Result<Vec<f64>, SceneError> {
        let at = self.at(&raw.span());
        if every <= 0.0 {
            return Err(SceneError::InvalidValue {
                at,
                field: "time.check_every".into(),
                reason: format!("= {every} must be positive"),
            });
        }
        let count = ((end - start) / every + 1e-9).floor();
        if count.is_nan() || count < 1.0 {
            return Err(SceneError::InvalidValue {
                at,
                field: "time.check_every".into(),
                reason: format!("= {every} gives no check time in ({start}, {end}]"),
            });
        }
        if count.is_nan() || count > MAX_CHECK_TIMES as f64 {
            return Err(SceneError::TooManyCheckTimes {
                at,
                count,
                max: MAX_CHECK_TIMES,
            });
        }
        let n = count as usize;
        let mut out = Vec::with_capacity(n);
        for k in 1..=n {
            let t = (k as f64).mul_add(every, start).min(end);
            if out.last().is_some_and(|&p: &f64| t <= p) {
                // Steps below the resolution of the times themselves.
                return Err(SceneError::InvalidValue {
                    at,
                    field: "time.check_every".into(),
                    reason: format!("= {every} is too small to separate check times near {t}"),
                });
            }
            out.push(t);
        }
        Ok(out)
    }

    fn names(
        &self,
        field: &str,
        raw: Spanned<Vec<Spanned<String>>>,
        known: &[&str],
        unknown: impl Fn(Location, String) -> SceneError,
    ) -> Result<Vec<String>, SceneError> {
        let span = raw.span();
        let list = raw.into_inner();
        if list.is_empty() {
            return Err(SceneError::InvalidValue {
                at: self.at(&span),
                field: field.into(),
                reason: "is empty: leave it out to sweep all".into(),
            });
        }
        let mut out: Vec<String> = Vec::with_capacity(list.len());
        for item in list {
            let at = self.at(&item.span());
            let name = item.into_inner();
            if !known.contains(&name.as_str()) {
                return Err(unknown(at, name));
            }
            if out.contains(&name) {
                return Err(SceneError::Duplicate {
                    at,
                    field: field.into(),
                    name,
                });
            }
            out.push(name);
        }
        Ok(out)
    }

    fn sweep(&self, raw: RawSweep) -> Result<Sweep, SceneError> {
        let defaults = Sweep::default();
        let solvers = match raw.solvers {
            Some(list) => self.names("sweep.solvers", list, KNOWN_SOLVERS, |at, name| {
                SceneError::UnknownSolver { at, name }
            })?,
            None => defaults.solvers,
        };
        let formulations = match raw.formulations {
            Some(list) => self.names(
                "sweep.formulations",
                list,
                KNOWN_FORMULATIONS,
                |at, name| SceneError::UnknownFormulation { at, name },
            )?,
            None => defaults.formulations,
        };
        let tolerances = match raw.tolerances {
            Some(list) => {
                let span = list.span();
                let list = list.into_inner();
                if list.is_empty() {
                    return Err(SceneError::InvalidValue {
                        at: self.at(&span),
                        field: "sweep.tolerances".into(),
                        reason: "is empty: leave it out for 1e-5 … 1e-12".into(),
                    });
                }
                let mut out: Vec<f64> = Vec::with_capacity(list.len());
                for item in list {
                    let at = self.at(&item.span());
                    let value = item.into_inner();
                    if let Err(issue) = dae_solvers::options::check_uniform(value) {
                        return Err(SceneError::InvalidTolerance { at, value, issue });
                    }
                    if out.contains(&value) {
                        return Err(SceneError::Duplicate {
                            at,
                            field: "sweep.tolerances".into(),
                            name: format!("{value:e}"),
                        });
                    }
                    out.push(value);
                }
                out
            }
            None => defaults.tolerances,
        };
        let max_steps = match raw.max_steps {
            Some(n) => {
                let at = self.at(&n.span());
                match usize::try_from(n.into_inner()) {
                    Ok(n) if n > 0 => Some(n),
                    _ => {
                        return Err(SceneError::InvalidValue {
                            at,
                            field: "sweep.max_steps".into(),
                            reason: "must be a positive whole number of steps".into(),
                        })
                    }
                }
            }
            None => None,
        };
        Ok(Sweep {
            solvers,
            formulations,
            tolerances,
            max_steps,
        })
    }
}

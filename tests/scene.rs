//! Scene files (`dae::scene`): the built-in scenarios, check-time
//! generation, model path resolution, and every validation error with the
//! field and line it names.

use dae::scene::{
    CheckRule, ModelSource, ReferenceSpec, Scene, SceneError, Sweep, DEFAULT_TOLERANCES,
    KNOWN_FORMULATIONS, KNOWN_SOLVERS, MAX_CHECK_TIMES,
};
use std::path::{Path, PathBuf};

#[allow(clippy::excessive_precision)] // the paper's digits, as written in the scene files
const G: f64 = 13.750_371_637_329_454_4;

/// A valid scene; the tests below break one line at a time.
const BASE: &str = r#"name = "T"
model = "pendulum"
[parameters]
g = 9.81
l = 2.0
[initial]
x = 2.0
y = 0.0
v = 0.0
w = 0.0
[time]
end = 20.0
check = [10.0, 20.0]
[reference]
kind = "pendulum-exact"
[sweep]
solvers = ["radau5"]
formulations = ["ori2", "ggl1"]
tolerances = [1e-6, 1e-8]
"#;

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, "t.toml", None)
}

/// `BASE` with line `line` (1-based) replaced by `new` (which may hold
/// several lines, or be empty to delete the line).
fn with_line(line: usize, new: &str) -> String {
    let mut lines: Vec<&str> = BASE.lines().collect();
    assert!(line >= 1 && line <= lines.len());
    if new.is_empty() {
        lines.remove(line - 1);
    } else {
        lines[line - 1] = new;
    }
    lines.join("\n") + "\n"
}

/// Parse, expect an error, and check that its message names `field` and
/// the place `t.toml:LINE:`.
fn expect_err(text: &str, field: &str, line: usize) -> SceneError {
    let err = match parse(text) {
        Ok(_) => panic!("expected an error for `{field}` on line {line}:\n{text}"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(msg.contains(field), "message should name `{field}`: {msg}");
    assert!(
        msg.starts_with(&format!("t.toml:{line}:")),
        "message should point at line {line}: {msg}"
    );
    err
}

#[test]
fn base_scene_parses() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.name, "T");
    assert_eq!(s.model, ModelSource::Builtin("pendulum".into()));
    assert_eq!(s.parameter("g"), Some(9.81));
    assert_eq!(s.parameter("l"), Some(2.0));
    assert_eq!(s.initial_value("x"), Some(2.0));
    assert_eq!(s.time.start, 0.0);
    assert_eq!(s.time.end, 20.0);
    assert_eq!(s.time.checks, vec![10.0, 20.0]);
    assert_eq!(s.time.rule, CheckRule::List);
    assert_eq!(
        s.reference,
        ReferenceSpec::Exact {
            closed_form: "pendulum".into()
        }
    );
    assert_eq!(s.sweep.solvers, vec!["radau5"]);
    assert_eq!(s.sweep.formulations, vec!["ori2", "ggl1"]);
    assert_eq!(s.sweep.tolerances, vec![1e-6, 1e-8]);
    // Lines and columns of the keys are kept.
    let g = &s.parameters[0];
    assert_eq!((g.name.as_str(), g.line, g.column), ("g", 4, 1));
    assert_eq!(s.initial[3].line, 10);
}

#[test]
fn entries_keep_file_order() {
    let text = BASE.replace(
        "x = 2.0\ny = 0.0\nv = 0.0\nw = 0.0",
        "w = 0.0\nv = 0.0\ny = 0.0\nx = 2.0",
    );
    let s = parse(&text).unwrap();
    let names: Vec<&str> = s.initial.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["w", "v", "y", "x"]);
    let names: Vec<&str> = s.parameters.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["g", "l"]);
}

#[test]
fn defaults() {
    let text = "name = \"d\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\nend = 5\n";
    let s = parse(text).unwrap();
    assert!(s.parameters.is_empty());
    assert_eq!(s.initial_value("x"), Some(1.0)); // integers are numbers too
    assert_eq!((s.time.start, s.time.end), (0.0, 5.0));
    assert_eq!(s.time.checks, vec![5.0]);
    assert_eq!(s.time.rule, CheckRule::EndOnly);
    assert_eq!(s.reference, ReferenceSpec::None);
    assert_eq!(s.sweep, Sweep::default());
    assert_eq!(s.sweep.solvers, KNOWN_SOLVERS);
    assert_eq!(
        s.sweep.formulations,
        ["ori2", "rcd1", "rcd0", "ovd1", "ovd0", "ggl1", "psi1", "psi0", "mex0"]
    );
    assert_eq!(s.sweep.tolerances, DEFAULT_TOLERANCES);
    assert_eq!(
        DEFAULT_TOLERANCES,
        [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
    );
    // A partial [sweep] keeps the defaults for what it leaves out.
    let s = parse(&format!("{text}[sweep]\nsolvers = [\"bdf\"]\n")).unwrap();
    assert_eq!(s.sweep.solvers, ["bdf"]);
    assert_eq!(s.sweep.formulations, KNOWN_FORMULATIONS);
    // An explicit start; "none" reference.
    let s = parse(&text.replace("end = 5", "start = 1.5\nend = 5")).unwrap();
    assert_eq!((s.time.start, s.time.checks.as_slice()), (1.5, &[5.0][..]));
    let s = parse(&format!("{text}[reference]\nkind = \"none\"\n")).unwrap();
    assert_eq!(s.reference, ReferenceSpec::None);
}

#[test]
fn builtins_are_the_shipped_files() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in ["s01", "s02"] {
        let path = dir.join(format!("{name}.toml"));
        let mut from_file = Scene::load(&path).unwrap();
        let builtin = Scene::builtin(name).unwrap();
        assert_eq!(from_file.origin, path.display().to_string());
        assert_eq!(builtin.origin, format!("<built-in {name}>"));
        from_file.origin = builtin.origin.clone();
        assert_eq!(from_file, builtin, "{name}");
        assert_eq!(
            Scene::builtin(&name.to_uppercase()).as_ref(),
            Some(&builtin)
        );
    }
}

#[test]
fn builtins_are_the_papers_scenarios() {
    for (name, end) in [("s01", 20.0), ("s02", 2000.0)] {
        let s = Scene::builtin(name).unwrap();
        assert_eq!(s.name, name.to_uppercase());
        assert_eq!(s.model, ModelSource::Builtin("pendulum".into()));
        assert_eq!(s.parameter("g"), Some(G));
        assert_eq!(s.parameter("m"), Some(1.0));
        assert_eq!(s.parameter("l"), Some(1.0));
        let init: Vec<(&str, f64)> = s
            .initial
            .iter()
            .map(|e| (e.name.as_str(), e.value))
            .collect();
        assert_eq!(init, [("x", 1.0), ("y", 0.0), ("v", 0.0), ("w", 0.0)]);
        assert_eq!((s.time.start, s.time.end), (0.0, end));
        assert_eq!(
            s.reference,
            ReferenceSpec::Exact {
                closed_form: "pendulum".into()
            }
        );
        assert_eq!(s.sweep, Sweep::default());
        assert!(s
            .check_names(&["x", "y", "v", "w", "lambda"], &["m", "l", "g"])
            .is_ok());
    }
    assert_eq!(Scene::builtin("s01").unwrap().time.checks, vec![20.0]);
    let s02 = Scene::builtin("s02").unwrap();
    assert_eq!(s02.time.rule, CheckRule::Every(2.0));
    assert_eq!(s02.time.checks.len(), 1000);
    for (k, &t) in s02.time.checks.iter().enumerate() {
        assert_eq!(t, 2.0 * (k as f64 + 1.0));
    }
    assert_eq!(s02.time.checks.last(), Some(&2000.0));
    assert!(Scene::builtin("s03").is_none());
}

#[test]
fn check_every_generation() {
    let text = |time: &str| {
        format!("name = \"c\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n[time]\n{time}\n")
    };
    // Rounding: 3·0.1 > 0.3 in floating point, yet t = 0.3 is a check time.
    let s = parse(&text("end = 0.3\ncheck_every = 0.1")).unwrap();
    assert_eq!(s.time.checks.len(), 3);
    assert_eq!(s.time.checks.last(), Some(&0.3));
    // From a non-zero start; the end is not added when not on the grid.
    let s = parse(&text("start = 1.0\nend = 2.0\ncheck_every = 0.3")).unwrap();
    assert_eq!(s.time.checks.len(), 3);
    assert!((s.time.checks[2] - 1.9).abs() < 1e-15);
    // Long horizons: 2·10⁴ s every 2 s.
    let s = parse(&text("end = 20000\ncheck_every = 2")).unwrap();
    assert_eq!(s.time.checks.len(), 10_000);
    assert_eq!(s.time.checks[9_999], 20_000.0);
    // Errors.
    let err = expect_err(&text("end = 1\ncheck_every = 0"), "time.check_every", 7);
    assert!(matches!(err, SceneError::InvalidValue { .. }), "{err}");
    expect_err(&text("end = 1\ncheck_every = -2"), "time.check_every", 7);
    expect_err(&text("end = 1\ncheck_every = 5"), "time.check_every", 7);
    expect_err(&text("end = 1\ncheck_every = nan"), "time.check_every", 7);
    let err = expect_err(
        &text("end = 1e6\ncheck_every = 1e-300"),
        "time.check_every",
        7,
    );
    assert!(
        matches!(err, SceneError::TooManyCheckTimes { max, .. } if max == MAX_CHECK_TIMES),
        "{err}"
    );
    let err = expect_err(
        &text("end = 10\ncheck = [5.0]\ncheck_every = 2"),
        "time.check",
        8,
    );
    assert!(matches!(err, SceneError::CheckConflict { .. }), "{err}");
}

#[test]
fn bad_toml() {
    let err = expect_err(&with_line(1, "name = \"T"), "invalid TOML", 1);
    assert!(matches!(err, SceneError::Syntax { .. }), "{err}");
    let err = expect_err(&with_line(12, "end = = 20"), "invalid TOML", 12);
    assert!(matches!(err, SceneError::Syntax { .. }), "{err}");
    // A duplicated key is a TOML error too.
    let err = expect_err(&with_line(8, "x = 3.0"), "invalid TOML", 8);
    assert!(matches!(err, SceneError::Syntax { .. }), "{err}");
}

#[test]
fn wrong_types_name_the_field() {
    let err = expect_err(&with_line(12, "end = \"20\""), "time.end", 12);
    assert!(matches!(err, SceneError::InvalidType { .. }), "{err}");
    let err = expect_err(&with_line(9, "v = \"fast\""), "initial.v", 9);
    assert!(matches!(err, SceneError::InvalidType { .. }), "{err}");
    expect_err(&with_line(19, "tolerances = 1e-6"), "sweep.tolerances", 19);
    expect_err(&with_line(2, "model = 3"), "model", 2);
}

#[test]
fn missing_fields() {
    for (line, field) in [(1, "name"), (2, "model")] {
        let err = expect_err(&with_line(line, ""), &format!("missing field `{field}`"), 1);
        assert!(matches!(err, SceneError::MissingField { .. }), "{err}");
    }
    // time.end: reported at the [time] table.
    let err = expect_err(
        &with_line(12, "start = 0.0"),
        "missing field `time.end`",
        11,
    );
    assert!(matches!(err, SceneError::MissingField { .. }), "{err}");
    // Whole tables.
    let no_initial = BASE.replace("[initial]\nx = 2.0\ny = 0.0\nv = 0.0\nw = 0.0\n", "");
    expect_err(&no_initial, "missing field `initial`", 1);
    let no_time = BASE.replace("[time]\nend = 20.0\ncheck = [10.0, 20.0]\n", "");
    expect_err(&no_time, "missing field `time`", 1);
    expect_err(&with_line(15, "kinds = \"none\""), "reference.kinds", 15);
    let empty_initial = BASE.replace("x = 2.0\ny = 0.0\nv = 0.0\nw = 0.0\n", "");
    expect_err(&empty_initial, "initial", 6);
}

#[test]
fn unknown_fields() {
    let err = expect_err(&with_line(1, "nmae = \"T\""), "unknown field `nmae`", 1);
    assert!(matches!(err, SceneError::UnknownField { .. }), "{err}");
    let err = expect_err(
        &with_line(12, "ends = 20.0"),
        "unknown field `time.ends`",
        12,
    );
    assert!(
        err.to_string().contains("check_every"),
        "lists the allowed fields: {err}"
    );
    expect_err(
        &with_line(17, "solver = [\"bdf\"]"),
        "unknown field `sweep.solver`",
        17,
    );
    expect_err(&with_line(14, "[refrence]"), "unknown field `refrence`", 14);
}

#[test]
fn bad_tolerances() {
    for (value, shown) in [
        ("nan", "NaN"),
        ("inf", "inf"),
        ("-1e-6", "-1e-6"),
        ("0.0", "0e0"),
        ("1.5", "1.5e0"),
        // The library's rule, shared with --tol: not 1, not below 100 ε.
        ("1.0", "1e0"),
        ("1e-16", "1e-16"),
    ] {
        let err = expect_err(
            &with_line(19, &format!("tolerances = [1e-6, {value}]")),
            "sweep.tolerances",
            19,
        );
        assert!(
            matches!(err, SceneError::InvalidTolerance { .. }),
            "{value}: {err}"
        );
        assert!(err.to_string().contains(shown), "{value}: {err}");
        // The column points at the offending entry.
        assert!(err.to_string().starts_with("t.toml:19:21:"), "{err}");
    }
    let err = expect_err(
        &with_line(19, "tolerances = [1e-6, 1e-6]"),
        "sweep.tolerances",
        19,
    );
    assert!(matches!(err, SceneError::Duplicate { .. }), "{err}");
    expect_err(&with_line(19, "tolerances = []"), "sweep.tolerances", 19);
}

#[test]
fn bad_horizons_and_check_times() {
    let err = expect_err(&with_line(12, "end = 0.0"), "time.end", 12);
    assert!(matches!(err, SceneError::EmptyHorizon { .. }), "{err}");
    let err = expect_err(&with_line(12, "start = 30.0\nend = 20.0"), "time.end", 13);
    assert!(matches!(err, SceneError::EmptyHorizon { .. }), "{err}");
    let err = expect_err(&with_line(12, "end = -1.0"), "time.end", 12);
    assert!(matches!(err, SceneError::EmptyHorizon { .. }), "{err}");
    let err = expect_err(&with_line(12, "end = inf"), "time.end", 12);
    assert!(matches!(err, SceneError::NotFinite { .. }), "{err}");
    let err = expect_err(&with_line(13, "check = [10.0, 25.0]"), "time.check", 13);
    assert!(
        matches!(err, SceneError::CheckOutsideHorizon { time, .. } if time == 25.0),
        "{err}"
    );
    assert!(err.to_string().starts_with("t.toml:13:16:"), "{err}");
    expect_err(&with_line(13, "check = [-1.0]"), "time.check", 13);
    let err = expect_err(&with_line(13, "check = [20.0, 10.0]"), "time.check", 13);
    assert!(
        matches!(err, SceneError::CheckNotIncreasing { .. }),
        "{err}"
    );
    expect_err(&with_line(13, "check = [5.0, 5.0]"), "time.check", 13);
    expect_err(&with_line(13, "check = [nan]"), "time.check", 13);
    expect_err(&with_line(13, "check = []"), "time.check", 13);
    // Multi-line arrays: the line of the entry, not of the key.
    let err = expect_err(
        &with_line(13, "check = [\n  10.0,\n  99.0,\n]"),
        "time.check",
        15,
    );
    assert!(
        matches!(err, SceneError::CheckOutsideHorizon { .. }),
        "{err}"
    );
}

#[test]
fn unknown_reference_kind() {
    let err = expect_err(&with_line(15, "kind = \"analytic\""), "reference.kind", 15);
    assert!(
        matches!(err, SceneError::UnknownReference { ref kind, .. } if kind == "analytic"),
        "{err}"
    );
    assert!(
        err.to_string().contains("exact, values, trajectory, none"),
        "lists the known kinds: {err}"
    );
}

#[test]
fn non_finite_values() {
    let err = expect_err(&with_line(7, "x = nan"), "initial.x", 7);
    assert!(matches!(err, SceneError::NotFinite { .. }), "{err}");
    let err = expect_err(&with_line(4, "g = inf"), "parameters.g", 4);
    assert!(matches!(err, SceneError::NotFinite { .. }), "{err}");
    expect_err(&with_line(5, "l = -inf"), "parameters.l", 5);
}

/// Finite but absurd: magnitudes above 1e150 overflow when squared or
/// multiplied (an `x = 1e308` start hung the exact reference).
#[test]
fn absurdly_large_values_name_the_field() {
    for (line, text, field) in [
        (7, "x = 1e308", "initial.x"),
        (8, "y = -1e151", "initial.y"),
        (4, "g = 1e200", "parameters.g"),
        (12, "end = 1e300", "time.end"),
        (12, "start = -1e200\nend = 1.0", "time.start"),
        (13, "check_every = 1e160", "time.check_every"),
    ] {
        let err = expect_err(&with_line(line, text), field, line);
        assert!(matches!(err, SceneError::TooLarge { .. }), "{err}");
        assert!(err.to_string().contains("1e150"), "{err}");
    }
    // The bound itself is accepted.
    assert!(parse(&with_line(4, "g = 1e150")).is_ok());
}

#[test]
fn fields_are_located_after_parsing() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.locate("initial.y").to_string(), "t.toml:8:1");
    assert_eq!(s.locate("parameters.l").to_string(), "t.toml:5:1");
    assert_eq!(s.locate("time.end").to_string(), "t.toml:12:7");
    assert_eq!(s.locate("model").to_string(), "t.toml:2:9");
    // Not in the file: its table, else `reference.kind`.
    assert_eq!(
        s.locate("time.start").to_string(),
        s.locate("time").to_string()
    );
    assert_eq!(s.locate("parameters.m").to_string(), "t.toml:15:8");
}

#[test]
fn unknown_solver_or_formulation() {
    let err = expect_err(
        &with_line(17, "solvers = [\"radau5\", \"dassl\"]"),
        "sweep.solvers",
        17,
    );
    assert!(
        matches!(err, SceneError::UnknownSolver { ref name, .. } if name == "dassl"),
        "{err}"
    );
    assert!(
        err.to_string().contains("radau5, bdf"),
        "lists the known solvers: {err}"
    );
    let err = expect_err(
        &with_line(18, "formulations = [\"ori3\"]"),
        "sweep.formulations",
        18,
    );
    assert!(
        matches!(err, SceneError::UnknownFormulation { ref name, .. } if name == "ori3"),
        "{err}"
    );
    assert!(err.to_string().contains("psi0"), "{err}");
    let err = expect_err(
        &with_line(17, "solvers = [\"bdf\", \"bdf\"]"),
        "sweep.solvers",
        17,
    );
    assert!(matches!(err, SceneError::Duplicate { .. }), "{err}");
    expect_err(&with_line(17, "solvers = []"), "sweep.solvers", 17);
}

#[test]
fn names_checked_against_the_model() {
    let s = parse(BASE).unwrap();
    let vars = ["x", "y", "v", "w", "lambda"];
    let params = ["m", "l", "g"];
    assert!(s.check_names(&vars, &params).is_ok());
    let err = s.check_names(&["x", "y", "v"], &params).unwrap_err();
    assert!(
        matches!(err, SceneError::UnknownVariable { ref name, .. } if name == "w"),
        "{err}"
    );
    assert!(
        err.to_string().starts_with("t.toml:10:1: `initial.w`"),
        "{err}"
    );
    assert!(
        err.to_string().contains("x, y, v"),
        "lists the model's variables: {err}"
    );
    let err = s.check_names(&vars, &["m", "g"]).unwrap_err();
    assert!(
        matches!(err, SceneError::UnknownParameter { ref name, .. } if name == "l"),
        "{err}"
    );
    assert!(
        err.to_string().starts_with("t.toml:5:1: `parameters.l`"),
        "{err}"
    );
}

/// A fresh directory under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("dae-scene-test-{}-{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn model_paths_resolve_against_the_scene_directory() {
    let tmp = TempDir::new("models");
    std::fs::create_dir_all(tmp.0.join("models")).unwrap();
    std::fs::write(tmp.0.join("models/double.dae"), "// a model\n").unwrap();
    let scene = tmp.0.join("scene.toml");
    std::fs::write(
        &scene,
        BASE.replace("model = \"pendulum\"", "model = \"models/double.dae\""),
    )
    .unwrap();
    let s = Scene::load(&scene).unwrap();
    assert_eq!(s.model, ModelSource::File(tmp.0.join("models/double.dae")));
    assert_eq!(s.origin, scene.display().to_string());

    // A missing model file is reported with the line of `model`.
    std::fs::write(
        &scene,
        BASE.replace("model = \"pendulum\"", "model = \"nope.dae\""),
    )
    .unwrap();
    let err = Scene::load(&scene).unwrap_err();
    assert!(
        matches!(err, SceneError::ModelNotFound { ref path, .. } if *path == tmp.0.join("nope.dae")),
        "{err}"
    );
    assert!(
        err.to_string()
            .starts_with(&format!("{}:2:9:", scene.display())),
        "{err}"
    );

    // Errors in a file name the file.
    std::fs::write(&scene, with_line(12, "end = -5")).unwrap();
    let err = Scene::load(&scene).unwrap_err();
    assert!(
        err.to_string()
            .starts_with(&format!("{}:12:7:", scene.display())),
        "{err}"
    );
}

#[test]
fn load_files_builtins_and_io_errors() {
    assert_eq!(Scene::load("s01").unwrap(), Scene::builtin("s01").unwrap());
    assert_eq!(Scene::load("S02").unwrap().time.checks.len(), 1000);
    let err = Scene::load("no/such/scene.toml").unwrap_err();
    assert!(matches!(err, SceneError::NotFound { .. }), "{err}");
    assert!(
        err.to_string().contains("no/such/scene.toml") && err.to_string().contains("s01, s02"),
        "{err}"
    );
    // A directory exists but cannot be read as a file: a typed IO error with the path.
    let tmp = TempDir::new("io");
    let err = Scene::load(&tmp.0).unwrap_err();
    assert!(
        matches!(err, SceneError::Io { ref path, .. } if *path == tmp.0),
        "{err}"
    );
    assert!(
        err.to_string().contains(&tmp.0.display().to_string()),
        "{err}"
    );
}

#[test]
fn scene_serialises_to_json() {
    let json = serde_json::to_value(Scene::builtin("s01").unwrap()).unwrap();
    assert_eq!(json["name"], "S01");
    assert_eq!(json["time"]["checks"][0], 20.0);
    assert_eq!(json["reference"]["kind"], "exact");
    assert_eq!(json["reference"]["closed_form"], "pendulum");
}

/// `[sweep] max_steps` bounds every run; anything but a positive whole
/// number is refused at its place.
#[test]
fn sweep_max_steps() {
    let s = parse(&format!("{BASE}max_steps = 2000000\n")).unwrap();
    assert_eq!(s.sweep.max_steps, Some(2_000_000));
    assert_eq!(parse(BASE).unwrap().sweep.max_steps, None);
    for bad in ["0", "-5"] {
        let err = expect_err(&format!("{BASE}max_steps = {bad}\n"), "sweep.max_steps", 20);
        assert!(err.to_string().contains("positive whole number"), "{err}");
    }
    for bad in ["1.5", "\"many\""] {
        expect_err(&format!("{BASE}max_steps = {bad}\n"), "sweep.max_steps", 20);
    }
}

/// A mistyped solver or formulation gets the closest known name.
#[test]
fn unknown_names_suggest_the_closest_known_one() {
    let err = expect_err(
        &with_line(17, "solvers = [\"radua5\"]"),
        "sweep.solvers",
        17,
    );
    assert!(
        matches!(err, SceneError::UnknownSolver { .. })
            && err.suggestion().as_deref() == Some("radau5"),
        "{err}"
    );
    assert!(err.to_string().contains("did you mean `radau5`?"), "{err}");
    let err = expect_err(
        &with_line(18, "formulations = [\"ggl\"]"),
        "sweep.formulations",
        18,
    );
    assert!(err.to_string().contains("did you mean `ggl1`?"), "{err}");
    // Nothing close: the list only.
    let err = expect_err(&with_line(17, "solvers = [\"dassl\"]"), "sweep.solvers", 17);
    assert!(!err.to_string().contains("did you mean"), "{err}");
    // Variables and parameters too.
    let s = parse(&with_line(4, "gravity = 9.81")).unwrap();
    let err = s
        .check_names(&["x", "y", "v", "w"], &["m", "l", "gravty"])
        .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("t.toml:4:1: `parameters.gravity`: the model has no parameter `gravity`; did you mean `gravty`?"),
        "{err}"
    );
    // A one-letter name is never "close": every other one is one edit away.
    let s = parse(BASE).unwrap();
    let err = s
        .check_names(&["x", "yy", "v", "w"], &["m", "l", "g"])
        .unwrap_err();
    assert!(!err.to_string().contains("did you mean"), "{err}");
    let err = s
        .check_names(&["x", "y", "v", "w"], &["m", "len", "g"])
        .unwrap_err();
    assert!(!err.to_string().contains("did you mean"), "{err}");
}

/// `[tolerance]`: numbers or per-unknown tables, each value by the
/// library's rule, located when refused; names checked against the model.
#[test]
fn tolerance_section() {
    use dae::scene::TolSpec;
    let s = parse(BASE).unwrap();
    assert_eq!(
        (s.tolerance.rtol.clone(), s.tolerance.atol.clone()),
        (None, None)
    );
    let s = parse(&format!(
        "{BASE}[tolerance]\nrtol = 1e-6\natol = {{ x = 1e-9, lamda = 0 }}\n"
    ))
    .unwrap();
    assert_eq!(s.tolerance.rtol, Some(TolSpec::Uniform(1e-6)));
    let Some(TolSpec::PerUnknown(list)) = &s.tolerance.atol else {
        panic!("{:?}", s.tolerance.atol)
    };
    let named: Vec<(&str, f64, usize, usize)> = list
        .iter()
        .map(|e| (e.name.as_str(), e.value, e.line, e.column))
        .collect();
    assert_eq!(named, [("x", 1e-9, 22, 10), ("lamda", 0.0, 22, 20)]);
    let vars = ["x", "y", "v", "w", "lambda"];
    let err = s.check_names(&vars, &["m", "l", "g"]).unwrap_err();
    assert!(
        matches!(err, SceneError::UnknownVariable { section, .. } if section == "tolerance.atol"),
        "{err}"
    );
    assert!(
        err.to_string().starts_with(
            "t.toml:22:20: `tolerance.atol.lamda`: the model has no variable `lamda`; did you mean `lambda`?"
        ),
        "{err}"
    );
    // Integers are numbers.
    let s = parse(&format!("{BASE}[tolerance]\natol = 0\nrtol = 1e-8\n")).unwrap();
    assert_eq!(s.tolerance.atol, Some(TolSpec::Uniform(0.0)));
    for (line, field) in [
        ("rtol = 1e-16", "tolerance.rtol"),
        ("rtol = 1.0", "tolerance.rtol"),
        ("rtol = -1e-6", "tolerance.rtol"),
        ("atol = -1e-6", "tolerance.atol"),
        ("atol = nan", "tolerance.atol"),
        ("atol = { x = -1.0 }", "tolerance.atol.x"),
        ("rtol = { x = 2.0 }", "tolerance.rtol.x"),
        ("atol = { x = 1e-6, x = 1e-7 }", "duplicate key"),
        ("atol = {}", "tolerance.atol"),
        ("atol = \"small\"", "tolerance.atol"),
        ("tol = 1e-8", "tolerance.tol"),
    ] {
        expect_err(&format!("{BASE}[tolerance]\n{line}\n"), field, 21);
    }
}

/// `[guess]`: optional, in file order, located, checked against the
/// model's unknowns like `[initial]`, and never for a value `[initial]`
/// fixes.
#[test]
fn guesses_parse_with_places_and_are_checked() {
    let s = parse(BASE).unwrap();
    assert!(s.guess.is_empty() && s.guess_values().is_empty());
    let text = with_line(10, "w = 0.0\n[guess]\nlambda = -3.5\nlamda = 1");
    let s = parse(&text).unwrap();
    assert_eq!(
        s.guess_values(),
        [("lambda".to_string(), -3.5), ("lamda".to_string(), 1.0)]
    );
    assert_eq!(s.locate("guess.lambda").to_string(), "t.toml:12:1");
    let vars = ["x", "y", "v", "w", "lambda"];
    let err = s.check_names(&vars, &["m", "l", "g"]).unwrap_err();
    assert!(
        matches!(&err, SceneError::UnknownVariable { section: "guess", name, .. } if name == "lamda"),
        "{err}"
    );
    assert!(
        err.to_string().starts_with("t.toml:13:1: `guess.lamda`"),
        "{err}"
    );
    assert_eq!(err.suggestion().as_deref(), Some("lambda"));
    assert!(err.to_string().contains("did you mean `lambda`?"), "{err}");
    // Not finite, not a number: the field and its line.
    expect_err(
        &with_line(10, "w = 0.0\n[guess]\nlambda = nan"),
        "guess.lambda",
        12,
    );
    expect_err(
        &with_line(10, "w = 0.0\n[guess]\nlambda = \"a\""),
        "guess",
        12,
    );
    // A value [initial] fixes cannot be guessed too.
    let err = expect_err(
        &with_line(10, "w = 0.0\n[guess]\nlambda = 1\nx = 2.5"),
        "guess.x",
        13,
    );
    assert!(err.to_string().contains("fixed by [initial]"), "{err}");
}

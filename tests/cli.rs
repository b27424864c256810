//! The `dae` binary end to end: `derive` and `run` contracts, exit codes,
//! error messages with positions, determinism.

use std::io::Write;
use std::process::{Command, Output};

fn dae(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dae"))
        .args(args)
        .output()
        .expect("the dae binary runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn temp_file(name: &str, text: &str) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::File::create(&path)
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let p = path.display().to_string();
    (dir, p)
}

#[test]
fn derive_json_is_deterministic_and_has_the_contract_shape() {
    let a = dae(&["derive", "--format", "json"]);
    let b = dae(&["derive", "--format", "json"]);
    assert!(a.status.success(), "{}", stderr(&a));
    assert_eq!(a.stdout, b.stdout, "two runs must be byte-identical");
    let v: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    for k in [
        "model",
        "variables",
        "parameters",
        "constraints",
        "invariants",
        "formulations",
    ] {
        assert!(keys.contains(&k), "missing {k}");
    }
    assert_eq!(v["model"], "Pendulum");
    assert_eq!(v["variables"][4]["kind"], "algebraic");
    assert_eq!(v["constraints"][1]["expr"], "2*x*v + 2*y*w");
    assert_eq!(v["constraints"][2]["level"], 2);
    let f = &v["formulations"];
    assert_eq!(f.as_array().unwrap().len(), 9);
    let ovd0 = f
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["name"] == "ovd0")
        .unwrap();
    assert_eq!(ovd0["equations"], 7);
    assert!(ovd0["d_index"].is_null());
    assert_eq!(ovd0["algebraic_equations"], 3);
    // The JSON text keeps the contract's field order.
    let text = stdout(&a);
    let pos = |k: &str| text.find(&format!("\"{k}\"")).unwrap();
    assert!(pos("model") < pos("variables") && pos("variables") < pos("parameters"));
    assert!(pos("constraints") < pos("invariants") && pos("invariants") < pos("formulations"));
}

#[test]
fn derive_text_and_latex_render_files() {
    for fmt in ["text", "latex"] {
        let o = dae(&["derive", "scenes/double_pendulum.dae", "--format", fmt]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stdout(&o).contains("lambda2") || stdout(&o).contains("\\lambda_{2}"));
    }
}

#[test]
fn bad_model_files_report_line_and_column_and_exit_2() {
    let cases = [
        ("pub M {\n  differential { x }\n  equations { der(x) = q; }\n}\n", "3:24", "unknown name `q`"),
        ("pub M {\n  differential { x }\n  algebraic { z }\n  equations { der(z) = x; 0 = x; }\n}\n", "4:19", "algebraic"),
        ("pub M {\n  parameters { k = abc }\n  differential { x }\n  equations { der(x) = x; }\n}\n", "2:20", "must be a numeric literal"),
        ("pub M {\n  differential { x }\n  equations { der(x) = sinh(x); }\n}\n", "3:24", "unknown function"),
        ("pub M {}\n", "1:5", "empty"),
        // A lexical error is one line at its place, not proc_macro2's
        // placeless "cannot parse string into token stream".
        ("pub M {\n  differential { x }\n  equations { der(x) = (x; }\n}\n", "3:28", "does not close the `(` opened at 3:24"),
    ];
    for (text, at, msg) in cases {
        let (_dir, path) = temp_file("bad.dae", text);
        let o = dae(&["derive", &path]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{text}: {err}");
        assert!(err.contains(msg), "{text}: expected `{msg}` in {err}");
        assert!(
            err.contains(&format!("{path}:{at}")),
            "{text}: expected position {at} in {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
    let o = dae(&["derive", "no/such/file.dae"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("cannot read model file"));
}

#[test]
fn garbage_never_panics() {
    let inputs = [
        "", "{", "}", "pub", "pub M", "pub M {", "pub M { differential }", "pub M { equations { = ; } }",
        "pub M { differential { x } equations { der(x) = x^^2; } }", "\u{0}\u{1}", "pub M { differential { x, } equations { der(x) = 1/0; } }",
        "pub M { differential { x } equations { der(x) = x; 0 = 0; } }", "#[derive] pub M {}",
        "pub M { differential { x } algebraic { z } equations { der(x) = z; 0 = x; } formulations { } }",
    ];
    for text in inputs {
        let (_dir, path) = temp_file("g.dae", text);
        let o = dae(&["derive", &path, "--format", "json"]);
        assert_eq!(o.status.code(), Some(2), "{text:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{text:?}: {}", stderr(&o));
    }
}

#[test]
fn run_honours_the_json_contract() {
    let o = dae(&[
        "run",
        "s01",
        "--solver",
        "radau5",
        "--formulation",
        "rcd0",
        "--tol",
        "1e-7",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in [
        "scene",
        "solver",
        "formulation",
        "tol",
        "status",
        "error",
        "t_end",
        "final",
        "err",
        "err_sum",
        "err_l2",
        "err_algebraic",
        "scd",
        "accuracy",
        "accuracy_note",
        "tsim_s",
        "stats",
        "residuals",
        "invariant_drift",
    ] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert_eq!(v["accuracy"], "accurate", "{v}");
    assert_eq!(v["status"], "ok");
    assert!(v["error"].is_null());
    assert_eq!(v["t_end"], 20.0);
    assert!(v["err"].as_f64().unwrap() < 1e-3);
    for k in [
        "steps",
        "rejected",
        "residual_evals",
        "jacobian_evals",
        "factorizations",
        "newton_iterations",
    ] {
        assert!(v["stats"][k].as_u64().is_some(), "stats.{k}");
    }
    for k in ["level0", "level1", "level2"] {
        assert!(v["residuals"][k].as_f64().is_some(), "residuals.{k}");
    }
    assert!(v["invariant_drift"]["energy"].as_f64().is_some());
    assert!(v["final"]["lambda"].as_f64().is_some());
}

#[test]
fn run_rejects_bad_flags_with_exit_2() {
    for args in [
        &["run", "--tol", "-1"][..],
        &["run", "--tol", "NaN"],
        &["run", "--tol", "0"],
        &["run", "--solver", "euler"],
        &["run", "--formulation", "xyz"],
        &["run", "--solver", "radau5", "--formulation", "ovd0"],
        &["run", "no-such-scene"],
        &["run", "--estimate", "richardson"],
    ] {
        let o = dae(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).is_empty());
    }
}

#[test]
fn malformed_scene_files_exit_2_naming_the_field_and_line() {
    let good = "name = \"T\"\nmodel = \"pendulum\"\n[initial]\nx = 1.0\ny = 0.0\nv = 0.0\nw = 0.0\n[time]\nend = 1.0\n[reference]\nkind = \"none\"\n";
    let cases = [
        (good.replace("model = \"pendulum\"\n", ""), "model"),
        (
            good.replace("[initial]\nx = 1.0", "[initial]\nq = 1.0"),
            "q",
        ),
        (
            good.replace("end = 1.0", "end = 1.0\n[sweep]\nsolvers = [\"euler\"]"),
            "euler",
        ),
        (
            good.replace("end = 1.0", "end = 1.0\n[sweep]\nformulations = [\"abc\"]"),
            "abc",
        ),
        (
            good.replace("end = 1.0", "end = 1.0\n[sweep]\ntolerances = [nan]"),
            "tolerances",
        ),
        (
            good.replace("end = 1.0", "end = 1.0\n[sweep]\ntolerances = [-1e-6]"),
            "tolerances",
        ),
        (good.replace("name = \"T\"", "name = \"T"), "TOML"),
    ];
    for (text, needle) in cases {
        let (_dir, path) = temp_file("scene.toml", &text);
        let o = dae(&["run", &path]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{text}: {err}");
        assert!(err.contains(needle), "expected `{needle}` in: {err}");
        assert!(err.contains(&path), "expected the file name in: {err}");
    }
    // The good one runs.
    let (_dir, path) = temp_file("scene.toml", good);
    let o = dae(&["run", &path, "--solver", "radau5", "--formulation", "rcd0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// A scene in `dir` whose solution `x' = x², x(0) = 1` blows up at t = 1,
/// before its end t = 2 (every solver fails); `extra` is appended to the
/// scene file. Returns the scene's path.
fn blowup_scene(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    std::fs::write(
        dir.join("blowup.dae"),
        "pub Blowup {\n  differential { x }\n  equations { der(x) = x^2; }\n}\n",
    )
    .unwrap();
    let scene = dir.join("blowup.toml");
    std::fs::write(
        &scene,
        format!(
            "name = \"blowup\"\nmodel = \"blowup.dae\"\n[initial]\nx = 1.0\n[time]\nend = 2.0\n{extra}"
        ),
    )
    .unwrap();
    scene
}

#[test]
fn solver_failure_prints_json_and_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    let scene = blowup_scene(dir.path(), "[reference]\nkind = \"none\"\n");
    for solver in ["radau5", "bdf"] {
        let o = dae(&[
            "run",
            scene.to_str().unwrap(),
            "--solver",
            solver,
            "--formulation",
            "ori2",
        ]);
        assert_eq!(o.status.code(), Some(3), "{solver}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["status"], "error");
        assert_eq!(v["error"]["kind"], "step_size_too_small", "{solver}: {v}");
        let t = v["error"]["t"].as_f64().unwrap();
        assert!(
            (0.9..1.01).contains(&t),
            "{solver}: blow-up at t = 1, stopped at {t}"
        );
        assert!(v["err"].is_null());
    }
}

#[test]
fn inconsistent_start_is_projected_or_refused() {
    let scene = "name = \"off\"\nmodel = \"pendulum\"\n[initial]\nx = 1.1\ny = 0.0\nv = 0.0\nw = 0.0\n[time]\nend = 1.0\n[reference]\nkind = \"none\"\n";
    let (_dir, path) = temp_file("off.toml", scene);
    let o = dae(&["run", &path, "--solver", "radau5", "--formulation", "rcd0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let x = v["init"]["projected"]["x"].as_f64().unwrap();
    assert!(
        (x - 1.0).abs() < 1e-12,
        "projected onto the circle: x = {x}"
    );
    let o = dae(&[
        "run",
        &path,
        "--solver",
        "radau5",
        "--formulation",
        "rcd0",
        "--strict-init",
    ]);
    // Refused initial values are bad input (2), not a solver failure (3):
    // the message on stderr names the violated equation, stdout is empty.
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(o.stdout.is_empty(), "{}", stdout(&o));
    let err = stderr(&o);
    assert!(err.contains("x^2 + y^2 - l^2"), "{err}");
    assert!(
        err.contains(&path) && err.contains("--strict-init"),
        "{err}"
    );
}

/// A directory named like a built-in scene in the working directory does
/// not hide the built-in (it used to be read as the scene file and fail).
#[test]
fn a_directory_named_s01_does_not_hide_the_builtin_scene() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("s01")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_dae"))
        .args([
            "run", "s01", "--solver", "radau5", "--tol", "1e-5", "--format", "text",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.starts_with("S01 radau5("), "{out}");
}

/// `--max-steps` bounds every run of a sweep: a run that needs more stops
/// with the typed step-limit failure, the report says the bound, and 0 is
/// refused.
#[test]
fn sweep_max_steps_bounds_every_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bounded");
    let out_s = out.display().to_string();
    let bounded = |n: &str| {
        let mut args: Vec<&str> = "sweep s01 --solvers radau5 --formulations rcd1 --tols 1e-6 \
                                   --repeats 1 --quiet --format json --max-steps"
            .split_whitespace()
            .collect();
        args.extend([n, "--out", &out_s]);
        dae(&args)
    };
    let o = bounded("50");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["sweep"]["max_steps"], 50);
    let run = &v["runs"][0];
    assert_eq!(run["status"], "error", "{run}");
    assert_eq!(run["error"]["kind"], "step_limit", "{run}");
    // The stopped run records its work and where it got to (issue 27,
    // defect 3: it used to report zero steps and no final values).
    let steps = run["stats"]["steps"].as_u64().unwrap();
    assert!(steps > 0 && steps <= 50, "{run}");
    assert!(
        run["stats"]["residual_evals"].as_u64().unwrap() > 0,
        "{run}"
    );
    let t = run["t_end"].as_f64().unwrap();
    assert!(t > 0.0 && t < 20.0, "{run}");
    assert_eq!(run["final"].as_object().unwrap().len(), 5, "{run}");
    assert!(run["final"]["x"].as_f64().unwrap().is_finite(), "{run}");
    // The CSV too: its `steps` column.
    let mut csv = csv::Reader::from_path(out.join("results.csv")).unwrap();
    let col = csv.headers().unwrap().iter().position(|h| h == "steps");
    let row = csv.records().next().unwrap().unwrap();
    assert_eq!(
        row.get(col.unwrap()),
        Some(steps.to_string().as_str()),
        "{row:?}"
    );
    let o = bounded("0");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--max-steps 0"), "{}", stderr(&o));
}

// ------------------------------------------------- what a newcomer meets

/// The paper's S01 with the pendulum read from a `.dae` file — a user's
/// model, as a newcomer would write the scene — in a temporary directory.
fn user_pendulum_scene() -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    std::fs::copy(
        format!("{root}/scenes/pendulum.dae"),
        dir.path().join("pendulum.dae"),
    )
    .unwrap();
    let s01 = std::fs::read_to_string(format!("{root}/scenes/s01.toml")).unwrap();
    let scene = s01.replace("model = \"pendulum\"", "model = \"pendulum.dae\"");
    assert_ne!(scene, s01, "the scene names the model file");
    let path = dir.path().join("user.toml");
    std::fs::write(&path, scene).unwrap();
    (dir, path.display().to_string())
}

/// The double pendulum of `scenes/`, a model with no exact solution, copied
/// into a temporary directory.
fn user_double_pendulum_scene() -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    for f in ["double_pendulum.dae", "double_pendulum.toml"] {
        std::fs::copy(format!("{root}/scenes/{f}"), dir.path().join(f)).unwrap();
    }
    let path = dir.path().join("double_pendulum.toml");
    (dir, path.display().to_string())
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}{}", stdout(o), stderr(o)))
}

/// Without `--formulation`, `dae run` takes the solver's preferred
/// formulation (`dae_solvers::core::policy::preferred_formulations`) and
/// says so, in the JSON and in the text. On a user's pendulum radau5 used
/// to get the scene's first, the index-3 ori2: "ok — INACCURATE" at 224 ×
/// the tolerance.
#[test]
fn run_takes_the_solvers_preferred_formulation_and_says_which() {
    let (_dir, scene) = user_pendulum_scene();
    let o = dae(&["run", &scene, "--solver", "radau5"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["formulation"], "ggl1", "{v}");
    assert_eq!(v["formulation_choice"]["by"], "policy", "{v}");
    assert_eq!(v["formulation_choice"]["preference"][0], "ggl1", "{v}");
    assert_eq!(v["accuracy"], "accurate", "{v}");
    // The index-3 ori2 it used to pick is inaccurate at the same tolerance.
    let o = dae(&["run", &scene, "--solver", "radau5", "--formulation", "ori2"]);
    let ori2 = json(&o);
    assert_eq!(ori2["accuracy"], "inaccurate", "{ori2}");
    assert_eq!(ori2["formulation_choice"]["by"], "flag", "{ori2}");
    // The text says it too, right under the first line.
    let o = dae(&["run", &scene, "--format", "text"]);
    let text = stdout(&o);
    assert!(
        text.starts_with("S01 radau5(ggl1) tol 1e-8: ok\n"),
        "{text}"
    );
    assert!(
        text.contains("formulation ggl1: the default for radau5 (its preference: ggl1 > rcd1"),
        "{text}"
    );

    // bdf: no formulation is accurate on S01 at 1e-8 (BDF leaves the
    // index-2 unknowns out of its error test; the index-3 ori2 is refused
    // with a variable step: core::policy::variable_step_index3). The
    // preferred psi0 is the one accurate at 1e-12, where it has the
    // smallest error of all five it takes (9.2e-11; rcd1 3.7e-8, rcd0
    // 7.6e-8, ggl1 2.7e-8, psi1 4.8e-9). At 1e-8 it beats rcd0 (3.9e-5
    // against 8.2e-5); since bdf's Newton norm keeps the index-2 unknowns
    // (EXTREMES.md "ix2bdf13") rcd1, ggl1 and psi1 are ahead of it there
    // (1.3e-5, 4.7e-6, 3.0e-5), in about half its steps.
    let o = dae(&["run", &scene, "--solver", "bdf"]);
    let v = json(&o);
    assert_eq!(
        (v["formulation"].as_str(), v["status"].as_str()),
        (Some("psi0"), Some("ok")),
        "{v}"
    );
    let err = v["err"].as_f64().unwrap();
    let o = dae(&["run", &scene, "--solver", "bdf", "--formulation", "rcd0"]);
    let e = json(&o)["err"].as_f64().unwrap();
    assert!(err < e, "bdf(psi0) err {err:e} vs bdf(rcd0) {e:e}");
    let o = dae(&["run", &scene, "--solver", "bdf", "--tol", "1e-12"]);
    let v = json(&o);
    assert_eq!(v["formulation"], "psi0", "{v}");
    assert_eq!(v["accuracy"], "accurate", "{v}");
    let err = v["err"].as_f64().unwrap();
    for other in ["rcd1", "rcd0", "ggl1", "psi1"] {
        let args = [
            "run",
            &scene,
            "--solver",
            "bdf",
            "--formulation",
            other,
            "--tol",
            "1e-12",
        ];
        let w = json(&dae(&args));
        let e = w["err"].as_f64().unwrap();
        assert!(
            err < e,
            "1e-12: bdf(psi0) err {err:e} vs bdf({other}) {e:e}"
        );
    }

    // A model with no reference: neither default is suspect.
    let (_dir, double) = user_double_pendulum_scene();
    for (solver, formulation) in [("radau5", "ggl1"), ("bdf", "psi0")] {
        let o = dae(&["run", &double, "--solver", solver]);
        let v = json(&o);
        assert_eq!(v["formulation"], formulation, "{v}");
        assert_eq!(v["status"], "ok", "{v}");
        assert_eq!(v["accuracy"], "unverified", "{v}");
    }
}

/// A scene that lists only some formulations: the default is the solver's
/// most preferred among them; and the scene's own order when none of the
/// preferred ones will do.
#[test]
fn the_default_formulation_respects_the_scenes_list() {
    let (dir, scene) = user_pendulum_scene();
    let text = std::fs::read_to_string(&scene).unwrap();
    let restricted = text.replace(
        "formulations = [\"ori2\", \"rcd1\", \"rcd0\", \"ovd1\", \"ovd0\", \"ggl1\", \"psi1\", \"psi0\", \"mex0\"]",
        "formulations = [\"ori2\", \"rcd0\"]",
    );
    assert_ne!(restricted, text);
    let path = dir.path().join("restricted.toml");
    std::fs::write(&path, restricted).unwrap();
    let path = path.display().to_string();
    let o = dae(&["run", &path, "--solver", "radau5", "--tol", "1e-6"]);
    let v = json(&o);
    assert_eq!(v["formulation"], "rcd0", "{v}");
    let skipped: Vec<&str> = v["formulation_choice"]["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["formulation"].as_str().unwrap())
        .collect();
    assert_eq!(skipped, ["ggl1", "rcd1"], "{v}");
    // odbdf takes neither ori2 nor (not listed) ovd0/psi0: rcd0.
    let o = dae(&["run", &path, "--solver", "odbdf", "--tol", "1e-6"]);
    assert_eq!(json(&o)["formulation"], "rcd0");
}

/// Initial values the scene does not give (0) and values projected onto
/// the constraints are reported in the text output too: which unknowns,
/// from what to what.
#[test]
fn defaulted_and_projected_initial_values_are_reported_in_text() {
    let scene = "name = \"off\"\nmodel = \"pendulum\"\n[initial]\nx = 1.1\ny = 0.0\nv = 0.3\n[time]\nend = 1.0\n[reference]\nkind = \"none\"\n";
    let (_dir, path) = temp_file("off.toml", scene);
    let o = dae(&["run", &path, "--format", "text"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("  initial values: not given, started from 0: w\n"),
        "{text}"
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("  initial values: projected onto the constraints: "))
        .unwrap_or_else(|| panic!("no projection line in {text}"));
    assert!(line.contains("x 1.1e0 -> 1e0"), "{line}");
    assert!(line.contains("v 3e-1 -> "), "{line}");
    let v = json(&dae(&["run", &path]));
    assert_eq!(v["init"]["defaulted"], serde_json::json!(["w"]), "{v}");
    assert_eq!(v["init"]["changes"][0]["name"], "x", "{v}");
    assert_eq!(v["init"]["changes"][0]["from"], 1.1, "{v}");
    // A consistent start given in full says nothing.
    let o = dae(&["run", "s01", "--format", "text", "--tol", "1e-5"]);
    assert!(!stdout(&o).contains("initial values"), "{}", stdout(&o));
    assert!(json(&dae(&["run", "s01", "--tol", "1e-5"]))
        .get("init")
        .is_none());
}

/// Every exit path of `dae run` against the documented rule: 0 for a run
/// that reached the end (accurate or not), 2 for bad input with a message
/// on stderr and nothing on stdout, 3 for a solver failure with the JSON.
#[test]
fn run_exit_codes_follow_the_documented_rule() {
    // 0, even when inaccurate (the output says so).
    let o = dae(&["run", "s01", "--formulation", "ori2"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(json(&o)["accuracy"], "inaccurate");
    let dir = tempfile::tempdir().unwrap();
    let not_a_dir = dir
        .path()
        .join("missing")
        .join("t.csv")
        .display()
        .to_string();
    let scene_bad_name =
        "name = \"q\"\nmodel = \"pendulum\"\n[initial]\nq = 1.0\n[time]\nend = 1.0\n";
    let (_d, bad_scene) = temp_file("bad.toml", scene_bad_name);
    let bad: Vec<Vec<&str>> = vec![
        vec!["run", "--tol", "0"],
        vec!["run", "--tol", "1e-8", "--rtol", "1e-6"],
        vec!["run", "--tol", "1e-8", "--atol", "1e-6"],
        vec!["run", "--rtol", "2"],
        vec!["run", "--rtol", "-1e-6"],
        vec!["run", "--atol", "-1e-6"],
        vec!["run", "--atol", "inf"],
        vec!["run", "--rtol", "0", "--atol", "0"],
        vec!["run", "--solver", "radua5"],
        vec!["run", "--formulation", "ggl"],
        vec!["run", "--solver", "gauss", "--formulation", "ori2"],
        vec!["run", "--format", "yaml"],
        vec!["run", "no-such-scene"],
        vec!["run", &bad_scene],
        vec!["run", "--trajectory", &not_a_dir],
        vec!["run", "--no-such-flag"],
    ];
    for args in &bad {
        let o = dae(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(o.stdout.is_empty(), "{args:?}: {}", stdout(&o));
        assert!(!stderr(&o).is_empty(), "{args:?}");
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
    // --rtol 0 is a purely absolute tolerance, allowed beside --atol.
    let o = dae(&["run", "--rtol", "0", "--atol", "1e-6"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// `did you mean` for a mistyped solver or formulation, on the command
/// line and in scene files, with the known names listed.
#[test]
fn mistyped_names_get_a_suggestion() {
    let cases: [(&[&str], &str); 2] = [
        (&["run", "--solver", "radua5"], "did you mean `radau5`?"),
        (&["run", "--formulation", "ggl"], "did you mean `ggl1`?"),
    ];
    for (args, hint) in cases {
        let o = dae(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(hint), "{args:?}: {err}");
        assert!(err.contains("(known: "), "{args:?}: {err}");
    }
    let good = "name = \"T\"\nmodel = \"pendulum\"\n[initial]\nx = 1.0\ny = 0.0\nv = 0.0\nw = 0.0\n[time]\nend = 1.0\n[sweep]\n";
    for (line, hint) in [
        ("solvers = [\"radua5\"]", "did you mean `radau5`?"),
        ("formulations = [\"ggl\"]", "did you mean `ggl1`?"),
    ] {
        let (_dir, path) = temp_file("scene.toml", &format!("{good}{line}\n"));
        let o = dae(&["run", &path]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(hint), "{line}: {err}");
        assert!(err.contains(&format!("{path}:11:")), "{line}: {err}");
    }
    // Nothing close: no suggestion, the list only.
    let o = dae(&["run", "--solver", "euler"]);
    assert!(!stderr(&o).contains("did you mean"), "{}", stderr(&o));
    assert!(stderr(&o).contains("radau5, bdf"), "{}", stderr(&o));
}

/// `--trajectory FILE.csv`: every accepted step, from the consistent start,
/// as CSV with a header `t,<unknowns>`; on S01 at tol 1e-10 every row
/// agrees with the pendulum's closed form.
#[test]
fn trajectory_rows_follow_the_exact_pendulum() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("s01.csv");
    let o = dae(&[
        "run",
        "s01",
        "--solver",
        "radau5",
        "--formulation",
        "rcd1",
        "--tol",
        "1e-10",
        "--trajectory",
        file.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    let steps = v["stats"]["steps"].as_u64().unwrap() as usize;
    assert_eq!(v["trajectory_file"]["rows"], steps + 1, "{v}");
    let mut reader = csv::Reader::from_path(&file).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header, ["t", "x", "y", "v", "w", "lambda"]);
    let scene = dae::scene::Scene::builtin("s01").unwrap();
    let p = |n: &str| scene.parameter(n).unwrap();
    let exact =
        dae::reference::PendulumExact::from_state(1.0, 0.0, 0.0, 0.0, p("l"), p("g"), p("m"))
            .unwrap();
    let (mut rows, mut last_t, mut worst, mut worst_lambda) = (0, -1.0, 0.0f64, 0.0f64);
    for record in reader.records() {
        let row: Vec<f64> = record.unwrap().iter().map(|c| c.parse().unwrap()).collect();
        let t = row[0];
        assert!(t > last_t, "times increase: {t} after {last_t}");
        last_t = t;
        let e = exact.state(t);
        for i in 0..4 {
            worst = worst.max((row[1 + i] - e[i]).abs());
        }
        // λ is up to 1.5·m·g ≈ 21 here: measured relative to max(1, |λ*|),
        // the scaling of the accuracy verdict.
        worst_lambda = worst_lambda.max((row[5] - e[4]).abs() / e[4].abs().max(1.0));
        rows += 1;
    }
    assert_eq!(rows, steps + 1);
    assert_eq!(last_t, 20.0);
    // x, y, v, w: 100 · tol, the accuracy verdict's bound, at every step
    // (measured 6.6e-11).
    // λ: 1000 · tol. It is an index-2 unknown of rcd1, which Radau IIA
    // approximates to order 3 where the others get order 5 (Hairer &
    // Wanner VII.4), and the verdict leaves it out for that reason;
    // measured 1.2e-8 (120 · tol) at its worst row.
    assert!(
        worst <= 1e-8,
        "largest error of x, y, v, w over the rows: {worst:e}"
    );
    assert!(
        worst_lambda <= 1e-7,
        "largest scaled error of lambda: {worst_lambda:e}"
    );
    println!("rows {rows}: max |y - y*| {worst:e}, max |lambda - lambda*|/max(1, |lambda*|) {worst_lambda:e}");
}

/// The file appears whole or not at all: nothing when the solver fails,
/// nothing (and no temporary file) when it cannot be written, and a
/// previous file is kept in both cases.
#[test]
fn trajectory_is_written_whole_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let scene = blowup_scene(dir.path(), "");
    let file = dir.path().join("out.csv");
    std::fs::write(&file, "previous").unwrap();
    let o = dae(&[
        "run",
        scene.to_str().unwrap(),
        "--trajectory",
        file.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(json(&o).get("trajectory_file").is_none());
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "previous");
    // A directory in the way: refused, nothing left behind.
    let target = dir.path().join("a_dir.csv");
    std::fs::create_dir(&target).unwrap();
    let o = dae(&[
        "run",
        "--tol",
        "1e-5",
        "--trajectory",
        target.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--trajectory"), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["a_dir.csv", "blowup.dae", "blowup.toml", "out.csv"]);
    // Success replaces the previous file.
    let o = dae(&[
        "run",
        "--tol",
        "1e-5",
        "--trajectory",
        file.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&file)
        .unwrap()
        .starts_with("t,x,y,v,w,lambda,eta\n"));
}

/// `--rtol`/`--atol`: equal values are `--tol`; separate ones change the
/// run and are reported; a scene's per-unknown tolerances apply, and a
/// mistyped unknown there is refused with its line and a suggestion.
#[test]
fn separate_and_per_unknown_tolerances() {
    let base = ["run", "s01", "--formulation", "rcd1"];
    let with = |extra: &[&str]| json(&dae(&[&base[..], extra].concat()));
    let tol = with(&["--tol", "1e-7"]);
    let same = with(&["--rtol", "1e-7", "--atol", "1e-7"]);
    assert_eq!(tol["stats"], same["stats"], "--rtol T --atol T is --tol T");
    assert_eq!(tol["err"], same["err"]);
    assert!(same.get("tolerances").is_none(), "{same}");
    // rtol alone: atol stays at the default 1e-8.
    let loose = with(&["--rtol", "1e-5"]);
    assert_eq!(loose["tolerances"]["rtol"], 1e-5, "{loose}");
    assert_eq!(loose["tolerances"]["atol"], 1e-8, "{loose}");
    // The verdict holds the run to the loosest of the two.
    assert_eq!(loose["tol"], 1e-5, "{loose}");
    assert_ne!(loose["stats"], with(&["--tol", "1e-5"])["stats"]);
    let text = stdout(&dae(
        &[&base[..], &["--rtol", "1e-5", "--format", "text"]].concat()
    ));
    assert!(
        text.contains("  tolerances: rtol 1e-5  atol 1e-8"),
        "{text}"
    );

    let scene = |tolerance: &str| {
        format!(
            "name = \"T\"\nmodel = \"pendulum\"\n[initial]\nx = 1.0\ny = 0.0\nv = 0.0\nw = 0.0\n\
             [time]\nend = 2.0\n[reference]\nkind = \"exact\"\n[tolerance]\n{tolerance}\n"
        )
    };
    let (_d, path) = temp_file("t.toml", &scene("rtol = 1e-7\natol = { lambda = 1e-4 }"));
    let v = json(&dae(&["run", &path, "--formulation", "rcd1"]));
    assert_eq!(v["status"], "ok", "{v}");
    assert_eq!(v["tolerances"]["rtol"], 1e-7, "{v}");
    assert_eq!(v["tolerances"]["atol_of"]["lambda"], 1e-4, "{v}");
    // The command line replaces the scene's numbers, not its per-unknown
    // entries.
    let v = json(&dae(&[
        "run",
        &path,
        "--formulation",
        "rcd1",
        "--tol",
        "1e-6",
    ]));
    assert_eq!(
        (
            v["tolerances"]["rtol"].as_f64(),
            v["tolerances"]["atol"].as_f64()
        ),
        (Some(1e-6), Some(1e-6))
    );
    assert_eq!(v["tolerances"]["atol_of"]["lambda"], 1e-4, "{v}");
    let (_d, path) = temp_file("t.toml", &scene("atol = { lamda = 1e-4 }"));
    let o = dae(&["run", &path]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("{path}:13:10:")), "{err}");
    assert!(err.contains("`tolerance.atol.lamda`"), "{err}");
    assert!(err.contains("did you mean `lambda`?"), "{err}");
    let (_d, path) = temp_file("t.toml", &scene("rtol = 1e-20"));
    let o = dae(&["run", &path]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("`tolerance.rtol` = 1e-20"),
        "{}",
        stderr(&o)
    );
}

/// `dae run --estimate`: the BDF methods' error estimate. On the IVP Test
/// Set's transistor amplifier at 1e-7 DASSL's own takes 35 917 steps
/// (its order-one cycle, BENCHMARKS.md §18), the default checked one
/// 7 310, the propagated one 7 708; the JSON's statistics say so.
#[test]
fn run_estimate_flag_reaches_the_bdf_methods() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/literature/transamp.toml"
    );
    // `--estimate E` for `Some(E)`, the default for `None`.
    let steps = |estimate: Option<&str>| {
        let mut args = vec![
            "run",
            scene,
            "--solver",
            "bdf",
            "--formulation",
            "rcd0",
            "--tol",
            "1e-7",
        ];
        args.extend(estimate.map(|e| ["--estimate", e]).into_iter().flatten());
        let o = dae(&args);
        assert_eq!(o.status.code(), Some(0), "{estimate:?}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON");
        v["stats"]["steps"].as_u64().expect("steps")
    };
    let dassl = steps(Some("dassl"));
    let (checked, propagated) = (steps(Some("checked")), steps(Some("propagated")));
    assert!(dassl > 3 * checked, "dassl {dassl}, checked {checked}");
    assert!(
        propagated < dassl / 3,
        "dassl {dassl}, propagated {propagated}"
    );
    // The default is the checked estimate.
    assert_eq!(steps(None), checked);
}

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
    assert_eq!(f.as_array().unwrap().len(), 8);
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

#[test]
fn solver_failure_prints_json_and_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("blowup.dae"),
        "pub Blowup {\n  differential { x }\n  equations { der(x) = x^2; }\n}\n",
    )
    .unwrap();
    let scene = dir.path().join("blowup.toml");
    std::fs::write(
        &scene,
        "name = \"blowup\"\nmodel = \"blowup.dae\"\n[initial]\nx = 1.0\n[time]\nend = 2.0\n[reference]\nkind = \"none\"\n",
    )
    .unwrap();
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
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["error"]["kind"], "inconsistent_initial_values");
    assert!(
        v["error"]["message"]
            .as_str()
            .unwrap()
            .contains("x^2 + y^2 - l^2"),
        "{v}"
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
    let o = bounded("0");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--max-steps 0"), "{}", stderr(&o));
}

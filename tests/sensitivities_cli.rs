//! `dae run --sensitivities` and a scene's `[sensitivities]` (issue 25,
//! items 2 and 5): the JSON shape, agreement with the exact derivatives of
//! `data/pendulum_sensitivities.csv`, and bad input as exit code 2 with a
//! message naming what is wrong.

use std::io::Write;
use std::process::{Command, Output};

fn dae(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dae"))
        .args(args)
        .output()
        .expect("the dae binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).expect("JSON on stdout")
}

/// A scene (and a model beside it when `model` is given) in a temporary
/// directory: the scene's path.
fn scene(dir: &tempfile::TempDir, text: &str, model: Option<&str>) -> String {
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::File::create(&path)
            .unwrap()
            .write_all(text.as_bytes())
            .unwrap();
        path.display().to_string()
    };
    if let Some(m) = model {
        write("model.dae", m);
    }
    write("scene.toml", text)
}

const SCENE: &str = "name = \"t\"\nmodel = \"pendulum\"\n[initial]\nx = 1\n\
                     [time]\nend = 4\ncheck = [2.0, 4.0]\n";

/// `--sensitivities g,l` on S01's pendulum: `{"g": {"x": [...]}}` at the
/// check times, against the closed form at t = 2 and 4 (the pendulum
/// released at x = l = 1 with S01's g: whole periods of 2).
#[test]
fn json_sensitivities_match_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene(&dir, SCENE, None);
    let o = dae(&[
        "run",
        &path,
        "--solver",
        "radau5",
        "--formulation",
        "rcd0",
        "--tol",
        "1e-10",
        "--sensitivities",
        "g,l",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    let s = &v["sensitivities"];
    assert_eq!(s["times"], serde_json::json!([2.0, 4.0]));
    assert_eq!(s["error_control"], true);
    let csv = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/pendulum_sensitivities.csv"
    ))
    .unwrap();
    let mut compared = 0;
    for line in csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("t,"))
    {
        let f: Vec<&str> = line.split(',').collect();
        let t: f64 = f[0].parse().unwrap();
        let k = match t {
            2.0 => 0,
            4.0 => 1,
            _ => continue,
        };
        let exact: f64 = f[4].parse().unwrap();
        let got = s["values"][f[1]][f[2]][k].as_f64().unwrap();
        // Within 1e-6 of the largest derivative there (27.5, dw/dl at
        // t = 4; at whole periods most are zero to 1e-9), as
        // dae-solvers/tests/sensitivity.rs measures: 2e-5 absolute.
        assert!(
            (got - exact).abs() < 1e-6 * 20.0,
            "d{}/d{} at t = {t}: {got} vs {exact}",
            f[2],
            f[1]
        );
        compared += 1;
    }
    assert_eq!(compared, 16);
    assert!(s["final"]["l"]["x"].as_f64().is_some());
}

/// The scene's `[sensitivities]`, error control off, in the text output.
#[test]
fn scene_section_and_text_output() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{SCENE}[sensitivities]\nparameters = [\"l\"]\nerror_control = false\n");
    let path = scene(&dir, &text, None);
    let o = dae(&[
        "run",
        &path,
        "--solver",
        "bdf",
        "--formulation",
        "ggl1",
        "--format",
        "text",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("sensitivities (out of the error test"),
        "{out}"
    );
    assert!(out.contains("dx/dl = "), "{out}");
}

/// Bad input: exit code 2, nothing on stdout, the message names it.
#[test]
fn bad_sensitivity_requests_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene(&dir, SCENE, None);
    let bad = |args: &[&str], wanted: &[&str]| {
        let mut all = vec!["run", path.as_str(), "--solver", "radau5"];
        all.extend_from_slice(args);
        let o = dae(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(o.stdout.is_empty(), "{args:?}");
        for w in wanted {
            assert!(stderr(&o).contains(w), "{args:?}: {}", stderr(&o));
        }
    };
    // A parameter that does not exist.
    bad(&["--sensitivities", "gravity"], &["`gravity`", "m, l, g"]);
    // A formulation that cannot carry sensitivities.
    bad(
        &["--formulation", "mex0", "--sensitivities", "g"],
        &["mex0", "dummy derivatives"],
    );
    // m multiplies der(v): the leading matrix would depend on it.
    bad(
        &["--formulation", "rcd0", "--sensitivities", "m"],
        &["rcd0", "leading matrix"],
    );
    bad(&["--sensitivities", "g,g"], &["`g` is named twice"]);

    // A derived parameter.
    let model =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/pendulum.dae"))
            .unwrap()
            .replace(
                "    differential",
                "    derived { gl = g * l; }\n    differential",
            );
    let dir = tempfile::tempdir().unwrap();
    let text =
        SCENE.replace("\"pendulum\"", "\"model.dae\"") + "[sensitivities]\nparameters = [\"gl\"]\n";
    let path = scene(&dir, &text, Some(&model));
    let o = dae(&["run", &path, "--solver", "radau5"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("`gl` is a derived parameter"),
        "{}",
        stderr(&o)
    );
    // A misspelt key of the section.
    let text = format!("{SCENE}[sensitivities]\nparameter = [\"g\"]\n");
    let path = scene(&dir, &text, None);
    let o = dae(&["run", &path]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("parameter"), "{}", stderr(&o));
}

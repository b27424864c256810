//! What `dae run` reports about initialisation (issue 23, item 4): every
//! unknown's given value, guess, consistent value, move and how; the
//! warning for a nonlinear multiplier started from 0; a scene's `[guess]`
//! choosing the other root; bad `[guess]` entries refused with their place.
//! The model is `tests/data/two_roots.dae` (a Hessenberg index-2 DAE whose
//! multiplier has the consistent values 1 and −2).

use serde_json::{json, Value};
use std::io::Write;
use std::process::{Command, Output};

fn dae(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dae"))
        .args(args)
        .output()
        .expect("the dae binary runs")
}

fn data(name: &str) -> String {
    format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn json_of(o: &Output) -> Value {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("JSON on stdout")
}

fn entry<'a>(v: &'a Value, name: &str) -> &'a Value {
    v["initialisation"]
        .as_array()
        .expect("an initialisation array")
        .iter()
        .find(|e| e["name"] == name)
        .unwrap_or_else(|| panic!("no entry for {name} in {v}"))
}

#[test]
fn without_a_guess_newton_starts_from_zero_and_says_so() {
    let v = json_of(&dae(&["run", &data("two_roots.toml")]));
    let names: Vec<&str> = v["initialisation"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["x", "y", "z"]);
    for x in ["x", "y"] {
        let e = entry(&v, x);
        assert_eq!(
            (
                &e["given"],
                &e["guess"],
                &e["value"],
                &e["moved"],
                &e["how"]
            ),
            (
                &json!(1.0),
                &Value::Null,
                &json!(1.0),
                &json!(0.0),
                &json!("fixed")
            ),
            "{e}"
        );
    }
    let z = entry(&v, "z");
    assert_eq!((&z["given"], &z["guess"]), (&Value::Null, &Value::Null));
    assert_eq!(
        (&z["how"], &z["nonlinear"]),
        (&json!("defaulted"), &json!(true))
    );
    let value = z["value"].as_f64().unwrap();
    assert!((value - 1.0).abs() < 1e-12, "z = {value}");
    assert_eq!(z["moved"].as_f64().unwrap(), value.abs());
    // The run integrates from that root: z stays 1.
    let end = v["final"]["z"].as_f64().unwrap();
    assert!((end - 1.0).abs() < 1e-5, "z(1) = {end}");

    let o = dae(&["run", &data("two_roots.toml"), "--format", "text"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(
            "  WARNING: z started from 0 (no [guess]); the DAE may have other consistent values\n"
        ),
        "{text}"
    );
    let row = text
        .lines()
        .find(|l| l.trim_start().starts_with("z "))
        .unwrap_or_else(|| panic!("no table row for z in {text}"));
    let cells: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(
        cells,
        ["z", "-", "-", "1.000e0", "1.00e0", "defaulted"],
        "{row}"
    );
}

#[test]
fn a_guess_chooses_the_other_root_without_a_warning() {
    let v = json_of(&dae(&["run", &data("two_roots_guess.toml")]));
    let z = entry(&v, "z");
    assert_eq!((&z["given"], &z["guess"]), (&Value::Null, &json!(-1.0)));
    assert_eq!(
        (&z["how"], &z["nonlinear"]),
        (&json!("guessed"), &json!(true))
    );
    let value = z["value"].as_f64().unwrap();
    assert!((value + 2.0).abs() < 1e-12, "z = {value}");
    assert!((z["moved"].as_f64().unwrap() - 1.0).abs() < 1e-12, "{z}");
    let end = v["final"]["z"].as_f64().unwrap();
    assert!((end + 2.0).abs() < 1e-5, "z(1) = {end}");
    let o = dae(&["run", &data("two_roots_guess.toml"), "--format", "text"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(!text.contains("WARNING"), "{text}");
    assert!(text.contains("  initialisation:\n"), "{text}");
}

#[test]
fn the_paper_scene_reports_fixed_values_and_a_linear_multiplier() {
    let v = json_of(&dae(&["run", "s01", "--tol", "1e-5"]));
    for x in ["x", "y", "v", "w"] {
        assert_eq!(entry(&v, x)["how"], "fixed", "{v}");
        assert_eq!(entry(&v, x)["moved"], 0.0, "{v}");
    }
    let lambda = entry(&v, "lambda");
    assert_eq!(lambda["how"], "defaulted");
    // λ enters the pendulum's equations linearly: one consistent value.
    assert_eq!(lambda["nonlinear"], false);
    let o = dae(&["run", "s01", "--tol", "1e-5", "--format", "text"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("WARNING"));
}

/// A scene in a temporary directory beside a copy of the model.
fn scene_with(text: &str) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("two_roots.dae"), dir.path().join("two_roots.dae")).unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::File::create(&path)
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let p = path.display().to_string();
    (dir, p)
}

#[test]
fn bad_guesses_are_refused_with_their_place() {
    let head = "name = \"t\"\nmodel = \"two_roots.dae\"\n[initial]\nx = 1.0\ny = 1.0\n";
    // An unknown name: its line, and the closest name.
    let (_dir, path) = scene_with(&format!("{head}[guess]\nZ = -1.0\n[time]\nend = 1.0\n"));
    let o = dae(&["run", &path]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml:7:1"), "{err}");
    assert!(err.contains("`guess.Z`"), "{err}");
    assert!(err.contains("did you mean `z`?"), "{err}");
    // A value fixed by [initial] cannot be guessed too.
    let (_dir, path) = scene_with(&format!(
        "{head}[guess]\nz = 1.0\ny = 2.0\n[time]\nend = 1.0\n"
    ));
    let o = dae(&["run", &path]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml:8:1"), "{err}");
    assert!(err.contains("`guess.y`"), "{err}");
    assert!(err.contains("fixed by [initial]"), "{err}");
}

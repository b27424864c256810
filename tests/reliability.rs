//! Reliability: each test reproduces a defect that once hung, gave a wrong
//! figure with exit 0, took quadratic time, left a partial output set, or
//! accepted a meaningless input silently. Each failed before its fix.
//! Scenes are built here as TOML text; horizons are short.

use dae::cli::run::load_model;
use dae::prelude::*;
use dae::runner::{self, RunSpec};
use dae::scene::Scene;
use dae::sweep::{self, SweepOptions};
use dae_solvers::init::{self, InitMode};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

// ---------------------------------------------------------------- helpers

/// Run the `dae` binary; kill it and fail after `limit`.
fn dae_within(args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dae"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the dae binary starts");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait works").is_some() {
            return child.wait_with_output().expect("output is readable");
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("dae {args:?} still running after {limit:?}: killed");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn dae(args: &[&str]) -> Output {
    dae_within(args, Duration::from_secs(60))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}\nstderr: {}", stdout(o), stderr(o)))
}

/// A pendulum scene: `[parameters]`, `[initial]` and `[time]` bodies given.
fn scene_text(parameters: &str, initial: &str, time: &str, reference: &str) -> String {
    format!(
        "name = \"T\"\nmodel = \"pendulum\"\n[parameters]\n{parameters}\n[initial]\n{initial}\n\
         [time]\n{time}\n[reference]\nkind = \"{reference}\"\n"
    )
}

/// Write `text` to `name` in a fresh temporary directory.
fn scene_file(name: &str, text: &str) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join(name);
    std::fs::write(&path, text).expect("the scene is written");
    let p = path.display().to_string();
    (dir, p)
}

/// One run of a parsed scene through the runner, as `dae run` does it.
fn run_scene(scene: &Scene, solver: &str, formulation: &str, tol: f64) -> runner::RunRecord {
    let model = load_model(scene).unwrap_or_else(|f| panic!("{}", f.message));
    let initial: Vec<(String, f64)> = scene
        .initial
        .iter()
        .map(|v| (v.name.clone(), v.value))
        .collect();
    let reference = runner::pendulum_reference(&*model, &initial).expect("a reference");
    runner::run(&RunSpec {
        scene: &scene.name,
        model: &*model,
        initial: &initial,
        t0: scene.time.start,
        t_end: scene.time.end,
        check: &scene.time.checks,
        reference: Some(&reference),
        solver,
        formulation,
        tol,
        init_mode: InitMode::Project,
        samples: &[],
        repeats: 1,
    })
    .expect("the run starts")
}

// ------------------------------------------------- 1. the reference hang

/// `x = 1e308`: the power-of-two search of the reference doubled to
/// infinity and then halved infinity forever. Now a typed error naming the
/// field, at once.
#[test]
fn huge_start_is_refused_naming_the_field_instead_of_hanging() {
    for (field, initial) in [
        ("initial.x", "x = 1e308\ny = 0.0"),
        ("initial.y", "x = 1.0\ny = -1e308"),
    ] {
        let text = scene_text("g = 9.81", initial, "end = 1.0", "pendulum-exact");
        let (_dir, path) = scene_file("huge.toml", &text);
        let o = dae_within(&["run", &path], Duration::from_secs(20));
        assert_eq!(o.status.code(), Some(2), "{field}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains(field), "{field} not named: {err}");
        assert!(err.contains(&path), "file not named: {err}");
    }
}

/// Whatever the exact reference refuses is reported at the scene field to
/// blame, with its place in the file.
#[test]
fn reference_refusals_name_the_scene_field() {
    for (parameters, initial, needle) in [
        ("g = -9.81", "x = 1.0\ny = 0.0", ":4:1: `parameters.g`"),
        ("g = 9.81", "x = 0.6\ny = -0.9", ":6:1: `initial.x`"),
        // A period of 1e-150 s: a one-second horizon is beyond 2^51 periods.
        (
            "l = 1e-150\ng = 1e150",
            "x = 1e-150\ny = 0.0",
            ":10:7: `time.end`",
        ),
    ] {
        let text = scene_text(parameters, initial, "end = 1.0", "pendulum-exact");
        let (_dir, path) = scene_file("r.toml", &text);
        let o = dae(&["run", &path]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.starts_with(&format!("{path}{needle}")),
            "{needle}: {err}"
        );
        assert!(err.contains("pendulum-exact reference"), "{err}");
    }
}

/// The reference itself, given the huge start directly: a typed error at
/// once (it looped forever), whatever the rod length.
#[test]
fn reference_refuses_unrepresentable_starts_at_once() {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let results: Vec<_> = [
            (1e308, 0.0, 1.0),
            (1.0, -1e308, 1.0),
            (f64::MAX, f64::MAX, 1.0),
            // On the circle, but λ ~ m(L²θ'² + gL)/L² overflows on the way.
            (1e308, 0.0, 1e308),
            // On the circle, but √(g/L) overflows.
            (1e-310, 0.0, 1e-310),
        ]
        .into_iter()
        .map(|(x, y, l)| dae::reference::PendulumExact::from_start(x, y, l, 9.81, 1.0))
        .collect();
        let _ = tx.send(results);
    });
    let results = rx
        .recv_timeout(Duration::from_secs(10))
        .expect("the reference answers at once");
    for r in results {
        let e = r.expect_err("no representable reference");
        let msg = e.to_string();
        assert!(
            ["x0", "y0", "L ="].iter().any(|f| msg.contains(f)),
            "names no input: {msg}"
        );
    }
}


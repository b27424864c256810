//! Reliability: each test reproduces a defect that once hung, gave a wrong
//! figure with exit 0, took quadratic time, left a partial output set, or
//! accepted a meaningless input silently. Each failed before its fix.
//! Scenes are built here as TOML text; horizons are short.

use dae::inputs::inputs;
use dae::prelude::*;
use dae::runner;
use dae::scene::Scene;
use dae::sweep::write::publish_dir;
use dae::sweep::{self, SweepOptions};
use dae_solvers::init;
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
    let inputs = inputs(scene).unwrap_or_else(|e| panic!("{e}"));
    assert!(inputs.reference.is_some(), "a reference");
    runner::run(&inputs.spec(scene, solver, formulation, tol)).expect("the run starts")
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

// ------------------------------------- 2. the reference at a nonzero start

/// With `time.start = 1` the exact solution was evaluated at `t`, not
/// `t − t0`: "err": 2.0 for a run whose true error is 3e-9.
#[test]
fn nonzero_start_measures_against_the_shifted_reference() {
    let shifted = scene_text(
        "g = 13.7503716373294544",
        "x = 1.0\ny = 0.0",
        "start = 1.0\nend = 11.0\ncheck = [6.0, 11.0]",
        "pendulum-exact",
    );
    let from_zero = scene_text(
        "g = 13.7503716373294544",
        "x = 1.0\ny = 0.0",
        "end = 10.0\ncheck = [5.0, 10.0]",
        "pendulum-exact",
    );
    let a = run_scene(
        &Scene::parse(&shifted, "a.toml", None).unwrap(),
        "radau5",
        "ggl1",
        1e-10,
    );
    let b = run_scene(
        &Scene::parse(&from_zero, "b.toml", None).unwrap(),
        "radau5",
        "ggl1",
        1e-10,
    );
    let (ea, eb) = (a.err.unwrap(), b.err.unwrap());
    // The same motion, shifted by one second: the integrator sees the same
    // problem up to the rounding of t, so the errors agree closely (both
    // ~1e-9); they were 2.0 and 3e-9.
    assert!(
        ea < 1e-7 && eb < 1e-7,
        "errors {ea:e} (from t = 1) and {eb:e}"
    );
    assert!(
        (ea - eb).abs() <= 0.5 * eb.max(1e-10),
        "errors {ea:e} (from t = 1) and {eb:e} (from t = 0) should agree"
    );
}

// ------------------------------------------------ 3. quadratic check scan

/// 200 000 check times: every output point scanned the whole check list
/// (about 30 s here); a merge of the two sorted lists takes milliseconds.
#[test]
fn many_check_times_cost_linear_time() {
    let n = 200_000;
    let text = scene_text(
        "g = 13.7503716373294544",
        "x = 1.0\ny = 0.0",
        &format!("end = 2.0\ncheck_every = {}", 2.0 / n as f64),
        "pendulum-exact",
    );
    let scene = Scene::parse(&text, "many.toml", None).unwrap();
    assert_eq!(scene.time.checks.len(), n);
    let start = Instant::now();
    let rec = run_scene(&scene, "radau5", "rcd0", 1e-6);
    let took = start.elapsed();
    assert_eq!(rec.status, "ok");
    assert!(rec.err.unwrap() < 1e-4);
    // Measured ~0.3 s (debug-opt2); the quadratic scan took ~30 s. The
    // bound is generous for a loaded machine.
    assert!(
        took < Duration::from_secs(8),
        "{n} check times took {took:?}"
    );
}

/// The merge marks exactly the output times within 1e-12 of a check time,
/// whatever the order of the checks.
#[test]
fn check_flags_match_the_pointwise_rule() {
    let times: Vec<f64> = (0..=1000).map(|i| f64::from(i) * 0.01).collect();
    let mut checks: Vec<f64> = (0..=100).map(|i| f64::from(i) * 0.1).collect();
    checks.push(5.0 + 1e-13); // within the slack of 5.0: still 5.0
    checks.push(7.005); // between two output times: matches neither
    checks.reverse();
    let flags = runner::check_flags(&times, &checks);
    for (t, flag) in times.iter().zip(&flags) {
        let pointwise = checks
            .iter()
            .any(|c| (c - t).abs() <= 1e-12 * (1.0 + t.abs()));
        assert_eq!(*flag, pointwise, "t = {t}");
    }
    assert_eq!(flags.iter().filter(|f| **f).count(), 101);
    assert!(runner::check_flags(&[], &checks).is_empty());
    assert_eq!(runner::check_flags(&times[..3], &[]), [false; 3]);
}

// ---------------------------------------------- 4. atomic sweep output set

fn tiny_sweep() -> (sweep::SweepReport, sweep::Summary) {
    let scene = Scene::builtin("s01").unwrap();
    let opts = SweepOptions {
        solvers: vec!["radau5".into()],
        formulations: vec!["rcd1".into()],
        tolerances: vec![1e-5],
        repeats: 1,
        progress: false,
        ..SweepOptions::from_scene(&scene)
    };
    let report = sweep::run(&scene, &opts).expect("the sweep runs");
    let summary = sweep::Summary::of(&report);
    (report, summary)
}

/// A write that fails midway (here: `index.html` cannot replace what is in
/// the way) used to leave the new results.csv and results.json beside the
/// old index.html. Now the previous set stays whole.
#[test]
fn failed_sweep_write_leaves_the_previous_output_whole() {
    let (report, summary) = tiny_sweep();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s01");
    std::fs::create_dir_all(out.join("index.html")).unwrap();
    std::fs::write(out.join("results.csv"), "old csv").unwrap();
    std::fs::write(out.join("results.json"), "old json").unwrap();
    assert!(sweep::write_outputs(&report, &summary, &out, None).is_err());
    assert_eq!(
        std::fs::read_to_string(out.join("results.csv")).unwrap(),
        "old csv"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("results.json")).unwrap(),
        "old json"
    );
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["index.html", "results.csv", "results.json"]);
    // Nothing temporary is left beside the destination either.
    let beside: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(beside, ["s01"]);
}

fn entries(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A fill that fails half-way through the set: the previous set stays, and
/// nothing is left beside it.
#[test]
fn publish_dir_keeps_the_old_set_when_the_fill_fails() {
    let root = tempfile::tempdir().unwrap();
    let dest = root.path().join("out");
    std::fs::create_dir(&dest).unwrap();
    std::fs::write(dest.join("results.csv"), "old").unwrap();
    let r: Result<(), Box<dyn std::error::Error>> = publish_dir(&dest, None, |staging| {
        std::fs::write(staging.join("results.csv"), "new")?;
        std::fs::write(staging.join("results.json"), "{\"half\":")?;
        Err(std::io::Error::other("injected: disk full").into())
    });
    assert!(r.is_err());
    assert_eq!(entries(&dest), ["results.csv"]);
    assert_eq!(
        std::fs::read_to_string(dest.join("results.csv")).unwrap(),
        "old"
    );
    assert_eq!(entries(root.path()), ["out"]);
}

/// A complete set replaces the old one as a whole (a stale figure goes).
#[test]
fn publish_dir_replaces_the_whole_set() {
    let root = tempfile::tempdir().unwrap();
    let dest = root.path().join("out");
    std::fs::create_dir(&dest).unwrap();
    std::fs::write(dest.join("stale.svg"), "old figure").unwrap();
    let r: Result<u8, Box<dyn std::error::Error>> = publish_dir(&dest, None, |staging| {
        std::fs::write(staging.join("index.html"), "new")?;
        Ok(7)
    });
    assert_eq!(r.unwrap(), 7);
    assert_eq!(entries(&dest), ["index.html"]);
    assert_eq!(entries(root.path()), ["out"]);
}

/// A run killed while writing leaves its staging directory (clearly named)
/// beside the destination; the next run removes it. A directory with files
/// a sweep does not write is not replaced at all.
#[test]
fn sweep_output_leftovers_are_cleaned_and_foreign_directories_kept() {
    let (report, summary) = tiny_sweep();
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("s01");
    let killed = root.path().join(".s01.dae-sweep-new-4000000000-0");
    std::fs::create_dir(&killed).unwrap();
    std::fs::write(killed.join(".solution.svg.tmp-4000000000-3.svg"), "<svg").unwrap();
    let written = sweep::write_outputs(&report, &summary, &out, None).unwrap();
    assert!(written
        .files
        .iter()
        .all(|f| f.parent() == Some(&*out) && f.is_file()));
    assert_eq!(entries(root.path()), ["s01"]);
    assert!(entries(&out).iter().all(|n| !n.starts_with('.')));
    for f in ["results.csv", "results.json", "index.html"] {
        assert!(out.join(f).is_file(), "{f}");
    }

    let mine = root.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "my notes").unwrap();
    let err = sweep::write_outputs(&report, &summary, &mine, None).unwrap_err();
    assert!(matches!(err, sweep::SweepError::NotOurs { .. }), "{err}");
    assert!(err.to_string().contains("notes.txt"), "{err}");
    assert_eq!(entries(&mine), ["notes.txt"]);
}

/// `dae sweep` killed part-way: the previous output directory is intact
/// (whenever the kill lands) and the next run leaves nothing beside it.
#[test]
fn killed_sweep_leaves_the_previous_output_intact() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("s01");
    let out_s = out.display().to_string();
    let tiny = [
        "sweep",
        "s01",
        "--solvers",
        "radau5",
        "--formulations",
        "rcd1",
        "--tols",
        "1e-5",
        "--repeats",
        "1",
        "--quiet",
        "--out",
        &out_s,
    ];
    let o = dae(&tiny);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let before: Vec<(String, Vec<u8>)> = entries(&out)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect();
    for delay_ms in [150, 600] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dae"))
            .args([
                "sweep",
                "s01",
                "--tols",
                "1e-5,1e-6",
                "--repeats",
                "1",
                "--quiet",
                "--out",
                &out_s,
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        let _ = child.kill();
        let _ = child.wait();
        let after: Vec<(String, Vec<u8>)> = entries(&out)
            .into_iter()
            .map(|n| {
                let bytes = std::fs::read(out.join(&n)).unwrap();
                (n, bytes)
            })
            .collect();
        // Killed before it published: the old set, byte for byte. (Had it
        // finished, a whole new set: results.json would differ but be whole.)
        if after != before {
            assert_eq!(
                entries(&out),
                before.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>()
            );
            let json = std::fs::read_to_string(out.join("results.json")).unwrap();
            assert!(serde_json::from_str::<serde_json::Value>(&json).is_ok());
        }
        // Only clearly named leftovers beside it: staging directories and
        // the lock file (its lock died with the process; the next sweep
        // takes it and removes it).
        for n in entries(root.path()) {
            assert!(
                n == "s01" || n.starts_with(".s01.dae-sweep-") || n == ".s01.dae-lock",
                "{n}"
            );
        }
    }
    let o = dae(&tiny);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(entries(root.path()), ["s01"]);
}

// ------------------------------------------------------- 5. tolerances

/// `--tol 1` and `--tol 2` ran (bdf: exit 0, error ≈ 1) although scenes
/// refuse tolerances outside (0, 1).
#[test]
fn cli_tolerances_follow_the_scene_rule() {
    for tol in ["1", "2", "1e300", "1e-16", "1e-30"] {
        let o = dae(&["run", "s01", "--solver", "bdf", "--tol", tol]);
        assert_eq!(o.status.code(), Some(2), "--tol {tol}: {}", stderr(&o));
        assert!(stderr(&o).contains("--tol"), "{}", stderr(&o));
        let o = dae(&["sweep", "s01", "--tols", &format!("1e-6,{tol}"), "--quiet"]);
        assert_eq!(o.status.code(), Some(2), "--tols {tol}: {}", stderr(&o));
    }
}

fn pendulum_start(form: &str) -> (BoxedSystem, Vec<f64>) {
    let model = dae::models::load("pendulum").unwrap();
    let sys = model.formulation(form).unwrap();
    let n = sys.info().unknowns();
    let mut y = vec![0.0; n];
    y[sys.info().variable("x").unwrap()] = 1.0;
    let start = init::consistent(&*sys, 0.0, &y, &Default::default()).unwrap();
    (sys, start.y)
}

/// The library accepted `tol = 1e300` and returned Ok with x = −29.3 on a
/// unit pendulum; and BDF at 1e-16 ground on to the step limit (~17 s).
#[test]
fn library_refuses_tolerances_it_cannot_honour() {
    for form in ["rcd0", "ggl1"] {
        let (sys, y0) = pendulum_start(form);
        let problem = Problem {
            system: &*sys,
            t0: 0.0,
            y0: &y0,
            t_end: 20.0,
        };
        for name in ["radau5", "bdf"] {
            let solver = dae_solvers::solver_by_name(name).unwrap();
            for tol in [1e300, 1.0, 1e-16, 1e-30] {
                let start = Instant::now();
                let r = solver.solve(&problem, &Options::with_tol(tol));
                let e = match r {
                    Ok(s) => panic!("{name} {form} tol {tol:e}: Ok, x = {:?}", s.last()),
                    Err(e) => e,
                };
                assert!(
                    start.elapsed() < Duration::from_secs(1),
                    "{name}: slow refusal"
                );
                assert_eq!(e.t(), None, "{name} {form} tol {tol:e}: {e}");
                let msg = e.to_string();
                assert!(msg.contains("rtol"), "{msg}");
                assert!(msg.contains(&format!("{tol:e}")), "{msg}");
            }
        }
    }
}

/// Per-component relative tolerances follow the same rule and name the
/// component; a purely absolute tolerance (rtol = 0) is still allowed.
#[test]
fn per_component_tolerances_name_the_component() {
    use dae_solvers::options::{Tol, ToleranceIssue};
    let mut options = Options::with_tol(1e-8);
    options.tol.rtol = Tol::PerComponent(vec![1e-8, 1e-8, 1e-20, 1e-8, 1e-8]);
    let err = options.validate(5, 0.0, 1.0).unwrap_err();
    assert!(
        matches!(
            err,
            SolveError::ToleranceOutOfRange {
                name: "rtol",
                index: Some(2),
                issue: ToleranceIssue::BelowRoundOff,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().starts_with("rtol[2] = 1e-20"), "{err}");
    assert_eq!(err.kind(), "tolerance_out_of_range");
    options.tol.rtol = Tol::Scalar(0.0);
    assert!(options.validate(5, 0.0, 1.0).is_ok());
    // The uniform rule is exactly what Options::with_tol validates.
    for tol in [1e-14, 2.3e-14, 0.5, 0.999_999, 1.0] {
        assert_eq!(
            dae_solvers::options::check_uniform(tol).is_ok(),
            Options::with_tol(tol).validate(5, 0.0, 1.0).is_ok(),
            "{tol:e}"
        );
    }
}

// ------------------------------------------------------- 6. messages

/// A directory given as the model was reported as "does not exist".
#[test]
fn model_directory_is_reported_as_a_directory() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("models.dae")).unwrap();
    let text = scene_text("g = 9.81", "x = 1.0", "end = 1.0", "none")
        .replace("\"pendulum\"", "\"models.dae\"");
    let path = dir.path().join("s.toml");
    std::fs::write(&path, text).unwrap();
    let msg = Scene::load(&path).unwrap_err().to_string();
    assert!(msg.contains("is a directory"), "{msg}");
    assert!(!msg.contains("does not exist"), "{msg}");
    assert!(
        msg.starts_with(&format!("{}:2:9:", path.display())),
        "{msg}"
    );
}

/// `model = "pendlum"` (neither a path nor a built-in model) failed later
/// without the scene file, field or line.
#[test]
fn unknown_model_name_names_the_field_and_place() {
    let text = scene_text("g = 9.81", "x = 1.0", "end = 1.0", "none")
        .replace("\"pendulum\"", "\"pendlum\"");
    let err = Scene::parse(&text, "t.toml", None)
        .expect_err("an unknown model is a scene error")
        .to_string();
    assert!(err.starts_with("t.toml:2:9:"), "{err}");
    assert!(err.contains("`model`") && err.contains("pendlum"), "{err}");
    assert!(err.contains("pendulum"), "lists the built-in models: {err}");
}

/// `dae derive` says the same: a directory is a directory, an unknown
/// name is neither a built-in model nor a file.
#[test]
fn derive_names_directories_and_unknown_models() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display().to_string();
    let o = dae(&["derive", &d]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("is a directory"), "{}", stderr(&o));
    let o = dae(&["derive", "pendlum"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("neither a built-in model (built-in: pendulum)"),
        "{}",
        stderr(&o)
    );
}

// ----------------------------------------------- 7. accuracy verdict

/// The pendulum released at 179.99°, on g = 9.81: bdf's error is far above
/// its tolerance but was reported as plain "ok".
const NEAR_TOP: &str = "x = 1.7453292431344840e-4\ny = 0.9999999847691291";

#[test]
fn confident_wrong_answers_are_flagged() {
    let text = scene_text("g = 9.81", NEAR_TOP, "end = 5.0", "pendulum-exact");
    let (_dir, path) = scene_file("top.toml", &text);
    for (solver, tol, verdict) in [
        ("bdf", "1e-6", "inaccurate"),
        ("bdf", "1e-3", "inaccurate"),
        ("radau5", "1e-6", "accurate"),
    ] {
        let args = [
            "run",
            &path,
            "--solver",
            solver,
            "--formulation",
            "rcd0",
            "--tol",
            tol,
        ];
        let o = dae(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v = json(&o);
        assert_eq!(v["status"], "ok");
        assert_eq!(v["accuracy"], verdict, "{solver} {tol}: {v}");
        let mut text_args = args.to_vec();
        text_args.extend(["--format", "text"]);
        let o = dae(&text_args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let shown = stdout(&o).contains("INACCURATE");
        assert_eq!(shown, verdict == "inaccurate", "{}", stdout(&o));
    }
}

/// g/L = 1e6 released near the top: bdf's error was ~1e3 and its energy
/// drift 6e5, reported as "ok". With the reference: inaccurate; without
/// one, the residuals give it away: suspect. radau5 on the benign S01 start
/// without a reference: unverified.
#[test]
fn stiff_wrong_answers_are_inaccurate_or_suspect() {
    let run = |parameters: &str, initial: &str, reference: &str, solver: &str| {
        let text = scene_text(parameters, initial, "end = 0.05", reference);
        let scene = Scene::parse(&text, "stiff.toml", None).unwrap();
        let inputs = inputs(&scene).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(inputs.reference.is_some(), reference == "pendulum-exact");
        let rec = runner::run(&inputs.spec(&scene, solver, "rcd0", 1e-6)).unwrap();
        assert_eq!(rec.status, "ok", "{:?}", rec.error);
        rec
    };
    let rec = run("g = 9.81e6", NEAR_TOP, "pendulum-exact", "bdf");
    assert_eq!(
        rec.accuracy,
        Some(runner::Accuracy::Inaccurate),
        "{:?}",
        rec.accuracy_note
    );
    let rec = run("g = 9.81e6", NEAR_TOP, "none", "bdf");
    assert_eq!(
        rec.accuracy,
        Some(runner::Accuracy::Suspect),
        "{:?}",
        rec.accuracy_note
    );
    assert!(rec.accuracy_note.unwrap().contains("residual"));
    let rec = run("g = 13.75", "x = 1.0\ny = 0.0", "none", "radau5");
    assert_eq!(
        rec.accuracy,
        Some(runner::Accuracy::Unverified),
        "{:?}",
        rec.accuracy_note
    );
}

/// The sweep's tables carry the verdict next to "reached the end": the
/// success matrix (text and index.html), results.csv and results.json.
#[test]
fn sweep_tables_show_the_verdict() {
    let scene = Scene::builtin("s01").unwrap();
    let opts = SweepOptions {
        solvers: vec!["radau5".into(), "bdf".into()],
        formulations: vec!["rcd0".into()],
        tolerances: vec![1e-5],
        repeats: 1,
        progress: false,
        ..SweepOptions::from_scene(&scene)
    };
    let report = sweep::run(&scene, &opts).unwrap();
    let summary = sweep::Summary::of(&report);
    // S01 at 1e-5: radau5 within 100·tol, bdf about 1e3·tol off.
    let cell = |s| summary.success.cell(s, "rcd0").unwrap().label();
    assert_eq!(
        (cell("radau5"), cell("bdf")),
        ("X 1/1".into(), "X 0/1".into())
    );
    let text = sweep::table::text_report(&report, &summary);
    assert!(text.contains("1 of 2 finished runs accurate"), "{text}");
    assert!(text.contains("INACCURATE"), "{text}");
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("s01");
    sweep::write_outputs(&report, &summary, &out, None).unwrap();
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(&head[4..6], ["status", "accuracy"]);
    assert!(
        csv.lines().nth(1).unwrap().contains(",ok,accurate,"),
        "{csv}"
    );
    assert!(
        csv.lines().nth(2).unwrap().contains(",ok,inaccurate,"),
        "{csv}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["runs"][1]["accuracy"], "inaccurate");
    assert_eq!(json["success"]["rows"][1]["cells"][0]["inaccurate"], 1);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("<small class=\"bad\">0/1</small>"), "{html}");
    assert!(html.contains("<small>1/1</small>"));
}

// ------------------------------------------- 8. the looping pendulum

/// A start with speed enough to loop over the top had no reference at all
/// ("pendulum-exact describes a release at rest").
#[test]
fn looping_start_has_an_exact_reference() {
    // At the bottom with speed 10 on g = 9.81, L = 1: k² = 100/(4·9.81) > 1.
    let text = scene_text(
        "g = 9.81",
        "x = 0.0\ny = -1.0\nv = 10.0\nw = 0.0",
        "end = 3.0\ncheck_every = 0.5",
        "pendulum-exact",
    );
    let (_dir, path) = scene_file("loop.toml", &text);
    let o = dae(&[
        "run",
        &path,
        "--solver",
        "radau5",
        "--formulation",
        "ggl1",
        "--tol",
        "1e-10",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    let err = v["err"].as_f64().expect("an error against the reference");
    assert!(err < 1e-7, "err {err:e}");
}

/// A velocity off the tangent is refused at its field.
#[test]
fn radial_start_velocity_is_refused_at_its_field() {
    let text = scene_text(
        "g = 9.81",
        "x = 1.0\ny = 0.0\nv = 1.0\nw = 0.0",
        "end = 1.0",
        "pendulum-exact",
    );
    let (_dir, path) = scene_file("radial.toml", &text);
    let o = dae(&["run", &path]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.starts_with(&format!("{path}:8:1: `initial.v`")),
        "{err}"
    );
    assert!(err.contains("not tangent"), "{err}");
}

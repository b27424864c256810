//! The least-squares solvers `odradau` and `odbdf` through the root crate:
//! scenes with interpreted models (the double pendulum of
//! `scenes/double_pendulum.dae`, the spherical pendulum of
//! `scenes/spherical_pendulum.dae`) on their overdetermined formulations,
//! run by `dae::runner` as `dae run` and `dae sweep` run them; and the
//! `dae run` command line with the new solvers.

use dae::inputs::inputs;
use dae::runner::{self, RunError, RunRecord, RunSpec};
use dae::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// The spherical pendulum released off the vertical with a velocity across
/// the meridian (a consistent start: `x u + y v + z w = 0`), checked every
/// 0.1 s.
const SPHERICAL: &str = r#"name = "spherical"
model = "spherical_pendulum.dae"
[initial]
x = 0.6
y = 0.0
z = -0.8
u = 0.0
v = 1.5
w = 0.0
[time]
end = 3.0
check_every = 0.1
[reference]
kind = "none"
"#;

fn double_pendulum() -> Scene {
    let mut scene = Scene::load(scenes_dir().join("double_pendulum.toml")).expect("scene loads");
    // A short horizon: three seconds, checked every 0.1 s.
    scene.time.end = 3.0;
    scene.time.checks = (1..=30).map(|k| 0.1 * f64::from(k)).collect();
    scene
}

fn spherical_pendulum() -> Scene {
    Scene::parse(SPHERICAL, "spherical.toml", Some(&scenes_dir())).expect("scene parses")
}

/// One run of `scene` as `dae run` does it.
fn run(scene: &Scene, solver: &str, formulation: &str, tol: f64) -> Result<RunRecord, RunError> {
    let inputs = inputs(scene).unwrap_or_else(|e| panic!("{e}"));
    runner::run(&RunSpec {
        reference: None,
        ..inputs.spec(scene, solver, formulation, tol)
    })
}

/// The overdetermined runs: `odradau` on `ovd0` and `ovd1`, `odbdf` on
/// `ovd0`.
const OD_RUNS: [(&str, &str); 3] = [("odradau", "ovd0"), ("odradau", "ovd1"), ("odbdf", "ovd0")];

/// Succeeds to the end of the horizon with constraint residuals (largest
/// over the check times, dense output) and energy drift near the
/// tolerance; prints what it measured.
fn check_run(scene: &Scene, solver: &str, formulation: &str, tol: f64) -> RunRecord {
    let what = format!("{} {solver} {formulation} {tol:e}", scene.name);
    let r = run(scene, solver, formulation, tol).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(r.status, "ok", "{what}: {:?}", r.error);
    assert!(r.error.is_none());
    assert_eq!(r.t_end, scene.time.end, "{what}");
    assert_eq!(
        (r.solver.as_str(), r.formulation.as_str()),
        (solver, formulation)
    );
    let res = &r.residuals;
    let (l0, l1, l2) = (
        res.level(0).expect("position level"),
        res.level(1).expect("velocity level"),
        res.level(2).expect("acceleration level"),
    );
    let drift = r.invariant_drift.get("energy").expect("energy");
    println!(
        "{what}: {} steps, residuals {l0:.1e} {l1:.1e} {l2:.1e}, energy drift {drift:.1e}",
        r.stats.steps
    );
    let s = r.stats;
    assert!(s.steps > 10 && s.newton_iterations >= s.steps && s.factorizations > 0);
    // odradau holds the stages on the constraints, to far below the
    // tolerance even between the steps; odbdf to its Newton tolerance times
    // the constraint gradients, and its dense output (BDF interpolation)
    // is within its local error of them.
    let (b0, b1) = if solver == "odradau" {
        (0.1, 1.0)
    } else {
        (50.0, 500.0)
    };
    assert!(l0 <= b0 * tol, "{what}: position residual {l0:e}");
    assert!(l1 <= b1 * tol, "{what}: velocity residual {l1:e}");
    assert!(l2.is_finite());
    assert!(drift <= 1e3 * tol, "{what}: energy drift {drift:e}");
    r
}

#[test]
fn double_pendulum_on_the_overdetermined_formulations() {
    let scene = double_pendulum();
    for (solver, formulation) in OD_RUNS {
        for tol in [1e-6, 1e-8] {
            check_run(&scene, solver, formulation, tol);
        }
    }
}

#[test]
fn spherical_pendulum_on_the_overdetermined_formulations() {
    let scene = spherical_pendulum();
    for (solver, formulation) in OD_RUNS {
        for tol in [1e-6, 1e-8] {
            let r = check_run(&scene, solver, formulation, tol);
            // The angular momentum about the vertical is conserved too.
            let lz = r
                .invariant_drift
                .get("angular_momentum_z")
                .expect("angular momentum");
            assert!(lz <= 1e3 * tol, "{solver} {formulation} {tol:e}: {lz:e}");
        }
    }
}

/// Over three seconds the overdetermined runs agree with `radau5` on the
/// strangeness-free `psi0` to far better than the motion's scale.
#[test]
fn overdetermined_runs_agree_with_radau5() {
    let tol = 1e-9;
    for scene in [double_pendulum(), spherical_pendulum()] {
        let reference = run(&scene, "radau5", "psi0", tol).expect("radau5 psi0");
        assert_eq!(reference.status, "ok", "{:?}", reference.error);
        for (solver, formulation) in OD_RUNS {
            let r = run(&scene, solver, formulation, tol).expect("run");
            assert_eq!(r.status, "ok", "{:?}", r.error);
            let diff = r
                .final_values
                .0
                .iter()
                .zip(&reference.final_values.0)
                .filter(|((name, _), _)| !name.starts_with("lambda"))
                .map(|((na, a), (nb, b))| {
                    assert_eq!(na, nb);
                    (a - b).abs()
                })
                .fold(0.0, f64::max);
            println!(
                "{} {solver} {formulation}: final state differs from radau5 psi0 by {diff:.1e}",
                scene.name
            );
            let bound = if solver == "odradau" { 1e-6 } else { 1e-3 };
            assert!(
                diff <= bound,
                "{} {solver} {formulation}: {diff:e}",
                scene.name
            );
        }
    }
}

#[test]
fn refused_formulations_are_input_errors() {
    let scene = double_pendulum();
    for (solver, formulation, c_level, max) in [
        ("odradau", "ori2", 2, 1),
        ("odbdf", "ori2", 2, 0),
        ("odbdf", "ovd1", 1, 0),
        ("odbdf", "ggl1", 1, 0),
    ] {
        match run(&scene, solver, formulation, 1e-6) {
            Err(RunError::NotApplicable {
                solver: s,
                formulation: f,
                why,
            }) => {
                assert_eq!((s.as_str(), f.as_str()), (solver, formulation));
                assert_eq!(
                    why,
                    format!("constraint level {c_level}: solver needs c-level at most {max}")
                );
            }
            other => panic!("{solver} {formulation}: {:?}", other.map(|r| r.status)),
        }
    }
}

// ---------------------------------------------------------------------------
// The command line
// ---------------------------------------------------------------------------

fn dae(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dae"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the dae binary runs")
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: {}\n{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    })
}

/// Every key path of a JSON value (`stats.steps`, …) through its objects,
/// sorted. (`final` and `invariant_drift` are keyed by the model's names:
/// the same for `rcd0`, `ovd1` and `ovd0`, which share their unknowns.)
fn key_paths(v: &serde_json::Value) -> Vec<String> {
    fn walk(v: &serde_json::Value, prefix: &str, out: &mut Vec<String>) {
        if let Some(map) = v.as_object() {
            for (k, child) in map {
                let path = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                walk(child, &path, out);
                out.push(path);
            }
        }
    }
    let mut out = Vec::new();
    walk(v, "", &mut out);
    out.sort();
    out
}

#[test]
fn dae_run_with_the_overdetermined_solvers() {
    let run_json = |solver: &str, formulation: &str| {
        let o = dae(&[
            "run",
            "s01",
            "--solver",
            solver,
            "--formulation",
            formulation,
            "--tol",
            "1e-6",
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{solver} {formulation}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        json(&o)
    };
    let base = run_json("radau5", "rcd0");
    let base_keys = key_paths(&base);
    for key in ["stats.steps", "stats.newton_iterations", "residuals.level2"] {
        assert!(base_keys.iter().any(|k| k == key), "radau5 lacks {key}");
    }
    for (solver, formulation) in OD_RUNS {
        let v = run_json(solver, formulation);
        assert_eq!(
            key_paths(&v),
            base_keys,
            "{solver} {formulation}: the JSON shape"
        );
        assert_eq!(v["status"], "ok");
        assert_eq!(v["solver"], solver);
        assert_eq!(v["formulation"], formulation);
        assert_eq!(v["t_end"], 20.0);
        for k in [
            "steps",
            "rejected",
            "residual_evals",
            "jacobian_evals",
            "factorizations",
            "newton_iterations",
        ] {
            let n = v["stats"][k].as_u64();
            assert!(n.is_some(), "{solver}: stats.{k}");
        }
        assert!(v["stats"]["steps"].as_u64().unwrap() > 100);
        let err = v["err"]
            .as_f64()
            .expect("an error against the exact solution");
        println!("dae run s01 {solver} {formulation}: err {err:.1e}");
        assert!(err < 0.05, "{solver} {formulation}: err {err:e}");
        let l0 = v["residuals"]["level0"].as_f64().unwrap();
        assert!(
            l0 < 1e-4,
            "{solver} {formulation}: position residual {l0:e}"
        );
    }
}

#[test]
fn dae_run_picks_the_solvers_preferred_formulation() {
    // Without --formulation, the first of the solver's preferred ones
    // (dae_solvers::core::policy::preferred_formulations): for both
    // least-squares solvers the overdetermined ovd0, which keeps every
    // constraint level (it used to be the scene's first they accept:
    // rcd1 and rcd0).
    for (solver, expected) in [("odradau", "ovd0"), ("odbdf", "ovd0")] {
        let o = dae(&["run", "s01", "--solver", solver, "--tol", "1e-5"]);
        assert_eq!(o.status.code(), Some(0), "{solver}");
        assert_eq!(json(&o)["formulation"], expected, "{solver}");
    }
}

#[test]
fn dae_run_refuses_what_the_solver_does_not_accept() {
    for (solver, formulation) in [("odbdf", "ovd1"), ("odradau", "ori2")] {
        let o = dae(&[
            "run",
            "s01",
            "--solver",
            solver,
            "--formulation",
            formulation,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{solver} {formulation}: {err}");
        assert!(err.contains("constraint level"), "{err}");
        assert!(err.contains(solver) && err.contains(formulation), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

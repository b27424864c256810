//! References as data (`dae::reference::data`, `[reference]` in scenes):
//! each kind measured against the same run, the scalings, the IVP Test
//! Set's significant correct digits, and the refusals with their places.

use dae::inputs::{inputs, InputError};
use dae::reference::PendulumExact;
use dae::runner::{self, RunRecord};
use dae::scene::{ModelSource, Scene, SceneError};
use std::fmt::Write as _;
use std::path::Path;

const G: f64 = 9.81;

/// The pendulum released at `x = 1`, over two seconds, with `reference`.
fn scene_text(time: &str, reference: &str) -> String {
    format!(
        "name = \"R\"\nmodel = \"pendulum\"\n[parameters]\ng = {G}\n[initial]\nx = 1.0\ny = 0.0\n\
         v = 0.0\nw = 0.0\n[time]\nend = 2.0\n{time}\n[reference]\n{reference}\n"
    )
}

fn scene(text: &str, dir: Option<&Path>) -> Scene {
    Scene::parse(text, "r.toml", dir).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn exact() -> PendulumExact {
    PendulumExact::from_start(1.0, 0.0, 1.0, G, 1.0).unwrap()
}

/// radau5 on ggl1 (which appends the `eta` unknowns: the reference's
/// names, not positions, pick the components) at `tol`.
fn run(scene: &Scene, tol: f64) -> RunRecord {
    let inputs = inputs(scene).unwrap_or_else(|e| panic!("{e}"));
    let r = runner::run(&inputs.spec(scene, "radau5", "ggl1", tol)).unwrap();
    assert_eq!(r.status, "ok", "{:?}", r.error);
    r
}

/// A `values` reference holding the closed form at 0.5 and 2.0 measures
/// exactly what the `exact` reference measures when checked at those
/// times: the same err, err_sum, err_l2 and algebraic error, to the last
/// bits.
#[test]
fn values_at_given_times_measure_what_the_closed_form_measures() {
    let times = [0.5, 2.0];
    let mut values = String::new();
    for (j, name) in PendulumExact::COMPONENTS.iter().enumerate() {
        let list: Vec<String> = times
            .iter()
            .map(|&t| format!("{:e}", exact().state(t)[j]))
            .collect();
        let _ = write!(values, "{name} = [{}], ", list.join(", "));
    }
    let by_values = run(
        &scene(
            &scene_text(
                "check_every = 0.25",
                &format!(
                    "kind = \"values\"\ntimes = [0.5, 2.0]\nvalues = {{ {} }}",
                    values.trim_end_matches(", ")
                ),
            ),
            None,
        ),
        1e-8,
    );
    let by_exact = run(
        &scene(&scene_text("check = [0.5, 2.0]", "kind = \"exact\""), None),
        1e-8,
    );
    for (what, a, b) in [
        ("err", by_values.err, by_exact.err),
        ("err_sum", by_values.err_sum, by_exact.err_sum),
        ("err_l2", by_values.err_l2, by_exact.err_l2),
        (
            "err_algebraic",
            by_values.err_algebraic,
            by_exact.err_algebraic,
        ),
    ] {
        let (a, b) = (a.expect(what), b.expect(what));
        assert!(
            a > 0.0 && (a - b).abs() <= 1e-12 * b,
            "{what}: {a:e} vs {b:e}"
        );
    }
    assert!(by_values.err.unwrap() < 1e-6);
    assert_eq!(by_values.accuracy, by_exact.accuracy);
    // The errors were measured at the reference's times only, not at the
    // eight check times: err_sum of two times.
    let by_exact_all = run(
        &scene(&scene_text("check_every = 0.25", "kind = \"exact\""), None),
        1e-8,
    );
    assert!(by_exact_all.err_sum.unwrap() > by_values.err_sum.unwrap());
}

/// A trajectory sampled every millisecond, read from a CSV beside the
/// scene and interpolated at the check times, measures what the closed
/// form measures, up to the interpolation error (~1e-11, far below the
/// run's error).
#[test]
fn a_sampled_trajectory_is_interpolated_at_the_check_times() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("# the pendulum, sampled\nt, x, y, v, w, lambda\n");
    for i in 0..=2000 {
        let t = f64::from(i) * 1e-3;
        let s = exact().state(t);
        let _ = writeln!(
            csv,
            "{t:e},{:e},{:e},{:e},{:e},{:e}",
            s[0], s[1], s[2], s[3], s[4]
        );
    }
    std::fs::write(dir.path().join("traj.csv"), csv).unwrap();
    let text = scene_text(
        "check_every = 0.1",
        "kind = \"trajectory\"\nfile = \"traj.csv\"",
    );
    let by_trajectory = run(&scene(&text, Some(dir.path())), 1e-6);
    let by_exact = run(
        &scene(&scene_text("check_every = 0.1", "kind = \"exact\""), None),
        1e-6,
    );
    let (a, b) = (by_trajectory.err.unwrap(), by_exact.err.unwrap());
    assert!(b > 1e-9 && (a - b).abs() < 1e-9, "{a:e} vs {b:e}");
    let (a, b) = (by_trajectory.err_sum.unwrap(), by_exact.err_sum.unwrap());
    assert!((a - b).abs() < 1e-7 * 20.0, "{a:e} vs {b:e}");
    // The figure series: one (t, error) per output time.
    assert_eq!(
        by_trajectory.trajectory.err.len(),
        by_trajectory.trajectory.t.len()
    );
}

/// Relative scaling divides by the reference value; the significant
/// correct digits are −log₁₀ of the largest scaled error, as the IVP Test
/// Set computes them from the final values.
#[test]
fn relative_scaling_and_significant_correct_digits() {
    let s = exact().state(2.0);
    // x and y only (no algebraic unknown): err_algebraic is null.
    let reference = format!(
        "kind = \"values\"\ntimes = [2.0]\nvalues = {{ x = [{:e}], y = [{:e}] }}\nscaling = \"relative\"",
        s[0], s[1]
    );
    let r = run(&scene(&scene_text("", &reference), None), 1e-7);
    let fx = r.final_values.get("x").unwrap();
    let fy = r.final_values.get("y").unwrap();
    let rel = [((fx - s[0]) / s[0]).abs(), ((fy - s[1]) / s[1]).abs()];
    let worst = rel[0].max(rel[1]);
    assert!((r.err.unwrap() - worst).abs() <= 1e-12 * worst);
    assert!((r.err_sum.unwrap() - (rel[0] + rel[1])).abs() <= 1e-12 * worst);
    let l2 = rel[0].hypot(rel[1]);
    assert!((r.err_l2.unwrap() - l2).abs() <= 1e-12 * l2);
    assert!((r.scd.unwrap() + worst.log10()).abs() < 1e-12);
    assert!(r.scd.unwrap() > 4.0, "{:?}", r.scd);
    assert_eq!(r.err_algebraic, None);
    // Per component: y absolute, x relative.
    let reference = reference.replace("scaling = \"relative\"", "scaling = { x = \"relative\" }");
    let r = run(&scene(&scene_text("", &reference), None), 1e-7);
    let mixed = rel[0] + (fy - s[1]).abs();
    assert!((r.err_sum.unwrap() - mixed).abs() <= 1e-12 * mixed);
}

/// Every refusal names the field and its place, at parse time where the
/// scene alone shows the problem, when the inputs are built where the
/// model does.
#[test]
fn refusals_name_the_field_and_place() {
    let parse_err = |reference: &str, dir: Option<&Path>| -> SceneError {
        let text = scene_text("", reference);
        Scene::parse(&text, "r.toml", dir).expect_err(reference)
    };
    let cases: [(&str, &str); 8] = [
        ("kind = \"values\"", "missing field `reference.file`"),
        ("kind = \"values\"\ntimes = [1.0]", "missing field `reference.values`"),
        (
            "kind = \"values\"\ntimes = [1.0, 2.0]\nvalues = { x = [1.0] }",
            "`reference.values.x`: 1 values for the 2 times",
        ),
        (
            "kind = \"values\"\ntimes = [2.0, 1.0]\nvalues = { x = [1.0, 2.0] }",
            "times must increase strictly",
        ),
        (
            "kind = \"values\"\ntimes = [1.0]\nvalues = { x = [1.0] }\nscaling = \"digits\"",
            "must be one of absolute, relative",
        ),
        (
            "kind = \"values\"\ntimes = [1.0]\nvalues = { x = [1.0] }\nscaling = { z = \"relative\" }",
            "`z` is not a column of the reference",
        ),
        ("kind = \"exact\"\nfile = \"a.csv\"", "does not apply to a reference of kind \"exact\""),
        ("kind = \"exact\"\nclosed_form = \"kepler\"", "\"kepler\" is unknown (known: pendulum)"),
    ];
    for (reference, expected) in cases {
        let msg = parse_err(reference, None).to_string();
        assert!(msg.starts_with("r.toml:1"), "{reference}: {msg}");
        assert!(msg.contains(expected), "{reference}: {msg}");
    }
    // Files: missing, not regular, malformed (with the CSV line).
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.csv"), "t,x\n0,1\n1,x1\n").unwrap();
    std::fs::create_dir(dir.path().join("folder.csv")).unwrap();
    for (file, expected) in [
        ("missing.csv", "cannot read"),
        ("folder.csv", "not a regular file"),
        ("bad.csv", "line 3: column `x`: `x1` is not a number"),
    ] {
        let reference = format!("kind = \"trajectory\"\nfile = \"{file}\"");
        let msg = parse_err(&reference, Some(dir.path())).to_string();
        assert!(
            msg.contains("`reference.file`") && msg.contains(expected),
            "{msg}"
        );
    }
    // Needs the model or the horizon: when the inputs are built.
    for (reference, expected) in [
        (
            "kind = \"values\"\ntimes = [1.0]\nvalues = { q = [1.0] }",
            "`q` is not an unknown of the model",
        ),
        (
            "kind = \"values\"\ntimes = [3.0]\nvalues = { x = [1.0] }",
            "reference time 3 is outside the horizon [0, 2]",
        ),
    ] {
        let s = scene(&scene_text("", reference), None);
        let Err(e @ InputError::Reference { .. }) = inputs(&s) else {
            panic!("{reference}: expected a reference refusal")
        };
        let msg = e.to_string();
        assert!(
            msg.starts_with("r.toml:") && msg.contains(expected),
            "{msg}"
        );
    }
    // A trajectory that does not cover the check times.
    let mut csv = String::from("t,x\n");
    for t in [0.0, 0.5, 1.0] {
        let _ = writeln!(csv, "{t},{}", exact().state(t)[0]);
    }
    std::fs::write(dir.path().join("short.csv"), csv).unwrap();
    let s = scene(
        &scene_text("", "kind = \"trajectory\"\nfile = \"short.csv\""),
        Some(dir.path()),
    );
    let msg = inputs(&s).err().expect("not covered").to_string();
    assert!(
        msg.contains("check time 2 is outside the trajectory's samples [0, 1]"),
        "{msg}"
    );
}

/// A model file whose path reads like a built-in's name is still the file.
#[test]
fn a_model_file_named_like_a_builtin_is_loaded_as_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let text = dae::models::PENDULUM_SOURCE.replace("g = 13.7503716373294544", "g = 1.5");
    std::fs::write(dir.path().join("pendulum"), text).unwrap();
    let mut s = scene(&scene_text("", "kind = \"none\""), None);
    s.model = ModelSource::File(dir.path().join("pendulum"));
    s.parameters.clear();
    let model = inputs(&s).unwrap_or_else(|e| panic!("{e}")).model;
    assert_eq!(model.parameter("g"), Some(1.5));
}

/// The shipped published-reference scene: Andrews' squeezing mechanism
/// against the IVP Test Set's values at t = 0.03. Its sweep has error
/// columns, a Pareto front by error and, besides the work-precision
/// diagram, the Test Set's scd diagram.
#[test]
fn andrews_against_the_ivp_test_set() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::load(dir.join("andrews.toml")).unwrap_or_else(|e| panic!("{e}"));
    let opts = dae::sweep::SweepOptions {
        solvers: vec!["radau5".into(), "bdf".into()],
        formulations: vec!["rcd0".into(), "ovd0".into(), "ori2".into()],
        tolerances: vec![1e-5, 1e-6],
        repeats: 1,
        progress: false,
        ..dae::sweep::SweepOptions::from_scene(&scene)
    };
    let report = dae::sweep::run(&scene, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(report.has_reference());
    let radau = report
        .runs
        .iter()
        .find(|r| {
            let r = &r.record;
            r.solver == "radau5" && r.formulation == "rcd0" && r.tol == 1e-6
        })
        .expect("radau5(rcd0) at 1e-6");
    assert_eq!(radau.record.status, "ok", "{:?}", radau.record.error);
    // Measured 10.07 significant correct digits on the seven angles (the
    // Test Set reports about 6–10 for RADAU5 at these tolerances).
    let scd = radau.record.scd.expect("scd");
    assert!(scd > 8.0, "scd {scd}");
    assert!((radau.record.err.unwrap() - 10f64.powf(-scd)).abs() < 1e-12);
    // The Test Set's own index-3 form, the way RADAU5 runs it there: the 13
    // accelerations and multipliers of index 3, their errors scaled by h².
    // radau5(ori2) measured 5.38 and 5.96 scd at 1e-5 and 1e-6; before the
    // multipliers had their index (they were taken as index 1) every
    // tolerance failed at t = 0 (newton_failure), bdf's too. bdf refuses
    // it now, before a step: variable-step BDF has no convergence theory
    // at index 3 (core::policy::variable_step_index3; EXTREMES.md §5,
    // idx10: it gave 0.4 and 1.3 digits here at 1e-5 and 1e-6).
    for r in report
        .runs
        .iter()
        .filter(|r| r.record.formulation == "ori2")
    {
        let r = &r.record;
        if r.solver == "bdf" {
            let e = r.error.as_ref().expect("bdf(ori2) is refused");
            assert_eq!(e.kind, "not_applicable", "{}", e.message);
            assert!(e.message.contains("variable-step BDF"), "{}", e.message);
            continue;
        }
        assert_eq!(
            r.status, "ok",
            "{}(ori2) at {:e}: {:?}",
            r.solver, r.tol, r.error
        );
        if r.solver == "radau5" {
            let scd = r.scd.expect("scd");
            assert!(scd > 5.0, "radau5(ori2) at {:e}: scd {scd}", r.tol);
        }
    }
    let summary = dae::sweep::Summary::of(&report);
    assert!(!summary.pareto.is_empty());
    let figures = dae::sweep::plot::figures(&report);
    let files: Vec<&str> = figures.figures.iter().map(|f| f.file.as_str()).collect();
    assert!(
        files.contains(&"work_precision") && files.contains(&"scd"),
        "{files:?}"
    );
}

/// Andrews' squeezer in rcd0 at tolerances where the Newton increments of
/// the Radau solvers stop at the arithmetic's floor, 0.03–0.34 of the
/// tolerance at 1e-9 whatever the step (`core::newton`'s round-off floor):
/// with the floor at 1e-2 radau5 failed at t = 0.011 (1e-9) and t = 5.6e-5
/// (1e-10), odradau at 1e-10, all `newton_failure`. Both now reach t = 0.03
/// with 9.57 significant digits, the arithmetic's limit here (10.1 at 1e-6).
#[test]
fn andrews_rcd0_at_the_newton_round_off_floor() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::load(dir.join("andrews.toml")).unwrap_or_else(|e| panic!("{e}"));
    let inputs = inputs(&scene).unwrap_or_else(|e| panic!("{e}"));
    for solver in ["radau5", "odradau"] {
        for tol in [1e-9, 1e-10] {
            let spec = inputs.spec(&scene, solver, "rcd0", tol);
            let record = runner::run(&spec).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(
                record.status, "ok",
                "{solver} at {tol:e}: {:?}",
                record.error
            );
            let scd = record.scd.expect("scd");
            assert!(scd > 9.0, "{solver} at {tol:e}: scd {scd}");
        }
    }
}

/// mebdf on the squeezer's rcd0 at 1e-5 met an accepted value whose
/// acceleration `dea` missed its equation by 8e-4 (Newton had converged
/// under the weights of the value before, when `dea` was larger): the
/// order-one error estimate then stayed at 2.48 for every step from 1e-6
/// down to 3e-17 and the run stopped (`step_size_too_small` at t = 0.021).
/// mebdf now restarts from its order-one attempt once the estimate stops
/// falling with the step (`multistep::stale`, `restart`). And at 1e-9, where
/// its Newton iteration meets the arithmetic's floor.
#[test]
fn mebdf_restarts_when_its_estimate_stops_falling_with_the_step() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::load(dir.join("andrews.toml")).unwrap_or_else(|e| panic!("{e}"));
    let inputs = inputs(&scene).unwrap_or_else(|e| panic!("{e}"));
    let record =
        runner::run(&inputs.spec(&scene, "mebdf", "rcd0", 1e-5)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(record.status, "ok", "{:?}", record.error);
    // mebdf's rcd0 is loose here as on the pendulum (BENCHMARKS §2d: 1.9e-2
    // at 1e-4, 1.4e-4 at 1e-6); measured 1.3e-3 (2.89 digits).
    let scd = record.scd.expect("scd");
    assert!(scd > 2.0, "scd {scd}");
    // At 1e-9 the stage increments stagnate at 1e-4 … 1e-3 of the
    // tolerance (round-off), which DASSL's rule took for divergence at every
    // step size (`newton_failure`); mebdf's Newton floor takes it for
    // convergence. Measured 6.52 digits.
    let record =
        runner::run(&inputs.spec(&scene, "mebdf", "rcd0", 1e-9)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(record.status, "ok", "1e-9: {:?}", record.error);
    let scd = record.scd.expect("scd");
    assert!(scd > 6.0, "1e-9: scd {scd}");
}

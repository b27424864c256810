//! Defaults are decided in one place (`dae_solvers::core::policy`): the
//! library with default `Options` and `dae run` (the runner) give the same
//! run for the same inputs.
//!
//! The case that showed they did not: BDF on the spherical pendulum in
//! `ggl1` at tolerance 1e-6. With the index-2 multipliers in the error test
//! (the library's old default) it took 2,301,932 steps; the runner, which
//! left them out, 1,588.

use dae::dae_solvers::{bdf::Bdf, init, Options, Problem, Solver};
use dae::runner::{run, RunSpec};
use dae_core::system::Model;
use dae_solvers::InitMode;

mod spherical {
    dae::dae! { include "scenes/spherical_pendulum.dae" }
}

const T_END: f64 = 10.0;
const TOL: f64 = 1e-6;

fn initial() -> Vec<(String, f64)> {
    [
        ("x", 0.6),
        ("y", 0.0),
        ("z", -0.8),
        ("u", 0.0),
        ("v", 2.0),
        ("w", 0.0),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

#[test]
fn bdf_defaults_equal_the_runner_on_the_spherical_pendulum_ggl1() {
    let model = spherical::SphericalPendulum::default();
    let sys = model.formulation("ggl1").expect("ggl1 is provided");
    let info = sys.info().clone();
    let mut y = vec![0.0; info.unknowns()];
    for (name, v) in initial() {
        y[info.variable(&name).expect("known unknown")] = v;
    }
    let start = init::consistent(&*sys, 0.0, &y, &Default::default()).expect("consistent start");
    let problem = Problem {
        system: &*sys,
        t0: 0.0,
        y0: &start.y,
        t_end: T_END,
    };
    let library = Bdf
        .solve(&problem, &Options::with_tol(TOL))
        .expect("default options succeed");
    assert!(
        library.stats.steps < 20_000,
        "default options: {} steps",
        library.stats.steps
    );

    let initial = initial();
    let record = run(&RunSpec {
        scene: "spherical",
        model: &model,
        initial: &initial,
        guess: &[],
        t0: 0.0,
        t_end: T_END,
        check: &[T_END],
        reference: None,
        solver: "bdf",
        formulation: "ggl1",
        tol: TOL,
        tolerances: None,
        record_steps: false,
        init_mode: InitMode::Project,
        samples: &[],
        repeats: 1,
        max_steps: None,
        events: &[],
        estimate: Default::default(),
    })
    .expect("the runner runs");
    assert_eq!(record.status, "ok");
    assert_eq!(record.stats, library.stats, "library and runner differ");

    // Asking for the multipliers in the test is still possible, and is the
    // expensive choice the old default made.
    let strict = Options {
        index2_in_error_test: Some(true),
        max_steps: 20 * library.stats.steps,
        ..Options::with_tol(TOL)
    };
    match Bdf.solve(&problem, &strict) {
        Ok(sol) => assert!(
            sol.stats.steps > 5 * library.stats.steps,
            "{} vs {}",
            sol.stats.steps,
            library.stats.steps
        ),
        Err(e) => assert!(
            matches!(e.kind(), "step_limit" | "step_size_too_small"),
            "{e}"
        ),
    }
}

//! The solution object and the stepper against the exact pendulum:
//! `Solution::at` between the steps, access by name, and
//! `Solver::integrator` stepped to the end or to given times, for every
//! solver of the crate.
//!
//! The model is the built-in pendulum of the `dae!` macro (`scenes/
//! pendulum.dae`: `m = l = 1`, the paper's `g`, unknowns `x, y, v, w,
//! lambda`), started at rest at `x = 1`; its exact solution is
//! [`common::pendulum_exact`] (Jacobi elliptic functions, no files read).

mod common;

use common::pendulum_exact;
use dae::models::builtin::Pendulum;
use dae_core::system::{DaeSystem, Model};
use dae_solvers::{
    solver_by_name, Options, Problem, Solution, SolutionError, SolveError, Solver, StepOutcome,
};

/// Horizon: one period of the paper's pendulum (≈ 2 s), past both turning
/// points.
const T_END: f64 = 2.0;

/// The consistent start `x = 1, y = v = w = λ = 0` (`η = 0` for ggl1).
fn start(sys: &dyn DaeSystem) -> Vec<f64> {
    let mut y = vec![1.0, 0.0, 0.0, 0.0, 0.0];
    y.resize(sys.info().unknowns(), 0.0);
    y
}

/// Every solver with a formulation it integrates, and the variation of its
/// options the test also covers: bdf and mebdf with a constant step
/// (their start-up run, then the constant-step run).
fn cases() -> Vec<(&'static str, &'static str, Option<f64>)> {
    vec![
        ("radau5", "rcd1", None),
        ("radau5", "ori2", None),
        ("bdf", "rcd0", None),
        ("bdf", "rcd0", Some(1e-3)),
        ("odradau", "ovd1", None),
        ("odbdf", "ovd0", None),
        ("mebdf", "rcd0", None),
        ("mebdf", "rcd0", Some(1e-3)),
        ("idec", "rcd0", None),
        ("gauss", "rcd0", None),
    ]
}

/// Run `f` with the solver, the system and the options of a case.
fn with_case<R>(
    (solver, form, fixed): (&str, &str, Option<f64>),
    tol: f64,
    output_times: Vec<f64>,
    f: impl FnOnce(&dyn Solver, &Problem<'_>, &Options) -> R,
) -> R {
    let model = Pendulum::default();
    let sys = model
        .formulation(form)
        .expect("the pendulum has the formulation");
    let y0 = start(&*sys);
    let problem = Problem {
        system: &*sys,
        t0: 0.0,
        y0: &y0,
        t_end: T_END,
    };
    let options = Options {
        output_times,
        fixed_step: fixed,
        ..Options::with_tol(tol)
    };
    let solver = solver_by_name(solver).expect("a solver of the crate");
    f(&*solver, &problem, &options)
}

/// 200 times strictly inside the horizon, none of them a round number.
fn inner_times() -> Vec<f64> {
    (0..200)
        .map(|k| T_END * (k as f64 + 0.37) / 200.0)
        .collect()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// `at` reproduces each method's own dense polynomial: at the output times,
/// where the solve evaluated that polynomial itself, `at` agrees to
/// rounding (the barycentric interpolant on `d + 1` nodes of a polynomial
/// of degree `≤ d` is that polynomial; the bound is a few hundred units of
/// round-off of values of size ≤ 30, λ the largest). `gauss` projects its
/// output-time values onto the algebraic rows (`rcd0`: λ, the last
/// unknown, recomputed) and `at` keeps the polynomial: there the
/// differential unknowns agree.
#[test]
fn at_reproduces_every_methods_dense_output() {
    for case in cases() {
        with_case(case, 1e-7, inner_times(), |solver, problem, options| {
            let sol = solver.solve(problem, options).unwrap();
            let dense = sol.dense.as_ref().expect("dense output is on by default");
            assert!(dense.step_ends().len() > 10, "{case:?}");
            let compared = if case.0 == "gauss" { 4 } else { 5 };
            let mut worst = 0.0f64;
            for (t, y) in sol.t.iter().zip(&sol.y) {
                let at = sol.at(*t).unwrap();
                worst = worst.max(max_diff(&at[..compared], &y[..compared]));
            }
            assert!(
                worst < 1e-11,
                "{case:?}: at vs the solve's dense output {worst:e}"
            );
        });
    }
}

/// Radau5 and BDF at tol 1e-10 on the exact pendulum, `at` at 200 times
/// between the step points.
///
/// The bound: `at(t)` is the method's dense polynomial on the step, whose
/// error is the global error carried into the step plus the polynomial's
/// own error. Radau IIA's collocation polynomial has local error `O(h⁴)`
/// inside the step against `O(h⁶)` at its end; it is exactly the order
/// RADAU5's embedded estimate controls (`O(h⁴)`, kept below the
/// tolerance), and BDF's interpolant is the polynomial whose distance to
/// the predictor its error test bounds. So between the steps the error is
/// at most the error at the step points plus the local error the
/// tolerance allows, whose weight `atol + rtol |y|` reaches `6 tol` for
/// the velocities (`|v| ≤ 5.3`): asserted as `≤ 3 · err_steps + 10 · tol`
/// per unknown (λ, of size up to 30, relative to 30). Measured (printed
/// with `--nocapture`): radau5(rcd1), 1 651 steps, x, y, v, w 8e-14..5e-13
/// at the steps and 3e-12..4e-11 between them (the collocation
/// polynomial's `O(h⁴)`), λ/30 5.4e-9 and 4.0e-9; bdf(rcd0), 1 086 steps,
/// the same at the steps and between them (4e-9..2e-8: BDF's error is the
/// global error).
#[test]
fn at_between_steps_follows_the_exact_pendulum() {
    let tol = 1e-10;
    for case in [("radau5", "rcd1", None), ("bdf", "rcd0", None)] {
        with_case(case, tol, vec![], |solver, problem, options| {
            let options = Options {
                record_steps: true,
                ..options.clone()
            };
            let sol = solver.solve(problem, &options).unwrap();
            // The error at the step points, per unknown (λ relative to 30).
            let scale = [1.0, 1.0, 1.0, 1.0, 30.0];
            let err = |t: f64, y: &[f64]| {
                let exact = pendulum_exact(t);
                let mut e = [0.0; 5];
                for i in 0..5 {
                    e[i] = (y[i] - exact[i]).abs() / scale[i];
                }
                e
            };
            let mut at_steps = [0.0f64; 5];
            for (t, y) in &sol.steps {
                for (a, e) in at_steps.iter_mut().zip(err(*t, y)) {
                    *a = a.max(e);
                }
            }
            let step_times: Vec<f64> = sol.steps.iter().map(|s| s.0).collect();
            let mut between = [0.0f64; 5];
            let mut inside = 0;
            for t in inner_times() {
                if step_times.contains(&t) {
                    continue;
                }
                inside += 1;
                let y = sol.at(t).unwrap();
                for (b, e) in between.iter_mut().zip(err(t, &y)) {
                    *b = b.max(e);
                }
            }
            assert_eq!(inside, 200, "no time falls on a step point");
            for i in 0..5 {
                assert!(
                    between[i] <= 3.0 * at_steps[i] + 10.0 * tol,
                    "{case:?} unknown {i}: between steps {:e}, at the steps {:e}",
                    between[i],
                    at_steps[i]
                );
            }
            eprintln!(
                "{case:?} tol {tol:e}: {} steps; max error at the steps {:?}, between {:?}",
                sol.steps.len(),
                at_steps.map(|e| format!("{e:.1e}")),
                between.map(|e| format!("{e:.1e}"))
            );
        });
    }
}

/// By name equals by index, at any time and at the output times; a wrong
/// name is a typed error naming the closest one.
#[test]
fn by_name_equals_by_index() {
    with_case(
        ("radau5", "ggl1", None),
        1e-8,
        inner_times(),
        |solver, problem, options| {
            let sol = solver.solve(problem, options).unwrap();
            assert_eq!(sol.names, ["x", "y", "v", "w", "lambda", "eta"]);
            for (i, name) in sol.names.iter().enumerate() {
                assert_eq!(sol.index_of(name), Ok(i));
                let series = sol.component(name).unwrap();
                assert_eq!(series.len(), sol.t.len());
                for (k, t) in sol.t.iter().enumerate() {
                    assert_eq!(series[k], sol.y[k][i]);
                    assert_eq!(sol.value(*t, name).unwrap(), sol.at(*t).unwrap()[i]);
                }
            }
            match sol.value(1.0, "Lambda") {
                Err(SolutionError::UnknownName {
                    suggestion, known, ..
                }) => {
                    assert_eq!(suggestion.as_deref(), Some("lambda"));
                    assert_eq!(known, sol.names);
                }
                other => panic!("{other:?}"),
            }
            // (`theta` would be two edits from `eta`: a suggestion under
            // the shared rule of `dae_core::names::did_you_mean`.)
            assert!(matches!(
                sol.component("omega"),
                Err(SolutionError::UnknownName {
                    suggestion: None,
                    ..
                })
            ));
        },
    );
}

/// The stepper run to `t_end` is `solve`: the same values, statistics,
/// step points and dense output, for every solver (also through a
/// start-up run).
#[test]
fn stepper_to_the_end_is_solve() {
    for case in cases() {
        with_case(case, 1e-6, vec![0.5, 1.25], |solver, problem, options| {
            let options = Options {
                record_steps: true,
                ..options.clone()
            };
            let solved = solver.solve(problem, &options).unwrap();
            let mut integ = solver.integrator(problem, &options).unwrap();
            assert_eq!(integ.t(), 0.0);
            assert_eq!(integ.names(), solved.names);
            let mut accepted = 0;
            let mut last = 0.0;
            loop {
                match integ.step().unwrap() {
                    StepOutcome::Accepted { t } => {
                        assert!(t > last && t < T_END, "{case:?}: t = {t}");
                        assert_eq!(integ.t(), t);
                        accepted += 1;
                        last = t;
                    }
                    StepOutcome::Finished { t } => {
                        assert_eq!(t, T_END);
                        break;
                    }
                    StepOutcome::Event { t } => panic!("{case:?}: no events, one at {t}"),
                }
            }
            // Finished stays finished.
            assert_eq!(integ.step(), Ok(StepOutcome::Finished { t: T_END }));
            assert_eq!(integ.y(), solved.steps.last().unwrap().1.as_slice());
            assert_eq!(integ.stats(), solved.stats);
            let stepped: Solution = integ.finish().unwrap();
            assert_eq!(stepped, solved, "{case:?}");
            if case.2.is_none() {
                // One accepted step per call (the fixed-step runs record
                // their grid, not the start-up run's steps).
                assert_eq!(accepted + 1, solved.steps.len(), "{case:?}");
            }
        });
    }
}

/// `advance_to` at the output times gives `solve`'s values there, bit for
/// bit (the same dense polynomial on the same step), never stepping past
/// `t_end`; earlier times come from the recorded dense output.
#[test]
fn advance_to_output_times_equals_solve() {
    let times = inner_times();
    for case in cases() {
        with_case(case, 1e-7, times.clone(), |solver, problem, options| {
            let solved = solver.solve(problem, options).unwrap();
            let mut integ = solver.integrator(problem, options).unwrap();
            for (t, y) in solved.t.iter().zip(&solved.y) {
                assert_eq!(
                    integ.advance_to(*t).unwrap(),
                    y.as_slice(),
                    "{case:?} t = {t}"
                );
                assert!(integ.t() >= *t && integ.t() <= T_END);
            }
            assert!(integ.finished());
            // Back in time: the recorded dense output, as `Solution::at`.
            let back = integ.advance_to(times[3]).unwrap().to_vec();
            assert_eq!(back, solved.at(times[3]).unwrap());
            assert_eq!(integ.advance_to(0.0).unwrap(), problem.y0);
            assert!(matches!(
                integ.advance_to(T_END + 1e-9),
                Err(SolveError::OutOfReach { .. })
            ));
        });
    }
}

/// Without dense output: `at` says so, `advance_to` reaches back only into
/// the last step, and the values at the output times are unchanged.
#[test]
fn without_dense_output() {
    with_case(
        ("bdf", "rcd0", None),
        1e-7,
        vec![0.5],
        |solver, problem, options| {
            let off = Options {
                dense_output: false,
                ..options.clone()
            };
            let sol = solver.solve(problem, &off).unwrap();
            let with = solver.solve(problem, options).unwrap();
            assert_eq!((&sol.t, &sol.y, sol.stats), (&with.t, &with.y, with.stats));
            assert_eq!(sol.dense, None);
            assert_eq!(sol.at(0.5), Err(SolutionError::NoDenseOutput));
            assert_eq!(sol.value(0.5, "x"), Err(SolutionError::NoDenseOutput));
            assert_eq!(sol.component("x").unwrap()[0], sol.y[0][0]);
            assert!(matches!(
                with.at(-0.1),
                Err(SolutionError::OutsideHorizon { .. })
            ));

            let mut integ = solver.integrator(problem, &off).unwrap();
            integ.advance_to(1.0).unwrap();
            match integ.advance_to(0.5) {
                Err(SolveError::OutOfReach { t, from, to }) => {
                    assert_eq!((t, to), (0.5, T_END));
                    assert!(from > 0.5 && from < 1.0);
                }
                other => panic!("{other:?}"),
            }
        },
    );
}

/// A failed step is a typed error, returned again by every later call.
#[test]
fn a_failure_is_sticky() {
    with_case(
        ("radau5", "rcd1", None),
        1e-8,
        vec![],
        |solver, problem, options| {
            let options = Options {
                max_steps: 5,
                ..options.clone()
            };
            let mut integ = solver.integrator(problem, &options).unwrap();
            let err = loop {
                if let Err(e) = integ.step() {
                    break e;
                }
            };
            assert!(matches!(err, SolveError::StepLimit { max_steps: 5, .. }));
            assert_eq!(integ.step(), Err(err.clone()));
            assert_eq!(integ.advance_to(T_END), Err(err.clone()));
            assert_eq!(integ.finish(), Err(err));
        },
    );
}

/// A run that stops reports the work it did and where it got to, for
/// every solver (issue 27, defect 3: failed runs used to report nothing):
/// a step-limited run's `Stopped` carries the steps, evaluations and
/// Newton iterations the stepper counted, and the time and values of its
/// last accepted step — the same the stepper shows when stepped by hand
/// to the same failure. Constant-step runs are left out: their step
/// count is known before the first step, so a limit below it is refused at
/// `t0` with nothing done.
#[test]
fn a_stopped_run_reports_its_work() {
    const MAX_STEPS: usize = 25;
    for case in cases().into_iter().filter(|c| c.2.is_none()) {
        with_case(case, 1e-8, vec![], |solver, problem, options| {
            let options = Options {
                max_steps: MAX_STEPS,
                ..options.clone()
            };
            let stopped = solver.run(problem, &options).unwrap_err();
            assert!(
                matches!(
                    stopped.error,
                    SolveError::StepLimit {
                        max_steps: MAX_STEPS,
                        ..
                    }
                ),
                "{case:?}: {}",
                stopped.error
            );
            let st = stopped.stats;
            assert!(st.steps > 0, "{case:?}: {st:?}");
            // Step attempts are bounded by the limit; idec counts a step per
            // grid point of its intervals and the limit in intervals.
            if case.0 != "idec" {
                assert!(st.steps + st.rejected <= MAX_STEPS, "{case:?}: {st:?}");
            }
            assert!(st.residual_evals >= st.steps, "{case:?}: {st:?}");
            // idec is linearly implicit: no Newton iterations.
            assert!(st.factorizations > 0, "{case:?}: {st:?}");
            assert!(
                stopped.t > 0.0 && stopped.t < T_END,
                "{case:?}: {}",
                stopped.t
            );
            // An accepted state, not a failed attempt's iterate: on the
            // circle (`x² + y² = l² = 1`; a few accepted steps at tol 1e-8
            // drift far less than 1e-6, whatever the formulation).
            let (x, y) = (stopped.y[0], stopped.y[1]);
            assert!(
                (x * x + y * y - 1.0).abs() < 1e-6,
                "{case:?}: {:?}",
                stopped.y
            );
            // The stepper by hand, to the same failure.
            let mut integ = solver.integrator(problem, &options).unwrap();
            let mut accepted = 0;
            while integ.step().is_ok() {
                accepted += 1;
            }
            assert_eq!(integ.stats(), st, "{case:?}");
            assert_eq!(integ.t(), stopped.t, "{case:?}");
            assert_eq!(integ.y(), stopped.y.as_slice(), "{case:?}");
            assert!(accepted > 0 && accepted <= st.steps, "{case:?}");
            // `solve` is the same run: the same error.
            assert_eq!(solver.solve(problem, &options).unwrap_err(), stopped.error);
        });
    }
}

/// A run refused before its first step reports no work, at `t0` with
/// `y0`.
#[test]
fn a_refused_run_reports_no_work() {
    with_case(
        ("bdf", "rcd0", None),
        1e-8,
        vec![],
        |solver, problem, options| {
            let options = Options {
                tol: dae_solvers::Tolerances::uniform(-1.0),
                ..options.clone()
            };
            let stopped = solver.run(problem, &options).unwrap_err();
            assert_eq!(stopped.error.kind(), "invalid_input");
            assert_eq!(stopped.stats, dae_solvers::Stats::default());
            assert_eq!((stopped.t, stopped.y.as_slice()), (problem.t0, problem.y0));
        },
    );
}

//! Tests of `gauss` (three-stage Gauss–Legendre collocation): the observed
//! order 6 with fixed steps, the paper's pendulum in rcd0 and psi0 against
//! the exact solution, what symmetry buys over many periods (a quadratic
//! invariant kept, an error that grows far slower than radau5's), the
//! quasi-constant step, and the typed refusals and errors.

mod common;

use common::*;
use dae_core::system::DaeSystem;
use dae_solvers::gauss::Gauss;
use dae_solvers::radau5::Radau5;
use dae_solvers::{NotApplicable, Options, Solution, SolveError, Solver};

fn solve(
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    options: &Options,
) -> Result<Solution, SolveError> {
    solve_with(&Gauss, sys, y0, t_end, options)
}

/// Fixed-step errors at `t_end` (max over `comps`) for each step count.
fn fixed_step_errors(
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    steps: &[usize],
    exact: &[f64],
    comps: &[usize],
) -> Vec<f64> {
    steps
        .iter()
        .map(|&n| {
            let options = Options {
                fixed_step: Some(t_end / n as f64),
                ..Options::with_tol(1e-12)
            };
            let sol = solve(sys, y0, t_end, &options).expect("fixed-step run");
            assert_eq!(sol.stats.steps, n);
            let y = sol.last().expect("output at t_end");
            comps
                .iter()
                .map(|&c| (y[c] - exact[c]).abs())
                .fold(0.0, f64::max)
        })
        .collect()
}

fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

#[test]
fn fixed_step_order_is_six_on_an_ode_and_an_index1_dae() {
    // Gauss–Legendre (s = 3): order 2s = 6. On the index-1 problem the
    // algebraic unknown is recomputed at every end point, so it keeps the
    // order of the differential ones. Measured: ODE 6.00, 6.00; index 1
    // y 5.99, 6.00, z 5.99, 6.00.
    let sys = ode();
    let errs = fixed_step_errors(
        &sys,
        &ode_exact(0.0),
        2.0,
        &[4, 8, 16],
        &ode_exact(2.0),
        &[0, 1],
    );
    let p = orders(&errs);
    println!("ode: {errs:?} orders {p:.2?}");
    assert!(p.iter().all(|&p| (5.7..=6.4).contains(&p)), "{p:?}");

    let sys = index1();
    let exact = index1_exact(1.0);
    for comps in [&[0usize, 1][..], &[2]] {
        let errs = fixed_step_errors(&sys, &index1_exact(0.0), 1.0, &[4, 8, 16], &exact, comps);
        let p = orders(&errs);
        println!("index 1 {comps:?}: {errs:?} orders {p:.2?}");
        assert!(
            p.iter().all(|&p| (5.7..=6.4).contains(&p)),
            "{comps:?}: {p:?}"
        );
    }
}

#[test]
fn s01_rcd0_and_psi0_reach_the_exact_solution() {
    // Ten periods. Measured (x, y, v, w error at t = 20, in units of tol):
    // rcd0 0.47 / 0.81 at tol 1e-6 / 1e-8; psi0 0.83 / 0.73.
    let exact = s01_exact_at_20();
    for form in [Form::Rcd0, Form::Psi0] {
        let sys = Pendulum::new(form);
        for tol in [1e-6, 1e-8] {
            let sol = solve(&sys, &sys.y0(), 20.0, &Options::with_tol(tol)).expect("S01");
            let err = err_max(sol.last().unwrap(), &exact);
            println!(
                "{}: tol {tol:e} err {err:.2e} steps {}",
                form.name(),
                sol.stats.steps
            );
            assert!(err < 5.0 * tol, "{} tol {tol:e}: err {err:e}", form.name());
        }
    }
}

/// `rcd0` drops the position and velocity constraints; `xv + yw` is still a
/// quadratic invariant of it, which Gauss–Legendre keeps. Over 100 periods
/// at a fixed step it stays at round-off (measured 1.7e-14 at the check
/// times; 1.1e-11, and an error of 1.9e-7 instead of 2.4e-10, with the
/// Newton iteration stopped at 10 units of round-off instead of 0.1).
#[test]
fn rcd0_keeps_its_quadratic_invariant_over_100_periods() {
    let sys = Pendulum::new(Form::Rcd0);
    let t_end = 200.0;
    let options = Options {
        fixed_step: Some(1.0 / 160.0),
        output_times: (1..=100).map(|k| 2.0 * f64::from(k)).collect(),
        ..Options::with_tol(1e-10)
    };
    let sol = solve(&sys, &sys.y0(), t_end, &options).expect("100 periods");
    let mut worst: f64 = 0.0;
    for y in &sol.y {
        worst = worst.max((y[0] * y[2] + y[1] * y[3]).abs());
    }
    let exact = pendulum_exact(t_end);
    let err = err_max(sol.last().unwrap(), &exact);
    println!("|xv + yw| ≤ {worst:.2e}, err {err:.2e}");
    assert!(worst < 1e-12, "xv + yw drifted to {worst:e}");
    assert!(err < 1e-9, "error {err:e} after 100 periods");
}

/// At equal steps over 100 periods Gauss–Legendre's error is orders of
/// magnitude below Radau IIA's: the symmetric method's phase error grows
/// like `t`, the damping one's like `t²` (measured at 20 steps per period:
/// radau5 3.3, gauss 1.6e-3).
#[test]
fn symmetry_beats_damping_over_100_periods() {
    let sys = Pendulum::new(Form::Rcd0);
    let t_end = 200.0;
    let options = Options {
        fixed_step: Some(0.1),
        ..Options::with_tol(1e-10)
    };
    let exact = pendulum_exact(t_end);
    let gauss = solve(&sys, &sys.y0(), t_end, &options).expect("gauss");
    let radau = solve_with(&Radau5, &sys, &sys.y0(), t_end, &options).expect("radau5");
    let (eg, er) = (
        err_max(gauss.last().unwrap(), &exact),
        err_max(radau.last().unwrap(), &exact),
    );
    println!("gauss {eg:.2e}, radau5 {er:.2e}");
    assert!(eg * 100.0 < er, "gauss {eg:e} vs radau5 {er:e}");
}

#[test]
fn the_step_settles_on_a_periodic_motion() {
    // After the start-up the step changes only when it must: on ten
    // periods of the pendulum a handful of step sizes, not one per step
    // (measured: 10 changes in 926 steps, most in the first period).
    let sys = Pendulum::new(Form::Rcd0);
    let options = Options {
        record_steps: true,
        ..Options::with_tol(1e-7)
    };
    let sol = solve(&sys, &sys.y0(), 20.0, &options).expect("S01");
    let t: Vec<f64> = sol.steps.iter().map(|(t, _)| *t).collect();
    let mut sizes: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    sizes.pop(); // the last step ends at t_end
    let changes = sizes
        .windows(2)
        .filter(|w| (w[1] / w[0] - 1.0).abs() > 1e-9)
        .count();
    println!("{} steps, {changes} step-size changes", sizes.len());
    assert!(sizes.len() > 100);
    assert!(
        changes * 20 < sizes.len(),
        "{changes} changes in {} steps",
        sizes.len()
    );
}

#[test]
fn index_two_and_overdetermined_formulations_are_refused() {
    for form in [Form::Rcd1, Form::Ggl1, Form::Psi1, Form::Ori2] {
        let sys = Pendulum::new(form);
        match Gauss.accepts(sys.info()) {
            Err(NotApplicable::IndexTooHigh { index, max: 1 }) => assert!(index >= 2),
            other => panic!("{}: {other:?}", form.name()),
        }
        let err = solve(&sys, &sys.y0(), 1.0, &Options::default()).unwrap_err();
        assert_eq!(err.kind(), "not_applicable", "{}", form.name());
    }
    let sys = Simple::overdetermined();
    assert!(matches!(
        Gauss.accepts(sys.info()),
        Err(NotApplicable::Overdetermined { .. })
    ));
    assert!(Gauss.accepts(Pendulum::new(Form::Rcd0).info()).is_ok());
    assert!(Gauss.accepts(Pendulum::new(Form::Psi0).info()).is_ok());
}

#[test]
fn errors_are_typed() {
    let sys = Pendulum::new(Form::Rcd0);
    let mut y0 = sys.y0();
    y0[2] = f64::NAN;
    assert_eq!(
        solve(&sys, &y0, 1.0, &Options::default()).unwrap_err(),
        SolveError::NonFinite {
            t: 0.0,
            what: "initial values"
        }
    );
    assert_eq!(
        solve(&nan_rhs(), &[1.0], 1.0, &Options::default())
            .unwrap_err()
            .kind(),
        "non_finite"
    );
    match solve(&blow_up(), &[1.0], 2.0, &Options::with_tol(1e-6)).unwrap_err() {
        SolveError::StepSizeTooSmall { t, .. } => assert!((t - 1.0).abs() < 1e-6, "t = {t}"),
        other => panic!("expected StepSizeTooSmall, got {other:?}"),
    }
    let options = Options {
        max_steps: 10,
        ..Options::with_tol(1e-6)
    };
    assert!(matches!(
        solve(&sys, &sys.y0(), 20.0, &options),
        Err(SolveError::StepLimit { max_steps: 10, .. })
    ));
    let bad = Options::with_tol(-1.0);
    assert_eq!(
        solve(&sys, &sys.y0(), 1.0, &bad).unwrap_err().kind(),
        "invalid_input"
    );
}

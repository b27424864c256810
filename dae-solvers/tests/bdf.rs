//! Tests of the BDF solver (`dae_solvers::bdf`): accuracy on the pendulum
//! benchmark (Scenario S01), observed convergence orders at fixed step and
//! order, every typed error, dense output, and the absence of allocation in
//! the step loop. The long Scenario S02 runs are in `examples/bdf_s02.rs`.

#[path = "common/alloc.rs"]
mod alloc;
mod common;

use alloc::allocations_of;
use common::*;
use dae_core::system::DaeSystem;
use dae_solvers::bdf::Bdf;
use dae_solvers::options::Tol;
use dae_solvers::{NotApplicable, Options, Solution, SolveError, Solver};

/// Integrate `sys` from `y0` at `t = 0` to `t_end`.
fn run(
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    options: &Options,
) -> Result<Solution, SolveError> {
    solve_with(&Bdf, sys, y0, t_end, options)
}

/// Options for the pendulum: uniform tolerance, index-2 unknowns out of the
/// error test for the index-2 formulations (DASPK).
fn pendulum_options(form: Form, tol: f64) -> Options {
    let mut options = Options::with_tol(tol);
    options.index2_in_error_test = Some(!form.has_index2());
    options
}

#[test]
fn accepts_square_rejects_overdetermined() {
    let sys = Pendulum::new(Form::Rcd0);
    assert!(Bdf.accepts(sys.info()).is_ok());
    assert_eq!(Bdf.name(), "bdf");
    let mut info = sys.info().clone();
    info.rows.push(info.rows[4].clone());
    assert_eq!(
        Bdf.accepts(&info),
        Err(NotApplicable::Overdetermined {
            equations: 6,
            unknowns: 5
        })
    );
}

/// Scenario S01 at tolerances 1e-6 and 1e-10: error at t = 20 against the
/// exact solution.
///
/// Measured (this solver, x86-64):
///
/// | form | 1e-6: err, err_λ | 1e-10: err, err_λ | DASSL (Fortran) 1e-6 / 1e-10 |
/// |------|------------------|-------------------|------------------------------|
/// | rcd1 | 6.0e-3, 9.9e-4   | 2.6e-6, 2.9e-7    | —                            |
/// | rcd0 | 1.8e-2, 1.0e-2   | 1.1e-6, 1.8e-6    | 1.3e-2 / 9.7e-7              |
/// | ggl1 | 5.9e-3, 1.3e-3   | 1.6e-6, 3.3e-7    | —                            |
/// | psi1 | 9.7e-3, 1.7e-3   | 1.7e-6, 3.4e-7    | —                            |
/// | psi0 | 3.4e-3, 9.9e-4   | 1.1e-7, 6.6e-8    | 4.1e-3 / 2.1e-8              |
///
/// The global error of a local-error-controlled code over ten periods is not
/// monotone in the tolerance (rcd0: 1e-5 gives 1.0e-2, 1e-6 gives 1.8e-2),
/// so the bounds are the measured values rounded up by a factor of about
/// three: loose enough for round-off differences between platforms, tight
/// enough to catch a lost order of magnitude.
#[test]
fn s01_error_bounds_at_1e6_and_1e10() {
    let end = s01_exact_at_20();
    // (form, [bound x,y,v,w at 1e-6, bound λ at 1e-6, at 1e-10, λ at 1e-10])
    let bounds = [
        (Form::Rcd1, [2e-2, 3e-3, 8e-6, 1e-6]),
        (Form::Rcd0, [5e-2, 3e-2, 3e-6, 5e-6]),
        (Form::Ggl1, [2e-2, 4e-3, 5e-6, 1e-6]),
        (Form::Psi1, [3e-2, 5e-3, 5e-6, 1e-6]),
        (Form::Psi0, [1e-2, 3e-3, 3e-7, 2e-7]),
    ];
    for (form, b) in bounds {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        for (tol, bound, bound_lambda) in [(1e-6, b[0], b[1]), (1e-10, b[2], b[3])] {
            let sol = run(&sys, &y0, 20.0, &pendulum_options(form, tol))
                .unwrap_or_else(|e| panic!("{} at {tol:e}: {e}", form.name()));
            assert_eq!(sol.t, vec![20.0]);
            let u = sol.last().expect("one output");
            let err = err_max(u, &end);
            let err_lambda = (u[Pendulum::LAMBDA] - end[4]).abs();
            assert!(
                err <= bound && err_lambda <= bound_lambda,
                "{} at {tol:e}: err {err:e} (bound {bound:e}), λ {err_lambda:e} (bound {bound_lambda:e})",
                form.name()
            );
            let s = sol.stats;
            assert!(s.steps > 0 && s.residual_evals > s.steps && s.newton_iterations >= s.steps);
            // The checked estimate never leaves DASSL's on the pendulum.
            assert_eq!(s.propagated_from, None, "{}", form.name());
            assert!(s.factorizations > 0 && s.jacobian_evals >= s.factorizations);
        }
    }
}

/// Every tolerance 1e-5 … 1e-12 succeeds on S01 for every formulation, with
/// the work of the Fortran DASSL anchors (rcd0 at 1e-12: 22 662 steps).
#[test]
fn s01_succeeds_at_every_tolerance() {
    let end = s01_exact_at_20();
    for form in Form::INDEX_AT_MOST_2 {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        for i in 5..=12 {
            let tol = 10f64.powi(-i);
            let sol = run(&sys, &y0, 20.0, &pendulum_options(form, tol))
                .unwrap_or_else(|e| panic!("{} at 1e-{i}: {e}", form.name()));
            let err = err_max(sol.last().expect("output"), &end);
            assert!(err < 0.1, "{} at 1e-{i}: err {err:e}", form.name());
            assert!(sol.stats.steps < 60_000, "{} at 1e-{i}", form.name());
        }
    }
}

/// Errors at `t_end` for fixed steps `h0 / 2^j`, `j = 0..levels`, and the
/// observed orders `log2(e_j / e_{j+1})`.
fn observed_orders(
    sys: &dyn DaeSystem,
    exact: fn(f64) -> Vec<f64>,
    t_end: f64,
    h0: f64,
    order: usize,
    component: Option<usize>,
) -> (Vec<f64>, Vec<f64>) {
    let y0 = exact(0.0);
    let errors: Vec<f64> = (0..5)
        .map(|j| {
            let mut options = Options::with_tol(1e-13);
            options.fixed_step = Some(h0 / 2f64.powi(j));
            options.fixed_order = Some(order);
            let sol = run(sys, &y0, t_end, &options).expect("fixed-step run");
            let u = sol.last().expect("output");
            let ex = exact(t_end);
            let diff = |i: usize| (u[i] - ex[i]).abs();
            match component {
                Some(i) => diff(i),
                None => (0..u.len()).map(diff).fold(0.0, f64::max),
            }
        })
        .collect();
    let orders = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    (errors, orders)
}

/// Constant-step BDF-k converges with order k, k = 1 … 5 (starting values
/// from the adaptive solver at tolerance 1e-13). Measured orders on the
/// last two halvings (h = 0.05 → 0.025 → 0.0125): 0.970/0.985,
/// 1.981/1.991, 2.970/2.986, 3.955/3.980, 4.939/4.974.
#[test]
fn fixed_step_orders_on_an_ode() {
    let sys = ode();
    for k in 1..=5 {
        let (errors, orders) = observed_orders(&sys, ode_exact, 2.0, 0.2, k, None);
        for p in &orders[2..] {
            assert!(
                (p - k as f64).abs() < 0.15,
                "ode, order {k}: errors {errors:?}, observed orders {orders:?}"
            );
        }
    }
}

/// The same on a semi-explicit index-1 DAE, for the differential and the
/// algebraic unknowns. Measured on the last two halvings (h = 0.025 →
/// 0.0125 → 0.00625): 0.979/0.990, 1.982/1.991, 2.978/2.985, 3.991/3.985,
/// 4.962/4.923 (max over components); the algebraic component alone
/// 2.919/3.018 at order 3, 4.149/3.984 at order 4, 4.907/4.966 at order 5.
#[test]
fn fixed_step_orders_on_an_index1_dae() {
    let sys = dae1();
    for k in 1..=5 {
        let (errors, orders) = observed_orders(&sys, dae1_exact, 1.2, 0.1, k, None);
        for p in &orders[2..] {
            assert!(
                (p - k as f64).abs() < 0.15,
                "dae1, order {k}: errors {errors:?}, observed orders {orders:?}"
            );
        }
        let (errors, orders) = observed_orders(&sys, dae1_exact, 1.2, 0.1, k, Some(2));
        for p in &orders[2..] {
            assert!(
                (p - k as f64).abs() < 0.35,
                "dae1 algebraic, order {k}: errors {errors:?}, observed orders {orders:?}"
            );
        }
    }
}

#[test]
fn fixed_step_reaches_t_end_exactly_with_requested_outputs() {
    let sys = ode();
    let mut options = Options::with_tol(1e-12);
    options.fixed_step = Some(0.3); // 2.0 / 0.3 is not an integer: h = 2/7
    options.fixed_order = Some(3);
    options.output_times = vec![0.1, 1.0, 1.5];
    options.record_steps = true;
    let sol = run(&sys, &[0.0, 1.0, 1.0], 2.0, &options).expect("run");
    assert_eq!(sol.t, vec![0.1, 1.0, 1.5, 2.0]);
    let (t_last, _) = sol.steps.last().expect("steps");
    assert_eq!(*t_last, 2.0);
    // The constant-step part runs on the grid 2j/7.
    let h = 2.0 / 7.0;
    for (t, _) in &sol.steps {
        let j = t / h;
        assert!((j - j.round()).abs() < 1e-9, "step at {t} off the grid");
    }
    for (t, u) in sol.t.iter().zip(&sol.y) {
        let ex = ode_exact(*t);
        for (a, b) in u.iter().zip(&ex) {
            assert!((a - b).abs() < 0.05, "t = {t}: {u:?} vs {ex:?}");
        }
    }
}

#[test]
fn invalid_input_is_a_typed_error() {
    let sys = Pendulum::new(Form::Rcd0);
    let y0 = sys.y0();
    let is_invalid =
        |r: Result<Solution, SolveError>| matches!(r, Err(SolveError::InvalidInput { .. }));

    let mut options = Options::with_tol(1e-6);
    options.tol.rtol = Tol::Scalar(-1e-6);
    assert!(is_invalid(run(&sys, &y0, 1.0, &options)));

    let mut options = Options::with_tol(1e-6);
    options.tol.atol = Tol::Scalar(f64::NAN);
    assert!(is_invalid(run(&sys, &y0, 1.0, &options)));

    assert!(is_invalid(run(&sys, &y0, 0.0, &Options::default())));
    assert!(is_invalid(run(
        &sys,
        &y0,
        f64::INFINITY,
        &Options::default()
    )));
    assert!(is_invalid(run(&sys, &y0[..4], 1.0, &Options::default())));

    let options = Options {
        fixed_order: Some(6),
        ..Options::default()
    };
    assert!(is_invalid(run(&sys, &y0, 1.0, &options)));

    let options = Options {
        h0: Some(-1.0),
        ..Options::default()
    };
    assert!(is_invalid(run(&sys, &y0, 1.0, &options)));

    // A huge initial step is clipped, not an overflow.
    let options = Options {
        h0: Some(1e300),
        ..Options::with_tol(1e-6)
    };
    assert!(run(&sys, &y0, 1.0, &options).is_ok());
}

#[test]
fn nan_initial_values_are_non_finite() {
    let sys = Pendulum::new(Form::Rcd0);
    let r = run(
        &sys,
        &[1.0, f64::NAN, 0.0, 0.0, 0.0],
        1.0,
        &Options::default(),
    );
    assert!(
        matches!(r, Err(SolveError::NonFinite { t, what: "initial values" }) if t == 0.0),
        "{r:?}"
    );
}

#[test]
fn nan_in_the_residual_is_non_finite() {
    // y' = −y up to t = 0.5, NaN beyond: steps approach 0.5 and stop there.
    let r = run(&nan_beyond_half(), &[1.0], 2.0, &Options::with_tol(1e-6));
    match r {
        Err(SolveError::NonFinite { t, what }) => {
            assert_eq!(what, "residual");
            assert!((0.49..=0.5).contains(&t), "t = {t}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn step_limit() {
    let sys = Pendulum::new(Form::Rcd0);
    let mut options = Options::with_tol(1e-6);
    options.max_steps = 50;
    let r = run(&sys, &sys.y0(), 20.0, &options);
    assert!(
        matches!(r, Err(SolveError::StepLimit { max_steps: 50, t }) if t > 0.0 && t < 20.0),
        "{r:?}"
    );
    // A fixed step needing more steps than allowed is refused at once.
    let mut options = Options::with_tol(1e-6);
    options.max_steps = 100;
    options.fixed_step = Some(1e-3);
    let r = run(&sys, &sys.y0(), 20.0, &options);
    assert!(matches!(r, Err(SolveError::StepLimit { .. })), "{r:?}");
}

/// `y' = y²`, `y(0) = 1` blows up at t = 1: past it the step size collapses.
#[test]
fn blow_up_gives_step_size_too_small() {
    for tol in [1e-4, 1e-6, 1e-10] {
        let r = run(&blow_up(), &[1.0], 2.0, &Options::with_tol(tol));
        match r {
            Err(SolveError::StepSizeTooSmall { t, h }) => {
                assert!((0.99..1.0).contains(&t) && h < 1e-14, "t = {t}, h = {h}");
            }
            other => panic!("tol {tol}: {other:?}"),
        }
    }
}

/// With a fixed step the corrector of `y' = y²` has no solution once
/// `4 h y > 1`: Newton fails and cannot retry with a smaller step.
#[test]
fn blow_up_at_fixed_step_gives_newton_failure() {
    let mut options = Options::with_tol(1e-6);
    options.fixed_step = Some(0.3);
    options.fixed_order = Some(1);
    let r = run(&blow_up(), &[1.0], 2.0, &options);
    assert!(
        matches!(r, Err(SolveError::NewtonFailure { t, iterations, .. }) if t == 0.0 && iterations > 0),
        "{r:?}"
    );
}

/// An unknown that appears in no equation makes every iteration matrix
/// singular: three step-size reductions, then the typed error.
#[test]
fn structurally_singular_system() {
    let r = run(
        &structurally_singular(),
        &[1.0, 0.0],
        1.0,
        &Options::default(),
    );
    assert!(
        matches!(r, Err(SolveError::SingularMatrix { t, .. }) if t == 0.0),
        "{r:?}"
    );
}

#[test]
fn inconsistent_initial_values_are_reported() {
    // λ0 = 1 violates the acceleration-level row of rcd0.
    let sys = Pendulum::new(Form::Rcd0);
    let r = run(&sys, &[1.0, 0.0, 0.0, 0.0, 1.0], 1.0, &Options::default());
    match r {
        Err(SolveError::InconsistentInitialValues { equation, residual }) => {
            assert!(equation.contains("lambda"), "{equation}");
            assert!((residual.abs() - 4.0).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    // A velocity that violates the velocity constraint of ggl1.
    let sys = Pendulum::new(Form::Ggl1);
    let r = run(
        &sys,
        &[1.0, 0.0, 0.1, 0.0, 0.0, 0.0],
        1.0,
        &Options::default(),
    );
    assert!(
        matches!(&r, Err(SolveError::InconsistentInitialValues { equation, .. }) if equation == "0 = 2*x*v + 2*y*w"),
        "{r:?}"
    );
    // Within the tolerance: accepted.
    let sys = Pendulum::new(Form::Rcd0);
    assert!(run(
        &sys,
        &[1.0, 0.0, 0.0, 0.0, 1e-9],
        1.0,
        &Options::with_tol(1e-6)
    )
    .is_ok());
}

/// Leaving the index-2 multiplier in the error test makes the index-2
/// formulations fail (the paper's DASSL/DASPK result); leaving it out makes
/// them run.
#[test]
fn index2_unknowns_in_the_error_test() {
    let sys = Pendulum::new(Form::Rcd1);
    let mut options = Options::with_tol(1e-8);
    options.index2_in_error_test = Some(true);
    let r = run(&sys, &sys.y0(), 20.0, &options);
    assert!(
        matches!(r, Err(SolveError::StepSizeTooSmall { .. })),
        "{r:?}"
    );
    options.index2_in_error_test = Some(false);
    assert!(run(&sys, &sys.y0(), 20.0, &options).is_ok());
}

/// Order limits: every `max_order` and every adaptive `fixed_order` succeed.
#[test]
fn order_options() {
    let end = s01_exact_at_20();
    for form in [Form::Rcd0, Form::Ggl1, Form::Psi0] {
        let sys = Pendulum::new(form);
        for k in 1..=5 {
            let mut options = pendulum_options(form, 1e-6);
            options.max_order = k;
            let sol = run(&sys, &sys.y0(), 20.0, &options)
                .unwrap_or_else(|e| panic!("{} max_order {k}: {e}", form.name()));
            assert!(err_max(sol.last().expect("output"), &end) < 3.0);
            let mut options = pendulum_options(form, 1e-6);
            options.fixed_order = Some(k);
            let sol = run(&sys, &sys.y0(), 20.0, &options)
                .unwrap_or_else(|e| panic!("{} fixed_order {k}: {e}", form.name()));
            assert!(err_max(sol.last().expect("output"), &end) < 3.0);
        }
        // h_max bounds every step.
        let mut options = pendulum_options(form, 1e-6);
        options.h_max = Some(0.01);
        options.record_steps = true;
        let sol = run(&sys, &sys.y0(), 20.0, &options).expect("h_max run");
        let mut t_prev = 0.0;
        for (t, _) in &sol.steps {
            assert!(t - t_prev <= 0.01 * (1.0 + 1e-12), "step {t_prev} -> {t}");
            t_prev = *t;
        }
    }
}

/// Dense output at requested times (unsorted, some outside the horizon)
/// matches the exact solution to the accuracy of the steps.
#[test]
fn dense_output_at_requested_times() {
    let sys = ode();
    let mut options = Options::with_tol(1e-10);
    options.output_times = vec![1.7, 0.3, -1.0, 0.0, 2.0, 5.0, 1.234_567, 0.9];
    let sol = run(&sys, &ode_exact(0.0), 2.0, &options).expect("run");
    assert_eq!(sol.t, vec![0.0, 0.3, 0.9, 1.234_567, 1.7, 2.0]);
    assert_eq!(sol.y.len(), sol.t.len());
    assert_eq!(sol.y[0], ode_exact(0.0));
    for (t, u) in sol.t.iter().zip(&sol.y) {
        let ex = ode_exact(*t);
        for (a, b) in u.iter().zip(&ex) {
            assert!((a - b).abs() < 1e-8, "t = {t}: {a} vs {b}");
        }
    }
}

/// Dense output along the whole S01 trajectory (every 0.05 s) of psi0 and
/// rcd1 at 1e-10: within a small multiple of the error at t = 20.
/// Measured: max error 1.9e-7 (psi0), 5.0e-6 (rcd1) over the 400 times,
/// against 1.1e-7 and 2.6e-6 at t = 20.
#[test]
fn dense_output_along_the_pendulum_trajectory() {
    let exact = reference("pendulum_s01_exact.csv");
    for (form, bound) in [(Form::Psi0, 5e-7), (Form::Rcd1, 1e-5)] {
        let sys = Pendulum::new(form);
        let mut options = pendulum_options(form, 1e-10);
        options.output_times = exact.iter().map(|(t, _)| *t).filter(|&t| t > 0.0).collect();
        let sol = run(&sys, &sys.y0(), 20.0, &options).expect("run");
        assert_eq!(sol.t.len(), exact.len() - 1);
        let worst = sol
            .y
            .iter()
            .zip(&exact[1..])
            .map(|(u, (_, ex))| err_max(u, ex))
            .fold(0.0, f64::max);
        assert!(worst < bound, "{}: {worst:e}", form.name());
    }
}

#[test]
fn record_steps_lists_every_accepted_step() {
    let sys = Pendulum::new(Form::Psi1);
    let mut options = pendulum_options(Form::Psi1, 1e-7);
    options.record_steps = true;
    let sol = run(&sys, &sys.y0(), 2.0, &options).expect("run");
    assert_eq!(sol.steps.len(), sol.stats.steps);
    assert!(sol.steps.windows(2).all(|w| w[0].0 < w[1].0));
    let (t_last, y_last) = sol.steps.last().expect("steps");
    assert_eq!(*t_last, 2.0);
    assert_eq!(Some(y_last.as_slice()), sol.last());
}

/// The number of allocations does not depend on the number of steps: none
/// happens in the step loop.
#[test]
fn no_allocation_in_the_step_loop() {
    let cases: Vec<(Form, Options)> = vec![
        (Form::Rcd0, pendulum_options(Form::Rcd0, 1e-8)),
        (Form::Psi1, pendulum_options(Form::Psi1, 1e-8)),
        (Form::Ggl1, {
            let mut o = pendulum_options(Form::Ggl1, 1e-10);
            o.fixed_step = Some(1e-3);
            o.fixed_order = Some(3);
            o
        }),
    ];
    for (form, options) in cases {
        // The dense output record grows with the steps (amortised pushes,
        // `Options::dense_output`); the step loop itself allocates nothing.
        let options = Options {
            dense_output: false,
            ..options
        };
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        let mut steps = [0usize; 2];
        let counts: Vec<usize> = [2.0, 20.0]
            .iter()
            .enumerate()
            .map(|(i, &t_end)| {
                let (count, sol) = allocations_of(|| run(&sys, &y0, t_end, &options).expect("run"));
                steps[i] = sol.stats.steps;
                count
            })
            .collect();
        assert!(steps[1] > 5 * steps[0], "{steps:?}");
        assert_eq!(
            counts[0],
            counts[1],
            "{}: allocations {counts:?} for steps {steps:?}",
            form.name()
        );
    }
}

/// The propagated estimate (`Options::estimate`) on an index-1 DAE whose
/// algebraic unknown DASSL's estimate does not see ([`amplified_circle`]:
/// `z = 100 (y0² + y1² − 1)`, constant on the solution, so its divided
/// differences measure nothing of the radial error the constraint carries
/// into it). Measured (|z(10)| in steps): DASSL's own estimate 5.1e-1 in
/// 19 610 (1e-5), 4.6e-2 in 215 518 (1e-7), 4.6e-3 in 2 177 464 (1e-9);
/// checked 3.4e-4 in 231, 4.3e-6 in 565, 1.1e-7 in 1 002; propagated
/// throughout 1.1e-4 in 259, 6.4e-6 in 607, 8.5e-8 in 981.
#[test]
fn checked_estimate_sees_the_amplified_constraint() {
    assert_checked_estimate_sees_amplified_circle(&Bdf);
}

//! Tests of `radau5`: accuracy on the paper's pendulum in six formulations
//! (Scenario S01), dense output, observed convergence orders with fixed
//! steps (index 1, 2, 3), every error kind, option semantics, statistics,
//! and an allocation-free step loop.

#[path = "common/alloc.rs"]
mod alloc;
mod common;

use alloc::allocations_of;
use common::*;
use dae_core::system::DaeSystem;
use dae_solvers::radau5::Radau5;
use dae_solvers::{NotApplicable, Options, Solution, SolveError, Solver, Tolerances};

// ---------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------

fn solve(
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    options: &Options,
) -> Result<Solution, SolveError> {
    solve_with(&Radau5, sys, y0, t_end, options)
}

/// `max_i |a_i − b_i|` over the first `k` components.
fn max_err(a: &[f64], b: &[f64], k: usize) -> f64 {
    a.iter()
        .zip(b)
        .take(k)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Fixed-step errors at `t_end` per component, for each number of steps in
/// `steps`.
fn fixed_step_errors(
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    steps: &[usize],
    exact: &[f64],
) -> Vec<Vec<f64>> {
    steps
        .iter()
        .map(|&n| {
            let mut options = Options::with_tol(1e-13);
            options.fixed_step = Some(t_end / n as f64);
            let sol = solve(sys, y0, t_end, &options).expect("fixed-step run");
            assert_eq!(sol.stats.steps, n, "fixed step count");
            assert_eq!(sol.stats.rejected, 0);
            let y = sol.last().expect("output at t_end");
            y.iter().zip(exact).map(|(a, b)| (a - b).abs()).collect()
        })
        .collect()
}

/// Observed orders `log2(e(h)/e(h/2))` of the component group `comps`
/// (max-norm over the group) from runs whose step counts double.
fn observed_orders(errors: &[Vec<f64>], comps: &[usize]) -> Vec<f64> {
    let group: Vec<f64> = errors
        .iter()
        .map(|e| comps.iter().map(|&c| e[c]).fold(0.0, f64::max))
        .collect();
    group.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

// ---------------------------------------------------------------------------
// The exact reference
// ---------------------------------------------------------------------------

#[test]
fn exact_pendulum_matches_the_reference_files() {
    for row in EXACT_ROWS {
        let ex = pendulum_exact(row[0]);
        let err = max_err(&ex, &row[1..], 5);
        // ω t and 4K carry relative roundings of 1e-16, which the phase
        // accumulates: measured 3.7e-14 at t = 20.
        let bound = 1e-14 + 5e-15 * row[0];
        assert!(
            err < bound,
            "t = {}: {ex:?} vs {:?} ({err:e})",
            row[0],
            &row[1..]
        );
    }
}

// ---------------------------------------------------------------------------
// Scenario S01 in all six formulations
// ---------------------------------------------------------------------------

/// The exact state at `t = 20` (row of `pendulum_s01_exact.csv`).
fn exact_at_20() -> [f64; 5] {
    let row = EXACT_ROWS[2];
    assert_eq!(row[0], 20.0);
    [row[1], row[2], row[3], row[4], row[5]]
}

/// Bounds on the error at `t = 20` (S01) per formulation, relative to the
/// tolerance, for `(x, y, v, w)` and for `λ`. Measured (tol 1e-6 / 1e-10,
/// errors in units of tol):
///
/// | form | x,y,v,w     | λ           |
/// |------|-------------|-------------|
/// | ori2 | 6.8 / 200   | 120 / 1.8e4 |
/// | rcd1 | 0.23 / 3.0  | 0.03 / 0.69 |
/// | rcd0 | 0.13 / 0.10 | 0.01 / 0.02 |
/// | ggl1 | 0.35 / 7.2  | 0.07 / 1.6  |
/// | psi1 | 0.38 / 6.0  | 0.08 / 0.71 |
/// | psi0 | 0.26 / 0.36 | 0.05 / 0.07 |
///
/// The index-1 formulations stay below the tolerance after three periods
/// (the tolerance map makes the global error proportional to `tol`); the
/// index-2 ones reach a few `tol` at 1e-10, where round-off in the index-2
/// multipliers (`ε/h`) starts to show; `ori2` pays for index 3: `λ` is
/// accurate to `O(h²)` only and its round-off grows like `ε/h²`, so it is
/// bounded in absolute terms (1e-3 at tol 1e-6, 1e-5 at tol 1e-10).
fn s01_bounds(form: Form, tol: f64) -> (f64, f64) {
    match form {
        Form::Rcd0 | Form::Psi0 => (tol, tol),
        Form::Rcd1 | Form::Ggl1 | Form::Psi1 => (20.0 * tol, 5.0 * tol),
        Form::Ori2 => (1e3 * tol, if tol > 1e-8 { 1e-3 } else { 1e-5 }),
        Form::Ovd1 => unreachable!("ovd1 is not square"),
    }
}

#[test]
fn s01_every_formulation_reaches_t20_accurately() {
    let exact = exact_at_20();
    for form in Form::SQUARE {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        for tol in [1e-6, 1e-10] {
            let (bound, bound_lambda) = s01_bounds(form, tol);
            let sol = solve(&sys, &y0, 20.0, &Options::with_tol(tol))
                .unwrap_or_else(|e| panic!("{} at {tol:e}: {e}", form.name()));
            assert_eq!(sol.t, vec![20.0]);
            let y = sol.last().unwrap();
            let err = max_err(y, &exact, 4);
            let err_lambda = (y[4] - exact[4]).abs();
            let name = form.name();
            assert!(err < bound, "{name} tol {tol:e}: err {err:e}");
            assert!(
                err_lambda < bound_lambda,
                "{name} tol {tol:e}: λ err {err_lambda:e}"
            );
        }
    }
}

#[test]
fn s01_constraints_hold_where_the_formulation_enforces_them() {
    // ori2, ggl1, psi1, psi0 keep the position constraint; rcd1/rcd0 drift.
    let tol = 1e-8;
    for form in [Form::Ori2, Form::Ggl1, Form::Psi1, Form::Psi0] {
        let sys = Pendulum::new(form);
        let sol = solve(&sys, &sys.y0(), 20.0, &Options::with_tol(tol)).unwrap();
        let mut g = [0.0; 3];
        sys.constraints(20.0, sol.last().unwrap(), &mut g);
        assert!(
            g[0].abs() < 1e-12,
            "{}: position residual {:e}",
            form.name(),
            g[0]
        );
    }
}

// ---------------------------------------------------------------------------
// Dense output
// ---------------------------------------------------------------------------

#[test]
fn dense_output_matches_the_exact_solution_index1() {
    let sys = index1();
    let y0 = index1_exact(0.0);
    let tol = 1e-8;
    let mut options = Options::with_tol(tol);
    options.output_times = (1..1000).map(|k| 0.0137 * f64::from(k)).collect();
    let sol = solve(&sys, &y0, 10.0, &options).unwrap();
    // 729 times inside (0, 10], then t_end.
    assert_eq!(sol.t.len(), 730);
    assert_eq!(sol.t.last(), Some(&10.0));
    // Far fewer steps than output times: outputs do not shorten steps.
    assert!(sol.stats.steps < 600, "{} steps", sol.stats.steps);
    for (t, y) in sol.t.iter().zip(&sol.y) {
        let err = max_err(y, &index1_exact(*t), 3);
        // Measured 3.4e-9: the collocation polynomial is as accurate as
        // the step points.
        assert!(err < tol, "t = {t}: {err:e}");
    }
}

#[test]
fn dense_output_matches_the_exact_pendulum_every_0_05() {
    // Measured max errors over 400 output times (tol 1e-6 / 1e-8), in units
    // of tol: x,y,v,w 0.2–0.7 for index ≤ 2, ori2 16 / 440; λ of index 1
    // ≤ 1.7, of index 2 20–240 (the polynomial of an index-2 component is
    // less accurate between the nodes than at them), of index 3 4e3 / 7e4.
    for form in Form::SQUARE {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        for tol in [1e-6, 1e-8] {
            let mut options = Options::with_tol(tol);
            options.output_times = (1..=400).map(|k| 0.05 * f64::from(k)).collect();
            let sol = solve(&sys, &y0, 20.0, &options).unwrap();
            assert_eq!(sol.t.len(), 400);
            let mut err = 0.0f64;
            let mut err_lambda = 0.0f64;
            for (t, y) in sol.t.iter().zip(&sol.y) {
                let ex = pendulum_exact(*t);
                err = err.max(max_err(y, &ex, 4));
                err_lambda = err_lambda.max((y[4] - ex[4]).abs());
            }
            let (bound, bound_lambda) = match form {
                Form::Rcd0 | Form::Psi0 => (2.0, 5.0),
                Form::Rcd1 | Form::Ggl1 | Form::Psi1 => (2.0, 1e3),
                Form::Ori2 => (2e3, 1e6),
                Form::Ovd1 => unreachable!("ovd1 is not square"),
            };
            let name = form.name();
            assert!(err < bound * tol, "{name} {tol:e}: {err:e}");
            assert!(
                err_lambda < bound_lambda * tol,
                "{name} {tol:e}: λ {err_lambda:e}"
            );
        }
    }
}

#[test]
fn output_times_are_filtered_sorted_and_end_with_t_end() {
    let sys = index1();
    let y0 = index1_exact(0.0);
    let mut options = Options::with_tol(1e-8);
    options.output_times = vec![3.0, -1.0, 0.0, 1.5, 3.0, 7.0, 2.0, 12.0];
    let sol = solve(&sys, &y0, 5.0, &options).unwrap();
    // One rule for every solver (core::output): a requested t0 is reported
    // as the initial values; repeats once.
    assert_eq!(sol.t, vec![0.0, 1.5, 2.0, 3.0, 5.0]);
    assert_eq!(sol.y.len(), 5);
    assert_eq!(sol.y[0], y0.to_vec());
    // t_end requested explicitly is reported once.
    options.output_times = vec![5.0, 1.0];
    let sol = solve(&sys, &y0, 5.0, &options).unwrap();
    assert_eq!(sol.t, vec![1.0, 5.0]);
    // Solution::last is the value at t_end.
    assert!(max_err(sol.last().unwrap(), &index1_exact(5.0), 3) < 1e-8);
}

// ---------------------------------------------------------------------------
// Observed orders with fixed steps (Hairer–Wanner VII.4)
// ---------------------------------------------------------------------------

fn assert_orders(what: &str, orders: &[f64], lo: f64, hi: f64) {
    println!("{what}: {orders:.2?}");
    for &p in orders {
        assert!(
            (lo..=hi).contains(&p),
            "{what}: observed orders {orders:?} not in [{lo}, {hi}]"
        );
    }
}

#[test]
fn fixed_step_order_index1_is_five() {
    // Radau IIA (s = 3) on index 1: order 2s − 1 = 5 in y and z.
    // Measured: 5.01, 5.01, 5.22 (y) and 5.01, 5.01, 5.23 (z).
    let sys = index1();
    let (t_end, y0) = (1.0, index1_exact(0.0));
    let errs = fixed_step_errors(&sys, &y0, t_end, &[10, 20, 40, 80], &index1_exact(t_end));
    assert_orders("index 1, y", &observed_orders(&errs, &[0, 1]), 4.7, 5.5);
    assert_orders("index 1, z", &observed_orders(&errs, &[2]), 4.7, 5.5);
}

#[test]
fn fixed_step_orders_index2_are_five_and_three() {
    // Index 2 (Hessenberg): y 2s − 1 = 5, z s = 3 (HW VII.4, Table 4.1).
    // Measured: y 4.93, 4.97, 4.99; z 2.90, 2.94, 2.97.
    let sys = Sys(Idec::new());
    let (t_end, y0) = (1.0, Idec::exact(0.0));
    let errs = fixed_step_errors(&sys, &y0, t_end, &[5, 10, 20, 40], &Idec::exact(t_end));
    assert_orders(
        "index 2, y",
        &observed_orders(&errs, &[0, 1, 2, 3]),
        4.7,
        5.3,
    );
    assert_orders("index 2, z", &observed_orders(&errs, &[4, 5]), 2.8, 3.2);
}

#[test]
fn fixed_step_orders_index3_are_five_three_two() {
    // Index 3 (ori2 pendulum, position y, velocity z, multiplier u):
    // y 2s − 1 = 5, z s = 3, u s − 1 = 2 (Hairer, Lubich & Roche 1989;
    // HW VII.4). Measured: positions 5.7, 5.6, 4.9; velocities 2.98,
    // 2.99, 3.00; λ 2.06, 2.02, 2.00.
    let sys = Pendulum::new(Form::Ori2);
    let (t_end, y0) = (0.5, sys.y0());
    let errs = fixed_step_errors(&sys, &y0, t_end, &[10, 20, 40, 80], &pendulum_exact(t_end));
    assert_orders(
        "index 3, positions",
        &observed_orders(&errs, &[0, 1]),
        4.5,
        6.0,
    );
    assert_orders(
        "index 3, velocities",
        &observed_orders(&errs, &[2, 3]),
        2.8,
        3.2,
    );
    assert_orders(
        "index 3, multiplier",
        &observed_orders(&errs, &[4]),
        1.8,
        2.3,
    );
}

#[test]
fn fixed_step_order_with_state_dependent_leading_matrix() {
    // psi0 (index 1, E depends on y): order 5 in every component.
    // Measured 4.82, 4.92, 4.96 (positions), 5.00 (velocities, λ).
    let sys = Pendulum::new(Form::Psi0);
    let (t_end, y0) = (0.5, sys.y0());
    let errs = fixed_step_errors(&sys, &y0, t_end, &[10, 20, 40, 80], &pendulum_exact(t_end));
    assert_orders(
        "psi0, all",
        &observed_orders(&errs, &[0, 1, 2, 3, 4]),
        4.6,
        5.4,
    );
}

// ---------------------------------------------------------------------------
// Errors: every kind, never a panic
// ---------------------------------------------------------------------------

#[test]
fn invalid_input_is_rejected() {
    use dae_solvers::options::Tol;
    let sys = Pendulum::new(Form::Rcd1);
    let y0 = sys.y0();
    let invalid =
        |r: Result<Solution, SolveError>| matches!(r, Err(SolveError::InvalidInput { .. }));

    let mut options = Options::with_tol(1e-6);
    options.tol = Tolerances {
        rtol: Tol::Scalar(-1e-6),
        atol: Tol::Scalar(1e-6),
    };
    assert!(invalid(solve(&sys, &y0, 1.0, &options)));
    options.tol = Tolerances::uniform(0.0);
    assert!(invalid(solve(&sys, &y0, 1.0, &options)));
    options.tol = Tolerances {
        rtol: Tol::PerComponent(vec![1e-6; 3]),
        atol: Tol::Scalar(1e-6),
    };
    assert!(invalid(solve(&sys, &y0, 1.0, &options)));
    options.tol = Tolerances::uniform(f64::NAN);
    assert!(invalid(solve(&sys, &y0, 1.0, &options)));

    let options = Options::with_tol(1e-6);
    assert!(invalid(solve(&sys, &y0[..3], 1.0, &options)));
    assert!(invalid(solve(&sys, &y0, 0.0, &options)));
    assert!(invalid(solve(&sys, &y0, f64::INFINITY, &options)));
    for bad in [
        Options {
            h0: Some(-1.0),
            ..Options::with_tol(1e-6)
        },
        Options {
            h_max: Some(0.0),
            ..Options::with_tol(1e-6)
        },
        Options {
            max_steps: 0,
            ..Options::with_tol(1e-6)
        },
        Options {
            output_times: vec![f64::NAN],
            ..Options::with_tol(1e-6)
        },
    ] {
        assert!(invalid(solve(&sys, &y0, 1.0, &bad)));
    }
}

#[test]
fn overdetermined_systems_are_refused() {
    let sys = Simple::overdetermined();
    assert_eq!(
        Radau5.accepts(sys.info()),
        Err(NotApplicable::Overdetermined {
            equations: 2,
            unknowns: 1
        })
    );
    let err = solve(&sys, &[1.0], 1.0, &Options::default()).unwrap_err();
    assert_eq!(err.kind(), "not_applicable");
    assert!(err.to_string().contains("overdetermined"), "{err}");
    assert!(Radau5.accepts(Pendulum::new(Form::Ggl1).info()).is_ok());
}

#[test]
fn non_finite_values_are_reported() {
    let sys = Pendulum::new(Form::Rcd0);
    let mut y0 = sys.y0();
    y0[2] = f64::NAN;
    let err = solve(&sys, &y0, 1.0, &Options::default()).unwrap_err();
    assert_eq!(
        err,
        SolveError::NonFinite {
            t: 0.0,
            what: "initial values"
        }
    );
    y0[2] = f64::INFINITY;
    assert_eq!(
        solve(&sys, &y0, 1.0, &Options::default())
            .unwrap_err()
            .kind(),
        "non_finite"
    );

    let err = solve(&nan_rhs(), &[1.0], 1.0, &Options::default()).unwrap_err();
    assert_eq!(
        err,
        SolveError::NonFinite {
            t: 0.0,
            what: "residual"
        }
    );
}

#[test]
fn step_limit_is_reported() {
    let sys = Pendulum::new(Form::Rcd1);
    let options = Options {
        max_steps: 10,
        ..Options::with_tol(1e-6)
    };
    match solve(&sys, &sys.y0(), 20.0, &options) {
        Err(SolveError::StepLimit { t, max_steps }) => {
            assert_eq!(max_steps, 10);
            assert!(t > 0.0 && t < 20.0);
        }
        other => panic!("expected a step limit, got {other:?}"),
    }
}

#[test]
fn blow_up_gives_step_size_too_small() {
    // y' = y², y(0) = 1: y = 1/(1 − t) blows up at t = 1.
    let err = solve(&blow_up(), &[1.0], 2.0, &Options::with_tol(1e-6)).unwrap_err();
    match err {
        SolveError::StepSizeTooSmall { t, h } => {
            assert!((t - 1.0).abs() < 1e-6, "t = {t}");
            assert!(h > 0.0 && h < 1e-12, "h = {h}");
        }
        other => panic!("expected StepSizeTooSmall, got {other:?}"),
    }
}

#[test]
fn unsolvable_stage_equations_give_newton_failure() {
    // 0 = y² + 1 has no real solution: Newton fails at every step size.
    let err = solve(&no_real_root(), &[1.0], 1.0, &Options::with_tol(1e-6)).unwrap_err();
    assert!(
        matches!(err, SolveError::NewtonFailure { t, .. } if t == 0.0),
        "{err:?}"
    );
    // With a fixed step the first failure with a fresh Jacobian is final.
    let options = Options {
        fixed_step: Some(0.1),
        ..Options::with_tol(1e-6)
    };
    let err = solve(&no_real_root(), &[1.0], 1.0, &options).unwrap_err();
    assert_eq!(err.kind(), "newton_failure");
}

#[test]
fn singular_iteration_matrix_is_reported() {
    // E = 0 and ∂f/∂y = 0: every iteration matrix is zero.
    let err = solve(&zero_equals_one(), &[0.0], 1.0, &Options::default()).unwrap_err();
    match err {
        SolveError::SingularMatrix { t, h } => {
            assert_eq!(t, 0.0);
            // Five attempts, the step halved after each of the first four.
            assert!((h - 1e-6 / 16.0).abs() < 1e-20, "h = {h}");
        }
        other => panic!("expected SingularMatrix, got {other:?}"),
    }
    let options = Options {
        fixed_step: Some(0.1),
        ..Options::default()
    };
    let err = solve(&zero_equals_one(), &[0.0], 1.0, &options).unwrap_err();
    assert_eq!(err.kind(), "singular_matrix");
}

#[test]
fn extreme_options_do_not_panic() {
    let sys = Pendulum::new(Form::Ggl1);
    let y0 = sys.y0();
    for options in [
        Options {
            h0: Some(1e3),
            ..Options::with_tol(1e-6)
        },
        Options {
            h0: Some(1e-300),
            ..Options::with_tol(1e-6)
        },
        Options {
            h_max: Some(1e-3),
            ..Options::with_tol(1e-4)
        },
        Options::with_tol(1e-16),
        Options::with_tol(1.0),
        Options {
            fixed_step: Some(5.0),
            ..Options::with_tol(1e-6)
        },
        Options {
            tol: Tolerances {
                rtol: dae_solvers::options::Tol::Scalar(0.0),
                atol: dae_solvers::options::Tol::Scalar(1e-8),
            },
            ..Options::default()
        },
    ] {
        // Success or a typed error, never a panic.
        let _ = solve(&sys, &y0, 2.0, &options);
    }
}

// ---------------------------------------------------------------------------
// Options and statistics
// ---------------------------------------------------------------------------

#[test]
fn record_steps_h0_and_h_max_are_respected() {
    let sys = Pendulum::new(Form::Psi1);
    let y0 = sys.y0();
    let options = Options {
        record_steps: true,
        h0: Some(1e-3),
        h_max: Some(0.01),
        ..Options::with_tol(1e-6)
    };
    let sol = solve(&sys, &y0, 2.0, &options).unwrap();
    assert_eq!(sol.steps.len(), sol.stats.steps);
    assert!(sol.steps[0].0 <= 1e-3);
    let mut t_prev = 0.0;
    for (t, y) in &sol.steps {
        assert!(*t > t_prev);
        assert!(t - t_prev <= 0.01 * (1.0 + 1e-12), "step {}", t - t_prev);
        assert_eq!(y.len(), 5);
        t_prev = *t;
    }
    assert_eq!(t_prev, 2.0, "the last step ends exactly at t_end");
    assert_eq!(sol.steps.last().unwrap().1, sol.y[0]);
}

#[test]
fn fixed_steps_are_constant() {
    let sys = index1();
    let options = Options {
        fixed_step: Some(0.1),
        record_steps: true,
        ..Options::with_tol(1e-10)
    };
    let sol = solve(&sys, &index1_exact(0.0), 1.0, &options).unwrap();
    assert_eq!(sol.stats.steps, 10);
    for (k, (t, _)) in sol.steps.iter().enumerate() {
        assert!((t - 0.1 * (k + 1) as f64).abs() < 1e-14);
    }
    assert_eq!(sol.t, vec![1.0]);
}

#[test]
fn statistics_are_consistent() {
    let sys = Pendulum::new(Form::Rcd1);
    let sol = solve(&sys, &sys.y0(), 20.0, &Options::with_tol(1e-6)).unwrap();
    let s = sol.stats;
    assert!(s.steps > 100);
    assert!(s.jacobian_evals >= 1 && s.jacobian_evals <= s.steps + s.rejected);
    assert!(s.factorizations >= s.jacobian_evals);
    assert!(s.newton_iterations >= s.steps);
    // Three stage residuals per Newton iteration, plus f(t_n, y_n) per step.
    assert!(s.residual_evals >= 3 * s.newton_iterations + s.steps);
    assert!(s.residual_evals <= 3 * s.newton_iterations + 2 * (s.steps + s.rejected) + 1);
    assert_eq!(Radau5.name(), "radau5");
    assert!(dae_solvers::solver_by_name("radau5").is_some());
}

// ---------------------------------------------------------------------------
// No allocation in the step loop
// ---------------------------------------------------------------------------

#[test]
fn the_step_loop_does_not_allocate() {
    for form in [Form::Ori2, Form::Ggl1, Form::Psi0] {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        // The dense output record grows with the steps (amortised pushes,
        // `Options::dense_output`); the step loop itself allocates nothing.
        let options = Options {
            dense_output: false,
            ..Options::with_tol(1e-8)
        };
        let (short, short_steps) =
            allocations_of(|| solve(&sys, &y0, 2.0, &options).unwrap().stats.steps);
        let (long, long_steps) =
            allocations_of(|| solve(&sys, &y0, 20.0, &options).unwrap().stats.steps);
        assert!(long_steps > 5 * short_steps);
        assert_eq!(
            short,
            long,
            "{}: allocations depend on the number of steps",
            form.name()
        );
    }
    // With output times: one allocation per reported value, no more.
    let sys = Pendulum::new(Form::Rcd1);
    let y0 = sys.y0();
    let mut options = Options {
        dense_output: false,
        ..Options::with_tol(1e-8)
    };
    let (base, _) = allocations_of(|| solve(&sys, &y0, 20.0, &options).unwrap());
    options.output_times = (1..=400).map(|k| 0.05 * f64::from(k)).collect();
    let (with_output, _) = allocations_of(|| solve(&sys, &y0, 20.0, &options).unwrap());
    // One vector per output time but the last, which the base run reports
    // too.
    assert_eq!(with_output, base + 399, "{with_output} vs {base}");
}

/// At tight tolerances (`radau5::TIGHT_TOL`) the step updates are summed
/// with compensation and the Newton iteration is stopped closer to the
/// solution: S01 then reaches errors no uncompensated run reaches
/// (BENCHMARKS.md §6b). On this system rcd0 reaches 1.2e-13, 1.2e-13 and
/// 8.1e-14 at the three tolerances; before, 2.5e-12, 7.6e-12 and 1.6e-11
/// (the error grew as the tolerance fell). The bound sits 4× above the
/// first and 5–30× below the second.
#[test]
fn s01_tight_tolerances_reach_the_last_digits() {
    let exact = exact_at_20();
    let sys = Pendulum::new(Form::Rcd0);
    let y0 = sys.y0();
    for tol in [1e-13, 5e-14, 2.5e-14] {
        let sol = solve(&sys, &y0, 20.0, &Options::with_tol(tol))
            .unwrap_or_else(|e| panic!("rcd0 at {tol:e}: {e}"));
        let err = max_err(sol.last().unwrap(), &exact, 4);
        println!("rcd0 tol {tol:e}: err {err:e}, {} steps", sol.stats.steps);
        assert!(err < 5e-13, "rcd0 tol {tol:e}: err {err:e}");
    }
}

//! Ensembles (issue 25, done-when 4, the ensemble half): the pendulum's
//! period over release angles, measured with events in parallel, against
//! the exact period by the arithmetic–geometric mean; the same results
//! bit for bit with 1 and 2 threads; a failing member reported in its slot.

use dae::dae_solvers::{radau5::Radau5, Direction, EventSpec, SolveError, StepOutcome};
use dae::ensemble::{Ensemble, MemberError};
use dae::prelude::*;

dae! {
    /// The pendulum (g = 9.81, l = 1) with the rod's crossings of the
    /// downward vertical as an event.
    pub Swing {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        differential { x, y, v, w }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(y) = w;
            m * der(v) = -2 * x * lambda;
            m * der(w) = -2 * y * lambda - m * g;
            0 = x^2 + y^2 - l^2;
        }
        events { cross = x; }
        formulations { ggl1 }
    }
}

const G: f64 = 9.81;

/// `K(k) = π / (2 M(1, √(1 − k²)))` by the arithmetic–geometric mean.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    // Quadratic convergence: a handful of iterations reach round-off (a
    // bound, not a tolerance below ε, which could cycle).
    for _ in 0..32 {
        if (a - b).abs() <= 4.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (a + b)
}

/// The exact period at release angle `theta0` (l = 1).
fn exact_period(theta0: f64) -> f64 {
    4.0 * (1.0 / G).sqrt() * elliptic_k((0.5 * theta0).sin())
}

#[derive(Debug, thiserror::Error)]
enum PeriodError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error("fewer than two falling crossings of x = 0 before t = {t_end}")]
    NoCrossing { t_end: f64 },
}

/// The period of the release from rest at `theta0`: the time between the
/// first two falling crossings of x = 0 (at T/4 and 5T/4), located by the
/// events on radau5's dense output, at tol 1e-10.
fn measured_period(theta0: f64) -> Result<(f64, usize), PeriodError> {
    let sys = Swing::default().ggl1();
    let y0 = [theta0.sin(), -theta0.cos(), 0.0, 0.0, 0.0, 0.0];
    let start = dae::dae_solvers::init::consistent(&sys, 0.0, &y0, &Default::default())?;
    let t_end = 20.0;
    let problem = Problem {
        system: &sys,
        t0: 0.0,
        y0: &start.y,
        t_end,
    };
    let options = Options {
        events: vec![EventSpec::record("cross").direction(Direction::Falling)],
        dense_output: false,
        ..Options::with_tol(1e-10)
    };
    let mut stepper = Radau5.integrator(&problem, &options)?;
    while stepper.events().len() < 2 {
        if let StepOutcome::Finished { .. } = stepper.step()? {
            return Err(PeriodError::NoCrossing { t_end });
        }
    }
    let e = stepper.events();
    Ok((e[1].t - e[0].t, stepper.stats().steps))
}

fn angles(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 0.05 + 3.0 * k as f64 / (n - 1) as f64)
        .collect()
}

#[test]
fn periods_match_the_agm_formula_and_do_not_depend_on_the_threads() {
    let theta = angles(20);
    let one = Ensemble::new()
        .threads(1)
        .run(&theta, |&t| measured_period(t))
        .unwrap();
    let two = Ensemble::new()
        .threads(2)
        .run(&theta, |&t| measured_period(t))
        .unwrap();
    let mut worst = (0.0f64, 0.0f64);
    for (k, (a, b)) in one.iter().zip(&two).enumerate() {
        let (p1, steps1) = *a.as_ref().unwrap();
        let (p2, steps2) = *b.as_ref().unwrap();
        // Each member is one thread's computation from its angle alone.
        assert_eq!(p1.to_bits(), p2.to_bits(), "member {k}");
        assert_eq!(steps1, steps2, "member {k}");
        let exact = exact_period(theta[k]);
        let rel = (p1 - exact).abs() / exact;
        if rel > worst.0 {
            worst = (rel, theta[k]);
        }
        // The bound: done-when 1 of issue 25 holds the events to 1e-9 s
        // on a crossing at tol 1e-10 (tests/events.rs); a period is the
        // difference of two crossings, ≤ 2e-9 s on a period ≥ 2 s, so
        // ≤ 1e-9 relative. Measured: 3.8e-12 at θ₀ = 3.05 (the slow,
        // nearly inverted release), ~1e-14 below θ₀ = 1.
        assert!(
            rel < 1e-9,
            "θ₀ = {}: period {p1}, exact {exact}, rel. {rel:.1e}",
            theta[k]
        );
    }
    eprintln!(
        "worst relative period error {:.2e} at θ₀ = {:.3}",
        worst.0, worst.1
    );
}

#[test]
fn a_failing_member_is_an_error_in_its_slot() {
    // θ₀ = π: the bob balanced upright never falls (x = sin π = 1.2e-16
    // and v = 0 stay so to round-off), so there is no crossing; a NaN angle
    // is refused by the solver. Their neighbours are unaffected.
    let theta = [0.5, std::f64::consts::PI, 1.0, f64::NAN, 2.0];
    let out = Ensemble::new()
        .threads(2)
        .run(&theta, |&t| measured_period(t))
        .unwrap();
    assert_eq!(out.len(), 5);
    for k in [0, 2, 4] {
        let (p, _) = *out[k].as_ref().unwrap();
        assert!((p - exact_period(theta[k])).abs() < 1e-7, "member {k}: {p}");
    }
    assert!(
        matches!(
            &out[1],
            Err(MemberError::Failed {
                index: 1,
                error: PeriodError::NoCrossing { .. }
            })
        ),
        "{:?}",
        out[1]
    );
    assert!(
        matches!(
            &out[3],
            Err(MemberError::Failed {
                index: 3,
                error: PeriodError::Solve(_)
            })
        ),
        "{:?}",
        out[3]
    );
    assert_eq!(out[3].as_ref().unwrap_err().index(), 3);
}

#[test]
fn a_panicking_member_is_caught_in_its_slot() {
    let out = Ensemble::new()
        .threads(2)
        .run(&[1usize, 0, 2], |&k| {
            assert!(k != 0, "member zero");
            Ok::<_, String>(10 * k)
        })
        .unwrap();
    assert_eq!(out[0].as_ref().ok(), Some(&10));
    assert!(
        matches!(&out[1], Err(MemberError::Panicked { index: 1, message }) if message == "member zero")
    );
    assert_eq!(out[2].as_ref().ok(), Some(&20));
}

//! Tests of the MEBDF solver (`dae_solvers::mebdf`).

mod common;

use common::*;
use dae_core::system::DaeSystem;
use dae_solvers::mebdf::Mebdf;
use dae_solvers::{Options, Problem, Solution, SolveError, Solver};

/// Integrate `sys` from `y0` at `t = 0` to `t_end`.
fn run(
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    options: &Options,
) -> Result<Solution, SolveError> {
    let problem = Problem {
        system: sys,
        t0: 0.0,
        y0,
        t_end,
    };
    Mebdf.solve(&problem, options)
}

fn s01_exact_at_20() -> [f64; 5] {
    let exact = reference("pendulum_s01_exact.csv");
    let (t, values) = *exact.last().expect("reference rows");
    assert_eq!(t, 20.0);
    values
}

const FORMS: [Form; 4] = [Form::Ori2, Form::Rcd1, Form::Rcd0, Form::Ggl1];

#[test]
#[ignore]
fn explore_s01() {
    let end = s01_exact_at_20();
    for form in FORMS {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        for i in 5..=12 {
            let tol = 10f64.powi(-i);
            match run(&sys, &y0, 20.0, &Options::with_tol(tol)) {
                Ok(sol) => {
                    let err = err_sum(sol.last().unwrap(), &end);
                    println!("{} 1e-{i}: err {err:.2e} {:?}", form.name(), sol.stats);
                }
                Err(e) => println!("{} 1e-{i}: {e}", form.name()),
            }
        }
    }
}

/// Errors at `t_end` for fixed steps `h0 / 2^j`, and observed orders.
fn observed_orders(
    sys: &dyn DaeSystem,
    exact: fn(f64) -> Vec<f64>,
    t_end: f64,
    h0: f64,
    steps: usize,
    levels: i32,
) -> (Vec<f64>, Vec<f64>) {
    let y0 = exact(0.0);
    let errors: Vec<f64> = (0..levels)
        .map(|j| {
            let mut options = Options::with_tol(1e-13);
            options.fixed_step = Some(h0 / 2f64.powi(j));
            options.fixed_order = Some(steps);
            let sol = run(sys, &y0, t_end, &options).expect("fixed-step run");
            let u = sol.last().expect("output");
            let ex = exact(t_end);
            (0..u.len()).map(|i| (u[i] - ex[i]).abs()).fold(0.0, f64::max)
        })
        .collect();
    let orders = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    (errors, orders)
}

#[test]
#[ignore]
fn explore_orders() {
    for k in 1..=5 {
        let (e, o) = observed_orders(&ode(), ode_exact, 2.0, 0.2, k, 5);
        println!("ode k={k}: {e:?} {o:.3?}");
        let (e, o) = observed_orders(&dae1(), dae1_exact, 1.2, 0.1, k, 5);
        println!("dae1 k={k}: {e:?} {o:.3?}");
    }
}

#[test]
#[ignore]
fn explore_one() {
    let form = match std::env::var("FORM").as_deref() {
        Ok("ori2") => Form::Ori2,
        Ok("rcd1") => Form::Rcd1,
        Ok("ggl1") => Form::Ggl1,
        _ => Form::Rcd0,
    };
    let tol: f64 = std::env::var("TOL").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-7);
    let t_end: f64 = std::env::var("TEND").ok().and_then(|s| s.parse().ok()).unwrap_or(20.0);
    let sys = Pendulum::new(form);
    let r = run(&sys, &sys.y0(), t_end, &Options::with_tol(tol));
    println!("{:?}", r.map(|s| s.stats));
}

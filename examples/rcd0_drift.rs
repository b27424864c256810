//! The drift of the pendulum's rcd0 formulation off its position and
//! velocity constraints over a long run (S02's constants), stepped with
//! the public stepper: rcd0 keeps only the acceleration-level constraint,
//! so `g = x² + y² − 1` and `g_v = x v + y w` are not restored — `g_v` is
//! an invariant of the rcd0 equations and takes every error a step makes
//! in it along, and `g` drifts by `2 g_v` per unit time.
//!
//! ```text
//! cargo run --release --example rcd0_drift SOLVER TOL T_END
//! ```
//!
//! Prints the first time `|g|` exceeds 1e-3, 1e-2, 1e-1 and 0.5, then
//! the end: `t`, `g`, `g_v`, the energy and `λ`, or the typed failure.
use dae::dae_solvers::{init, solver_by_name, Options, Problem};
use dae::models::builtin::Pendulum;
use dae::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("usage: rcd0_drift SOLVER TOL T_END");
        std::process::exit(2);
    }
    let solver = solver_by_name(&args[0]).expect("a solver name");
    let tol: f64 = args[1].parse().expect("TOL");
    let t_end: f64 = args[2].parse().expect("T_END");
    let model = Pendulum {
        g: 13.750_371_637_329_454,
        ..Pendulum::default()
    };
    let sys = Model::formulation(&model, "rcd0").expect("rcd0");
    let mut y0 = vec![0.0; sys.info().unknowns()];
    y0[0] = 1.0;
    let start = init::consistent(&*sys, 0.0, &y0, &Default::default()).expect("start");
    let options = Options {
        dense_output: false,
        ..Options::with_tol(tol)
    };
    let problem = Problem {
        system: &*sys,
        t0: 0.0,
        y0: &start.y,
        t_end,
    };
    let mut stepper = solver.integrator(&problem, &options).expect("integrator");
    let state = |y: &[f64]| {
        let g = y[0] * y[0] + y[1] * y[1] - 1.0;
        let gv = y[0] * y[2] + y[1] * y[3];
        let energy = 0.5 * (y[2] * y[2] + y[3] * y[3]) + model.g * y[1];
        format!(
            "g {g:.3e} g_v {gv:.3e} energy {energy:.4e} lambda {:.3e}",
            y[4]
        )
    };
    let mut marks = [1e-3, 1e-2, 1e-1, 0.5].into_iter().peekable();
    loop {
        if let Err(e) = stepper.step() {
            println!(
                "failed: {e}; at t = {:.4}: {}",
                stepper.t(),
                state(stepper.y())
            );
            break;
        }
        let y = stepper.y();
        let g = (y[0] * y[0] + y[1] * y[1] - 1.0).abs();
        while marks.peek().is_some_and(|&m| g > m) {
            let m = marks.next().unwrap_or_default();
            println!("|g| > {m:e} from t = {:.4}", stepper.t());
        }
        if stepper.finished() {
            println!("t = {:.4}: {}", stepper.t(), state(y));
            break;
        }
    }
    println!(
        "steps {} rejected {}",
        stepper.stats().steps,
        stepper.stats().rejected
    );
}

//! The pendulum of S01/S02 integrated once by one solver on one
//! formulation, for counting what a step costs: run it under callgrind and
//! collect only inside [`integrate`], which holds the solver call and
//! nothing else (the model, the consistent initial values and the options
//! are built before it).
//!
//! ```text
//! cargo build --release --example step_cost
//! valgrind --tool=callgrind --toggle-collect='step_cost::integrate' \
//!     target/release/examples/step_cost radau5 rcd1 1e-8
//! ```
//!
//! Arguments: `SOLVER FORM TOL [T_END] [dassl|propagated]` (T_END 20 is
//! S01, 2000 is S02; `dassl`, `propagated`: the BDF methods' error
//! estimate, [`Estimate`](dae::dae_solvers::options::Estimate), instead of
//! the default).
//! The program prints the run's statistics; instructions per accepted step
//! are callgrind's total `Ir` divided by `steps`.
use dae::dae_solvers::options::Estimate;
use dae::dae_solvers::{init, solver_by_name, Options, Problem, Solution, Solver};
use dae::models::builtin::Pendulum;
use dae::prelude::*;

#[inline(never)]
fn integrate(solver: &dyn Solver, problem: &Problem<'_>, options: &Options) -> Solution {
    match solver.solve(problem, options) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("the run failed: {e}");
            std::process::exit(1);
        }
    }
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut estimate = Options::default().estimate;
    for (name, value) in [
        ("dassl", Estimate::Dassl),
        ("propagated", Estimate::Propagated),
    ] {
        if let Some(i) = args.iter().position(|a| a == name) {
            args.remove(i);
            estimate = value;
        }
    }
    if args.len() < 3 {
        eprintln!("usage: step_cost SOLVER FORM TOL [T_END] [dassl|propagated]");
        std::process::exit(2);
    }
    let Some(solver) = solver_by_name(&args[0]) else {
        eprintln!("no solver `{}`", args[0]);
        std::process::exit(2);
    };
    let Ok(tol) = args[2].parse::<f64>() else {
        eprintln!("TOL `{}` is not a number", args[2]);
        std::process::exit(2);
    };
    let t_end = match args.get(3).map(|s| s.parse::<f64>()) {
        None => 20.0,
        Some(Ok(t)) if t > 0.0 => t,
        Some(_) => {
            eprintln!("T_END must be a positive number");
            std::process::exit(2);
        }
    };
    let model = Pendulum {
        g: 13.750_371_637_329_454,
        ..Pendulum::default()
    };
    let sys = Model::formulation(&model, &args[1]).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let n = sys.info().unknowns();
    let mut y0 = vec![0.0; n];
    y0[0] = 1.0;
    let start = init::consistent(&*sys, 0.0, &y0, &Default::default()).unwrap_or_else(|e| {
        eprintln!("no consistent start: {e}");
        std::process::exit(1);
    });
    let checks: Vec<f64> = if t_end > 20.0 {
        (1..)
            .map(|k| 2.0 * k as f64)
            .take_while(|&t| t <= t_end)
            .collect()
    } else {
        vec![t_end]
    };
    let options = Options {
        output_times: checks,
        // Measures the step loop: no dense output kept.
        dense_output: false,
        estimate,
        ..Options::with_tol(tol)
    };
    let problem = Problem {
        system: &*sys,
        t0: 0.0,
        y0: &start.y,
        t_end,
    };
    let sol = integrate(&*solver, &problem, &options);
    let s = sol.stats;
    let last = sol.last().unwrap_or(&[]);
    println!(
        "{}({}) tol {tol:e}: steps {} rejected {} evals {} jac {} LU {} y(T) = {:?}",
        args[0],
        args[1],
        s.steps,
        s.rejected,
        s.residual_evals,
        s.jacobian_evals,
        s.factorizations,
        &last[..4.min(last.len())]
    );
}

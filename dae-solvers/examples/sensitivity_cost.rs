//! What forward sensitivities cost on the pendulum (issue 25, done-when 3):
//! the plain run against the same run with the sensitivities of 1 and 2
//! parameters (`dae_core::sensitivity`), S01 (t ∈ [0, 20]), each solver and
//! formulation, the sensitivities in the error test and out of it
//! (`SensitivitySystem::set_error_control`), counts and the least time of 5
//! runs.
//!
//! ```sh
//! cargo run --release -p dae-solvers --example sensitivity_cost [tol]
//! ```
//!
//! One case per process, integrated once, for an instruction count of the
//! integration alone (`solve_case` is the function to collect; the model's
//! derivation and the consistent start stay outside it):
//!
//! ```sh
//! valgrind --tool=callgrind --toggle-collect='*solve_case*' \
//!     target/release/examples/sensitivity_cost 1e-8 radau5 rcd0 1 on
//! ```
//!
//! with `P` = 0 for the plain run (the error control argument is then
//! ignored).

use dae_core::interp::InterpretedModel;
use dae_core::sensitivity::Sensitivities;
use dae_core::system::DaeSystem;
use dae_solvers::init::{consistent, InitOptions};
use dae_solvers::sensitivity::consistent_start;
use dae_solvers::{solver_by_name, Options, Problem, Stats};
use std::time::Instant;

/// One integration of S01's horizon: what an instruction count collects.
#[inline(never)]
fn solve_case(solver: &str, sys: &dyn DaeSystem, y0: &[f64], tol: f64) -> Stats {
    let options = Options::with_tol(tol);
    let problem = Problem {
        system: sys,
        t0: 0.0,
        y0,
        t_end: 20.0,
    };
    let solver = solver_by_name(solver).unwrap();
    solver.solve(&problem, &options).unwrap().stats
}

/// The counts of one run and the least wall time of `repeat`.
fn run(solver: &str, sys: &dyn DaeSystem, y0: &[f64], tol: f64, repeat: usize) -> (Stats, f64) {
    let mut best = f64::INFINITY;
    let mut stats = Stats::default();
    for _ in 0..repeat {
        let start = Instant::now();
        stats = solve_case(solver, sys, y0, tol);
        best = best.min(start.elapsed().as_secs_f64());
    }
    (stats, best)
}

/// The consistent start of the release x = 1, at rest.
fn released(
    sys: &dyn DaeSystem,
    start: impl Fn(&[f64]) -> Result<dae_solvers::init::Consistent, dae_solvers::SolveError>,
) -> Vec<f64> {
    let mut y0 = vec![0.0; sys.info().unknowns()];
    y0[0] = 1.0;
    start(&y0).unwrap().y
}

/// The model text of the pendulum.
fn pendulum() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/pendulum.dae");
    std::fs::read_to_string(path).unwrap()
}

/// The sensitivity parameters of `p` = 1 or 2.
fn parameters(p: usize) -> &'static [&'static str] {
    match p {
        1 => &["g"],
        _ => &["g", "l"],
    }
}

/// `solver formulation P on|off`: one integration, its counts.
fn one_case(tol: f64, args: &[String]) {
    let [solver, f, p, control] = args else {
        panic!("expected: tol solver formulation P on|off");
    };
    let p: usize = p.parse().expect("P: 0, 1 or 2");
    let src = pendulum();
    let stats = if p == 0 {
        let plain = InterpretedModel::from_str(&src).unwrap();
        let sys = plain.system(f).unwrap();
        let y0 = released(&sys, |y| consistent(&sys, 0.0, y, &InitOptions::default()));
        solve_case(solver, &sys, &y0, tol)
    } else {
        let model = Sensitivities::from_str(&src, parameters(p)).unwrap();
        let mut sys = model.formulation(f).unwrap();
        sys.set_error_control(control == "on");
        let y0 = released(&sys, |y| {
            consistent_start(&sys, 0.0, y, &InitOptions::default())
        });
        solve_case(solver, &sys, &y0, tol)
    };
    println!(
        "{solver}({f}) P = {p} error control {control}: steps {} rejected {} residual evals {} \
         Jacobians {} LUs {} Newton iterations {}",
        stats.steps,
        stats.rejected,
        stats.residual_evals,
        stats.jacobian_evals,
        stats.factorizations,
        stats.newton_iterations
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tol: f64 = args
        .first()
        .map_or(1e-8, |s| s.parse().expect("a tolerance"));
    if args.len() > 1 {
        return one_case(tol, &args[1..]);
    }
    let src = pendulum();
    let plain = InterpretedModel::from_str(&src).unwrap();
    let one = Sensitivities::from_str(&src, parameters(1)).unwrap();
    let two = Sensitivities::from_str(&src, parameters(2)).unwrap();
    println!("tol {tol:e}; time: least of 5 runs (wall, s); ratio: against the plain run");
    println!("| solver(formulation) | P | error control | steps | residual evals | Jacobians | LUs | time | time ratio | (1 + 0.6 P) |");
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    for solver in ["radau5", "bdf"] {
        for f in ["rcd0", "ggl1"] {
            let base = plain.system(f).unwrap();
            let (s0, t0) = run(
                solver,
                &base,
                &released(&base, |y| {
                    consistent(&base, 0.0, y, &InitOptions::default())
                }),
                tol,
                5,
            );
            let row = |p: usize, control: &str, s: &Stats, t: f64| {
                println!(
                    "| {solver}({f}) | {p} | {control} | {} | {} | {} | {} | {t:.4} | {:.2} | {:.1} |",
                    s.steps,
                    s.residual_evals,
                    s.jacobian_evals,
                    s.factorizations,
                    t / t0,
                    1.0 + 0.6 * p as f64
                )
            };
            row(0, "", &s0, t0);
            for control in [true, false] {
                for (p, model) in [(1, &one), (2, &two)] {
                    let mut sys = model.formulation(f).unwrap();
                    sys.set_error_control(control);
                    let y0 = released(&sys, |y| {
                        consistent_start(&sys, 0.0, y, &InitOptions::default())
                    });
                    let (s, t) = run(solver, &sys, &y0, tol, 5);
                    row(p, if control { "on" } else { "off" }, &s, t);
                }
            }
        }
    }
}

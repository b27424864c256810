//! Scenario S02 (pendulum, t ∈ [0, 2000], check times t = 2k) with the BDF
//! solver on five hand-written formulations and tolerances 1e-5 … 1e-12,
//! compared with the DASSL/DASPK rows of the paper's Table 9 and of the
//! Fortran anchors.
//!
//! ```text
//! cargo run --release -p dae-solvers --example bdf_s02 [--propagated] [formulation …]
//! ```
//!
//! The runs use DASSL's own error estimate ([`Estimate::Dassl`]), with
//! which the port takes the Fortran DASSL's steps; `--propagated` runs the
//! solver's default estimate instead (BENCHMARKS.md §18).
//!
//! Columns: `err_sum` = Σ over t = 2k, k = 1..1000 of
//! |x−x*|+|y−y*|+|v−v*|+|w−w*|+|λ−λ*| (SPEC §3, the paper's ERR);
//! `err_max` = max over the check times of max(|x−x*|, |y−y*|, |v−v*|,
//! |w−w*|) (the anchors' `err_true`); `err_lam` the same for λ.

#[path = "../tests/common/mod.rs"]
mod common;

use common::{err_max, err_sum, reference, reference_path, Form, Pendulum};
use dae_solvers::bdf::Bdf;
use dae_solvers::options::Estimate;
use dae_solvers::{Options, Problem, Solver};
use std::collections::HashMap;
use std::time::Instant;

/// The rows of a CSV file in the repository's `data/`, split at commas,
/// without comment lines (none when the file is missing).
fn csv_rows(file: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(reference_path(file)).unwrap_or_default();
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// `(solver, formulation, quantity) → values at tol 1e-5 … 1e-12`.
fn paper_table() -> HashMap<(String, String, String), Vec<String>> {
    csv_rows("paper_table9_s02.csv")
        .into_iter()
        .filter(|c| c.len() >= 11 && !c[0].starts_with("solver"))
        .map(|c| {
            (
                (c[0].clone(), c[1].clone(), c[2].clone()),
                c[3..11].to_vec(),
            )
        })
        .collect()
}

/// Fortran anchor rows `(solver, formulation, tol) → row` for S02.
fn anchors() -> HashMap<(String, String, String), Vec<String>> {
    csv_rows("fortran_anchors.csv")
        .into_iter()
        .filter(|c| c.len() >= 13 && c[2] == "S02")
        .map(|c| ((c[0].clone(), c[1].clone(), c[3].clone()), c))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let estimate = if args.iter().any(|a| a == "--propagated") {
        Estimate::Propagated
    } else {
        Estimate::Dassl
    };
    let filter: Vec<String> = args.into_iter().filter(|a| a != "--propagated").collect();
    let exact = reference("pendulum_s02_periods_exact.csv");
    let checks: Vec<(f64, [f64; 5])> = exact.into_iter().filter(|(t, _)| *t > 0.0).collect();
    let times: Vec<f64> = checks.iter().map(|(t, _)| *t).collect();
    let paper = paper_table();
    let anchor = anchors();

    println!(
        "{:<5} {:>6} {:<6} {:>10} {:>10} {:>10} {:>9} {:>6} {:>9} {:>6} {:>6} {:>8}",
        "form",
        "tol",
        "status",
        "err_sum",
        "err_max",
        "err_lam",
        "steps",
        "rej",
        "res_evals",
        "jac",
        "lu",
        "time_s"
    );
    for form in Form::INDEX_AT_MOST_2 {
        if !filter.is_empty() && !filter.iter().any(|f| f == form.name()) {
            continue;
        }
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        for (col, i) in (5..=12).enumerate() {
            let tol = 10f64.powi(-i);
            let mut options = Options::with_tol(tol);
            options.estimate = estimate;
            options.index2_in_error_test = Some(!form.has_index2());
            options.output_times = times.clone();
            let problem = Problem {
                system: &sys,
                t0: 0.0,
                y0: &y0,
                t_end: 2000.0,
            };
            let start = Instant::now();
            let result = Bdf.solve(&problem, &options);
            let secs = start.elapsed().as_secs_f64();
            match result {
                Ok(sol) => {
                    let (mut sum, mut emax, mut elam) = (0.0, 0.0_f64, 0.0_f64);
                    for (u, (_, ex)) in sol.y.iter().zip(&checks) {
                        sum += err_sum(u, ex);
                        emax = emax.max(err_max(u, ex));
                        elam = elam.max((u[Pendulum::LAMBDA] - ex[4]).abs());
                    }
                    let s = sol.stats;
                    println!(
                        "{:<5} {:>6} {:<6} {:>10.3e} {:>10.3e} {:>10.3e} {:>9} {:>6} {:>9} {:>6} {:>6} {:>8.3}",
                        form.name(),
                        format!("1e-{i}"),
                        "ok",
                        sum,
                        emax,
                        elam,
                        s.steps,
                        s.rejected,
                        s.residual_evals,
                        s.jacobian_evals,
                        s.factorizations,
                        secs
                    );
                }
                Err(e) => println!(
                    "{:<5} {:>6} FAIL   {e} ({:.3} s)",
                    form.name(),
                    format!("1e-{i}"),
                    secs
                ),
            }
            for solver in ["DASSL", "DASPK"] {
                let key = |q: &str| (solver.to_string(), form.name().to_string(), q.to_string());
                if let (Some(err), Some(ts)) = (paper.get(&key("err")), paper.get(&key("tsim_s"))) {
                    let (err, ts) = (&err[col], &ts[col]);
                    println!(
                        "      paper {solver:<5}: err {:>8}  tsim {:>8}",
                        if err.is_empty() { "fail" } else { err },
                        if ts.is_empty() { "-" } else { ts }
                    );
                }
                let akey = (
                    solver.to_lowercase(),
                    form.name().to_string(),
                    format!("1e-{i}"),
                );
                if let Some(row) = anchor.get(&akey) {
                    println!(
                        "      fortran {:<5}: {} err_max {} err_lam {} steps {} rej {} fevals {} jevals {} cpu {}",
                        row[0], row[4], row[5], row[6], row[8], row[9], row[10], row[11], row[7]
                    );
                }
            }
        }
    }
}

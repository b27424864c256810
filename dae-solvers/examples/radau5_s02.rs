//! Scenario S02 of the paper (pendulum, `t ∈ [0, 2000]`, check every 2 s)
//! with `radau5`: `ERR_sum` against the exact solution next to the paper's
//! RADAU5 value (Steinbrecher 2015, Table 9).
//!
//! ```text
//! cargo run --release -p dae-solvers --example radau5_s02 [-- FORM... [--t-end T]]
//! ```
//!
//! `FORM` is any of `ori2 rcd1 rcd0 ggl1 psi1 psi0` (default: `rcd1 rcd0
//! ggl1`, the formulations the paper's RADAU5 solved at every tolerance);
//! `--t-end 20` runs Scenario S01 instead (one check time, no paper value).
//!
//! `ERR_sum = Σ_k |x − x*| + |y − y*| + |v − v*| + |w − w*| + |λ − λ*|` over
//! the check times `t = 2k`, `k = 1..1000` (SPEC §3).

#[path = "../tests/common/mod.rs"]
mod common;

use common::{err_sum, pendulum_exact, Form, Pendulum};
use dae_solvers::radau5::Radau5;
use dae_solvers::{Options, Problem, Solver};
use std::time::Instant;

/// The paper's RADAU5 `ERR` row of Table 9 for tolerances `1e-5 … 1e-12`
/// (`None`: the integration failed).
fn paper_err(form: Form) -> Option<[Option<f64>; 8]> {
    let v = |a: [f64; 8]| Some(a.map(Some));
    match form {
        Form::Ori2 => Some([
            Some(4.5e2),
            Some(3.6e2),
            Some(1.6e1),
            Some(9.6e-1),
            Some(8.3e-2),
            Some(5.1e-3),
            None,
            None,
        ]),
        Form::Rcd1 => v([4.6e2, 2.1e1, 3.8e0, 2.7e-1, 7.1e-2, 1.5e-2, 3.5e-3, 5.5e-4]),
        Form::Rcd0 => v([5.7e2, 4.3e2, 2.0e2, 1.9e1, 8.8e-1, 1.1e-1, 8.0e-3, 2.3e-3]),
        Form::Ggl1 => v([4.7e2, 7.9e1, 9.2e0, 1.1e0, 1.5e-1, 2.3e-2, 3.4e-3, 5.2e-4]),
        Form::Psi1 | Form::Psi0 | Form::Ovd1 => None,
    }
}

fn parse_form(name: &str) -> Option<Form> {
    Form::SQUARE.into_iter().find(|f| f.name() == name)
}

fn main() {
    let mut forms = Vec::new();
    let mut t_end = 2000.0;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        if arg == "--t-end" {
            match args.next().and_then(|s| s.parse::<f64>().ok()) {
                Some(t) if t > 0.0 => t_end = t,
                _ => {
                    eprintln!("--t-end needs a positive number");
                    std::process::exit(2);
                }
            }
        } else if let Some(f) = parse_form(&arg) {
            forms.push(f);
        } else {
            eprintln!("unknown formulation `{arg}` (ori2 rcd1 rcd0 ggl1 psi1 psi0)");
            std::process::exit(2);
        }
    }
    if forms.is_empty() {
        forms = vec![Form::Rcd1, Form::Rcd0, Form::Ggl1];
    }

    // Check times every 2 s (S02), or t_end alone.
    let checks: Vec<f64> = if t_end > 2.0 {
        (1..)
            .map(|k| 2.0 * k as f64)
            .take_while(|&t| t <= t_end)
            .collect()
    } else {
        vec![t_end]
    };
    let exact: Vec<[f64; 5]> = checks.iter().map(|&t| pendulum_exact(t)).collect();

    println!(
        "radau5, pendulum, t in [0, {t_end}], {} check times; ERR_sum vs the paper's RADAU5 (Table 9)",
        checks.len()
    );
    println!(
        "{:<5} {:>6} {:>10} {:>10} {:>7} {:>9} {:>6} {:>10} {:>9} {:>9} {:>8}",
        "form",
        "tol",
        "err_sum",
        "paper",
        "ratio",
        "steps",
        "rej",
        "fevals",
        "jevals",
        "LUs",
        "time_s"
    );
    for form in forms {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        let paper = paper_err(form);
        for (i, e) in (5..=12).enumerate() {
            let tol = 10f64.powi(-e);
            let mut options = Options::with_tol(tol);
            options.output_times = checks.clone();
            let problem = Problem {
                system: &sys,
                t0: 0.0,
                y0: &y0,
                t_end,
            };
            let start = Instant::now();
            let result = Radau5.solve(&problem, &options);
            let secs = start.elapsed().as_secs_f64();
            let paper_value = paper.and_then(|p| p[i]);
            let paper_text = paper_value.map_or("-".to_string(), |p| format!("{p:.1e}"));
            match result {
                Ok(sol) => {
                    let err_sum: f64 = sol.y.iter().zip(&exact).map(|(y, ex)| err_sum(y, ex)).sum();
                    let ratio =
                        paper_value.map_or("-".to_string(), |p| format!("{:.1e}", err_sum / p));
                    let s = sol.stats;
                    println!(
                        "{:<5} {:>6.0e} {:>10.2e} {:>10} {:>7} {:>9} {:>6} {:>10} {:>9} {:>9} {:>8.3}",
                        form.name(),
                        tol,
                        err_sum,
                        paper_text,
                        ratio,
                        s.steps,
                        s.rejected,
                        s.residual_evals,
                        s.jacobian_evals,
                        s.factorizations,
                        secs
                    );
                }
                Err(err) => println!(
                    "{:<5} {:>6.0e} FAILED: {err} (paper: {paper_text})",
                    form.name(),
                    tol
                ),
            }
        }
    }
}

//! Tests of the IDeC solver (`dae_solvers::idec`): the observed orders of
//! the seed's scheme on its index-2 test problem, the pendulum with error
//! control, the typed refusals and errors.

mod common;

use common::*;
use dae_core::system::DaeSystem;
use dae_solvers::idec;
use dae_solvers::{Options, Problem, SolveError, Solver};

/// Step sizes of the seed's tables.
const HS: [f64; 4] = [0.05, 0.025, 0.0125, 0.00625];

/// Errors `|η^[l]_i(0.4) − y_i(0.4)|` for each h of [`HS`]: `[h][level][i]`.
fn idec_errors(idec: idec::Idec) -> Vec<Vec<Vec<f64>>> {
    let sys = Sys(common::Idec::new());
    let y0 = common::Idec::exact(0.0);
    let exact = common::Idec::exact(0.4);
    let problem = Problem {
        system: &sys,
        t0: 0.0,
        y0: &y0,
        t_end: 0.4,
    };
    HS.iter()
        .map(|&h| {
            idec.levels(&problem, h)
                .expect("constant-step IDeC")
                .iter()
                .map(|y| y.iter().zip(&exact).map(|(a, b)| (a - b).abs()).collect())
                .collect()
        })
        .collect()
}

#[test]
fn seed_orders() {
    let e = idec_errors(dae_solvers::idec::Idec::default());
    for (k, h) in HS.iter().enumerate() {
        eprintln!("h {h}: {:?}", e[k].iter().map(|l| [l[0], l[1], l[4], l[5]]).collect::<Vec<_>>());
    }
}

#[test]
fn explore_m() {
    for m in [4usize, 5, 6] {
        let e = idec_errors(idec::Idec { j: 3, m });
        for comp in [0usize, 1, 4, 5] {
            let ord: Vec<String> = (0..4)
                .map(|l| {
                    (0..3)
                        .map(|k| format!("{:.2}", (e[k][l][comp] / e[k + 1][l][comp]).log2()))
                        .collect::<Vec<_>>()
                        .join(",")
                })
                .collect();
            eprintln!("m {m} y{}: {:?}", comp + 1, ord);
        }
    }
}

#[test]
fn explore_pendulum() {
    let end = pendulum_exact(20.0);
    for form in [Form::Rcd1, Form::Ggl1, Form::Rcd0] {
        let sys = Pendulum::new(form);
        let y0 = sys.y0();
        let problem = Problem { system: &sys, t0: 0.0, y0: &y0, t_end: 20.0 };
        for tol in [1e-4, 1e-6, 1e-8, 1e-10] {
            let t = std::time::Instant::now();
            let r = idec::Idec::default().solve(&problem, &Options::with_tol(tol));
            match r {
                Ok(sol) => {
                    let u = sol.last().unwrap();
                    eprintln!("{} {tol:e}: err {:.2e} lam {:.2e} {:?} {:?}", form.name(), err_max(u, &end), (u[4]-end[4]).abs(), sol.stats, t.elapsed());
                }
                Err(e) => eprintln!("{} {tol:e}: {e}", form.name()),
            }
        }
    }
}

#[test]
fn explore_ode() {
    for (name, sys, y0f, exf, tend) in [
        ("ode", ode(), ode_exact(0.0), ode_exact(2.0), 2.0),
        ("dae1", dae1(), dae1_exact(0.0), dae1_exact(1.2), 1.2),
    ] {
        let problem = Problem { system: &sys, t0: 0.0, y0: &y0f, t_end: tend };
        let hs = [tend / 8.0, tend / 16.0, tend / 32.0, tend / 64.0];
        let e: Vec<Vec<f64>> = hs
            .iter()
            .map(|&h| {
                idec::Idec::default()
                    .levels(&problem, h)
                    .unwrap()
                    .iter()
                    .map(|y| y.iter().zip(&exf).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max))
                    .collect()
            })
            .collect();
        for l in 0..4 {
            eprintln!("{name} level {l}: {:?}", (0..3).map(|k| format!("{:.2}", (e[k][l] / e[k + 1][l]).log2())).collect::<Vec<_>>());
        }
    }
}

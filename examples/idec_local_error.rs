//! The local error of one error-controlled idec interval on the pendulum
//! (rcd0, S01's constants), against what its error estimate measures.
//!
//! From a point `y*` of the exact solution (radau5 at tol 1e-13 to
//! `t* = T_STAR`), one interval of `m = 4` Euler steps of size `H/4` is
//! taken by `idec` with `J = 3` corrections (the accepted value `η^[3]`)
//! and with `J = 2` (`η^[2]`: the levels do not depend on later
//! corrections, so this is the same interval's `η^[2]`), the tolerance so
//! loose that the interval is accepted as it is. The exact value at
//! `t* + H` is radau5's at tol 1e-13. Printed per `H`: the largest
//! component error of `η^[2]` and of `η^[3]`, and of the estimate
//! `η^[3] − η^[2]` idec's controller uses.
//!
//! ```text
//! cargo run --release --example idec_local_error
//! ```
use dae::dae_solvers::idec::Idec;
use dae::dae_solvers::radau5::Radau5;
use dae::dae_solvers::{init, Options, Problem, Solver};
use dae::models::builtin::Pendulum;
use dae::prelude::*;

/// Where the interval starts.
const T_STAR: f64 = 1.3;

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn main() {
    let model = Pendulum {
        g: 13.750_371_637_329_454,
        ..Pendulum::default()
    };
    let sys = Model::formulation(&model, "rcd0").expect("rcd0");
    let n = sys.info().unknowns();
    let mut y0 = vec![0.0; n];
    y0[0] = 1.0;
    let start = init::consistent(&*sys, 0.0, &y0, &Default::default()).expect("start");
    let exact = |t0: f64, y: &[f64], t1: f64| -> Vec<f64> {
        let problem = Problem {
            system: &*sys,
            t0,
            y0: y,
            t_end: t1,
        };
        let sol = Radau5
            .solve(&problem, &Options::with_tol(1e-13))
            .expect("radau5");
        sol.last().expect("last").to_vec()
    };
    let y_star = exact(0.0, &start.y, T_STAR);
    println!(
        "H          err eta2   err eta3   estimate   eta3/est   (max over x, y, v, w, lambda)"
    );
    for k in 0..7 {
        let big_h = 0.2 / 2f64.powi(k);
        let reference = exact(T_STAR, &y_star, T_STAR + big_h);
        let level = |j: usize| -> Vec<f64> {
            let problem = Problem {
                system: &*sys,
                t0: T_STAR,
                y0: &y_star,
                t_end: T_STAR + big_h,
            };
            let options = Options {
                h0: Some(big_h / 4.0),
                ..Options::with_tol(0.9)
            };
            let sol = Idec { j, m: 4 }.solve(&problem, &options).expect("idec");
            assert_eq!(sol.stats.steps, 4, "one interval");
            sol.last().expect("last").to_vec()
        };
        let (eta2, eta3) = (level(2), level(3));
        let (e2, e3) = (max_diff(&eta2, &reference), max_diff(&eta3, &reference));
        let est = max_diff(&eta3, &eta2);
        println!(
            "{big_h:.3e}  {e2:.3e}  {e3:.3e}  {est:.3e}  {:.3}",
            e3 / est
        );
    }
}

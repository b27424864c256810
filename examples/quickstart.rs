//! The README example: write a model, get its formulations at compile
//! time, integrate one with Radau IIA.
use dae::dae_solvers::{init, radau5::Radau5};
use dae::prelude::*;

dae! {
    /// A point mass on a rod of length l.
    pub Pendulum {
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
        formulations { ggl1 }
    }
}

fn main() -> Result<(), SolveError> {
    let sys = Pendulum {
        g: 13.75,
        ..Pendulum::default()
    }
    .ggl1();
    println!(
        "{}: d-index {:?}, rows {:?}",
        sys.info().name,
        sys.info().d_index,
        sys.info().rows[0].text
    );
    let start = init::consistent(
        &sys,
        0.0,
        &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        &Default::default(),
    )?;
    let problem = Problem {
        system: &sys,
        t0: 0.0,
        y0: &start.y,
        t_end: 10.0,
    };
    let solution = Radau5.solve(&problem, &Options::with_tol(1e-10))?;
    if let Some(&[x, y, v, w, ..]) = solution.last() {
        println!("at t = 10: x = {x:.10}, y = {y:.10}, v = {v:.10}, w = {w:.10}");
    }
    println!("{} steps", solution.stats.steps);
    Ok(())
}

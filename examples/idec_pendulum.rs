//! IDeC on the pendulum with constant steps, correction by correction:
//! errors of the positions and velocities (max of |x|, |y|, |v|, |w|
//! errors) and of the multiplier λ at `t_end` for the linearly implicit
//! Euler solution (LIE) and its first, second and third defect
//! corrections, m = 4, for the index-2 formulations `rcd1` and `ggl1`,
//! with the observed orders `log2(e_h / e_{h/2})` (expected 1, 2, 3, 4).
//!
//! The scheme is the seed's constant-step scheme with the global
//! connection, but with the Jacobian evaluated at every Euler step at the
//! step's own point (`Jacobian::EveryStep`; the seed's frozen Jacobian
//! goes non-finite on the pendulum at t ≈ 0.5). The horizon is t = 1, not
//! S01's t = 20: the basic solution is integrated over the whole horizon
//! without correction, and over 20 s its phase error is O(1), outside the
//! regime the corrections need.
//!
//! ```text
//! cargo run --release --example idec_pendulum          # t_end = 1
//! cargo run --release --example idec_pendulum -- 2.0   # another t_end
//! ```
use dae::dae_solvers::idec::{Idec, Jacobian};
use dae::models::builtin::Pendulum;
use dae::prelude::*;
use dae::reference::PendulumExact;

/// Euler steps (m h divides t_end = 1 for each).
const HS: [f64; 5] = [2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4];
const LEVELS: [&str; 4] = ["LIE", "1.DC", "2.DC", "3.DC"];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let t_end: f64 = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 1.0,
    };
    let exact = PendulumExact::from_start(1.0, 0.0, 1.0, 13.750371637329454, 1.0)?;
    let end = exact.state(t_end);
    let p = Pendulum::default();
    let (rcd1, ggl1) = (p.rcd1(), p.ggl1());
    let forms: [(&str, &dyn DaeSystem); 2] = [("rcd1", &rcd1), ("ggl1", &ggl1)];
    let idec = Idec { j: 3, m: 4 };
    for (name, sys) in forms {
        // ggl1 has one more unknown (its second multiplier, 0 exactly).
        let mut y0 = vec![0.0; sys.info().unknowns()];
        y0[..5].copy_from_slice(&exact.state(0.0));
        let problem = Problem {
            system: sys,
            t0: 0.0,
            y0: &y0,
            t_end,
        };
        // errors[h][level] = (max error of x, y, v, w; error of λ)
        let mut errors = Vec::new();
        for h in HS {
            let levels = idec.levels_with(&problem, h, Jacobian::EveryStep)?;
            errors.push(
                levels
                    .iter()
                    .map(|y| {
                        let xv = (0..4).map(|i| (y[i] - end[i]).abs()).fold(0.0, f64::max);
                        [xv, (y[4] - end[4]).abs()]
                    })
                    .collect::<Vec<_>>(),
            );
        }
        for (c, what) in ["x,y,v,w", "λ"].iter().enumerate() {
            println!("\n{name}, error in {what} at t = {t_end} (m = 4, J every step)");
            print!("{:>9}", "h");
            for l in LEVELS {
                print!(" {l:>9}");
            }
            println!();
            for (k, h) in HS.iter().enumerate() {
                print!("{h:>9.2e}");
                for e in &errors[k] {
                    print!(" {:>9.2e}", e[c]);
                }
                println!();
            }
            println!("observed orders");
            for k in 0..HS.len() - 1 {
                print!("{:>9}", "");
                for (coarse, fine) in errors[k].iter().zip(&errors[k + 1]) {
                    print!(" {:>9.2}", (coarse[c] / fine[c]).log2());
                }
                println!();
            }
        }
    }
    Ok(())
}

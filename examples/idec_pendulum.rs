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
//! goes non-finite on the pendulum at t ≈ 0.5). The basic solution is
//! integrated over the whole horizon without correction, so the horizon
//! sets how small `h` must be before every level is in its asymptotic
//! regime: at t = 1, h = 2e-3 … 1.25e-4 suffice; over S01's 20 s the
//! uncorrected solution's phase error is O(1) at those steps, and `--s01`
//! runs h = 2.5e-5 … 1.953125e-7 instead (102 million Euler steps per
//! level at the finest; about 12 minutes in release on a shared 2-core
//! machine). The constant-step scheme sums compensated; with plain sums
//! the third correction met a round-off floor of 1e-8 … 5e-8 at t = 20
//! before it was asymptotic (docs/bench_idec.md §5).
//! The errors are against the exact solution of S01 (`PendulumExact`, the
//! reference the harness uses).
//!
//! ```text
//! cargo run --release --example idec_pendulum                 # t_end = 1
//! cargo run --release --example idec_pendulum -- 2.0          # another t_end
//! cargo run --release --example idec_pendulum -- --s01        # S01, t_end = 20
//! cargo run --release --example idec_pendulum -- --s01 --hs 1e-4,5e-5
//! cargo run --release --example idec_pendulum -- --s01 --components  # 3.DC per component
//! ```
use dae::dae_solvers::idec::{Idec, Jacobian};
use dae::models::builtin::Pendulum;
use dae::prelude::*;
use dae::reference::PendulumExact;

/// Euler steps at t_end = 1 (m h divides t_end for each).
const HS: [f64; 5] = [2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4];
/// Euler steps for `--s01` (t_end = 20; m h divides 20 for each).
const HS_S01: [f64; 8] = [
    2.5e-5,
    1.25e-5,
    6.25e-6,
    3.125e-6,
    1.5625e-6,
    7.8125e-7,
    3.90625e-7,
    1.953125e-7,
];
const LEVELS: [&str; 4] = ["LIE", "1.DC", "2.DC", "3.DC"];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let s01 = args.iter().any(|a| a == "--s01");
    let components = args.iter().any(|a| a == "--components");
    let mut hs: Vec<f64> = if s01 { HS_S01.to_vec() } else { HS.to_vec() };
    let mut t_end = if s01 { 20.0 } else { 1.0 };
    let mut rest = args
        .iter()
        .filter(|a| *a != "--s01" && *a != "--components");
    while let Some(arg) = rest.next() {
        if arg == "--hs" {
            let list = rest.next().ok_or("--hs needs a comma-separated list")?;
            hs = list.split(',').map(str::parse).collect::<Result<_, _>>()?;
        } else {
            t_end = arg.parse()?;
        }
    }
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
        // last[h][i] = error of component i (x, y, v, w, λ) after the last
        // correction.
        let mut last = Vec::new();
        for &h in &hs {
            let started = std::time::Instant::now();
            let levels = idec.levels_with(&problem, h, Jacobian::EveryStep)?;
            if let Some(best) = levels.last() {
                last.push((0..5).map(|i| (best[i] - end[i]).abs()).collect::<Vec<_>>());
            }
            errors.push(
                levels
                    .iter()
                    .map(|y| {
                        let xv = (0..4).map(|i| (y[i] - end[i]).abs()).fold(0.0, f64::max);
                        [xv, (y[4] - end[4]).abs()]
                    })
                    .collect::<Vec<_>>(),
            );
            eprintln!(
                "{name}, h = {h:.3e}: {:.1} s",
                started.elapsed().as_secs_f64()
            );
        }
        for (c, what) in ["x,y,v,w", "λ"].iter().enumerate() {
            println!("\n{name}, error in {what} at t = {t_end} (m = 4, J every step)");
            print!("{:>9}", "h");
            for l in LEVELS {
                print!(" {l:>9}");
            }
            println!();
            for (k, h) in hs.iter().enumerate() {
                print!("{h:>9.2e}");
                for e in &errors[k] {
                    print!(" {:>9.2e}", e[c]);
                }
                println!();
            }
            println!("observed orders");
            for k in 0..hs.len() - 1 {
                print!("{:>9}", "");
                for (coarse, fine) in errors[k].iter().zip(&errors[k + 1]) {
                    print!(" {:>9.2}", (coarse[c] / fine[c]).log2());
                }
                println!();
            }
        }
        if components {
            let best = LEVELS[LEVELS.len() - 1];
            println!("\n{name}, {best} error per component at t = {t_end}");
            print!("{:>9}", "h");
            for c in ["x", "y", "v", "w", "λ"] {
                print!(" {c:>9}");
            }
            println!();
            for (h, e) in hs.iter().zip(&last) {
                print!("{h:>9.2e}");
                for v in e {
                    print!(" {v:>9.2e}");
                }
                println!();
            }
            println!("observed orders");
            for pair in last.windows(2) {
                print!("{:>9}", "");
                for (coarse, fine) in pair[0].iter().zip(&pair[1]) {
                    print!(" {:>9.2}", (coarse / fine).log2());
                }
                println!();
            }
        }
    }
    Ok(())
}

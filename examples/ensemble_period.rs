//! The pendulum's period against its release angle: an ensemble of 1 000
//! releases from rest, θ₀ = 0.01 … 3.1 rad, integrated in parallel
//! ([`dae::ensemble`]), each period measured with events (the time between
//! the first two falling crossings of x = 0, located on radau5's dense
//! output at tol 1e-10), against the exact period
//! `T(θ₀) = 4 √(l/g) K(sin(θ₀/2))` (K by the arithmetic–geometric mean).
//!
//! ```sh
//! cargo run --release --example ensemble_period -- [--members N] [--threads N] [--out DIR]
//! ```
//!
//! Writes `DIR/ensemble_period.csv` (every member: θ₀, measured and exact
//! period, relative error) and draws `DIR/ensemble_period.svg` and `.png`
//! (default `DIR`: `out/ensemble_period`):
//! T/T₀ against θ₀, the exact curve and the ensemble's points, and the
//! relative error of each period on a second panel; prints the worst
//! relative error and the wall and CPU time (BENCHMARKS.md §17).

use dae::dae_solvers::{init, radau5::Radau5, Direction, EventSpec, SolveError, StepOutcome};
use dae::ensemble::Ensemble;
use dae::prelude::*;
use dae::sweep::plot::{self, Figure, Line, Look, Marker, Markers, Panel, Series};
use plotters::style::RGBColor;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

dae! {
    /// The pendulum with the rod's crossings of the downward vertical as
    /// an event.
    pub Swing {
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
        events { cross = x; }
        formulations { ggl1 }
    }
}

/// Why a member has no period.
#[derive(Debug, thiserror::Error)]
enum PeriodError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error("fewer than two falling crossings of x = 0 before t = {t_end}")]
    NoCrossing { t_end: f64 },
}

/// A member's outcome: the measured period and the steps it took.
struct Measured {
    period: f64,
    steps: usize,
}

/// `K(k) = π / (2 M(1, √(1 − k²)))`, the complete elliptic integral of the
/// first kind, by the arithmetic–geometric mean (quadratic convergence:
/// five or six iterations reach round-off for k < 0.9998).
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    // A bound on the iterations, not a tolerance below ε that could cycle.
    for _ in 0..32 {
        if (a - b).abs() <= 4.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (a + b)
}

/// The exact period of the release from rest at `theta0`.
fn exact_period(model: &Swing, theta0: f64) -> f64 {
    4.0 * (model.l / model.g).sqrt() * elliptic_k((0.5 * theta0).sin())
}

/// The period measured by the events: released from rest at `theta0`
/// (x = l sin θ₀, y = −l cos θ₀), the first two falling crossings of x = 0
/// are at T/4 and 5T/4.
fn measured_period(model: &Swing, theta0: f64) -> Result<Measured, PeriodError> {
    let sys = model.ggl1();
    let y0 = [
        model.l * theta0.sin(),
        -model.l * theta0.cos(),
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let start = init::consistent(&sys, 0.0, &y0, &Default::default())?;
    // 5T/4 is below 8.5 s for every θ₀ ≤ 3.1 at g = 9.81, l = 1.
    let t_end = 20.0;
    let problem = Problem {
        system: &sys,
        t0: 0.0,
        y0: &start.y,
        t_end,
    };
    let options = Options {
        events: vec![EventSpec::record("cross").direction(Direction::Falling)],
        dense_output: false,
        ..Options::with_tol(1e-10)
    };
    let mut stepper = Radau5.integrator(&problem, &options)?;
    while stepper.events().len() < 2 {
        if let StepOutcome::Finished { .. } = stepper.step()? {
            return Err(PeriodError::NoCrossing { t_end });
        }
    }
    let e = stepper.events();
    Ok(Measured {
        period: e[1].t - e[0].t,
        steps: stepper.stats().steps,
    })
}

struct Args {
    members: usize,
    threads: Option<usize>,
    out: std::path::PathBuf,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        members: 1000,
        threads: None,
        out: "out/ensemble_period".into(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let count = || {
            value
                .parse::<usize>()
                .map_err(|e| format!("{flag} {value}: {e}"))
        };
        match flag.as_str() {
            "--members" if count()? >= 2 => a.members = count()?,
            "--members" => return Err("--members: at least 2".into()),
            "--threads" => a.threads = Some(count()?),
            "--out" => a.out = value.into(),
            _ => {
                return Err(format!(
                    "unknown argument {flag} (--members N, --threads N, --out DIR)"
                ))
            }
        }
    }
    Ok(a)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = args()?;
    let model = Swing::default();
    let n = args.members;
    let theta: Vec<f64> = (0..n)
        .map(|k| 0.01 + (3.1 - 0.01) * k as f64 / (n - 1) as f64)
        .collect();

    let mut ensemble = Ensemble::new().progress("periods");
    if let Some(threads) = args.threads {
        ensemble = ensemble.threads(threads);
    }
    // Members per worker thread: the evidence of the parallel run that
    // does not depend on the machine's load (a count, not a time).
    let workers = args.threads.unwrap_or_else(rayon::current_num_threads);
    let per_thread: Vec<AtomicUsize> = (0..workers).map(|_| AtomicUsize::new(0)).collect();
    let wall = Instant::now();
    let cpu = cpu_time::ProcessTime::try_now().ok();
    let results = ensemble.run(&theta, |&t| {
        if let Some(slot) = rayon::current_thread_index().and_then(|i| per_thread.get(i)) {
            slot.fetch_add(1, Ordering::Relaxed);
        }
        measured_period(&model, t)
    })?;
    let wall_s = wall.elapsed().as_secs_f64();
    let cpu_s = cpu.map(|c| c.elapsed().as_secs_f64());

    // The exact period at θ₀ → 0: the small-oscillation period T₀.
    let t0 = 2.0 * std::f64::consts::PI * (model.l / model.g).sqrt();
    let mut points = Vec::new();
    let mut errors = Vec::new();
    let mut worst = (0.0f64, f64::NAN);
    let mut steps = 0;
    // The table: every member, `theta0,period,exact,relative_error`
    // (empty period and error for a failed member, its error on stderr).
    let mut table = String::from("theta0,period,exact,relative_error\n");
    for (k, r) in results.iter().enumerate() {
        let exact = exact_period(&model, theta[k]);
        match r {
            Ok(m) => {
                table.push_str(&format!(
                    "{},{},{exact},{:e}\n",
                    theta[k],
                    m.period,
                    (m.period - exact).abs() / exact
                ));
                let rel = (m.period - exact).abs() / exact;
                if rel >= worst.0 {
                    worst = (rel, theta[k]);
                }
                steps += m.steps;
                points.push((theta[k], m.period / t0));
                // An exact period on the log axis: drawn at its floor.
                errors.push((theta[k], rel.max(1e-17)));
            }
            Err(e) => {
                table.push_str(&format!("{},,{exact},\n", theta[k]));
                eprintln!("{e}");
            }
        }
    }
    let failed = n - points.len();
    let threads = args.threads.map_or_else(
        || format!("{} (one per core)", rayon::current_num_threads()),
        |t| t.to_string(),
    );
    println!("members:   {n} release angles, θ₀ = 0.01 … 3.1 rad ({failed} failed)");
    let shares: Vec<String> = per_thread
        .iter()
        .map(|c| c.load(Ordering::Relaxed).to_string())
        .collect();
    println!(
        "threads:   {threads}, members per thread {}",
        shares.join(" + ")
    );
    println!(
        "worst relative period error: {:.2e} (at θ₀ = {:.4})",
        worst.0, worst.1
    );
    println!("steps:     {steps} in all (radau5, ggl1, tol 1e-10)");
    match cpu_s {
        Some(c) => println!("time:      wall {wall_s:.2} s, CPU {c:.2} s"),
        None => println!("time:      wall {wall_s:.2} s (CPU time unavailable)"),
    }
    // The spread, ten rows of the table.
    println!("     θ₀      T/T₀ measured   T/T₀ exact      rel. error");
    for (k, r) in results.iter().enumerate().step_by(n.div_ceil(10)) {
        let exact = exact_period(&model, theta[k]);
        match r {
            Ok(m) => println!(
                "{:>8.4}  {:>14.10}  {:>14.10}  {:>10.2e}",
                theta[k],
                m.period / t0,
                exact / t0,
                (m.period - exact).abs() / exact
            ),
            Err(e) => println!("{:>8.4}  {e}", theta[k]),
        }
    }

    let fine = 2000;
    let exact: Vec<(f64, f64)> = (0..=fine)
        .map(|k| {
            let t = 3.1 * k as f64 / fine as f64;
            (t, exact_period(&model, t) / t0)
        })
        .collect();
    let line = Look {
        color: RGBColor(90, 90, 90),
        line: Line::Solid,
        marker: Marker::None,
        hollow: false,
        marker_color: RGBColor(90, 90, 90),
        width: 2,
    };
    let dots = Look {
        color: plot::solver_color("radau5"),
        line: Line::Hidden,
        marker: Marker::Circle,
        hollow: false,
        marker_color: plot::solver_color("radau5"),
        width: 1,
    };
    let ensemble_label = format!("radau5(ggl1), {} members", points.len());
    let figure = Figure {
        file: "ensemble_period".into(),
        title: "The pendulum's period against its release angle".into(),
        caption: format!(
            "T/T₀ (T₀ = 2π√(l/g)) of {n} releases from rest, each period the time between two \
             falling crossings of x = 0 located by the events (radau5, ggl1, tol 1e-10), against \
             the exact 4√(l/g) K(sin(θ₀/2)); worst relative error {:.1e}",
            worst.0
        ),
        panels: vec![
            Panel {
                title: "period T/T₀".into(),
                x_label: "release angle θ₀ [rad]".into(),
                y_label: "T / T₀".into(),
                x_log: false,
                y_log: false,
                markers: Markers::Every,
                drop_zeros: false,
                // The exact curve drawn over the points.
                series: vec![
                    Series {
                        label: ensemble_label.clone(),
                        look: dots,
                        points,
                        labels: vec![],
                    },
                    Series {
                        label: "exact: 4√(l/g) K(sin(θ₀/2))".into(),
                        look: line,
                        points: exact,
                        labels: vec![],
                    },
                ],
            },
            Panel {
                title: "relative error of the measured period".into(),
                x_label: "release angle θ₀ [rad]".into(),
                y_label: "|T − T_exact| / T_exact".into(),
                x_log: false,
                y_log: true,
                markers: Markers::Every,
                drop_zeros: false,
                series: vec![Series {
                    label: ensemble_label.clone(),
                    look: dots,
                    points: errors,
                    labels: vec![],
                }],
            },
        ],
        cols: 2,
        size: (1500, 650),
        legend: vec![
            ("exact: 4√(l/g) K(sin(θ₀/2))".into(), line, false),
            (format!("radau5(ggl1), {} members", n - failed), dots, true),
        ],
    };
    std::fs::create_dir_all(&args.out)?;
    let csv = args.out.join("ensemble_period.csv");
    std::fs::write(&csv, table)?;
    println!("wrote {}", csv.display());
    for path in plot::render(&figure, &args.out)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

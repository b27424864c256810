//! The set-up cost of a model read at run time, part by part: derivation,
//! then lowering each formulation to tapes on its own (what loading a model
//! cost before `compile_all`), then all formulations at once with
//! [`compile_all`] (what `dae run` and `dae sweep` pay now).
//!
//! ```sh
//! scripts/fekete.py 20 /tmp/fekete20
//! cargo run --release -p dae-core --example setup_cost -- /tmp/fekete20.dae
//! ```
//!
//! Times are the process's CPU time (user + system, from `/proc/self/stat`,
//! so Linux only, 10 ms resolution): on a shared machine wall time measures
//! the other jobs as well.

use dae_core::compile::{compile, compile_all};
use dae_core::derive::Derived;

/// CPU time of this process so far, in seconds.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat (Linux)");
    // Fields after the command name in parentheses: utime and stime are the
    // 12th and 13th, in clock ticks of 1/100 s.
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or_default()
        .split_whitespace()
        .collect();
    let ticks = |k: usize| {
        fields
            .get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: setup_cost MODEL.dae");
        std::process::exit(2);
    };
    let src = match std::fs::read_to_string(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    let t = cpu_seconds();
    let d = match Derived::from_str(&src) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    println!("derive: {:.2} s", cpu_seconds() - t);
    let mut each = 0.0;
    for f in &d.formulations {
        let t = cpu_seconds();
        let c = compile(&d, f);
        let dt = cpu_seconds() - t;
        each += dt;
        println!(
            "compile {}: {dt:.2} s ({} entries of ∂f/∂y, {} of ∂g/∂y)",
            f.name,
            c.rhs_jacobian.entries.len(),
            c.constraints_jacobian.entries.len()
        );
    }
    println!("compile, each on its own: {each:.2} s");
    let t = cpu_seconds();
    let all = compile_all(&d);
    println!(
        "compile_all ({} formulations): {:.2} s",
        all.len(),
        cpu_seconds() - t
    );
}

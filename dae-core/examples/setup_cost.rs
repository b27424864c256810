//! The set-up cost of a model read at run time, part by part: derivation,
//! then lowering each formulation to tapes on its own (what loading a model
//! cost before `compile_all`), then all formulations at once with
//! [`compile_all`] (what `dae sweep` pays for a model it runs in all its
//! formulations). With a formulation's name after the model, only that
//! formulation is lowered, as `dae run` lowers the one it runs: derivation
//! and lowering are then the set-up of a run but for the solver's own
//! (the consistent initial values, the sparsity pattern), and a count of
//! instructions under callgrind measures them without the noise of a
//! shared machine.
//!
//! ```sh
//! scripts/fekete.py 20 /tmp/fekete20
//! cargo run --release -p dae-core --example setup_cost -- /tmp/fekete20.dae
//! cargo build --release -p dae-core --example setup_cost
//! valgrind --tool=callgrind target/release/examples/setup_cost /tmp/fekete20.dae ggl1
//! ```
//!
//! Times are the process's CPU time (user + system, from `/proc/self/stat`,
//! so Linux only, 10 ms resolution): on a shared machine wall time measures
//! the other jobs as well.

use dae_core::compile::{compile, compile_all, compile_selected};
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
        eprintln!("usage: setup_cost MODEL.dae [FORMULATION]");
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
    if let Some(name) = std::env::args().nth(2) {
        let Some(k) = d.formulations.iter().position(|f| f.name == name) else {
            eprintln!("{path}: no formulation {name}");
            std::process::exit(2);
        };
        let t = cpu_seconds();
        let c = compile_selected(&d, &[k]).remove(0);
        println!(
            "compile {name}: {:.2} s ({} entries of ∂f/∂y, {} of ∂g/∂y, {} + {} tape nodes)",
            cpu_seconds() - t,
            c.rhs_jacobian.entries.len(),
            c.constraints_jacobian.entries.len(),
            c.rhs_jacobian.tape.nodes.len(),
            c.constraints_jacobian.tape.nodes.len()
        );
        return;
    }
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

//! What `dae derive` costs before any output format: read a model file,
//! derive it ([`Derived::from_str`]) and render the text report — the
//! harness of the derive-cost figures in EXTREMES.md ("Bounded
//! derivation"), counted by callgrind rather than timed:
//!
//! ```sh
//! python3 scripts/chain.py 60 /tmp/chain60
//! cargo build --profile test -p dae-core --example derive_cost
//! valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.out \
//!     target/debug/examples/derive_cost /tmp/chain60.dae
//! ```

use dae_core::derive::{render_error, Derived};
use dae_core::report;

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: derive_cost MODEL.dae");
        std::process::exit(2);
    };
    let src = match std::fs::read_to_string(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    match Derived::from_str(&src) {
        Ok(d) => println!("{} bytes of report", report::text(&d).len()),
        Err(e) => {
            eprintln!("{}", render_error(&e, &path));
            std::process::exit(1);
        }
    }
}

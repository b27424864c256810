//! Expansion benchmark: how long `dae!` takes and how much code it emits.
//!
//! Runs the macro's own expansion function (the same source files,
//! compiled here as plain modules) on
//!
//! * the built-in pendulum with one formulation and with all eight, and
//! * a chain of N planar pendulums (N = 1, 2, 4, 8, 16), all formulations
//!   that apply and `rcd1` alone,
//!
//! and reports the time of the front half (parse, check, index analysis,
//! formulations: `Derived`), of the lowering to tapes (`compile`), of the
//! whole expansion, and the size of the generated code (token trees, bytes
//! of the printed token stream, and bytes and lines after `rustfmt` when it
//! is on the PATH).
//!
//! ```text
//! cargo run --release -p dae-macros --example expansion
//! cargo run --release -p dae-macros --example expansion -- --dump pendulum|N|FILE.dae
//! cargo run --release -p dae-macros --example expansion -- --chain 100 "rcd0, ggl1"
//! ```
//!
//! `--chain N LIST` measures one chain of `N` links with the formulations of
//! `LIST` (the large models of issue 24; `--dump-chain N LIST` prints its
//! model text, to paste into a crate's `dae!` and time `cargo build`).

#[path = "../src/codegen.rs"]
mod codegen;
#[path = "../src/expand.rs"]
mod expand;

use dae_core::compile::compile;
use dae_core::derive::Derived;
use proc_macro2::TokenStream;
use std::io::Write;
use std::process::{Command, Stdio};
use std::str::FromStr;
use std::time::Instant;

const PENDULUM: &str = include_str!("../../scenes/pendulum.dae");
const ALL: &str = "ori2, rcd1, rcd0, ovd1, ovd0, ggl1, psi1, psi0";

/// A chain of `n` point masses joined by rods of length `l`, the first
/// hinged at the origin: positions `x_k, y_k`, velocities `u_k, w_k`,
/// multipliers `lam_k`, constraints
/// `(x_k − x_{k−1})² + (y_k − y_{k−1})² − l² = 0` with `x_0 = y_0 = 0`.
fn chain(n: usize, formulations: Option<&str>) -> String {
    let d = |c: &str, k: usize| {
        if k == 1 {
            format!("{c}1")
        } else {
            format!("({c}{k} - {c}{})", k - 1)
        }
    };
    let mut s = format!("/// A chain of {n} planar pendulums.\npub Chain{n} {{\n    parameters {{ m = 1.0, l = 1.0, g = 9.81 }}\n");
    let list = |f: &dyn Fn(usize) -> String| (1..=n).map(f).collect::<Vec<_>>().join(", ");
    s += &format!(
        "    differential {{ {}, {}, {}, {} }}\n",
        list(&|k| format!("x{k}")),
        list(&|k| format!("y{k}")),
        list(&|k| format!("u{k}")),
        list(&|k| format!("w{k}"))
    );
    s += &format!(
        "    algebraic {{ {} }}\n    equations {{\n",
        list(&|k| format!("lam{k}"))
    );
    for k in 1..=n {
        s += &format!("        der(x{k}) = u{k};\n        der(y{k}) = w{k};\n");
    }
    for k in 1..=n {
        for c in ["x", "y"] {
            let v = if c == "x" { "u" } else { "w" };
            let mut rhs = format!("-2 * {} * lam{k}", d(c, k));
            if k < n {
                rhs += &format!(" + 2 * {} * lam{}", d(c, k + 1), k + 1);
            }
            if c == "y" {
                rhs += " - m * g";
            }
            s += &format!("        m * der({v}{k}) = {rhs};\n");
        }
    }
    for k in 1..=n {
        s += &format!("        0 = {}^2 + {}^2 - l^2;\n", d("x", k), d("y", k));
    }
    s += "    }\n    invariants { energy = m * (";
    s += &list(&|k| format!("u{k}^2 + w{k}^2")).replace(", ", " + ");
    s += ") / 2 + m * g * (";
    s += &list(&|k| format!("y{k}")).replace(", ", " + ");
    s += "); }\n";
    if let Some(f) = formulations {
        s += &format!("    formulations {{ {f} }}\n");
    }
    s += "}\n";
    s
}

struct Row {
    case: String,
    formulations: usize,
    derive_ms: f64,
    compile_ms: f64,
    expand_ms: f64,
    tokens: usize,
    bytes: usize,
    pretty: Option<(usize, usize)>,
}

/// Best of `reps` runs of `f`, in milliseconds.
fn best<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..reps {
        let start = Instant::now();
        let out = f();
        best = best.min(start.elapsed().as_secs_f64() * 1e3);
        last = Some(out);
    }
    (best, last.expect("reps > 0"))
}

fn rustfmt(code: &str) -> Option<String> {
    let mut child = Command::new("rustfmt")
        .args(["--edition", "2021", "--emit", "stdout", "--quiet"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    child.stdin.take()?.write_all(code.as_bytes()).ok()?;
    let out = child.wait_with_output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

fn measure(case: &str, text: &str) -> Row {
    let reps = 3;
    let tokens = || TokenStream::from_str(text).expect("model text lexes");
    let (derive_ms, derived) = best(reps, || {
        Derived::from_tokens(tokens()).expect("model derives")
    });
    let (compile_ms, _) = best(reps, || {
        derived
            .formulations
            .iter()
            .map(|f| compile(&derived, f))
            .collect::<Vec<_>>()
    });
    let (expand_ms, out) = best(reps, || expand::expand(tokens()));
    let printed = out.to_string();
    assert!(!printed.contains("compile_error"), "{case}: {printed}");
    assert_eq!(
        printed,
        expand::expand(tokens()).to_string(),
        "{case}: expansion is not deterministic"
    );
    let pretty = rustfmt(&printed).map(|p| (p.len(), p.lines().count()));
    Row {
        case: case.to_string(),
        formulations: derived.formulations.len(),
        derive_ms,
        compile_ms,
        expand_ms,
        tokens: expand::count_tokens(&out),
        bytes: printed.len(),
        pretty,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [flag, what] = args.as_slice() {
        if flag == "--dump" {
            let text = match what.as_str() {
                "pendulum" => PENDULUM.to_string(),
                path if path.ends_with(".dae") => {
                    std::fs::read_to_string(path).expect("readable model file")
                }
                n => chain(n.parse().expect("--dump pendulum | N | FILE.dae"), None),
            };
            let out = expand::expand(TokenStream::from_str(&text).expect("lexes")).to_string();
            println!("{}", rustfmt(&out).unwrap_or(out));
            return;
        }
    }

    if let [flag, n, list] = args.as_slice() {
        let n: usize = n.parse().expect("--chain N \"f1, f2\"");
        let text = chain(n, Some(list));
        match flag.as_str() {
            "--chain" => {
                print_header();
                print_row(&measure(&format!("chain N={n}, {list}"), &text));
            }
            "--dump-chain" => println!("{text}"),
            _ => panic!("unknown option {flag}"),
        }
        return;
    }

    let mut cases: Vec<(String, String)> = vec![
        ("pendulum, rcd1".into(), PENDULUM.replace(ALL, "rcd1")),
        ("pendulum, all 8".into(), PENDULUM.to_string()),
    ];
    for n in [1, 2, 4, 8, 16] {
        cases.push((format!("chain N={n}, rcd1"), chain(n, Some("rcd1"))));
        cases.push((format!("chain N={n}, all that apply"), chain(n, None)));
    }
    print_header();
    for (case, text) in &cases {
        print_row(&measure(case, text));
    }

    println!();
    println!("Per formulation (one listed at a time):");
    println!();
    print_header();
    for n in [1, 4, 8] {
        for f in ALL.split(", ") {
            let text = chain(n, Some(f));
            if Derived::from_tokens(TokenStream::from_str(&text).expect("lexes")).is_ok() {
                print_row(&measure(&format!("chain N={n}, {f}"), &text));
            } else {
                println!("| chain N={n}, {f} | does not apply | | | | | | | | |");
            }
        }
    }
}

fn print_header() {
    println!(
        "| case | formulations | derive ms | compile ms | expand ms | emit ms | tokens | bytes | rustfmt bytes | rustfmt lines |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
}

fn print_row(r: &Row) {
    let (pb, pl) = r
        .pretty
        .map_or(("–".to_string(), "–".to_string()), |(b, l)| {
            (b.to_string(), l.to_string())
        });
    println!(
        "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} |",
        r.case,
        r.formulations,
        r.derive_ms,
        r.compile_ms,
        r.expand_ms,
        (r.expand_ms - r.derive_ms - r.compile_ms).max(0.0),
        r.tokens,
        r.bytes,
        pb,
        pl
    );
}

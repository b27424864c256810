//! Bodies of the fuzz targets, one per front door of `dae`.
//!
//! Each takes arbitrary bytes and drives one entry point as far as the input
//! lets it, asserting what must hold for every input: no panic, no abort, a
//! bounded running time (libFuzzer's `-timeout`), and an oracle where one
//! exists (the `dae!` expansion must be valid Rust syntax whatever it was
//! given). The bodies live in a library so that the seed corpus can also be
//! replayed by `cargo test` in this crate without libFuzzer.

use dae::scene::{ModelSource, Scene};
use dae_core::derive::{render_error, Derived};
use dae_core::interp::InterpretedModel;
use dae_core::report;
use dae_core::system::{DaeSystem, Model};
use proc_macro2::TokenStream;
use std::str::FromStr;

// The expansion of `dae!` is compiled here from the proc-macro crate's own
// sources: a proc-macro crate cannot be linked as a library, and the fuzz
// target must exercise exactly the code rustc runs.
#[allow(dead_code)]
#[path = "../../dae-macros/src/codegen.rs"]
mod codegen;
#[allow(dead_code)]
#[path = "../../dae-macros/src/expand.rs"]
mod expand;

/// Inputs longer than this are skipped (256 KiB, the `-max_len` of the
/// derive target's long runs): derivation is bounded in time and memory
/// for any model text (issue 27), so the targets take inputs well above
/// the 16 KiB they were once limited to.
const MAX_LEN: usize = 256 * 1024;

/// The stack of the threads the model text is derived on: the default of
/// a spawned thread (2 MiB), as in `dae sweep --jobs N`'s rayon workers,
/// where the model is loaded and derived — a quarter of the main thread's.
const WORKER_STACK: usize = 2 * 1024 * 1024;

fn text(data: &[u8]) -> Option<&str> {
    if data.len() > MAX_LEN {
        return None;
    }
    std::str::from_utf8(data).ok()
}

/// The `dae derive` path: parse, check and derive model text, render the
/// report in every format, then build the interpreter and evaluate every
/// formulation and its Jacobians at one point — on a thread with a sweep
/// worker's stack ([`WORKER_STACK`]), so that a recursion too deep for a
/// worker (issue 27, defect 1) aborts here too.
pub fn derive(data: &[u8]) {
    let Some(src) = text(data) else { return };
    std::thread::scope(|s| {
        let worker = std::thread::Builder::new()
            .name("dae-fuzz-derive".into())
            .stack_size(WORKER_STACK)
            .spawn_scoped(s, || derive_here(src))
            .expect("the fuzz harness could not start a thread");
        // A panic on the thread is a finding (libfuzzer-sys's hook aborts
        // already; without libFuzzer it is re-raised here).
        if let Err(payload) = worker.join() {
            std::panic::resume_unwind(payload);
        }
    });
}

fn derive_here(src: &str) {
    let d = match Derived::from_str(src) {
        Ok(d) => d,
        Err(e) => {
            let msg = render_error(&e, "fuzz.dae");
            assert!(!msg.is_empty(), "an error must say something");
            return;
        }
    };
    let _ = report::text(&d);
    let _ = report::latex(&d);
    let _ = report::Report::new(&d).to_json();
    let model = InterpretedModel::new(&d);
    let names: Vec<String> = model
        .model_info()
        .formulations
        .iter()
        .map(|f| f.to_string())
        .collect();
    for name in names {
        let Ok(sys) = model.formulation(&name) else {
            continue;
        };
        evaluate(&*sys);
    }
}

/// Every function of a formulation at one point (values chosen away from
/// the obvious singularities 0 and 1).
fn evaluate(sys: &dyn DaeSystem) {
    let info = sys.info();
    let (m, n) = (info.equations(), info.unknowns());
    let y: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
    let yp: Vec<f64> = (0..n).map(|i| -0.2 + 0.05 * i as f64).collect();
    let t = 0.7;
    let mut r = vec![0.0; m];
    sys.rhs(t, &y, &mut r);
    sys.residual(t, &y, &yp, &mut r);
    let mut a = dae::__private::DMatrix::zeros(m, n);
    sys.leading(t, &y, &mut a);
    sys.rhs_jacobian(t, &y, &mut a);
    sys.leading_jacobian(t, &y, &yp, &mut a);
    let nc = info.constraints.len();
    let mut c = vec![0.0; nc];
    sys.constraints(t, &y, &mut c);
    let mut cj = dae::__private::DMatrix::zeros(nc, n);
    sys.constraints_jacobian(t, &y, &mut cj);
    let mut inv = vec![0.0; info.invariants.len()];
    sys.invariants(t, &y, &mut inv);
}

/// The scene loader: parse a scene; for a built-in model, go on to what
/// `dae run` does before integrating (names, parameters, the reference),
/// then a small sweep of the scene with two worker threads
/// ([`small_sweep`]). Scenes naming a model file are not followed: the path
/// comes from the input and could name anything on the machine.
pub fn scene(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let scene = match Scene::parse(src, "fuzz.toml", None) {
        Ok(s) => s,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    if !matches!(scene.model, ModelSource::Builtin(_)) {
        return;
    }
    if let Err(e) = dae::inputs::inputs(&scene) {
        assert!(!e.to_string().is_empty());
        return;
    }
    small_sweep(&scene);
}

/// A small, bounded sweep of a scene: `dae sweep --jobs 2` on at most
/// two of its solvers, two of its formulations and two of its tolerances
/// (the scene's defaults when it names none), each run stopped after
/// [`SWEEP_STEPS`] steps, one timing round, no figures. What it reaches
/// that the loader does not: the pairs and the refusals of the grid, the
/// model loaded and prepared on rayon worker threads, the records of runs
/// that fail or stop at the step limit, the reference at the check times.
pub fn small_sweep(scene: &Scene) {
    let first_two = |v: &[String]| v.iter().take(2).cloned().collect::<Vec<_>>();
    let mut opts = dae::sweep::SweepOptions::from_scene(scene);
    opts.solvers = first_two(&opts.solvers);
    opts.formulations = first_two(&opts.formulations);
    opts.tolerances.truncate(2);
    opts.repeats = 1;
    opts.min_timed_cpu_s = 0.0;
    opts.jobs = 2;
    opts.progress = false;
    opts.max_steps = Some(SWEEP_STEPS);
    opts.figures = false;
    match dae::sweep::run(scene, &opts) {
        Ok(report) => {
            let summary = dae::sweep::Summary::of(&report);
            let _ = dae::sweep::results_json_string(&report, &summary);
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// The step limit of each run of [`small_sweep`]: enough to pass the
/// consistent start and a few hundred steps, small enough that a sweep
/// costs milliseconds whatever horizon and tolerance the input asks for.
const SWEEP_STEPS: usize = 200;

/// The `dae!` expansion: whatever tokens it is given, it must return valid
/// Rust items (the model's items, or `compile_error!`s and stubs).
pub fn expand(data: &[u8]) {
    let Some(src) = text(data) else { return };
    // `include "path"` reads a file named by the input: not followed.
    if src.contains("include") {
        return;
    }
    let Ok(tokens) = TokenStream::from_str(src) else {
        return;
    };
    let out = expand::expand(tokens);
    if let Err(e) = syn::parse2::<syn::File>(out.clone()) {
        panic!("the expansion is not valid Rust: {e}\n{out}");
    }
}

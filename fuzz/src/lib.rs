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

/// Inputs longer than this are skipped: the targets look for wrong
/// behaviour, not for the (documented, linear) cost of huge models.
const MAX_LEN: usize = 16 * 1024;

fn text(data: &[u8]) -> Option<&str> {
    if data.len() > MAX_LEN {
        return None;
    }
    std::str::from_utf8(data).ok()
}

/// The `dae derive` path: parse, check and derive model text, render the
/// report in every format, then build the interpreter and evaluate every
/// formulation and its Jacobians at one point.
pub fn derive(data: &[u8]) {
    let Some(src) = text(data) else { return };
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

/// The scene loader: parse a scene; for the built-in model, go on to what
/// `dae run` does before integrating (names, parameters, the reference).
/// Scenes naming a model file are not followed: the path comes from the
/// input and could name anything on the machine.
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
    }
}

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

//! Compile-fail and pass tests of the `dae!` macro (trybuild): one small
//! file and its exact diagnostics per case, grouped by kind — `parse/`,
//! `structure/`, `definitions/`, `index/`, `formulation/` — plus `pass/`, which must build
//! without a warning under `#![deny(warnings)]`.
//!
//! Regenerate the `.stderr` files with `TRYBUILD=overwrite`, then read every
//! one: the message must name the problem and the caret must sit on the
//! offending token.

#[test]
fn ui() {
    let t = trybuild::TestCases::new();
    // `tests/ui/*/*.rs` would also match `pass/`: list the kinds.
    for kind in ["parse", "structure", "definitions", "index", "formulation"] {
        t.compile_fail(format!("tests/ui/{kind}/*.rs"));
    }
    t.pass("tests/ui/pass/*.rs");
}

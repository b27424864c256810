//! Deep and long expressions (issue 9, defects 2 and 3): nesting past
//! [`MAX_DEPTH`] is one error at its place, everything up to it runs in a
//! small stack (derivatives included), flat sums and products of any length
//! cost no stack, and the symbolic work grows near-linearly with nesting and
//! with the number of unknowns.

use dae_core::derive::render_error;
use dae_core::dsl::MAX_DEPTH;
use dae_core::expr;
use dae_core::interp::InterpretedModel;
use dae_core::Derived;
use proc_macro2::TokenStream;
use std::str::FromStr;

/// Stack for the runs at the limit: a quarter of the default 8 MiB main
/// thread (test builds are optimised; unoptimised builds need about 1.5 MiB
/// at the limit, see `MAX_DEPTH`).
const STACK: usize = 2 << 20;

fn model(rhs: &str) -> String {
    format!("pub C {{\n    differential {{ x }}\n    equations {{ der(x) = {rhs}; }}\n}}\n")
}

/// Run `f` on a thread with a [`STACK`]-byte stack.
fn small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(STACK)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap()
}

/// Nested forms with `n` levels, each written the way it nests.
fn nested(n: usize) -> Vec<(&'static str, String)> {
    let fs = ["sin", "cos", "tan", "exp", "ln", "sqrt"];
    vec![
        (
            "parentheses",
            format!("{}x{}", "(".repeat(n), ")".repeat(n)),
        ),
        ("minus", format!("{}x", "-".repeat(n))),
        ("sin", format!("{}x{}", "sin(".repeat(n), ")".repeat(n))),
        ("powers", vec!["x"; n + 1].join("^")),
        (
            "mixed",
            format!(
                "{}x{}",
                (0..n)
                    .map(|i| format!("{}(x*", fs[i % 6]))
                    .collect::<String>(),
                ")".repeat(n)
            ),
        ),
    ]
}

/// Derive, compile, interpret and report the model; the first error line.
fn everything(src: String) -> Result<(), String> {
    small_stack(move || {
        let d = Derived::from_str(&src).map_err(|e| render_error(&e, "m.dae"))?;
        let m = InterpretedModel::new(&d);
        let _ = dae_core::report::text(&d);
        let _ = dae_core::report::latex(&d);
        drop(m);
        Ok(())
    })
}

#[test]
fn at_the_limit_everything_runs_in_a_small_stack() {
    for (what, rhs) in nested(MAX_DEPTH) {
        if let Err(e) = everything(model(&rhs)) {
            panic!("{what} at the limit: {e}");
        }
    }
}

#[test]
fn past_the_limit_is_one_error_at_its_place() {
    let message = format!("expression nested too deep (limit {MAX_DEPTH})");
    for n in [MAX_DEPTH + 1, 10_000] {
        for (what, rhs) in nested(n) {
            let e = everything(model(&rhs)).expect_err(what);
            assert_eq!(e.lines().count(), 1, "{what}: {e}");
            assert!(e.starts_with("m.dae:3:"), "{what}: {e}");
            assert!(e.ends_with(&message), "{what}: {e}");
        }
    }
    // The column is that of the first level too many: here the opening
    // parenthesis number MAX_DEPTH + 1 (the right-hand side starts at 26).
    let e = everything(model(&nested(10_000)[0].1)).unwrap_err();
    assert_eq!(e, format!("m.dae:3:{}: error: {message}", 26 + MAX_DEPTH));
}

/// Tokens that come from rustc (the `dae!` path) skip the text scan: the
/// parser's own limit catches them.
#[test]
fn deep_tokens_are_an_error_too() {
    for (what, rhs) in nested(5_000) {
        let src = model(&rhs);
        let e = small_stack(move || {
            let tokens = TokenStream::from_str(&src).unwrap();
            Derived::from_tokens(tokens)
                .map(|_| ())
                .map_err(|e| e.to_string())
        })
        .expect_err(what);
        assert!(e.contains("expression nested too deep"), "{what}: {e}");
    }
}

#[test]
fn long_flat_sums_and_products_cost_no_stack() {
    let n = 20_000;
    let sum = vec!["x"; n].join("+");
    let product = vec!["x"; n].join("*");
    let mixed = (1..=2_000)
        .map(|k| format!("x^{k}"))
        .collect::<Vec<_>>()
        .join(" - ");
    let quotient = format!("x{}", "/x*x".repeat(n / 2));
    small_stack(move || {
        let d = Derived::from_str(&model(&sum)).unwrap();
        assert_eq!(d.model.text(&d.model.dynamics[0].rhs), format!("{n}*x"));
        let d = Derived::from_str(&model(&product)).unwrap();
        assert_eq!(d.model.text(&d.model.dynamics[0].rhs), format!("x^{n}"));
        let d = Derived::from_str(&model(&quotient)).unwrap();
        assert_eq!(d.model.text(&d.model.dynamics[0].rhs), "x");
        let d = Derived::from_str(&model(&mixed)).unwrap();
        let rhs = &d.model.dynamics[0].rhs;
        assert!(matches!(rhs, expr::Expr::Sum(s) if s.terms.len() == 2_000));
        let _ = InterpretedModel::new(&d);
    });
}

/// A constraint whose derivative has the depth of the input: a deep
/// expression differentiated along the dynamics, then its Jacobian.
#[test]
fn derivatives_of_expressions_at_the_limit_stay_in_the_stack() {
    let deep = format!(
        "{}x{}",
        "sin(".repeat(MAX_DEPTH - 2),
        ")".repeat(MAX_DEPTH - 2)
    );
    let src = format!(
        "pub D {{
    differential {{ x, y }}
    algebraic {{ z }}
    equations {{
        der(x) = z;
        der(y) = -y;
        0 = {deep} + y;
    }}
}}"
    );
    everything(src).unwrap();
}

/// Work (comparison and derivative steps, [`expr::work`]) of deriving and
/// compiling a model.
fn work_of(src: &str) -> u64 {
    let before = expr::work();
    let d = Derived::from_str(src).unwrap();
    let _ = InterpretedModel::new(&d);
    expr::work() - before
}

#[test]
fn nested_functions_cost_near_linear_work() {
    // Before the fix each level of the chain rule rebuilt and re-sorted the
    // product below it with comparisons as deep as the chain: cubic (300
    // levels took 25 s). Now it is one product per chain, with comparisons
    // that stop at the first difference in height.
    let w = |n: usize| work_of(&model(&format!("{}x{}", "sin(".repeat(n), ")".repeat(n))));
    let (w50, w200) = (w(50), w(200));
    // Four times the depth: near-linear is ~4-5x the work; the old cubic
    // growth was 64x. The bound leaves room for log factors.
    assert!(w200 < 8 * w50, "work {w50} at 50 levels, {w200} at 200");
}

#[test]
fn many_unknowns_cost_near_linear_work() {
    // Before the fix the Jacobians differentiated every row by every
    // unknown (n² derivatives, > 10 s at 2,001 unknowns).
    let chain = |n: usize| {
        let names: Vec<String> = (0..n).map(|i| format!("x{i}")).collect();
        let eqs: String = (0..n)
            .map(|i| format!("der(x{i}) = x{} - z;\n", (i + 1) % n))
            .collect();
        format!(
            "pub M {{ differential {{ {} }} algebraic {{ z }} equations {{ {eqs} 0 = x0 + x1 - 1; }} }}",
            names.join(", ")
        )
    };
    let (w250, w1000) = (work_of(&chain(250)), work_of(&chain(1000)));
    assert!(
        w1000 < 8 * w250,
        "work {w250} at 250 unknowns, {w1000} at 1000"
    );
}

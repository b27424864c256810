//! Functions of non-integer constants (issue 9, defect 1): the printer used
//! to recurse forever on a rational that is not an integer, aborting the
//! process with a stack overflow (and rustc with SIGSEGV inside `dae!`).

use dae_core::expr::{self, Expr};
use dae_core::interp::InterpretedModel;
use dae_core::Derived;

fn model(rhs: &str) -> String {
    format!("pub C {{\n    differential {{ x }}\n    equations {{ der(x) = {rhs}; }}\n}}\n")
}

#[test]
fn functions_of_rational_constants_derive_and_print() {
    for rhs in [
        "sin(0.5)",
        "sin(1/2)",
        "exp(3/2)",
        "sqrt(1/2)",
        "(3/2)^x",
        "-(3/2)^x",
        "(1/2)^(1/3) * x",
        "ln(2/3) - 1/7",
        "1/2",
        "-5/3",
        "cos(-2/3) * x",
        "tan(-2)^x",
    ] {
        let src = model(rhs);
        let d = Derived::from_str(&src).unwrap_or_else(|e| panic!("{rhs}: {e}"));
        for f in &d.formulations {
            for i in 0..f.rows.len() {
                let text = f.row_text(&d.model, i);
                assert!(text.starts_with("der(x) = "), "{rhs}: {text}");
                let _ = f.row_latex(&d.model, i);
            }
        }
        // The printed right-hand side reads back as the same expression.
        let rhs_expr = &d.model.dynamics[0].rhs;
        let text = d.model.text(rhs_expr);
        let back = d
            .model
            .parse_expr(&text)
            .unwrap_or_else(|e| panic!("{text}: {e}"));
        assert!(
            expr::sub(rhs_expr, &back).is_zero(),
            "{rhs}: `{text}` reads back differently"
        );
        let _ = InterpretedModel::new(&d);
    }
}

#[test]
fn rational_constants_print_as_fractions() {
    let d = Derived::from_str(&model("sin(1/2) + (3/2)^x")).unwrap();
    let text = d.model.text(&d.model.dynamics[0].rhs);
    assert_eq!(text, "(3/2)^(x) + sin(1/2)");
    let half = Expr::num(expr::qr(-1, 2));
    assert_eq!(d.model.text(&half), "-1/2");
    assert_eq!(
        d.model.text(&expr::func(expr::Func::Exp, &half)),
        "exp(-1/2)"
    );
}

//! Messages a newcomer met (issue 28, papercuts): a function the language
//! does not have is named as unknown whatever its arguments, with the known
//! ones listed and a hint; a `;` left out between two equations is reported
//! as a missing `;` at the end of the first, not as "exactly one `=`". The
//! binary renders these as `file:line:column`; `tests/ui/` checks the
//! macro's carets.

use dae_core::derive::render_error;
use dae_core::Derived;

fn error(src: &str) -> String {
    match Derived::from_str(src) {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => render_error(&e, "m.dae"),
    }
}

/// A two-unknown model whose equations section is `equations`.
fn model(equations: &str) -> String {
    format!(
        "pub M {{\n    parameters {{ k = 2.0 }}\n    differential {{ u, w }}\n    equations {{\n{equations}\n    }}\n}}\n"
    )
}

#[test]
fn a_function_the_language_lacks_is_unknown_whatever_its_arguments() {
    let e = error(&model(
        "        der(u) = atan2(u, w);\n        der(w) = -k * u;",
    ));
    assert_eq!(
        e,
        "m.dae:5:18: error: unknown function `atan2` (known: sin, cos, tan, exp, ln, sqrt, der); \
         there are no inverse trigonometric functions: write the model in coordinates, \
         or make the angle an unknown",
    );
    assert!(!e.contains("argument"), "{e}");
}

#[test]
fn a_mistyped_function_gets_a_did_you_mean() {
    let e = error(&model("        der(u) = sqr(w);\n        der(w) = -k * u;"));
    assert_eq!(
        e,
        "m.dae:5:18: error: unknown function `sqr` (known: sin, cos, tan, exp, ln, sqrt, der); \
         did you mean `sqrt`?"
    );
    let e = error(&model("        der(u) = w;\n        der(w) = -k * log(u);"));
    assert!(e.ends_with("; the natural logarithm is `ln`"), "{e}");
    // Nothing close: the list alone.
    let e = error(&model(
        "        der(u) = w;\n        der(w) = -k * spline(u);",
    ));
    assert!(
        e.ends_with("unknown function `spline` (known: sin, cos, tan, exp, ln, sqrt, der)"),
        "{e}"
    );
}

#[test]
fn unknown_names_inside_an_unknown_function_are_reported_too() {
    let e = error(&model(
        "        der(u) = atan2(u, q);\n        der(w) = -k * u;",
    ));
    let lines: Vec<&str> = e.lines().collect();
    assert_eq!(lines.len(), 2, "{e}");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("m.dae:5:27: error: unknown name `q`")),
        "{e}"
    );
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("m.dae:5:18: error: unknown function `atan2`")),
        "{e}"
    );
}

#[test]
fn a_known_function_with_two_arguments_still_says_so() {
    let e = error(&model(
        "        der(u) = sin(u, w);\n        der(w) = -k * u;",
    ));
    assert_eq!(e, "m.dae:5:18: error: `sin` takes one argument, found 2");
}

#[test]
fn a_semicolon_left_out_between_equations_is_named_where_it_belongs() {
    // After an identifier, before a `der(…)` equation.
    let e = error(&model("        der(u) = w\n        der(w) = -k * u;"));
    assert_eq!(
        e,
        "m.dae:5:18: error: expected `;` after `w`: the next equation begins without one"
    );
    // After a call, before a constraint `0 = …` (a model with an algebraic
    // unknown): the caret on the call's `)`.
    let src = "pub M {\n    differential { x, y }\n    algebraic { mu }\n    equations {\n        \
               der(x) = y;\n        der(y) = -x * sqrt(mu)\n        0 = x^2 + y^2 - 1;\n    }\n}\n";
    let e = error(src);
    assert_eq!(
        e,
        "m.dae:6:30: error: expected `;` after `(…)`: the next equation begins without one"
    );
    // After a number, before a coefficient times a derivative.
    let e = error(&model("        der(u) = 2\n        k * der(w) = -u;"));
    assert_eq!(
        e,
        "m.dae:5:18: error: expected `;` after `2`: the next equation begins without one"
    );
}

#[test]
fn two_equals_with_no_gap_between_operands_say_what_to_write() {
    // `… = u - w = …`: no place where a `;` is evidently missing.
    let e = error(&model(
        "        der(u) = u - w = 1;\n        der(w) = -k * u;",
    ));
    assert!(
        e.starts_with(
            "m.dae:5:24: error: a second `=` in one equation: end each equation with `;`"
        ),
        "{e}"
    );
    // No `=` at all.
    let e = error(&model("        der(u) + w;\n        der(w) = -k * u;"));
    assert!(
        e.starts_with("m.dae:5:9: error: an equation needs one `=`"),
        "{e}"
    );
}

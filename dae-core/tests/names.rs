//! Names the language must refuse (issue 9, defect 4): `t` is time, so an
//! unknown or parameter called `t` silently shadowed it; two invariants with
//! the same name were both kept.

use dae_core::derive::render_error;
use dae_core::Derived;

fn errors(src: &str) -> String {
    match Derived::from_str(src) {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => render_error(&e, "m.dae"),
    }
}

#[test]
fn time_is_not_a_name_to_declare() {
    let unknown =
        "pub M {\n    differential { x, t }\n    equations { der(x) = -x; der(t) = 1; }\n}\n";
    let e = errors(unknown);
    assert!(
        e.starts_with("m.dae:2:23: error: `t` is reserved (time)"),
        "{e}"
    );
    // One error: `der(t)` does not add a cascade.
    assert_eq!(e.lines().count(), 1, "{e}");
    let algebraic = "pub M {\n    differential { x }\n    algebraic { t }\n    equations { der(x) = t; 0 = t - x; }\n}\n";
    let e = errors(algebraic);
    assert!(
        e.starts_with("m.dae:3:17: error: `t` is reserved (time)"),
        "{e}"
    );
    let parameter = "pub M {\n    parameters { t = 1.0 }\n    differential { x }\n    equations { der(x) = t; }\n}\n";
    let e = errors(parameter);
    assert!(
        e.starts_with("m.dae:2:18: error: `t` is reserved (time)"),
        "{e}"
    );
    // Every reserved name of the language is refused the same way.
    for name in ["der", "sin", "cos", "tan", "exp", "ln", "sqrt"] {
        let src = format!("pub M {{ differential {{ x, {name} }} equations {{ der(x) = x; }} }}");
        let e = errors(&src);
        assert!(e.contains(&format!("`{name}` is reserved")), "{name}: {e}");
    }
    // Time itself is still usable.
    Derived::from_str("pub M { differential { x } equations { der(x) = t * x; } }").unwrap();
}

#[test]
fn invariant_names_are_unique() {
    let src = "pub M {\n    differential { x }\n    equations { der(x) = -x; }\n    invariants {\n        e = x^2;\n        e = 2 * x;\n    }\n}\n";
    let e = errors(src);
    let lines: Vec<&str> = e.lines().collect();
    assert_eq!(
        lines,
        [
            "m.dae:6:9: error: invariant `e` is declared twice",
            "m.dae:5:9: error: invariant `e` is first declared here",
        ],
        "{e}"
    );
}

//! Lexical errors in model text (issue 9, defect 5): each is one line that
//! says what is wrong and where, instead of proc_macro2's "cannot parse
//! string into token stream" or an echo of the rest of the file.

use dae_core::derive::render_error;
use dae_core::Derived;

const GOOD: &str = "pub M {
    parameters { k = 2.0 }
    differential { x }
    equations {
        der(x) = -k * x;
    }
}
";

fn error(src: &str) -> String {
    match Derived::from_str(src) {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => render_error(&e, "m.dae"),
    }
}

/// `GOOD` with line `line` (1-based) replaced.
fn with_line(line: usize, text: &str) -> String {
    let mut lines: Vec<&str> = GOOD.lines().collect();
    lines[line - 1] = text;
    lines.join("\n") + "\n"
}

#[test]
fn lexical_errors_are_one_line_at_their_place() {
    Derived::from_str(GOOD).unwrap();
    let cases = [
        (
            // The extra `{` is closed by the section's `}`, which leaves the
            // model's own open.
            with_line(4, "    equations {{"),
            "m.dae:1:7: error: unclosed `{`: the text ends before its `}`",
        ),
        (
            with_line(2, "    parameters { k = (2.0 }"),
            "m.dae:2:27: error: `}` does not close the `(` opened at 2:22 (expected `)`)",
        ),
        (
            with_line(5, "        der(x) = -k * x; }"),
            "m.dae:7:1: error: unexpected `}`: no bracket is open here",
        ),
        (
            with_line(5, "        der(x) = -k * (x;"),
            "m.dae:6:5: error: `}` does not close the `(` opened at 5:23 (expected `)`)",
        ),
        (
            with_line(5, "        der(x) = -k * 😀;"),
            "m.dae:5:23: error: character '😀' (U+1F600) not allowed",
        ),
        (
            with_line(5, "        der(x) = -k * x\0;"),
            "m.dae:5:24: error: NUL byte not allowed",
        ),
        (
            with_line(5, "        der(x) = \"-k * x;"),
            "m.dae:5:18: error: unterminated string: no closing `\"`",
        ),
        (
            with_line(5, "        der(x) = -k * x; /* note"),
            "m.dae:5:26: error: unterminated comment: no closing `*/`",
        ),
        (
            with_line(5, "        der(x) = -k ` x;"),
            "m.dae:5:21: error: character '`' (U+0060) not allowed",
        ),
    ];
    for (src, expected) in cases {
        assert_eq!(error(&src), expected, "{src}");
    }
}

#[test]
fn a_stray_quote_does_not_echo_the_file() {
    // The string runs from the stray quote to the next quote, two lines
    // down: the error names the token cut short, on one line.
    let src = "pub M {\n  differential { x }\n  equations { der(x) = \"x;\n  x\n  x\"; }\n}\n";
    let e = error(src);
    assert_eq!(
        e,
        "m.dae:3:24: error: `\"x;…` is not a number the model language understands"
    );
    let long = format!(
        "pub M {{ differential {{ x }} equations {{ der(x) = \"{}\"; }} }}",
        "x;\n".repeat(30)
    );
    let e = error(&long);
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.len() < 120, "{e}");
}

//! Models the unit tests of several modules share (test builds only).

/// The model text of the planar chain of `scripts/chain.py` with `n`
/// links (`5n` unknowns).
pub(crate) fn chain(n: usize) -> String {
    let mut s = format!("pub Chain{n} {{\n parameters {{ m = 1.0, l = 1.0, g = 9.81 }}\n");
    let names = |c: &str| (1..=n).map(|i| format!("{c}{i}")).collect::<Vec<_>>();
    let diff: Vec<String> = ["x", "y", "u", "v"].iter().flat_map(|c| names(c)).collect();
    s += &format!(" differential {{ {} }}\n", diff.join(", "));
    s += &format!(
        " algebraic {{ {} }}\n equations {{\n",
        names("la").join(", ")
    );
    for i in 1..=n {
        s += &format!("  der(x{i}) = u{i};\n  der(y{i}) = v{i};\n");
    }
    for i in 1..=n {
        let (dx, dy) = if i == 1 {
            ("x1".to_string(), "y1".to_string())
        } else {
            (
                format!("(x{i} - x{})", i - 1),
                format!("(y{i} - y{})", i - 1),
            )
        };
        let (mut fx, mut fy) = (format!("-2*la{i}*{dx}"), format!("-2*la{i}*{dy}"));
        if i < n {
            fx += &format!(" + 2*la{}*(x{} - x{i})", i + 1, i + 1);
            fy += &format!(" + 2*la{}*(y{} - y{i})", i + 1, i + 1);
        }
        s += &format!("  m*der(u{i}) = {fx};\n  m*der(v{i}) = {fy} - m*g;\n");
    }
    for i in 1..=n {
        if i == 1 {
            s += "  0 = x1^2 + y1^2 - l^2;\n";
        } else {
            s += &format!(
                "  0 = (x{i} - x{})^2 + (y{i} - y{})^2 - l^2;\n",
                i - 1,
                i - 1
            );
        }
    }
    s + " }\n}\n"
}

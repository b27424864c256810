//! Printing expressions as model-language text and as LaTeX.
//!
//! The text form re-parses to the same canonical expression (tested), so
//! derived constraints printed by `dae derive` can be pasted back into a
//! model.

use crate::expr::{q, qr, Expr, Sym, Q};
use num_traits::{One, Signed, Zero};

/// Gives every symbol its printed name.
pub trait Names {
    /// Name of `s` in the model language (`x`, `der(x)`, `lambda`, …).
    fn name(&self, s: Sym) -> String;
}

impl<F: Fn(Sym) -> String> Names for F {
    fn name(&self, s: Sym) -> String {
        self(s)
    }
}

/// Output flavour.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Style {
    Text,
    Latex,
}

/// Model-language text of `e`.
pub fn text(e: &Expr, names: &dyn Names) -> String {
    Printer {
        names,
        style: Style::Text,
    }
    .expr(e)
}

/// LaTeX of `e` (math mode, without delimiters).
pub fn latex(e: &Expr, names: &dyn Names) -> String {
    Printer {
        names,
        style: Style::Latex,
    }
    .expr(e)
}

/// LaTeX for a model-language name: Greek letters become commands,
/// `der(x)` becomes `\dot{x}`, a trailing number becomes a subscript.
pub fn latex_name(name: &str) -> String {
    if let Some(inner) = name.strip_prefix("der(").and_then(|s| s.strip_suffix(')')) {
        return format!("\\dot{{{}}}", latex_name(inner));
    }
    const GREEK: [&str; 24] = [
        "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
        "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi",
        "omega", "Omega",
    ];
    let split = name.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    let (stem, digits) = name.split_at(split);
    let stem = stem.trim_end_matches('_');
    let base = if GREEK.contains(&stem) {
        format!("\\{stem}")
    } else if stem.chars().count() > 1 {
        format!("\\mathrm{{{}}}", stem.replace('_', "\\_"))
    } else {
        stem.to_string()
    };
    if digits.is_empty() {
        base
    } else {
        format!("{base}_{{{digits}}}")
    }
}

struct Printer<'a> {
    names: &'a dyn Names,
    style: Style,
}

impl Printer<'_> {
    fn sym(&self, s: Sym) -> String {
        let n = self.names.name(s);
        match self.style {
            Style::Text => n,
            Style::Latex => latex_name(&n),
        }
    }

    fn num(&self, v: &Q) -> String {
        if v.denom().is_one() {
            v.numer().to_string()
        } else {
            match self.style {
                Style::Text => format!("{}/{}", v.numer(), v.denom()),
                Style::Latex => format!("\\frac{{{}}}{{{}}}", v.numer(), v.denom()),
            }
        }
    }

    /// A constant with its sign, as a whole expression: `3`, `-1/2`.
    fn signed_num(&self, v: &Q) -> String {
        if v.is_negative() {
            format!("-{}", self.num(&v.abs()))
        } else {
            self.num(v)
        }
    }

    /// A constant as an operand of `*` or `^`: bare when it is a
    /// non-negative integer, parenthesised otherwise (`(1/2)`, `(-3)`).
    fn num_atom(&self, v: &Q) -> String {
        if v.denom().is_one() && !v.is_negative() {
            return self.num(v);
        }
        match self.style {
            Style::Text => format!("({})", self.signed_num(v)),
            Style::Latex => format!("\\left({}\\right)", self.signed_num(v)),
        }
    }

    fn expr(&self, e: &Expr) -> String {
        match e {
            Expr::Sum(s) => {
                let mut out = String::new();
                // Positive terms first (stable), so rows read `y*v - x*w`.
                let mut parts: Vec<(Q, &Expr)> = s
                    .terms
                    .iter()
                    .filter(|(_, c)| c.is_positive())
                    .map(|(t, c)| (c.clone(), t))
                    .collect();
                parts.extend(
                    s.terms
                        .iter()
                        .filter(|(_, c)| c.is_negative())
                        .map(|(t, c)| (c.clone(), t)),
                );
                let one = Expr::one();
                if !s.constant.is_zero() {
                    parts.push((s.constant.clone(), &one));
                }
                for (i, (c, t)) in parts.iter().enumerate() {
                    let negative = c.is_negative();
                    if i == 0 {
                        if negative {
                            out.push('-');
                        }
                    } else {
                        out.push_str(if negative { " - " } else { " + " });
                    }
                    out.push_str(&self.term(&c.abs(), t));
                }
                out
            }
            Expr::Num(v) => self.signed_num(v),
            _ => self.term(&q(1), e),
        }
    }

    /// `c · t` with `c > 0`, `t` not a sum.
    fn term(&self, c: &Q, t: &Expr) -> String {
        if let Expr::Num(v) = t {
            // A constant term is its own coefficient.
            return self.signed_num(&(c * &**v));
        }
        let (mut num, mut den): (Vec<String>, Vec<String>) = (Vec::new(), Vec::new());
        if !c.numer().is_one() || t.is_one() {
            num.push(c.numer().to_string());
        }
        if !c.denom().is_one() {
            den.push(c.denom().to_string());
        }
        match t {
            Expr::Num(v) if v.is_one() => {}
            Expr::Prod(p) => {
                // Parameters first, derivatives last: `m*g*x`, `m*der(v)`.
                let rank = |b: &Expr| match b {
                    Expr::Sym(Sym::Param(_)) => 0,
                    Expr::Sym(Sym::Der(_)) => 2,
                    _ => 1,
                };
                let mut factors: Vec<&(Expr, Q)> = p.factors.iter().collect();
                factors.sort_by_key(|(b, _)| rank(b));
                for (b, x) in factors {
                    if x.is_negative() {
                        den.push(self.power(b, &x.abs()));
                    } else {
                        num.push(self.power(b, x));
                    }
                }
            }
            other => num.push(self.atom(other)),
        }
        let sep = match self.style {
            Style::Text => "*",
            Style::Latex => " ",
        };
        let numerator = if num.is_empty() {
            "1".to_string()
        } else {
            num.join(sep)
        };
        if den.is_empty() {
            return numerator;
        }
        match self.style {
            Style::Text => {
                let mut s = numerator;
                for d in den {
                    s.push('/');
                    s.push_str(&d);
                }
                s
            }
            Style::Latex => format!("\\frac{{{}}}{{{}}}", numerator, den.join(" ")),
        }
    }

    /// `b^x` with `x > 0`.
    fn power(&self, b: &Expr, x: &Q) -> String {
        if x.is_one() {
            return self.atom(b);
        }
        if *x == qr(1, 2) {
            return match self.style {
                Style::Text => format!("sqrt({})", self.expr(b)),
                Style::Latex => format!("\\sqrt{{{}}}", self.expr(b)),
            };
        }
        let exp = if x.denom().is_one() {
            x.numer().to_string()
        } else {
            match self.style {
                Style::Text => format!("({}/{})", x.numer(), x.denom()),
                Style::Latex => format!("{}/{}", x.numer(), x.denom()),
            }
        };
        match self.style {
            Style::Text => format!("{}^{}", self.base(b), exp),
            Style::Latex => format!("{}^{{{}}}", self.base(b), exp),
        }
    }

    /// The base of a power: an atom, parenthesised when it is itself a
    /// power (`^` groups to the right, so `(x^y)^3` needs them).
    fn base(&self, b: &Expr) -> String {
        match (b, self.style) {
            (Expr::Pow(_), Style::Text) => format!("({})", self.atom(b)),
            (Expr::Pow(_), Style::Latex) => format!("\\left({}\\right)", self.atom(b)),
            _ => self.atom(b),
        }
    }

    /// An operand that binds tighter than `*` and `^`.
    fn atom(&self, e: &Expr) -> String {
        match e {
            Expr::Sym(s) => self.sym(*s),
            // Every constant is printed here, never through `expr` (which
            // would come back to `atom` for a fraction).
            Expr::Num(v) => self.num_atom(v),
            Expr::Func(c) => match self.style {
                Style::Text => format!("{}({})", c.func.name(), self.expr(&c.arg)),
                Style::Latex => format!("\\{}\\left({}\\right)", c.func.name(), self.expr(&c.arg)),
            },
            Expr::Prod(p) if p.factors.len() == 1 && p.factors[0].1 == qr(1, 2) => {
                self.power(&p.factors[0].0, &qr(1, 2))
            }
            Expr::Pow(p) => match self.style {
                Style::Text => format!("{}^({})", self.base(&p.base), self.expr(&p.exponent)),
                Style::Latex => format!("{}^{{{}}}", self.base(&p.base), self.expr(&p.exponent)),
            },
            _ => match self.style {
                Style::Text => format!("({})", self.expr(e)),
                Style::Latex => format!("\\left({}\\right)", self.expr(e)),
            },
        }
    }
}

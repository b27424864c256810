//! The model language: one parser over `proc_macro2::TokenStream`, used by
//! the `dae!` macro at compile time and by the binary at run time (via
//! [`parse_str`]).
//!
//! ```text
//! /// doc comment (optional)
//! pub Pendulum {
//!     parameters { m = 1.0, l = 1.0, g = 13.7503716373294544 }
//!     differential { x, y, v, w }
//!     algebraic { lambda }
//!     equations {
//!         der(x) = v;
//!         der(y) = w;
//!         m * der(v) = -2 * x * lambda;
//!         m * der(w) = -2 * y * lambda - m * g;
//!         0 = x^2 + y^2 - l^2;
//!     }
//!     invariants { energy = m * (v^2 + w^2) / 2 + m * g * y; }
//!     formulations { ori2, rcd1, rcd0, ovd1, ovd0, ggl1, psi1, psi0 }
//! }
//! ```
//!
//! Two more sections name expressions, each `name = expr;`, read in order:
//!
//! - `derived { l2 = l^2; }` — derived parameters, expressions of the
//!   parameters and of earlier derived parameters ([`ModelAst::derived`]);
//! - `definitions { r2 = x^2 + y^2; }` — named subexpressions of
//!   parameters, unknowns, `t` and earlier definitions, usable in
//!   equations, invariants and later definitions
//!   ([`ModelAst::definitions`]).
//!
//! A dynamic equation may hold several `der()`, linearly, with
//! coefficients of parameters and positions: the rows of a mass matrix,
//! `(mc + m) * der(vs) + m * der(vu) = 0;` (see [`crate::model::Dynamic`]).
//!
//! Sections may come in any order; the parser keeps each as written and
//! [`crate::model::Model::check`] resolves the names.
//!
//! Expressions have their own grammar (a Pratt parser): Rust's `syn::Expr`
//! would read `^` as XOR with the wrong precedence. Binding, loosest first:
//! `+ -` (left), `* /` (left), unary `-` / `+`, `^` (right). So `-x^2` is
//! `-(x^2)` and `2^-1` is `2^(-1)`.
//!
//! Errors are [`syn::Error`]s at the offending token; several are combined
//! into one so the user sees every problem at once.

use crate::expr::Q;
use num_bigint::BigInt;
use proc_macro2::{Delimiter, Span, TokenStream, TokenTree};
use std::str::FromStr;

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `^`
    Pow,
}

/// An expression as written, with spans.
#[derive(Clone, Debug)]
pub enum Ast {
    /// Numeric literal, exact.
    Num(Q, Span),
    /// A name.
    Ident(String, Span),
    /// `name(args…)`.
    Call(String, Span, Vec<Ast>),
    /// Unary minus.
    Neg(Box<Ast>, Span),
    /// Binary operation; the span is the operator's.
    Bin(BinOp, Box<Ast>, Box<Ast>, Span),
    /// A left-associative chain of `+`/`−` or of `*`/`/`:
    /// `first op₁ a₁ op₂ a₂ …`, each operator with its span. A sum of
    /// 20,000 terms is one node, not a tree 20,000 deep.
    Chain(Box<Ast>, Vec<(BinOp, Ast, Span)>),
}

impl Ast {
    /// A span for error messages: the leftmost token.
    pub fn span(&self) -> Span {
        match self {
            Ast::Num(_, s) | Ast::Ident(_, s) | Ast::Call(_, s, _) | Ast::Neg(_, s) => *s,
            Ast::Bin(_, l, _, _) | Ast::Chain(l, _) => l.span(),
        }
    }
}

/// A name with its span.
#[derive(Clone, Debug)]
pub struct Name {
    /// The identifier.
    pub name: String,
    /// Where it was written.
    pub span: Span,
}

/// `name = value` in `parameters { … }`.
#[derive(Clone, Debug)]
pub struct ParamDecl {
    /// Parameter name.
    pub name: Name,
    /// Default value.
    pub value: f64,
}

/// `lhs = rhs;` in `equations { … }`.
#[derive(Clone, Debug)]
pub struct Equation {
    /// Left-hand side.
    pub lhs: Ast,
    /// Right-hand side.
    pub rhs: Ast,
    /// Span of the `=`.
    pub span: Span,
}

/// `name = expr;` in `invariants { … }`, `definitions { … }` or
/// `derived { … }`.
#[derive(Clone, Debug)]
pub struct InvariantDecl {
    /// The name being defined.
    pub name: Name,
    /// Its expression.
    pub expr: Ast,
}

/// `name = expr;` in `definitions { … }` or `derived { … }`: the same
/// shape as an invariant.
pub type NamedExpr = InvariantDecl;

/// A parsed (not yet checked) model.
#[derive(Clone, Debug)]
pub struct ModelAst {
    /// Doc comment lines joined.
    pub doc: String,
    /// `pub` was written.
    pub public: bool,
    /// Model name.
    pub name: Name,
    /// Parameters in order.
    pub parameters: Vec<ParamDecl>,
    /// Differential unknowns in order.
    pub differential: Vec<Name>,
    /// Algebraic unknowns in order.
    pub algebraic: Vec<Name>,
    /// Equations in order.
    pub equations: Vec<Equation>,
    /// Invariants in order.
    pub invariants: Vec<InvariantDecl>,
    /// Event functions (`events { hit = x + 0.5; }`) in order: the same
    /// shape as an invariant.
    pub events: Vec<NamedExpr>,
    /// Derived parameters (`derived { k = m * l^2; }`) in order.
    pub derived: Vec<NamedExpr>,
    /// Definitions (`definitions { r2 = x^2 + y^2; }`) in order.
    pub definitions: Vec<NamedExpr>,
    /// Requested formulations (`None` when the block is absent).
    pub formulations: Option<Vec<Name>>,
    /// Span of the model body (for errors about the whole model).
    pub body_span: Span,
}

/// Deepest nesting of an expression: parentheses, function calls, unary
/// signs and exponents each add a level. Real models stay below 20. The
/// parser, the lowering and the printer recurse once per level (and the
/// derivative passes once per level of the expressions derived from it), so
/// the limit is what keeps them inside the stack: at 200 levels the deepest
/// forms (`sin(x*cos(x*…))`, 10,000-character lines of parentheses) need
/// about 1.5 MiB unoptimised and a few hundred KiB optimised, well inside
/// an 8 MiB main thread or the thread rustc runs a procedural macro on.
pub const MAX_DEPTH: usize = 200;

/// Collects errors instead of stopping at the first.
#[derive(Default)]
pub struct Errors {
    errors: Option<syn::Error>,
}

impl Errors {
    /// Record an error at `span`.
    pub fn push(&mut self, span: Span, msg: impl std::fmt::Display) {
        self.push_error(syn::Error::new(span, msg));
    }
    /// Record a ready error.
    pub fn push_error(&mut self, e: syn::Error) {
        match &mut self.errors {
            Some(all) => all.combine(e),
            None => self.errors = Some(e),
        }
    }
    /// `true` when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.errors.is_none()
    }
    /// `Err` with every error, or `Ok(value)`.
    pub fn finish<T>(self, value: T) -> Result<T, syn::Error> {
        match self.errors {
            Some(e) => Err(e),
            None => Ok(value),
        }
    }
}

/// Parse model text read at run time (a `.dae` file). Lexical errors
/// (unbalanced brackets, stray characters, unterminated strings, …) are one
/// line each, at their position.
pub fn parse_str(src: &str) -> Result<ModelAst, syn::Error> {
    parse(lex(src)?)
}

/// Split text into tokens, after [`crate::lex::scan`] has checked that it
/// can be: every error at its position. The model body and a section add
/// two brackets around an expression's own.
pub fn lex(src: &str) -> Result<TokenStream, syn::Error> {
    crate::lex::scan(src, MAX_DEPTH + 2, MAX_DEPTH)
        .map_err(|e| syn::Error::new(span_at(e.pos()), e.message()))?;
    TokenStream::from_str(src).map_err(|e| {
        // Not expected after the scan; proc_macro2 still knows where.
        syn::Error::new(e.span(), "this text cannot be split into tokens")
    })
}

/// A span that starts at `pos` of the text being read: the span of a
/// placeholder token lexed at that line and column. Outside a procedural
/// macro (and under `proc_macro2::fallback::force`) spans of lexed text
/// carry their line and column, which is all an error needs.
fn span_at(pos: crate::lex::Pos) -> Span {
    let mut text = "\n".repeat(pos.line.saturating_sub(1));
    text.push_str(&" ".repeat(pos.column.saturating_sub(1)));
    text.push('x');
    TokenStream::from_str(&text)
        .ok()
        .and_then(|t| t.into_iter().next())
        .map_or_else(Span::call_site, |t| t.span())
}

/// A token as an error message shows it: a bracket group by its opening
/// bracket, a long literal cut short, never more than one line.
pub fn describe(t: &TokenTree) -> String {
    match t {
        TokenTree::Group(g) => match g.delimiter() {
            Delimiter::Parenthesis => "(".into(),
            Delimiter::Bracket => "[".into(),
            Delimiter::Brace => "{".into(),
            Delimiter::None => "…".into(),
        },
        other => {
            let text = other.to_string();
            let first = text.lines().next().unwrap_or("");
            let short: String = first.chars().take(24).collect();
            if short.len() < text.len() {
                format!("{short}…")
            } else {
                short
            }
        }
    }
}

/// Parse a model from tokens (the body of `dae! { … }`).
pub fn parse(tokens: TokenStream) -> Result<ModelAst, syn::Error> {
    let toks: Vec<TokenTree> = tokens.into_iter().collect();
    let mut errors = Errors::default();
    let mut i = 0;
    let mut doc = Vec::new();
    // Doc comments arrive as `# [doc = "..."]`.
    while i < toks.len() {
        match (&toks[i], toks.get(i + 1)) {
            (TokenTree::Punct(p), Some(TokenTree::Group(g)))
                if p.as_char() == '#' && g.delimiter() == Delimiter::Bracket =>
            {
                let inner: Vec<TokenTree> = g.stream().into_iter().collect();
                match inner.as_slice() {
                    [TokenTree::Ident(id), TokenTree::Punct(eq), TokenTree::Literal(lit)]
                        if id == "doc" && eq.as_char() == '=' =>
                    {
                        doc.push(unquote(&lit.to_string()));
                    }
                    _ => errors.push(g.span(), "only doc comments (`/// …`) may precede a model"),
                }
                i += 2;
            }
            _ => break,
        }
    }
    let mut public = false;
    if let Some(TokenTree::Ident(id)) = toks.get(i) {
        if id == "pub" {
            public = true;
            i += 1;
        }
    }
    let name = match toks.get(i) {
        Some(TokenTree::Ident(id)) => Name {
            name: id.to_string(),
            span: id.span(),
        },
        Some(t) => {
            return Err(syn::Error::new(
                t.span(),
                "expected the model name, e.g. `pub Pendulum { … }`",
            ))
        }
        None => {
            return Err(syn::Error::new(
                Span::call_site(),
                "empty model: expected `pub Name { … }`",
            ))
        }
    };
    i += 1;
    let body = match toks.get(i) {
        Some(TokenTree::Group(g)) if g.delimiter() == Delimiter::Brace => g.clone(),
        Some(t) => {
            return Err(syn::Error::new(
                t.span(),
                "expected `{` after the model name",
            ))
        }
        None => {
            return Err(syn::Error::new(
                name.span,
                "expected `{ … }` with the model's sections after its name",
            ))
        }
    };
    if let Some(t) = toks.get(i + 1) {
        errors.push(t.span(), "unexpected tokens after the model body");
    }
    let mut model = ModelAst {
        doc: doc.iter().map(|s| s.trim()).collect::<Vec<_>>().join("\n"),
        public,
        name,
        parameters: Vec::new(),
        differential: Vec::new(),
        algebraic: Vec::new(),
        equations: Vec::new(),
        invariants: Vec::new(),
        events: Vec::new(),
        derived: Vec::new(),
        definitions: Vec::new(),
        formulations: None,
        body_span: body.span(),
    };
    let sections: Vec<TokenTree> = body.stream().into_iter().collect();
    let mut seen: Vec<String> = Vec::new();
    let mut j = 0;
    while j < sections.len() {
        let TokenTree::Ident(kw) = &sections[j] else {
            errors.push(
                sections[j].span(),
                "expected a section: parameters, derived, differential, algebraic, definitions, equations, invariants, events or formulations",
            );
            break;
        };
        let kw_name = kw.to_string();
        let Some(TokenTree::Group(g)) = sections
            .get(j + 1)
            .filter(|t| matches!(t, TokenTree::Group(g) if g.delimiter() == Delimiter::Brace))
        else {
            errors.push(kw.span(), format!("expected `{{ … }}` after `{kw_name}`"));
            break;
        };
        if seen.contains(&kw_name) {
            errors.push(kw.span(), format!("section `{kw_name}` appears twice"));
        }
        seen.push(kw_name.clone());
        let inner: Vec<TokenTree> = g.stream().into_iter().collect();
        match kw_name.as_str() {
            "parameters" => model.parameters.extend(parse_parameters(&inner, &mut errors)),
            "differential" => model.differential.extend(parse_names(&inner, &mut errors)),
            "algebraic" => model.algebraic.extend(parse_names(&inner, &mut errors)),
            "equations" => model.equations.extend(parse_equations(&inner, &mut errors)),
            "invariants" => model.invariants.extend(parse_invariants(&inner, &mut errors)),
            "events" => model.events.extend(parse_invariants(&inner, &mut errors)),
            "derived" => model.derived.extend(parse_invariants(&inner, &mut errors)),
            "definitions" => model.definitions.extend(parse_invariants(&inner, &mut errors)),
            "formulations" => model.formulations = Some(parse_names(&inner, &mut errors)),
            other => errors.push(
                kw.span(),
                format!("unknown section `{other}` (expected parameters, derived, differential, algebraic, definitions, equations, invariants, events or formulations)"),
            ),
        }
        j += 2;
    }
    errors.finish(model)
}

fn unquote(lit: &str) -> String {
    // A doc literal is a plain Rust string literal.
    syn::parse_str::<syn::LitStr>(lit)
        .map(|l| l.value())
        .unwrap_or_else(|_| lit.trim_matches('"').to_string())
}

/// Split tokens at a separator punct (`,` or `;`), dropping empty pieces
/// after the last separator.
fn split(tokens: &[TokenTree], sep: char) -> Vec<(&[TokenTree], Option<Span>)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (k, t) in tokens.iter().enumerate() {
        if let TokenTree::Punct(p) = t {
            if p.as_char() == sep {
                out.push((&tokens[start..k], Some(p.span())));
                start = k + 1;
            }
        }
    }
    if start < tokens.len() {
        out.push((&tokens[start..], None));
    }
    out
}

fn parse_names(tokens: &[TokenTree], errors: &mut Errors) -> Vec<Name> {
    let mut out = Vec::new();
    for (piece, sep) in split(tokens, ',') {
        match piece {
            [TokenTree::Ident(id)] => out.push(Name {
                name: id.to_string(),
                span: id.span(),
            }),
            [] => errors.push(
                sep.unwrap_or_else(Span::call_site),
                "expected a name before `,`",
            ),
            [first, ..] => errors.push(first.span(), "expected a single name"),
        }
    }
    out
}

fn parse_parameters(tokens: &[TokenTree], errors: &mut Errors) -> Vec<ParamDecl> {
    let mut out = Vec::new();
    for (piece, sep) in split(tokens, ',') {
        let (name, rest) = match piece {
            [TokenTree::Ident(id), TokenTree::Punct(eq), rest @ ..] if eq.as_char() == '=' => {
                (id, rest)
            }
            [] => {
                errors.push(
                    sep.unwrap_or_else(Span::call_site),
                    "expected `name = value` before `,`",
                );
                continue;
            }
            [first, ..] => {
                errors.push(first.span(), "expected `name = value`, e.g. `m = 1.0`");
                continue;
            }
        };
        let (negative, lit_tokens) = match rest {
            [TokenTree::Punct(p), tail @ ..] if p.as_char() == '-' => (true, tail),
            _ => (false, rest),
        };
        let value = match lit_tokens {
            [TokenTree::Literal(lit)] => match number(&lit.to_string()) {
                Some(v) => {
                    let f = crate::expr::q_to_f64(&v);
                    if f == 0.0 && v != Q::from_integer(0.into()) {
                        // `1e-400` would silently become 0, where `1e400`
                        // is refused as not finite.
                        errors.push(
                            lit.span(),
                            format!(
                                "default of `{name}` underflows to 0 in double precision (the smallest positive value is 4.9e-324); write 0 if 0 is meant"
                            ),
                        );
                        continue;
                    }
                    if negative {
                        -f
                    } else {
                        f
                    }
                }
                None => {
                    errors.push(
                        lit.span(),
                        format!(
                            "default of `{name}` must be a number, found `{}`",
                            describe(&TokenTree::Literal(lit.clone()))
                        ),
                    );
                    continue;
                }
            },
            [] => {
                errors.push(
                    name.span(),
                    format!("parameter `{name}` needs a default value"),
                );
                continue;
            }
            [t, ..] => {
                errors.push(
                    t.span(),
                    format!(
                        "default of `{name}` must be a numeric literal, found `{}`",
                        describe(t)
                    ),
                );
                continue;
            }
        };
        out.push(ParamDecl {
            name: Name {
                name: name.to_string(),
                span: name.span(),
            },
            value,
        });
    }
    out
}

fn parse_equations(tokens: &[TokenTree], errors: &mut Errors) -> Vec<Equation> {
    let mut out = Vec::new();
    for (piece, sep) in split(tokens, ';') {
        if piece.is_empty() {
            continue;
        }
        if sep.is_none() {
            errors.push(
                piece[piece.len() - 1].span(),
                "expected `;` after the equation",
            );
        }
        let eqs: Vec<usize> = piece
            .iter()
            .enumerate()
            .filter(|(_, t)| matches!(t, TokenTree::Punct(p) if p.as_char() == '='))
            .map(|(k, _)| k)
            .collect();
        if eqs.len() >= 2 {
            // Two `=` in one piece: most often a `;` left out between two
            // equations. The first equation ends where two operands meet
            // with no operator between them (`… = v  der(y) = …`).
            match missing_separator(&piece[eqs[0] + 1..eqs[1]]) {
                Some(last) => {
                    let (what, span) = match last {
                        TokenTree::Group(g) => ("(…)".to_string(), g.span_close()),
                        other => (describe(other), other.span()),
                    };
                    errors.push(
                        span,
                        format!(
                            "expected `;` after `{what}`: the next equation begins without one"
                        ),
                    );
                }
                None => errors.push(
                    piece[eqs[1]].span(),
                    "a second `=` in one equation: end each equation with `;` \
                     (`coef * der(u) = rhs;` or `0 = constraint;`)",
                ),
            }
            continue;
        }
        if eqs.is_empty() {
            errors.push(
                piece[0].span(),
                "an equation needs one `=`: `coef * der(u) = rhs` or `0 = constraint`",
            );
            continue;
        }
        let k = eqs[0];
        let span = piece[k].span();
        if let TokenTree::Punct(p) = &piece[k] {
            if p.spacing() == proc_macro2::Spacing::Joint {
                if let Some(TokenTree::Punct(next)) = piece.get(k + 1) {
                    if next.as_char() == '=' {
                        errors.push(span, "use a single `=` in equations");
                        continue;
                    }
                }
            }
        }
        let lhs = parse_expr(&piece[..k], span, errors);
        let rhs = parse_expr(&piece[k + 1..], span, errors);
        if let (Some(lhs), Some(rhs)) = (lhs, rhs) {
            out.push(Equation { lhs, rhs, span });
        }
    }
    out
}

/// Where an equation ends without its `;`: in `tokens`, the text between
/// the first and the second `=` of a piece, the last token of the first
/// equation — the last operand directly followed by another operand (an
/// identifier, a literal, or a parenthesis that is not a call's argument
/// list). `None` if no two operands meet (`… = a - b = …`).
fn missing_separator(tokens: &[TokenTree]) -> Option<&TokenTree> {
    let is_operand = |t: &TokenTree| match t {
        TokenTree::Ident(_) | TokenTree::Literal(_) => true,
        TokenTree::Group(g) => g.delimiter() == Delimiter::Parenthesis,
        TokenTree::Punct(_) => false,
    };
    tokens.windows(2).rev().find_map(|pair| {
        let (a, b) = (&pair[0], &pair[1]);
        let call = matches!(a, TokenTree::Ident(_)) && matches!(b, TokenTree::Group(_));
        (is_operand(a) && is_operand(b) && !call).then_some(a)
    })
}

fn parse_invariants(tokens: &[TokenTree], errors: &mut Errors) -> Vec<InvariantDecl> {
    let mut out = Vec::new();
    for (piece, _) in split(tokens, ';') {
        match piece {
            [] => {}
            [TokenTree::Ident(id), TokenTree::Punct(eq), rest @ ..] if eq.as_char() == '=' => {
                if let Some(expr) = parse_expr(rest, eq.span(), errors) {
                    out.push(InvariantDecl {
                        name: Name {
                            name: id.to_string(),
                            span: id.span(),
                        },
                        expr,
                    });
                }
            }
            [first, ..] => errors.push(first.span(), "expected `name = expression;`"),
        }
    }
    out
}

/// Parse an exact decimal literal (`2`, `1.5`, `13.75`, `1e-3`, `2.5E+2`,
/// `1_000`). Type suffixes are not allowed.
pub fn number(lit: &str) -> Option<Q> {
    let s: String = lit.chars().filter(|&c| c != '_').collect();
    let (mantissa, exponent) = match s.find(['e', 'E']) {
        Some(k) => (&s[..k], s[k + 1..].parse::<i32>().ok()?),
        None => (s.as_str(), 0),
    };
    let (int, frac) = match mantissa.find('.') {
        Some(k) => (&mantissa[..k], &mantissa[k + 1..]),
        None => (mantissa, ""),
    };
    if int.is_empty()
        || !int.chars().all(|c| c.is_ascii_digit())
        || !frac.chars().all(|c| c.is_ascii_digit())
    {
        return None;
    }
    let digits = BigInt::from_str(&format!("{int}{frac}")).ok()?;
    let scale = exponent - frac.len() as i32;
    if scale.abs() > 400 {
        return None;
    }
    let ten = BigInt::from(10);
    let p = num_traits::pow(ten, scale.unsigned_abs() as usize);
    Some(if scale >= 0 {
        Q::from_integer(digits * p)
    } else {
        Q::new(digits, p)
    })
}

/// Parse an expression from a token slice; `at` locates errors in an empty
/// slice.
pub fn parse_expr(tokens: &[TokenTree], at: Span, errors: &mut Errors) -> Option<Ast> {
    parse_expr_at(tokens, at, errors, 0)
}

/// [`parse_expr`] for tokens nested `depth` levels deep.
fn parse_expr_at(tokens: &[TokenTree], at: Span, errors: &mut Errors, depth: usize) -> Option<Ast> {
    if tokens.is_empty() {
        errors.push(at, "expected an expression");
        return None;
    }
    let mut p = ExprParser {
        toks: tokens,
        pos: 0,
        depth,
    };
    match p.expr(0) {
        Ok(e) => {
            if let Some(t) = p.toks.get(p.pos) {
                errors.push_error(unexpected(t));
                None
            } else {
                Some(e)
            }
        }
        Err(e) => {
            errors.push_error(e);
            None
        }
    }
}

struct ExprParser<'a> {
    toks: &'a [TokenTree],
    pos: usize,
    /// Nesting level: parentheses, call arguments, unary signs and
    /// exponents each add one.
    depth: usize,
}

/// `+`/`−` and `*`/`/` chain separately.
fn chain_class(op: BinOp) -> u8 {
    match op {
        BinOp::Add | BinOp::Sub => 0,
        BinOp::Mul | BinOp::Div => 1,
        BinOp::Pow => 2,
    }
}

/// `first` followed by the chain read so far, as one node.
fn close_chain(first: Ast, chain: &mut Vec<(BinOp, Ast, Span)>) -> Ast {
    if chain.is_empty() {
        first
    } else {
        Ast::Chain(Box::new(first), std::mem::take(chain))
    }
}

const BP_ADD: u8 = 10;
const BP_MUL: u8 = 20;
const BP_UNARY: u8 = 25;
const BP_POW: u8 = 30;

impl ExprParser<'_> {
    fn peek_op(&self) -> Option<(BinOp, Span)> {
        match self.toks.get(self.pos) {
            Some(TokenTree::Punct(p)) => {
                let op = match p.as_char() {
                    '+' => BinOp::Add,
                    '-' => BinOp::Sub,
                    '*' => BinOp::Mul,
                    '/' => BinOp::Div,
                    '^' => BinOp::Pow,
                    _ => return None,
                };
                Some((op, p.span()))
            }
            _ => None,
        }
    }

    /// One level deeper, at the token of `span`; an error past
    /// [`MAX_DEPTH`].
    fn enter(&mut self, span: Span) -> Result<(), syn::Error> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(too_deep(span));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    fn expr(&mut self, min_bp: u8) -> Result<Ast, syn::Error> {
        let mut lhs = self.prefix()?;
        // Operands of the `+`/`−` or `*`/`/` chain being read (a loop, so
        // a long sum costs no stack).
        let mut chain: Vec<(BinOp, Ast, Span)> = Vec::new();
        while let Some((op, span)) = self.peek_op() {
            let (lbp, rbp) = match op {
                BinOp::Add | BinOp::Sub => (BP_ADD, BP_ADD + 1),
                BinOp::Mul | BinOp::Div => (BP_MUL, BP_MUL + 1),
                BinOp::Pow => (BP_POW, BP_POW),
            };
            if lbp < min_bp {
                break;
            }
            self.pos += 1;
            if op == BinOp::Pow {
                // `^` binds tighter than a chain, so it only ever follows a
                // single operand. The exponent may carry its own sign:
                // `x^-2`.
                lhs = close_chain(lhs, &mut chain);
                self.enter(span)?;
                let rhs = self.expr_or_unary(rbp)?;
                self.leave();
                lhs = Ast::Bin(op, Box::new(lhs), Box::new(rhs), span);
                continue;
            }
            let rhs = self.expr(rbp)?;
            if chain
                .first()
                .is_some_and(|(first, ..)| chain_class(*first) != chain_class(op))
            {
                lhs = close_chain(lhs, &mut chain);
            }
            chain.push((op, rhs, span));
        }
        Ok(close_chain(lhs, &mut chain))
    }

    fn expr_or_unary(&mut self, bp: u8) -> Result<Ast, syn::Error> {
        if let Some(TokenTree::Punct(p)) = self.toks.get(self.pos) {
            if p.as_char() == '-' || p.as_char() == '+' {
                let span = p.span();
                let negative = p.as_char() == '-';
                self.pos += 1;
                self.enter(span)?;
                let inner = self.expr_or_unary(bp)?;
                self.leave();
                return Ok(if negative {
                    Ast::Neg(Box::new(inner), span)
                } else {
                    inner
                });
            }
        }
        self.expr(bp)
    }

    // The recursive descent keeps each level's frame small: every case is
    // its own function and messages are formatted out of line, so an
    // expression at the nesting limit needs little stack even unoptimised.
    fn prefix(&mut self) -> Result<Ast, syn::Error> {
        let Some(tok) = self.toks.get(self.pos) else {
            let span = self
                .toks
                .last()
                .map(|t| t.span())
                .unwrap_or_else(Span::call_site);
            return Err(syn::Error::new(span, "expression ends unexpectedly"));
        };
        self.pos += 1;
        match tok {
            TokenTree::Literal(lit) => literal(lit),
            TokenTree::Ident(id) => self.name_or_call(id),
            TokenTree::Group(g) if g.delimiter() == Delimiter::Parenthesis => self.group(g),
            TokenTree::Punct(p) if p.as_char() == '-' || p.as_char() == '+' => self.unary(p),
            other => Err(unexpected(other)),
        }
    }

    fn name_or_call(&mut self, id: &proc_macro2::Ident) -> Result<Ast, syn::Error> {
        let name = id.to_string();
        let Some(TokenTree::Group(g)) = self.toks.get(self.pos) else {
            return Ok(Ast::Ident(name, id.span()));
        };
        if g.delimiter() != Delimiter::Parenthesis {
            return Ok(Ast::Ident(name, id.span()));
        }
        self.pos += 1;
        let inner: Vec<TokenTree> = g.stream().into_iter().collect();
        let mut errs = Errors::default();
        let mut args = Vec::new();
        self.enter(g.span())?;
        for (piece, _) in split(&inner, ',') {
            if let Some(a) = parse_expr_at(piece, g.span(), &mut errs, self.depth) {
                args.push(a);
            }
        }
        self.leave();
        errs.finish(())?;
        if args.is_empty() {
            return Err(needs_argument(&name, g.span()));
        }
        Ok(Ast::Call(name, id.span(), args))
    }

    fn group(&mut self, g: &proc_macro2::Group) -> Result<Ast, syn::Error> {
        let inner: Vec<TokenTree> = g.stream().into_iter().collect();
        let mut errs = Errors::default();
        self.enter(g.span())?;
        let e = parse_expr_at(&inner, g.span(), &mut errs, self.depth);
        self.leave();
        errs.finish(())?;
        e.ok_or_else(|| syn::Error::new(g.span(), "expected an expression inside parentheses"))
    }

    fn unary(&mut self, p: &proc_macro2::Punct) -> Result<Ast, syn::Error> {
        self.enter(p.span())?;
        let inner = self.expr(BP_UNARY)?;
        self.leave();
        Ok(if p.as_char() == '-' {
            Ast::Neg(Box::new(inner), p.span())
        } else {
            inner
        })
    }
}

fn literal(lit: &proc_macro2::Literal) -> Result<Ast, syn::Error> {
    let s = lit.to_string();
    number(&s)
        .map(|v| Ast::Num(v, lit.span()))
        .ok_or_else(|| not_a_number(lit))
}

#[cold]
#[inline(never)]
fn not_a_number(lit: &proc_macro2::Literal) -> syn::Error {
    syn::Error::new(
        lit.span(),
        format!(
            "`{}` is not a number the model language understands",
            describe(&TokenTree::Literal(lit.clone()))
        ),
    )
}

#[cold]
#[inline(never)]
fn needs_argument(name: &str, span: Span) -> syn::Error {
    syn::Error::new(span, format!("`{name}(…)` needs an argument"))
}

#[cold]
#[inline(never)]
fn unexpected(t: &TokenTree) -> syn::Error {
    syn::Error::new(
        t.span(),
        format!("unexpected `{}` in expression", describe(t)),
    )
}

#[cold]
#[inline(never)]
fn too_deep(span: Span) -> syn::Error {
    syn::Error::new(
        span,
        format!("expression nested too deep (limit {MAX_DEPTH})"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_exact() {
        assert_eq!(number("0.5").unwrap(), crate::expr::qr(1, 2));
        assert_eq!(number("1e-3").unwrap(), crate::expr::qr(1, 1000));
        assert_eq!(number("2.5E+2").unwrap(), crate::expr::q(250));
        assert!(number("1f64").is_none());
        assert!(number("0x10").is_none());
    }

    #[test]
    fn precedence() {
        let mut errs = Errors::default();
        let toks: Vec<TokenTree> = TokenStream::from_str("-x^2 * 3 + 2^-1")
            .unwrap()
            .into_iter()
            .collect();
        let e = parse_expr(&toks, Span::call_site(), &mut errs).unwrap();
        // (-(x^2) * 3) + (2^(-1))
        match e {
            Ast::Chain(l, rest) => {
                assert!(
                    matches!(*l, Ast::Chain(ref a, ref m) if m.len() == 1 && m[0].0 == BinOp::Mul && matches!(**a, Ast::Neg(ref b, _) if matches!(**b, Ast::Bin(BinOp::Pow, ..))))
                );
                assert_eq!(rest.len(), 1);
                assert_eq!(rest[0].0, BinOp::Add);
                assert!(
                    matches!(rest[0].1, Ast::Bin(BinOp::Pow, _, ref b, _) if matches!(**b, Ast::Neg(..)))
                );
            }
            other => panic!("wrong tree {other:?}"),
        }
    }
}

//! The checked model: names resolved, equations split into dynamic
//! equations `c · der(u) = f` and constraints `0 = g`, every node keeping the
//! span it came from.

use crate::dsl::{Ast, BinOp, Errors, ModelAst, Name};
use crate::expr::{self, Expr, Func, Sym};
use crate::system::{VarKind, FORMULATION_NAMES};
use proc_macro2::Span;
use std::collections::{HashMap, HashSet};

/// A parameter with its default.
#[derive(Clone, Debug)]
pub struct ParamDef {
    /// Name.
    pub name: String,
    /// Default value.
    pub default: f64,
    /// Declaration span.
    pub span: Span,
}

/// An unknown of the model.
#[derive(Clone, Debug)]
pub struct VarDef {
    /// Name.
    pub name: String,
    /// Differential or algebraic.
    pub kind: VarKind,
    /// Declaration span.
    pub span: Span,
}

/// `coef · der(var) = rhs`.
#[derive(Clone, Debug)]
pub struct Dynamic {
    /// The differential unknown this equation gives the derivative of.
    pub var: usize,
    /// Scalar coefficient (free of derivatives).
    pub coef: Expr,
    /// Right-hand side.
    pub rhs: Expr,
    /// Span of the equation.
    pub span: Span,
}

/// `0 = expr`.
#[derive(Clone, Debug)]
pub struct ConstraintDef {
    /// The constraint function `g`.
    pub expr: Expr,
    /// Span of the equation.
    pub span: Span,
}

/// A named invariant.
#[derive(Clone, Debug)]
pub struct InvariantDef {
    /// Name.
    pub name: String,
    /// Expression.
    pub expr: Expr,
    /// Span of the name.
    pub span: Span,
}

/// A checked model.
#[derive(Clone, Debug)]
pub struct Model {
    /// Model name.
    pub name: String,
    /// Span of the name.
    pub name_span: Span,
    /// Doc comment.
    pub doc: String,
    /// `pub` was written.
    pub public: bool,
    /// Parameters in order.
    pub params: Vec<ParamDef>,
    /// Unknowns: differential first (declaration order), then algebraic.
    pub vars: Vec<VarDef>,
    /// Number of differential unknowns (the first `n_diff` of `vars`).
    pub n_diff: usize,
    /// Dynamic equations, one per differential unknown, in unknown order.
    pub dynamics: Vec<Dynamic>,
    /// Constraints in order.
    pub constraints: Vec<ConstraintDef>,
    /// Invariants in order.
    pub invariants: Vec<InvariantDef>,
    /// Requested formulations (`None`: all that apply).
    pub requested: Option<Vec<Name>>,
}

/// Names of the elementary functions.
pub const FUNCTIONS: [&str; 6] = ["sin", "cos", "tan", "exp", "ln", "sqrt"];

/// The name of time, which no parameter or unknown may take.
pub const TIME: &str = "t";

impl Model {
    /// Check a parsed model; every problem is reported, each at its token.
    pub fn check(ast: &ModelAst) -> Result<Model, syn::Error> {
        let mut errors = Errors::default();
        // Hash maps for lookups only (never iterated): linear in the names.
        let mut seen: HashMap<String, Span> = HashMap::new();
        // Names declared twice or reserved: uses of them raise no further
        // errors.
        let mut dupes: HashSet<String> = HashSet::new();
        let mut declare = |n: &Name, errors: &mut Errors| {
            if let Some(first) = seen.get(&n.name) {
                errors.push(n.span, format!("`{}` is declared twice", n.name));
                errors.push(*first, format!("`{}` is first declared here", n.name));
                dupes.insert(n.name.clone());
                return false;
            }
            if n.name == TIME {
                errors.push(n.span, "`t` is reserved (time): choose another name");
                dupes.insert(n.name.clone());
                return false;
            }
            if FUNCTIONS.contains(&n.name.as_str()) || n.name == "der" {
                errors.push(
                    n.span,
                    format!(
                        "`{}` is reserved (a function of the model language)",
                        n.name
                    ),
                );
                dupes.insert(n.name.clone());
                return false;
            }
            seen.insert(n.name.clone(), n.span);
            true
        };
        let mut params = Vec::new();
        for p in &ast.parameters {
            if declare(&p.name, &mut errors) {
                if !p.value.is_finite() {
                    errors.push(
                        p.name.span,
                        format!("default of `{}` is not finite", p.name.name),
                    );
                }
                params.push(ParamDef {
                    name: p.name.name.clone(),
                    default: p.value,
                    span: p.name.span,
                });
            }
        }
        let mut vars = Vec::new();
        for n in &ast.differential {
            if declare(n, &mut errors) {
                vars.push(VarDef {
                    name: n.name.clone(),
                    kind: VarKind::Differential,
                    span: n.span,
                });
            }
        }
        let n_diff = vars.len();
        for n in &ast.algebraic {
            if declare(n, &mut errors) {
                vars.push(VarDef {
                    name: n.name.clone(),
                    kind: VarKind::Algebraic,
                    span: n.span,
                });
            }
        }
        if n_diff == 0 {
            errors.push(
                ast.name.span,
                format!("model `{}` is empty: it needs `differential {{ … }}` unknowns and `equations {{ … }}`", ast.name.name),
            );
        }

        let scope = Scope::new(&params, &vars, dupes);
        let mut dynamics: Vec<Option<Dynamic>> = vec![None; n_diff];
        let mut constraints = Vec::new();
        // An equation that failed to lower already has its error; counting
        // equations afterwards would only add a cascade of "too few".
        let mut lowered_all = true;
        for eq in &ast.equations {
            let (Some(lhs), Some(rhs)) = (
                scope.lower(&eq.lhs, &mut errors),
                scope.lower(&eq.rhs, &mut errors),
            ) else {
                lowered_all = false;
                continue;
            };
            // Equation-level errors point at the equation's first token.
            let eq_span = eq.lhs.span();
            let r = expr::sub(&lhs, &rhs);
            let ders: Vec<usize> = r
                .symbols()
                .into_iter()
                .filter_map(|s| match s {
                    Sym::Der(i) => Some(i as usize),
                    _ => None,
                })
                .collect();
            match ders.as_slice() {
                [] => {
                    let g = if lhs.is_zero() { rhs } else { expr::sub(&lhs, &rhs) };
                    if g.any_sym(&|s| matches!(s, Sym::Var(_))) {
                        constraints.push(ConstraintDef { expr: g, span: eq_span });
                    } else {
                        errors.push(eq_span, "this equation involves no unknown");
                    }
                }
                [j] => {
                    let coef = expr::diff(&r, Sym::Der(*j as u32));
                    if coef.any_sym(&|s| matches!(s, Sym::Der(_))) {
                        errors.push(
                            eq.lhs.span(),
                            format!(
                                "`der({})` must appear linearly: write `coef * der({}) = rhs` with a coefficient free of der()",
                                vars[*j].name, vars[*j].name
                            ),
                        );
                        lowered_all = false;
                        continue;
                    }
                    let f = expr::neg(&expr::subs(&r, &|s| matches!(s, Sym::Der(_)).then(Expr::zero)));
                    if coef.contains(Sym::Time) {
                        errors.push(
                            eq_span,
                            format!("the coefficient of `der({})` may not depend on time `t`", vars[*j].name),
                        );
                        lowered_all = false;
                        continue;
                    }
                    if coef.is_zero() {
                        errors.push(eq_span, format!("the coefficient of `der({})` vanishes", vars[*j].name));
                        lowered_all = false;
                        continue;
                    }
                    if dynamics[*j].is_some() {
                        errors.push(
                            eq_span,
                            format!("a second equation for `der({})`: each differential unknown has exactly one", vars[*j].name),
                        );
                        lowered_all = false;
                        continue;
                    }
                    dynamics[*j] = Some(Dynamic {
                        var: *j,
                        coef,
                        rhs: f,
                        span: eq_span,
                    });
                }
                _ => errors.push(
                    eq.lhs.span(),
                    format!(
                        "a dynamic equation gives the derivative of one unknown; this one has der() of {}",
                        ders.iter().map(|&j| format!("`{}`", vars[j].name)).collect::<Vec<_>>().join(", ")
                    ),
                ),
            }
        }
        let mut dyns = Vec::new();
        for (j, d) in dynamics.into_iter().enumerate() {
            match d {
                Some(d) => dyns.push(d),
                None if !lowered_all => {}
                None => errors.push(
                    vars[j].span,
                    format!(
                        "too few equations: no equation gives `der({})`",
                        vars[j].name
                    ),
                ),
            }
        }
        let n_alg = vars.len() - n_diff;
        if !lowered_all {
            // Counts are meaningless with equations missing.
        } else if constraints.len() > n_alg {
            for c in &constraints[n_alg..] {
                errors.push(
                    c.span,
                    format!(
                        "too many equations: {} constraints for {} algebraic unknown{} (a semi-explicit model has one constraint per algebraic unknown)",
                        constraints.len(),
                        n_alg,
                        if n_alg == 1 { "" } else { "s" }
                    ),
                );
            }
        } else if constraints.len() < n_alg {
            for v in &vars[n_diff + constraints.len()..] {
                errors.push(
                    v.span,
                    format!(
                        "too few equations: {} algebraic unknowns but {} constraints; add `0 = …` for `{}`",
                        n_alg,
                        constraints.len(),
                        v.name
                    ),
                );
            }
        }
        if lowered_all {
            for (a, v) in vars.iter().enumerate().skip(n_diff) {
                let s = Sym::Var(a as u32);
                let used = dyns.iter().any(|d| d.rhs.contains(s) || d.coef.contains(s))
                    || constraints.iter().any(|c| c.expr.contains(s));
                if !used {
                    errors.push(
                        v.span,
                        format!("structurally singular: `{}` appears in no equation, so nothing determines it", v.name),
                    );
                }
            }
        }
        let mut invariants = Vec::new();
        let mut invariant_names: HashMap<&str, Span> = HashMap::new();
        for inv in &ast.invariants {
            if let Some(first) = invariant_names.get(inv.name.name.as_str()) {
                errors.push(
                    inv.name.span,
                    format!("invariant `{}` is declared twice", inv.name.name),
                );
                errors.push(
                    *first,
                    format!("invariant `{}` is first declared here", inv.name.name),
                );
                continue;
            }
            invariant_names.insert(&inv.name.name, inv.name.span);
            if let Some(e) = scope.lower(&inv.expr, &mut errors) {
                if e.any_sym(&|s| matches!(s, Sym::Der(_))) {
                    errors.push(inv.expr.span(), "invariants may not contain der()");
                    continue;
                }
                invariants.push(InvariantDef {
                    name: inv.name.name.clone(),
                    expr: e,
                    span: inv.name.span,
                });
            }
        }
        if let Some(list) = &ast.formulations {
            let mut listed: Vec<&str> = Vec::new();
            for f in list {
                if !FORMULATION_NAMES.contains(&f.name.as_str()) {
                    errors.push(
                        f.span,
                        format!(
                            "unknown formulation `{}` (known: {})",
                            f.name,
                            FORMULATION_NAMES.join(", ")
                        ),
                    );
                } else if listed.contains(&f.name.as_str()) {
                    errors.push(f.span, format!("formulation `{}` is listed twice", f.name));
                } else {
                    listed.push(&f.name);
                }
            }
            if list.is_empty() {
                errors.push(ast.body_span, "`formulations { }` is empty: list at least one, or leave the block out for all");
            }
        }
        errors.finish(Model {
            name: ast.name.name.clone(),
            name_span: ast.name.span,
            doc: ast.doc.clone(),
            public: ast.public,
            params,
            vars,
            n_diff,
            dynamics: dyns,
            constraints,
            invariants,
            requested: ast.formulations.clone(),
        })
    }

    /// Name of a symbol in the model language; `extra` names unknowns past
    /// the model's own (GGL multipliers).
    pub fn sym_name(&self, s: Sym, extra: &[String]) -> String {
        let var = |i: u32| -> String {
            let i = i as usize;
            self.vars
                .get(i)
                .map(|v| v.name.clone())
                .or_else(|| extra.get(i - self.vars.len()).cloned())
                .unwrap_or_else(|| format!("y{i}"))
        };
        match s {
            Sym::Var(i) => var(i),
            Sym::Der(i) => format!("der({})", var(i)),
            Sym::Param(k) => self
                .params
                .get(k as usize)
                .map(|p| p.name.clone())
                .unwrap_or_else(|| format!("p{k}")),
            Sym::Time => "t".into(),
            Sym::Dir(i) => format!("z{i}"),
        }
    }

    /// Text of an expression in the model language.
    pub fn text(&self, e: &Expr) -> String {
        crate::print::text(e, &|s| self.sym_name(s, &[]))
    }

    /// The unknowns' rates `der(u) = f/c` for the total time derivative.
    /// `Err(s)` when `s` has no rate (an algebraic unknown).
    pub fn rate(&self, s: Sym) -> Result<Option<Expr>, Sym> {
        match s {
            Sym::Var(i) if (i as usize) < self.n_diff => {
                let d = &self.dynamics[i as usize];
                Ok(Some(expr::div(&d.rhs, &d.coef)))
            }
            Sym::Param(_) => Ok(None),
            Sym::Time => Ok(Some(Expr::one())),
            _ => Err(s),
        }
    }

    /// Number of algebraic unknowns.
    pub fn n_alg(&self) -> usize {
        self.vars.len() - self.n_diff
    }

    /// Parse an expression in this model's names (e.g. a hand-derived
    /// constraint to compare with a derived one).
    pub fn parse_expr(&self, src: &str) -> Result<Expr, syn::Error> {
        let tokens: Vec<proc_macro2::TokenTree> = crate::dsl::lex(src)?.into_iter().collect();
        let mut errors = Errors::default();
        let ast = crate::dsl::parse_expr(&tokens, Span::call_site(), &mut errors);
        let scope = Scope::new(&self.params, &self.vars, HashSet::new());
        let e = ast.and_then(|a| scope.lower(&a, &mut errors));
        match e {
            Some(e) => errors.finish(e),
            None => {
                errors.push(Span::call_site(), "invalid expression");
                errors.finish(Expr::zero())
            }
        }
    }

    /// Parse and check model text (a `.dae` file).
    #[allow(clippy::should_implement_trait)] // returns `syn::Error` with spans, unlike `str::parse`
    pub fn from_str(src: &str) -> Result<Model, syn::Error> {
        Model::check(&crate::dsl::parse_str(src)?)
    }
}

struct Scope<'a> {
    vars: &'a [VarDef],
    /// Every declared name.
    names: HashMap<&'a str, Sym>,
    /// Names declared twice or reserved (already reported).
    dupes: HashSet<String>,
}

impl<'a> Scope<'a> {
    fn new(params: &'a [ParamDef], vars: &'a [VarDef], dupes: HashSet<String>) -> Self {
        let mut names = HashMap::new();
        for (k, p) in params.iter().enumerate() {
            names.insert(p.name.as_str(), Sym::Param(k as u32));
        }
        // Declared names are unique (a second declaration is not kept).
        for (i, v) in vars.iter().enumerate() {
            names.insert(v.name.as_str(), Sym::Var(i as u32));
        }
        Scope { vars, names, dupes }
    }

    fn lookup(&self, name: &str) -> Option<Sym> {
        if let Some(s) = self.names.get(name) {
            return Some(*s);
        }
        (name == "t").then_some(Sym::Time)
    }

    fn lower(&self, ast: &Ast, errors: &mut Errors) -> Option<Expr> {
        match ast {
            Ast::Num(v, _) => Some(Expr::num(v.clone())),
            Ast::Ident(name, span) => match self.lookup(name) {
                Some(s) => Some(Expr::sym(s)),
                None => {
                    let hint = if FUNCTIONS.contains(&name.as_str()) || name == "der" {
                        format!(" (`{name}` is a function: write `{name}(…)`)")
                    } else {
                        String::new()
                    };
                    errors.push(*span, format!("unknown name `{name}`: not a parameter or an unknown of this model{hint}"));
                    None
                }
            },
            Ast::Call(name, span, args) => {
                if args.len() != 1 {
                    errors.push(
                        *span,
                        format!("`{name}` takes one argument, found {}", args.len()),
                    );
                    return None;
                }
                if name == "der" {
                    return match &args[0] {
                        Ast::Ident(v, vspan) => match self.names.get(v.as_str()).and_then(|s| {
                            match s {
                                Sym::Var(i) => Some(*i as usize),
                                _ => None,
                            }
                        }) {
                            Some(i) if self.vars[i].kind == VarKind::Differential => {
                                Some(Expr::der(i))
                            }
                            Some(_) if self.dupes.contains(v) => None,
                            Some(_) => {
                                errors.push(
                                    *vspan,
                                    format!("`der({v})`: `{v}` is algebraic; only differential unknowns have derivatives"),
                                );
                                None
                            }
                            None if self.dupes.contains(v) => None,
                            None => {
                                errors.push(
                                    *vspan,
                                    format!("`der({v})`: `{v}` is not an unknown of this model"),
                                );
                                None
                            }
                        },
                        other => {
                            errors.push(
                                other.span(),
                                "`der(…)` takes the name of a differential unknown",
                            );
                            None
                        }
                    };
                }
                let arg = self.lower(&args[0], errors)?;
                let f = match name.as_str() {
                    "sin" => Func::Sin,
                    "cos" => Func::Cos,
                    "tan" => Func::Tan,
                    "exp" => Func::Exp,
                    "ln" => Func::Ln,
                    "sqrt" => return Some(expr::sqrt(&arg)),
                    _ => {
                        errors.push(
                            *span,
                            format!(
                                "unknown function `{name}` (known: {}, der)",
                                FUNCTIONS.join(", ")
                            ),
                        );
                        return None;
                    }
                };
                if arg.any_sym(&|s| matches!(s, Sym::Der(_))) {
                    errors.push(
                        args[0].span(),
                        format!("der() must appear linearly, not inside `{name}(…)`"),
                    );
                    return None;
                }
                Some(expr::func(f, &arg))
            }
            Ast::Neg(inner, _) => Some(expr::neg(&self.lower(inner, errors)?)),
            Ast::Bin(op, l, r, span) => {
                let a = self.lower(l, errors);
                let b = self.lower(r, errors);
                let (a, b) = (a?, b?);
                let (a_der, b_der) = (has_der(&a), has_der(&b));
                binary(*op, &a, &b, (a_der, b_der), (*span, r.span()), errors)
            }
            Ast::Chain(first, rest) => {
                // Every operand is lowered (each reports its own errors),
                // then combined in a loop: a long chain costs no stack.
                let first = self.lower(first, errors);
                let operands: Vec<Option<Expr>> =
                    rest.iter().map(|(_, r, _)| self.lower(r, errors)).collect();
                let mut acc = first?;
                let operands: Vec<Expr> = operands.into_iter().collect::<Option<_>>()?;
                if matches!(rest.first(), Some((BinOp::Add | BinOp::Sub, ..))) {
                    // One canonical sum of all terms, not a sum rebuilt per
                    // term.
                    let mut terms = Vec::with_capacity(operands.len() + 1);
                    terms.push(acc);
                    for ((op, ..), e) in rest.iter().zip(operands) {
                        terms.push(if *op == BinOp::Sub { expr::neg(&e) } else { e });
                    }
                    return Some(expr::add_all(terms));
                }
                let mut acc_der = has_der(&acc);
                for ((op, r, span), b) in rest.iter().zip(operands) {
                    let b_der = has_der(&b);
                    acc = binary(*op, &acc, &b, (acc_der, b_der), (*span, r.span()), errors)?;
                    // A product can lose its der() (`der(x) * 0`): look
                    // again, but only when there was one.
                    acc_der = (acc_der || b_der) && has_der(&acc);
                }
                Some(acc)
            }
        }
    }
}

fn has_der(e: &Expr) -> bool {
    e.any_sym(&|s| matches!(s, Sym::Der(_)))
}

/// `a op b` with the checks of the language; `ders` says whether `a` and
/// `b` contain der(), `spans` are the operator's and `b`'s.
fn binary(
    op: BinOp,
    a: &Expr,
    b: &Expr,
    ders: (bool, bool),
    spans: (Span, Span),
    errors: &mut Errors,
) -> Option<Expr> {
    let (span, b_span) = spans;
    Some(match op {
        BinOp::Add => expr::add(a, b),
        BinOp::Sub => expr::sub(a, b),
        BinOp::Mul => {
            if ders.0 && ders.1 {
                errors.push(
                    span,
                    "product of two der() terms: der() must appear linearly",
                );
                return None;
            }
            expr::mul(a, b)
        }
        BinOp::Div => {
            if ders.1 {
                errors.push(
                    b_span,
                    "division by a der() term: der() must appear linearly",
                );
                return None;
            }
            if b.is_zero() {
                errors.push(b_span, "division by zero");
                return None;
            }
            expr::div(a, b)
        }
        BinOp::Pow => {
            if ders.0 || ders.1 {
                errors.push(span, "power of a der() term: der() must appear linearly");
                return None;
            }
            if a.is_zero() && b.as_num().is_some_and(num_traits::Signed::is_negative) {
                errors.push(span, "zero to a negative power");
                return None;
            }
            expr::pow(a, b)
        }
    })
}

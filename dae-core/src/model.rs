//! The checked model: names resolved, equations split into dynamic
//! equations `c · der(u) = f` and constraints `0 = g`, every node keeping the
//! span it came from.
//!
//! Definitions (`definitions { r2 = x^2 + y^2; }`) are resolved here and
//! leave no trace in the symbolic model: each use is replaced by the
//! definition's lowered expression, exactly as if it had been written out
//! in parentheses, so hidden constraints, formulations and Jacobians are
//! those of the pasted model. They are kept in [`Model::definitions`] for
//! reports only.
//!
//! Derived parameters (`derived { k = m * l^2 / 2; }`) stay symbols: they
//! are parameters `Sym::Param(k)` after the base ones, with
//! [`ParamDef::derived`] their expression in the base parameters. Back ends
//! compute their values from the base parameters (when a model is built or
//! a base parameter is set), never per evaluation, and refuse to set them.

use crate::dsl::{Ast, BinOp, Errors, ModelAst, Name};
use crate::expr::{self, Expr, Func, Sym};
use crate::system::{VarKind, FORMULATION_NAMES};
use proc_macro2::Span;
use std::collections::{BTreeSet, HashMap, HashSet};

/// A parameter with its default.
#[derive(Clone, Debug)]
pub struct ParamDef {
    /// Name.
    pub name: String,
    /// Default value (of a derived parameter: its value at the base
    /// parameters' defaults).
    pub default: f64,
    /// Declaration span.
    pub span: Span,
    /// `Some(expr)` for a derived parameter: its value as an expression of
    /// the base parameters only (earlier derived parameters substituted).
    pub derived: Option<Expr>,
}

/// A definition: a named expression substituted at every use.
#[derive(Clone, Debug)]
pub struct DefinitionDef {
    /// Name.
    pub name: String,
    /// The expression, definitions inside it already substituted.
    pub expr: Expr,
    /// Span of the name.
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

/// `coef · der(var) + Σ c_k · der(u_k) = rhs`.
///
/// Most dynamic equations give the derivative of one unknown. A row of a
/// mass matrix `M(q) v' = f` holds several; it is then assigned to one of
/// them (`var`, by a matching of equations to derivatives) and the others are
/// in `coupled`.
#[derive(Clone, Debug)]
pub struct Dynamic {
    /// The differential unknown this equation is assigned to.
    pub var: usize,
    /// Coefficient of `der(var)` (free of derivatives, of `t` and of
    /// algebraic unknowns).
    pub coef: Expr,
    /// The other der() terms `(unknown, coefficient)`, ascending; empty
    /// unless the equation is a row of a mass matrix.
    pub coupled: Vec<(usize, Expr)>,
    /// Right-hand side.
    pub rhs: Expr,
    /// Span of the equation.
    pub span: Span,
}

impl Dynamic {
    /// Every der() term `(unknown, coefficient)`: `var`'s first, then the
    /// coupled ones.
    pub fn terms(&self) -> impl Iterator<Item = (usize, &Expr)> {
        std::iter::once((self.var, &self.coef)).chain(self.coupled.iter().map(|(j, c)| (*j, c)))
    }
}

/// A dynamic equation as written, before it is assigned to an unknown: its
/// der() terms `(unknown, coefficient)`, right-hand side and span.
type Written = (Vec<(usize, Expr)>, Expr, Span);

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

/// A named event function (`events { hit = x + 0.5; }`): each zero
/// crossing of `expr` along a solution is an event. The same shape as an
/// invariant.
pub type EventDef = InvariantDef;

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
    /// Parameters in order: the base ones (`parameters { … }`), then the
    /// derived ones (`derived { … }`).
    pub params: Vec<ParamDef>,
    /// Number of base parameters (the first `n_base` of `params`); the
    /// others are derived.
    pub n_base: usize,
    /// Definitions in order (already substituted wherever used).
    pub definitions: Vec<DefinitionDef>,
    /// Unknowns: differential first (declaration order), then algebraic.
    pub vars: Vec<VarDef>,
    /// Number of differential unknowns (the first `n_diff` of `vars`).
    pub n_diff: usize,
    /// Dynamic equations in the order of the unknowns they are assigned
    /// to: one per differential unknown, except the implicit ones.
    pub dynamics: Vec<Dynamic>,
    /// Differential unknowns without a dynamic equation of their own
    /// (ascending): their der() appears only in rows assigned to other
    /// unknowns (`y1' + η t y2' = …`), and the constraints determine them,
    /// as they determine the algebraic unknowns.
    pub implicit: Vec<usize>,
    /// `coupled[j]`: differential unknown `j` is an unknown of a mass
    /// matrix (its der() shares an equation with another der()). Empty when
    /// the model has no mass matrix.
    pub coupled: Vec<bool>,
    /// Constraints in order.
    pub constraints: Vec<ConstraintDef>,
    /// Invariants in order.
    pub invariants: Vec<InvariantDef>,
    /// Event functions in order.
    pub events: Vec<EventDef>,
    /// Requested formulations (`None`: all that apply).
    pub requested: Option<Vec<Name>>,
}

/// Names of the elementary functions.
pub const FUNCTIONS: [&str; 6] = ["sin", "cos", "tan", "exp", "ln", "sqrt"];

/// What to say after "unknown function `name`": how to write a common
/// function the language lacks, or the known function `name` is a typo of
/// (one edit away: `sni`, `sqr`, `exq`), or nothing.
///
/// ```
/// use dae_core::model::unknown_function_hint;
/// assert_eq!(unknown_function_hint("sqr"), "; did you mean `sqrt`?");
/// assert!(unknown_function_hint("atan2").contains("no inverse trigonometric"));
/// assert!(unknown_function_hint("log").contains("`ln`"));
/// assert_eq!(unknown_function_hint("frobnicate"), "");
/// ```
pub fn unknown_function_hint(name: &str) -> String {
    let advice = match name {
        "log" => Some("the natural logarithm is `ln`"),
        "log10" => Some("write `ln(x) / ln(10)`"),
        "log2" => Some("write `ln(x) / ln(2)`"),
        "pow" => Some("powers are written `x^y`"),
        "sinh" => Some("`sinh(x)` is `(exp(x) - exp(-x)) / 2`"),
        "cosh" => Some("`cosh(x)` is `(exp(x) + exp(-x)) / 2`"),
        "tanh" => Some("`tanh(x)` is `(exp(x) - exp(-x)) / (exp(x) + exp(-x))`"),
        "asin" | "acos" | "atan" | "atan2" | "arcsin" | "arccos" | "arctan" => Some(
            "there are no inverse trigonometric functions: write the model in \
             coordinates, or make the angle an unknown",
        ),
        _ => None,
    };
    if let Some(advice) = advice {
        return format!("; {advice}");
    }
    let known: Vec<&str> = FUNCTIONS.iter().copied().chain(["der"]).collect();
    crate::names::did_you_mean(name, &known)
        .map(|known| format!("; did you mean `{known}`?"))
        .unwrap_or_default()
}

/// The name of time, which no parameter or unknown may take.
pub const TIME: &str = "t";

impl Model {
    /// Check a parsed model; every problem is reported, each at its token.
    ///
    /// The phases, in order: names declared (`declare_names`), derived
    /// parameters lowered (`derive_parameters`), definitions lowered
    /// (`lower_definitions`), equations lowered and split into dynamic
    /// rows and constraints (`lower_equations`), dynamic rows assigned to
    /// the derivatives they give (`assign_dynamics`), equations counted
    /// against unknowns (`check_counts`), invariants and the formulation
    /// list. Each phase reports into the same [`Errors`].
    pub fn check(ast: &ModelAst) -> Result<Model, syn::Error> {
        let _budget = expr::Budget::start(expr::WORK_BUDGET);
        let mut errors = Errors::default();
        let mut decl = declare_names(ast, &mut errors);
        derive_parameters(&mut decl, &mut errors);
        let Declared {
            params,
            n_base,
            vars,
            n_diff,
            def_decls,
            dupes,
            ..
        } = decl;
        let (scope, definitions) =
            lower_definitions(&params, &vars, dupes, &def_decls, &mut errors);
        let Lowered {
            constraints,
            written,
            mut lowered_all,
        } = lower_equations(ast, &scope, &vars, n_diff, &mut errors);
        let (dyns, coupled, implicit) =
            assign_dynamics(&written, &vars, n_diff, &mut lowered_all, &mut errors);
        check_counts(
            &vars,
            n_diff,
            &implicit,
            &dyns,
            &constraints,
            lowered_all,
            &mut errors,
        );
        let invariants = lower_invariants(ast, &scope, &mut errors);
        let events = lower_events(ast, &scope, &mut errors);
        check_formulation_list(ast, &mut errors);
        errors.finish(Model {
            name: ast.name.name.clone(),
            name_span: ast.name.span,
            doc: ast.doc.clone(),
            public: ast.public,
            params,
            n_base,
            definitions,
            vars,
            n_diff,
            dynamics: dyns,
            implicit,
            coupled: if coupled.iter().any(|&c| c) {
                coupled
            } else {
                Vec::new()
            },
            constraints,
            invariants,
            events,
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

    /// The unknowns' rates `der(u) = f/c` for the total time derivative;
    /// an unknown of a mass matrix keeps its `der(u)` (its rate is
    /// `M⁻¹ f`, never formed symbolically). `Err(s)` when `s` has no rate
    /// (an algebraic unknown, or a der() itself).
    pub fn rate(&self, s: Sym) -> Result<Option<Expr>, Sym> {
        match s {
            Sym::Var(i) if self.is_coupled(i as usize) || self.is_implicit(i as usize) => {
                Ok(Some(Expr::der(i as usize)))
            }
            Sym::Var(i) if (i as usize) < self.n_diff => {
                let Some(d) = self.dynamic(i as usize) else {
                    return Err(s);
                };
                // `c u' + Σ c_k y_k' = f` with the y_k implicit (no rate
                // of their own): `u' = (f − Σ c_k y_k') / c`.
                let rest =
                    expr::add_all(d.coupled.iter().map(|(k, c)| expr::mul(c, &Expr::der(*k))));
                Ok(Some(expr::div(&expr::sub(&d.rhs, &rest), &d.coef)))
            }
            Sym::Param(_) => Ok(None),
            Sym::Time => Ok(Some(Expr::one())),
            _ => Err(s),
        }
    }

    /// `true` when differential unknown `j` is an unknown of a mass matrix:
    /// its der() shares an equation with another der().
    pub fn is_coupled(&self, j: usize) -> bool {
        self.coupled.get(j).copied().unwrap_or(false)
    }

    /// `true` when any dynamic equation holds a mass-matrix row.
    pub fn has_mass_matrix(&self) -> bool {
        !self.coupled.is_empty()
    }

    /// Whether `e` holds the der() of a mass-matrix unknown whose block's
    /// equations contain a symbol of `pred`.
    fn involves_through_mass(&self, e: &Expr, pred: &dyn Fn(Sym) -> bool) -> bool {
        self.has_mass_matrix()
            && e.symbols().into_iter().any(|d| match d {
                Sym::Der(j) if self.is_coupled(j as usize) => self
                    .block(j as usize)
                    .iter()
                    .any(|&k| self.row_involves(k, pred)),
                _ => false,
            })
    }

    /// Whether the dynamic row of unknown `k` contains a symbol of `pred`.
    fn row_involves(&self, k: usize, pred: &dyn Fn(Sym) -> bool) -> bool {
        self.dynamic(k)
            .is_some_and(|d| d.rhs.any_sym(pred) || d.terms().any(|(_, c)| c.any_sym(pred)))
    }

    /// The dynamic equation assigned to differential unknown `j`; `None`
    /// for an implicit one (see [`Model::implicit`]) or an algebraic one.
    pub fn dynamic(&self, j: usize) -> Option<&Dynamic> {
        // Sorted by the unknown they are assigned to.
        self.dynamics
            .binary_search_by_key(&j, |d| d.var)
            .ok()
            .map(|k| &self.dynamics[k])
    }

    /// `true` when differential unknown `j` has no dynamic equation of its
    /// own (see [`Model::implicit`]).
    pub fn is_implicit(&self, j: usize) -> bool {
        self.implicit.binary_search(&j).is_ok()
    }

    /// The unknowns the constraints determine: the implicit differential
    /// ones, then the algebraic ones, ascending.
    pub fn determined(&self) -> Vec<usize> {
        self.implicit
            .iter()
            .copied()
            .chain(self.n_diff..self.vars.len())
            .collect()
    }

    /// The mass-matrix block of coupled unknown `j`: the unknowns linked to
    /// it through shared equations, ascending (empty if `j` is not coupled).
    pub fn block(&self, j: usize) -> Vec<usize> {
        if !self.is_coupled(j) {
            return Vec::new();
        }
        let mut block = vec![j];
        let mut grew = true;
        while grew {
            grew = false;
            for d in &self.dynamics {
                let row: Vec<usize> = d.terms().map(|(k, _)| k).collect();
                if row.iter().any(|k| block.contains(k)) {
                    for k in row {
                        if !block.contains(&k) {
                            block.push(k);
                            grew = true;
                        }
                    }
                }
            }
        }
        block.sort_unstable();
        block
    }

    /// `true` when `e` depends on `s`: directly, or through the der() of a
    /// mass-matrix unknown, whose value `M⁻¹ f` depends on everything the
    /// equations of its block contain.
    pub fn involves(&self, e: &Expr, s: Sym) -> bool {
        e.contains(s) || self.involves_through_mass(e, &|x| x == s)
    }

    /// Every symbol `s` with [`Model::involves`]`(e, s)`, ascending: those
    /// of `e`, and through a mass matrix those of the dynamic rows of the
    /// coupled blocks whose der() `e` holds.
    pub fn involved(&self, e: &Expr) -> BTreeSet<Sym> {
        let mut out: BTreeSet<Sym> = e.symbols().into_iter().collect();
        if self.has_mass_matrix() {
            for d in e.symbols() {
                let Sym::Der(j) = d else { continue };
                if !self.is_coupled(j as usize) {
                    continue;
                }
                for k in self.block(j as usize) {
                    if let Some(row) = self.dynamic(k) {
                        out.extend(row.rhs.symbols());
                        for (_, c) in row.terms() {
                            out.extend(c.symbols());
                        }
                    }
                }
            }
        }
        out
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
        let mut scope = Scope::new(&self.params, &self.vars, HashSet::new());
        for d in &self.definitions {
            scope.defs.insert(d.name.clone(), d.expr.clone());
        }
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

/// The names a model declares, after [`declare_names`].
struct Declared<'a> {
    params: Vec<ParamDef>,
    n_base: usize,
    /// `derived_asts[k]` is the expression of `params[n_base + k]`.
    derived_asts: Vec<&'a crate::dsl::NamedExpr>,
    vars: Vec<VarDef>,
    n_diff: usize,
    def_decls: Vec<&'a crate::dsl::NamedExpr>,
    /// Names declared twice or reserved: uses of them raise no further
    /// errors.
    dupes: HashSet<String>,
}

/// Phase 1: every name declared once, none reserved; parameters with
/// finite defaults, unknowns, definitions (not yet lowered).
fn declare_names<'a>(ast: &'a ModelAst, errors: &mut Errors) -> Declared<'a> {
    // Hash maps for lookups only (never iterated): linear in the names.
    let mut seen: HashMap<String, (Span, &'static str)> = HashMap::new();
    // Names declared twice or reserved: uses of them raise no further
    // errors.
    let mut dupes: HashSet<String> = HashSet::new();
    let mut declare = |n: &Name, kind: &'static str, errors: &mut Errors| {
        if let Some((first, first_kind)) = seen.get(&n.name) {
            let named = [DEFINITION, DERIVED];
            if named.contains(&kind) || named.contains(first_kind) {
                errors.push(
                    n.span,
                    format!("{kind} `{}` clashes with the {first_kind} `{}`: every name of a model is unique", n.name, n.name),
                );
                errors.push(
                    *first,
                    format!("the {first_kind} `{}` is declared here", n.name),
                );
            } else {
                errors.push(n.span, format!("`{}` is declared twice", n.name));
                errors.push(*first, format!("`{}` is first declared here", n.name));
            }
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
        seen.insert(n.name.clone(), (n.span, kind));
        true
    };
    let mut params = Vec::new();
    for p in &ast.parameters {
        if declare(&p.name, "parameter", errors) {
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
                derived: None,
            });
        }
    }
    let n_base = params.len();
    // Derived parameters are declared now and lowered once every name
    // is known; `derived_asts[k]` is the expression of `params[n_base + k]`.
    let mut derived_asts = Vec::new();
    for d in &ast.derived {
        if declare(&d.name, DERIVED, errors) {
            params.push(ParamDef {
                name: d.name.name.clone(),
                default: f64::NAN,
                span: d.name.span,
                derived: None,
            });
            derived_asts.push(d);
        }
    }
    // Differential unknowns first, then algebraic ones.
    let mut vars = Vec::new();
    let mut n_diff = 0;
    for (names, kind, what) in [
        (
            &ast.differential,
            VarKind::Differential,
            "differential unknown",
        ),
        (&ast.algebraic, VarKind::Algebraic, "algebraic unknown"),
    ] {
        for n in names {
            if declare(n, what, errors) {
                vars.push(VarDef {
                    name: n.name.clone(),
                    kind,
                    span: n.span,
                });
            }
        }
        if kind == VarKind::Differential {
            n_diff = vars.len();
        }
    }
    if n_diff == 0 {
        errors.push(
            ast.name.span,
            format!("model `{}` is empty: it needs `differential {{ … }}` unknowns and `equations {{ … }}`", ast.name.name),
        );
    }

    let mut def_decls = Vec::new();
    for d in &ast.definitions {
        if declare(&d.name, DEFINITION, errors) {
            def_decls.push(d);
        }
    }
    Declared {
        params,
        n_base,
        derived_asts,
        vars,
        n_diff,
        def_decls,
        dupes,
    }
}

/// Phase 2: derived parameters, in order, each an expression of the base
/// parameters (earlier derived ones substituted), with its default.
fn derive_parameters(decl: &mut Declared<'_>, errors: &mut Errors) {
    let Declared {
        params,
        n_base,
        derived_asts,
        vars,
        def_decls,
        dupes,
        ..
    } = decl;
    let n_base = *n_base;
    // Derived parameters, in order: each an expression of the base
    // parameters and of earlier derived ones.
    let mut derived_exprs: Vec<Option<Expr>> = Vec::new();
    let base_defaults: Vec<f64> = params.iter().map(|p| p.default).collect();
    let mut derived_defaults = Vec::new();
    {
        let mut scope = Scope::new(params, vars, dupes.clone());
        scope.forward = derived_asts.iter().map(|d| (*d).clone()).collect();
        scope.definition_names = def_decls.iter().map(|d| d.name.name.clone()).collect();
        for (k, d) in derived_asts.iter().enumerate() {
            scope.mode = Mode::Derived(k, n_base);
            let Some(e) = scope.lower(&d.expr, errors) else {
                derived_exprs.push(None);
                continue;
            };
            // In the base parameters only.
            let base = expr::subs(&e, &|s| match s {
                Sym::Param(j) if j as usize >= n_base => Some(
                    derived_exprs[j as usize - n_base]
                        .clone()
                        .unwrap_or_else(Expr::zero),
                ),
                _ => None,
            });
            let value = base.eval(&|s| match s {
                Sym::Param(j) => base_defaults[j as usize],
                _ => f64::NAN,
            });
            if !value.is_finite() {
                errors.push(
                    d.name.span,
                    format!(
                        "derived parameter `{}` is {value} at the parameters' defaults",
                        d.name.name
                    ),
                );
            }
            derived_defaults.push((n_base + k, value));
            derived_exprs.push(Some(base));
        }
    }
    for (k, value) in derived_defaults {
        params[k].default = value;
    }
    for (k, e) in derived_exprs.into_iter().enumerate() {
        params[n_base + k].derived = Some(e.unwrap_or_else(Expr::zero));
    }
}

/// Phase 3: definitions, in order, each lowered once; the scope every
/// later expression is lowered in.
fn lower_definitions<'a>(
    params: &'a [ParamDef],
    vars: &'a [VarDef],
    dupes: HashSet<String>,
    def_decls: &[&crate::dsl::NamedExpr],
    errors: &mut Errors,
) -> (Scope<'a>, Vec<DefinitionDef>) {
    let mut scope = Scope::new(params, vars, dupes);
    // Definitions, in order: each lowered once and substituted at
    // every later use.
    scope.forward = def_decls.iter().map(|d| (*d).clone()).collect();
    let mut definitions = Vec::new();
    scope.forward_index = def_decls
        .iter()
        .enumerate()
        .map(|(k, d)| (d.name.name.clone(), k))
        .collect();
    for (k, d) in def_decls.iter().enumerate() {
        scope.mode = Mode::Definition(k);
        if expr::exhausted() {
            // The budget is spent (reported once, at the definition that
            // spent it): the rest stay quiet.
            scope.failed.insert(d.name.name.clone());
            continue;
        }
        let lowered = scope
            .lower(&d.expr, errors)
            .and_then(|e| match expr::check_growth(&e) {
                Ok(()) => Some(e),
                Err(grew) => {
                    errors.push(
                        d.name.span,
                        format!("{DEFINITION} `{}` {grew}", d.name.name),
                    );
                    None
                }
            })
            .filter(|e| check_constants(e, d.name.span, errors));
        match lowered {
            Some(e) => {
                scope.defs.insert(d.name.name.clone(), e.clone());
                definitions.push(DefinitionDef {
                    name: d.name.name.clone(),
                    expr: e,
                    span: d.name.span,
                });
            }
            None => {
                // Already reported: uses of it stay quiet.
                scope.failed.insert(d.name.name.clone());
            }
        }
    }
    scope.mode = Mode::Model;
    let scope = scope;
    (scope, definitions)
}

/// The equations after [`lower_equations`].
struct Lowered {
    constraints: Vec<ConstraintDef>,
    /// Dynamic equations as written, before assignment.
    written: Vec<Written>,
    /// `false` when an equation failed to lower (already reported): counts
    /// are then meaningless.
    lowered_all: bool,
}

/// Phase 4: every equation lowered; those without der() are constraints,
/// the others dynamic equations whose der() terms are checked (linear, with
/// coefficients free of der() and of algebraic unknowns; they may depend on `t`, the leading matrix is `E(t, y)`).
fn lower_equations(
    ast: &ModelAst,
    scope: &Scope<'_>,
    vars: &[VarDef],
    n_diff: usize,
    errors: &mut Errors,
) -> Lowered {
    let mut constraints = Vec::new();
    // Dynamic equations as written: every der() term with its
    // coefficient, assigned to unknowns below.
    let mut written: Vec<Written> = Vec::new();
    // An equation that failed to lower already has its error; counting
    // equations afterwards would only add a cascade of "too few".
    let mut lowered_all = true;
    for eq in &ast.equations {
        if expr::exhausted() {
            // Reported once, where the budget was spent.
            lowered_all = false;
            continue;
        }
        let (Some(lhs), Some(rhs)) = (scope.lower(&eq.lhs, errors), scope.lower(&eq.rhs, errors))
        else {
            lowered_all = false;
            continue;
        };
        // Equation-level errors point at the equation's first token.
        let eq_span = eq.lhs.span();
        let r = expr::sub(&lhs, &rhs);
        if let Err(grew) = expr::check_growth(&r) {
            errors.push(eq_span, format!("this equation {grew}"));
            lowered_all = false;
            continue;
        }
        if !check_constants(&r, eq_span, errors) {
            lowered_all = false;
            continue;
        }
        let (ders, rest) = expr::split_ders(&r);
        if ders.is_empty() {
            let g = if lhs.is_zero() {
                rhs
            } else {
                expr::sub(&lhs, &rhs)
            };
            if g.any_sym(&|s| matches!(s, Sym::Var(_))) {
                constraints.push(ConstraintDef {
                    expr: g,
                    span: eq_span,
                });
            } else {
                errors.push(eq_span, "this equation involves no unknown");
            }
            continue;
        }
        let mut ok = true;
        for (j, coef) in &ders {
            let name = &vars[*j].name;
            let problem = if coef.any_sym(&|s| matches!(s, Sym::Der(_))) {
                Some(if ders.len() == 1 {
                    format!("`der({name})` must appear linearly: write `coef * der({name}) = rhs` with a coefficient free of der()")
                } else {
                    format!("`der({name})` must appear linearly: write `a*der({name}) + b*der(…) = rhs` with coefficients free of der()")
                })
            } else if coef.is_zero() {
                Some(format!("the coefficient of `der({name})` vanishes"))
            } else {
                (n_diff..vars.len())
                    .find(|&a| coef.contains(Sym::Var(a as u32)))
                    .map(|a| format!(
                        "the coefficient of `der({name})` depends on the algebraic unknown `{}`: a coefficient of der() may depend on parameters and positions only",
                        vars[a].name
                    ))
            };
            if let Some(msg) = problem {
                errors.push(eq_span, msg);
                ok = false;
                break;
            }
        }
        if !ok {
            lowered_all = false;
            continue;
        }
        written.push((ders, expr::neg(&rest), eq_span));
    }
    Lowered {
        constraints,
        written,
        lowered_all,
    }
}

/// Phase 5: every dynamic equation assigned to a derivative it gives (a
/// matching; where no perfect one exists, one that prefers constant
/// coefficients); differential unknowns left without an equation of their
/// own are implicit when their der() appears in some row. The rows of a
/// mass matrix (several der() of assigned unknowns) may not depend on its
/// velocities. Returns the dynamic equations in unknown order, which
/// unknowns are coupled, and the implicit ones.
fn assign_dynamics(
    written: &[Written],
    vars: &[VarDef],
    n_diff: usize,
    lowered_all: &mut bool,
    errors: &mut Errors,
) -> (Vec<Dynamic>, Vec<bool>, Vec<usize>) {
    // Assign equations to unknowns: a perfect matching between the
    // dynamic equations and the derivatives they contain (a structurally
    // nonsingular mass matrix has one).
    let adj: Vec<Vec<usize>> = written
        .iter()
        .map(|(terms, _, _)| terms.iter().map(|(j, _)| *j).collect())
        .collect();
    let mut assign = crate::index::max_matching(&adj, n_diff);
    if assign.iter().any(Option::is_none) {
        // Some derivative has no equation of its own: the unknowns that
        // keep one should be those with the simplest coefficients (a
        // number before a parameter before an expression of unknowns or
        // `t`), so that their rates divide by no vanishing coefficient.
        let rank = |c: &Expr| {
            if c.as_num().is_some() {
                0
            } else if !c.any_sym(&|s| matches!(s, Sym::Var(_) | Sym::Time)) {
                1
            } else {
                2
            }
        };
        let preferred: Vec<Vec<usize>> = written
            .iter()
            .map(|(terms, _, _)| {
                let mut t: Vec<(usize, usize)> = terms.iter().map(|(j, c)| (rank(c), *j)).collect();
                t.sort();
                t.into_iter().map(|(_, j)| j).collect()
            })
            .collect();
        assign = crate::index::max_matching(&preferred, n_diff);
    }
    let mut dynamics: Vec<Option<Dynamic>> = vec![None; n_diff];
    let mut placed = vec![false; written.len()];
    for (j, owner) in assign.iter().enumerate() {
        if let Some(e) = owner {
            let (terms, rhs, span) = &written[*e];
            placed[*e] = true;
            let coef = terms.iter().find(|(k, _)| *k == j).map(|(_, c)| c.clone());
            dynamics[j] = Some(Dynamic {
                var: j,
                coef: coef.unwrap_or_else(Expr::one),
                coupled: terms.iter().filter(|(k, _)| *k != j).cloned().collect(),
                rhs: rhs.clone(),
                span: *span,
            });
        }
    }
    for (e, (terms, _, span)) in written.iter().enumerate() {
        if placed[e] {
            continue;
        }
        *lowered_all = false;
        if let [(j, _)] = terms.as_slice() {
            errors.push(
                *span,
                format!(
                    "a second equation for `der({})`: each differential unknown has exactly one",
                    vars[*j].name
                ),
            );
        } else {
            errors.push(
                *span,
                format!(
                    "structurally singular mass matrix: the equations with der() of {} give fewer independent derivatives than equations",
                    terms.iter().map(|(j, _)| format!("`{}`", vars[*j].name)).collect::<Vec<_>>().join(", ")
                ),
            );
        }
    }
    // Implicit: no equation of their own, der() in some row.
    let in_rows = |j: usize| {
        written
            .iter()
            .any(|(t, _, _)| t.iter().any(|(k, _)| *k == j))
    };
    let implicit: Vec<usize> = (0..n_diff)
        .filter(|&j| dynamics[j].is_none() && in_rows(j))
        .collect();
    // Coupled unknowns: those whose der() shares an equation with another
    // assigned unknown's der() (a mass matrix). A coefficient in such an
    // equation may not depend on a coupled unknown (a velocity).
    let assigned = |j: &usize| dynamics[*j].is_some();
    let mut coupled = vec![false; n_diff];
    for (terms, _, _) in written {
        let own: Vec<usize> = terms.iter().map(|(j, _)| *j).filter(assigned).collect();
        if own.len() > 1 {
            for j in own {
                coupled[j] = true;
            }
        }
    }
    for (terms, _, span) in written {
        if terms.iter().map(|(j, _)| *j).filter(assigned).count() < 2 {
            continue;
        }
        for (j, c) in terms {
            if let Some(k) = (0..n_diff).find(|&k| coupled[k] && c.contains(Sym::Var(k as u32))) {
                errors.push(
                    *span,
                    format!(
                        "the coefficient of `der({})` depends on `{}`, whose der() appears with others (a velocity): a mass matrix may depend on parameters and positions only",
                        vars[*j].name, vars[k].name
                    ),
                );
                *lowered_all = false;
            }
        }
    }
    let mut dyns = Vec::new();
    for (j, d) in dynamics.into_iter().enumerate() {
        match d {
            Some(d) => dyns.push(d),
            None if !*lowered_all || implicit.contains(&j) => {}
            None => errors.push(
                vars[j].span,
                format!(
                    "too few equations: no equation gives `der({})`",
                    vars[j].name
                ),
            ),
        }
    }
    (dyns, coupled, implicit)
}

/// Phase 6: one constraint per unknown the constraints determine (the
/// algebraic ones and the implicit differential ones), and every algebraic
/// unknown in some equation.
fn check_counts(
    vars: &[VarDef],
    n_diff: usize,
    implicit: &[usize],
    dyns: &[Dynamic],
    constraints: &[ConstraintDef],
    lowered_all: bool,
    errors: &mut Errors,
) {
    let n_alg = vars.len() - n_diff;
    let wanted = n_alg + implicit.len();
    // Who the constraints are for, as the messages name them.
    let determined = || {
        if implicit.is_empty() {
            format!(
                "{n_alg} algebraic unknown{}",
                if n_alg == 1 { "" } else { "s" }
            )
        } else {
            let names: Vec<String> = implicit
                .iter()
                .map(|&j| format!("`{}`", vars[j].name))
                .collect();
            format!(
                "{wanted} unknowns they determine ({n_alg} algebraic, and {} whose der() has no equation of its own)",
                names.join(", ")
            )
        }
    };
    if !lowered_all {
        // Counts are meaningless with equations missing.
    } else if constraints.len() > wanted {
        for c in &constraints[wanted..] {
            errors.push(
                c.span,
                format!(
                    "too many equations: {} constraints for {} (a semi-explicit model has one constraint per algebraic unknown)",
                    constraints.len(),
                    determined()
                ),
            );
        }
    } else if constraints.len() < wanted {
        if implicit.is_empty() {
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
        } else {
            for &j in implicit {
                errors.push(
                    vars[j].span,
                    format!(
                        "too few equations: no equation gives `der({})`, so the constraints must determine it, but there are {} constraints for {}",
                        vars[j].name,
                        constraints.len(),
                        determined()
                    ),
                );
            }
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
}

/// Phase 7: invariants, each named once and free of der().
fn lower_invariants(ast: &ModelAst, scope: &Scope<'_>, errors: &mut Errors) -> Vec<InvariantDef> {
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
        if let Some(e) = scope.lower(&inv.expr, errors) {
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
    invariants
}

/// Phase 7b: event functions, each named once, free of der(), and not
/// identically zero (after canonicalisation: `x - x` is refused, as it has
/// no crossing to locate).
fn lower_events(ast: &ModelAst, scope: &Scope<'_>, errors: &mut Errors) -> Vec<EventDef> {
    let mut events = Vec::new();
    let mut names: HashMap<&str, Span> = HashMap::new();
    for ev in &ast.events {
        let name = ev.name.name.as_str();
        if let Some(first) = names.get(name) {
            errors.push(ev.name.span, format!("event `{name}` is declared twice"));
            errors.push(*first, format!("event `{name}` is first declared here"));
            continue;
        }
        names.insert(name, ev.name.span);
        let Some(e) = scope.lower(&ev.expr, errors) else {
            continue;
        };
        if e.any_sym(&|s| matches!(s, Sym::Der(_))) {
            errors.push(ev.expr.span(), "event functions may not contain der()");
            continue;
        }
        if e.is_zero() {
            errors.push(
                ev.expr.span(),
                format!("event `{name}` is identically zero: it has no crossing to locate"),
            );
            continue;
        }
        events.push(EventDef {
            name: ev.name.name.clone(),
            expr: e,
            span: ev.name.span,
        });
    }
    events
}

/// Phase 8: a `formulations { … }` list names known formulations, once each.
fn check_formulation_list(ast: &ModelAst, errors: &mut Errors) {
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
            errors.push(
                ast.body_span,
                "`formulations { }` is empty: list at least one, or leave the block out for all",
            );
        }
    }
}

/// What `definition` is called in messages.
const DEFINITION: &str = "definition";
/// What a derived parameter is called in messages.
const DERIVED: &str = "derived parameter";

/// What is being lowered: the names it may use differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// An equation or invariant: every name.
    Model,
    /// Definition `k` (of `Scope::forward`): parameters, unknowns, `t` and
    /// definitions before it; no der().
    Definition(usize),
    /// Derived parameter `k` (parameter `n_base + k`, expression
    /// `Scope::forward[k]`): parameters and derived parameters before it.
    Derived(usize, usize),
}

struct Scope<'a> {
    params: &'a [ParamDef],
    vars: &'a [VarDef],
    /// Every declared name.
    names: HashMap<&'a str, Sym>,
    /// Names declared twice or reserved (already reported).
    dupes: HashSet<String>,
    /// Definitions lowered so far.
    defs: HashMap<String, Expr>,
    /// Definitions that failed to lower (already reported).
    failed: HashSet<String>,
    /// Every definition's name (for messages about derived parameters,
    /// lowered before the definitions).
    definition_names: HashSet<String>,
    /// The definitions, or the derived parameters, being lowered in order:
    /// to tell a use before the definition from a cycle.
    forward: Vec<crate::dsl::NamedExpr>,
    /// Position in `forward` of each definition's name (a lookup per use,
    /// not a scan: 40,000 definitions stay linear).
    forward_index: HashMap<String, usize>,
    mode: Mode,
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
        Scope {
            params,
            vars,
            names,
            dupes,
            defs: HashMap::new(),
            failed: HashSet::new(),
            definition_names: HashSet::new(),
            forward: Vec::new(),
            forward_index: HashMap::new(),
            mode: Mode::Model,
        }
    }

    /// The message for a use of `forward[to]` while lowering `forward[from]`
    /// (`to >= from`): a self-reference, a cycle, or a use before the
    /// definition.
    fn forward_use(&self, from: usize, to: usize, what: &str) -> String {
        let name = |k: usize| self.forward[k].name.name.as_str();
        if from == to {
            return format!("{what} `{}` refers to itself", name(from));
        }
        // Depth-first from `to` through the names each expression uses,
        // looking for `from`: the path back is the cycle.
        let index: HashMap<&str, usize> = (0..self.forward.len()).map(|k| (name(k), k)).collect();
        let mut path = vec![to];
        let mut visited = HashSet::from([to]);
        let mut stack = vec![idents(&self.forward[to].expr)];
        while let Some(top) = stack.last_mut() {
            let Some(next) = top.pop() else {
                stack.pop();
                path.pop();
                continue;
            };
            let Some(&k) = index.get(next.as_str()) else {
                continue;
            };
            if k == from {
                let mut cycle = vec![name(from)];
                cycle.extend(path.iter().map(|&k| name(k)));
                cycle.push(name(from));
                return format!(
                    "{what}s form a cycle: {}",
                    cycle
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(" → ")
                );
            }
            if visited.insert(k) {
                path.push(k);
                stack.push(idents(&self.forward[k].expr));
            }
        }
        format!(
            "{what} `{}` is used before it is defined: {what}s are read in order, so move `{}` above `{}`",
            name(to),
            name(to),
            name(from)
        )
    }

    fn lookup(&self, name: &str) -> Option<Sym> {
        if let Some(s) = self.names.get(name) {
            return Some(*s);
        }
        (name == "t").then_some(Sym::Time)
    }
}

/// Every name an expression uses (not function names), last first.
fn idents(ast: &Ast) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![ast];
    while let Some(a) = stack.pop() {
        match a {
            Ast::Num(..) => {}
            Ast::Ident(n, _) => out.push(n.clone()),
            Ast::Call(_, _, args) => stack.extend(args.iter()),
            Ast::Neg(e, _) => stack.push(e),
            Ast::Bin(_, l, r, _) => {
                stack.push(l);
                stack.push(r);
            }
            Ast::Chain(first, rest) => {
                stack.push(first);
                stack.extend(rest.iter().map(|(_, e, _)| e));
            }
        }
    }
    out.reverse();
    out
}

impl Scope<'_> {
    /// A name of a definition or derived parameter not (yet) usable here;
    /// `None` when it may be resolved normally.
    fn restricted(&self, name: &str) -> Option<Option<String>> {
        match self.mode {
            Mode::Model => None,
            Mode::Definition(from) => {
                if self.failed.contains(name) {
                    return Some(None);
                }
                let to = *self.forward_index.get(name)?;
                (to >= from).then(|| Some(self.forward_use(from, to, DEFINITION)))
            }
            Mode::Derived(from, n_base) => {
                let d = &self.params[n_base + from].name;
                let why = match self.names.get(name) {
                    Some(Sym::Param(k)) if (*k as usize) < n_base + from => return None,
                    Some(Sym::Param(k)) => {
                        return Some(Some(self.forward_use(from, *k as usize - n_base, DERIVED)))
                    }
                    Some(Sym::Var(_)) => format!("`{name}` is an unknown"),
                    Some(_) => return None,
                    None if name == TIME => "time `t` is not".into(),
                    None if self.definition_names.contains(name) => {
                        format!("`{name}` is a definition")
                    }
                    None => return None,
                };
                Some(Some(format!(
                    "derived parameter `{d}` may depend on parameters only, and {why}"
                )))
            }
        }
    }

    fn lower(&self, ast: &Ast, errors: &mut Errors) -> Option<Expr> {
        match ast {
            Ast::Num(v, _) => Some(Expr::num(v.clone())),
            Ast::Ident(name, span) => match self.restricted(name) {
                Some(Some(msg)) => {
                    errors.push(*span, msg);
                    None
                }
                Some(None) => None,
                None => self.lookup_expr(name, *span, errors),
            },
            Ast::Call(name, span, args) if name == "der" && self.mode != Mode::Model => {
                let _ = args;
                let what = match self.mode {
                    Mode::Definition(_) => "a definition: a definition is an expression of parameters, unknowns and `t`; write der() in the equation",
                    _ => "a derived parameter: a derived parameter is an expression of parameters",
                };
                errors.push(*span, format!("der() is not allowed in {what}"));
                None
            }
            other => self.lower_rest(other, errors),
        }
    }

    /// A name in an expression: a parameter, an unknown, `t`, or a
    /// definition (its expression).
    fn lookup_expr(&self, name: &str, span: Span, errors: &mut Errors) -> Option<Expr> {
        if let Some(s) = self.lookup(name) {
            return Some(Expr::sym(s));
        }
        if let Some(e) = self.defs.get(name) {
            return Some(e.clone());
        }
        if self.failed.contains(name) {
            return None;
        }
        let hint = if FUNCTIONS.contains(&name) || name == "der" {
            format!(" (`{name}` is a function: write `{name}(…)`)")
        } else {
            String::new()
        };
        errors.push(
            span,
            format!("unknown name `{name}`: not a parameter, an unknown or a definition of this model{hint}"),
        );
        None
    }

    fn lower_rest(&self, ast: &Ast, errors: &mut Errors) -> Option<Expr> {
        match ast {
            Ast::Num(..) | Ast::Ident(..) => self.lower(ast, errors),
            Ast::Call(name, span, args) => {
                if !FUNCTIONS.contains(&name.as_str()) && name != "der" {
                    // Unknown whatever its arguments (`atan2(u, w)`): name
                    // it, still checking the arguments' own names.
                    for arg in args {
                        self.lower(arg, errors);
                    }
                    errors.push(
                        *span,
                        format!(
                            "unknown function `{name}` (known: {}, der){}",
                            FUNCTIONS.join(", "),
                            unknown_function_hint(name)
                        ),
                    );
                    return None;
                }
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
                    // Unknown names were refused above.
                    _ => return None,
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

/// Refuse a constant that is not a finite real number (`sqrt(-1)`,
/// `ln(0)`) at `span`: every evaluation of the model would give `NaN` or an
/// infinity. Checked on what a model's definitions and equations lower to,
/// not in `Scope::lower` itself, which also reads single expressions back
/// ([`Model::parse_expr`]), where `ln(-1)` is a valid expression of the
/// language (the property test `printed_text_reads_back` generates such
/// constants and expects them to read back). `true` when there is none.
///
/// A number double precision cannot hold ([`Expr::unrepresentable_number`]:
/// `1e400`, or `1e-400`, which would silently be 0) is refused the same
/// way, in the words of a parameter default's refusal.
fn check_constants(e: &Expr, span: Span, errors: &mut Errors) -> bool {
    if let Some(u) = e.unrepresentable_number() {
        errors.push(span, u.to_string());
        return false;
    }
    let Some(c) = e.non_finite_constant() else {
        return true;
    };
    let names = |s: Sym| format!("{s}");
    errors.push(
        span,
        format!(
            "the constant `{}` is {}: not a finite real number, so every evaluation would fail",
            crate::print::text(&c, &names),
            c.eval(&|_| f64::NAN)
        ),
    );
    false
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

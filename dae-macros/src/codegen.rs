//! Emission: a derived model and its compiled formulations → Rust items.
//!
//! Everything symbolic has already happened in `dae_core` (checking, hidden
//! constraints, formulations, Jacobians, tapes). This module only prints:
//! one `let` per live tape node, in tape order, then the output writes.
//! Output depends on nothing but its input (no hash-map iteration), so the
//! same model always expands to the same tokens.

use dae_core::compile::{AccelTapes, Compiled, Sparse};
use dae_core::derive::Derived;
use dae_core::dsl::Errors;
use dae_core::expr::Sym;
use dae_core::system::{
    ConstraintInfo, FormulationInfo, ModelInfo, RowKind, VarInfo, VarKind, FORMULATION_NAMES,
};
use dae_core::tape::{Op, Tape};
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote, quote_spanned, ToTokens};
use std::str::FromStr;

/// Where the spans of generated identifiers come from.
#[derive(Clone, Copy)]
pub enum Spans {
    /// The model's own tokens (an inline `dae! { … }` body).
    Model,
    /// One span for everything (the path literal of `include "…"`; the
    /// model's tokens were lexed from a file and carry no usable span).
    At(Span),
}

impl Spans {
    fn pick(self, model_span: Span) -> Span {
        match self {
            Spans::Model => model_span,
            Spans::At(span) => span,
        }
    }
}

/// Lint attributes for every generated item (as serde_derive does): the
/// code is straight-line arithmetic written for speed, not for reading.
fn allow() -> TokenStream {
    quote! {
        #[allow(
            dead_code,
            non_camel_case_types,
            non_snake_case,
            unused_qualifications,
            clippy::all,
            clippy::pedantic,
            clippy::nursery
        )]
    }
}

/// Rust keywords that cannot name a field or type as written.
const KEYWORDS: [&str; 51] = [
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try",
];

/// Keywords that cannot even be raw identifiers.
const NOT_RAW: [&str; 4] = ["crate", "self", "Self", "super"];

/// An identifier for a model name, as a raw identifier when it is a Rust
/// keyword.
pub fn ident(name: &str, span: Span) -> Result<Ident, syn::Error> {
    let bare = name.strip_prefix("r#").unwrap_or(name);
    if NOT_RAW.contains(&bare) {
        return Err(syn::Error::new(
            span,
            format!("`{bare}` cannot name a generated Rust item or field; rename it"),
        ));
    }
    Ok(if KEYWORDS.contains(&bare) || bare != name {
        Ident::new_raw(bare, span)
    } else {
        Ident::new(bare, span)
    })
}

/// `foo` → `Foo`.
fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(first) => first.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

/// Name of the type generated for formulation `f` of model `model`.
pub fn formulation_type(model: &str, f: &str, span: Span) -> Ident {
    let bare = model.strip_prefix("r#").unwrap_or(model);
    format_ident!("{}{}", bare, capitalise(f), span = span)
}

/// A float literal that round-trips (`{:?}` prints the shortest
/// representation that parses back to the same `f64`). Negative values are
/// a `-` followed by the literal; `typed` adds the `f64` suffix where the
/// literal stands alone and its type could not be inferred.
fn float(x: f64, typed: bool) -> TokenStream {
    let magnitude = if x.is_nan() {
        quote!(::core::f64::NAN)
    } else if x.is_infinite() {
        quote!(::core::f64::INFINITY)
    } else {
        let text = format!("{:?}{}", x.abs(), if typed { "f64" } else { "" });
        let lit = Literal::from_str(&text).unwrap_or_else(|_| {
            if typed {
                Literal::f64_suffixed(x.abs())
            } else {
                Literal::f64_unsuffixed(x.abs())
            }
        });
        quote!(#lit)
    };
    if x.is_sign_negative() && !x.is_nan() {
        quote!(-#magnitude)
    } else {
        magnitude
    }
}

/// An unsuffixed integer literal.
fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

fn string(s: &str) -> TokenStream {
    quote!(::dae::__private::String::from(#s))
}

fn vec_of(items: Vec<TokenStream>) -> TokenStream {
    if items.is_empty() {
        quote!(::dae::__private::Vec::new())
    } else {
        quote!(::dae::__private::Vec::from([#(#items),*]))
    }
}

fn doc_lines(text: &str) -> TokenStream {
    let lines = text.lines().map(|l| format!(" {l}"));
    quote!(#(#[doc = #lines])*)
}

// ---------------------------------------------------------------------------
// Tapes → straight-line code
// ---------------------------------------------------------------------------

/// Which inputs a method body reads.
#[derive(Default)]
struct Uses {
    t: bool,
    y: bool,
    yp: bool,
    z: bool,
    out: bool,
}

/// What a method may read besides `self` and `y`.
#[derive(Clone, Copy)]
struct Available {
    t: bool,
    yp: bool,
    z: bool,
}

/// How a tape's outputs are written.
enum Out<'a> {
    /// `out[k] = …` (a slice of the tape's length).
    Dense,
    /// `out.fill(0.0); out[i + j·rows] = …` (a column-major matrix).
    Sparse(&'a [(u32, u32)]),
}

struct Body {
    stmts: TokenStream,
    uses: Uses,
}

fn node(k: usize) -> Ident {
    format_ident!("v{}", k)
}

/// Mark the nodes the outputs depend on.
fn live(tape: &Tape) -> Vec<bool> {
    let mut live = vec![false; tape.nodes.len()];
    for &o in &tape.outputs {
        live[o as usize] = true;
    }
    for k in (0..tape.nodes.len()).rev() {
        if !live[k] {
            continue;
        }
        let mut mark = |c: u32| live[c as usize] = true;
        match &tape.nodes[k] {
            Op::Const(_) | Op::Input(_) => {}
            Op::Add(_, terms) => terms.iter().for_each(|&(_, c)| mark(c)),
            Op::Mul(xs) => xs.iter().for_each(|&c| mark(c)),
            Op::Div(a, b) | Op::Pow(a, b) => {
                mark(*a);
                mark(*b);
            }
            Op::Powi(a, _) | Op::Sqrt(a) | Op::Powf(a, _) | Op::Func(_, a) => mark(*a),
        }
    }
    live
}

/// Straight-line code for one tape. Constants are written in place;
/// every other live node becomes one `let`.
/// How generated code reads parameter `k`: a base parameter is a field of
/// the model struct (`self.params.m` in a formulation, `this.m` in
/// [`derived_values`]); a derived one is an element of the formulation's
/// `derived` array, computed by its constructor.
#[derive(Clone, Copy)]
struct Params<'a> {
    /// The base parameters' fields.
    fields: &'a [Ident],
    /// Inside a formulation (`self.params.f`) or on the model (`this.f`).
    in_formulation: bool,
}

impl Params<'_> {
    fn read(self, k: usize) -> TokenStream {
        match self.fields.get(k) {
            Some(field) if self.in_formulation => quote!(self.params.#field),
            Some(field) => quote!(this.#field),
            None => {
                let j = index(k - self.fields.len());
                quote!(self.derived[#j])
            }
        }
    }
}

fn body(tape: &Tape, out: Out<'_>, fields: Params<'_>, avail: Available) -> Body {
    let live = live(tape);
    let mut uses = Uses::default();
    // A node as an operand: its variable, or its constant (typed, so that
    // method calls on it resolve).
    let operand = |k: u32| -> TokenStream {
        match &tape.nodes[k as usize] {
            Op::Const(c) if c.is_sign_negative() => {
                let c = float(*c, true);
                quote!((#c))
            }
            Op::Const(c) => float(*c, true),
            _ => node(k as usize).into_token_stream(),
        }
    };
    let mut stmts = TokenStream::new();
    for (k, op) in tape.nodes.iter().enumerate() {
        if !live[k] || matches!(op, Op::Const(_)) {
            continue;
        }
        let value = match op {
            Op::Const(_) => continue,
            Op::Input(s) => match *s {
                Sym::Var(i) => {
                    uses.y = true;
                    let i = index(i as usize);
                    quote!(y[#i])
                }
                Sym::Der(i) => {
                    uses.yp |= avail.yp;
                    let i = index(i as usize);
                    if avail.yp {
                        quote!(yp[#i])
                    } else {
                        // Not an input of this method (cannot happen for
                        // the tapes dae-core builds); the interpreter reads
                        // an empty slice here.
                        quote!(::core::f64::NAN)
                    }
                }
                Sym::Param(p) => fields.read(p as usize),
                Sym::Time => {
                    if avail.t {
                        uses.t = true;
                        quote!(t)
                    } else {
                        // Only the derived parameters' values take no
                        // time: they are functions of the base
                        // parameters alone.
                        quote!(0.0f64)
                    }
                }
                Sym::Dir(i) => {
                    uses.z |= avail.z;
                    let i = index(i as usize);
                    if avail.z {
                        quote!(z[#i])
                    } else {
                        quote!(::core::f64::NAN)
                    }
                }
            },
            Op::Add(c, terms) => {
                let mut parts: Vec<(bool, TokenStream)> = Vec::new();
                if *c != 0.0 {
                    parts.push((*c < 0.0, float(c.abs(), false)));
                }
                for &(coef, x) in terms {
                    let x = operand(x);
                    let magnitude = if coef.abs() == 1.0 {
                        x
                    } else {
                        let k = float(coef.abs(), false);
                        quote!(#k * #x)
                    };
                    parts.push((coef < 0.0, magnitude));
                }
                let mut e = TokenStream::new();
                for (n, (negative, part)) in parts.into_iter().enumerate() {
                    e.extend(match (n, negative) {
                        (0, false) => part,
                        (0, true) => quote!(-#part),
                        (_, false) => quote!(+ #part),
                        (_, true) => quote!(- #part),
                    });
                }
                if e.is_empty() || terms.is_empty() {
                    // A constant in disguise: give it its type.
                    float(*c, true)
                } else {
                    e
                }
            }
            Op::Mul(xs) => {
                let mut e = TokenStream::new();
                for (n, &x) in xs.iter().enumerate() {
                    if n > 0 {
                        e.extend(quote!(*));
                    }
                    e.extend(operand(x));
                }
                e
            }
            Op::Div(a, b) => {
                let (a, b) = (operand(*a), operand(*b));
                quote!(#a / #b)
            }
            Op::Powi(a, n) => {
                let a = operand(*a);
                let n = Literal::i32_unsuffixed(*n);
                quote!(#a.powi(#n))
            }
            Op::Sqrt(a) => {
                let a = operand(*a);
                quote!(#a.sqrt())
            }
            Op::Powf(a, c) => {
                let a = operand(*a);
                let c = float(*c, false);
                quote!(#a.powf(#c))
            }
            Op::Pow(a, b) => {
                let (a, b) = (operand(*a), operand(*b));
                quote!(#a.powf(#b))
            }
            Op::Func(f, a) => {
                let a = operand(*a);
                let f = format_ident!("{}", f.name());
                quote!(#a.#f())
            }
        };
        let v = node(k);
        stmts.extend(quote!(let #v = #value;));
    }
    // Output values: a variable, or a constant written as is.
    let value = |k: u32| -> TokenStream {
        match &tape.nodes[k as usize] {
            Op::Const(c) => float(*c, false),
            _ => node(k as usize).into_token_stream(),
        }
    };
    match out {
        Out::Dense => {
            for (i, &o) in tape.outputs.iter().enumerate() {
                let (i, v) = (index(i), value(o));
                stmts.extend(quote!(out[#i] = #v;));
            }
            uses.out = !tape.outputs.is_empty();
        }
        Out::Sparse(entries) => {
            // Column-major storage written directly: nalgebra's `fill` and
            // `(i, j)` indexing go through generic iterators and two bounds
            // checks, which cost more than a small Jacobian's arithmetic.
            stmts.extend(quote!(
                let rows = out.nrows();
                let out = out.as_mut_slice();
                out.fill(0.0);
            ));
            for (&(i, j), &o) in entries.iter().zip(&tape.outputs) {
                let (i, j) = (index(i as usize), index(j as usize));
                let v = value(o);
                stmts.extend(quote!(out[#i + #j * rows] = #v;));
            }
            uses.out = true;
        }
    }
    Body { stmts, uses }
}

/// A parameter name, `_`-prefixed when the body does not read it.
fn param(name: &str, used: bool) -> Ident {
    if used {
        format_ident!("{}", name)
    } else {
        format_ident!("_{}", name)
    }
}

// ---------------------------------------------------------------------------
// Static descriptions as literal data
// ---------------------------------------------------------------------------

fn var_kind(k: VarKind) -> TokenStream {
    match k {
        VarKind::Differential => quote!(::dae::__private::VarKind::Differential),
        VarKind::Algebraic => quote!(::dae::__private::VarKind::Algebraic),
    }
}

fn var_infos(vars: &[VarInfo]) -> TokenStream {
    vec_of(
        vars.iter()
            .map(|v| {
                let name = string(&v.name);
                let kind = var_kind(v.kind);
                let idx = index(v.index.into());
                quote!(::dae::__private::VarInfo { name: #name, kind: #kind, index: #idx })
            })
            .collect(),
    )
}

fn constraint_infos(cs: &[ConstraintInfo]) -> TokenStream {
    vec_of(
        cs.iter()
            .map(|c| {
                let (level, source, expr) = (index(c.level.into()), index(c.source.into()), string(&c.expr));
                quote!(::dae::__private::ConstraintInfo { level: #level, source: #source, expr: #expr })
            })
            .collect(),
    )
}

fn strings(items: &[String]) -> TokenStream {
    vec_of(items.iter().map(|s| string(s)).collect())
}

fn row_kind(k: RowKind) -> TokenStream {
    match k {
        RowKind::Differential => quote!(::dae::__private::RowKind::Differential),
        RowKind::Constraint { level, source } => {
            let (level, source) = (index(level.into()), index(source.into()));
            quote!(::dae::__private::RowKind::Constraint { level: #level, source: #source })
        }
    }
}

/// The model-wide lists every description shares, as helper functions
/// inside the `const _` block.
struct Shared {
    constraints: Vec<ConstraintInfo>,
    invariants: Vec<String>,
    parameters: Vec<String>,
}

fn formulation_info(info: &FormulationInfo, shared: &Shared) -> TokenStream {
    let model = string(&info.model);
    let name = string(&info.name);
    let variables = var_infos(&info.variables);
    let rows = vec_of(
        info.rows
            .iter()
            .map(|r| {
                let kind = row_kind(r.kind);
                let text = string(&r.text);
                quote!(::dae::__private::RowInfo { kind: #kind, text: #text })
            })
            .collect(),
    );
    let d_index = match info.d_index {
        Some(d) => {
            let d = index(d.into());
            quote!(::core::option::Option::Some(#d))
        }
        None => quote!(::core::option::Option::None),
    };
    let (s_index, c_level, constant_leading, constant_differential_leading) = (
        index(info.s_index.into()),
        index(info.c_level.into()),
        info.constant_leading,
        info.constant_differential_leading,
    );
    let constraints = if info.constraints == shared.constraints {
        quote!(constraint_chain())
    } else {
        constraint_infos(&info.constraints)
    };
    let invariants = if info.invariants == shared.invariants {
        quote!(invariant_names())
    } else {
        strings(&info.invariants)
    };
    let parameters = if info.parameters == shared.parameters {
        quote!(parameter_names())
    } else {
        strings(&info.parameters)
    };
    quote! {
        ::dae::__private::FormulationInfo {
            model: #model,
            name: #name,
            variables: #variables,
            rows: #rows,
            d_index: #d_index,
            s_index: #s_index,
            c_level: #c_level,
            constant_leading: #constant_leading,
            constant_differential_leading: #constant_differential_leading,
            constraints: #constraints,
            invariants: #invariants,
            parameters: #parameters,
        }
    }
}

fn model_info(info: &ModelInfo) -> TokenStream {
    let name = string(&info.name);
    let doc = string(&info.doc);
    let variables = var_infos(&info.variables);
    let parameters = vec_of(
        info.parameters
            .iter()
            .map(|p| {
                let name = string(&p.name);
                let default = float(p.default, false);
                let derived = match &p.derived {
                    Some(e) => {
                        let e = string(e);
                        quote!(::core::option::Option::Some(#e))
                    }
                    None => quote!(::core::option::Option::None),
                };
                quote!(::dae::__private::ParamInfo { name: #name, default: #default, derived: #derived })
            })
            .collect(),
    );
    let formulations = strings(&info.formulations);
    let events = strings(&info.events);
    quote! {
        ::dae::__private::ModelInfo {
            name: #name,
            doc: #doc,
            variables: #variables,
            parameters: #parameters,
            constraints: constraint_chain(),
            invariants: invariant_names(),
            events: #events,
            formulations: #formulations,
        }
    }
}

// ---------------------------------------------------------------------------
// Items
// ---------------------------------------------------------------------------

/// Names and spans shared by all the items of one model.
struct Names {
    model: Ident,
    vis: TokenStream,
    fields: Vec<Ident>,
    span: Span,
}

fn names(d: &Derived, spans: Spans) -> Result<Names, syn::Error> {
    let m = &d.model;
    let mut errors = Errors::default();
    let span = spans.pick(m.name_span);
    let model = ident(&m.name, span);
    let mut fields = Vec::new();
    for p in &m.params[..m.n_base] {
        match ident(&p.name, spans.pick(p.span)) {
            Ok(f) => fields.push(f),
            Err(e) => errors.push_error(e),
        }
    }
    let model = match model {
        Ok(model) => Some(model),
        Err(e) => {
            errors.push_error(e);
            None
        }
    };
    let names = model.map(|model| Names {
        model,
        // The item's span starts at `pub`: give it the name's span too.
        vis: if m.public {
            quote_spanned!(span=> pub)
        } else {
            TokenStream::new()
        },
        fields,
        span,
    });
    errors.finish(())?;
    names.ok_or_else(|| syn::Error::new(span, "invalid model name"))
}

/// Every item of a derived model: the parameter struct, one type per
/// provided formulation, and their trait implementations.
pub fn emit(d: &Derived, compiled: &[Compiled], spans: Spans) -> Result<TokenStream, syn::Error> {
    let n = names(d, spans)?;
    let m = &d.model;
    let Names {
        model,
        vis,
        fields,
        span,
    } = &n;
    let allow = allow();

    // The parameter struct.
    let doc = if m.doc.is_empty() {
        doc_lines(&format!("Model `{}`, generated by `dae!`.", m.name))
    } else {
        doc_lines(&m.doc)
    };
    let base = &m.params[..m.n_base];
    let derived = &m.params[m.n_base..];
    let n_derived = derived.len();
    let field_docs = base
        .iter()
        .map(|p| format!(" Parameter `{}` (default `{:?}`).", p.name, p.default));
    let defaults: Vec<TokenStream> = base.iter().map(|p| float(p.default, false)).collect();
    let derived_doc = if derived.is_empty() {
        TokenStream::new()
    } else {
        let mut text = String::from(
            "\nDerived parameters (computed from the fields when a formulation is built; read them with `Model::parameter`):\n",
        );
        for p in derived {
            let e = p.derived.as_ref().map(|e| m.text(e)).unwrap_or_default();
            text.push_str(&format!("\n- `{} = {}`", p.name, e));
        }
        doc_lines(&text)
    };
    let model_struct = quote_spanned! {*span=>
        #doc
        #derived_doc
        #[derive(::core::clone::Clone, ::core::marker::Copy, ::core::fmt::Debug, ::core::cmp::PartialEq)]
        #allow
        #vis struct #model {
            #(#[doc = #field_docs] #vis #fields: f64,)*
        }
    };

    // One type per provided formulation.
    let mut types = TokenStream::new();
    let mut impls = TokenStream::new();
    let mut constructors = TokenStream::new();
    let mut arms = TokenStream::new();
    for c in compiled {
        let ty = formulation_type(&m.name, &c.info.name, *span);
        let method = format_ident!("{}", c.info.name, span = *span);
        let info = &c.info;
        let mut doc = format!(
            "Formulation `{}` of [`{}`]: {} unknowns, {} equations",
            info.name,
            m.name.trim_start_matches("r#"),
            info.unknowns(),
            info.equations()
        );
        match info.d_index {
            Some(d) => doc.push_str(&format!(", differentiation index {d}")),
            None => doc.push_str(" (overdetermined)"),
        }
        doc.push_str(&format!(
            ", maximal constraint level {}.\n\n```text\n",
            info.c_level
        ));
        for r in &info.rows {
            doc.push_str(&r.text);
            doc.push('\n');
        }
        doc.push_str("```");
        let doc = doc_lines(&doc);
        if derived.is_empty() {
            types.extend(quote_spanned! {*span=>
                #doc
                #[derive(::core::clone::Clone, ::core::marker::Copy, ::core::fmt::Debug, ::core::cmp::PartialEq)]
                #allow
                #vis struct #ty {
                    /// Parameter values.
                    #vis params: #model,
                }
            });
            let ctor_doc = format!(" Formulation `{}` with these parameter values.", info.name);
            constructors.extend(quote! {
                #[doc = #ctor_doc]
                #vis fn #method(&self) -> #ty {
                    #ty { params: *self }
                }
            });
        } else {
            // The derived parameters are computed once, here, and stored:
            // the fields are private so that they cannot go stale.
            let n = index(n_derived);
            types.extend(quote_spanned! {*span=>
                #doc
                #[derive(::core::clone::Clone, ::core::marker::Copy, ::core::fmt::Debug, ::core::cmp::PartialEq)]
                #allow
                #vis struct #ty {
                    params: #model,
                    derived: [f64; #n],
                }
            });
            let ctor_doc = format!(
                " Formulation `{}` with these parameter values (the derived ones computed from them now).",
                info.name
            );
            constructors.extend(quote! {
                #[doc = #ctor_doc]
                #vis fn #method(&self) -> #ty {
                    #ty { params: *self, derived: derived_values(self) }
                }
            });
        }
        let name = &info.name;
        if name == dae_core::dummy::NAME {
            // `mex0` selects its rows at run time from these (dae_core::dummy).
            arms.extend(quote!(#name => ::dae::__private::dummy_boxed(self.#method(), Self::model_info_static()),));
        } else {
            arms.extend(quote!(#name => ::core::result::Result::Ok(::dae::__private::Box::new(self.#method())),));
        }
        impls.extend(system_impl(
            c,
            &ty,
            fields,
            m.params.len() - m.n_base,
            &Shared::of(d),
        ));
    }

    // Known formulations this model does not provide.
    let provided: Vec<&str> = compiled.iter().map(|c| c.info.name.as_str()).collect();
    let missing: Vec<&str> = FORMULATION_NAMES
        .iter()
        .copied()
        .filter(|f| !provided.contains(f))
        .collect();
    let model_name = string(&m.name);
    if !missing.is_empty() {
        let available = string(&provided.join(", "));
        arms.extend(quote! {
            #(#missing)|* => ::core::result::Result::Err(::dae::__private::FormulationError::NotProvided {
                model: #model_name,
                name: ::dae::__private::String::from(name),
                available: #available,
            }),
        });
    }

    let shared = Shared::of(d);
    let chain = constraint_infos(&shared.constraints);
    let invariant_names = strings(&shared.invariants);
    let parameter_names = strings(&shared.parameters);
    let info = model_info(&d.model_info());
    let provided_lits = &provided;

    let names: Vec<&str> = base.iter().map(|p| p.name.as_str()).collect();
    let all_names: Vec<&str> = m.params.iter().map(|p| p.name.as_str()).collect();
    let derived_fn = derived_values(d, model, fields);
    let (get, set) = if !derived.is_empty() {
        let derived_names: Vec<&str> = derived.iter().map(|p| p.name.as_str()).collect();
        let exprs: Vec<TokenStream> = derived
            .iter()
            .map(|p| string(&p.derived.as_ref().map(|e| m.text(e)).unwrap_or_default()))
            .collect();
        let js: Vec<Literal> = (0..n_derived).map(index).collect();
        (
            quote! {
                fn parameter(&self, name: &str) -> ::core::option::Option<f64> {
                    match name {
                        #(#names => ::core::option::Option::Some(self.#fields),)*
                        #(#derived_names => ::core::option::Option::Some(derived_values(self)[#js]),)*
                        _ => ::core::option::Option::None,
                    }
                }
            },
            quote! {
                fn set_parameter(&mut self, name: &str, value: f64)
                    -> ::core::result::Result<(), ::dae::__private::ParameterError> {
                    let mut next = *self;
                    let slot = match name {
                        #(#names => &mut next.#fields,)*
                        #(#derived_names => return ::core::result::Result::Err(
                            ::dae::__private::ParameterError::Derived {
                                model: #model_name,
                                name: ::dae::__private::String::from(name),
                                expr: ::dae::__private::String::from(#exprs),
                            }),)*
                        _ => return ::core::result::Result::Err(unknown_parameter(name)),
                    };
                    ::dae::__private::check_parameter(name, value)?;
                    *slot = value;
                    let values = derived_values(&next);
                    const DERIVED: [&str; #n_derived] = [#(#derived_names),*];
                    for (k, v) in values.iter().enumerate() {
                        if !v.is_finite() {
                            return ::core::result::Result::Err(
                                ::dae::__private::ParameterError::DerivedNotFinite {
                                    name: ::dae::__private::String::from(name),
                                    value,
                                    derived: ::dae::__private::String::from(DERIVED[k]),
                                    result: *v,
                                });
                        }
                    }
                    *self = next;
                    ::core::result::Result::Ok(())
                }
            },
        )
    } else if fields.is_empty() {
        (
            quote! {
                fn parameter(&self, _name: &str) -> ::core::option::Option<f64> {
                    ::core::option::Option::None
                }
            },
            quote! {
                fn set_parameter(&mut self, name: &str, _value: f64)
                    -> ::core::result::Result<(), ::dae::__private::ParameterError> {
                    ::core::result::Result::Err(unknown_parameter(name))
                }
            },
        )
    } else {
        (
            quote! {
                fn parameter(&self, name: &str) -> ::core::option::Option<f64> {
                    match name {
                        #(#names => ::core::option::Option::Some(self.#fields),)*
                        _ => ::core::option::Option::None,
                    }
                }
            },
            quote! {
                fn set_parameter(&mut self, name: &str, value: f64)
                    -> ::core::result::Result<(), ::dae::__private::ParameterError> {
                    let slot = match name {
                        #(#names => &mut self.#fields,)*
                        _ => return ::core::result::Result::Err(unknown_parameter(name)),
                    };
                    ::dae::__private::check_parameter(name, value)?;
                    *slot = value;
                    ::core::result::Result::Ok(())
                }
            },
        )
    };
    let known = string(&all_names.join(", "));

    Ok(quote! {
        #model_struct
        #types
        #[allow(non_upper_case_globals, clippy::all, clippy::pedantic, clippy::nursery)]
        const _: () = {
            #[automatically_derived]
            #allow
            #derived_fn

            impl ::core::default::Default for #model {
                fn default() -> Self {
                    #model { #(#fields: #defaults,)* }
                }
            }

            #allow
            impl #model {
                #constructors

                /// Names of the formulations this model provides.
                #vis const FORMULATIONS: &'static [&'static str] = &[#(#provided_lits),*];

                /// Static description of the model.
                #vis fn model_info_static() -> &'static ::dae::__private::ModelInfo {
                    static INFO: ::dae::__private::OnceLock<::dae::__private::ModelInfo> =
                        ::dae::__private::OnceLock::new();
                    INFO.get_or_init(|| #info)
                }
            }

            fn constraint_chain() -> ::dae::__private::Vec<::dae::__private::ConstraintInfo> {
                #chain
            }

            fn invariant_names() -> ::dae::__private::Vec<::dae::__private::String> {
                #invariant_names
            }

            fn parameter_names() -> ::dae::__private::Vec<::dae::__private::String> {
                #parameter_names
            }

            fn unknown_parameter(name: &str) -> ::dae::__private::ParameterError {
                ::dae::__private::ParameterError::Unknown {
                    model: #model_name,
                    name: ::dae::__private::String::from(name),
                    known: #known,
                }
            }

            #[automatically_derived]
            #allow
            impl ::dae::__private::Model for #model {
                fn model_info(&self) -> &::dae::__private::ModelInfo {
                    Self::model_info_static()
                }

                #get

                #set

                fn formulation(&self, name: &str)
                    -> ::core::result::Result<::dae::__private::BoxedSystem, ::dae::__private::FormulationError> {
                    match name {
                        #arms
                        _ => ::core::result::Result::Err(::dae::__private::FormulationError::Unknown {
                            name: ::dae::__private::String::from(name),
                        }),
                    }
                }
            }

            #impls
        };
    })
}

impl Shared {
    fn of(d: &Derived) -> Shared {
        Shared {
            constraints: d.constraint_infos(),
            invariants: d.model.invariants.iter().map(|i| i.name.clone()).collect(),
            parameters: d.model.params.iter().map(|p| p.name.clone()).collect(),
        }
    }
}

/// `DaeSystem` and `StaticSize` for one formulation.
fn system_impl(
    c: &Compiled,
    ty: &Ident,
    fields: &[Ident],
    n_derived: usize,
    shared: &Shared,
) -> TokenStream {
    let fields = Params {
        fields,
        in_formulation: true,
    };
    let allow = allow();
    let info = formulation_info(&c.info, shared);
    let all = Available {
        t: true,
        yp: false,
        z: false,
    };
    let dense = |tape: &Tape, avail: Available| body(tape, Out::Dense, fields, avail);
    let sparse =
        |s: &Sparse, avail: Available| body(&s.tape, Out::Sparse(&s.entries), fields, avail);

    // fn(&self, t, y, out: &mut [f64])
    let t_y_slice = |name: &str, b: Body| {
        let name = format_ident!("{}", name);
        let (t, y, out, stmts) = (
            param("t", b.uses.t),
            param("y", b.uses.y),
            param("out", b.uses.out),
            b.stmts,
        );
        quote! {
            fn #name(&self, #t: f64, #y: &[f64], #out: &mut [f64]) { #stmts }
        }
    };
    let t_y_matrix = |name: &str, b: Body| {
        let name = format_ident!("{}", name);
        let (t, y, stmts) = (param("t", b.uses.t), param("y", b.uses.y), b.stmts);
        quote! {
            fn #name(&self, #t: f64, #y: &[f64], out: &mut ::dae::__private::DMatrix<f64>) { #stmts }
        }
    };

    let rhs = t_y_slice("rhs", dense(&c.rhs, all));
    let (constraints, constraints_jacobian, accel) = match &c.accel {
        None => (
            t_y_slice("constraints", dense(&c.constraints, all)),
            t_y_matrix("constraints_jacobian", sparse(&c.constraints_jacobian, all)),
            TokenStream::new(),
        ),
        Some(a) => accel_impl(
            c,
            a,
            ty,
            &allow,
            Emit {
                dense: &dense,
                sparse: &sparse,
                t_y_slice: &t_y_slice,
                t_y_matrix: &t_y_matrix,
            },
        ),
    };
    let invariants = t_y_slice("invariants", dense(&c.invariants, all));
    // The event functions: only for a model that has them (the trait's
    // defaults say "none" otherwise).
    let events = if c.event_names.is_empty() {
        TokenStream::new()
    } else {
        let names = strings(&c.event_names);
        let eval = t_y_slice("events", dense(&c.events, all));
        quote! {
            fn event_names(&self) -> &[::dae::__private::String] {
                static NAMES: ::dae::__private::OnceLock<::dae::__private::Vec<::dae::__private::String>> =
                    ::dae::__private::OnceLock::new();
                NAMES.get_or_init(|| #names)
            }
            #eval
        }
    };
    let rhs_jacobian = t_y_matrix("rhs_jacobian", sparse(&c.rhs_jacobian, all));

    let residual = t_y_yp_slice(
        "residual",
        dense(&c.residual, Available { yp: true, ..all }),
    );
    let leading = t_y_matrix("leading", sparse(&c.leading, all));
    let leading_jacobian = t_y_z_matrix(
        "leading_jacobian",
        sparse(&c.leading_jacobian, Available { z: true, ..all }),
    );

    let values = vec_of(
        (0..fields.fields.len() + n_derived)
            .map(|k| fields.read(k))
            .collect(),
    );
    let (unknowns, equations, chain) = (
        index(c.info.unknowns()),
        index(c.info.equations()),
        index(c.info.constraints.len()),
    );
    quote! {
        #[automatically_derived]
        #allow
        impl ::dae::__private::DaeSystem for #ty {
            fn info(&self) -> &::dae::__private::FormulationInfo {
                static INFO: ::dae::__private::OnceLock<::dae::__private::FormulationInfo> =
                    ::dae::__private::OnceLock::new();
                INFO.get_or_init(|| #info)
            }

            fn parameter_values(&self) -> ::dae::__private::Vec<f64> {
                #values
            }

            #rhs
            #residual
            #leading
            #rhs_jacobian
            #leading_jacobian
            #constraints
            #constraints_jacobian
            #invariants
            #events
        }

        #accel

        #[automatically_derived]
        #allow
        impl ::dae::__private::StaticSize for #ty {
            const UNKNOWNS: usize = #unknowns;
            const EQUATIONS: usize = #equations;
            const CONSTRAINTS: usize = #chain;
        }
    }
}

/// `fn name(&self, t, y, z, out: &mut DMatrix<f64>)` around a tape's body.
fn t_y_z_matrix(name: &str, b: Body) -> TokenStream {
    let name = format_ident!("{}", name);
    let (t, y, z, stmts) = (
        param("t", b.uses.t),
        param("y", b.uses.y),
        param("z", b.uses.z),
        b.stmts,
    );
    quote! {
        fn #name(&self, #t: f64, #y: &[f64], #z: &[f64], out: &mut ::dae::__private::DMatrix<f64>) { #stmts }
    }
}

/// `fn name(&self, t, y, yp, out: &mut [f64])` around a tape's body.
fn t_y_yp_slice(name: &str, b: Body) -> TokenStream {
    let name = format_ident!("{}", name);
    let (t, y, yp, out, stmts) = (
        param("t", b.uses.t),
        param("y", b.uses.y),
        param("yp", b.uses.yp),
        param("out", b.uses.out),
        b.stmts,
    );
    quote! {
        fn #name(&self, #t: f64, #y: &[f64], #yp: &[f64], #out: &mut [f64]) { #stmts }
    }
}

/// The printers [`accel_impl`] shares with [`system_impl`].
struct Emit<'a> {
    dense: &'a dyn Fn(&Tape, Available) -> Body,
    sparse: &'a dyn Fn(&Sparse, Available) -> Body,
    t_y_slice: &'a dyn Fn(&str, Body) -> TokenStream,
    t_y_matrix: &'a dyn Fn(&str, Body) -> TokenStream,
}

/// For a model with a mass matrix: `constraints` and
/// `constraints_jacobian` eliminate the accelerations through
/// `dae_core::accel`, and the formulation implements its `AccelParts`.
fn accel_impl(
    c: &Compiled,
    a: &AccelTapes,
    ty: &Ident,
    allow: &TokenStream,
    emit: Emit<'_>,
) -> (TokenStream, TokenStream, TokenStream) {
    let all = Available {
        t: true,
        yp: false,
        z: false,
    };
    let with_yp = Available { yp: true, ..all };
    let constraints = quote! {
        fn constraints(&self, t: f64, y: &[f64], out: &mut [f64]) {
            ::dae::__private::accel::constraints(self, t, y, out)
        }
    };
    let constraints_jacobian = quote! {
        fn constraints_jacobian(&self, t: f64, y: &[f64], out: &mut ::dae::__private::DMatrix<f64>) {
            ::dae::__private::accel::constraints_jacobian(self, t, y, out)
        }
    };
    let n_diff = index(a.n_diff);
    let rhs = (emit.t_y_slice)("accel_rhs", (emit.dense)(&a.rhs, all));
    let rhs_jacobian = (emit.t_y_matrix)("accel_rhs_jacobian", (emit.sparse)(&a.rhs_jacobian, all));
    let chain_der = (emit.t_y_matrix)("chain_der", (emit.sparse)(&a.chain_der, all));
    let leading = (emit.t_y_matrix)("accel_leading", (emit.sparse)(&a.leading, all));
    let leading_jacobian = t_y_z_matrix(
        "accel_leading_jacobian",
        (emit.sparse)(&a.leading_jacobian, Available { z: true, ..all }),
    );
    let chain_at = t_y_yp_slice("chain_at", (emit.dense)(&c.constraints, with_yp));
    let chain_jacobian_at = {
        let b = (emit.sparse)(&c.constraints_jacobian, with_yp);
        let (t, y, yp, stmts) = (
            param("t", b.uses.t),
            param("y", b.uses.y),
            param("yp", b.uses.yp),
            b.stmts,
        );
        quote! {
            fn chain_jacobian_at(&self, #t: f64, #y: &[f64], #yp: &[f64], out: &mut ::dae::__private::DMatrix<f64>) { #stmts }
        }
    };
    let parts = quote! {
        #[automatically_derived]
        #allow
        impl ::dae::__private::accel::AccelParts for #ty {
            fn accel_dim(&self) -> usize {
                #n_diff
            }
            #leading
            #rhs
            #rhs_jacobian
            #leading_jacobian
            #chain_at
            #chain_jacobian_at
            #chain_der
        }
    };
    (constraints, constraints_jacobian, parts)
}

/// `fn derived_values(this: &Model) -> [f64; K]`: the derived parameters
/// from the base ones (empty when there are none).
fn derived_values(d: &Derived, model: &Ident, fields: &[Ident]) -> TokenStream {
    let m = &d.model;
    let derived = &m.params[m.n_base..];
    if derived.is_empty() {
        return TokenStream::new();
    }
    let mut b = dae_core::tape::TapeBuilder::new();
    for p in derived {
        b.output(p.derived.as_ref().unwrap_or(&dae_core::expr::Expr::zero()));
    }
    let tape = b.finish();
    let params = Params {
        fields,
        in_formulation: false,
    };
    let none = Available {
        t: false,
        yp: false,
        z: false,
    };
    let stmts = body(&tape, Out::Dense, params, none).stmts;
    let n = index(derived.len());
    quote! {
        fn derived_values(this: &#model) -> [f64; #n] {
            let _ = this;
            let mut out = [0.0f64; #n];
            #stmts
            out
        }
    }
}

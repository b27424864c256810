//! The whole expansion as a plain function over `proc_macro2` tokens:
//! input (inline model or `include "file.dae"`) → `dae_core` (parse, check,
//! derive, compile) → [`super::codegen`] → tokens.
//!
//! Nothing here touches `proc_macro`, so the expansion also runs outside a
//! compiler (unit tests, the expansion benchmark in `examples/`).

use super::codegen::{self, Spans};
use dae_core::compile::{compile_all, Compiled};
use dae_core::derive::Derived;
use dae_core::dsl::ModelAst;
use dae_core::system::FORMULATION_NAMES;
use proc_macro2::{Delimiter, Literal, Span, TokenStream, TokenTree};
use quote::{quote, quote_spanned};
use std::path::Path;

/// Expand the body of `dae! { … }`.
///
/// On error the result is one `compile_error!` carrying every problem (each
/// at its token), followed by a stub of the model's items so that code
/// using them reports nothing further.
pub fn expand(input: TokenStream) -> TokenStream {
    // `stub` holds the fallback items while anything can still fail.
    let mut stub = TokenStream::new();
    let mut out = try_expand(input, &mut stub).unwrap_or_else(syn::Error::into_compile_error);
    out.extend(stub);
    out
}

/// Number of token trees, groups counted with their contents.
pub fn count_tokens(tokens: &TokenStream) -> usize {
    tokens
        .clone()
        .into_iter()
        .map(|t| match t {
            TokenTree::Group(g) => 1 + count_tokens(&g.stream()),
            _ => 1,
        })
        .sum()
}

fn try_expand(input: TokenStream, stub: &mut TokenStream) -> Result<TokenStream, syn::Error> {
    let items = match include_path(&input)? {
        Some(lit) => expand_include(&lit, stub)?,
        None => {
            *stub = Stub::guess(&input, Spans::Model).emit();
            let ast = dae_core::dsl::parse(input)?;
            *stub = Stub::from_ast(&ast, Spans::Model).emit();
            let derived = Derived::from_ast(&ast)?;
            let compiled = compile_all(&derived);
            codegen::emit(&derived, &compiled, Spans::Model)?
        }
    };
    *stub = TokenStream::new();
    Ok(items)
}

/// `include "path"`: the path literal, if the body is one.
fn include_path(input: &TokenStream) -> Result<Option<syn::LitStr>, syn::Error> {
    let tokens: Vec<TokenTree> = input.clone().into_iter().collect();
    match tokens.as_slice() {
        [TokenTree::Ident(kw), TokenTree::Literal(lit), rest @ ..] if kw == "include" => {
            if let Some(extra) = rest.first() {
                return Err(syn::Error::new(
                    extra.span(),
                    "unexpected tokens after `include \"…\"`",
                ));
            }
            let lit = TokenTree::Literal(lit.clone());
            syn::parse2::<syn::LitStr>(lit.into())
                .map(Some)
                .map_err(|e| {
                    syn::Error::new(
                        e.span(),
                        "expected a path string: `include \"scenes/model.dae\"`",
                    )
                })
        }
        _ => Ok(None),
    }
}

/// `include "path"`: read the file (relative to the invoking crate's
/// `CARGO_MANIFEST_DIR`), derive it, and make cargo rebuild when it
/// changes.
fn expand_include(lit: &syn::LitStr, stub: &mut TokenStream) -> Result<TokenStream, syn::Error> {
    let span = lit.span();
    let rel = lit.value();
    let dir = std::env::var_os("CARGO_MANIFEST_DIR").ok_or_else(|| {
        syn::Error::new(span, "CARGO_MANIFEST_DIR is not set: `include` needs cargo")
    })?;
    let path = Path::new(&dir).join(&rel);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        syn::Error::new(
            span,
            format!("cannot read `{rel}` (paths are relative to the crate root, CARGO_MANIFEST_DIR): {e}"),
        )
    })?;
    let abs = path
        .to_str()
        .ok_or_else(|| syn::Error::new(span, format!("the path of `{rel}` is not valid UTF-8")))?;

    let (analysed, guess) = with_file_positions(|| analyse_text(&text));
    if let Some(guess) = guess {
        *stub = guess.at(span).emit();
    }
    let (derived, compiled) = analysed.map_err(|problems| {
        let mut all: Option<syn::Error> = None;
        for (line, column, msg) in problems {
            let e = syn::Error::new(span, format!("{rel}:{line}:{column}: {msg}"));
            match &mut all {
                Some(all) => all.combine(e),
                None => all = Some(e),
            }
        }
        all.unwrap_or_else(|| syn::Error::new(span, format!("{rel}: invalid model")))
    })?;
    let items = codegen::emit(&derived, &compiled, Spans::At(span))?;
    let abs = Literal::string(abs);
    Ok(quote! {
        const _: &str = ::core::include_str!(#abs);
        #items
    })
}

/// A problem in a model file: line (1-based), column (1-based), message.
type Problem = (usize, usize, String);

/// Parse, check, derive and compile model text. Spans are only turned into
/// positions here: none of them leaves this function.
#[allow(clippy::type_complexity)]
fn analyse_text(text: &str) -> (Result<(Derived, Vec<Compiled>), Vec<Problem>>, Option<Stub>) {
    let positions = |e: syn::Error| -> Vec<Problem> {
        e.into_iter()
            .map(|e| {
                let start = e.span().start();
                (start.line, start.column + 1, e.to_string())
            })
            .collect()
    };
    let ast = match dae_core::dsl::parse_str(text) {
        Ok(ast) => ast,
        Err(e) => {
            let guess = text
                .parse::<TokenStream>()
                .ok()
                .map(|t| Stub::guess(&t, Spans::Model));
            return (Err(positions(e)), guess.map(Stub::without_span));
        }
    };
    let guess = Stub::from_ast(&ast, Spans::Model).without_span();
    let result = Derived::from_ast(&ast).map(|d| {
        let c = compile_all(&d);
        (d, c)
    });
    (result.map_err(positions), Some(guess))
}

/// Run `f` with proc-macro2's own lexer and spans, which know the line and
/// column of every token of a string. Inside a procedural macro, tokens
/// lexed from a string all carry the call-site span, so errors in an
/// included file could not say where they are. `f` must not let any token
/// or span escape (it returns plain data and spanless trees).
fn with_file_positions<T>(f: impl FnOnce() -> T) -> T {
    struct Restore;
    impl Drop for Restore {
        fn drop(&mut self) {
            proc_macro2::fallback::unforce();
        }
    }
    proc_macro2::fallback::force();
    let _restore = Restore;
    f()
}

/// Whether a name can be a struct or field name in the stub: an identifier
/// that is not `_` and not a keyword (syn's `Ident` parser refuses both).
fn is_ident(name: &str) -> bool {
    syn::parse_str::<syn::Ident>(name).is_ok()
}

fn usable(id: &proc_macro2::Ident) -> bool {
    is_ident(&id.to_string())
}

/// What is known of a model's items when it fails: enough to declare them
/// so that the code using them type-checks and only the real error shows.
struct Stub {
    public: bool,
    name: Option<(String, Option<Span>)>,
    params: Vec<(String, Option<Span>)>,
    formulations: Vec<&'static str>,
}

impl Stub {
    /// From the raw tokens: `[#[doc …]]* [pub] Name …`.
    fn guess(tokens: &TokenStream, spans: Spans) -> Stub {
        let toks: Vec<TokenTree> = tokens.clone().into_iter().collect();
        let mut i = 0;
        while let (Some(TokenTree::Punct(p)), Some(TokenTree::Group(g))) =
            (toks.get(i), toks.get(i + 1))
        {
            if p.as_char() != '#' || g.delimiter() != Delimiter::Bracket {
                break;
            }
            i += 2;
        }
        let public = matches!(toks.get(i), Some(TokenTree::Ident(id)) if id == "pub");
        if public {
            i += 1;
        }
        let name = match toks.get(i) {
            Some(TokenTree::Ident(id)) if usable(id) => {
                Some((id.to_string(), span_of(spans, id.span())))
            }
            _ => None,
        };
        let mut stub = Stub {
            public,
            name,
            params: Vec::new(),
            formulations: FORMULATION_NAMES.to_vec(),
        };
        // The sections that shape the items: `parameters { p = …, … }` and
        // `formulations { … }`, read as loosely as possible.
        let Some(TokenTree::Group(body)) = toks.get(i + 1) else {
            return stub;
        };
        let sections: Vec<TokenTree> = body.stream().into_iter().collect();
        for pair in sections.windows(2) {
            let (TokenTree::Ident(kw), TokenTree::Group(g)) = (&pair[0], &pair[1]) else {
                continue;
            };
            let inner: Vec<TokenTree> = g.stream().into_iter().collect();
            if kw == "parameters" {
                for w in inner.windows(2) {
                    if let (TokenTree::Ident(p), TokenTree::Punct(eq)) = (&w[0], &w[1]) {
                        if !usable(p) {
                            continue;
                        }
                        let p = p.to_string();
                        if eq.as_char() == '=' && !stub.params.iter().any(|(n, _)| *n == p) {
                            stub.params.push((p, span_of(spans, w[0].span())));
                        }
                    }
                }
            } else if kw == "formulations" {
                stub.formulations.retain(|f| {
                    inner
                        .iter()
                        .any(|t| matches!(t, TokenTree::Ident(id) if id == f))
                });
            }
        }
        stub
    }

    /// From a parsed model: the name, the parameters, the formulations.
    fn from_ast(ast: &ModelAst, spans: Spans) -> Stub {
        let mut params: Vec<(String, Option<Span>)> = Vec::new();
        for p in &ast.parameters {
            if !is_ident(&p.name.name) {
                continue;
            }
            if !params.iter().any(|(n, _)| *n == p.name.name) {
                params.push((p.name.name.clone(), span_of(spans, p.name.span)));
            }
        }
        let formulations = match &ast.formulations {
            Some(list) => FORMULATION_NAMES
                .iter()
                .copied()
                .filter(|f| list.iter().any(|n| n.name == *f))
                .collect(),
            None => FORMULATION_NAMES.to_vec(),
        };
        Stub {
            public: ast.public,
            name: is_ident(&ast.name.name)
                .then(|| (ast.name.name.clone(), span_of(spans, ast.name.span))),
            params,
            formulations,
        }
    }

    fn without_span(mut self) -> Stub {
        if let Some((_, s)) = &mut self.name {
            *s = None;
        }
        for (_, s) in &mut self.params {
            *s = None;
        }
        self
    }

    fn at(mut self, span: Span) -> Stub {
        if let Some((_, s)) = &mut self.name {
            *s = Some(span);
        }
        for (_, s) in &mut self.params {
            *s = Some(span);
        }
        self
    }

    /// The stub items: the parameter struct, the formulation types and
    /// their constructors, and the traits, with bodies that never run (the
    /// crate does not compile).
    fn emit(&self) -> TokenStream {
        let Some((name, span)) = &self.name else {
            return TokenStream::new();
        };
        let span = span.unwrap_or_else(Span::call_site);
        let Ok(model) = codegen::ident(name, span) else {
            return TokenStream::new();
        };
        let fields: Vec<_> = self
            .params
            .iter()
            .filter_map(|(p, s)| codegen::ident(p, s.unwrap_or(span)).ok())
            .collect();
        let vis = if self.public {
            quote_spanned!(span=> pub)
        } else {
            TokenStream::new()
        };
        let tys: Vec<_> = self
            .formulations
            .iter()
            .map(|f| codegen::formulation_type(name, f, span))
            .collect();
        let methods: Vec<_> = self
            .formulations
            .iter()
            .map(|f| proc_macro2::Ident::new(f, span))
            .collect();
        let allow = quote! {
            #[allow(dead_code, non_camel_case_types, non_snake_case, unused_variables, clippy::all)]
        };
        quote! {
            #allow
            #[derive(::core::clone::Clone, ::core::marker::Copy, ::core::fmt::Debug, ::core::default::Default, ::core::cmp::PartialEq)]
            #vis struct #model { #(#vis #fields: f64,)* }
            #(
                #allow
                #[derive(::core::clone::Clone, ::core::marker::Copy, ::core::fmt::Debug, ::core::cmp::PartialEq)]
                #vis struct #tys { #vis params: #model }
            )*
            #allow
            const _: () = {
                impl #model {
                    #(#vis fn #methods(&self) -> #tys { ::core::unreachable!() })*
                    #vis const FORMULATIONS: &'static [&'static str] = &[];
                    #vis fn model_info_static() -> &'static ::dae::__private::ModelInfo { ::core::unreachable!() }
                }
                impl ::dae::__private::Model for #model {
                    fn model_info(&self) -> &::dae::__private::ModelInfo { ::core::unreachable!() }
                    fn parameter(&self, _: &str) -> ::core::option::Option<f64> { ::core::unreachable!() }
                    fn set_parameter(&mut self, _: &str, _: f64)
                        -> ::core::result::Result<(), ::dae::__private::ParameterError> { ::core::unreachable!() }
                    fn formulation(&self, _: &str)
                        -> ::core::result::Result<::dae::__private::BoxedSystem, ::dae::__private::FormulationError> {
                        ::core::unreachable!()
                    }
                }
                #(
                    impl ::dae::__private::DaeSystem for #tys {
                        fn info(&self) -> &::dae::__private::FormulationInfo { ::core::unreachable!() }
                        fn parameter_values(&self) -> ::dae::__private::Vec<f64> { ::core::unreachable!() }
                        fn rhs(&self, _: f64, _: &[f64], _: &mut [f64]) { ::core::unreachable!() }
                        fn residual(&self, _: f64, _: &[f64], _: &[f64], _: &mut [f64]) { ::core::unreachable!() }
                        fn leading(&self, _: f64, _: &[f64], _: &mut ::dae::__private::DMatrix<f64>) { ::core::unreachable!() }
                        fn rhs_jacobian(&self, _: f64, _: &[f64], _: &mut ::dae::__private::DMatrix<f64>) {
                            ::core::unreachable!()
                        }
                        fn leading_jacobian(&self, _: f64, _: &[f64], _: &[f64], _: &mut ::dae::__private::DMatrix<f64>) {
                            ::core::unreachable!()
                        }
                        fn constraints(&self, _: f64, _: &[f64], _: &mut [f64]) { ::core::unreachable!() }
                        fn constraints_jacobian(&self, _: f64, _: &[f64], _: &mut ::dae::__private::DMatrix<f64>) {
                            ::core::unreachable!()
                        }
                        fn invariants(&self, _: f64, _: &[f64], _: &mut [f64]) { ::core::unreachable!() }
                    }
                )*
            };
        }
    }
}

fn span_of(spans: Spans, model_span: Span) -> Option<Span> {
    match spans {
        Spans::Model => Some(model_span),
        Spans::At(s) => Some(s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::str::FromStr;

    const PENDULUM: &str = include_str!("../../scenes/pendulum.dae");

    #[test]
    fn expansion_is_deterministic() {
        let a = expand(TokenStream::from_str(PENDULUM).unwrap()).to_string();
        let b = expand(TokenStream::from_str(PENDULUM).unwrap()).to_string();
        assert_eq!(a, b);
        assert!(!a.contains("compile_error"), "{a}");
        assert!(a.contains("PendulumPsi0"));
    }

    #[test]
    fn only_listed_formulations_are_emitted() {
        let src = PENDULUM.replace(
            "formulations { ori2, rcd1, rcd0, ovd1, ovd0, ggl1, psi1, psi0, mex0 }",
            "formulations { rcd0 }",
        );
        let out = expand(TokenStream::from_str(&src).unwrap()).to_string();
        assert!(out.contains("PendulumRcd0"));
        assert!(!out.contains("PendulumRcd1"));
    }

    #[test]
    fn errors_in_an_included_file_carry_its_positions() {
        let dir = std::env::temp_dir().join(format!("dae-macros-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("bad.dae");
        std::fs::write(
            &file,
            "pub Bad {\n    differential { x }\n    equations { der(x) = q; }\n}\n",
        )
        .unwrap();
        let input = format!("include {:?}", file.to_str().unwrap());
        let out = expand(TokenStream::from_str(&input).unwrap()).to_string();
        let _ = std::fs::remove_dir_all(&dir);
        assert!(out.contains("compile_error"), "{out}");
        assert!(out.contains(":3:26: unknown name `q`"), "{out}");
        // The stub still declares the model.
        assert!(out.contains("struct Bad"), "{out}");
    }

    #[test]
    fn a_missing_include_is_one_error_at_the_literal() {
        let out =
            expand(TokenStream::from_str("include \"no/such/file.dae\"").unwrap()).to_string();
        assert!(out.contains("cannot read `no/such/file.dae`"), "{out}");
    }

    #[test]
    fn keyword_parameters_become_raw_fields() {
        let src =
            "Kw { parameters { type = 2.0 } differential { x } equations { der(x) = -type * x; } }";
        let out = expand(TokenStream::from_str(src).unwrap()).to_string();
        assert!(out.contains("r#type"), "{out}");
        assert!(!out.contains("compile_error"), "{out}");
    }

    #[test]
    fn expansions_are_rust_items_with_round_tripping_literals() {
        let src = "Tiny {
            parameters { a = 1e-7, b = 1e300, c = -2.5 }
            differential { x }
            equations { der(x) = 1e-20 * x^-3 + b * x^1.5 - c * 2^x + a; }
        }";
        for text in [src, PENDULUM] {
            let out = expand(TokenStream::from_str(text).unwrap());
            let file: syn::File = syn::parse2(out.clone()).unwrap_or_else(|e| panic!("{e}: {out}"));
            assert!(!file.items.is_empty());
        }
        let out = expand(TokenStream::from_str(src).unwrap()).to_string();
        for lit in ["1e-7", "1e300", "1e-20", "1.5"] {
            assert!(out.contains(lit), "{lit} missing: {out}");
        }
    }

    /// Found by the `expand` fuzz target: a model whose guessed name or
    /// parameter is `_` or a keyword (`_// …` at the start) got a stub
    /// `struct _ {}` that is not Rust, so rustc reported a second, unrelated
    /// syntax error after the real one. The stub skips such names.
    #[test]
    fn stubs_of_broken_models_are_valid_rust() {
        let fuzzed = include_str!("../../fuzz/regressions/expand/underscore-model-name.dae");
        for src in [
            fuzzed,
            "_ { differential { x } }",
            "pub fn { parameters { _ = 1, type = 2, k = 3 } differential { x } }",
            "pub M { parameters { self = 1.0 } differential { x } equations { der(x) = x; } }",
        ] {
            let Ok(tokens) = TokenStream::from_str(src) else {
                panic!("{src} should lex");
            };
            let out = expand(tokens);
            syn::parse2::<syn::File>(out.clone()).unwrap_or_else(|e| panic!("{src}: {e}: {out}"));
            assert!(out.to_string().contains("compile_error"), "{src}: {out}");
        }
    }

    /// Issue 9, defect 1: a function of a fraction used to crash rustc
    /// (the row texts of the generated docs recursed forever).
    #[test]
    fn functions_of_fractions_expand() {
        for rhs in ["sin(0.5)", "exp(3/2)", "sqrt(1/2)", "(3/2)^x"] {
            let src = format!("C {{ differential {{ x }} equations {{ der(x) = {rhs}; }} }}");
            let out = expand(TokenStream::from_str(&src).unwrap());
            let file: syn::File = syn::parse2(out.clone()).unwrap_or_else(|e| panic!("{e}: {out}"));
            assert!(!file.items.is_empty());
            assert!(!out.to_string().contains("compile_error"), "{out}");
        }
    }

    /// Issue 9, defect 2: the expansion of models at the nesting limit
    /// runs in a quarter of an 8 MiB stack; past the limit it is one
    /// `compile_error!`; a 20,000-term sum is a flat node.
    #[test]
    fn deep_and_long_models_expand_in_a_small_stack() {
        let limit = dae_core::dsl::MAX_DEPTH;
        let cases = [
            (
                format!("{}x{}", "sin(".repeat(limit), ")".repeat(limit)),
                true,
            ),
            (format!("{}x{}", "(".repeat(limit), ")".repeat(limit)), true),
            (vec!["x"; 20_000].join(" + "), true),
            (
                format!("{}x{}", "sin(".repeat(limit + 1), ")".repeat(limit + 1)),
                false,
            ),
            (format!("{}x", "-".repeat(10_000)), false),
        ];
        for (rhs, ok) in cases {
            let out = std::thread::Builder::new()
                .stack_size(2 << 20)
                .spawn(move || {
                    let src =
                        format!("C {{ differential {{ x }} equations {{ der(x) = {rhs}; }} }}");
                    expand(TokenStream::from_str(&src).unwrap()).to_string()
                })
                .unwrap()
                .join()
                .unwrap();
            if ok {
                assert!(
                    !out.contains("compile_error"),
                    "{}",
                    &out[..out.len().min(300)]
                );
            } else {
                assert!(
                    out.contains("expression nested too deep"),
                    "{}",
                    &out[..out.len().min(300)]
                );
            }
        }
    }

    #[test]
    fn tokens_are_counted_with_groups() {
        let t = TokenStream::from_str("a (b c) [d]").unwrap();
        assert_eq!(count_tokens(&t), 6);
    }
}

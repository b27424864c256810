//! The front half in one call: text or tokens → checked model → index
//! analysis → formulations, with every error at its token.

use crate::expr;
use crate::formulation::{self, Formulation};
use crate::index::{self, Analysis};
use crate::model::Model;
use crate::system::{ModelInfo, ParamInfo, VarInfo};
use proc_macro2::TokenStream;

/// A model with its hidden constraints and the formulations it provides.
#[derive(Clone, Debug)]
pub struct Derived {
    /// The checked model.
    pub model: Model,
    /// Its constraint chains.
    pub analysis: Analysis,
    /// The formulations it provides, in the paper's order.
    pub formulations: Vec<Formulation>,
}

impl Derived {
    /// Derive from the tokens of a `dae! { … }` body.
    pub fn from_tokens(tokens: TokenStream) -> Result<Derived, syn::Error> {
        let ast = crate::dsl::parse(tokens)?;
        Self::from_ast(&ast)
    }

    /// Derive from model text (a `.dae` file).
    #[allow(clippy::should_implement_trait)] // returns `syn::Error` with spans, unlike `str::parse`
    pub fn from_str(src: &str) -> Result<Derived, syn::Error> {
        let ast = crate::dsl::parse_str(src)?;
        Self::from_ast(&ast)
    }

    /// Derive from a parsed model.
    ///
    /// The whole derivation spends at most [`expr::WORK_BUDGET`] units of
    /// symbolic work ([`expr::Budget`]); a model that needs more stops with
    /// an error at the definition, equation or constraint that grew, or at
    /// the model's name for a formulation.
    pub fn from_ast(ast: &crate::dsl::ModelAst) -> Result<Derived, syn::Error> {
        let _budget = expr::Budget::start(expr::WORK_BUDGET);
        let model = Model::check(ast)?;
        let analysis = index::analyse(&model)?;
        let grew = |what: &str| {
            expr::exhausted().then(|| {
                let why = expr::Grew::Work {
                    limit: expr::WORK_BUDGET,
                };
                syn::Error::new(model.name_span, format!("{what} {why}"))
            })
        };
        if let Some(e) = grew("the hidden constraints' analysis") {
            return Err(e);
        }
        let names = formulation::provided(&model, &analysis)?;
        let mut formulations = Vec::new();
        for n in names {
            let f = formulation::build(&model, &analysis, n);
            if let Some(e) = grew(&format!("formulation `{n}`")) {
                return Err(e);
            }
            formulations.push(f.map_err(|why| syn::Error::new(model.name_span, why))?);
        }
        Ok(Derived {
            model,
            analysis,
            formulations,
        })
    }

    /// The formulation called `name`, if provided.
    pub fn formulation(&self, name: &str) -> Option<&Formulation> {
        self.formulations.iter().find(|f| f.name == name)
    }

    /// Static description of the model.
    pub fn model_info(&self) -> ModelInfo {
        let m = &self.model;
        ModelInfo {
            name: m.name.clone(),
            doc: m.doc.clone(),
            variables: m
                .vars
                .iter()
                .map(|v| VarInfo {
                    name: v.name.clone(),
                    kind: v.kind,
                    index: 1,
                })
                .collect(),
            parameters: m
                .params
                .iter()
                .map(|p| ParamInfo {
                    name: p.name.clone(),
                    default: p.default,
                    derived: p.derived.as_ref().map(|e| m.text(e)),
                })
                .collect(),
            constraints: self.constraint_infos(),
            invariants: m.invariants.iter().map(|i| i.name.clone()).collect(),
            events: m.events.iter().map(|e| e.name.clone()).collect(),
            formulations: self
                .formulations
                .iter()
                .map(|f| f.name.to_string())
                .collect(),
        }
    }
}

/// Render an error with `line:column` positions (for run-time models).
pub fn render_error(err: &syn::Error, file: &str) -> String {
    err.clone()
        .into_iter()
        .map(|e| {
            let start = e.span().start();
            format!("{file}:{}:{}: error: {}", start.line, start.column + 1, e)
        })
        .collect::<Vec<_>>()
        .join("\n")
}

//! What `dae derive` prints: the hidden constraints, the formulations and
//! their structural numbers, as text, LaTeX or JSON.
//!
//! The JSON shape is a contract (field order included):
//! `{"model", "variables": [{"name", "kind"}], "parameters": {name: value},
//! "constraints": [{"level", "source", "expr"}], "invariants": [{"name",
//! "expr"}], "formulations": [{"name", "unknowns", "equations",
//! "differential_equations", "algebraic_equations", "d_index", "s_index",
//! "c_level", "rows"}]}`.

use crate::derive::Derived;
use crate::system::VarKind;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use std::fmt::Write;

/// The derive report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Model name.
    pub model: String,
    /// Unknowns.
    pub variables: Vec<Variable>,
    /// Parameters with defaults, in model order.
    pub parameters: Parameters,
    /// The constraint chain.
    pub constraints: Vec<crate::system::ConstraintInfo>,
    /// Invariants.
    pub invariants: Vec<Invariant>,
    /// Formulations.
    pub formulations: Vec<FormulationReport>,
}

/// An unknown.
#[derive(Clone, Debug, Serialize)]
pub struct Variable {
    /// Name.
    pub name: String,
    /// `differential` or `algebraic`.
    pub kind: VarKind,
}

/// Parameters as an ordered JSON object.
#[derive(Clone, Debug)]
pub struct Parameters(pub Vec<(String, f64)>);

impl Serialize for Parameters {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// An invariant.
#[derive(Clone, Debug, Serialize)]
pub struct Invariant {
    /// Name.
    pub name: String,
    /// Expression in the model language.
    pub expr: String,
}

/// One formulation.
#[derive(Clone, Debug, Serialize)]
pub struct FormulationReport {
    /// Name.
    pub name: String,
    /// Number of unknowns.
    pub unknowns: usize,
    /// Number of equations.
    pub equations: usize,
    /// Differential rows.
    pub differential_equations: usize,
    /// Constraint rows.
    pub algebraic_equations: usize,
    /// Differentiation index (`null` when undefined).
    pub d_index: Option<u8>,
    /// Strangeness index.
    pub s_index: u8,
    /// Maximal constraint level.
    pub c_level: u8,
    /// Rows in the model language.
    pub rows: Vec<String>,
}

impl Report {
    /// Build the report of a derived model.
    pub fn new(d: &Derived) -> Report {
        let m = &d.model;
        Report {
            model: m.name.clone(),
            variables: m
                .vars
                .iter()
                .map(|v| Variable {
                    name: v.name.clone(),
                    kind: v.kind,
                })
                .collect(),
            parameters: Parameters(
                m.params
                    .iter()
                    .map(|p| (p.name.clone(), p.default))
                    .collect(),
            ),
            constraints: d.constraint_infos(),
            invariants: m
                .invariants
                .iter()
                .map(|i| Invariant {
                    name: i.name.clone(),
                    expr: m.text(&i.expr),
                })
                .collect(),
            formulations: d
                .formulations
                .iter()
                .map(|f| {
                    let diff = f.differential_rows();
                    FormulationReport {
                        name: f.name.to_string(),
                        unknowns: f.vars.len(),
                        equations: f.rows.len(),
                        differential_equations: diff,
                        algebraic_equations: f.rows.len() - diff,
                        d_index: f.d_index,
                        s_index: f.s_index,
                        c_level: f.c_level,
                        rows: (0..f.rows.len()).map(|i| f.row_text(m, i)).collect(),
                    }
                })
                .collect(),
        }
    }

    /// Pretty JSON (deterministic: field order fixed, no maps with hashed
    /// order).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}

fn dash(v: Option<u8>) -> String {
    v.map_or_else(|| "-".to_string(), |v| v.to_string())
}

/// Human-readable text.
pub fn text(d: &Derived) -> String {
    let r = Report::new(d);
    let mut s = String::new();
    let _ = writeln!(s, "model {}", r.model);
    if !d.model.doc.is_empty() {
        for line in d.model.doc.lines() {
            let _ = writeln!(s, "  /// {line}");
        }
    }
    let names = |kind: VarKind| {
        r.variables
            .iter()
            .filter(|v| v.kind == kind)
            .map(|v| v.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(s, "  differential: {}", names(VarKind::Differential));
    let _ = writeln!(s, "  algebraic:    {}", names(VarKind::Algebraic));
    let params: Vec<String> = r
        .parameters
        .0
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    let _ = writeln!(s, "  parameters:   {}", params.join(", "));
    let _ = writeln!(
        s,
        "\nconstraints (level k = k-th total time derivative along the dynamics)"
    );
    for c in &r.constraints {
        let _ = writeln!(s, "  [{}] level {}: 0 = {}", c.source, c.level, c.expr);
    }
    if !r.invariants.is_empty() {
        let _ = writeln!(s, "\ninvariants");
        for i in &r.invariants {
            let _ = writeln!(s, "  {} = {}", i.name, i.expr);
        }
    }
    let _ = writeln!(s, "\nformulations");
    let _ = writeln!(s, "  name  unknowns/equations  d-index  s-index  c-level");
    for f in &r.formulations {
        let _ = writeln!(
            s,
            "  {:<5} {:>8}/{:<9} {:>7}  {:>7}  {:>7}",
            f.name,
            f.unknowns,
            f.equations,
            dash(f.d_index),
            f.s_index,
            f.c_level
        );
    }
    for f in &r.formulations {
        let _ = writeln!(
            s,
            "\n{} ({} unknowns, {} equations)",
            f.name, f.unknowns, f.equations
        );
        for row in &f.rows {
            let _ = writeln!(s, "  {row}");
        }
    }
    s
}

/// LaTeX (an `align*` environment per block).
pub fn latex(d: &Derived) -> String {
    let m = &d.model;
    let mut s = String::new();
    let _ = writeln!(s, "% {} — derived by dae", m.name);
    let _ = writeln!(s, "\\paragraph{{Constraints}}\n\\begin{{align*}}");
    let chain = d.analysis.flat();
    for (k, (source, level, e)) in chain.iter().enumerate() {
        let end = if k + 1 < chain.len() { " \\\\" } else { "" };
        let _ = writeln!(
            s,
            "  0 &= {} && \\text{{constraint {source}, level {level}}}{end}",
            crate::print::latex(e, &|sym| m.sym_name(sym, &[]))
        );
    }
    let _ = writeln!(s, "\\end{{align*}}");
    for f in &d.formulations {
        let _ = writeln!(
            s,
            "\\paragraph{{{}}} d-index {}, s-index {}, c-level {}.\n\\begin{{align*}}",
            f.name,
            dash(f.d_index),
            f.s_index,
            f.c_level
        );
        for i in 0..f.rows.len() {
            let row = f.row_latex(m, i).replacen(" = ", " &= ", 1);
            let end = if i + 1 < f.rows.len() { " \\\\" } else { "" };
            let _ = writeln!(s, "  {row}{end}");
        }
        let _ = writeln!(s, "\\end{{align*}}");
    }
    s
}

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
    /// Event functions (`events { … }`), with the same shape as
    /// invariants; omitted from JSON when the model has none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<Invariant>,
    /// Formulations.
    pub formulations: Vec<FormulationReport>,
    /// The paper's formulations this model does not offer, each with why.
    pub not_offered: Vec<NotOffered>,
}

/// A formulation the model does not offer.
#[derive(Clone, Debug, Serialize)]
pub struct NotOffered {
    /// Its name.
    pub name: String,
    /// Why: the structural reason it does not apply, or that the model's
    /// `formulations { … }` list leaves it out.
    pub reason: String,
}

/// The formulations of [`FORMULATION_NAMES`](crate::system::FORMULATION_NAMES)
/// that `d` does not provide, with the reason.
pub fn not_offered(d: &Derived) -> Vec<NotOffered> {
    crate::system::FORMULATION_NAMES
        .iter()
        .filter(|n| !d.formulations.iter().any(|f| f.name == **n))
        .map(|n| NotOffered {
            name: n.to_string(),
            reason: match crate::formulation::applicable(&d.model, &d.analysis, n) {
                Err(why) => why,
                Ok(()) => "applies, but the model's `formulations { … }` list leaves it out".into(),
            },
        })
        .collect()
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
    /// Rows in the model language (for `mex0`, the rows it chooses from).
    pub rows: Vec<String>,
    /// `mex0`: the dummy derivatives to choose, per order (empty for the
    /// other formulations, and then left out of the JSON).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dummies: Vec<DummyReport>,
}

/// The dummy derivatives one order of `mex0`'s rows chooses.
#[derive(Clone, Debug, Serialize)]
pub struct DummyReport {
    /// Differentiations still below the top of the rows' chains.
    pub order: u8,
    /// How many dummies.
    pub count: usize,
    /// The differential unknowns they are chosen among.
    pub among: Vec<String>,
    /// Algebraic unknowns these rows also determine.
    pub algebraic: Vec<String>,
    /// `true` when one choice serves everywhere (as many candidates as
    /// dummies, or a constant Jacobian): made once; otherwise re-chosen at
    /// run time where it degenerates.
    pub fixed: bool,
}

/// `mex0`'s dummy derivatives, read off the symbolic chain.
fn dummies(d: &Derived) -> Vec<DummyReport> {
    let m = &d.model;
    let Ok(blocks) = crate::dummy::symbolic_blocks(m, &d.analysis) else {
        return Vec::new();
    };
    let flat = d.analysis.flat();
    let names = |js: &[usize]| js.iter().map(|&j| m.vars[j].name.clone()).collect();
    blocks
        .iter()
        .map(|b| {
            let constant = b.members.iter().all(|&r| {
                b.columns().into_iter().all(|j| {
                    let entry = crate::expr::diff(flat[r].2, crate::expr::Sym::Var(j as u32));
                    !entry.any_sym(&|s| {
                        matches!(s, crate::expr::Sym::Var(_) | crate::expr::Sym::Time)
                    })
                })
            });
            DummyReport {
                order: b.order,
                count: b.dummies(),
                among: names(&b.candidates),
                algebraic: names(&b.algebraic),
                fixed: constant || b.candidates.len() == b.dummies(),
            }
        })
        .collect()
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
            events: m
                .events
                .iter()
                .map(|e| Invariant {
                    name: e.name.clone(),
                    expr: m.text(&e.expr),
                })
                .collect(),
            formulations: d
                .formulations
                .iter()
                .map(|f| {
                    let mut diff = f.differential_rows();
                    let mut equations = f.rows.len();
                    let mut dummy = Vec::new();
                    if f.name == crate::dummy::NAME {
                        // Square: the dummies' dynamics rows are dropped.
                        dummy = dummies(d);
                        diff -= dummy.iter().map(|b| b.count).sum::<usize>();
                        equations = f.vars.len();
                    }
                    FormulationReport {
                        name: f.name.to_string(),
                        unknowns: f.vars.len(),
                        equations,
                        differential_equations: diff,
                        algebraic_equations: equations - diff,
                        d_index: f.d_index,
                        s_index: f.s_index,
                        c_level: f.c_level,
                        rows: (0..f.rows.len()).map(|i| f.row_text(m, i)).collect(),
                        dummies: dummy,
                    }
                })
                .collect(),
            not_offered: not_offered(d),
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
    let own = d.analysis.chains.len();
    for c in &r.constraints {
        let _ = write!(s, "  [{}] level {}: 0 = {}", c.source, c.level, c.expr);
        if let Some(i) = (c.source as usize)
            .checked_sub(own)
            .and_then(|k| d.analysis.implied.get(k))
        {
            let rows: Vec<String> = i
                .rows
                .iter()
                .map(|(u, w)| {
                    let row = format!("row of der({})", d.model.vars[*u].name);
                    if w.is_one() {
                        row
                    } else {
                        format!("({})·{row}", d.model.text(w))
                    }
                })
                .collect();
            let _ = write!(
                s,
                "   (implied by the singular mass matrix: der() cancels in {})",
                rows.join(" + ")
            );
        }
        let _ = writeln!(s);
    }
    if !r.invariants.is_empty() {
        let _ = writeln!(s, "\ninvariants");
        for i in &r.invariants {
            let _ = writeln!(s, "  {} = {}", i.name, i.expr);
        }
    }
    if !r.events.is_empty() {
        let _ = writeln!(s, "\nevents (zero crossings located along a solution)");
        for e in &r.events {
            let _ = writeln!(s, "  {} = {}", e.name, e.expr);
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
    for n in &r.not_offered {
        let _ = writeln!(s, "  {:<5} not offered: {}", n.name, n.reason);
    }
    for f in &r.formulations {
        let _ = writeln!(
            s,
            "\n{} ({} unknowns, {} equations)",
            f.name, f.unknowns, f.equations
        );
        for b in &f.dummies {
            let also = if b.algebraic.is_empty() {
                String::new()
            } else {
                format!(", with {}", b.algebraic.join(", "))
            };
            let how = if b.fixed {
                "chosen once"
            } else {
                "chosen at run time and re-chosen where the choice degenerates"
            };
            let _ = writeln!(
                s,
                "  dummy derivatives of order {}: {} of {}{also}, {how}",
                b.order,
                b.count,
                b.among.join(", "),
            );
        }
        if !f.dummies.is_empty() {
            let _ = writeln!(
                s,
                "  rows (the dummies' dynamics rows are dropped, every other row kept):"
            );
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    const PENDULUM: &str = "pub P {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        differential { x, y, v, w }
        algebraic { lambda }
        equations {
            der(x) = v; der(y) = w;
            m * der(v) = -2 * x * lambda;
            m * der(w) = -2 * y * lambda - m * g;
            0 = x^2 + y^2 - l^2;
        }
        FORMS
    }";

    #[test]
    fn derive_says_why_a_formulation_is_not_offered() {
        // All nine apply to the pendulum: nothing left out.
        let d = Derived::from_str(&PENDULUM.replace("FORMS", "")).unwrap();
        assert!(not_offered(&d).is_empty());
        // A list leaves the others out, and says so.
        let d =
            Derived::from_str(&PENDULUM.replace("FORMS", "formulations { ggl1, rcd0 }")).unwrap();
        let n = not_offered(&d);
        let names: Vec<&str> = n.iter().map(|x| x.name.as_str()).collect();
        assert_eq!(
            names,
            ["ori2", "rcd1", "ovd1", "ovd0", "psi1", "psi0", "mex0"]
        );
        assert!(
            n.iter().all(|x| x.reason.contains("leaves it out")),
            "{n:?}"
        );
        let text = text(&d);
        assert!(text.contains("ori2  not offered: applies, but"), "{text}");
        // An index-1 model (an algebraic equation that is not a position
        // constraint): the structural reason.
        let index1 = "pub Q {
            parameters { k = 1.0 }
            differential { x }
            algebraic { z }
            equations { der(x) = z; 0 = z + k * x; }
        }";
        let d = Derived::from_str(index1).unwrap();
        let n = not_offered(&d);
        let rcd1 = n
            .iter()
            .find(|x| x.name == "rcd1")
            .expect("rcd1 not offered");
        assert!(
            rcd1.reason.contains("hidden velocity level"),
            "{}",
            rcd1.reason
        );
        let json = serde_json::to_value(Report::new(&d)).unwrap();
        assert_eq!(json["not_offered"][0]["name"], n[0].name.as_str());
    }
}

//! Structural analysis beyond mechanics (issue 23): models whose algebraic
//! unknowns are not all multipliers of one constraint chain, analysed by the
//! Σ-method, with their hidden constraints checked against hand derivations
//! and the Jacobians of every formulation against central differences.

use dae_core::check::check_jacobians;
use dae_core::expr;
use dae_core::interp::InterpretedModel;
use dae_core::system::Model;
use dae_core::Derived;

/// A continuous stirred tank reactor whose output concentration is
/// prescribed (Brenan, Campbell & Petzold's form): `c` and `temp`
/// differential, the reaction rate `r` algebraic with its own equation, the
/// coolant temperature `tc` the control that makes `c = u(t)`. Index 3.
mod common;
use common::{assert_same, derive};

const CSTR: &str = "
pub Cstr {
    parameters { k1 = 1.0, k2 = 1.0, k3 = 1.0, k4 = 1.0, k5 = 1.0, c0 = 2.0, t0 = 1.0 }
    differential { c, temp }
    algebraic { r, tc }
    equations {
        der(c) = k1*(c0 - c) - r;
        der(temp) = k1*(t0 - temp) + k2*r - k3*(temp - tc);
        0 = r - k5*exp(-k4/temp)*c;
        0 = c - (1 + sin(t)/2);
    }
}";

#[test]
fn cstr_offsets_chains_and_index() {
    let d = derive(CSTR);
    let st = &d.analysis.structure;
    // Rows: the two dynamic equations, then the two constraints.
    assert_eq!(st.c, vec![1, 0, 1, 2]);
    assert_eq!(st.d, vec![2, 1, 1, 0]);
    assert_eq!(st.index(), 3);
    // The rate law determines r (level 0) and gives its derivative.
    assert_eq!(d.analysis.chains[0].levels.len(), 1);
    assert_eq!(d.analysis.rates.len(), 1);
    assert_eq!(d.analysis.rates[0].0, 2);
    // The prescribed output is differentiated twice; its top level holds tc.
    let out = &d.analysis.chains[1];
    assert_eq!(out.levels.len(), 3);
    assert_same(&d, &out.levels[1], "k1*(c0 - c) - r - cos(t)/2");
    assert!(out.levels[2].contains(expr::Sym::Var(3)));
    assert_eq!(d.analysis.matching, vec![2, 3]);
    let ori = d.formulation("ori2").unwrap();
    assert_eq!(ori.d_index, Some(3));
    let rcd0 = d.formulation("rcd0").unwrap();
    assert_eq!(rcd0.d_index, Some(1));
    // Index 1 for the rate (fixed by its own equation), 3 for the control.
    // Index 1 for the concentration (prescribed), 2 for the rate (the
    // output's first derivative gives it), 3 for the control. The
    // temperature's is 2 as well (it follows from the rate through the rate
    // law), but the first-appearance rule of `formulation` counts the level
    // at which it enters the output's chain (2) and reports 3: an
    // over-estimate, which only loosens the error weight of `temp` in
    // `ori2` (Radau scales index-k components by h^(k−1)).
    let idx: Vec<u8> = ori.vars.iter().map(|v| v.index).collect();
    assert_eq!((idx[0], idx[2], idx[3]), (1, 2, 3));
    assert!(idx[1] >= 2);
    // rcd1: the rate law as written, the output differentiated once.
    let rcd1 = d.formulation("rcd1").unwrap();
    assert_eq!(rcd1.d_index, Some(2));
    for f in ["rcd0", "ovd0"] {
        let f = d.formulation(f).unwrap();
        assert!(f.vars.iter().all(|v| v.index == 1), "{}", f.name);
    }
}

#[test]
fn cstr_jacobians_of_every_formulation() {
    let model = InterpretedModel::from_str(CSTR).unwrap();
    let names = model.model_info().formulations.clone();
    assert!(names.len() >= 5, "{names:?}");
    for name in &names {
        let sys = model.formulation(name).unwrap();
        // As in paper.rs: central differences are accurate to ~1e-10 here.
        if let Err(m) = check_jacobians(&sys, 5, 42, 1e-7) {
            panic!("{name}: {m}");
        }
    }
}

/// Two coupled pairs of a constant mass matrix that is singular (rows
/// `−c·a' + c·b' = f1`, `c·a' − c·b' = f2`, as in the IVP Test Set's
/// transistor amplifier), and a regular pair beside them.
const SINGULAR_MASS: &str = "
pub SingularMass {
    parameters { c = 2.0, k = 3.0 }
    differential { a, b, p, q }
    equations {
        -c*der(a) + c*der(b) = a - sin(t);
        c*der(a) - c*der(b) = b;
        der(p) + der(q) = -p;
        der(p) - k*der(q) = q;
    }
}";

#[test]
fn a_constant_singular_mass_matrix_implies_its_row_combinations() {
    let d = derive(SINGULAR_MASS);
    let implied = &d.analysis.implied;
    assert_eq!(implied.len(), 1, "only the (a, b) block is singular");
    let rows: Vec<usize> = implied[0].rows.iter().map(|(u, _)| *u).collect();
    assert_eq!(rows, vec![0, 1]);
    assert!(implied[0].rows.iter().all(|(_, w)| w.is_one()));
    assert_same(&d, &implied[0].expr, "a - sin(t) + b");
    // A member of the chain (initialisation checks it), not a row.
    let chain = d.constraint_infos();
    assert_eq!(chain.len(), 1);
    assert_eq!((chain[0].source, chain[0].level), (0, 0));
    let ori = d.formulation("ori2").unwrap();
    assert_eq!(ori.rows.len(), 4);
    assert!(dae_core::report::text(&d).contains("implied by the singular mass matrix"));
}

#[test]
fn dependent_or_inconsistent_mass_rows_are_refused_at_the_row() {
    let redundant = SINGULAR_MASS.replace("= b;", "= -(a - sin(t));");
    let e = Derived::from_str(&redundant).unwrap_err().to_string();
    assert!(e.contains("linearly dependent"), "{e}");
    let inconsistent = SINGULAR_MASS.replace("= b;", "= 1 - (a - sin(t));");
    let e = Derived::from_str(&inconsistent).unwrap_err().to_string();
    assert!(e.contains("inconsistent"), "{e}");
}

/// A linear DAE of index 2 whose second unknown has no equation for its
/// derivative of its own (the Gear–Hsu–Petzold structure with a constant
/// coefficient): `y1 + c y2 = f1`, `y1' + c y2' + (1 + c) y2 = f2`.
const IMPLICIT: &str = "
pub Implicit {
    parameters { c = 2.0 }
    differential { y1, y2 }
    equations {
        0 = y1 + c*y2 - exp(-t);
        der(y1) + c*der(y2) + (1 + c)*y2 = sin(t);
    }
}";

#[test]
fn a_differential_unknown_without_its_own_equation_is_determined_by_the_constraints() {
    let d = derive(IMPLICIT);
    assert_eq!(d.model.implicit, vec![1]);
    assert_eq!(d.model.dynamics.len(), 1);
    assert_eq!(d.model.dynamics[0].var, 0);
    let chain = &d.analysis.chains[0];
    assert_eq!(chain.levels.len(), 2);
    // y1' = sin t − (1 + c) y2 − c y2' substituted: the der() cancel.
    assert_same(&d, &chain.levels[1], "sin(t) - (1 + c)*y2 + exp(-t)");
    assert_eq!(d.analysis.matching, vec![1]);
    let ori = d.formulation("ori2").unwrap();
    assert_eq!(ori.d_index, Some(2));
    let idx: Vec<u8> = ori.vars.iter().map(|v| v.index).collect();
    assert_eq!(idx, vec![1, 2]);
    let rcd0 = d.formulation("rcd0").unwrap();
    assert_eq!(rcd0.d_index, Some(1));
    // The dynamic row keeps both der(): E = [[1, c], [0, 0]].
    let row = rcd0.rows.iter().find(|r| r.e.len() == 2).unwrap();
    assert_eq!(
        row.e.iter().map(|(j, _)| *j).collect::<Vec<_>>(),
        vec![0, 1]
    );
    let model = InterpretedModel::from_str(IMPLICIT).unwrap();
    for name in &model.model_info().formulations.clone() {
        let sys = model.formulation(name).unwrap();
        if let Err(m) = check_jacobians(&sys, 5, 42, 1e-7) {
            panic!("{name}: {m}");
        }
    }
}

#[test]
fn an_implicit_unknown_still_needs_its_constraint() {
    let e = Derived::from_str(&IMPLICIT.replace("0 = y1 + c*y2 - exp(-t);", ""))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("too few equations: no equation gives `der(y2)`"),
        "{e}"
    );
}

//! Definitions and derived parameters change how a model is written, not
//! what is derived from it: a model written with them and the same model
//! with them pasted in give equal formulations — equal tapes in the
//! interpreter, equal residuals and Jacobians at random points interpreted
//! and compiled alike. Derived parameters follow their base parameters and
//! cannot be set.

use dae::dae_core::check::{check_jacobians, Lcg};
use dae::dae_core::compile::compile;
use dae::dae_core::derive::{render_error, Derived};
use dae::dae_core::interp::InterpretedModel;
use dae::dae_core::system::ParameterError;
use dae::dae_core::tape::Op;
use dae::prelude::*;
use nalgebra::DMatrix;

mod andrews {
    dae::dae! { include "scenes/andrews.dae" }
}
mod andrews_pasted {
    dae::dae! { include "tests/data/andrews_pasted.dae" }
}
mod pendulum {
    dae::dae! { include "scenes/pendulum.dae" }
}
mod derived {
    dae::dae! { include "tests/data/pendulum_derived.dae" }
}

const ANDREWS: &str = include_str!("../scenes/andrews.dae");
const ANDREWS_PASTED: &str = include_str!("data/andrews_pasted.dae");
const PENDULUM: &str = include_str!("../scenes/pendulum.dae");
const PENDULUM_DERIVED: &str = include_str!("data/pendulum_derived.dae");

/// `|a − b| ≤ tol · max(1, |b|)` for every element.
fn close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (k, (x, z)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - z).abs() <= tol * z.abs().max(1.0),
            "{what}[{k}]: {x} vs {z}"
        );
    }
}

/// Every function of the runtime trait of `a` and `b` at `points` random
/// points: values within `tol` (relative).
fn same_numbers(a: &dyn DaeSystem, b: &dyn DaeSystem, points: usize, tol: f64, label: &str) {
    let mut rng = Lcg(17);
    let (n, m, k) = (
        a.info().unknowns(),
        a.info().equations(),
        a.info().constraints.len(),
    );
    assert_eq!(
        (n, m, k),
        (
            b.info().unknowns(),
            b.info().equations(),
            b.info().constraints.len()
        ),
        "{label}: sizes"
    );
    let ni = a.info().invariants.len();
    let dense = |f: &dyn Fn(&dyn DaeSystem, &mut [f64]), len: usize, what: &str| {
        let (mut x, mut z) = (vec![0.0; len], vec![0.0; len]);
        f(a, &mut x);
        f(b, &mut z);
        close(&x, &z, tol, &format!("{label} {what}"));
    };
    let matrix = |f: &dyn Fn(&dyn DaeSystem, &mut DMatrix<f64>), rows: usize, what: &str| {
        let (mut x, mut z) = (DMatrix::zeros(rows, n), DMatrix::zeros(rows, n));
        f(a, &mut x);
        f(b, &mut z);
        close(x.as_slice(), z.as_slice(), tol, &format!("{label} {what}"));
    };
    for _ in 0..points {
        let y: Vec<f64> = (0..n).map(|_| rng.range(-1.5, 1.5)).collect();
        let yp: Vec<f64> = (0..n).map(|_| rng.range(-1.5, 1.5)).collect();
        let z: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let t = rng.range(0.0, 1.0);
        dense(&|s, o| s.residual(t, &y, &yp, o), m, "residual");
        dense(&|s, o| s.rhs(t, &y, o), m, "rhs");
        dense(&|s, o| s.constraints(t, &y, o), k, "constraints");
        dense(&|s, o| s.invariants(t, &y, o), ni, "invariants");
        matrix(&|s, o| s.leading(t, &y, o), m, "leading");
        matrix(&|s, o| s.rhs_jacobian(t, &y, o), m, "rhs_jacobian");
        matrix(
            &|s, o| s.leading_jacobian(t, &y, &z, o),
            m,
            "leading_jacobian",
        );
        matrix(
            &|s, o| s.constraints_jacobian(t, &y, o),
            k,
            "constraints_jacobian",
        );
    }
}

/// Andrews' squeezer with definitions derives exactly the formulations of
/// the pasted model: the same rows, indices and compiled tapes.
#[test]
fn andrews_definitions_derive_the_pasted_formulations() {
    let with =
        Derived::from_str(ANDREWS).unwrap_or_else(|e| panic!("{}", render_error(&e, "andrews")));
    let pasted = Derived::from_str(ANDREWS_PASTED).unwrap();
    assert_eq!(with.model.definitions.len(), 6);
    assert_eq!(with.formulations.len(), pasted.formulations.len());
    assert_eq!(with.constraint_infos(), pasted.constraint_infos());
    for (f, g) in with.formulations.iter().zip(&pasted.formulations) {
        assert_eq!(f.name, g.name);
        assert_eq!(compile(&with, f), compile(&pasted, g), "{}", f.name);
    }
}

/// The same, numerically: interpreted and compiled, with and without
/// definitions, all four agree at random points.
#[test]
fn andrews_definitions_agree_interpreted_and_compiled() {
    let interp = InterpretedModel::from_str(ANDREWS).unwrap();
    let interp_pasted = InterpretedModel::from_str(ANDREWS_PASTED).unwrap();
    let compiled = andrews::Andrews::default();
    let compiled_pasted = andrews_pasted::Andrews::default();
    // rcd1/ovd1 keep the seven algebraic equations (level 0) as written
    // and the six constraints at the velocity level.
    assert_eq!(
        compiled.model_info().formulations,
        ["ori2", "rcd1", "rcd0", "ovd1", "ovd0", "mex0"]
    );
    // `mex0` chooses its rows where it is first evaluated: its rows are
    // compared, each instance chooses on its own (tests/mex0.rs).
    let mex0: [(&str, Box<dyn DaeSystem>); 3] = [
        ("interpreted", Box::new(interp.system("mex0").unwrap())),
        ("compiled", Box::new(compiled.mex0())),
        ("compiled pasted", Box::new(compiled_pasted.mex0())),
    ];
    let reference = interp_pasted.system("mex0").unwrap();
    for (label, sys) in mex0 {
        same_numbers(&*sys, &reference, 3, 1e-12, &format!("{label}/mex0 rows"));
    }
    for name in &compiled.model_info().formulations {
        if name == "mex0" {
            continue;
        }
        let reference = interp_pasted.formulation(name).unwrap();
        for (label, sys) in [
            ("interpreted", interp.formulation(name).unwrap()),
            ("compiled", compiled.formulation(name).unwrap()),
            (
                "compiled pasted",
                compiled_pasted.formulation(name).unwrap(),
            ),
        ] {
            same_numbers(&*sys, &*reference, 3, 1e-12, &format!("{label}/{name}"));
        }
    }
}

/// A subexpression pasted six times is evaluated once: the tapes share
/// identical subexpressions (hash consing in `TapeBuilder`), so the
/// residual of `ori2` holds one square root, the spring's length, whether
/// it was written with `lang` or pasted. The macro emits one `let` per
/// tape node, so the compiled residual computes it once too.
#[test]
fn a_definition_is_evaluated_once_per_call() {
    for src in [ANDREWS, ANDREWS_PASTED] {
        let d = Derived::from_str(src).unwrap();
        let c = compile(&d, d.formulation("ori2").unwrap());
        let roots = |nodes: &[Op]| nodes.iter().filter(|op| matches!(op, Op::Sqrt(_))).count();
        assert_eq!(roots(&c.residual.nodes), 1);
        assert_eq!(roots(&c.rhs.nodes), 1);
        // Its Jacobian divides by powers of the same root: still one.
        assert_eq!(roots(&c.rhs_jacobian.tape.nodes), 1);
    }
}

/// The pendulum with derived parameters and definitions and the plain
/// pendulum: the same numbers everywhere, at the defaults and after a base
/// parameter changed, interpreted and compiled.
#[test]
fn derived_parameters_give_the_plain_pendulum() {
    let mut interp = InterpretedModel::from_str(PENDULUM_DERIVED).unwrap();
    let mut compiled = derived::PendulumDerived::default();
    let mut plain_interp = InterpretedModel::from_str(PENDULUM).unwrap();
    let mut plain = pendulum::Pendulum::default();
    for step in 0..2 {
        if step == 1 {
            for (name, value) in [("l", 1.7), ("m", 0.6), ("g", 9.81)] {
                interp.set_parameter(name, value).unwrap();
                compiled.set_parameter(name, value).unwrap();
                plain_interp.set_parameter(name, value).unwrap();
                plain.set_parameter(name, value).unwrap();
            }
        }
        for (label, model) in [
            ("interpreted", &interp as &dyn Model),
            ("compiled", &compiled as &dyn Model),
        ] {
            let l = model.parameter("l").unwrap();
            assert_eq!(model.parameter("l2"), Some(l * l), "{label}");
            let (m, g) = (model.parameter("m").unwrap(), model.parameter("g").unwrap());
            assert_eq!(model.parameter("weight"), Some(m * g), "{label}");
            for name in &model.model_info().formulations {
                let sys = model.formulation(name).unwrap();
                for (plain_label, reference) in [
                    ("plain interpreted", plain_interp.formulation(name).unwrap()),
                    ("plain compiled", plain.formulation(name).unwrap()),
                ] {
                    same_numbers(
                        &*sys,
                        &*reference,
                        4,
                        1e-12,
                        &format!("{label} vs {plain_label}/{name} (step {step})"),
                    );
                }
                if let Err(e) = check_jacobians(&*sys, 3, 5, 1e-7) {
                    panic!("{label}/{name}: {e}");
                }
                // The derived values follow the base ones.
                let values = sys.parameter_values();
                assert_eq!(values.len(), 6);
                assert_eq!(values[3], l * l, "{label}/{name}");
            }
        }
    }
    // Interpreted and compiled describe the model alike.
    assert_eq!(interp.model_info(), compiled.model_info());
    let info = compiled.model_info();
    assert_eq!(info.parameters[3].derived.as_deref(), Some("l^2"));
    assert_eq!(info.parameters[0].derived, None);
}

/// Setting a derived parameter is a typed error, and so is a base value
/// that would make a derived one non-finite; neither changes anything.
#[test]
fn derived_parameters_cannot_be_set() {
    let mut interp = InterpretedModel::from_str(PENDULUM_DERIVED).unwrap();
    let mut compiled = derived::PendulumDerived::default();
    for (label, model) in [
        ("interpreted", &mut interp as &mut dyn Model),
        ("compiled", &mut compiled as &mut dyn Model),
    ] {
        let e = model.set_parameter("l2", 4.0).unwrap_err();
        assert_eq!(
            e,
            ParameterError::Derived {
                model: "PendulumDerived".into(),
                name: "l2".into(),
                expr: "l^2".into(),
            },
            "{label}"
        );
        assert_eq!(
            e.to_string(),
            "parameter `l2` of model `PendulumDerived` is derived (`l2 = l^2`): set the parameters it is computed from instead"
        );
        assert_eq!(model.parameter("l2"), Some(1.0), "{label}");
        let e = model.set_parameter("l", 1e200).unwrap_err();
        assert!(
            matches!(&e, ParameterError::DerivedNotFinite { name, derived, .. } if name == "l" && derived == "l2"),
            "{label}: {e}"
        );
        assert_eq!(model.parameter("l"), Some(1.0), "{label}: unchanged");
        assert!(matches!(
            model.set_parameter("l3", 1.0),
            Err(ParameterError::Unknown { known, .. }) if known == "m, l, g, l2, weight, half_m"
        ));
    }
}

/// The binary's messages for the mistakes the new sections allow, each at
/// `file:line:column`.
#[test]
fn mistakes_are_located() {
    let model = |derived: &str, definitions: &str, constraint: &str| {
        format!(
            "P {{\n    parameters {{ m = 1.0, l = 1.0, g = 9.81 }}\n    derived {{ {derived} }}\n    differential {{ x, y, v, w }}\n    algebraic {{ lambda }}\n    definitions {{ {definitions} }}\n    equations {{\n        der(x) = v;\n        der(y) = w;\n        m * der(v) = -2 * x * lambda;\n        m * der(w) = -2 * y * lambda - m * g;\n        0 = {constraint};\n    }}\n}}\n"
        )
    };
    let cases = [
        (
            model("", "r2 = x^2 + yy^2;", "r2 - l^2"),
            "m.dae:6:30: error: unknown name `yy`: not a parameter, an unknown or a definition of this model",
        ),
        (
            model("", "r2 = x^2 + y^2;", "r3 - l^2"),
            "m.dae:12:13: error: unknown name `r3`: not a parameter, an unknown or a definition of this model",
        ),
        (
            model("", "a = b + x; b = a * y; r2 = x^2 + y^2;", "r2 - l^2"),
            "m.dae:6:23: error: definitions form a cycle: `a` → `b` → `a`",
        ),
        (
            model("", "r2 = sx + y^2; sx = x^2;", "r2 - l^2"),
            "m.dae:6:24: error: definition `sx` is used before it is defined: definitions are read in order, so move `sx` above `r2`",
        ),
        (
            model("", "r2 = r2 + x^2;", "r2 - l^2"),
            "m.dae:6:24: error: definition `r2` refers to itself",
        ),
        (
            model("", "v = 2; r2 = x^2 + y^2;", "r2 - l^2"),
            "m.dae:6:19: error: definition `v` clashes with the differential unknown `v`: every name of a model is unique\nm.dae:4:26: error: the differential unknown `v` is declared here",
        ),
        (
            model("", "cos = 2; r2 = x^2 + y^2;", "r2 - l^2"),
            "m.dae:6:19: error: `cos` is reserved (a function of the model language)",
        ),
        (
            model("", "r2 = x^2 + y^2 + der(x);", "r2 - l^2"),
            "m.dae:6:36: error: der() is not allowed in a definition: a definition is an expression of parameters, unknowns and `t`; write der() in the equation",
        ),
        (
            model("g = 2;", "r2 = x^2 + y^2;", "r2 - l^2"),
            "m.dae:3:15: error: derived parameter `g` clashes with the parameter `g`: every name of a model is unique\nm.dae:2:36: error: the parameter `g` is declared here",
        ),
        (
            model("k = l * x;", "r2 = x^2 + y^2;", "r2 - k"),
            "m.dae:3:23: error: derived parameter `k` may depend on parameters only, and `x` is an unknown",
        ),
        (
            model("k = l + r2;", "r2 = x^2 + y^2;", "r2 - k"),
            "m.dae:3:23: error: derived parameter `k` may depend on parameters only, and `r2` is a definition",
        ),
        (
            model("k = j; j = k;", "r2 = x^2 + y^2;", "r2 - k"),
            "m.dae:3:19: error: derived parameters form a cycle: `k` → `j` → `k`",
        ),
        (
            model("k = ln(l - 1);", "r2 = x^2 + y^2;", "r2 - k"),
            "m.dae:3:15: error: derived parameter `k` is -inf at the parameters' defaults",
        ),
    ];
    let mut wrong = Vec::new();
    for (src, expected) in cases {
        let e = Derived::from_str(&src).map(|_| ()).unwrap_err();
        let got = render_error(&e, "m.dae");
        if got != expected {
            wrong.push(format!("{src}\n  got:      {got}\n  expected: {expected}"));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

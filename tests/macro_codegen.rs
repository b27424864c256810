//! The code `dae!` generates against the interpreter of the same model:
//! one model text, two implementations of `DaeSystem`, the same numbers.
//!
//! The pendulum is expanded twice — from `include "scenes/pendulum.dae"`
//! and inline — and every formulation of both is compared with
//! `InterpretedModel` at pseudo-random points: every method to 1e-13
//! relative, `info()` equal, buffers overwritten whole.

use dae::dae_core::check::Lcg;
use dae_core::interp::InterpretedModel;
use dae_core::system::{DaeSystem, FormulationError, Model, ParameterError, StaticSize};
use nalgebra::DMatrix;

const PENDULUM: &str = include_str!("../scenes/pendulum.dae");

/// The pendulum's default `g` (the model text has one more digit than an
/// `f64` keeps).
const G_DEFAULT: f64 = 13.750_371_637_329_454;

mod included {
    dae::dae! { include "scenes/pendulum.dae" }
}

mod inline {
    dae::dae! {
        /// The simple pendulum (Steinbrecher 2015, example M001): a point mass on a
        /// massless rod of length l, in absolute coordinates.
        pub Pendulum {
            parameters { m = 1.0, l = 1.0, g = 13.7503716373294544 }
            differential { x, y, v, w }
            algebraic { lambda }
            equations {
                der(x) = v;
                der(y) = w;
                m * der(v) = -2 * x * lambda;
                m * der(w) = -2 * y * lambda - m * g;
                0 = x^2 + y^2 - l^2;
            }
            invariants { energy = m * (v^2 + w^2) / 2 + m * g * y; }
            formulations { ori2, rcd1, rcd0, ovd1, ovd0, ggl1, psi1, psi0, mex0 }
        }
    }
}

const RCD0_ONLY: &str = "
pub Pendulum {
    parameters { m = 1.0, l = 1.0, g = 9.81 }
    differential { x, y, v, w }
    algebraic { lambda }
    equations {
        der(x) = v;
        der(y) = w;
        m * der(v) = -2 * x * lambda;
        m * der(w) = -2 * y * lambda - m * g;
        0 = x^2 + y^2 - l^2;
    }
    formulations { rcd0 }
}";

mod rcd0_only {
    dae::dae! {
        pub Pendulum {
            parameters { m = 1.0, l = 1.0, g = 9.81 }
            differential { x, y, v, w }
            algebraic { lambda }
            equations {
                der(x) = v;
                der(y) = w;
                m * der(v) = -2 * x * lambda;
                m * der(w) = -2 * y * lambda - m * g;
                0 = x^2 + y^2 - l^2;
            }
            formulations { rcd0 }
        }
    }
}

/// `n` uniform numbers in `[-1.5, 1.5)`.
fn vector(rng: &mut Lcg, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.range(-1.5, 1.5)).collect()
}

fn close(what: &str, a: f64, b: f64) {
    let scale = a.abs().max(b.abs());
    assert!(
        a == b || (a - b).abs() <= 1e-13 * scale,
        "{what}: compiled {a:e} vs interpreted {b:e}"
    );
}

fn close_slices(what: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        close(&format!("{what}[{k}]"), *x, *y);
    }
}

fn close_matrices(what: &str, a: &DMatrix<f64>, b: &DMatrix<f64>) {
    assert_eq!(a.shape(), b.shape(), "{what}: shapes");
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            close(&format!("{what}[({i}, {j})]"), a[(i, j)], b[(i, j)]);
        }
    }
}

/// Every method of `compiled` agrees with `interpreted` at `points`
/// pseudo-random arguments. Output buffers start as NaN, so an entry the
/// compiled code forgets to write shows.
fn agree(compiled: &dyn DaeSystem, interpreted: &dyn DaeSystem, rng: &mut Lcg, points: usize) {
    let info = interpreted.info();
    let name = &info.name;
    assert_eq!(compiled.info(), info, "{name}: info");
    close_slices(
        &format!("{name}: parameters"),
        &compiled.parameter_values(),
        &interpreted.parameter_values(),
    );
    let (n, m, k, i) = (
        info.unknowns(),
        info.equations(),
        info.constraints.len(),
        info.invariants.len(),
    );
    let dense = |len: usize| (vec![f64::NAN; len], vec![f64::NAN; len]);
    let matrix = |rows: usize| {
        (
            DMatrix::from_element(rows, n, f64::NAN),
            DMatrix::from_element(rows, n, f64::NAN),
        )
    };
    for _ in 0..points {
        let t = rng.range(-2.0, 2.0);
        let (y, yp, z) = (vector(rng, n), vector(rng, n), vector(rng, n));

        let (mut a, mut b) = dense(m);
        compiled.rhs(t, &y, &mut a);
        interpreted.rhs(t, &y, &mut b);
        close_slices(&format!("{name}: rhs"), &a, &b);

        let (mut a, mut b) = dense(m);
        compiled.residual(t, &y, &yp, &mut a);
        interpreted.residual(t, &y, &yp, &mut b);
        close_slices(&format!("{name}: residual"), &a, &b);

        let (mut a, mut b) = matrix(m);
        compiled.leading(t, &y, &mut a);
        interpreted.leading(t, &y, &mut b);
        close_matrices(&format!("{name}: leading"), &a, &b);

        let (mut a, mut b) = matrix(m);
        compiled.rhs_jacobian(t, &y, &mut a);
        interpreted.rhs_jacobian(t, &y, &mut b);
        close_matrices(&format!("{name}: rhs_jacobian"), &a, &b);

        let (mut a, mut b) = matrix(m);
        compiled.leading_jacobian(t, &y, &z, &mut a);
        interpreted.leading_jacobian(t, &y, &z, &mut b);
        close_matrices(&format!("{name}: leading_jacobian"), &a, &b);

        let (mut a, mut b) = dense(k);
        compiled.constraints(t, &y, &mut a);
        interpreted.constraints(t, &y, &mut b);
        close_slices(&format!("{name}: constraints"), &a, &b);

        let (mut a, mut b) = matrix(k);
        compiled.constraints_jacobian(t, &y, &mut a);
        interpreted.constraints_jacobian(t, &y, &mut b);
        close_matrices(&format!("{name}: constraints_jacobian"), &a, &b);

        let (mut a, mut b) = dense(i);
        compiled.invariants(t, &y, &mut a);
        interpreted.invariants(t, &y, &mut b);
        close_slices(&format!("{name}: invariants"), &a, &b);
    }
}

/// Every formulation of `compiled` against the interpreter, with the
/// default parameters and with changed ones.
fn agree_model(compiled: &mut dyn Model, seed: u64) {
    let mut interpreted = InterpretedModel::from_str(PENDULUM).expect("the pendulum derives");
    assert_eq!(compiled.model_info(), interpreted.model_info());
    let mut rng = Lcg(seed);
    for pass in 0..2 {
        if pass == 1 {
            for (name, value) in [("m", 1.3), ("l", 0.8), ("g", 9.81)] {
                compiled.set_parameter(name, value).unwrap();
                interpreted.set_parameter(name, value).unwrap();
            }
        }
        let names = interpreted.model_info().formulations.clone();
        assert_eq!(names.len(), 9);
        for name in &names {
            let c = compiled.formulation(name).unwrap();
            let i = interpreted.formulation(name).unwrap();
            agree(&*c, &*i, &mut rng, 25);
        }
    }
}

#[test]
fn included_pendulum_agrees_with_the_interpreter() {
    agree_model(&mut included::Pendulum::default(), 1);
}

#[test]
fn inline_pendulum_agrees_with_the_interpreter() {
    agree_model(&mut inline::Pendulum::default(), 2);
}

#[test]
fn typed_systems_agree_too() {
    // The concrete types, not only through `Box<dyn DaeSystem>`.
    let p = included::Pendulum {
        l: 1.7,
        ..Default::default()
    };
    let mut interp = InterpretedModel::from_str(PENDULUM).unwrap();
    interp.set_parameter("l", 1.7).unwrap();
    let mut rng = Lcg(3);
    agree(&p.rcd1(), &interp.system("rcd1").unwrap(), &mut rng, 10);
    agree(&p.ggl1(), &interp.system("ggl1").unwrap(), &mut rng, 10);
    agree(&p.psi0(), &interp.system("psi0").unwrap(), &mut rng, 10);
    assert_eq!(p.psi1().params, p);
}

#[test]
fn model_struct_fields_and_defaults() {
    let p = included::Pendulum::default();
    assert_eq!((p.m, p.l, p.g), (1.0, 1.0, G_DEFAULT));
    assert_eq!(p, inline::Pendulum::default().rcd1().params.into_included());
    assert_eq!(
        included::Pendulum::FORMULATIONS,
        ["ori2", "rcd1", "rcd0", "ovd1", "ovd0", "ggl1", "psi1", "psi0", "mex0"]
    );
    let info = included::Pendulum::model_info_static();
    assert!(info.doc.starts_with("The simple pendulum"), "{}", info.doc);
    assert_eq!(p.rcd1().parameter_values(), vec![1.0, 1.0, G_DEFAULT]);
}

/// The two expansions of the pendulum are distinct types with the same
/// fields.
trait IntoIncluded {
    fn into_included(self) -> included::Pendulum;
}

impl IntoIncluded for inline::Pendulum {
    fn into_included(self) -> included::Pendulum {
        included::Pendulum {
            m: self.m,
            l: self.l,
            g: self.g,
        }
    }
}

#[test]
fn static_sizes_match_the_descriptions() {
    fn check<S: DaeSystem + StaticSize>(s: &S) {
        let info = s.info();
        assert_eq!(S::UNKNOWNS, info.unknowns(), "{}", info.name);
        assert_eq!(S::EQUATIONS, info.equations(), "{}", info.name);
        assert_eq!(S::CONSTRAINTS, info.constraints.len(), "{}", info.name);
    }
    let p = included::Pendulum::default();
    check(&p.ori2());
    check(&p.rcd1());
    check(&p.rcd0());
    check(&p.ovd1());
    check(&p.ovd0());
    check(&p.ggl1());
    check(&p.psi1());
    check(&p.psi0());
    assert_eq!(
        (
            <included::PendulumRcd1 as StaticSize>::UNKNOWNS,
            <included::PendulumRcd1 as StaticSize>::EQUATIONS,
            <included::PendulumRcd1 as StaticSize>::CONSTRAINTS,
        ),
        (5, 5, 3)
    );
    assert_eq!(<included::PendulumOvd0 as StaticSize>::EQUATIONS, 7);
    assert_eq!(<included::PendulumGgl1 as StaticSize>::UNKNOWNS, 6);
}

#[test]
fn parameters_by_name() {
    let mut p = included::Pendulum::default();
    let mut i = InterpretedModel::from_str(PENDULUM).unwrap();
    assert_eq!(p.parameter("g"), Some(G_DEFAULT));
    assert_eq!(p.parameter("q"), None);
    p.set_parameter("m", 2.5).unwrap();
    assert_eq!((p.m, p.parameter("m")), (2.5, Some(2.5)));

    let unknown = p.set_parameter("mass", 1.0).unwrap_err();
    assert_eq!(unknown, i.set_parameter("mass", 1.0).unwrap_err());
    assert_eq!(
        unknown,
        ParameterError::Unknown {
            model: "Pendulum".into(),
            name: "mass".into(),
            known: "m, l, g".into()
        }
    );

    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let e = p.set_parameter("l", bad).unwrap_err();
        assert!(
            matches!(&e, ParameterError::NotFinite { name, value } if name == "l" && value.to_bits() == bad.to_bits()),
            "{e:?}"
        );
        assert!(matches!(
            i.set_parameter("l", bad),
            Err(ParameterError::NotFinite { .. })
        ));
    }
    assert_eq!(p.l, 1.0, "a rejected value leaves the parameter alone");
    // The formulation sees the current values.
    assert_eq!(
        p.formulation("rcd1").unwrap().parameter_values(),
        vec![2.5, 1.0, G_DEFAULT]
    );
}

#[test]
fn formulation_errors() {
    let p = included::Pendulum::default();
    let e = p.formulation("rcd2").err().unwrap();
    assert_eq!(
        e,
        FormulationError::Unknown {
            name: "rcd2".into()
        }
    );

    let q = rcd0_only::Pendulum::default();
    let i = InterpretedModel::from_str(RCD0_ONLY).unwrap();
    assert_eq!(rcd0_only::Pendulum::FORMULATIONS, ["rcd0"]);
    assert_eq!(q.model_info(), i.model_info());
    for name in ["ori2", "rcd1", "ovd1", "ovd0", "ggl1", "psi1", "psi0"] {
        let e = q.formulation(name).err().unwrap();
        assert_eq!(
            e,
            FormulationError::NotProvided {
                model: "Pendulum".into(),
                name: name.into(),
                available: "rcd0".into()
            }
        );
        assert_eq!(Some(e), i.formulation(name).err());
    }
    assert_eq!(q.formulation("nope").err(), i.formulation("nope").err());
    let mut rng = Lcg(4);
    agree(
        &*q.formulation("rcd0").unwrap(),
        &*i.formulation("rcd0").unwrap(),
        &mut rng,
        10,
    );
}

#[test]
fn systems_are_send_and_sync() {
    fn check<T: Send + Sync + 'static>() {}
    check::<included::Pendulum>();
    check::<included::PendulumPsi0>();
    check::<rcd0_only::PendulumRcd0>();
}

//! The projected formulations where the symbolic selector fails: a
//! numerical selector computed at run time (`dae_core::selector`), chosen by
//! the runner and reported in the run's record.

use dae::dae_core::check::check_jacobians;
use dae::dae_core::interp::InterpretedModel;
use dae::dae_core::selector::{NumericSelector, Projected};
use dae::inputs::{inputs, Inputs};
use dae::prelude::*;
use dae::runner::{self, RunRecord};
use dae::scene::Scene;

fn scene(path: &str) -> (Scene, Inputs) {
    let scene = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let inputs = inputs(&scene).unwrap_or_else(|e| panic!("{e}"));
    (scene, inputs)
}

fn run(scene: &Scene, inputs: &Inputs, solver: &str, formulation: &str, tol: f64) -> RunRecord {
    let r = runner::run(&inputs.spec(scene, solver, formulation, tol)).unwrap();
    assert_eq!(
        r.status, "ok",
        "{solver}({formulation}) at {tol:e}: {:?}",
        r.error
    );
    r
}

fn value(r: &RunRecord, name: &str) -> f64 {
    r.final_values.0.iter().find(|(n, _)| n == name).unwrap().1
}

/// The spherical pendulum started on the equator, z = 0, where the symbolic
/// selector `[[z, 0, −x], [0, z, −y]]` has rank one: radau5's symbolic run
/// stops at once, the numerical one reaches the end, on the sphere and
/// with the energy of the ggl1 run.
#[test]
fn the_spherical_pendulum_from_the_equator_runs_with_a_numerical_selector() {
    let (scene, inputs) = scene("scenes/spherical_pendulum.toml");
    let tol = 1e-8;
    let ggl1 = run(&scene, &inputs, "radau5", "ggl1", tol);
    assert_eq!(ggl1.selector, None);
    for f in ["psi1", "psi0"] {
        let r = run(&scene, &inputs, "radau5", f, tol);
        assert_eq!(r.selector, Some("numerical"), "{f}");
        let json = serde_json::to_string(&r).unwrap();
        assert!(json.contains("\"selector\":\"numerical\""), "{json}");
        assert!(
            r.residuals.level(0).unwrap() <= 1e-7,
            "{f}: {:?}",
            r.residuals
        );
        for name in ["x", "y", "z"] {
            let (a, b) = (value(&r, name), value(&ggl1, name));
            assert!((a - b).abs() <= 1e-5, "{f} {name}: {a} vs ggl1 {b}");
        }
    }
}

/// A pivot driven as `r*sin(om*t)`: the symbolic selector would depend on
/// `t`, which `E(y)` may not, so the model offers no symbolic psi (and says
/// why); the runner projects ovd1/ovd0 numerically and agrees with ggl1.
#[test]
fn a_time_dependent_constraint_gets_psi_through_a_numerical_selector() {
    let src = std::fs::read_to_string("scenes/driven_pendulum.dae").unwrap();
    let model = InterpretedModel::from_str(&src).unwrap();
    assert!(!model
        .model_info()
        .formulations
        .iter()
        .any(|f| f.starts_with("psi")));
    let why = match model.formulation("psi1") {
        Err(e) => e.to_string(),
        Ok(_) => panic!("psi1 offered"),
    };
    assert!(why.contains("psi1"), "{why}");
    let d = dae::dae_core::Derived::from_str(&src).unwrap();
    let reason = dae::dae_core::formulation::applicable(&d.model, &d.analysis, "psi1").unwrap_err();
    assert!(reason.contains("depends on `t`"), "{reason}");

    let (scene, inputs) = scene("scenes/driven_pendulum.toml");
    let tol = 1e-8;
    let ggl1 = run(&scene, &inputs, "radau5", "ggl1", tol);
    for (solver, f) in [("radau5", "psi1"), ("radau5", "psi0"), ("bdf", "psi1")] {
        let r = run(&scene, &inputs, solver, f, tol);
        assert_eq!(r.selector, Some("numerical"));
        let bound = if solver == "bdf" { 1e-3 } else { 1e-5 };
        for name in ["x", "y"] {
            let (a, b) = (value(&r, name), value(&ggl1, name));
            assert!(
                (a - b).abs() <= bound,
                "{solver}({f}) {name}: {a} vs ggl1 {b}"
            );
        }
    }
}

/// Where the symbolic selector serves (the pendulum), it is used.
#[test]
fn the_pendulum_keeps_its_symbolic_selector() {
    let (scene, inputs) = scene("s01");
    let r = run(&scene, &inputs, "radau5", "psi1", 1e-6);
    assert_eq!(r.selector, Some("symbolic"));
}

/// The numerical selector's rows are linear combinations of ovd1's/ovd0's
/// with weights constant between updates: its Jacobians are exact, checked
/// against central differences. (`leading` may re-choose σ at a new random
/// point; every comparison is between evaluations at one point and its
/// neighbours, where σ stays.)
#[test]
fn numerical_selector_jacobians_match_central_differences() {
    let src = std::fs::read_to_string("scenes/spherical_pendulum.dae").unwrap();
    let model = InterpretedModel::from_str(&src).unwrap();
    for which in [Projected::Psi1, Projected::Psi0] {
        let inner = model.formulation(which.source()).unwrap();
        let y0 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
        let sys = NumericSelector::new(inner, which, 0.0, &y0).unwrap();
        let info = sys.info();
        assert_eq!(info.unknowns(), info.equations(), "{}", info.name);
        assert_eq!(info.name, which.name());
        if let Err(m) = check_jacobians(&sys, 5, 17, 1e-7) {
            panic!("{}: {m}", which.name());
        }
    }
}

/// psi0 finds the multipliers in the acceleration-level constraint; a model
/// with a mass matrix holds `v'` there instead, so there is no psi0 to build.
/// The cart pendulum couples the cart's velocity, which no constraint holds,
/// with the bob's: the numerical psi0 used to be built anyway and stopped
/// with a singular iteration matrix at t = 0 for every solver. It is refused,
/// typed, and a run of it reports the formulation as not provided.
#[test]
fn a_mass_matrix_model_has_no_numerical_psi0() {
    let src = std::fs::read_to_string("scenes/cart_pendulum.dae").unwrap();
    let model = InterpretedModel::from_str(&src).unwrap();
    let inner = model.formulation("ovd0").unwrap();
    let y0 = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let err = NumericSelector::new(inner, Projected::Psi0, 0.0, &y0).unwrap_err();
    assert_eq!(err, dae::dae_core::selector::SelectorError::MassMatrix);
    // psi1 projects only the kinematic rows: it exists.
    let inner = model.formulation("ovd1").unwrap();
    assert!(NumericSelector::new(inner, Projected::Psi1, 0.0, &y0).is_ok());
    let (scene, inputs) = scene("scenes/cart_pendulum.toml");
    let spec = inputs.spec(&scene, "radau5", "psi0", 1e-6);
    match runner::run(&spec) {
        // The refusal carries the selector's reason, not only the name.
        Err(e) => assert!(
            e.to_string().contains("psi0") && e.to_string().contains("mass matrix"),
            "{e}"
        ),
        Ok(r) => panic!("psi0 ran: {:?} {:?}", r.status, r.error),
    }
    // The sweep's success matrix gives the same reason.
    let pairs = dae::sweep::pairs(&model, &["radau5".into()], &["psi0".into()]).unwrap();
    let why = pairs[0].not_applicable.as_deref().unwrap_or_default();
    assert!(
        why.starts_with("not provided by the model: ") && why.contains("mass matrix"),
        "{why}"
    );
}

//! The macro-generated formulations of the three shipped models: Jacobians
//! against central differences, and agreement with the interpreter on
//! everything the runtime trait exposes.

use dae::dae_core::check::{check_jacobians, Lcg};
use dae::dae_core::interp::InterpretedModel;
use dae::prelude::*;

mod pendulum {
    dae::dae! { include "scenes/pendulum.dae" }
}
mod double {
    dae::dae! { include "scenes/double_pendulum.dae" }
}
mod spherical {
    dae::dae! { include "scenes/spherical_pendulum.dae" }
}

fn models() -> Vec<(&'static str, Box<dyn Model>, &'static str)> {
    vec![
        (
            "pendulum",
            Box::new(pendulum::Pendulum::default()),
            include_str!("../scenes/pendulum.dae"),
        ),
        (
            "double",
            Box::new(double::DoublePendulum::default()),
            include_str!("../scenes/double_pendulum.dae"),
        ),
        (
            "spherical",
            Box::new(spherical::SphericalPendulum::default()),
            include_str!("../scenes/spherical_pendulum.dae"),
        ),
    ]
}

#[test]
fn compiled_jacobians_match_central_differences() {
    for (label, model, _) in models() {
        assert_eq!(
            model.model_info().formulations.len(),
            8,
            "{label}: all eight formulations apply"
        );
        for name in &model.model_info().formulations {
            let sys = model.formulation(name).unwrap();
            // Relative 1e-7, the bound (see dae_core::check).
            if let Err(m) = check_jacobians(&sys, 5, 11, 1e-7) {
                panic!("{label}/{name}: {m}");
            }
        }
    }
}

#[test]
fn compiled_and_interpreted_agree() {
    let mut rng = Lcg(3);
    for (label, model, src) in models() {
        let interp = InterpretedModel::from_str(src).unwrap();
        assert_eq!(model.model_info(), interp.model_info(), "{label}");
        for name in &model.model_info().formulations {
            let a = model.formulation(name).unwrap();
            let b = interp.formulation(name).unwrap();
            assert_eq!(a.info(), b.info(), "{label}/{name}");
            let (n, m) = (a.info().unknowns(), a.info().equations());
            let y: Vec<f64> = (0..n).map(|_| rng.range(-1.5, 1.5)).collect();
            let yp: Vec<f64> = (0..n).map(|_| rng.range(-1.5, 1.5)).collect();
            let (mut ra, mut rb) = (vec![0.0; m], vec![0.0; m]);
            a.residual(0.3, &y, &yp, &mut ra);
            b.residual(0.3, &y, &yp, &mut rb);
            for (x, z) in ra.iter().zip(&rb) {
                assert!(
                    (x - z).abs() <= 1e-13 * (1.0 + z.abs()),
                    "{label}/{name}: {x} vs {z}"
                );
            }
        }
    }
}

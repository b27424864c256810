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
mod cart {
    dae::dae! { include "scenes/cart_pendulum.dae" }
}
mod andrews {
    dae::dae! { include "scenes/andrews_natural.dae" }
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
        // Mass matrices: constant and coupled (the cart), position-dependent
        // in three coupled pairs (Andrews' squeezer in natural form).
        (
            "cart",
            Box::new(cart::CartPendulum::default()),
            include_str!("../scenes/cart_pendulum.dae"),
        ),
        (
            "andrews",
            Box::new(andrews::AndrewsNatural::default()),
            include_str!("../scenes/andrews_natural.dae"),
        ),
    ]
}

/// Tolerance of the central-difference check (relative to `max(1, |entry|)`).
/// 1e-7 is the bound. Andrews' squeezer gets 1e-5, for round-off in
/// the differences, not in the Jacobian: its inertias of 1e-7 kg·m² make the
/// acceleration level of its chain reach 6·10³ at the random points, so a
/// central difference with `h ≈ 2·10⁻⁶` carries round-off up to
/// 1e-16 · 6·10³ / 10⁻⁶ ≈ 10⁻⁶ (measured: 1.4e-6 at the worst entry). With
/// `h = 10⁻²` (the chain is polynomial in the velocities) the same entry
/// agreed with the analytic one to 1e-10 relative.
fn fd_tolerance(label: &str) -> f64 {
    if label == "andrews" {
        1e-5
    } else {
        1e-7
    }
}

/// The formulations a model offers: all eight, except `psi0` for a model
/// with a mass matrix (its reason is tested in `tests/mass_matrix.rs`).
fn expected_formulations(label: &str) -> usize {
    // `mex0` too, except where rows couple derivatives (the mass matrices).
    if matches!(label, "cart" | "andrews") {
        7
    } else {
        9
    }
}

#[test]
fn compiled_jacobians_match_central_differences() {
    for (label, model, _) in models() {
        assert_eq!(
            model.model_info().formulations.len(),
            expected_formulations(label),
            "{label}: the formulations that apply"
        );
        for name in &model.model_info().formulations {
            let sys = model.formulation(name).unwrap();
            // Relative 1e-7, the bound (see dae_core::check).
            if let Err(m) = check_jacobians(&sys, 5, 11, fd_tolerance(label)) {
                panic!("{label}/{name}: {m}");
            }
        }
    }
}

/// The interpreter's Jacobians of the mass-matrix models against central
/// differences, as the compiled ones above.
#[test]
fn interpreted_mass_matrix_jacobians_match_central_differences() {
    for (label, model, src) in models() {
        if expected_formulations(label) == 8 {
            continue;
        }
        let interp = InterpretedModel::from_str(src).unwrap();
        for name in &model.model_info().formulations {
            let sys = interp.formulation(name).unwrap();
            if let Err(m) = check_jacobians(&sys, 5, 13, fd_tolerance(label)) {
                panic!("interpreted {label}/{name}: {m}");
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
            // The constraint chain (for a mass matrix: with the
            // accelerations eliminated numerically) and its Jacobian.
            let k = a.info().constraints.len();
            let (mut ga, mut gb) = (vec![0.0; k], vec![0.0; k]);
            a.constraints(0.3, &y, &mut ga);
            b.constraints(0.3, &y, &mut gb);
            let (mut ja, mut jb) = (
                nalgebra::DMatrix::zeros(k, n),
                nalgebra::DMatrix::zeros(k, n),
            );
            a.constraints_jacobian(0.3, &y, &mut ja);
            b.constraints_jacobian(0.3, &y, &mut jb);
            for (x, z) in ga.iter().chain(ja.iter()).zip(gb.iter().chain(jb.iter())) {
                assert!(
                    (x - z).abs() <= 1e-12 * (1.0 + z.abs()),
                    "{label}/{name}: chain {x} vs {z}"
                );
            }
        }
    }
}

//! The pendulum builds without a warning, and its items are usable.
#![deny(warnings, missing_docs)]

/// The model, in a public module.
pub mod model {
    dae::dae! {
        /// The simple pendulum.
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
            formulations { ori2, rcd1, rcd0, ovd1, ovd0, ggl1, psi1, psi0 }
        }
    }
}

use dae::prelude::{DaeSystem, Model, StaticSize};
use model::{Pendulum, PendulumPsi0, PendulumRcd1};

fn main() {
    let mut p = Pendulum::default();
    p.set_parameter("l", 2.0).unwrap();
    let s = p.rcd1();
    let mut f = [0.0; <PendulumRcd1 as StaticSize>::EQUATIONS];
    s.rhs(0.0, &[2.0, 0.0, 0.0, 0.0, 0.0], &mut f);
    assert_eq!(s.info().name, "rcd1");
    assert_eq!(<PendulumPsi0 as StaticSize>::EQUATIONS, 5);
    assert_eq!(Pendulum::FORMULATIONS.len(), 8);
    let boxed = p.formulation("ggl1").unwrap();
    assert_eq!(boxed.info().unknowns(), 6);
}

// Definitions and derived parameters build without a warning.
#![deny(warnings)]

dae::dae! {
    /// The pendulum with a derived parameter and a definition.
    pub Pendulum {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        derived { l2 = l^2; two = 2; }
        differential { x, y, v, w }
        algebraic { lambda }
        definitions { r2 = x^2 + y^2; }
        equations {
            der(x) = v;
            der(y) = w;
            m * der(v) = -two * x * lambda;
            m * der(w) = -two * y * lambda - m * g;
            0 = r2 - l2;
        }
        invariants { radius = r2; }
    }
}

fn main() {
    use dae::prelude::*;
    let mut p = Pendulum { l: 2.0, ..Pendulum::default() };
    assert_eq!(p.parameter("l2"), Some(4.0));
    p.set_parameter("l", 3.0).unwrap();
    assert!(p.set_parameter("l2", 1.0).is_err());
    let sys = p.rcd1();
    assert_eq!(sys.parameter_values(), vec![1.0, 3.0, 9.81, 9.0, 2.0]);
}

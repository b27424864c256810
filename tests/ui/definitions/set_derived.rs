// A derived parameter is not a field of the model struct: it cannot be
// set (at run time `set_parameter("l2", …)` is `ParameterError::Derived`).
dae::dae! {
    pub Pendulum {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        derived { l2 = l^2; }
        differential { x, y, v, w }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(y) = w;
            m * der(v) = -2 * x * lambda;
            m * der(w) = -2 * y * lambda - m * g;
            0 = x^2 + y^2 - l2;
        }
    }
}

fn main() {
    let mut p = Pendulum::default();
    p.l = 2.0;
    p.l2 = 4.0;
    let _ = p.rcd1();
}

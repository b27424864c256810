// `lenght` is neither a parameter nor an unknown.
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
            0 = x^2 + y^2 - lenght^2;
        }
    }
}

fn main() {
    // The stub keeps these lines from adding errors of their own.
    let p = Pendulum {
        m: 2.0,
        ..Pendulum::default()
    };
    let _ = p.rcd1();
}

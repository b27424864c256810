// A parameter default must be a numeric literal.
dae::dae! {
    pub Pendulum {
        parameters { m = 1.0, l = "one", g = 9.81 }
        differential { x, y, v, w }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(y) = w;
            m * der(v) = -2 * x * lambda;
            m * der(w) = -2 * y * lambda - m * g;
            0 = x^2 + y^2 - l^2;
        }
    }
}

fn main() {
    let p = Pendulum::default();
    let _ = p.rcd1();
}

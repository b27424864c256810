// A formulation may be listed once.
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
        formulations { rcd1, ggl1, rcd1 }
    }
}

fn main() {}

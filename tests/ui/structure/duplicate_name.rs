// `l` is both a parameter and an unknown.
dae::dae! {
    pub Pendulum {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        differential { x, y, v, l }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(y) = l;
            m * der(v) = -2 * x * lambda;
            m * der(l) = -2 * y * lambda - m * g;
            0 = x^2 + y^2 - 1;
        }
    }
}

fn main() {}

// Both constraints can only determine `lambda`; nothing determines `mu`.
dae::dae! {
    pub Pendulum {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        differential { x, y, v, w }
        algebraic { lambda, mu }
        equations {
            der(x) = v;
            der(y) = w;
            m * der(v) = -2 * x * lambda;
            m * der(w) = -2 * y * lambda - m * g;
            0 = x^2 + y^2 - l^2;
            0 = x - y;
        }
    }
}

fn main() {}

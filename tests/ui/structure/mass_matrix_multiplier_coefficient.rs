//! A der() coefficient may not depend on a multiplier (an algebraic
//! unknown): the multipliers are what the constraints determine.
dae::dae! {
    Pendulum {
        differential { x, y, v, w }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(y) = w;
            (1 + lambda^2) * der(v) = -2*x*lambda;
            der(w) = -2*y*lambda - 9.81;
            0 = x^2 + y^2 - 1;
        }
    }
}

fn main() {}

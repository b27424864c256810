//! A coefficient of der() may depend on the unknowns, not on time: the
//! leading matrix E(y) of a formulation is evaluated without `t`.
dae::dae! {
    Forced {
        differential { x, v }
        equations {
            der(x) = v;
            (2 + t) * der(v) = -x;
        }
    }
}

fn main() {}

//! A mass matrix may depend on the positions, not on the velocities whose
//! der() it multiplies: `E(y)` would then hold the velocities, and the
//! equations would not be those of a mechanical system.
dae::dae! {
    Cart {
        differential { s, u, vs, vu }
        equations {
            der(s) = vs;
            der(u) = vu;
            (2 + vu^2) * der(vs) + der(vu) = 0;
            der(vs) + der(vu) = -u;
        }
    }
}

fn main() {}

#![deny(warnings)]
//! A model with a mass matrix (the cart pendulum of `scenes/`) builds
//! without a warning.
dae::dae! {
    pub CartPendulum {
        parameters { mc = 2.0, m = 1.0, l = 1.0, g = 9.81 }
        differential { s, u, w, vs, vu, vw }
        algebraic { lambda }
        equations {
            der(s) = vs;
            der(u) = vu;
            der(w) = vw;
            (mc + m) * der(vs) + m * der(vu) = 0;
            m * der(vs) + m * der(vu) = -2*u*lambda;
            m * der(vw) = -m*g - 2*w*lambda;
            0 = u^2 + w^2 - l^2;
        }
    }
}

fn main() {
    use dae::prelude::*;
    let model = CartPendulum::default();
    assert!(model.formulation("rcd1").is_ok());
    assert!(model.formulation("psi0").is_err());
}

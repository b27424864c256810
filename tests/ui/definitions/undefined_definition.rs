// `rr` is not defined (a typo for `r2`).
dae::dae! {
    pub Pendulum {
        parameters { m = 1.0, l = 1.0, g = 9.81 }
        
        differential { x, y, v, w }
        algebraic { lambda }
        definitions { r2 = x^2 + y^2; }
        equations {
            der(x) = v;
            der(y) = w;
            m * der(v) = -2 * x * lambda;
            m * der(w) = -2 * y * lambda - m * g;
            0 = rr - l^2;
        }
    }
}

fn main() {
    // The stub keeps these lines from adding errors of their own.
    let p = Pendulum::default();
    let _ = p.rcd1();
}

//! A private model that nothing uses still builds without a warning: no
//! dead code, no unused variables. It covers the less common code paths:
//! no constraints and no invariants, a keyword as a parameter name, a
//! leading matrix depending on `y`, time in the right-hand side, every elementary function,
//! real and negative powers, and a negative default.
#![deny(warnings)]

dae::dae! {
    Gadget {
        parameters { type = 2.0, k = -0.5, c = 1e-3 }
        differential { x, v }
        equations {
            (1 + x^2) * der(x) = v;
            (2 + v^2) * der(v) = -type * sin(x) + cos(t) * exp(-c * v) + ln(2 + x^2)
                + sqrt(1 + v^2) + tan(k * x) + (3 + x^2)^1.5 + x^-2 - 2^x;
        }
    }
}

dae::dae! {
    /// No parameters at all.
    Bare {
        differential { x }
        equations { der(x) = -x; }
        formulations { rcd0 }
    }
}

fn main() {
    fn local() {
        dae::dae! {
            Inner {
                parameters { a = 3 }
                differential { q, p }
                algebraic { mu }
                equations {
                    der(q) = p;
                    der(p) = -a * q - mu;
                    0 = q - sin(t);
                }
            }
        }
    }
    local();
}

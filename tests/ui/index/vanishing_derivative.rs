// `x` is constant, so the constraint's time derivative is identically zero.
dae::dae! {
    pub Frozen {
        differential { x, y }
        algebraic { lambda }
        equations {
            der(x) = 0;
            der(y) = -lambda;
            0 = x - 1;
        }
    }
}

fn main() {}

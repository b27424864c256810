// `lambda` appears in no equation: differentiating the constraint never
// reaches it.
dae::dae! {
    pub Oscillator {
        differential { x, v }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(v) = -x;
            0 = x - 1;
        }
    }
}

fn main() {}

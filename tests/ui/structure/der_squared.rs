// The model must be quasi-linear: der() may not be raised to a power.
dae::dae! {
    pub Decay {
        parameters { k = 0.5 }
        differential { x }
        equations { der(x)^2 = k * x; }
    }
}

fn main() {}

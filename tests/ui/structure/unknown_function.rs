// `sinh` is not a function of the model language.
dae::dae! {
    pub Oscillator {
        parameters { k = 2.0 }
        differential { x, v }
        equations {
            der(x) = v;
            der(v) = -k * sinh(x);
        }
    }
}

fn main() {}

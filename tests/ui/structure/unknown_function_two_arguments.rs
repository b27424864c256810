// `atan2` is not a function of the model language: it is named as unknown
// (not "takes one argument"), with the known functions and a hint.
dae::dae! {
    pub Angle {
        differential { u, w }
        equations {
            der(u) = atan2(u, w);
            der(w) = -u;
        }
    }
}

fn main() {}

// A `;` left out between two equations: the caret at the end of the first.
dae::dae! {
    pub Decay {
        parameters { k = 0.5 }
        differential { x, y }
        equations {
            der(x) = -k * x
            der(y) = x - y;
        }
    }
}

fn main() {}

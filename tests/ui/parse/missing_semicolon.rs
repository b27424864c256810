// Equations end with `;`.
dae::dae! {
    pub Decay {
        parameters { k = 0.5 }
        differential { x, y }
        equations {
            der(x) = -k * x;
            der(y) = x - y
        }
    }
}

fn main() {}

// A product of two derivatives is not quasi-linear.
dae::dae! {
    pub Coupled {
        differential { x, y }
        equations {
            der(x) * der(y) = x;
            der(y) = -y;
        }
    }
}

fn main() {}

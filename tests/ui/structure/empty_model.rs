// A model needs unknowns and equations.
dae::dae! {
    pub Nothing {}
}

fn main() {
    let _ = Nothing::default();
}

// A misspelt section name.
dae::dae! {
    pub Decay {
        parameters { k = 0.5 }
        differential { x }
        equation { der(x) = -k * x; }
    }
}

fn main() {
    let _ = Decay::default().k;
}

// An index-2 model (the constraint determines `mu` after one
// differentiation): `rcd1` would be `ori2` again, and the GGL and projected
// formulations need position-level constraints of a mechanical system.
dae::dae! {
    pub Index2 {
        differential { x, y }
        algebraic { mu }
        equations {
            der(x) = y + mu;
            der(y) = -x;
            0 = x - sin(t);
        }
        formulations { rcd1, ggl1, psi1 }
    }
}

fn main() {
    let _ = Index2::default().rcd1();
}

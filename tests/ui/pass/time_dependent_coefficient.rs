//! A coefficient of der() may depend on time: the leading matrix of the
//! formulations is `E(t, y)`, evaluated at the time of each stage.
#![deny(warnings)]

dae::dae! {
    Forced {
        differential { x, v }
        equations {
            der(x) = v;
            (2 + t) * der(v) = -x;
        }
    }
}

fn main() {
    use dae::prelude::*;
    let model = Forced::default();
    let sys = model.formulation("rcd0").unwrap();
    let mut e = nalgebra::DMatrix::zeros(2, 2);
    sys.leading(1.0, &[0.0, 0.0], &mut e);
    assert_eq!(e[(1, 1)], 3.0);
}

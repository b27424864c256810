//! Three equations holding der() of only two of three velocities: no
//! assignment of equations to derivatives exists, so the mass matrix is
//! singular whatever its entries (and `der(c)` has no equation).
dae::dae! {
    Rods {
        differential { a, b, c, va, vb, vc }
        equations {
            der(a) = va;
            der(b) = vb;
            der(c) = vc;
            der(va) + der(vb) = -a;
            der(va) - der(vb) = -b;
            2 * der(va) + der(vb) = -c;
        }
    }
}

fn main() {}

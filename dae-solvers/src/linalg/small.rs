//! Vector updates of a multistep method's history, for the few unknowns of
//! a mechanical model: each instantiated for the constant lengths 1 … 12
//! by [`with_size!`], where a loop's own counting and bounds checks would
//! otherwise cost as much as its arithmetic. Every kernel performs, entry
//! by entry, the operations its name says in the order it says them.

/// `a += b`.
pub(crate) fn add_assign(a: &mut [f64], b: &[f64]) {
    let n = a.len();
    with_size!(n, |N| {
        let (a, b) = (&mut a[..N], &b[..N]);
        for i in 0..N {
            a[i] += b[i];
        }
    })
}

/// `a *= s`.
pub(crate) fn scale(a: &mut [f64], s: f64) {
    let n = a.len();
    with_size!(n, |N| {
        let a = &mut a[..N];
        for v in a.iter_mut() {
            *v *= s;
        }
    })
}

/// `d = p + e`.
pub(crate) fn sum(d: &mut [f64], p: &[f64], e: &[f64]) {
    let n = d.len();
    with_size!(n, |N| {
        let (d, p, e) = (&mut d[..N], &p[..N], &e[..N]);
        for i in 0..N {
            d[i] = p[i] + e[i];
        }
    })
}

/// `d = e − p`.
pub(crate) fn difference(d: &mut [f64], e: &[f64], p: &[f64]) {
    let n = d.len();
    with_size!(n, |N| {
        let (d, e, p) = (&mut d[..N], &e[..N], &p[..N]);
        for i in 0..N {
            d[i] = e[i] - p[i];
        }
    })
}

/// The predictor of a method in divided differences: `y = φ_0 + φ_1 + … +
/// φ_k`, `y' = 0 + γ_1 φ_1 + … + γ_k φ_k` (`φ_j` the `j`-th block of `n` in
/// `phi`), summed in that order.
pub(crate) fn predict(phi: &[f64], gamma: &[f64], k: usize, y: &mut [f64], yp: &mut [f64]) {
    let n = y.len();
    with_size!(n, |N| {
        let (y, yp) = (&mut y[..N], &mut yp[..N]);
        y.copy_from_slice(&phi[..N]);
        yp.fill(0.0);
        for j in 1..=k {
            let g = gamma[j];
            let col = &phi[j * N..(j + 1) * N];
            for i in 0..N {
                y[i] += col[i];
                yp[i] += g * col[i];
            }
        }
    })
}

/// One Newton correction `δ` of a multistep corrector: `y −= δ`, `e −= δ`,
/// `y' −= c δ`.
pub(crate) fn correct(y: &mut [f64], yp: &mut [f64], e: &mut [f64], delta: &[f64], c: f64) {
    let n = y.len();
    with_size!(n, |N| {
        let (y, yp, e, d) = (&mut y[..N], &mut yp[..N], &mut e[..N], &delta[..N]);
        for i in 0..N {
            y[i] -= d[i];
            e[i] -= d[i];
            yp[i] -= c * d[i];
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_do_what_they_say_at_every_size() {
        for n in [1, 5, 12, 13] {
            let v = |o: f64| (0..n).map(|i| i as f64 * 0.5 + o).collect::<Vec<f64>>();
            let mut a = v(1.0);
            add_assign(&mut a, &v(2.0));
            assert_eq!(a, (0..n).map(|i| i as f64 + 3.0).collect::<Vec<_>>());
            scale(&mut a, 2.0);
            assert_eq!(a, (0..n).map(|i| 2.0 * i as f64 + 6.0).collect::<Vec<_>>());
            let mut d = vec![0.0; n];
            sum(&mut d, &v(1.0), &v(0.0));
            assert_eq!(d, (0..n).map(|i| i as f64 + 1.0).collect::<Vec<_>>());
            difference(&mut d, &v(3.0), &v(1.0));
            assert_eq!(d, vec![2.0; n]);
            // φ_0 = 1, φ_1 = 2, φ_2 = 4 (every entry), γ = (·, 0.5, 0.25).
            let phi: Vec<f64> = [1.0, 2.0, 4.0].iter().flat_map(|&x| vec![x; n]).collect();
            let (mut y, mut yp) = (vec![0.0; n], vec![9.0; n]);
            predict(&phi, &[0.0, 0.5, 0.25], 2, &mut y, &mut yp);
            assert_eq!((y[n - 1], yp[n - 1]), (7.0, 2.0));
            let mut e = vec![1.0; n];
            correct(&mut y, &mut yp, &mut e, &vec![1.0; n], 3.0);
            assert_eq!((y[0], yp[0], e[0]), (6.0, -1.0, 0.0));
        }
    }
}

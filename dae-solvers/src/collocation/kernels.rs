//! The per-unknown loops of a collocation step (any [`Collocation`]), written once for `n`
//! unknowns and instantiated for the constant sizes 1 … 12 by
//! [`with_size!`](crate::linalg::with_size): at five unknowns a loop's own
//! counting and bounds checks cost as much as its arithmetic. Stages are
//! stored stage-major (`Z_1, Z_2, Z_3`, `n` apart); transformed
//! right-hand sides `m` apart.

use super::tableau::{Collocation, EndPoint};
use crate::linalg::{two_sum, with_size};

/// The stage points: `Y_i = y + Z_i` into `ys`, `Y'_i = (1/h) Σ_j A⁻¹_ij
/// Z_j` into `yd` (both stage-major, `3n`).
pub(super) fn stage_points<K: Collocation>(
    y: &[f64],
    z: &[f64],
    h: f64,
    ys: &mut [f64],
    yd: &mut [f64],
) {
    let n = y.len();
    with_size!(n, |N| stage_points_n::<K>(
        &y[..N],
        &z[..3 * N],
        h,
        &mut ys[..3 * N],
        &mut yd[..3 * N],
        N
    ))
}

#[inline(always)]
fn stage_points_n<K: Collocation>(
    y: &[f64],
    z: &[f64],
    h: f64,
    ys: &mut [f64],
    yd: &mut [f64],
    n: usize,
) {
    let (z1, z2, z3) = (&z[..n], &z[n..2 * n], &z[2 * n..3 * n]);
    for (i, a) in K::TABLEAU.ainv.iter().enumerate() {
        let zi = &z[i * n..(i + 1) * n];
        let (ysi, ydi) = (&mut ys[i * n..(i + 1) * n], &mut yd[i * n..(i + 1) * n]);
        for k in 0..n {
            ysi[k] = y[k] + zi[k];
            ydi[k] = (a[0] * z1[k] + a[1] * z2[k] + a[2] * z3[k]) / h;
        }
    }
}

/// `R = −(T⁻¹ ⊗ I) G`: the stage residuals `res` (three blocks of `m`)
/// into the transformed right-hand sides `dw` (three blocks of `m`).
/// Whether every residual is finite (checked on the way, not in a pass of
/// its own).
pub(super) fn transform_residuals<K: Collocation>(res: &[f64], dw: &mut [f64], m: usize) -> bool {
    with_size!(m, |M| transform_residuals_n::<K>(
        &res[..3 * M],
        &mut dw[..3 * M],
        M
    ))
}

#[inline(always)]
fn transform_residuals_n<K: Collocation>(res: &[f64], dw: &mut [f64], m: usize) -> bool {
    // `x · 0` is zero for a finite `x` and NaN otherwise: one multiplication
    // and one addition per entry instead of a classification.
    let mut check = 0.0;
    let (g1, g2, g3) = (&res[..m], &res[m..2 * m], &res[2 * m..3 * m]);
    let (r1, r) = dw.split_at_mut(m);
    let (r2, r3) = r.split_at_mut(m);
    let (r1, r2, r3) = (&mut r1[..m], &mut r2[..m], &mut r3[..m]);
    for k in 0..m {
        let (g1, g2, g3) = (g1[k], g2[k], g3[k]);
        check += g1 * 0.0 + g2 * 0.0 + g3 * 0.0;
        r1[k] = -(K::TABLEAU.ti[0][0] * g1 + K::TABLEAU.ti[0][1] * g2 + K::TABLEAU.ti[0][2] * g3);
        r2[k] = -(K::TABLEAU.ti[1][0] * g1 + K::TABLEAU.ti[1][1] * g2 + K::TABLEAU.ti[1][2] * g3);
        r3[k] = -(K::TABLEAU.ti[2][0] * g1 + K::TABLEAU.ti[2][1] * g2 + K::TABLEAU.ti[2][2] * g3);
    }
    check == 0.0
}

/// `Z += (T ⊗ I) ΔW` (`T₃₂ = 1`, `T₃₃ = 0`): the increments, the first `n`
/// of each block of `dw` (`m` apart), added to the stages `z`.
pub(super) fn add_increments<K: Collocation>(dw: &[f64], m: usize, z: &mut [f64], n: usize) {
    with_size!(n, |N| add_increments_n::<K>(dw, m, &mut z[..3 * N], N))
}

#[inline(always)]
fn add_increments_n<K: Collocation>(dw: &[f64], m: usize, z: &mut [f64], n: usize) {
    let (a1, a2, a3) = (&dw[..n], &dw[m..m + n], &dw[2 * m..2 * m + n]);
    let (z1, zr) = z.split_at_mut(n);
    let (z2, z3) = zr.split_at_mut(n);
    let (z1, z2, z3) = (&mut z1[..n], &mut z2[..n], &mut z3[..n]);
    for k in 0..n {
        let (a1, a2, a3) = (a1[k], a2[k], a3[k]);
        z1[k] += K::TABLEAU.t[0][0] * a1 + K::TABLEAU.t[0][1] * a2 + K::TABLEAU.t[0][2] * a3;
        z2[k] += K::TABLEAU.t[1][0] * a1 + K::TABLEAU.t[1][1] * a2 + K::TABLEAU.t[1][2] * a3;
        z3[k] += K::TABLEAU.t[2][0] * a1 + a2;
    }
}

/// Starting stages: the collocation polynomial `cont` (`4n`, Newton form)
/// of the last step extrapolated to the new nodes, `ratio = h / h_old`.
pub(super) fn extrapolate<K: Collocation>(cont: &[f64], ratio: f64, z: &mut [f64], n: usize) {
    with_size!(n, |N| extrapolate_n::<K>(
        &cont[..4 * N],
        ratio,
        &mut z[..3 * N],
        N
    ))
}

#[inline(always)]
fn extrapolate_n<K: Collocation>(cont: &[f64], ratio: f64, z: &mut [f64], n: usize) {
    let (d1, d2, d3) = (&cont[n..2 * n], &cont[2 * n..3 * n], &cont[3 * n..4 * n]);
    for (i, &ci) in K::TABLEAU.c.iter().enumerate() {
        let s = ci * ratio;
        let zi = &mut z[i * n..(i + 1) * n];
        for k in 0..n {
            zi[k] = K::polynomial_increment(&[d1[k], d2[k], d3[k]], s);
        }
    }
}

/// `(1/h) Σ d_i Z_i` into `out` (the embedded estimate's combination).
pub(super) fn error_combination<K: Collocation>(z: &[f64], h: f64, out: &mut [f64], n: usize) {
    with_size!(n, |N| error_combination_n::<K>(
        &z[..3 * N],
        h,
        &mut out[..N],
        N
    ))
}

#[inline(always)]
fn error_combination_n<K: Collocation>(z: &[f64], h: f64, out: &mut [f64], n: usize) {
    let (z1, z2, z3) = (&z[..n], &z[n..2 * n], &z[2 * n..3 * n]);
    for k in 0..n {
        out[k] =
            (K::TABLEAU.dd[0] * z1[k] + K::TABLEAU.dd[1] * z2[k] + K::TABLEAU.dd[2] * z3[k]) / h;
    }
}

/// An accepted step: `y += Z_3` (or `Σ END_i Z_i`), the new collocation
/// polynomial `cont` (Newton form, see [`Collocation`]) and `y'(t_{n+1})`
/// into `yp`.
/// With `y_lo` the sum is compensated: `y + y_lo` carries the rounding
/// error of every update so far (Knuth's two-sum), so that millions of
/// steps do not add up millions of roundings.
pub(super) fn advance<K: Collocation>(
    z: &[f64],
    h: f64,
    y: &mut [f64],
    y_lo: Option<&mut [f64]>,
    yp: &mut [f64],
    cont: &mut [f64],
) {
    let n = y.len();
    match y_lo {
        None => with_size!(n, |N| advance_n::<K, false>(
            &z[..3 * N],
            h,
            &mut y[..N],
            &mut [],
            &mut yp[..N],
            &mut cont[..4 * N],
            N
        )),
        Some(lo) => with_size!(n, |N| advance_n::<K, true>(
            &z[..3 * N],
            h,
            &mut y[..N],
            &mut lo[..N],
            &mut yp[..N],
            &mut cont[..4 * N],
            N
        )),
    }
}

#[inline(always)]
fn advance_n<K: Collocation, const COMPENSATED: bool>(
    z: &[f64],
    h: f64,
    y: &mut [f64],
    y_lo: &mut [f64],
    yp: &mut [f64],
    cont: &mut [f64],
    n: usize,
) {
    let (z1, z2, z3) = (&z[..n], &z[n..2 * n], &z[2 * n..3 * n]);
    let (c0, c) = cont.split_at_mut(n);
    let (c1, c) = c.split_at_mut(n);
    let (c2, c3) = c.split_at_mut(n);
    let (c0, c1, c2, c3) = (&mut c0[..n], &mut c1[..n], &mut c2[..n], &mut c3[..n]);
    for k in 0..n {
        let (z1, z2, z3) = (z1[k], z2[k], z3[k]);
        // The increment of the step: `Z_3` for a stiffly accurate method,
        // `Σ END_i Z_i` otherwise.
        let dy = match K::TABLEAU.end {
            EndPoint::LastStage => z3,
            EndPoint::Projected(e) => e[0] * z1 + e[1] * z2 + e[2] * z3,
        };
        if COMPENSATED {
            (y[k], y_lo[k]) = two_sum(y[k], dy + y_lo[k]);
        } else {
            y[k] += dy;
        }
        let d = K::divided_differences(z1, z2, z3);
        c0[k] = y[k];
        c1[k] = d[0];
        c2[k] = d[1];
        c3[k] = d[2];
        yp[k] = K::end_slope([z1, z2, z3], &d) / h;
    }
}

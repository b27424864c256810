//! Checking a [`DaeSystem`]'s analytic Jacobians against central
//! differences — the test every implementation (generated, interpreted, or
//! hand-written) must pass.

use crate::system::DaeSystem;
use nalgebra::{DMatrix, DVector};

/// A Jacobian entry that disagrees with its central difference.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{which} entry ({row}, {col}) at y = {y:?}: analytic {analytic:e}, central difference {fd:e} (relative error {rel:e})")]
pub struct Mismatch {
    /// Which Jacobian (`∂f/∂y`, `∂(Ez)/∂y`, `∂g/∂y`, or `residual`).
    pub which: &'static str,
    /// Row.
    pub row: usize,
    /// Column.
    pub col: usize,
    /// The point.
    pub y: Vec<f64>,
    /// Analytic value.
    pub analytic: f64,
    /// Central difference.
    pub fd: f64,
    /// `|analytic − fd| / max(1, |fd|, |analytic|)`.
    pub rel: f64,
}

/// Deterministic pseudo-random numbers in `[0, 1)` (64-bit LCG).
#[derive(Clone, Debug)]
pub struct Lcg(pub u64);

impl Lcg {
    /// Next number in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
    /// Uniform in `[a, b)`.
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next_f64()
    }
}

/// Compare `∂f/∂y`, `∂(E z)/∂y`, `∂g/∂y` and the residual identity
/// `r = E yp − f` with central differences at `points` random points
/// (components of magnitude 0.3–1.3 with random signs). Returns the worst
/// relative error, or the first entry worse than `tol`.
pub fn check_jacobians(
    sys: &dyn DaeSystem,
    points: usize,
    seed: u64,
    tol: f64,
) -> Result<f64, Box<Mismatch>> {
    let mut rng = Lcg(seed);
    let info = sys.info();
    let (n, m, k) = (info.unknowns(), info.equations(), info.constraints.len());
    let mut worst: f64 = 0.0;
    for _ in 0..points {
        let y: Vec<f64> = (0..n)
            .map(|_| rng.range(0.3, 1.3) * if rng.next_f64() < 0.5 { -1.0 } else { 1.0 })
            .collect();
        let z: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let t = rng.range(0.0, 1.0);
        let mut j = DMatrix::zeros(m, n);
        sys.rhs_jacobian(t, &y, &mut j);
        worst = worst.max(compare(&j, &y, m, tol, "∂f/∂y", |yy, out| {
            sys.rhs(t, yy, out)
        })?);
        let mut je = DMatrix::zeros(m, n);
        sys.leading_jacobian(t, &y, &z, &mut je);
        let ez = |yy: &[f64], out: &mut [f64]| {
            let mut e = DMatrix::zeros(m, n);
            sys.leading(t, yy, &mut e);
            let v = e * DVector::from_column_slice(&z);
            out.copy_from_slice(v.as_slice());
        };
        worst = worst.max(compare(&je, &y, m, tol, "∂(Ez)/∂y", ez)?);
        let mut jg = DMatrix::zeros(k, n);
        sys.constraints_jacobian(t, &y, &mut jg);
        worst = worst.max(compare(&jg, &y, k, tol, "∂g/∂y", |yy, out| {
            sys.constraints(t, yy, out)
        })?);
        // The residual is E yp − f.
        let yp: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut r = vec![0.0; m];
        sys.residual(t, &y, &yp, &mut r);
        let mut e = DMatrix::zeros(m, n);
        sys.leading(t, &y, &mut e);
        let mut f = vec![0.0; m];
        sys.rhs(t, &y, &mut f);
        let ey = &e * DVector::from_column_slice(&yp);
        for i in 0..m {
            let expected = ey[i] - f[i];
            let rel = (r[i] - expected).abs() / 1f64.max(expected.abs());
            if rel > 1e-12 {
                return Err(Box::new(Mismatch {
                    which: "residual",
                    row: i,
                    col: 0,
                    y,
                    analytic: r[i],
                    fd: expected,
                    rel,
                }));
            }
        }
    }
    Ok(worst)
}

fn compare(
    j: &DMatrix<f64>,
    y: &[f64],
    rows: usize,
    tol: f64,
    which: &'static str,
    f: impl Fn(&[f64], &mut [f64]),
) -> Result<f64, Box<Mismatch>> {
    let mut worst: f64 = 0.0;
    let (mut fp, mut fm) = (vec![0.0; rows], vec![0.0; rows]);
    for c in 0..y.len() {
        let h = 1e-6 * (1.0 + y[c].abs());
        let mut yp = y.to_vec();
        yp[c] += h;
        let mut ym = y.to_vec();
        ym[c] -= h;
        f(&yp, &mut fp);
        f(&ym, &mut fm);
        for r in 0..rows {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let rel = (fd - j[(r, c)]).abs() / 1f64.max(fd.abs()).max(j[(r, c)].abs());
            if rel > tol || rel.is_nan() {
                return Err(Box::new(Mismatch {
                    which,
                    row: r,
                    col: c,
                    y: y.to_vec(),
                    analytic: j[(r, c)],
                    fd,
                    rel,
                }));
            }
            worst = worst.max(rel);
        }
    }
    Ok(worst)
}

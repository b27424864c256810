//! Hand-written test models for the Radau IIA tests: the paper's pendulum in
//! six formulations (written out by hand, independent of the `dae!` macro),
//! small DAEs with closed-form solutions for convergence-order studies, and
//! pathological systems that provoke each [`dae_solvers::SolveError`].
//!
//! Shared by `tests/radau5.rs` and `examples/radau5_s02.rs` (included there
//! with `#[path]`), hence the `dead_code` allowance.
#![allow(dead_code)]

use dae_core::system::{
    ConstraintInfo, DaeSystem, FormulationInfo, RowInfo, RowKind, VarInfo, VarKind,
};
use nalgebra::DMatrix;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------
// The pendulum (SPEC §1–§3)
// ---------------------------------------------------------------------------

/// The paper's gravity constant (SPEC §3).
pub const G_PAPER: f64 = 13.750371637329454;

/// The six square formulations of the pendulum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// Index 3: the model as written.
    Ori2,
    /// Index 2: position constraint replaced by the velocity constraint.
    Rcd1,
    /// Index 1: position constraint replaced by the acceleration constraint.
    Rcd0,
    /// Gear–Gupta–Leimkuhler stabilisation, multiplier `eta`.
    Ggl1,
    /// Projected, position and velocity constraints; `E` depends on `y`.
    Psi1,
    /// Projected, strangeness-free; `E` depends on `y`.
    Psi0,
}

impl Form {
    /// All six, in the paper's order.
    pub const ALL: [Form; 6] = [
        Form::Ori2,
        Form::Rcd1,
        Form::Rcd0,
        Form::Ggl1,
        Form::Psi1,
        Form::Psi0,
    ];

    /// The paper's name.
    pub fn name(self) -> &'static str {
        match self {
            Form::Ori2 => "ori2",
            Form::Rcd1 => "rcd1",
            Form::Rcd0 => "rcd0",
            Form::Ggl1 => "ggl1",
            Form::Psi1 => "psi1",
            Form::Psi0 => "psi0",
        }
    }
}

/// The pendulum `x' = v, y' = w, m v' = −2xλ, m w' = −2yλ − mg,
/// 0 = x² + y² − L²` in one of its formulations, unknowns
/// `(x, y, v, w, λ)` (plus `η` for `ggl1`).
pub struct Pendulum {
    form: Form,
    m: f64,
    l: f64,
    g: f64,
    info: FormulationInfo,
}

fn var(name: &str, kind: VarKind, index: u8) -> VarInfo {
    VarInfo {
        name: name.into(),
        kind,
        index,
    }
}

fn diff_row(text: &str) -> RowInfo {
    RowInfo {
        kind: RowKind::Differential,
        text: text.into(),
    }
}

fn constraint_row(level: u8, text: &str) -> RowInfo {
    RowInfo {
        kind: RowKind::Constraint { level, source: 0 },
        text: text.into(),
    }
}

const POS: &str = "0 = x^2 + y^2 - L^2";
const VEL: &str = "0 = 2*x*v + 2*y*w";
const ACC: &str = "0 = 2*v^2 + 2*w^2 - 2*y*g - 4/m*(x^2 + y^2)*lambda";

impl Pendulum {
    /// The paper's pendulum: `m = 1`, `L = 1`, `g = 13.75…`.
    pub fn new(form: Form) -> Self {
        Pendulum::with_parameters(form, 1.0, 1.0, G_PAPER)
    }

    /// Any parameters.
    pub fn with_parameters(form: Form, m: f64, l: f64, g: f64) -> Self {
        use VarKind::{Algebraic as A, Differential as D};
        let (i_vw, i_lambda) = match form {
            Form::Ori2 => (2, 3),
            Form::Rcd1 | Form::Ggl1 | Form::Psi1 => (1, 2),
            Form::Rcd0 | Form::Psi0 => (1, 1),
        };
        let mut variables = vec![
            var("x", D, 1),
            var("y", D, 1),
            var("v", D, i_vw),
            var("w", D, i_vw),
            var("lambda", A, i_lambda),
        ];
        let dyn4 = || {
            vec![
                diff_row("der(x) = v"),
                diff_row("der(y) = w"),
                diff_row("m*der(v) = -2*x*lambda"),
                diff_row("m*der(w) = -2*y*lambda - m*g"),
            ]
        };
        let (rows, d_index, s_index, c_level) = match form {
            Form::Ori2 => {
                let mut r = dyn4();
                r.push(constraint_row(0, POS));
                (r, 3, 2, 2)
            }
            Form::Rcd1 => {
                let mut r = dyn4();
                r.push(constraint_row(1, VEL));
                (r, 2, 1, 1)
            }
            Form::Rcd0 => {
                let mut r = dyn4();
                r.push(constraint_row(2, ACC));
                (r, 1, 0, 0)
            }
            Form::Ggl1 => {
                variables.push(var("eta", A, 2));
                let r = vec![
                    diff_row("der(x) = v - 2*x*eta"),
                    diff_row("der(y) = w - 2*y*eta"),
                    diff_row("m*der(v) = -2*x*lambda"),
                    diff_row("m*der(w) = -2*y*lambda - m*g"),
                    constraint_row(0, POS),
                    constraint_row(1, VEL),
                ];
                (r, 2, 1, 1)
            }
            Form::Psi1 => {
                let r = vec![
                    diff_row("y*der(x) - x*der(y) = y*v - x*w"),
                    diff_row("m*der(v) = -2*x*lambda"),
                    diff_row("m*der(w) = -2*y*lambda - m*g"),
                    constraint_row(0, POS),
                    constraint_row(1, VEL),
                ];
                (r, 2, 1, 1)
            }
            Form::Psi0 => {
                let r = vec![
                    diff_row("y*der(x) - x*der(y) = y*v - x*w"),
                    diff_row("m*(y*der(v) - x*der(w)) = y*(-2*x*lambda) - x*(-2*y*lambda - m*g)"),
                    constraint_row(0, POS),
                    constraint_row(1, VEL),
                    constraint_row(2, ACC),
                ];
                (r, 1, 0, 0)
            }
        };
        let chain = [POS, VEL, ACC]
            .iter()
            .enumerate()
            .map(|(level, text)| ConstraintInfo {
                level: level as u8,
                source: 0,
                expr: text.trim_start_matches("0 = ").into(),
            })
            .collect();
        let info = FormulationInfo {
            model: "Pendulum".into(),
            name: form.name().into(),
            variables,
            rows,
            d_index: Some(d_index),
            s_index,
            c_level,
            constant_leading: !matches!(form, Form::Psi1 | Form::Psi0),
            constraints: chain,
            invariants: vec!["energy".into()],
            parameters: vec!["m".into(), "L".into(), "g".into()],
        };
        Pendulum {
            form,
            m,
            l,
            g,
            info,
        }
    }

    /// The consistent start `x = L, y = v = w = λ = 0` (`η = 0`).
    pub fn y0(&self) -> Vec<f64> {
        let mut y = vec![self.l, 0.0, 0.0, 0.0, 0.0];
        if self.form == Form::Ggl1 {
            y.push(0.0);
        }
        y
    }

    /// The formulation.
    pub fn form(&self) -> Form {
        self.form
    }

    fn acc(&self, x: f64, y: f64, v: f64, w: f64, lam: f64) -> f64 {
        2.0 * v * v + 2.0 * w * w - 2.0 * y * self.g - 4.0 / self.m * (x * x + y * y) * lam
    }

    fn acc_gradient(&self, x: f64, y: f64, v: f64, w: f64, lam: f64) -> [f64; 5] {
        let m = self.m;
        [
            -8.0 / m * x * lam,
            -2.0 * self.g - 8.0 / m * y * lam,
            4.0 * v,
            4.0 * w,
            -4.0 / m * (x * x + y * y),
        ]
    }
}

impl DaeSystem for Pendulum {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }

    fn parameter_values(&self) -> Vec<f64> {
        vec![self.m, self.l, self.g]
    }

    fn rhs(&self, _t: f64, u: &[f64], f: &mut [f64]) {
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        let (m, g, l) = (self.m, self.g, self.l);
        let pos = x * x + y * y - l * l;
        let vel = 2.0 * x * v + 2.0 * y * w;
        match self.form {
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 => {
                f[0] = v;
                f[1] = w;
                f[2] = -2.0 * x * lam;
                f[3] = -2.0 * y * lam - m * g;
                f[4] = match self.form {
                    Form::Ori2 => pos,
                    Form::Rcd1 => vel,
                    _ => self.acc(x, y, v, w, lam),
                };
            }
            Form::Ggl1 => {
                let eta = u[5];
                f[0] = v - 2.0 * x * eta;
                f[1] = w - 2.0 * y * eta;
                f[2] = -2.0 * x * lam;
                f[3] = -2.0 * y * lam - m * g;
                f[4] = pos;
                f[5] = vel;
            }
            Form::Psi1 => {
                f[0] = y * v - x * w;
                f[1] = -2.0 * x * lam;
                f[2] = -2.0 * y * lam - m * g;
                f[3] = pos;
                f[4] = vel;
            }
            Form::Psi0 => {
                f[0] = y * v - x * w;
                f[1] = y * (-2.0 * x * lam) - x * (-2.0 * y * lam - m * g);
                f[2] = pos;
                f[3] = vel;
                f[4] = self.acc(x, y, v, w, lam);
            }
        }
    }

    fn residual(&self, t: f64, u: &[f64], up: &[f64], r: &mut [f64]) {
        self.rhs(t, u, r);
        let m = self.m;
        let (x, y) = (u[0], u[1]);
        // E(y) y' row by row; the remaining (constraint) rows of E are zero.
        let ey: [f64; 4] = match self.form {
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 | Form::Ggl1 => {
                [up[0], up[1], m * up[2], m * up[3]]
            }
            Form::Psi1 => [y * up[0] - x * up[1], m * up[2], m * up[3], 0.0],
            Form::Psi0 => [y * up[0] - x * up[1], m * (y * up[2] - x * up[3]), 0.0, 0.0],
        };
        for (i, ri) in r.iter_mut().enumerate() {
            *ri = ey.get(i).copied().unwrap_or(0.0) - *ri;
        }
    }

    fn leading(&self, u: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        let m = self.m;
        match self.form {
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 | Form::Ggl1 => {
                e[(0, 0)] = 1.0;
                e[(1, 1)] = 1.0;
                e[(2, 2)] = m;
                e[(3, 3)] = m;
            }
            Form::Psi1 => {
                e[(0, 0)] = u[1];
                e[(0, 1)] = -u[0];
                e[(1, 2)] = m;
                e[(2, 3)] = m;
            }
            Form::Psi0 => {
                e[(0, 0)] = u[1];
                e[(0, 1)] = -u[0];
                e[(1, 2)] = m * u[1];
                e[(1, 3)] = -m * u[0];
            }
        }
    }

    fn rhs_jacobian(&self, _t: f64, u: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        let m = self.m;
        let pos = [2.0 * x, 2.0 * y, 0.0, 0.0, 0.0];
        let vel = [2.0 * v, 2.0 * w, 2.0 * x, 2.0 * y, 0.0];
        let acc = self.acc_gradient(x, y, v, w, lam);
        let set_row = |j: &mut DMatrix<f64>, r: usize, row: &[f64; 5]| {
            for (c, &val) in row.iter().enumerate() {
                j[(r, c)] = val;
            }
        };
        match self.form {
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 => {
                j[(0, 2)] = 1.0;
                j[(1, 3)] = 1.0;
                j[(2, 0)] = -2.0 * lam;
                j[(2, 4)] = -2.0 * x;
                j[(3, 1)] = -2.0 * lam;
                j[(3, 4)] = -2.0 * y;
                let last = match self.form {
                    Form::Ori2 => pos,
                    Form::Rcd1 => vel,
                    _ => acc,
                };
                set_row(j, 4, &last);
            }
            Form::Ggl1 => {
                let eta = u[5];
                j[(0, 0)] = -2.0 * eta;
                j[(0, 2)] = 1.0;
                j[(0, 5)] = -2.0 * x;
                j[(1, 1)] = -2.0 * eta;
                j[(1, 3)] = 1.0;
                j[(1, 5)] = -2.0 * y;
                j[(2, 0)] = -2.0 * lam;
                j[(2, 4)] = -2.0 * x;
                j[(3, 1)] = -2.0 * lam;
                j[(3, 4)] = -2.0 * y;
                set_row(j, 4, &pos);
                set_row(j, 5, &vel);
            }
            Form::Psi1 => {
                set_row(j, 0, &[-w, v, y, -x, 0.0]);
                j[(1, 0)] = -2.0 * lam;
                j[(1, 4)] = -2.0 * x;
                j[(2, 1)] = -2.0 * lam;
                j[(2, 4)] = -2.0 * y;
                set_row(j, 3, &pos);
                set_row(j, 4, &vel);
            }
            Form::Psi0 => {
                set_row(j, 0, &[-w, v, y, -x, 0.0]);
                // y(−2xλ) − x(−2yλ − mg): the λ terms cancel.
                set_row(
                    j,
                    1,
                    &[
                        -2.0 * y * lam + 2.0 * y * lam + m * self.g,
                        -2.0 * x * lam + 2.0 * x * lam,
                        0.0,
                        0.0,
                        -2.0 * x * y + 2.0 * x * y,
                    ],
                );
                set_row(j, 2, &pos);
                set_row(j, 3, &vel);
                set_row(j, 4, &acc);
            }
        }
    }

    fn leading_jacobian(&self, _u: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        let m = self.m;
        match self.form {
            Form::Psi1 => {
                j[(0, 0)] = -z[1];
                j[(0, 1)] = z[0];
            }
            Form::Psi0 => {
                j[(0, 0)] = -z[1];
                j[(0, 1)] = z[0];
                j[(1, 0)] = -m * z[3];
                j[(1, 1)] = m * z[2];
            }
            _ => {}
        }
    }

    fn constraints(&self, _t: f64, u: &[f64], g: &mut [f64]) {
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        g[0] = x * x + y * y - self.l * self.l;
        g[1] = 2.0 * x * v + 2.0 * y * w;
        g[2] = self.acc(x, y, v, w, lam);
    }

    fn constraints_jacobian(&self, _t: f64, u: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        let rows = [
            [2.0 * x, 2.0 * y, 0.0, 0.0, 0.0],
            [2.0 * v, 2.0 * w, 2.0 * x, 2.0 * y, 0.0],
            self.acc_gradient(x, y, v, w, lam),
        ];
        for (r, row) in rows.iter().enumerate() {
            for (c, &val) in row.iter().enumerate() {
                j[(r, c)] = val;
            }
        }
    }

    fn invariants(&self, _t: f64, u: &[f64], out: &mut [f64]) {
        let (y, v, w) = (u[1], u[2], u[3]);
        out[0] = 0.5 * self.m * (v * v + w * w) + self.m * self.g * y;
    }
}

// ---------------------------------------------------------------------------
// The exact pendulum solution (SPEC §3)
// ---------------------------------------------------------------------------

/// Arithmetic–geometric mean.
fn agm(mut a: f64, mut b: f64) -> f64 {
    for _ in 0..64 {
        if (a - b).abs() <= f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    a
}

/// Complete elliptic integral of the first kind `K(m) = π / (2 AGM(1, √(1−m)))`.
pub fn ellip_k(m: f64) -> f64 {
    PI / (2.0 * agm(1.0, (1.0 - m).sqrt()))
}

/// Jacobi `sn(u|m)`, `cn(u|m)` for `0 ≤ m < 1` by the descending Landen
/// (AGM) scheme (Abramowitz & Stegun 16.4; DLMF 22.20(ii)).
pub fn sn_cn(u: f64, m: f64) -> (f64, f64) {
    const LEVELS: usize = 24;
    let mut a = [0.0; LEVELS + 1];
    let mut c = [0.0; LEVELS + 1];
    a[0] = 1.0;
    c[0] = m.sqrt();
    let mut b = (1.0 - m).sqrt();
    let mut n = 0;
    while n < LEVELS && c[n].abs() > f64::EPSILON * a[n] {
        a[n + 1] = 0.5 * (a[n] + b);
        c[n + 1] = 0.5 * (a[n] - b);
        b = (a[n] * b).sqrt();
        n += 1;
    }
    let mut phi = 2f64.powi(n as i32) * a[n] * u;
    for k in (1..=n).rev() {
        phi = 0.5 * (phi + (c[k] / a[k] * phi.sin()).asin());
    }
    (phi.sin(), phi.cos())
}

/// The exact pendulum state `(x, y, v, w, λ)` at `t` for the start at rest
/// at angle `θ₀` from the downward vertical (`θ₀ = π/2`: `x = L, y = 0`):
/// `sin(θ/2) = k sn(K − ωt | k²)`, `θ' = −2kω cn(K − ωt | k²)`,
/// `k = sin(θ₀/2)`, `ω = √(g/L)`, `λ = m(v² + w² − g y)/(2L²)`.
pub fn pendulum_exact_at(t: f64, m: f64, l: f64, g: f64, theta0: f64) -> [f64; 5] {
    let k = (0.5 * theta0).sin();
    let mpar = k * k;
    let kk = ellip_k(mpar);
    let omega = (g / l).sqrt();
    let period = 4.0 * kk;
    let mut u = kk - omega * t;
    u -= period * (u / period).round();
    let (sn, cn) = sn_cn(u, mpar);
    let s = k * sn;
    let c = (1.0 - s * s).max(0.0).sqrt();
    let (sin_t, cos_t) = (2.0 * s * c, 1.0 - 2.0 * s * s);
    let dtheta = -2.0 * k * omega * cn;
    let (x, y) = (l * sin_t, -l * cos_t);
    let (v, w) = (l * cos_t * dtheta, l * sin_t * dtheta);
    let lambda = m * (v * v + w * w - g * y) / (2.0 * l * l);
    [x, y, v, w, lambda]
}

/// The exact solution of the paper's scenarios (`m = L = 1`, `g` of the
/// paper, `θ₀ = π/2`).
pub fn pendulum_exact(t: f64) -> [f64; 5] {
    pendulum_exact_at(t, 1.0, 1.0, G_PAPER, 0.5 * PI)
}

/// Rows `(t, x, y, v, w, λ)` of `shared/reference/pendulum_s01_exact.csv`
/// and `pendulum_s02_periods_exact.csv` (20-digit closed-form values),
/// embedded to check [`pendulum_exact`] without reading files.
pub const EXACT_ROWS: [[f64; 6]; 5] = [
    [
        0.05,
        0.9998522934828797,
        -0.01718694903190989,
        -0.011815997747868187,
        -0.6873967232962528,
        0.354490404750901,
    ],
    [
        0.15,
        0.9880780632827857,
        -0.15395369712786788,
        -0.3167797414815319,
        -2.0330990375003823,
        3.175380825673565,
    ],
    [
        20.0,
        1.0,
        -6.039001248008826e-18,
        -7.78251371967686e-26,
        -1.2887087450500034e-08,
        1.245577672176266e-16,
    ],
    [
        1000.0,
        1.0,
        -1.5097503120022064e-14,
        -9.728142149596073e-21,
        -6.443543725250017e-07,
        3.113944180440665e-13,
    ],
    [
        2000.0,
        1.0,
        -6.039001248008826e-14,
        -7.782513719676859e-20,
        -1.2887087450500034e-06,
        1.245577672176266e-12,
    ],
];

// ---------------------------------------------------------------------------
// Small systems with closed-form solutions and pathological systems
// ---------------------------------------------------------------------------

type RhsFn = fn(f64, &[f64], &mut [f64]);
type JacFn = fn(f64, &[f64], &mut DMatrix<f64>);

/// A system `E y' = f(t, y)` with constant diagonal `E`, given by plain
/// functions.
pub struct Simple {
    info: FormulationInfo,
    e_diag: Vec<f64>,
    f: RhsFn,
    jac: JacFn,
}

impl Simple {
    fn new(name: &str, vars: &[(&str, u8)], e_diag: &[f64], f: RhsFn, jac: JacFn) -> Self {
        let variables = vars
            .iter()
            .zip(e_diag)
            .map(|(&(name, index), &e)| {
                let kind = if e != 0.0 {
                    VarKind::Differential
                } else {
                    VarKind::Algebraic
                };
                var(name, kind, index)
            })
            .collect();
        let rows = e_diag
            .iter()
            .enumerate()
            .map(|(i, &e)| {
                if e != 0.0 {
                    diff_row(&format!("row {i}"))
                } else {
                    constraint_row(0, &format!("row {i}"))
                }
            })
            .collect();
        let max_index = vars.iter().map(|v| v.1).max().unwrap_or(1);
        Simple {
            info: FormulationInfo {
                model: name.into(),
                name: name.into(),
                variables,
                rows,
                d_index: Some(if e_diag.iter().all(|&e| e != 0.0) {
                    0
                } else {
                    max_index
                }),
                s_index: max_index.saturating_sub(1),
                c_level: 0,
                constant_leading: true,
                constraints: Vec::new(),
                invariants: Vec::new(),
                parameters: Vec::new(),
            },
            e_diag: e_diag.to_vec(),
            f,
            jac,
        }
    }

    /// Same system, reported as having one equation too many (for the
    /// overdetermined-input checks; never integrated).
    pub fn overdetermined() -> Self {
        let mut s = blowup();
        s.info.rows.push(constraint_row(0, "extra"));
        s.info.name = "overdetermined".into();
        s
    }
}

impl DaeSystem for Simple {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        Vec::new()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        (self.f)(t, y, f)
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        (self.f)(t, y, r);
        for ((ri, e), ypi) in r.iter_mut().zip(&self.e_diag).zip(yp) {
            *ri = e * ypi - *ri;
        }
    }
    fn leading(&self, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        for (i, &d) in self.e_diag.iter().enumerate() {
            e[(i, i)] = d;
        }
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        (self.jac)(t, y, j)
    }
    fn leading_jacobian(&self, _y: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }
    fn constraints(&self, _t: f64, _y: &[f64], _g: &mut [f64]) {}
    fn constraints_jacobian(&self, _t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    fn invariants(&self, _t: f64, _y: &[f64], _out: &mut [f64]) {}
}

/// Semi-explicit index 1, nonlinear, with a time-varying algebraic unknown:
///
/// ```text
///     p' = (z − p²) q,   q' = −(z − p²) p,   0 = z − 1 − p²
/// ```
///
/// `p = sin t`, `q = cos t`, `z = 1 + sin² t`.
pub fn index1() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        let (p, q, z) = (y[0], y[1], y[2]);
        f[0] = (z - p * p) * q;
        f[1] = -(z - p * p) * p;
        f[2] = z - 1.0 - p * p;
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let (p, q, z) = (y[0], y[1], y[2]);
        j[(0, 0)] = -2.0 * p * q;
        j[(0, 1)] = z - p * p;
        j[(0, 2)] = q;
        j[(1, 0)] = -z + 3.0 * p * p;
        j[(1, 2)] = -p;
        j[(2, 0)] = -2.0 * p;
        j[(2, 2)] = 1.0;
    }
    Simple::new(
        "index1",
        &[("p", 1), ("q", 1), ("z", 1)],
        &[1.0, 1.0, 0.0],
        f,
        jac,
    )
}

/// Exact solution of [`index1`].
pub fn index1_exact(t: f64) -> [f64; 3] {
    [t.sin(), t.cos(), 1.0 + t.sin() * t.sin()]
}

/// Semi-explicit index 2 (SPEC §4, the IDeC test problem of seed 002):
///
/// ```text
///     y1' = y2,  y2' = y4 − y2 y6,  y3' = −y5 y1,  y4' = −y5 y2,
///     0 = 1 − y1² − y2²,  0 = y1 y3 + y2 y4,
/// ```
///
/// `y = (sin t, cos t, −cos t, sin t, −1, 2 tan t)`; `y5`, `y6` have index 2.
pub fn index2() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[1];
        f[1] = y[3] - y[1] * y[5];
        f[2] = -y[4] * y[0];
        f[3] = -y[4] * y[1];
        f[4] = 1.0 - y[0] * y[0] - y[1] * y[1];
        f[5] = y[0] * y[2] + y[1] * y[3];
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 1)] = 1.0;
        j[(1, 1)] = -y[5];
        j[(1, 3)] = 1.0;
        j[(1, 5)] = -y[1];
        j[(2, 0)] = -y[4];
        j[(2, 4)] = -y[0];
        j[(3, 1)] = -y[4];
        j[(3, 4)] = -y[1];
        j[(4, 0)] = -2.0 * y[0];
        j[(4, 1)] = -2.0 * y[1];
        j[(5, 0)] = y[2];
        j[(5, 1)] = y[3];
        j[(5, 2)] = y[0];
        j[(5, 3)] = y[1];
    }
    Simple::new(
        "index2",
        &[
            ("y1", 1),
            ("y2", 1),
            ("y3", 1),
            ("y4", 1),
            ("y5", 2),
            ("y6", 2),
        ],
        &[1.0, 1.0, 1.0, 1.0, 0.0, 0.0],
        f,
        jac,
    )
}

/// Exact solution of [`index2`].
pub fn index2_exact(t: f64) -> [f64; 6] {
    [t.sin(), t.cos(), -t.cos(), t.sin(), -1.0, 2.0 * t.tan()]
}

/// `y' = y²`, `y(0) = 1`: blows up at `t = 1`.
pub fn blowup() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[0] * y[0];
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = 2.0 * y[0];
    }
    Simple::new("blowup", &[("y", 1)], &[1.0], f, jac)
}

/// `0 = y² + 1`: no real solution, so every Newton iteration fails.
pub fn no_real_root() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -(y[0] * y[0] + 1.0);
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = -2.0 * y[0];
    }
    Simple::new("no_real_root", &[("y", 1)], &[0.0], f, jac)
}

/// `0 = 1`, with `E = 0` and `∂f/∂y = 0`: every iteration matrix is zero.
pub fn structurally_singular() -> Simple {
    fn f(_t: f64, _y: &[f64], f: &mut [f64]) {
        f[0] = 1.0;
    }
    fn jac(_t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    Simple::new("singular", &[("y", 1)], &[0.0], f, jac)
}

/// `y' = f` with `f` NaN everywhere.
pub fn nan_rhs() -> Simple {
    fn f(_t: f64, _y: &[f64], f: &mut [f64]) {
        f[0] = f64::NAN;
    }
    fn jac(_t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    Simple::new("nan_rhs", &[("y", 1)], &[1.0], f, jac)
}

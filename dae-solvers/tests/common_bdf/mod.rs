//! Hand-written test models for the BDF tests: the simple pendulum in five
//! formulations (SPEC §2, Jacobians by hand) and small problems with known
//! solutions or known failures.
#![allow(dead_code)]

use dae_core::system::{
    ConstraintInfo, DaeSystem, FormulationInfo, RowInfo, RowKind, VarInfo, VarKind,
};
use nalgebra::DMatrix;

/// Pendulum parameters of the benchmark (SPEC §3).
pub const M: f64 = 1.0;
/// Length.
pub const L: f64 = 1.0;
/// Gravity: the period is 1.99999999990628 s.
pub const G: f64 = 13.750_371_637_329_454;

/// The formulations written by hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// Position constraint replaced by the velocity constraint (λ index 2).
    Rcd1,
    /// Position constraint replaced by the acceleration constraint.
    Rcd0,
    /// Gear–Gupta–Leimkuhler (λ, η index 2).
    Ggl1,
    /// Projected, position and velocity constraints (λ index 2).
    Psi1,
    /// Projected strangeness-free, all three constraints.
    Psi0,
}

impl Form {
    /// All five, in report order.
    pub const ALL: [Form; 5] = [Form::Rcd1, Form::Rcd0, Form::Ggl1, Form::Psi1, Form::Psi0];

    /// Short name as in the paper.
    pub fn name(self) -> &'static str {
        match self {
            Form::Rcd1 => "rcd1",
            Form::Rcd0 => "rcd0",
            Form::Ggl1 => "ggl1",
            Form::Psi1 => "psi1",
            Form::Psi0 => "psi0",
        }
    }

    /// Whether the formulation has index-2 unknowns (run with them out of
    /// the error test).
    pub fn has_index2(self) -> bool {
        matches!(self, Form::Rcd1 | Form::Ggl1 | Form::Psi1)
    }
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
const ACC: &str = "0 = 2*v^2 + 2*w^2 - 2*y*g - (4/m)*(x^2 + y^2)*lambda";

/// The simple pendulum in one formulation.
pub struct Pendulum {
    /// Which formulation.
    pub form: Form,
    info: FormulationInfo,
}

impl Pendulum {
    /// The benchmark pendulum (m = 1, L = 1, g of SPEC §3).
    pub fn new(form: Form) -> Self {
        use VarKind::{Algebraic as A, Differential as D};
        let mut variables = vec![
            var("x", D, 1),
            var("y", D, 1),
            var("v", D, 1),
            var("w", D, 1),
        ];
        let lambda_index = if form.has_index2() { 2 } else { 1 };
        variables.push(var("lambda", A, lambda_index));
        if form == Form::Ggl1 {
            variables.push(var("eta", A, 2));
        }
        let rows = match form {
            Form::Rcd1 | Form::Rcd0 => vec![
                diff_row("der(x) = v"),
                diff_row("der(y) = w"),
                diff_row("m*der(v) = -2*x*lambda"),
                diff_row("m*der(w) = -2*y*lambda - m*g"),
                if form == Form::Rcd1 {
                    constraint_row(1, VEL)
                } else {
                    constraint_row(2, ACC)
                },
            ],
            Form::Ggl1 => vec![
                diff_row("der(x) = v - 2*x*eta"),
                diff_row("der(y) = w - 2*y*eta"),
                diff_row("m*der(v) = -2*x*lambda"),
                diff_row("m*der(w) = -2*y*lambda - m*g"),
                constraint_row(0, POS),
                constraint_row(1, VEL),
            ],
            Form::Psi1 => vec![
                diff_row("y*der(x) - x*der(y) = y*v - x*w"),
                diff_row("m*der(v) = -2*x*lambda"),
                diff_row("m*der(w) = -2*y*lambda - m*g"),
                constraint_row(0, POS),
                constraint_row(1, VEL),
            ],
            Form::Psi0 => vec![
                diff_row("y*der(x) - x*der(y) = y*v - x*w"),
                diff_row("m*(y*der(v) - x*der(w)) = y*(-2*x*lambda) - x*(-2*y*lambda - m*g)"),
                constraint_row(0, POS),
                constraint_row(1, VEL),
                constraint_row(2, ACC),
            ],
        };
        let (d_index, s_index, c_level) = match form {
            Form::Rcd1 => (2, 1, 1),
            Form::Rcd0 => (1, 0, 0),
            Form::Ggl1 | Form::Psi1 => (2, 1, 1),
            Form::Psi0 => (1, 0, 0),
        };
        let constraints = [POS, VEL, ACC]
            .iter()
            .enumerate()
            .map(|(level, expr)| ConstraintInfo {
                level: level as u8,
                source: 0,
                expr: expr.trim_start_matches("0 = ").into(),
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
            constraints,
            invariants: vec!["energy".into()],
            parameters: vec!["m".into(), "L".into(), "g".into()],
        };
        Pendulum { form, info }
    }

    /// Consistent initial values x = 1, y = v = w = λ (= η) = 0.
    pub fn y0(&self) -> Vec<f64> {
        let mut y = vec![1.0, 0.0, 0.0, 0.0, 0.0];
        if self.form == Form::Ggl1 {
            y.push(0.0);
        }
        y
    }

    /// Position of λ among the unknowns.
    pub const LAMBDA: usize = 4;
}

impl DaeSystem for Pendulum {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }

    fn parameter_values(&self) -> Vec<f64> {
        vec![M, L, G]
    }

    fn rhs(&self, _t: f64, u: &[f64], f: &mut [f64]) {
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        let pos = x * x + y * y - L * L;
        let vel = 2.0 * x * v + 2.0 * y * w;
        let acc = 2.0 * v * v + 2.0 * w * w - 2.0 * y * G - (4.0 / M) * (x * x + y * y) * lam;
        match self.form {
            Form::Rcd1 | Form::Rcd0 => {
                f[0] = v;
                f[1] = w;
                f[2] = -2.0 * x * lam;
                f[3] = -2.0 * y * lam - M * G;
                f[4] = if self.form == Form::Rcd1 { vel } else { acc };
            }
            Form::Ggl1 => {
                let eta = u[5];
                f[0] = v - 2.0 * x * eta;
                f[1] = w - 2.0 * y * eta;
                f[2] = -2.0 * x * lam;
                f[3] = -2.0 * y * lam - M * G;
                f[4] = pos;
                f[5] = vel;
            }
            Form::Psi1 => {
                f[0] = y * v - x * w;
                f[1] = -2.0 * x * lam;
                f[2] = -2.0 * y * lam - M * G;
                f[3] = pos;
                f[4] = vel;
            }
            Form::Psi0 => {
                f[0] = y * v - x * w;
                f[1] = y * (-2.0 * x * lam) - x * (-2.0 * y * lam - M * G);
                f[2] = pos;
                f[3] = vel;
                f[4] = acc;
            }
        }
    }

    fn residual(&self, t: f64, u: &[f64], up: &[f64], r: &mut [f64]) {
        self.rhs(t, u, r);
        for ri in r.iter_mut() {
            *ri = -*ri;
        }
        let (x, y) = (u[0], u[1]);
        match self.form {
            Form::Rcd1 | Form::Rcd0 | Form::Ggl1 => {
                r[0] += up[0];
                r[1] += up[1];
                r[2] += M * up[2];
                r[3] += M * up[3];
            }
            Form::Psi1 => {
                r[0] += y * up[0] - x * up[1];
                r[1] += M * up[2];
                r[2] += M * up[3];
            }
            Form::Psi0 => {
                r[0] += y * up[0] - x * up[1];
                r[1] += M * (y * up[2] - x * up[3]);
            }
        }
    }

    fn leading(&self, u: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        let (x, y) = (u[0], u[1]);
        match self.form {
            Form::Rcd1 | Form::Rcd0 | Form::Ggl1 => {
                e[(0, 0)] = 1.0;
                e[(1, 1)] = 1.0;
                e[(2, 2)] = M;
                e[(3, 3)] = M;
            }
            Form::Psi1 => {
                e[(0, 0)] = y;
                e[(0, 1)] = -x;
                e[(1, 2)] = M;
                e[(2, 3)] = M;
            }
            Form::Psi0 => {
                e[(0, 0)] = y;
                e[(0, 1)] = -x;
                e[(1, 2)] = M * y;
                e[(1, 3)] = -M * x;
            }
        }
    }

    fn rhs_jacobian(&self, _t: f64, u: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        // Rows of the three constraint levels.
        let pos = [2.0 * x, 2.0 * y, 0.0, 0.0, 0.0];
        let vel = [2.0 * v, 2.0 * w, 2.0 * x, 2.0 * y, 0.0];
        let acc = [
            -(8.0 / M) * x * lam,
            -2.0 * G - (8.0 / M) * y * lam,
            4.0 * v,
            4.0 * w,
            -(4.0 / M) * (x * x + y * y),
        ];
        let mut set_row = |row: usize, vals: &[f64; 5]| {
            for (c, &v) in vals.iter().enumerate() {
                j[(row, c)] = v;
            }
        };
        match self.form {
            Form::Rcd1 | Form::Rcd0 | Form::Ggl1 => {
                set_row(0, &[0.0, 0.0, 1.0, 0.0, 0.0]);
                set_row(1, &[0.0, 0.0, 0.0, 1.0, 0.0]);
                set_row(2, &[-2.0 * lam, 0.0, 0.0, 0.0, -2.0 * x]);
                set_row(3, &[0.0, -2.0 * lam, 0.0, 0.0, -2.0 * y]);
                match self.form {
                    Form::Rcd1 => set_row(4, &vel),
                    Form::Rcd0 => set_row(4, &acc),
                    _ => {
                        set_row(4, &pos);
                        set_row(5, &vel);
                        let eta = u[5];
                        j[(0, 0)] = -2.0 * eta;
                        j[(0, 5)] = -2.0 * x;
                        j[(1, 1)] = -2.0 * eta;
                        j[(1, 5)] = -2.0 * y;
                    }
                }
            }
            Form::Psi1 => {
                set_row(0, &[-w, v, y, -x, 0.0]);
                set_row(1, &[-2.0 * lam, 0.0, 0.0, 0.0, -2.0 * x]);
                set_row(2, &[0.0, -2.0 * lam, 0.0, 0.0, -2.0 * y]);
                set_row(3, &pos);
                set_row(4, &vel);
            }
            Form::Psi0 => {
                set_row(0, &[-w, v, y, -x, 0.0]);
                // f1 = y(-2xλ) - x(-2yλ - mg), differentiated as written.
                set_row(
                    1,
                    &[
                        -2.0 * y * lam + 2.0 * y * lam + M * G,
                        -2.0 * x * lam + 2.0 * x * lam,
                        0.0,
                        0.0,
                        -2.0 * x * y + 2.0 * x * y,
                    ],
                );
                set_row(2, &pos);
                set_row(3, &vel);
                set_row(4, &acc);
            }
        }
    }

    fn leading_jacobian(&self, _u: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        match self.form {
            Form::Psi1 => {
                j[(0, 0)] = -z[1];
                j[(0, 1)] = z[0];
            }
            Form::Psi0 => {
                j[(0, 0)] = -z[1];
                j[(0, 1)] = z[0];
                j[(1, 0)] = -M * z[3];
                j[(1, 1)] = M * z[2];
            }
            _ => {}
        }
    }

    fn constraints(&self, _t: f64, u: &[f64], g: &mut [f64]) {
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        g[0] = x * x + y * y - L * L;
        g[1] = 2.0 * x * v + 2.0 * y * w;
        g[2] = 2.0 * v * v + 2.0 * w * w - 2.0 * y * G - (4.0 / M) * (x * x + y * y) * lam;
    }

    fn constraints_jacobian(&self, _t: f64, u: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        let rows = [
            [2.0 * x, 2.0 * y, 0.0, 0.0, 0.0],
            [2.0 * v, 2.0 * w, 2.0 * x, 2.0 * y, 0.0],
            [
                -(8.0 / M) * x * lam,
                -2.0 * G - (8.0 / M) * y * lam,
                4.0 * v,
                4.0 * w,
                -(4.0 / M) * (x * x + y * y),
            ],
        ];
        for (r, row) in rows.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                j[(r, c)] = v;
            }
        }
    }

    fn invariants(&self, _t: f64, u: &[f64], out: &mut [f64]) {
        let (y, v, w) = (u[1], u[2], u[3]);
        out[0] = 0.5 * M * (v * v + w * w) + M * G * y;
    }
}

/// Exact pendulum values `(t, [x, y, v, w, λ])` from a reference file in
/// `shared/reference/`.
pub fn reference(file: &str) -> Vec<(f64, [f64; 5])> {
    let path = format!(
        "{}/../../shared/reference/{file}",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|line| {
            let v: Vec<f64> = line
                .split(',')
                .map(|s| s.trim().parse().expect("number"))
                .collect();
            (v[0], [v[1], v[2], v[3], v[4], v[5]])
        })
        .collect()
}

/// `Σ_i |u_i − exact_i|` over x, y, v, w, λ.
pub fn err_sum(u: &[f64], exact: &[f64; 5]) -> f64 {
    (0..5).map(|i| (u[i] - exact[i]).abs()).sum()
}

/// `max(|x−x*|, |y−y*|, |v−v*|, |w−w*|)`.
pub fn err_max(u: &[f64], exact: &[f64; 5]) -> f64 {
    (0..4).map(|i| (u[i] - exact[i]).abs()).fold(0.0, f64::max)
}

/// A semi-explicit system `diag(d) y' = f(t, y)` given by plain functions.
pub struct SemiExplicit {
    info: FormulationInfo,
    diag: Vec<f64>,
    f: fn(f64, &[f64], &mut [f64]),
    jac: fn(f64, &[f64], &mut DMatrix<f64>),
}

impl SemiExplicit {
    /// `diag[i] = 1` for a differential row, `0` for an algebraic one.
    pub fn new(
        name: &str,
        diag: &[f64],
        f: fn(f64, &[f64], &mut [f64]),
        jac: fn(f64, &[f64], &mut DMatrix<f64>),
    ) -> Self {
        let variables = diag
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                if d != 0.0 {
                    var(&format!("y{i}"), VarKind::Differential, 1)
                } else {
                    var(&format!("z{i}"), VarKind::Algebraic, 1)
                }
            })
            .collect();
        let rows = diag
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                if d != 0.0 {
                    diff_row(&format!("der(y{i}) = f{i}"))
                } else {
                    constraint_row(0, &format!("0 = f{i}"))
                }
            })
            .collect();
        let info = FormulationInfo {
            model: name.into(),
            name: name.into(),
            variables,
            rows,
            d_index: Some(if diag.contains(&0.0) { 1 } else { 0 }),
            s_index: 0,
            c_level: 0,
            constant_leading: true,
            constraints: vec![],
            invariants: vec![],
            parameters: vec![],
        };
        SemiExplicit {
            info,
            diag: diag.to_vec(),
            f,
            jac,
        }
    }
}

impl DaeSystem for SemiExplicit {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        vec![]
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        (self.f)(t, y, f)
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        (self.f)(t, y, r);
        for ((ri, d), p) in r.iter_mut().zip(&self.diag).zip(yp) {
            *ri = d * p - *ri;
        }
    }
    fn leading(&self, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        for (i, &d) in self.diag.iter().enumerate() {
            e[(i, i)] = d;
        }
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        (self.jac)(t, y, j)
    }
    fn leading_jacobian(&self, _y: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }
    fn constraints(&self, _t: f64, _y: &[f64], _g: &mut [f64]) {}
    fn constraints_jacobian(&self, _t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    fn invariants(&self, _t: f64, _y: &[f64], _out: &mut [f64]) {}
}

/// ODE `y0' = y1, y1' = −y0, y2' = −2t y2²`: `(sin t, cos t, 1/(1+t²))`.
pub fn ode() -> SemiExplicit {
    fn f(t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[1];
        f[1] = -y[0];
        f[2] = -2.0 * t * y[2] * y[2];
    }
    fn jac(t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -1.0;
        j[(2, 2)] = -4.0 * t * y[2];
    }
    SemiExplicit::new("ode", &[1.0, 1.0, 1.0], f, jac)
}

/// Exact solution of [`ode`].
pub fn ode_exact(t: f64) -> Vec<f64> {
    vec![t.sin(), t.cos(), 1.0 / (1.0 + t * t)]
}

/// Semi-explicit index-1 DAE `y0' = z, y1' = y0 z, 0 = y0² + z² − 1`:
/// `(sin t, sin²t / 2, cos t)` for `t < π/2`.
pub fn dae1() -> SemiExplicit {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[2];
        f[1] = y[0] * y[2];
        f[2] = y[0] * y[0] + y[2] * y[2] - 1.0;
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        j[(0, 2)] = 1.0;
        j[(1, 0)] = y[2];
        j[(1, 2)] = y[0];
        j[(2, 0)] = 2.0 * y[0];
        j[(2, 2)] = 2.0 * y[2];
    }
    SemiExplicit::new("dae1", &[1.0, 1.0, 0.0], f, jac)
}

/// Exact solution of [`dae1`].
pub fn dae1_exact(t: f64) -> Vec<f64> {
    vec![t.sin(), 0.5 * t.sin() * t.sin(), t.cos()]
}

/// `y' = y²`, `y(0) = 1`: blows up at `t = 1`.
pub fn blow_up() -> SemiExplicit {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[0] * y[0];
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = 2.0 * y[0];
    }
    SemiExplicit::new("blow_up", &[1.0], f, jac)
}

/// `y0' = −y0, 0 = 0`: the second unknown appears nowhere, so every
/// iteration matrix has a zero column.
pub fn structurally_singular() -> SemiExplicit {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -y[0];
        f[1] = 0.0;
    }
    fn jac(_t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        j[(0, 0)] = -1.0;
    }
    SemiExplicit::new("singular", &[1.0, 0.0], f, jac)
}

/// `y' = −y` for `t ≤ 0.5`, NaN beyond.
pub fn nan_beyond_half() -> SemiExplicit {
    fn f(t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = if t <= 0.5 { -y[0] } else { f64::NAN };
    }
    fn jac(_t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = -1.0;
    }
    SemiExplicit::new("nan_beyond_half", &[1.0], f, jac)
}

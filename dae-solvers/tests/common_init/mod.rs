//! Hand-written formulations for the tests of consistent initialisation:
//! the simple pendulum (rcd0, ggl1, ovd1, psi1), the planar double pendulum
//! (rcd0) and the index-2 test problem of the IDeC paper. Every Jacobian is
//! derived by hand and checked against finite differences in the tests.

#![allow(dead_code)]

use dae_core::system::{
    ConstraintInfo, DaeSystem, FormulationInfo, RowInfo, RowKind, VarInfo, VarKind,
};
use nalgebra::DMatrix;

/// Gravity of the paper's scenarios.
pub const G: f64 = 13.750_371_637_329_454;

/// What a hand-written formulation provides; [`Sys`] turns it into a
/// [`DaeSystem`].
pub trait Hand {
    fn info(&self) -> &FormulationInfo;
    fn params(&self) -> Vec<f64>;
    /// `E(y)`.
    fn e(&self, y: &[f64], e: &mut DMatrix<f64>);
    /// `f(t, y)`.
    fn f(&self, t: f64, y: &[f64], f: &mut [f64]);
    /// `∂f/∂y`.
    fn fy(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>);
    /// `∂(E(y) z)/∂y`.
    fn ey(&self, _y: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }
    /// The model's constraint chain.
    fn chain(&self, t: f64, y: &[f64], g: &mut [f64]);
    /// Its Jacobian.
    fn chain_y(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>);
    fn inv(&self, _t: f64, _y: &[f64], _out: &mut [f64]) {}
}

/// A [`Hand`] as a [`DaeSystem`].
pub struct Sys<H>(pub H);

impl<H: Hand> DaeSystem for Sys<H> {
    fn info(&self) -> &FormulationInfo {
        self.0.info()
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.0.params()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        self.0.f(t, y, f)
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let info = self.0.info();
        let mut e = DMatrix::zeros(info.equations(), info.unknowns());
        self.0.e(y, &mut e);
        self.0.f(t, y, r);
        for (i, ri) in r.iter_mut().enumerate() {
            let ey: f64 = (0..yp.len()).map(|j| e[(i, j)] * yp[j]).sum();
            *ri = ey - *ri;
        }
    }
    fn leading(&self, y: &[f64], e: &mut DMatrix<f64>) {
        self.0.e(y, e)
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.0.fy(t, y, j)
    }
    fn leading_jacobian(&self, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        self.0.ey(y, z, j)
    }
    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.0.chain(t, y, g)
    }
    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.0.chain_y(t, y, j)
    }
    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.0.inv(t, y, out)
    }
}

fn var(name: &str, kind: VarKind, index: u8) -> VarInfo {
    VarInfo {
        name: name.to_string(),
        kind,
        index,
    }
}

fn diff_row(text: &str) -> RowInfo {
    RowInfo {
        kind: RowKind::Differential,
        text: text.to_string(),
    }
}

fn con_row(level: u8, source: u16, text: &str) -> RowInfo {
    RowInfo {
        kind: RowKind::Constraint { level, source },
        text: text.to_string(),
    }
}

fn member(level: u8, source: u16, expr: &str) -> ConstraintInfo {
    ConstraintInfo {
        level,
        source,
        expr: expr.to_string(),
    }
}

// ---------------------------------------------------------------------------
// The simple pendulum.

/// Formulations of the pendulum written by hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// Position constraint replaced by the acceleration level: 5 × 5, index 1.
    Rcd0,
    /// Gear–Gupta–Leimkuhler: 6 × 6 with `eta`.
    Ggl1,
    /// Model + velocity constraint: 6 equations, 5 unknowns.
    Ovd1,
    /// Projected with selector `[[y, -x, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]`:
    /// `E` depends on `y`.
    Psi1,
}

/// Level-0 text of the pendulum's constraint.
pub const PENDULUM_L0: &str = "x^2 + y^2 - L^2";
/// Level-1 text.
pub const PENDULUM_L1: &str = "2*x*v + 2*y*w";
/// Level-2 text.
pub const PENDULUM_L2: &str = "2*v^2 + 2*w^2 - 2*y*g - 4/m*(x^2 + y^2)*lambda";

/// `m v' = -2xλ, m w' = -2yλ - mg, 0 = x² + y² - L²` in one of four
/// formulations. Unknowns `x, y, v, w, lambda` (`eta` last for ggl1).
pub struct Pendulum {
    pub m: f64,
    pub l: f64,
    pub g: f64,
    pub form: Form,
    info: FormulationInfo,
}

impl Pendulum {
    /// The paper's parameters.
    pub fn new(form: Form) -> Self {
        Self::with(form, 1.0, 1.0, G)
    }

    pub fn with(form: Form, m: f64, l: f64, g: f64) -> Self {
        let d = VarKind::Differential;
        let a = VarKind::Algebraic;
        let mut variables = vec![
            var("x", d, 1),
            var("y", d, 1),
            var("v", d, 1),
            var("w", d, 1),
        ];
        let dyn_rows = |first: &str, second: &str| {
            vec![
                diff_row(first),
                diff_row(second),
                diff_row("m*der(v) = -2*x*lambda"),
                diff_row("m*der(w) = -2*y*lambda - m*g"),
            ]
        };
        let (name, rows) = match form {
            Form::Rcd0 => {
                variables.push(var("lambda", a, 1));
                let mut rows = dyn_rows("der(x) = v", "der(y) = w");
                rows.push(con_row(2, 0, PENDULUM_L2));
                ("rcd0", rows)
            }
            Form::Ggl1 => {
                variables.push(var("lambda", a, 2));
                variables.push(var("eta", a, 2));
                let mut rows = dyn_rows("der(x) = v - 2*x*eta", "der(y) = w - 2*y*eta");
                rows.push(con_row(0, 0, PENDULUM_L0));
                rows.push(con_row(1, 0, PENDULUM_L1));
                ("ggl1", rows)
            }
            Form::Ovd1 => {
                variables.push(var("lambda", a, 2));
                let mut rows = dyn_rows("der(x) = v", "der(y) = w");
                rows.push(con_row(0, 0, PENDULUM_L0));
                rows.push(con_row(1, 0, PENDULUM_L1));
                ("ovd1", rows)
            }
            Form::Psi1 => {
                variables.push(var("lambda", a, 2));
                let mut rows = dyn_rows("y*der(x) - x*der(y) = y*v - x*w", "");
                rows.remove(1);
                rows.push(con_row(0, 0, PENDULUM_L0));
                rows.push(con_row(1, 0, PENDULUM_L1));
                ("psi1", rows)
            }
        };
        let info = FormulationInfo {
            model: "Pendulum".to_string(),
            name: name.to_string(),
            variables,
            rows,
            d_index: match form {
                Form::Rcd0 => Some(1),
                Form::Ovd1 => None,
                _ => Some(2),
            },
            s_index: if form == Form::Rcd0 { 0 } else { 1 },
            c_level: if form == Form::Rcd0 { 0 } else { 1 },
            constant_leading: form != Form::Psi1,
            constraints: vec![
                member(0, 0, PENDULUM_L0),
                member(1, 0, PENDULUM_L1),
                member(2, 0, PENDULUM_L2),
            ],
            invariants: vec!["energy".to_string()],
            parameters: vec!["m".to_string(), "L".to_string(), "g".to_string()],
        };
        Pendulum {
            m,
            l,
            g,
            form,
            info,
        }
    }

    fn g0(&self, y: &[f64]) -> f64 {
        y[0] * y[0] + y[1] * y[1] - self.l * self.l
    }
    fn g1(&self, y: &[f64]) -> f64 {
        2.0 * y[0] * y[2] + 2.0 * y[1] * y[3]
    }
    fn g2(&self, y: &[f64]) -> f64 {
        let (x, yy, v, w, lam) = (y[0], y[1], y[2], y[3], y[4]);
        2.0 * v * v + 2.0 * w * w - 2.0 * yy * self.g - 4.0 / self.m * (x * x + yy * yy) * lam
    }
    /// Write the gradient of chain member `level` into row `r` of `j`.
    fn grad(&self, level: usize, y: &[f64], j: &mut DMatrix<f64>, r: usize) {
        let (x, yy, v, w, lam) = (y[0], y[1], y[2], y[3], y[4]);
        let c = 4.0 / self.m;
        let g: [f64; 5] = match level {
            0 => [2.0 * x, 2.0 * yy, 0.0, 0.0, 0.0],
            1 => [2.0 * v, 2.0 * w, 2.0 * x, 2.0 * yy, 0.0],
            _ => [
                -2.0 * c * x * lam,
                -2.0 * self.g - 2.0 * c * yy * lam,
                4.0 * v,
                4.0 * w,
                -c * (x * x + yy * yy),
            ],
        };
        for (col, value) in g.iter().enumerate() {
            j[(r, col)] = *value;
        }
    }
}

impl Hand for Pendulum {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn params(&self) -> Vec<f64> {
        vec![self.m, self.l, self.g]
    }
    fn e(&self, y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        match self.form {
            Form::Psi1 => {
                e[(0, 0)] = y[1];
                e[(0, 1)] = -y[0];
                e[(1, 2)] = self.m;
                e[(2, 3)] = self.m;
            }
            _ => {
                e[(0, 0)] = 1.0;
                e[(1, 1)] = 1.0;
                e[(2, 2)] = self.m;
                e[(3, 3)] = self.m;
            }
        }
    }
    fn f(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        let (x, yy, v, w, lam) = (y[0], y[1], y[2], y[3], y[4]);
        let fv = -2.0 * x * lam;
        let fw = -2.0 * yy * lam - self.m * self.g;
        match self.form {
            Form::Rcd0 => {
                f.copy_from_slice(&[v, w, fv, fw, self.g2(y)]);
            }
            Form::Ggl1 => {
                let eta = y[5];
                f.copy_from_slice(&[
                    v - 2.0 * x * eta,
                    w - 2.0 * yy * eta,
                    fv,
                    fw,
                    self.g0(y),
                    self.g1(y),
                ]);
            }
            Form::Ovd1 => {
                f.copy_from_slice(&[v, w, fv, fw, self.g0(y), self.g1(y)]);
            }
            Form::Psi1 => {
                f.copy_from_slice(&[yy * v - x * w, fv, fw, self.g0(y), self.g1(y)]);
            }
        }
    }
    fn fy(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let (x, yy, v, w, lam) = (y[0], y[1], y[2], y[3], y[4]);
        j.fill(0.0);
        // The two force rows, at rows `r` and `r + 1`.
        let forces = |j: &mut DMatrix<f64>, r: usize| {
            j[(r, 0)] = -2.0 * lam;
            j[(r, 4)] = -2.0 * x;
            j[(r + 1, 1)] = -2.0 * lam;
            j[(r + 1, 4)] = -2.0 * yy;
        };
        match self.form {
            Form::Rcd0 => {
                j[(0, 2)] = 1.0;
                j[(1, 3)] = 1.0;
                forces(j, 2);
                self.grad(2, y, j, 4);
            }
            Form::Ggl1 => {
                let eta = y[5];
                j[(0, 0)] = -2.0 * eta;
                j[(0, 2)] = 1.0;
                j[(0, 5)] = -2.0 * x;
                j[(1, 1)] = -2.0 * eta;
                j[(1, 3)] = 1.0;
                j[(1, 5)] = -2.0 * yy;
                forces(j, 2);
                self.grad(0, y, j, 4);
                self.grad(1, y, j, 5);
            }
            Form::Ovd1 => {
                j[(0, 2)] = 1.0;
                j[(1, 3)] = 1.0;
                forces(j, 2);
                self.grad(0, y, j, 4);
                self.grad(1, y, j, 5);
            }
            Form::Psi1 => {
                j[(0, 0)] = -w;
                j[(0, 1)] = v;
                j[(0, 2)] = yy;
                j[(0, 3)] = -x;
                forces(j, 1);
                self.grad(0, y, j, 3);
                self.grad(1, y, j, 4);
            }
        }
    }
    fn ey(&self, _y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        if self.form == Form::Psi1 {
            // Row 0 of E(y) z is y*z0 - x*z1.
            j[(0, 0)] = -z[1];
            j[(0, 1)] = z[0];
        }
    }
    fn chain(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = self.g0(y);
        g[1] = self.g1(y);
        g[2] = self.g2(y);
    }
    fn chain_y(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        for level in 0..3 {
            self.grad(level, y, j, level);
        }
    }
    fn inv(&self, _t: f64, y: &[f64], out: &mut [f64]) {
        out[0] = 0.5 * self.m * (y[2] * y[2] + y[3] * y[3]) + self.m * self.g * y[1];
    }
}

/// The exact multiplier on the circle: `λ = m(v² + w² − g y)/(2L²)`.
pub fn pendulum_lambda(p: &Pendulum, y: &[f64]) -> f64 {
    p.m * (y[2] * y[2] + y[3] * y[3] - p.g * y[1]) / (2.0 * p.l * p.l)
}

// ---------------------------------------------------------------------------
// The planar double pendulum.

/// Two point masses on rigid massless rods, in rcd0 form. Unknowns
/// `x1, y1, x2, y2, v1, w1, v2, w2, lambda1, lambda2`; constraints
/// `a = x1² + y1² − L1²` (source 0) and `b = (x2−x1)² + (y2−y1)² − L2²`
/// (source 1). Chain order: a, b, a', b', a'', b''.
pub struct DoublePendulum {
    pub m1: f64,
    pub m2: f64,
    pub l1: f64,
    pub l2: f64,
    pub g: f64,
    info: FormulationInfo,
}

impl DoublePendulum {
    pub fn new(m1: f64, m2: f64, l1: f64, l2: f64, g: f64) -> Self {
        let d = VarKind::Differential;
        let a = VarKind::Algebraic;
        let variables = vec![
            var("x1", d, 1),
            var("y1", d, 1),
            var("x2", d, 1),
            var("y2", d, 1),
            var("v1", d, 1),
            var("w1", d, 1),
            var("v2", d, 1),
            var("w2", d, 1),
            var("lambda1", a, 1),
            var("lambda2", a, 1),
        ];
        let rows = vec![
            diff_row("der(x1) = v1"),
            diff_row("der(y1) = w1"),
            diff_row("der(x2) = v2"),
            diff_row("der(y2) = w2"),
            diff_row("m1*der(v1) = -2*x1*lambda1 + 2*(x2 - x1)*lambda2"),
            diff_row("m1*der(w1) = -2*y1*lambda1 + 2*(y2 - y1)*lambda2 - m1*g"),
            diff_row("m2*der(v2) = -2*(x2 - x1)*lambda2"),
            diff_row("m2*der(w2) = -2*(y2 - y1)*lambda2 - m2*g"),
            con_row(2, 0, DP_A2),
            con_row(2, 1, DP_B2),
        ];
        let info = FormulationInfo {
            model: "DoublePendulum".to_string(),
            name: "rcd0".to_string(),
            variables,
            rows,
            d_index: Some(1),
            s_index: 0,
            c_level: 0,
            constant_leading: true,
            constraints: vec![
                member(0, 0, DP_A0),
                member(0, 1, DP_B0),
                member(1, 0, DP_A1),
                member(1, 1, DP_B1),
                member(2, 0, DP_A2),
                member(2, 1, DP_B2),
            ],
            invariants: vec!["energy".to_string()],
            parameters: ["m1", "m2", "L1", "L2", "g"]
                .iter()
                .map(|s| s.to_string())
                .collect(),
        };
        DoublePendulum {
            m1,
            m2,
            l1,
            l2,
            g,
            info,
        }
    }

    /// The chain and its Jacobian (rows a, b, a', b', a'', b'').
    fn eval(&self, y: &[f64], g: &mut [f64], j: Option<&mut DMatrix<f64>>) {
        let [x1, y1, x2, y2, v1, w1, v2, w2, l1, l2] =
            [y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7], y[8], y[9]];
        let (dx, dy, dv, dw) = (x2 - x1, y2 - y1, v2 - v1, w2 - w1);
        let c = x1 * dx + y1 * dy;
        let r1 = x1 * x1 + y1 * y1;
        let r2 = dx * dx + dy * dy;
        let k1 = 4.0 / self.m1;
        let mu = 1.0 / self.m1 + 1.0 / self.m2;
        g[0] = r1 - self.l1 * self.l1;
        g[1] = r2 - self.l2 * self.l2;
        g[2] = 2.0 * x1 * v1 + 2.0 * y1 * w1;
        g[3] = 2.0 * dx * dv + 2.0 * dy * dw;
        g[4] = 2.0 * (v1 * v1 + w1 * w1) - 2.0 * y1 * self.g + k1 * (-r1 * l1 + c * l2);
        g[5] = 2.0 * (dv * dv + dw * dw) + k1 * c * l1 - 4.0 * mu * r2 * l2;
        if let Some(j) = j {
            j.fill(0.0);
            let rows: [[f64; 10]; 6] = [
                [2.0 * x1, 2.0 * y1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [
                    -2.0 * dx,
                    -2.0 * dy,
                    2.0 * dx,
                    2.0 * dy,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                ],
                [
                    2.0 * v1,
                    2.0 * w1,
                    0.0,
                    0.0,
                    2.0 * x1,
                    2.0 * y1,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                ],
                [
                    -2.0 * dv,
                    -2.0 * dw,
                    2.0 * dv,
                    2.0 * dw,
                    -2.0 * dx,
                    -2.0 * dy,
                    2.0 * dx,
                    2.0 * dy,
                    0.0,
                    0.0,
                ],
                [
                    k1 * (-2.0 * x1 * l1 + (dx - x1) * l2),
                    -2.0 * self.g + k1 * (-2.0 * y1 * l1 + (dy - y1) * l2),
                    k1 * x1 * l2,
                    k1 * y1 * l2,
                    4.0 * v1,
                    4.0 * w1,
                    0.0,
                    0.0,
                    -k1 * r1,
                    k1 * c,
                ],
                [
                    k1 * (dx - x1) * l1 + 8.0 * mu * dx * l2,
                    k1 * (dy - y1) * l1 + 8.0 * mu * dy * l2,
                    k1 * x1 * l1 - 8.0 * mu * dx * l2,
                    k1 * y1 * l1 - 8.0 * mu * dy * l2,
                    -4.0 * dv,
                    -4.0 * dw,
                    4.0 * dv,
                    4.0 * dw,
                    k1 * c,
                    -4.0 * mu * r2,
                ],
            ];
            for (r, row) in rows.iter().enumerate() {
                for (col, value) in row.iter().enumerate() {
                    j[(r, col)] = *value;
                }
            }
        }
    }

    /// A consistent state from angles (from the downward vertical) and
    /// angular velocities; the multipliers are set to 0.
    pub fn state(&self, th1: f64, th2: f64, om1: f64, om2: f64) -> Vec<f64> {
        let (x1, y1) = (self.l1 * th1.sin(), -self.l1 * th1.cos());
        let (x2, y2) = (x1 + self.l2 * th2.sin(), y1 - self.l2 * th2.cos());
        let (v1, w1) = (self.l1 * th1.cos() * om1, self.l1 * th1.sin() * om1);
        let (v2, w2) = (
            v1 + self.l2 * th2.cos() * om2,
            w1 + self.l2 * th2.sin() * om2,
        );
        vec![x1, y1, x2, y2, v1, w1, v2, w2, 0.0, 0.0]
    }
}

pub const DP_A0: &str = "x1^2 + y1^2 - L1^2";
pub const DP_B0: &str = "(x2 - x1)^2 + (y2 - y1)^2 - L2^2";
pub const DP_A1: &str = "2*x1*v1 + 2*y1*w1";
pub const DP_B1: &str = "2*(x2 - x1)*(v2 - v1) + 2*(y2 - y1)*(w2 - w1)";
pub const DP_A2: &str = "2*(v1^2 + w1^2) - 2*y1*g + 4/m1*(-(x1^2 + y1^2)*lambda1 + (x1*(x2 - x1) + y1*(y2 - y1))*lambda2)";
pub const DP_B2: &str = "2*((v2 - v1)^2 + (w2 - w1)^2) + 4/m1*(x1*(x2 - x1) + y1*(y2 - y1))*lambda1 - 4*(1/m1 + 1/m2)*((x2 - x1)^2 + (y2 - y1)^2)*lambda2";

impl Hand for DoublePendulum {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn params(&self) -> Vec<f64> {
        vec![self.m1, self.m2, self.l1, self.l2, self.g]
    }
    fn e(&self, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        for i in 0..4 {
            e[(i, i)] = 1.0;
        }
        e[(4, 4)] = self.m1;
        e[(5, 5)] = self.m1;
        e[(6, 6)] = self.m2;
        e[(7, 7)] = self.m2;
    }
    fn f(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        let [x1, y1, x2, y2, v1, w1, v2, w2, l1, l2] =
            [y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7], y[8], y[9]];
        let (dx, dy) = (x2 - x1, y2 - y1);
        let mut g = [0.0; 6];
        self.eval(y, &mut g, None);
        f.copy_from_slice(&[
            v1,
            w1,
            v2,
            w2,
            -2.0 * x1 * l1 + 2.0 * dx * l2,
            -2.0 * y1 * l1 + 2.0 * dy * l2 - self.m1 * self.g,
            -2.0 * dx * l2,
            -2.0 * dy * l2 - self.m2 * self.g,
            g[4],
            g[5],
        ]);
    }
    fn fy(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let [x1, y1, x2, y2, l1, l2] = [y[0], y[1], y[2], y[3], y[8], y[9]];
        let (dx, dy) = (x2 - x1, y2 - y1);
        j.fill(0.0);
        for i in 0..4 {
            j[(i, i + 4)] = 1.0;
        }
        // m1 v1' = -2 x1 l1 + 2 dx l2
        j[(4, 0)] = -2.0 * l1 - 2.0 * l2;
        j[(4, 2)] = 2.0 * l2;
        j[(4, 8)] = -2.0 * x1;
        j[(4, 9)] = 2.0 * dx;
        // m1 w1' = -2 y1 l1 + 2 dy l2 - m1 g
        j[(5, 1)] = -2.0 * l1 - 2.0 * l2;
        j[(5, 3)] = 2.0 * l2;
        j[(5, 8)] = -2.0 * y1;
        j[(5, 9)] = 2.0 * dy;
        // m2 v2' = -2 dx l2
        j[(6, 0)] = 2.0 * l2;
        j[(6, 2)] = -2.0 * l2;
        j[(6, 9)] = -2.0 * dx;
        // m2 w2' = -2 dy l2 - m2 g
        j[(7, 1)] = 2.0 * l2;
        j[(7, 3)] = -2.0 * l2;
        j[(7, 9)] = -2.0 * dy;
        let mut g = [0.0; 6];
        let mut cj = DMatrix::zeros(6, 10);
        self.eval(y, &mut g, Some(&mut cj));
        for c in 0..10 {
            j[(8, c)] = cj[(4, c)];
            j[(9, c)] = cj[(5, c)];
        }
    }
    fn chain(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        self.eval(y, g, None)
    }
    fn chain_y(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let mut g = [0.0; 6];
        self.eval(y, &mut g, Some(j))
    }
    fn inv(&self, _t: f64, y: &[f64], out: &mut [f64]) {
        out[0] = 0.5 * self.m1 * (y[4] * y[4] + y[5] * y[5])
            + 0.5 * self.m2 * (y[6] * y[6] + y[7] * y[7])
            + self.g * (self.m1 * y[1] + self.m2 * y[3]);
    }
}

// ---------------------------------------------------------------------------
// The IDeC test problem (seed 002, §5): a general index-2 DAE.

/// `y1' = y2, y2' = y4 − y2 y6, y3' = −y5 y1, y4' = −y5 y2,
/// 0 = 1 − y1² − y2², 0 = y1 y3 + y2 y4`, exact solution
/// `(sin t, cos t, −cos t, sin t, −1, 2 tan t)`. Chain order:
/// c0 (level 0, source 0), c1 (level 0, source 1), c0' , c1' (level 1).
pub struct Idec {
    info: FormulationInfo,
}

pub const IDEC_C0: &str = "1 - y1^2 - y2^2";
pub const IDEC_C1: &str = "y1*y3 + y2*y4";
pub const IDEC_C0D: &str = "-2*y1*y2 - 2*y2*y4 + 2*y2^2*y6";
pub const IDEC_C1D: &str = "y2*y3 - y5*(y1^2 + y2^2) + y4^2 - y2*y4*y6";

impl Idec {
    pub fn new() -> Self {
        let d = VarKind::Differential;
        let a = VarKind::Algebraic;
        let info = FormulationInfo {
            model: "Idec".to_string(),
            name: "ori1".to_string(),
            variables: vec![
                var("y1", d, 1),
                var("y2", d, 1),
                var("y3", d, 1),
                var("y4", d, 1),
                var("y5", a, 2),
                var("y6", a, 2),
            ],
            rows: vec![
                diff_row("der(y1) = y2"),
                diff_row("der(y2) = y4 - y2*y6"),
                diff_row("der(y3) = -y5*y1"),
                diff_row("der(y4) = -y5*y2"),
                con_row(0, 0, IDEC_C0),
                con_row(0, 1, IDEC_C1),
            ],
            d_index: Some(2),
            s_index: 1,
            c_level: 1,
            constant_leading: true,
            constraints: vec![
                member(0, 0, IDEC_C0),
                member(0, 1, IDEC_C1),
                member(1, 0, IDEC_C0D),
                member(1, 1, IDEC_C1D),
            ],
            invariants: vec![],
            parameters: vec![],
        };
        Idec { info }
    }

    /// The exact solution at `t`.
    pub fn exact(t: f64) -> Vec<f64> {
        vec![t.sin(), t.cos(), -t.cos(), t.sin(), -1.0, 2.0 * t.tan()]
    }
}

impl Default for Idec {
    fn default() -> Self {
        Self::new()
    }
}

impl Hand for Idec {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn params(&self) -> Vec<f64> {
        vec![]
    }
    fn e(&self, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        for i in 0..4 {
            e[(i, i)] = 1.0;
        }
    }
    fn f(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        let mut g = [0.0; 4];
        self.chain(0.0, y, &mut g);
        f.copy_from_slice(&[
            y[1],
            y[3] - y[1] * y[5],
            -y[4] * y[0],
            -y[4] * y[1],
            g[0],
            g[1],
        ]);
    }
    fn fy(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        j[(0, 1)] = 1.0;
        j[(1, 1)] = -y[5];
        j[(1, 3)] = 1.0;
        j[(1, 5)] = -y[1];
        j[(2, 0)] = -y[4];
        j[(2, 4)] = -y[0];
        j[(3, 1)] = -y[4];
        j[(3, 4)] = -y[1];
        let mut cj = DMatrix::zeros(4, 6);
        self.chain_y(0.0, y, &mut cj);
        for c in 0..6 {
            j[(4, c)] = cj[(0, c)];
            j[(5, c)] = cj[(1, c)];
        }
    }
    fn chain(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        let [y1, y2, y3, y4, y5, y6] = [y[0], y[1], y[2], y[3], y[4], y[5]];
        g[0] = 1.0 - y1 * y1 - y2 * y2;
        g[1] = y1 * y3 + y2 * y4;
        g[2] = -2.0 * y1 * y2 - 2.0 * y2 * y4 + 2.0 * y2 * y2 * y6;
        g[3] = y2 * y3 - y5 * (y1 * y1 + y2 * y2) + y4 * y4 - y2 * y4 * y6;
    }
    fn chain_y(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let [y1, y2, y3, y4, y5, y6] = [y[0], y[1], y[2], y[3], y[4], y[5]];
        let rows: [[f64; 6]; 4] = [
            [-2.0 * y1, -2.0 * y2, 0.0, 0.0, 0.0, 0.0],
            [y3, y4, y1, y2, 0.0, 0.0],
            [
                -2.0 * y2,
                -2.0 * y1 - 2.0 * y4 + 4.0 * y2 * y6,
                0.0,
                -2.0 * y2,
                0.0,
                2.0 * y2 * y2,
            ],
            [
                -2.0 * y1 * y5,
                y3 - 2.0 * y2 * y5 - y4 * y6,
                y2,
                2.0 * y4 - y2 * y6,
                -(y1 * y1 + y2 * y2),
                -y2 * y4,
            ],
        ];
        for (r, row) in rows.iter().enumerate() {
            for (c, value) in row.iter().enumerate() {
                j[(r, c)] = *value;
            }
        }
    }
}

// ---------------------------------------------------------------------------
// A chain whose level-1 member introduces no new unknown.

/// Unknowns `x, y` (differential), `x' = 0, y' = 0`; chain
/// `x + y − 1` (level 0) and `x − y` (declared level 1, same source): the
/// level-1 member cannot be satisfied by "new" unknowns, so the projection
/// falls back to a joint least-change correction.
pub struct Toy {
    info: FormulationInfo,
}

impl Toy {
    pub fn new() -> Self {
        let d = VarKind::Differential;
        Toy {
            info: FormulationInfo {
                model: "Toy".to_string(),
                name: "ode".to_string(),
                variables: vec![var("x", d, 1), var("y", d, 1)],
                rows: vec![diff_row("der(x) = 0"), diff_row("der(y) = 0")],
                d_index: Some(0),
                s_index: 0,
                c_level: 0,
                constant_leading: true,
                constraints: vec![member(0, 0, "x + y - 1"), member(1, 0, "x - y")],
                invariants: vec![],
                parameters: vec![],
            },
        }
    }
}

impl Toy {
    /// `x' = 0, y' = 0, 0 = z` with an empty constraint chain: nothing to
    /// check, and `z` appears in no constraint.
    pub fn unconstrained() -> Self {
        let d = VarKind::Differential;
        Toy {
            info: FormulationInfo {
                model: "Toy".to_string(),
                name: "free".to_string(),
                variables: vec![
                    var("x", d, 1),
                    var("y", d, 1),
                    var("z", VarKind::Algebraic, 1),
                ],
                rows: vec![
                    diff_row("der(x) = 0"),
                    diff_row("der(y) = 0"),
                    con_row(0, 0, "z"),
                ],
                d_index: Some(1),
                s_index: 0,
                c_level: 0,
                constant_leading: true,
                constraints: vec![],
                invariants: vec![],
                parameters: vec![],
            },
        }
    }
}

impl Default for Toy {
    fn default() -> Self {
        Self::new()
    }
}

impl Hand for Toy {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn params(&self) -> Vec<f64> {
        vec![]
    }
    fn e(&self, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        e[(0, 0)] = 1.0;
        e[(1, 1)] = 1.0;
    }
    fn f(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f.fill(0.0);
        if f.len() == 3 {
            f[2] = y[2];
        }
    }
    fn fy(&self, _t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        if j.nrows() == 3 {
            j[(2, 2)] = 1.0;
        }
    }
    fn chain(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        if g.len() == 2 {
            g[0] = y[0] + y[1] - 1.0;
            g[1] = y[0] - y[1];
        }
    }
    fn chain_y(&self, _t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        if j.nrows() == 2 {
            j.copy_from_slice(&[1.0, 1.0, 1.0, -1.0]);
        }
    }
}

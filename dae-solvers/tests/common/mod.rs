//! Hand-written test models, shared by `tests/radau5.rs`, `tests/bdf.rs`,
//! `tests/od.rs`, `tests/init.rs` and the S02 examples (included there with
//! `#[path]`, hence the `dead_code` allowance):
//!
//! * the paper's pendulum in seven formulations ([`Pendulum`], [`Form`]) and
//!   in `ovd0` ([`PendulumOvd0`]), its exact solution and the reference
//!   files shipped in the repository's `data/`;
//! * the planar double pendulum ([`DoublePendulum`]), the index-2 test
//!   problem of the IDeC paper ([`Idec`]) and two toy chains ([`Toy`]),
//!   written as [`Hand`] formulations;
//! * small DAEs with closed-form solutions for convergence-order studies,
//!   and pathological systems that provoke each
//!   [`dae_solvers::SolveError`] ([`Simple`]).
//!
//! Everything is written out by hand — independent of dae-core's symbolic
//! engine and of the `dae!` macro — Jacobians included; `tests/init.rs`
//! checks them against finite differences.
#![allow(dead_code)]

use dae_core::system::{
    ConstraintInfo, DaeSystem, FormulationInfo, RowInfo, RowKind, VarInfo, VarKind,
};
use dae_solvers::options::Estimate;
use dae_solvers::{Options, Problem, Solution, SolveError, Solver};
use nalgebra::DMatrix;
use std::f64::consts::PI;

/// Integrate `sys` with `solver` from `y0` at `t = 0` to `t_end`.
pub fn solve_with(
    solver: &dyn Solver,
    sys: &dyn DaeSystem,
    y0: &[f64],
    t_end: f64,
    options: &Options,
) -> Result<Solution, SolveError> {
    solver.solve(
        &Problem {
            system: sys,
            t0: 0.0,
            y0,
            t_end,
        },
        options,
    )
}

/// The exact pendulum state at the end of S01, `t = 20` (the last row of
/// `pendulum_s01_exact.csv`).
pub fn s01_exact_at_20() -> [f64; 5] {
    let exact = reference("pendulum_s01_exact.csv");
    let (t, values) = *exact.last().expect("reference rows");
    assert_eq!(t, 20.0);
    values
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

fn constraint_row(level: u8, source: u16, text: &str) -> RowInfo {
    RowInfo {
        kind: RowKind::Constraint { level, source },
        text: text.into(),
    }
}

fn member(level: u8, source: u16, expr: &str) -> ConstraintInfo {
    ConstraintInfo {
        level,
        source,
        expr: expr.into(),
    }
}

// ---------------------------------------------------------------------------
// The pendulum (SPEC §1–§3)
// ---------------------------------------------------------------------------

/// The paper's gravity constant (SPEC §3): the period is 1.99999999990628 s.
pub const G: f64 = 13.750_371_637_329_454;

/// The formulations of the pendulum written by hand.
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
    /// Overdetermined: the model and the velocity constraint, 6 equations
    /// for 5 unknowns.
    Ovd1,
}

impl Form {
    /// The six square formulations, in the paper's order.
    pub const SQUARE: [Form; 6] = [
        Form::Ori2,
        Form::Rcd1,
        Form::Rcd0,
        Form::Ggl1,
        Form::Psi1,
        Form::Psi0,
    ];

    /// The square formulations of index at most two (all but `ori2`), in
    /// the paper's order: those BDF integrates.
    pub const INDEX_AT_MOST_2: [Form; 5] =
        [Form::Rcd1, Form::Rcd0, Form::Ggl1, Form::Psi1, Form::Psi0];

    /// The paper's name.
    pub fn name(self) -> &'static str {
        match self {
            Form::Ori2 => "ori2",
            Form::Rcd1 => "rcd1",
            Form::Rcd0 => "rcd0",
            Form::Ggl1 => "ggl1",
            Form::Psi1 => "psi1",
            Form::Psi0 => "psi0",
            Form::Ovd1 => "ovd1",
        }
    }

    /// Whether the formulation has unknowns of index two or more (BDF runs
    /// it with them out of the error test).
    pub fn has_index2(self) -> bool {
        !matches!(self, Form::Rcd0 | Form::Psi0)
    }
}

/// Level-0 member of the pendulum's constraint chain.
pub const PENDULUM_L0: &str = "x^2 + y^2 - L^2";
/// Level 1.
pub const PENDULUM_L1: &str = "2*x*v + 2*y*w";
/// Level 2.
pub const PENDULUM_L2: &str = "2*v^2 + 2*w^2 - 2*y*g - 4/m*(x^2 + y^2)*lambda";

/// The pendulum `x' = v, y' = w, m v' = −2xλ, m w' = −2yλ − mg,
/// 0 = x² + y² − L²` in one of its formulations, unknowns
/// `(x, y, v, w, λ)` (plus `η` for `ggl1`).
pub struct Pendulum {
    pub form: Form,
    pub m: f64,
    pub l: f64,
    pub g: f64,
    info: FormulationInfo,
}

impl Pendulum {
    /// Position of λ among the unknowns.
    pub const LAMBDA: usize = 4;

    /// The paper's pendulum: `m = 1`, `L = 1`, `g = 13.75…`.
    pub fn new(form: Form) -> Self {
        Pendulum::with_parameters(form, 1.0, 1.0, G)
    }

    /// Any parameters.
    pub fn with_parameters(form: Form, m: f64, l: f64, g: f64) -> Self {
        use VarKind::{Algebraic as A, Differential as D};
        let (i_vw, i_lambda) = match form {
            Form::Ori2 => (2, 3),
            Form::Rcd1 | Form::Ggl1 | Form::Psi1 | Form::Ovd1 => (1, 2),
            Form::Rcd0 | Form::Psi0 => (1, 1),
        };
        let mut variables = vec![
            var("x", D, 1),
            var("y", D, 1),
            var("v", D, i_vw),
            var("w", D, i_vw),
            var("lambda", A, i_lambda),
        ];
        let [pos, vel, acc] =
            [PENDULUM_L0, PENDULUM_L1, PENDULUM_L2].map(|expr| format!("0 = {expr}"));
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
                r.push(constraint_row(0, 0, &pos));
                (r, Some(3), 2, 2)
            }
            Form::Rcd1 => {
                let mut r = dyn4();
                r.push(constraint_row(1, 0, &vel));
                (r, Some(2), 1, 1)
            }
            Form::Rcd0 => {
                let mut r = dyn4();
                r.push(constraint_row(2, 0, &acc));
                (r, Some(1), 0, 0)
            }
            Form::Ggl1 => {
                variables.push(var("eta", A, 2));
                let r = vec![
                    diff_row("der(x) = v - 2*x*eta"),
                    diff_row("der(y) = w - 2*y*eta"),
                    diff_row("m*der(v) = -2*x*lambda"),
                    diff_row("m*der(w) = -2*y*lambda - m*g"),
                    constraint_row(0, 0, &pos),
                    constraint_row(1, 0, &vel),
                ];
                (r, Some(2), 1, 1)
            }
            Form::Psi1 => {
                let r = vec![
                    diff_row("y*der(x) - x*der(y) = y*v - x*w"),
                    diff_row("m*der(v) = -2*x*lambda"),
                    diff_row("m*der(w) = -2*y*lambda - m*g"),
                    constraint_row(0, 0, &pos),
                    constraint_row(1, 0, &vel),
                ];
                (r, Some(2), 1, 1)
            }
            Form::Psi0 => {
                let r = vec![
                    diff_row("y*der(x) - x*der(y) = y*v - x*w"),
                    diff_row("m*(y*der(v) - x*der(w)) = y*(-2*x*lambda) - x*(-2*y*lambda - m*g)"),
                    constraint_row(0, 0, &pos),
                    constraint_row(1, 0, &vel),
                    constraint_row(2, 0, &acc),
                ];
                (r, Some(1), 0, 0)
            }
            Form::Ovd1 => {
                let mut r = dyn4();
                r.push(constraint_row(0, 0, &pos));
                r.push(constraint_row(1, 0, &vel));
                (r, None, 1, 1)
            }
        };
        let info = FormulationInfo {
            model: "Pendulum".into(),
            name: form.name().into(),
            variables,
            rows,
            d_index,
            s_index,
            c_level,
            constant_leading: !matches!(form, Form::Psi1 | Form::Psi0),
            constant_differential_leading: !matches!(form, Form::Psi1 | Form::Psi0),
            constraints: vec![
                member(0, 0, PENDULUM_L0),
                member(1, 0, PENDULUM_L1),
                member(2, 0, PENDULUM_L2),
            ],
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
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 | Form::Ovd1 => {
                f[0] = v;
                f[1] = w;
                f[2] = -2.0 * x * lam;
                f[3] = -2.0 * y * lam - m * g;
                match self.form {
                    Form::Ori2 => f[4] = pos,
                    Form::Rcd1 => f[4] = vel,
                    Form::Rcd0 => f[4] = self.acc(x, y, v, w, lam),
                    _ => {
                        f[4] = pos;
                        f[5] = vel;
                    }
                }
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
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 | Form::Ggl1 | Form::Ovd1 => {
                [up[0], up[1], m * up[2], m * up[3]]
            }
            Form::Psi1 => [y * up[0] - x * up[1], m * up[2], m * up[3], 0.0],
            Form::Psi0 => [y * up[0] - x * up[1], m * (y * up[2] - x * up[3]), 0.0, 0.0],
        };
        for (i, ri) in r.iter_mut().enumerate() {
            *ri = ey.get(i).copied().unwrap_or(0.0) - *ri;
        }
    }

    fn leading(&self, _t: f64, u: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        let m = self.m;
        match self.form {
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 | Form::Ggl1 | Form::Ovd1 => {
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
            Form::Ori2 | Form::Rcd1 | Form::Rcd0 | Form::Ovd1 => {
                j[(0, 2)] = 1.0;
                j[(1, 3)] = 1.0;
                j[(2, 0)] = -2.0 * lam;
                j[(2, 4)] = -2.0 * x;
                j[(3, 1)] = -2.0 * lam;
                j[(3, 4)] = -2.0 * y;
                match self.form {
                    Form::Ori2 => set_row(j, 4, &pos),
                    Form::Rcd1 => set_row(j, 4, &vel),
                    Form::Rcd0 => set_row(j, 4, &acc),
                    _ => {
                        set_row(j, 4, &pos);
                        set_row(j, 5, &vel);
                    }
                }
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
                // y(−2xλ) − x(−2yλ − mg), differentiated as written: the λ
                // terms cancel.
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

    fn leading_jacobian(&self, _t: f64, _u: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
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

/// The exact multiplier on the circle: `λ = m(v² + w² − g y)/(2L²)`.
pub fn pendulum_lambda(p: &Pendulum, y: &[f64]) -> f64 {
    p.m * (y[2] * y[2] + y[3] * y[3] - p.g * y[1]) / (2.0 * p.l * p.l)
}

// ---------------------------------------------------------------------------
// The pendulum's ovd0 (dynamics and all three constraint levels)
// ---------------------------------------------------------------------------

/// The pendulum in `ovd0` form: the four dynamic rows together with the
/// position, velocity and acceleration constraints, 7 equations for the 5
/// unknowns `(x, y, v, w, λ)` — constraint level 0, every unknown of index
/// one, as dae-core derives it (`d_index` none, `s_index` one).
///
/// A type of its own rather than a [`Form`] variant: the files that match on
/// [`Form`] exhaustively (`tests/radau5.rs`, `tests/harness.rs`,
/// `examples/radau5_s02.rs`) then compile unchanged. Constraints,
/// invariants and the helpers for the acceleration level are those of the
/// inner [`Pendulum`].
pub struct PendulumOvd0 {
    /// The same pendulum (its `rcd0` form), for parameters and the chain.
    pub p: Pendulum,
    info: FormulationInfo,
}

impl PendulumOvd0 {
    /// Rows of the position, velocity and acceleration constraints.
    pub const POS_ROW: usize = 4;
    pub const VEL_ROW: usize = 5;
    pub const ACC_ROW: usize = 6;

    /// The paper's pendulum: `m = 1`, `L = 1`, `g = 13.75…`.
    pub fn new() -> Self {
        PendulumOvd0::with_parameters(1.0, 1.0, G)
    }

    /// Any parameters.
    pub fn with_parameters(m: f64, l: f64, g: f64) -> Self {
        let p = Pendulum::with_parameters(Form::Rcd0, m, l, g);
        let mut info = p.info.clone();
        info.name = "ovd0".into();
        info.rows.truncate(4);
        for (level, expr) in [PENDULUM_L0, PENDULUM_L1, PENDULUM_L2].iter().enumerate() {
            info.rows
                .push(constraint_row(level as u8, 0, &format!("0 = {expr}")));
        }
        info.d_index = None;
        info.s_index = 1;
        info.c_level = 0;
        PendulumOvd0 { p, info }
    }

    /// The consistent start `x = L, y = v = w = λ = 0`.
    pub fn y0(&self) -> Vec<f64> {
        self.p.y0()
    }
}

impl Default for PendulumOvd0 {
    fn default() -> Self {
        Self::new()
    }
}

impl DaeSystem for PendulumOvd0 {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }

    fn parameter_values(&self) -> Vec<f64> {
        self.p.parameter_values()
    }

    fn rhs(&self, _t: f64, u: &[f64], f: &mut [f64]) {
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        let p = &self.p;
        f[0] = v;
        f[1] = w;
        f[2] = -2.0 * x * lam;
        f[3] = -2.0 * y * lam - p.m * p.g;
        f[4] = x * x + y * y - p.l * p.l;
        f[5] = 2.0 * x * v + 2.0 * y * w;
        f[6] = p.acc(x, y, v, w, lam);
    }

    fn residual(&self, t: f64, u: &[f64], up: &[f64], r: &mut [f64]) {
        self.rhs(t, u, r);
        let m = self.p.m;
        let ey = [up[0], up[1], m * up[2], m * up[3]];
        for (i, ri) in r.iter_mut().enumerate() {
            *ri = ey.get(i).copied().unwrap_or(0.0) - *ri;
        }
    }

    fn leading(&self, _t: f64, _u: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        e[(0, 0)] = 1.0;
        e[(1, 1)] = 1.0;
        e[(2, 2)] = self.p.m;
        e[(3, 3)] = self.p.m;
    }

    fn rhs_jacobian(&self, _t: f64, u: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        let (x, y, v, w, lam) = (u[0], u[1], u[2], u[3], u[4]);
        j[(0, 2)] = 1.0;
        j[(1, 3)] = 1.0;
        j[(2, 0)] = -2.0 * lam;
        j[(2, 4)] = -2.0 * x;
        j[(3, 1)] = -2.0 * lam;
        j[(3, 4)] = -2.0 * y;
        let rows = [
            [2.0 * x, 2.0 * y, 0.0, 0.0, 0.0],
            [2.0 * v, 2.0 * w, 2.0 * x, 2.0 * y, 0.0],
            self.p.acc_gradient(x, y, v, w, lam),
        ];
        for (r, row) in rows.iter().enumerate() {
            for (c, &val) in row.iter().enumerate() {
                j[(Self::POS_ROW + r, c)] = val;
            }
        }
    }

    fn leading_jacobian(&self, _t: f64, _u: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }

    fn constraints(&self, t: f64, u: &[f64], g: &mut [f64]) {
        self.p.constraints(t, u, g)
    }

    fn constraints_jacobian(&self, t: f64, u: &[f64], j: &mut DMatrix<f64>) {
        self.p.constraints_jacobian(t, u, j)
    }

    fn invariants(&self, t: f64, u: &[f64], out: &mut [f64]) {
        self.p.invariants(t, u, out)
    }
}

// ---------------------------------------------------------------------------
// The exact pendulum solution and the reference files (SPEC §3)
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
    pendulum_exact_at(t, 1.0, 1.0, G, 0.5 * PI)
}

/// Rows `(t, x, y, v, w, λ)` of `data/pendulum_s01_exact.csv`
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

/// The path of a reference file shipped in the repository's `data/`
/// (`data/README.md` says where each comes from). Only files inside the
/// repository: a fresh clone with nothing beside it passes its tests.
pub fn reference_path(file: &str) -> String {
    format!("{}/../data/{file}", env!("CARGO_MANIFEST_DIR"))
}

/// Exact pendulum values `(t, [x, y, v, w, λ])` from a reference file in
/// the repository's `data/`.
pub fn reference(file: &str) -> Vec<(f64, [f64; 5])> {
    let path = reference_path(file);
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

/// `Σ_i |u_i − exact_i|` over x, y, v, w, λ (the paper's `ERR` at one
/// check time, SPEC §3).
pub fn err_sum(u: &[f64], exact: &[f64; 5]) -> f64 {
    (0..5).map(|i| (u[i] - exact[i]).abs()).sum()
}

/// `max(|x−x*|, |y−y*|, |v−v*|, |w−w*|)`.
pub fn err_max(u: &[f64], exact: &[f64; 5]) -> f64 {
    (0..4).map(|i| (u[i] - exact[i]).abs()).fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------
// Small systems with closed-form solutions and pathological systems
// ---------------------------------------------------------------------------

type RhsFn = fn(f64, &[f64], &mut [f64]);
type JacFn = fn(f64, &[f64], &mut DMatrix<f64>);

/// A system `E y' = f(t, y)` with constant diagonal `E`, given by plain
/// functions (`∂f/∂y` written into a zeroed matrix); no constraint chain.
pub struct Simple {
    info: FormulationInfo,
    e_diag: Vec<f64>,
    f: RhsFn,
    jac: JacFn,
}

impl Simple {
    /// Unknowns `vars` (name, index), differential where `e_diag` is
    /// nonzero.
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
                    constraint_row(0, 0, &format!("row {i}"))
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
                constant_differential_leading: true,
                constraints: Vec::new(),
                invariants: Vec::new(),
                parameters: Vec::new(),
            },
            e_diag: e_diag.to_vec(),
            f,
            jac,
        }
    }

    /// [`blow_up`], reported as having one equation too many (for the
    /// overdetermined-input checks; never integrated).
    pub fn overdetermined() -> Self {
        let mut s = blow_up();
        s.info.rows.push(constraint_row(0, 0, "extra"));
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
    fn leading(&self, _t: f64, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        for (i, &d) in self.e_diag.iter().enumerate() {
            e[(i, i)] = d;
        }
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        (self.jac)(t, y, j)
    }
    fn leading_jacobian(&self, _t: f64, _y: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }
    fn constraints(&self, _t: f64, _y: &[f64], _g: &mut [f64]) {}
    fn constraints_jacobian(&self, _t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    fn invariants(&self, _t: f64, _y: &[f64], _out: &mut [f64]) {}
}

/// ODE `y0' = y1, y1' = −y0, y2' = −2t y2²`: `(sin t, cos t, 1/(1+t²))`.
pub fn ode() -> Simple {
    fn f(t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[1];
        f[1] = -y[0];
        f[2] = -2.0 * t * y[2] * y[2];
    }
    fn jac(t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -1.0;
        j[(2, 2)] = -4.0 * t * y[2];
    }
    Simple::new(
        "ode",
        &[("y0", 1), ("y1", 1), ("y2", 1)],
        &[1.0, 1.0, 1.0],
        f,
        jac,
    )
}

/// Exact solution of [`ode`].
pub fn ode_exact(t: f64) -> Vec<f64> {
    vec![t.sin(), t.cos(), 1.0 / (1.0 + t * t)]
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

/// The circle `y0' = −y1, y1' = y0` with the algebraic `z` its radius
/// defect amplified a hundredfold, `0 = 100 (y0² + y1² − 1) − z`:
/// `(cos t, sin t, 0)`. `z` is constant along the exact solution, so a
/// multistep estimate by differences of `z` sees nothing of the radial
/// error of `(y0, y1)` that the constraint carries into it.
pub fn amplified_circle() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -y[1];
        f[1] = y[0];
        f[2] = 100.0 * (y[0] * y[0] + y[1] * y[1] - 1.0) - y[2];
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 1)] = -1.0;
        j[(1, 0)] = 1.0;
        j[(2, 0)] = 200.0 * y[0];
        j[(2, 1)] = 200.0 * y[1];
        j[(2, 2)] = -1.0;
    }
    Simple::new(
        "amplified_circle",
        &[("y0", 1), ("y1", 1), ("z", 1)],
        &[1.0, 1.0, 0.0],
        f,
        jac,
    )
}

/// `solver` on [`amplified_circle`] over `t ∈ [0, 10]`: with the default
/// checked estimate `|z(10)|` within 200 tolerances in fewer than 2 000
/// steps at tol 1e-5, 1e-7, 1e-9, and at 1e-5 the method's own estimate
/// ([`Estimate::Dassl`]) a thousand times further off in ten times the
/// steps.
pub fn assert_checked_estimate_sees_amplified_circle(solver: &dyn Solver) {
    let sys = amplified_circle();
    let run_with = |tol, estimate| {
        let options = Options {
            estimate,
            ..Options::with_tol(tol)
        };
        let sol = solve_with(solver, &sys, &[1.0, 0.0, 0.0], 10.0, &options).expect("run");
        let switched = sol.stats.propagated_from.is_some();
        assert_eq!(switched, estimate == Estimate::Checked, "{estimate:?}");
        (sol.last().expect("output")[2].abs(), sol.stats.steps)
    };
    for tol in [1e-5, 1e-7, 1e-9] {
        let (z, steps) = run_with(tol, Estimate::Checked);
        assert!(
            z < 200.0 * tol && steps < 2000,
            "{tol:e}: |z| {z:e}, {steps} steps"
        );
    }
    let (z_own, steps_own) = run_with(1e-5, Estimate::Dassl);
    let (z, steps) = run_with(1e-5, Estimate::Checked);
    assert!(
        z_own > 1e3 * z && steps_own > 10 * steps,
        "the method's own estimate: |z| {z_own:e} in {steps_own} steps"
    );
}

/// Semi-explicit index-1 DAE `y0' = z, y1' = y0 z, 0 = y0² + z² − 1`:
/// `(sin t, sin²t / 2, cos t)` for `t < π/2`.
pub fn dae1() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[2];
        f[1] = y[0] * y[2];
        f[2] = y[0] * y[0] + y[2] * y[2] - 1.0;
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 2)] = 1.0;
        j[(1, 0)] = y[2];
        j[(1, 2)] = y[0];
        j[(2, 0)] = 2.0 * y[0];
        j[(2, 2)] = 2.0 * y[2];
    }
    Simple::new(
        "dae1",
        &[("y0", 1), ("y1", 1), ("z2", 1)],
        &[1.0, 1.0, 0.0],
        f,
        jac,
    )
}

/// Exact solution of [`dae1`].
pub fn dae1_exact(t: f64) -> Vec<f64> {
    vec![t.sin(), 0.5 * t.sin() * t.sin(), t.cos()]
}

/// `y' = y²`, `y(0) = 1`: blows up at `t = 1`.
pub fn blow_up() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[0] * y[0];
    }
    fn jac(_t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = 2.0 * y[0];
    }
    Simple::new("blow_up", &[("y", 1)], &[1.0], f, jac)
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
pub fn zero_equals_one() -> Simple {
    fn f(_t: f64, _y: &[f64], f: &mut [f64]) {
        f[0] = 1.0;
    }
    fn jac(_t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    Simple::new("zero_equals_one", &[("y", 1)], &[0.0], f, jac)
}

/// `y0' = −y0, 0 = 0`: the second unknown appears nowhere, so every
/// iteration matrix has a zero column.
pub fn structurally_singular() -> Simple {
    fn f(_t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -y[0];
        f[1] = 0.0;
    }
    fn jac(_t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = -1.0;
    }
    Simple::new("singular", &[("y0", 1), ("z1", 1)], &[1.0, 0.0], f, jac)
}

/// `y' = f` with `f` NaN everywhere.
pub fn nan_rhs() -> Simple {
    fn f(_t: f64, _y: &[f64], f: &mut [f64]) {
        f[0] = f64::NAN;
    }
    fn jac(_t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    Simple::new("nan_rhs", &[("y", 1)], &[1.0], f, jac)
}

/// `y' = −y` for `t ≤ 0.5`, NaN beyond.
pub fn nan_beyond_half() -> Simple {
    fn f(t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = if t <= 0.5 { -y[0] } else { f64::NAN };
    }
    fn jac(_t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        j[(0, 0)] = -1.0;
    }
    Simple::new("nan_beyond_half", &[("y", 1)], &[1.0], f, jac)
}

// ---------------------------------------------------------------------------
// Formulations given by E(y) and f(t, y)
// ---------------------------------------------------------------------------

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
    fn leading(&self, _t: f64, y: &[f64], e: &mut DMatrix<f64>) {
        self.0.e(y, e)
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.0.fy(t, y, j)
    }
    fn leading_jacobian(&self, _t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
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

// ---------------------------------------------------------------------------
// The planar double pendulum
// ---------------------------------------------------------------------------

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
            constraint_row(2, 0, DP_A2),
            constraint_row(2, 1, DP_B2),
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
            constant_differential_leading: true,
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
// The IDeC test problem (seed 002, §5): a general index-2 DAE
// ---------------------------------------------------------------------------

/// Semi-explicit index 2 (SPEC §4):
///
/// ```text
///     y1' = y2,  y2' = y4 − y2 y6,  y3' = −y5 y1,  y4' = −y5 y2,
///     0 = 1 − y1² − y2²,  0 = y1 y3 + y2 y4,
/// ```
///
/// exact solution `(sin t, cos t, −cos t, sin t, −1, 2 tan t)`; `y5`, `y6`
/// have index 2. Chain order: c0 (level 0, source 0), c1 (level 0,
/// source 1), c0', c1' (level 1).
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
                constraint_row(0, 0, IDEC_C0),
                constraint_row(0, 1, IDEC_C1),
            ],
            d_index: Some(2),
            s_index: 1,
            c_level: 1,
            constant_leading: true,
            constant_differential_leading: true,
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
// A chain whose level-1 member introduces no new unknown
// ---------------------------------------------------------------------------

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
                constant_differential_leading: true,
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
                    constraint_row(0, 0, "z"),
                ],
                d_index: Some(1),
                s_index: 0,
                c_level: 0,
                constant_leading: true,
                constant_differential_leading: true,
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

/// Central differences of `eval` (`n_out` outputs) at `y`: the Jacobian
/// the hand-written systems are checked against.
pub fn fd_matrix(
    n_out: usize,
    y: &[f64],
    mut eval: impl FnMut(&[f64], &mut [f64]),
) -> DMatrix<f64> {
    let n = y.len();
    let mut j = DMatrix::zeros(n_out, n);
    let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
    let (mut fp, mut fm) = (vec![0.0; n_out], vec![0.0; n_out]);
    for c in 0..n {
        let h = 1e-6 * (1.0 + y[c].abs());
        yp[c] = y[c] + h;
        ym[c] = y[c] - h;
        eval(&yp, &mut fp);
        eval(&ym, &mut fm);
        for r in 0..n_out {
            j[(r, c)] = (fp[r] - fm[r]) / (2.0 * h);
        }
        yp[c] = y[c];
        ym[c] = y[c];
    }
    j
}

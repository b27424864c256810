//! A leading matrix that depends on time: `E(t) y' = f(t, y)`.
//!
//! The system (index 1, written by hand, Jacobians included):
//!
//! ```text
//!     (1 + t) y1' = −y1 + y2 + (1 + t) cos t
//!               0 = −y2 − t y1
//! ```
//!
//! The algebraic row gives `y2 = −t y1`, so the first row is
//! `(1 + t) (y1' + y1 − cos t) = 0`: `y1' = −y1 + cos t`, and from
//! `y1(0) = 1` the closed form `y1 = (cos t + sin t + e^{−t}) / 2`,
//! `y2 = −t y1`. A solver that evaluated `E` at a wrong time would solve
//! another equation: with `E` frozen at `t = 0`, `y1' = −(1 + t) y1 + cos t`,
//! whose value at `t = 2` is 0.007 against the exact 0.314.
//!
//! radau5, bdf and gauss integrate it; mebdf and idec need an `E`
//! independent of `t` and `y` and refuse it with the typed reason.

use dae_core::check::check_jacobians;
use dae_core::system::{DaeSystem, FormulationInfo, RowInfo, RowKind, VarInfo, VarKind};
use dae_solvers::{solver_by_name, NotApplicable, Options, Problem, SolveError};
use nalgebra::DMatrix;

/// The system of the module documentation.
struct TimeLeading {
    info: FormulationInfo,
}

impl TimeLeading {
    fn new() -> Self {
        let var = |name: &str, kind| VarInfo {
            name: name.into(),
            kind,
            index: 1,
        };
        TimeLeading {
            info: FormulationInfo {
                model: "time_leading".into(),
                name: "rcd1".into(),
                variables: vec![
                    var("y1", VarKind::Differential),
                    var("y2", VarKind::Algebraic),
                ],
                rows: vec![
                    RowInfo {
                        kind: RowKind::Differential,
                        text: "(1 + t) der(y1) = -y1 + y2 + (1 + t) cos(t)".into(),
                    },
                    RowInfo {
                        kind: RowKind::Constraint {
                            level: 0,
                            source: 0,
                        },
                        text: "0 = -y2 - t y1".into(),
                    },
                ],
                d_index: Some(1),
                s_index: 0,
                c_level: 0,
                // `E` depends on `t`: not constant.
                constant_leading: false,
                constant_differential_leading: false,
                constraints: Vec::new(),
                invariants: Vec::new(),
                parameters: Vec::new(),
            },
        }
    }
}

/// The closed form `(y1, y2)` at `t`.
fn exact(t: f64) -> [f64; 2] {
    let y1 = 0.5 * (t.cos() + t.sin() + (-t).exp());
    [y1, -t * y1]
}

impl DaeSystem for TimeLeading {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        Vec::new()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -y[0] + y[1] + (1.0 + t) * t.cos();
        f[1] = -y[1] - t * y[0];
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        self.rhs(t, y, r);
        r[0] = (1.0 + t) * yp[0] - r[0];
        r[1] = -r[1];
    }
    fn leading(&self, t: f64, _y: &[f64], e: &mut DMatrix<f64>) {
        e.fill(0.0);
        e[(0, 0)] = 1.0 + t;
    }
    fn rhs_jacobian(&self, t: f64, _y: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
        j[(0, 0)] = -1.0;
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -t;
        j[(1, 1)] = -1.0;
    }
    fn leading_jacobian(&self, _t: f64, _y: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        // `E` does not depend on `y`.
        j.fill(0.0);
    }
    fn constraints(&self, _t: f64, _y: &[f64], _g: &mut [f64]) {}
    fn constraints_jacobian(&self, _t: f64, _y: &[f64], _j: &mut DMatrix<f64>) {}
    fn invariants(&self, _t: f64, _y: &[f64], _out: &mut [f64]) {}
}

const T_END: f64 = 2.0;

/// The analytic Jacobians agree with central differences, and the residual
/// is `E(t, y) y' − f(t, y)` at the time of each point (the check draws
/// `t` at random).
#[test]
fn jacobians_and_residual_match_differences() {
    let sys = TimeLeading::new();
    let worst = check_jacobians(&sys, 20, 7, 1e-7).expect("Jacobians agree");
    assert!(worst < 1e-7, "worst relative error {worst:e}");
}

/// `E` at two times differs as written: `1 + t` in the corner.
#[test]
fn leading_matrix_follows_the_time() {
    let sys = TimeLeading::new();
    let (mut e0, mut e1) = (DMatrix::zeros(2, 2), DMatrix::zeros(2, 2));
    sys.leading(0.0, &[1.0, 0.0], &mut e0);
    sys.leading(1.5, &[1.0, 0.0], &mut e1);
    assert_eq!((e0[(0, 0)], e1[(0, 0)]), (1.0, 2.5));
}

/// radau5, bdf and gauss reach `t = 2` with an error at the level of the
/// tolerance. The bound is `100 · tol` on each unknown at `t_end`
/// (mixed absolute/relative, the unknowns are of size ≤ 1): the global
/// error of a tolerance-controlled run is the accumulated local error,
/// typically a few times the tolerance; evaluating `E` at a wrong time
/// gives an error of about 0.3 (see the module documentation) or, at the
/// wrong stage time, of the order of the step.
#[test]
fn radau5_bdf_and_gauss_reach_the_closed_form() {
    let sys = TimeLeading::new();
    let y0 = exact(0.0);
    for tol in [1e-6, 1e-9] {
        for name in ["radau5", "bdf", "gauss"] {
            let solver = solver_by_name(name).expect("a solver of the crate");
            let problem = Problem {
                system: &sys,
                t0: 0.0,
                y0: &y0,
                t_end: T_END,
            };
            let sol = solver
                .solve(&problem, &Options::with_tol(tol))
                .unwrap_or_else(|e| panic!("{name} at {tol:e}: {e}"));
            let y = sol.last().expect("the end point");
            let want = exact(T_END);
            let err = (0..2)
                .map(|k| (y[k] - want[k]).abs() / (1.0 + want[k].abs()))
                .fold(0.0, f64::max);
            println!(
                "{name} tol {tol:e}: error {err:.2e} in {} steps",
                sol.stats.steps
            );
            assert!(err <= 100.0 * tol, "{name} at {tol:e}: error {err:e}");
        }
    }
}

/// mebdf and idec factor one `E` for the whole run: an `E` that depends on
/// `t` is refused with the typed reason, before any step.
#[test]
fn mebdf_and_idec_refuse_a_time_dependent_e() {
    let sys = TimeLeading::new();
    let y0 = exact(0.0);
    for name in ["mebdf", "idec"] {
        let solver = solver_by_name(name).expect("a solver of the crate");
        assert_eq!(
            solver.accepts(sys.info()),
            Err(NotApplicable::LeadingMatrixNotConstant),
            "{name}"
        );
        let problem = Problem {
            system: &sys,
            t0: 0.0,
            y0: &y0,
            t_end: T_END,
        };
        match solver.solve(&problem, &Options::with_tol(1e-6)) {
            Err(SolveError::NotApplicable(NotApplicable::LeadingMatrixNotConstant)) => {}
            other => panic!("{name}: {:?}", other.map(|s| s.stats)),
        }
    }
}

//! The compressed path of the step loops (issue 24): a large system that
//! reports its structure (`DaeSystem::sparsity`) is integrated with `J`
//! and `E` held on its iteration pattern; the same system with its
//! structure hidden takes the dense-evaluation path (the sparse LU on the
//! non-zeros gathered from dense matrices). Both must reach the same
//! solution. The chain of `scripts/chain.py`, 13 links (65 unknowns, above
//! `SPARSE_FROM` = 60).
#![cfg(feature = "sparse")]

use dae_core::interp::{InterpretedModel, InterpretedSystem};
use dae_core::system::{DaeSystem, FormulationInfo};
use dae_solvers::{consistent, InitOptions, Options, Problem};
use nalgebra::DMatrix;

// The chain generator the crate's unit tests use (an integration test
// cannot see `crate::test_models`, so the file is included as a module).
#[path = "../src/test_models.rs"]
mod test_models;
use test_models::chain;

/// A system with its structure hidden: `sparsity` and the `*_values`
/// methods are the trait's dense defaults.
struct Hidden<'a>(&'a dyn DaeSystem);

impl DaeSystem for Hidden<'_> {
    fn info(&self) -> &FormulationInfo {
        self.0.info()
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.0.parameter_values()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        self.0.rhs(t, y, f)
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        self.0.residual(t, y, yp, r)
    }
    fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>) {
        self.0.leading(t, y, e)
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.0.rhs_jacobian(t, y, j)
    }
    fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        self.0.leading_jacobian(t, y, z, j)
    }
    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.0.constraints(t, y, g)
    }
    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.0.constraints_jacobian(t, y, j)
    }
    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.0.invariants(t, y, out)
    }
}

/// Formulation `form` of the 13-link chain and its consistent start (the
/// chain stretched out horizontally at rest).
fn start(model: &InterpretedModel, form: &str) -> (InterpretedSystem, Vec<f64>) {
    let sys = model.system(form).expect("formulation");
    let guess: Vec<f64> = sys
        .info()
        .variables
        .iter()
        .map(|v| match v.name.strip_prefix('x') {
            Some(i) => i.parse().expect("x<i>"),
            None => 0.0,
        })
        .collect();
    let y0 = consistent(&sys, 0.0, &guess, &InitOptions::default())
        .expect("consistent start")
        .y;
    (sys, y0)
}

#[test]
fn compressed_and_dense_evaluation_reach_the_same_solution() {
    let model = InterpretedModel::from_str(&chain(13)).expect("the chain derives");
    for (solver, form) in [("radau5", "ggl1"), ("bdf", "rcd0")] {
        let (sys, y0) = start(&model, form);
        assert!(sys.info().unknowns() >= 60, "{form}: the sparse path");
        let solver = dae_solvers::solver_by_name(solver).expect("solver");
        let options = Options::with_tol(1e-6);
        let run = |system: &dyn DaeSystem| {
            solver
                .solve(
                    &Problem {
                        system,
                        t0: 0.0,
                        y0: &y0,
                        t_end: 0.5,
                    },
                    &options,
                )
                .unwrap_or_else(|e| panic!("{}: {e:?}", solver.name()))
        };
        let compressed = run(&sys);
        let dense = run(&Hidden(&sys));
        let (a, b) = (
            compressed.y.last().expect("end"),
            dense.y.last().expect("end"),
        );
        // The two paths pivot on other patterns (structural against the
        // first Jacobian's non-zeros), so the iterates differ in the last
        // bits and the step sequences may drift apart: the solutions agree
        // to the tolerance's order (1e-6; 1e-4 leaves room for the
        // multipliers, which the error test of an index-2 or index-3
        // unknown weighs less).
        let names = &sys.info().variables;
        for ((u, v), var) in a.iter().zip(b).zip(names) {
            assert!(
                (u - v).abs() <= 1e-4 * (1.0 + v.abs()),
                "{form} {}: {u} vs {v}",
                var.name
            );
        }
        assert!(compressed.stats.steps > 10 && dense.stats.steps > 10);
        let ratio = compressed.stats.steps as f64 / dense.stats.steps as f64;
        assert!((0.8..1.25).contains(&ratio), "{form}: steps {ratio}");
    }
}

/// bdf's start on a large semi-explicit system takes `y'₀` without an SVD
/// of `E` (a scaled partial permutation there): the result is still
/// `E y' = f` on the differential rows and `G y' = 0` on the constraint
/// chain (no explicit time), the defining conditions of the SVD's answer.
#[test]
fn initial_derivative_of_a_semi_explicit_chain() {
    let model = InterpretedModel::from_str(&chain(13)).expect("the chain derives");
    let (sys, y0) = start(&model, "rcd0");
    let info = sys.info();
    let (n, k) = (info.unknowns(), info.constraints.len());
    let yp = dae_solvers::initial_derivative(&sys, 0.0, &y0).expect("y'0");
    let mut e = DMatrix::zeros(n, n);
    sys.leading(0.0, &y0, &mut e);
    let mut f = vec![0.0; n];
    sys.rhs(0.0, &y0, &mut f);
    for r in (0..n).filter(|&r| (0..n).any(|c| e[(r, c)] != 0.0)) {
        let ey: f64 = (0..n).map(|c| e[(r, c)] * yp[c]).sum();
        assert!((ey - f[r]).abs() <= 1e-12 * (1.0 + f[r].abs()), "row {r}");
    }
    let mut g = DMatrix::zeros(k, n);
    sys.constraints_jacobian(0.0, &y0, &mut g);
    let gy = &g * nalgebra::DVector::from_column_slice(&yp);
    assert!(gy.amax() <= 1e-9, "G y' = {}", gy.amax());
}

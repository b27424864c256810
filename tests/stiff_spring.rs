//! A pendulum carrying a second mass on a stiff spring (k = 10⁷ … 10⁹ N/m):
//! issue 26, "done when" 3 — `radau5` finishes on every formulation it
//! takes, or fails typed with the reason. The index-1 forms (`rcd0`, `psi0`,
//! `mex0`) determine the rod's multiplier λ from the acceleration-level
//! constraint, into which the spring force enters with its stiffness: at
//! k = 10⁹ and tol 1e-8 the round-off of λ's equations is of the
//! tolerance's size, the Newton increments of λ stay at a fixed fraction of
//! it whatever the step, and the step is shrunk until the failure budget
//! ends it (`mex0`: the typed `round_off_floor`, naming λ). At k = 10⁷ every
//! form finishes since the spring's differences `(x₂ − x₁)`, `(y₂ − y₁)` stay
//! factored in the derivation (dae-core `expr::is_linear_form`).

use dae::dae_core::interp::InterpretedModel;
use dae::dae_core::system::Model;
use dae::dae_core::Derived;
use dae::dae_solvers::radau5::Radau5;
use dae::dae_solvers::{init, Options, Problem, SolveError, Solver};

const MODEL: &str = "
/// A pendulum (m1 on a rigid rod of length l) with m2 hanging from it on a
/// stiff spring (stiffness k, rest length r).
pub StiffSpring {
    parameters { m1 = 1.0, m2 = 1.0, l = 1.0, r = 0.5, k = 1e7, g = 9.81 }
    differential { x1, y1, x2, y2, vx1, vy1, vx2, vy2 }
    algebraic { lambda }
    definitions {
        d = sqrt((x2 - x1)^2 + (y2 - y1)^2);
        f = k * (d - r) / d;
    }
    equations {
        der(x1) = vx1;
        der(y1) = vy1;
        der(x2) = vx2;
        der(y2) = vy2;
        m1 * der(vx1) = -2 * x1 * lambda + f * (x2 - x1);
        m1 * der(vy1) = -2 * y1 * lambda + f * (y2 - y1) - m1 * g;
        m2 * der(vx2) = -f * (x2 - x1);
        m2 * der(vy2) = -f * (y2 - y1) - m2 * g;
        0 = x1^2 + y1^2 - l^2;
    }
}
";

/// `radau5` on `formulation` with spring stiffness `k` at `tol`, t ∈ [0, 1],
/// from the rod horizontal and the spring at its rest length, hanging.
fn run(formulation: &str, k: f64, tol: f64) -> Result<usize, SolveError> {
    let derived = Derived::from_str(MODEL).unwrap();
    let mut m = InterpretedModel::new(&derived);
    m.set_parameter("k", k).unwrap();
    let sys = m.formulation(formulation).unwrap();
    let info = sys.info().clone();
    let mut y0 = vec![0.0; info.unknowns()];
    for (name, v) in [("x1", 1.0), ("y1", 0.0), ("x2", 1.0), ("y2", -0.5)] {
        y0[info.variable(name).unwrap()] = v;
    }
    let start = init::consistent(&*sys, 0.0, &y0, &init::InitOptions::default()).unwrap();
    let problem = Problem {
        system: &*sys,
        t0: 0.0,
        y0: &start.y,
        t_end: 1.0,
    };
    Radau5
        .solve(&problem, &Options::with_tol(tol))
        .map(|s| s.stats.steps)
}

/// At k = 10⁹ the index-1 forms still stop at 1e-8. `mex0` stops typed,
/// `round_off_floor` naming λ; `rcd0` and `psi0` now reach t ≈ 0.06 (before
/// the spring's `(x₂ − x₁)`, `(y₂ − y₁)` were kept factored, all three
/// stopped before t = 10⁻³ with `round_off_floor`) and end there with
/// `newton_failure` / `step_size_too_small` at h ≈ 10⁻¹⁶: the stall rule does
/// not recognise that failure (an open defect of its classification, not of
/// the form; BENCHMARKS §14, "Linear forms kept factored, restricted to the
/// unknowns").
#[test]
fn the_index_1_forms_stop_early_at_k_1e9() {
    let k = 1e9;
    for f in ["rcd0", "psi0", "mex0"] {
        match run(f, k, 1e-8) {
            Err(SolveError::RoundOffFloor {
                unknown,
                level,
                h,
                h_from,
                t,
            }) => {
                assert_eq!(f, "mex0", "{f}: round_off_floor at t = {t}");
                assert_eq!(unknown, "lambda", "{f}, k = {k}");
                assert!((0.05..=4.0).contains(&level), "{f}: level {level}");
                // The stall is seen over a step shrunk at least eightfold.
                assert!(h * 8.0 <= h_from, "{f}: h {h}, from {h_from}");
                assert!(t < 0.1, "{f}: t = {t}");
            }
            Err(SolveError::NewtonFailure { t, h, .. } | SolveError::StepSizeTooSmall { t, h }) => {
                assert_ne!(f, "mex0", "{f}: {t} {h}");
                assert!(t < 0.1 && h < 1e-12, "{f}: t = {t}, h = {h}");
            }
            other => panic!("{f}, k = {k}: {other:?}"),
        }
    }
}

#[test]
fn the_other_forms_finish_and_the_index_1_forms_finish_where_the_floor_allows() {
    for k in [1e7, 1e9] {
        for f in ["ori2", "rcd1", "ggl1", "psi1"] {
            let steps = run(f, k, 1e-8).unwrap_or_else(|e| panic!("{f}, k = {k}: {e}"));
            assert!(steps < 10_000, "{f}, k = {k}: {steps} steps");
        }
    }
    // At k = 1e7 the index-1 forms finish at 1e-8 too (6 247 – 6 557 steps):
    // with the spring's differences evaluated as written, the floor of λ's
    // equations lies below 1e-8 (it lay between 1e-8 and 3e-8 when they were
    // expanded, and these runs ended with `round_off_floor`).
    for f in ["rcd0", "psi0", "mex0"] {
        let steps = run(f, 1e7, 1e-8).unwrap_or_else(|e| panic!("{f} at k = 1e7: {e}"));
        assert!(steps < 10_000, "{f} at k = 1e7: {steps} steps");
    }
    // At k = 1e9, rcd0 finishes at 1e-7 (16 171 steps).
    let steps = run("rcd0", 1e9, 1e-7).unwrap_or_else(|e| panic!("rcd0 at k = 1e9, 1e-7: {e}"));
    assert!(steps < 20_000, "rcd0 at k = 1e9, 1e-7: {steps} steps");
}

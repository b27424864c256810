//! Consistent initial values: `dae_solvers::init`.

mod common;

use common::{
    fd_matrix, pendulum_lambda, DoublePendulum, Form, Idec, Pendulum, Sys, Toy, DP_A0, DP_B0, G,
    IDEC_C0, IDEC_C1, PENDULUM_L0, PENDULUM_L1, PENDULUM_L2,
};
use dae_core::system::DaeSystem;
use dae_solvers::init::{
    consistent, consistent_from, initial_derivative, Consistent, How, InitMode, InitOptions,
    InitReport, Start,
};
use dae_solvers::{InitError, SolveError};
use nalgebra::{DMatrix, DVector};

fn pendulum(form: Form) -> Pendulum {
    Pendulum::new(form)
}

fn project(sys: &dyn DaeSystem, y0: &[f64]) -> Consistent {
    match consistent(sys, 0.0, y0, &InitOptions::default()) {
        Ok(c) => c,
        Err(e) => panic!("consistent failed: {e}"),
    }
}

fn chain(sys: &dyn DaeSystem, y: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
    let info = sys.info();
    let k = info.constraints.len();
    let mut g = vec![0.0; k];
    let mut j = DMatrix::zeros(k, info.unknowns());
    sys.constraints(0.0, y, &mut g);
    sys.constraints_jacobian(0.0, y, &mut j);
    (g, j)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

fn changed(report: &InitReport) -> Vec<&str> {
    report.changes.iter().map(|c| c.name.as_str()).collect()
}

/// Distance of `d` from the column space of `a` (least squares residual).
fn off_range(a: &DMatrix<f64>, d: &[f64]) -> f64 {
    let b = DVector::from_column_slice(d);
    let x = a
        .clone()
        .svd(true, true)
        .solve(&b, 1e-14)
        .expect("svd solve");
    (a * x - b).amax()
}

// ---------------------------------------------------------------------------
// The hand-written test systems are right.

fn check_jacobians(sys: &dyn DaeSystem, y: &[f64]) {
    let info = sys.info();
    let (m, n, k) = (info.equations(), info.unknowns(), info.constraints.len());
    let name = format!("{}/{}", info.model, info.name);

    let mut j = DMatrix::zeros(k, n);
    sys.constraints_jacobian(0.0, y, &mut j);
    let fd = fd_matrix(k, y, |y, g| sys.constraints(0.0, y, g));
    assert!(
        (&j - &fd).amax() < 1e-7,
        "{name}: chain Jacobian\n{j}\n{fd}"
    );

    let mut j = DMatrix::zeros(m, n);
    sys.rhs_jacobian(0.0, y, &mut j);
    let fd = fd_matrix(m, y, |y, f| sys.rhs(0.0, y, f));
    assert!((&j - &fd).amax() < 1e-7, "{name}: rhs Jacobian\n{j}\n{fd}");

    let z: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
    let mut j = DMatrix::zeros(m, n);
    sys.leading_jacobian(0.0, y, &z, &mut j);
    let fd = fd_matrix(m, y, |y, out| {
        let mut e = DMatrix::zeros(m, n);
        sys.leading(0.0, y, &mut e);
        let ez = &e * DVector::from_column_slice(&z);
        out.copy_from_slice(ez.as_slice());
    });
    assert!(
        (&j - &fd).amax() < 1e-7,
        "{name}: leading Jacobian\n{j}\n{fd}"
    );

    // residual = E yp - f
    let mut e = DMatrix::zeros(m, n);
    sys.leading(0.0, y, &mut e);
    let mut f = vec![0.0; m];
    sys.rhs(0.0, y, &mut f);
    let mut r = vec![0.0; m];
    sys.residual(0.0, y, &z, &mut r);
    let ez = &e * DVector::from_column_slice(&z);
    for i in 0..m {
        assert!((r[i] - (ez[i] - f[i])).abs() < 1e-12, "{name}: residual");
    }
}

/// Chain member `level + 1` is the time derivative of member `level` along
/// the dynamics: `g_{ℓ+1}(y) = ∇g_ℓ(y) · ẏ`, with `ẏ` from the first
/// (diagonal-`E`) differential rows.
fn check_chain_derivatives(sys: &dyn DaeSystem, y: &[f64], diff_rows: usize) {
    let info = sys.info();
    let (m, n) = (info.equations(), info.unknowns());
    let mut e = DMatrix::zeros(m, n);
    sys.leading(0.0, y, &mut e);
    let mut f = vec![0.0; m];
    sys.rhs(0.0, y, &mut f);
    let mut yd = vec![0.0; n];
    for i in 0..diff_rows {
        yd[i] = f[i] / e[(i, i)];
    }
    let (g, j) = chain(sys, y);
    for (a, ma) in info.constraints.iter().enumerate() {
        for (mb, gb) in info.constraints.iter().zip(&g) {
            if mb.source == ma.source && mb.level == ma.level + 1 {
                let dg: f64 = (0..n).map(|c| j[(a, c)] * yd[c]).sum();
                assert!(
                    (dg - gb).abs() < 1e-11 * (1.0 + dg.abs()),
                    "{}: d/dt of `{}` is {dg}, member `{}` is {gb}",
                    info.model,
                    ma.expr,
                    mb.expr,
                );
            }
        }
    }
}

#[test]
fn test_systems_have_correct_jacobians_and_chains() {
    let yp = [0.7, -0.4, 0.3, -1.1, 2.5, 0.35];
    for form in [Form::Rcd0, Form::Ggl1, Form::Ovd1, Form::Psi1] {
        let sys = pendulum(form);
        let n = sys.info().unknowns();
        check_jacobians(&sys, &yp[..n]);
    }
    check_chain_derivatives(&pendulum(Form::Rcd0), &yp[..5], 4);

    let dp = Sys(DoublePendulum::new(1.3, 0.7, 1.1, 0.8, G));
    let ydp = [0.5, -0.9, 1.2, -1.3, 0.4, -0.2, 0.9, 0.3, 2.1, -1.4];
    check_jacobians(&dp, &ydp);
    check_chain_derivatives(&dp, &ydp, 8);

    let idec = Sys(Idec::new());
    let yi = [0.3, 0.9, -0.8, 0.35, -1.2, 0.6];
    check_jacobians(&idec, &yi);
    check_chain_derivatives(&idec, &yi, 4);
    // The exact solution satisfies the whole chain.
    for t in [0.0, 0.2, 0.4] {
        let (g, _) = chain(&idec, &Idec::exact(t));
        assert!(max_abs(&g) < 1e-14, "t = {t}: {g:?}");
    }
}

// ---------------------------------------------------------------------------
// The pendulum.

#[test]
fn paper_start_gives_zero_multiplier_without_projection() {
    let sys = pendulum(Form::Rcd0);
    for guess in [0.0, 7.5] {
        let y0 = [1.0, 0.0, 0.0, 0.0, guess];
        let c = project(&sys, &y0);
        assert_eq!(&c.y[..4], &y0[..4]);
        assert_eq!(c.y[4], 0.0, "λ from guess {guess}");
        assert!(!c.report.projected);
        assert!(c.report.changes.is_empty());
        assert_eq!(c.report.projection_iterations, 0);
        // From the right λ there is nothing to correct.
        assert_eq!(c.report.newton_iterations, usize::from(guess != 0.0));
        assert_eq!(c.report.algebraic.len(), 1);
        assert_eq!(c.report.algebraic[0].name, "lambda");
        assert_eq!(c.report.algebraic[0].before, guess);
        assert!(c.report.zeroed.is_empty());
    }
}

#[test]
fn consistent_start_gives_exact_multiplier() {
    let p = Pendulum::new(Form::Rcd0);
    let expected = pendulum_lambda(&p, &[0.6, -0.8, 1.0, 0.75]);
    assert!((expected - (1.5625 + 0.8 * G) / 2.0).abs() < 1e-14);
    let sys = p;
    let y0 = [0.6, -0.8, 1.0, 0.75, 0.0];
    let c = project(&sys, &y0);
    assert_eq!(&c.y[..4], &y0[..4], "differential values untouched");
    assert!(!c.report.projected);
    assert!(
        (c.y[4] - expected).abs() <= 4.0 * f64::EPSILON * expected,
        "λ = {}, expected {expected}",
        c.y[4]
    );
    // Strict mode accepts it too and computes the same λ.
    let s = consistent(&sys, 0.0, &y0, &InitOptions::strict()).expect("strict");
    assert_eq!(s.y, c.y);
    assert_eq!(s.report.mode, InitMode::Strict);
}

#[test]
fn inconsistent_position_is_projected_to_the_closest_point() {
    let sys = pendulum(Form::Rcd0);
    let y0 = [1.1, 0.05, 0.0, 0.0, 0.0];
    let c = project(&sys, &y0);
    let r = (1.1_f64.powi(2) + 0.05_f64.powi(2)).sqrt();
    assert!((c.y[0] - 1.1 / r).abs() < 1e-12, "x = {}", c.y[0]);
    assert!((c.y[1] - 0.05 / r).abs() < 1e-12, "y = {}", c.y[1]);
    assert_eq!(&c.y[2..4], &[0.0, 0.0]);
    assert!(c.report.projected);
    assert_eq!(changed(&c.report), ["x", "y"]);
    assert_eq!(c.report.changes[0].before, 1.1);
    assert_eq!(c.report.changes[0].after, c.y[0]);
    let lam = pendulum_lambda(&Pendulum::new(Form::Rcd0), &c.y);
    assert!((c.y[4] - lam).abs() < 1e-12 * lam.abs());
    // Residuals per level, before and after.
    let l0 = &c.report.levels[0];
    assert_eq!(l0.level, 0);
    assert!((l0.before - (r * r - 1.0)).abs() < 1e-15);
    assert!(l0.after < 1e-14);
    assert!(c.report.projection_iterations >= 1);
    assert_eq!(
        c.report.constraints[0].equation,
        format!("0 = {PENDULUM_L0}")
    );
}

#[test]
fn inconsistent_position_and_velocity_are_projected_level_by_level() {
    let sys = pendulum(Form::Rcd0);
    let (v0, w0) = (0.3, -0.7);
    let y0 = [1.1, 0.05, v0, w0, 0.0];
    let c = project(&sys, &y0);
    let r = (1.1_f64.powi(2) + 0.05_f64.powi(2)).sqrt();
    let (x, y) = (1.1 / r, 0.05 / r);
    // Positions: the closest point, not moved by the velocity stage.
    assert!((c.y[0] - x).abs() < 1e-12 && (c.y[1] - y).abs() < 1e-12);
    // Velocity: orthogonal projection onto the tangent at the new position.
    let dot = v0 * x + w0 * y;
    assert!((c.y[2] - (v0 - dot * x)).abs() < 1e-12, "v = {}", c.y[2]);
    assert!((c.y[3] - (w0 - dot * y)).abs() < 1e-12, "w = {}", c.y[3]);
    assert_eq!(changed(&c.report), ["x", "y", "v", "w"]);
    let (g, _) = chain(&sys, &c.y);
    assert!(max_abs(&g) < 1e-12, "chain after: {g:?}");
    for l in &c.report.levels {
        assert!(l.after < 1e-12, "level {}: {}", l.level, l.after);
    }
    assert!(c.report.levels[1].before > 0.1);
    // Energy is that of the projected state.
    let mut e = [0.0];
    sys.invariants(0.0, &c.y, &mut e);
    assert!((e[0] - (0.5 * (c.y[2].powi(2) + c.y[3].powi(2)) + G * c.y[1])).abs() < 1e-12);
}

#[test]
fn inconsistent_velocity_alone_keeps_positions_bitwise() {
    let sys = pendulum(Form::Rcd0);
    let y0 = [0.6, -0.8, 1.0, 0.0, 0.0];
    let c = project(&sys, &y0);
    assert_eq!(&c.y[..2], &y0[..2]);
    // Tangent at (0.6, -0.8) is (0.8, 0.6): (1, 0) projects to 0.8·(0.8, 0.6).
    assert!((c.y[2] - 0.64).abs() < 1e-14 && (c.y[3] - 0.48).abs() < 1e-14);
    assert_eq!(changed(&c.report), ["v", "w"]);
}

#[test]
fn far_and_badly_scaled_starts_are_projected() {
    // Far inside the circle: the closest point of (0.01, 0) is (1, 0).
    let sys = pendulum(Form::Rcd0);
    let c = project(&sys, &[0.01, 0.0, 0.0, 0.0, 0.0]);
    assert!((c.y[0] - 1.0).abs() < 1e-12 && c.y[1].abs() < 1e-12);
    // Far outside.
    let c = project(&sys, &[5.0, 5.0, 1.0, 2.0, 0.0]);
    let s = 0.5_f64.sqrt();
    assert!((c.y[0] - s).abs() < 1e-12 && (c.y[1] - s).abs() < 1e-12);
    // A long pendulum (L = 1000): the tolerance is relative.
    let p = Pendulum::with_parameters(Form::Rcd0, 2.0, 1000.0, G);
    let lam_of = |y: &[f64]| 2.0 * (y[2] * y[2] + y[3] * y[3] - G * y[1]) / (2.0 * 1e6);
    let sys = p;
    let c = project(&sys, &[600.0, -800.0, 8.0, 6.0, 0.0]);
    assert!(!c.report.projected, "{:?}", c.report);
    assert!((c.y[4] - lam_of(&c.y)).abs() < 1e-13 * lam_of(&c.y).abs());
    let c = project(&sys, &[600.5, -800.0, 8.0, 6.1, 0.0]);
    assert!(c.report.projected);
    assert!(((c.y[0].powi(2) + c.y[1].powi(2)).sqrt() - 1000.0).abs() < 1e-9);
}

#[test]
fn strict_mode_names_the_violated_equation() {
    let sys = pendulum(Form::Rcd0);
    let err = consistent(
        &sys,
        0.0,
        &[1.1, 0.05, 0.3, -0.7, 0.0],
        &InitOptions::strict(),
    )
    .expect_err("position violated");
    match &err {
        SolveError::InconsistentInitialValues { equation, residual } => {
            assert_eq!(equation, &format!("0 = {PENDULUM_L0}"));
            assert!((residual - (1.1 * 1.1 + 0.05 * 0.05 - 1.0)).abs() < 1e-15);
        }
        other => panic!("wrong error {other:?}"),
    }
    assert_eq!(err.kind(), "inconsistent_initial_values");
    assert!(err.to_string().contains("x^2 + y^2 - L^2"));

    let err = consistent(
        &sys,
        0.0,
        &[0.6, -0.8, 1.0, 0.0, 0.0],
        &InitOptions::strict(),
    )
    .expect_err("velocity violated");
    match err {
        SolveError::InconsistentInitialValues { equation, residual } => {
            assert_eq!(equation, format!("0 = {PENDULUM_L1}"));
            assert!((residual - 1.2).abs() < 1e-15);
        }
        other => panic!("wrong error {other:?}"),
    }
}

#[test]
fn ggl1_sets_eta_to_zero_and_agrees_with_rcd0() {
    let sys = pendulum(Form::Ggl1);
    let c = project(&sys, &[1.1, 0.05, 0.3, -0.7, 0.0, 0.25]);
    assert_eq!(c.y[5], 0.0);
    assert_eq!(c.report.zeroed, ["eta"]);
    assert_eq!(c.report.algebraic.len(), 1);
    assert_eq!(c.report.algebraic[0].name, "lambda");
    let r = project(&pendulum(Form::Rcd0), &[1.1, 0.05, 0.3, -0.7, 0.0]);
    for i in 0..5 {
        assert!((c.y[i] - r.y[i]).abs() < 1e-13, "component {i}");
    }
    // The same values are consistent for every formulation.
    for form in [Form::Ovd1, Form::Psi1] {
        let o = project(&pendulum(form), &r.y);
        assert!(!o.report.projected);
        assert!((o.y[4] - r.y[4]).abs() < 1e-13);
    }
}

#[test]
fn projection_is_idempotent() {
    let sys = pendulum(Form::Rcd0);
    let c = project(&sys, &[1.1, 0.05, 0.3, -0.7, 0.0]);
    let again = project(&sys, &c.y);
    assert!(!again.report.projected);
    assert_eq!(&again.y[..4], &c.y[..4]);
    assert!((again.y[4] - c.y[4]).abs() <= 4.0 * f64::EPSILON * c.y[4].abs());
}

#[test]
fn many_pendulum_starts_project_to_closest_point_and_tangent() {
    let sys = pendulum(Form::Rcd0);
    let p = Pendulum::new(Form::Rcd0);
    for i in 0..60 {
        let a = 0.37 * i as f64;
        let r = 0.3 + 0.06 * i as f64;
        let (v0, w0) = (1.3 * (1.7 * a).sin(), -2.1 * (0.9 * a).cos());
        let y0 = [r * a.cos(), r * a.sin(), v0, w0, 0.0];
        let c = project(&sys, &y0);
        let (x, y) = (a.cos(), a.sin());
        let dot = v0 * x + w0 * y;
        let expected = [x, y, v0 - dot * x, w0 - dot * y];
        for (k, e) in expected.iter().enumerate() {
            assert!(
                (c.y[k] - e).abs() < 1e-12,
                "start {i}: y[{k}] = {}, expected {e}",
                c.y[k],
            );
        }
        let lam = pendulum_lambda(&p, &c.y);
        assert!((c.y[4] - lam).abs() < 1e-12 * (1.0 + lam.abs()));
    }
}

#[test]
fn level_without_new_unknowns_falls_back_to_joint_projection() {
    let sys = Sys(Toy::new());
    let c = project(&sys, &[1.0, 0.0]);
    assert!((c.y[0] - 0.5).abs() < 1e-15 && (c.y[1] - 0.5).abs() < 1e-15);
    assert!(
        c.report.notes.iter().any(|n| n.contains("jointly")),
        "{:?}",
        c.report.notes
    );
    assert!(c.report.algebraic.is_empty() && c.report.zeroed.is_empty());
    // Strict: level 0 holds, level 1 does not.
    match consistent(&sys, 0.0, &[1.0, 0.0], &InitOptions::strict()) {
        Err(SolveError::InconsistentInitialValues { equation, residual }) => {
            assert_eq!(equation, "0 = x - y");
            assert_eq!(residual, 1.0);
        }
        other => panic!("expected inconsistency, got {other:?}"),
    }
}

#[test]
fn empty_chain_keeps_the_values_and_zeroes_free_algebraic_unknowns() {
    let sys = Sys(Toy::unconstrained());
    let c = project(&sys, &[0.3, -2.0, 5.0]);
    assert_eq!(c.y, [0.3, -2.0, 0.0]);
    assert_eq!(c.report.zeroed, ["z"]);
    assert!(!c.report.projected && c.report.levels.is_empty());
    let yp = initial_derivative(&sys, 0.0, &c.y).expect("y'");
    assert_eq!(yp, [0.0, 0.0, 0.0]);
}

// ---------------------------------------------------------------------------
// Two constraints: the planar double pendulum.

fn double_pendulum() -> Sys<DoublePendulum> {
    Sys(DoublePendulum::new(1.3, 0.7, 1.1, 0.8, G))
}

#[test]
fn double_pendulum_at_rest_carries_the_weights() {
    let sys = double_pendulum();
    let p = &sys.0;
    let y0 = p.state(0.0, 0.0, 0.0, 0.0);
    let c = project(&sys, &y0);
    assert!(!c.report.projected);
    let l1 = (p.m1 + p.m2) * p.g / (2.0 * p.l1);
    let l2 = p.m2 * p.g / (2.0 * p.l2);
    assert!(
        (c.y[8] - l1).abs() < 1e-13 * l1,
        "λ1 = {}, expected {l1}",
        c.y[8]
    );
    assert!(
        (c.y[9] - l2).abs() < 1e-13 * l2,
        "λ2 = {}, expected {l2}",
        c.y[9]
    );
    let names: Vec<&str> = c.report.algebraic.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["lambda1", "lambda2"]);
}

#[test]
fn double_pendulum_consistent_start_solves_both_multipliers() {
    let sys = double_pendulum();
    let y0 = sys.0.state(0.7, -1.2, 1.5, -0.4);
    let c = project(&sys, &y0);
    assert!(!c.report.projected);
    assert_eq!(&c.y[..8], &y0[..8]);
    let (g, _) = chain(&sys, &c.y);
    assert!(max_abs(&g) < 1e-12, "{g:?}");
    // Newton on a system linear in λ: one correction and a confirmation.
    assert!(
        c.report.newton_iterations <= 3,
        "{}",
        c.report.newton_iterations
    );
    // The accelerations the multipliers produce keep both rods rigid:
    // d²/dt² of each position constraint vanishes (checked by the chain
    // test) — here against the Jacobian of level 1 applied to ẏ.
    let yp = initial_derivative(&sys, 0.0, &c.y).expect("y'");
    let (_, j) = chain(&sys, &c.y);
    for row in [2, 3] {
        let d: f64 = (0..10).map(|col| j[(row, col)] * yp[col]).sum();
        assert!(d.abs() < 1e-11, "row {row}: {d}");
    }
}

#[test]
fn double_pendulum_projection_is_least_change() {
    let sys = double_pendulum();
    let mut y0 = sys.0.state(0.7, -1.2, 1.5, -0.4);
    let kick = [0.03, -0.02, 0.05, 0.04, 0.2, -0.1, 0.15, 0.3];
    for (yi, k) in y0.iter_mut().zip(kick) {
        *yi += k;
    }
    let c = project(&sys, &y0);
    assert!(c.report.projected);
    let (g, j) = chain(&sys, &c.y);
    assert!(max_abs(&g) < 1e-12, "{g:?}");
    // Positions: q − q0 ∈ range(∂(a, b)/∂q)ᵀ — the closest point.
    let gq = j.view((0, 0), (2, 4)).transpose();
    let dq: Vec<f64> = (0..4).map(|i| c.y[i] - y0[i]).collect();
    assert!(off_range(&gq, &dq) < 1e-12, "positions not closest");
    // Velocities: v − v0 ∈ range(∂(a', b')/∂v)ᵀ — orthogonal projection.
    let gv = j.view((2, 4), (2, 4)).transpose();
    let dv: Vec<f64> = (4..8).map(|i| c.y[i] - y0[i]).collect();
    assert!(off_range(&gv, &dv) < 1e-12, "velocities not closest");
    // And it is a minimum: closer than rescaling each rod separately.
    let naive = {
        let (x1, y1) = (y0[0], y0[1]);
        let s1 = sys.0.l1 / (x1 * x1 + y1 * y1).sqrt();
        let (nx1, ny1) = (x1 * s1, y1 * s1);
        let (dx, dy) = (y0[2] - x1, y0[3] - y1);
        let s2 = sys.0.l2 / (dx * dx + dy * dy).sqrt();
        [nx1, ny1, nx1 + dx * s2, ny1 + dy * s2]
    };
    let dist = |q: &[f64]| (0..4).map(|i| (q[i] - y0[i]).powi(2)).sum::<f64>();
    assert!(dist(&c.y[..4]) <= dist(&naive));
    let names = changed(&c.report);
    assert_eq!(names, ["x1", "y1", "x2", "y2", "v1", "w1", "v2", "w2"]);
    // Strict mode names the worst of the two position constraints.
    match consistent(&sys, 0.0, &y0, &InitOptions::strict()) {
        Err(SolveError::InconsistentInitialValues { equation, .. }) => {
            assert!(
                equation == format!("0 = {DP_A0}") || equation == format!("0 = {DP_B0}"),
                "{equation}"
            );
        }
        other => panic!("expected inconsistency, got {other:?}"),
    }
}

#[test]
fn double_pendulum_far_start_reaches_the_global_closest_point() {
    let sys = double_pendulum();
    let (l1, l2) = (sys.0.l1, sys.0.l2);
    // Positions far off both rods (farther than their radius of
    // curvature); velocities zero.
    let y0 = [1.6, -0.2, 0.5, -2.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let c = project(&sys, &y0);
    let (g, _) = chain(&sys, &c.y);
    assert!(max_abs(&g) < 1e-12, "{g:?}");
    let dist = |q: &[f64]| (0..4).map(|i| (q[i] - y0[i]).powi(2)).sum::<f64>();
    let found = dist(&c.y[..4]);
    // Brute force over the two angles, refined around the best grid point.
    let point = |a: f64, b: f64| {
        let (x1, y1) = (l1 * a.sin(), -l1 * a.cos());
        [x1, y1, x1 + l2 * b.sin(), y1 - l2 * b.cos()]
    };
    let steps = 720;
    let h = std::f64::consts::TAU / steps as f64;
    let (mut best, mut ba, mut bb) = (f64::INFINITY, 0.0, 0.0);
    for i in 0..steps {
        for j in 0..steps {
            let (a, b) = (i as f64 * h, j as f64 * h);
            let d = dist(&point(a, b));
            if d < best {
                (best, ba, bb) = (d, a, b);
            }
        }
    }
    let mut step = h;
    while step > 1e-10 {
        let mut improved = false;
        for (da, db) in [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)] {
            let d = dist(&point(ba + da, bb + db));
            if d < best {
                (best, ba, bb) = (d, ba + da, bb + db);
                improved = true;
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    assert!(found <= best + 1e-12, "found {found}, brute force {best}");
    let q = point(ba, bb);
    for (i, qi) in q.iter().enumerate() {
        assert!(
            (c.y[i] - qi).abs() < 1e-7,
            "q[{i}] = {}, brute force {qi}",
            c.y[i],
        );
    }
}

// ---------------------------------------------------------------------------
// A general index-2 DAE with two sources (seed 002).

#[test]
fn idec_problem_gets_both_algebraic_unknowns() {
    let sys = Sys(Idec::new());
    let t = 0.3;
    let exact = Idec::exact(t);
    let mut y0 = exact.clone();
    y0[4] = 0.0;
    y0[5] = 0.0;
    let c = consistent(&sys, t, &y0, &InitOptions::default()).expect("consistent");
    assert!(!c.report.projected);
    assert!((c.y[4] + 1.0).abs() < 1e-14, "y5 = {}", c.y[4]);
    assert!((c.y[5] - exact[5]).abs() < 1e-14, "y6 = {}", c.y[5]);

    // Perturbed differential values: both level-0 constraints restored
    // jointly with the least change.
    let mut y1 = y0.clone();
    y1[0] += 0.02;
    y1[2] -= 0.03;
    let c = consistent(&sys, t, &y1, &InitOptions::default()).expect("consistent");
    assert!(c.report.projected);
    let (g, j) = chain(&sys, &c.y);
    assert!(max_abs(&g) < 1e-12, "{g:?}");
    let g0 = j.view((0, 0), (2, 4)).transpose();
    let d: Vec<f64> = (0..4).map(|i| c.y[i] - y1[i]).collect();
    assert!(off_range(&g0, &d) < 1e-12);
    match consistent(&sys, t, &y1, &InitOptions::strict()) {
        Err(SolveError::InconsistentInitialValues { equation, residual }) => {
            assert!(
                equation == format!("0 = {IDEC_C0}") || equation == format!("0 = {IDEC_C1}"),
                "{equation}"
            );
            assert!(residual.abs() > 1e-3);
        }
        other => panic!("expected inconsistency, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------
// Bad input never panics.

#[test]
fn non_finite_and_malformed_inputs_are_typed_errors() {
    let sys = pendulum(Form::Rcd0);
    let opts = InitOptions::default();
    for (i, bad) in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY]
        .into_iter()
        .enumerate()
    {
        let mut y0 = [0.6, -0.8, 1.0, 0.75, 0.0];
        y0[i + 1] = bad;
        match consistent(&sys, 0.0, &y0, &opts) {
            Err(SolveError::InvalidInput { what }) => {
                let name = ["y", "v", "w"][i];
                assert!(what.contains(&format!("`{name}`")), "{what}");
            }
            other => panic!("expected InvalidInput, got {other:?}"),
        }
        assert!(matches!(
            initial_derivative(&sys, 0.0, &y0),
            Err(SolveError::InvalidInput { .. })
        ));
    }
    let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
    assert!(matches!(
        consistent(&sys, 0.0, &y0[..4], &opts),
        Err(SolveError::InvalidInput { .. })
    ));
    assert!(matches!(
        consistent(&sys, f64::NAN, &y0, &opts),
        Err(SolveError::InvalidInput { .. })
    ));
    for bad in [
        InitOptions {
            tol: 0.0,
            ..InitOptions::default()
        },
        InitOptions {
            tol: f64::NAN,
            ..InitOptions::default()
        },
        InitOptions {
            max_iterations: 0,
            ..InitOptions::default()
        },
    ] {
        assert!(matches!(
            consistent(&sys, 0.0, &y0, &bad),
            Err(SolveError::InvalidInput { .. })
        ));
    }
}

#[test]
fn model_producing_nan_is_non_finite() {
    let sys = Pendulum::with_parameters(Form::Rcd0, 1.0, f64::NAN, G);
    let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
    let err = consistent(&sys, 0.0, &y0, &InitOptions::default()).expect_err("NaN model");
    assert_eq!(err.kind(), "init_non_finite", "{err:?}");
    match &err {
        SolveError::Init(InitError::NonFinite {
            equation,
            what,
            values,
            ..
        }) => {
            assert_eq!(equation, &format!("0 = {PENDULUM_L0}"));
            assert_eq!(*what, "residual");
            let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
            assert_eq!(names, ["x", "y", "v", "w", "lambda"]);
            assert_eq!(values[0].1, 1.0);
        }
        other => panic!("expected InitError::NonFinite, got {other:?}"),
    }
    let sys = Pendulum::with_parameters(Form::Rcd0, f64::NAN, 1.0, G);
    assert!(matches!(
        initial_derivative(&sys, 0.0, &y0),
        Err(SolveError::NonFinite { .. })
    ));
}

#[test]
fn rank_zero_constraint_jacobian_is_reported() {
    // At the pivot the position constraint has a zero gradient and cannot
    // be repaired.
    let sys = pendulum(Form::Rcd0);
    let y0 = [0.0, 0.0, 0.0, 0.0, 0.0];
    for opts in [InitOptions::default(), InitOptions::strict()] {
        match consistent(&sys, 0.0, &y0, &opts) {
            Err(SolveError::InconsistentInitialValues { equation, residual }) => {
                assert_eq!(equation, format!("0 = {PENDULUM_L0}"));
                assert_eq!(residual, -1.0);
            }
            other => panic!("expected inconsistency, got {other:?}"),
        }
    }
}

#[test]
fn singular_multiplier_block_is_reported() {
    // L = 0: the pivot is consistent, but λ's coefficient −(4/m)(x² + y²)
    // vanishes there.
    let sys = Pendulum::with_parameters(Form::Rcd0, 1.0, 0.0, G);
    let err = consistent(&sys, 0.0, &[0.0; 5], &InitOptions::default()).expect_err("singular");
    assert_eq!(err.kind(), "init_singular");
    assert!(err.to_string().contains(PENDULUM_L2), "{err}");
    match err {
        SolveError::Init(InitError::Singular {
            equations,
            unknowns,
            rank,
            rows,
            t,
        }) => {
            assert_eq!(equations, [format!("0 = {PENDULUM_L2}")]);
            assert_eq!(unknowns, ["lambda"]);
            assert_eq!((rank, rows, t), (0, 1, 0.0));
        }
        other => panic!("expected InitError::Singular, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------
// The initial derivative.

fn check_differential_rows(sys: &dyn DaeSystem, y: &[f64], yp: &[f64]) {
    let info = sys.info();
    let mut r = vec![0.0; info.equations()];
    sys.residual(0.0, y, yp, &mut r);
    for (i, row) in info.rows.iter().enumerate() {
        if row.kind == dae_core::system::RowKind::Differential {
            assert!(
                r[i].abs() < 1e-12,
                "{}: row {i} residual {}",
                info.name,
                r[i]
            );
        }
    }
}

#[test]
fn initial_derivative_solves_the_differential_rows() {
    let p = Pendulum::new(Form::Rcd0);
    let (m, l) = (p.m, p.l);
    let base = project(&p, &[0.6, -0.8, 1.0, 0.75, 0.0]).y;
    let (x, y, v, w, lam) = (base[0], base[1], base[2], base[3], base[4]);
    let exact = [
        v,
        w,
        -2.0 * x * lam / m,
        -2.0 * y * lam / m - G,
        -3.0 * m * G * w / (2.0 * l * l),
    ];
    for form in [Form::Rcd0, Form::Ggl1, Form::Ovd1, Form::Psi1] {
        let sys = pendulum(form);
        let mut y0 = base.clone();
        if form == Form::Ggl1 {
            y0.push(0.0);
        }
        let yp = initial_derivative(&sys, 0.0, &y0).expect("y'");
        check_differential_rows(&sys, &y0, &yp);
        for i in 0..5 {
            assert!(
                (yp[i] - exact[i]).abs() < 1e-11 * (1.0 + exact[i].abs()),
                "{form:?}: y'[{i}] = {}, expected {}",
                yp[i],
                exact[i]
            );
        }
        if form == Form::Ggl1 {
            assert!(yp[5].abs() < 1e-12, "η' = {}", yp[5]);
        }
    }

    let dp = double_pendulum();
    let y0 = project(&dp, &dp.0.state(0.7, -1.2, 1.5, -0.4)).y;
    let yp = initial_derivative(&dp, 0.0, &y0).expect("y'");
    check_differential_rows(&dp, &y0, &yp);

    // IDeC: y6 = 2 tan t, so y6' = 2 / cos² t; y5' = 0.
    let idec = Sys(Idec::new());
    let t = 0.3;
    let yp = initial_derivative(&idec, t, &Idec::exact(t)).expect("y'");
    let exact = [
        t.cos(),
        -t.sin(),
        t.sin(),
        t.cos(),
        0.0,
        2.0 / t.cos().powi(2),
    ];
    for i in 0..6 {
        assert!((yp[i] - exact[i]).abs() < 1e-12, "y'[{i}] = {}", yp[i]);
    }
}

#[test]
fn report_is_serializable() {
    fn serializable<T: serde::Serialize>(_: &T) {}
    let c = project(&pendulum(Form::Rcd0), &[1.0, 0.0, 0.0, 0.0, 0.0]);
    serializable(&c.report);
    serializable(&c);
    assert_eq!(InitOptions::default().mode, InitMode::Project);
}

// ---------------------------------------------------------------------------
// Guesses, the report of every value, typed failures (issue 23, item 4).

dae::dae! {
    /// Hessenberg index 2 with a multiplier that enters quadratically:
    /// `x = y = exp(t)`, and `z (z + 1) / 2 = 1`, so `z = 1` or `z = -2`.
    pub TwoRoots {
        differential { x, y }
        algebraic { z }
        equations {
            der(x) = y * z * (z + 1) / 2;
            der(y) = x;
            0 = x - exp(t);
        }
        formulations { ori2 }
    }
}

dae::dae! {
    /// A point on the unit circle held by the same constraint written
    /// twice: the two multipliers are not determined.
    pub Redundant {
        differential { x, y, v, w }
        algebraic { a, b }
        equations {
            der(x) = v;
            der(y) = w;
            der(v) = -2 * x * a - 4 * x * b;
            der(w) = -2 * y * a - 4 * y * b - 9.81;
            0 = x^2 + y^2 - 1;
            0 = 2 * x^2 + 2 * y^2 - 2;
        }
        formulations { rcd0 }
    }
}

dae::dae! {
    /// A constraint that is NaN for `x < 0`.
    pub Root {
        differential { x, v }
        algebraic { lambda }
        equations {
            der(x) = v;
            der(v) = -lambda;
            0 = sqrt(x) - 1;
        }
        formulations { rcd0 }
    }
}

#[test]
fn a_guess_chooses_the_root_and_a_default_start_is_flagged() {
    let sys = TwoRoots::default().ori2();
    let opts = InitOptions::default();
    // No guess: Newton from 0 (z ← 0 + 2, then to 1).
    let start = [Start::Fixed(1.0), Start::Fixed(1.0), Start::Omitted];
    let c = consistent_from(&sys, 0.0, &start, &opts).expect("consistent");
    assert!((c.y[2] - 1.0).abs() < 1e-13, "z = {}", c.y[2]);
    let v = &c.report.values;
    let names: Vec<&str> = v.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["x", "y", "z"]);
    for e in &v[..2] {
        assert_eq!(
            (e.how, e.given, e.guess, e.moved),
            (How::Fixed, Some(1.0), None, 0.0)
        );
        assert!(!e.nonlinear);
    }
    assert_eq!(
        (v[2].how, v[2].given, v[2].guess),
        (How::Defaulted, None, None)
    );
    assert!(v[2].nonlinear && v[2].root_chosen_by_default());
    assert_eq!(v[2].moved, c.y[2].abs());
    // The guess -1 leads Newton to the other root, z = -2.
    let start = [Start::Fixed(1.0), Start::Fixed(1.0), Start::Guess(-1.0)];
    let c = consistent_from(&sys, 0.0, &start, &opts).expect("consistent");
    assert!((c.y[2] + 2.0).abs() < 1e-13, "z = {}", c.y[2]);
    let z = &c.report.values[2];
    assert_eq!((z.how, z.guess), (How::Guessed, Some(-1.0)));
    assert!(z.nonlinear && !z.root_chosen_by_default());
    assert!((z.moved - 1.0).abs() < 1e-13);
    // `consistent` takes the algebraic value as a guess: the same root.
    let c = consistent(&sys, 0.0, &[1.0, 1.0, -1.0], &opts).expect("consistent");
    assert!((c.y[2] + 2.0).abs() < 1e-13);
    assert_eq!(c.report.values[2].how, How::Guessed);
}

#[test]
fn a_linear_multiplier_is_not_flagged_and_projections_are_named() {
    // The pendulum's λ enters linearly: one consistent value, no warning.
    let sys = pendulum(Form::Rcd1);
    let start = [
        Start::Fixed(1.1),
        Start::Omitted,
        Start::Fixed(0.0),
        Start::Fixed(0.0),
        Start::Omitted,
    ];
    let c = consistent_from(&sys, 0.0, &start, &InitOptions::default()).expect("consistent");
    let v = &c.report.values;
    assert_eq!(v[0].how, How::Projected);
    assert!((v[0].value - 1.0).abs() < 1e-12 && (v[0].moved - 0.1).abs() < 1e-12);
    assert_eq!(v[1].how, How::Defaulted);
    assert_eq!((v[2].how, v[3].how), (How::Fixed, How::Fixed));
    assert_eq!(v[4].how, How::Defaulted);
    assert!(v.iter().all(|e| !e.nonlinear), "{v:?}");
}

#[test]
fn redundant_constraints_are_named_by_the_pivoted_factorisation() {
    use dae::prelude::*;
    let sys = Redundant::default().rcd0();
    let err = consistent(
        &sys,
        0.0,
        &[0.6, 0.8, 0.0, 0.0, 0.0, 0.0],
        &InitOptions::default(),
    )
    .expect_err("singular");
    let text = err.to_string();
    match err {
        SolveError::Init(InitError::Singular {
            equations,
            unknowns,
            rank,
            rows,
            ..
        }) => {
            assert_eq!(unknowns, ["a", "b"]);
            assert_eq!((rank, rows), (1, 2));
            // The second row is twice the first: its pivot is taken first
            // (larger norm), the first row's vanishes.
            let first = sys
                .info()
                .constraints
                .iter()
                .filter(|m| m.source == 0)
                .max_by_key(|m| m.level)
                .expect("a member of the first constraint");
            assert_eq!(equations.len(), 1, "{equations:?}");
            assert!(equations[0].ends_with(first.expr.trim()), "{equations:?}");
        }
        other => panic!("expected InitError::Singular, got {other:?}"),
    }
    assert!(text.contains("rank 1"), "{text}");
}

#[test]
fn a_non_finite_row_is_named_with_the_point() {
    use dae::prelude::*;
    let sys = Root::default().rcd0();
    let err = consistent(&sys, 0.0, &[-1.0, 0.5, 0.0], &InitOptions::default())
        .expect_err("NaN constraint");
    assert_eq!(err.kind(), "init_non_finite");
    assert_eq!(err.t(), Some(0.0));
    match &err {
        SolveError::Init(InitError::NonFinite {
            equation,
            what,
            value,
            values,
            ..
        }) => {
            assert!(equation.contains("sqrt(x)"), "{equation}");
            assert_eq!(*what, "residual");
            assert!(value.is_nan());
            assert_eq!(
                values,
                &[
                    ("x".to_string(), -1.0),
                    ("v".to_string(), 0.5),
                    ("lambda".to_string(), 0.0)
                ]
            );
        }
        other => panic!("expected InitError::NonFinite, got {other:?}"),
    }
    assert!(err.to_string().contains("x = -1e0"), "{err}");
}

#[test]
fn newton_without_a_real_root_names_the_worst_row() {
    // y = -1: the hidden constraint asks z (z + 1) / 2 = -1, which has no
    // real solution; Newton wanders until the iteration limit.
    let sys = TwoRoots::default().ori2();
    let opts = InitOptions {
        max_iterations: 50,
        ..InitOptions::default()
    };
    let err = consistent(&sys, 0.0, &[1.0, -1.0, 0.0], &opts).expect_err("no root");
    assert_eq!(err.kind(), "init_not_converged");
    match &err {
        SolveError::Init(InitError::NotConverged {
            equation,
            residual,
            iterations,
            t,
        }) => {
            let level1 = sys
                .info()
                .constraints
                .iter()
                .find(|m| m.level == 1)
                .expect("the hidden constraint");
            assert!(equation.ends_with(level1.expr.trim()), "{equation}");
            // |z (z + 1) / 2 + 1| ≥ 7/8 for every real z.
            assert!(residual.abs() >= 0.875 - 1e-12, "{residual}");
            assert_eq!((*iterations, *t), (50, 0.0));
        }
        other => panic!("expected InitError::NotConverged, got {other:?}"),
    }
}

//! The pendulum paper, checked: hidden constraints (3a)/(3b), the rows of
//! formulations (4)–(10), the structural numbers of SPEC §2, and the
//! Jacobians of every formulation of every shipped model against central
//! differences.

use dae_core::expr::{self, Sym};
use dae_core::interp::InterpretedModel;
use dae_core::system::{DaeSystem, Model, RowKind};
use dae_core::Derived;
use nalgebra::DMatrix;

const PENDULUM: &str = include_str!("../../scenes/pendulum.dae");
const DOUBLE: &str = include_str!("../../scenes/double_pendulum.dae");
const SPHERICAL: &str = include_str!("../../scenes/spherical_pendulum.dae");

/// Small deterministic generator (no dependency, reproducible points).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

fn derive(src: &str) -> Derived {
    Derived::from_str(src).unwrap_or_else(|e| panic!("model does not derive: {e}"))
}

/// `derived − hand` simplifies to zero exactly.
fn assert_same(d: &Derived, derived: &expr::Expr, hand: &str) {
    let h = d
        .model
        .parse_expr(hand)
        .unwrap_or_else(|e| panic!("bad hand expression {hand}: {e}"));
    let diff = expr::sub(derived, &h);
    assert!(
        diff.is_zero(),
        "derived `{}` differs from `{hand}` by `{}`",
        d.model.text(derived),
        d.model.text(&diff)
    );
}

#[test]
fn pendulum_hidden_constraints_are_paper_3a_3b() {
    let d = derive(PENDULUM);
    let chain = &d.analysis.chains[0];
    assert_eq!(chain.levels.len(), 3);
    assert_same(&d, &chain.levels[0], "x^2 + y^2 - l^2");
    assert_same(&d, &chain.levels[1], "2*x*v + 2*y*w"); // (3a)
    assert_same(
        &d,
        &chain.levels[2],
        "2*v^2 + 2*w^2 - 2*y*g - (4/m)*(x^2 + y^2)*lambda",
    ); // (3b)
       // A wrong hand derivation is caught (the check can fail).
    let wrong = d
        .model
        .parse_expr("2*v^2 + 2*w^2 - 2*y*g - (4/m)*(x^2 + y^2)*lambda + x*v")
        .unwrap();
    assert!(!expr::sub(&chain.levels[2], &wrong).is_zero());
}

/// The paper's equations (4)–(10) as `lhs − rhs` residuals, in the paper's
/// row order, for `y = (x, y, v, w, λ[, η])`, `p = (m, L, g)`.
fn paper_rows(name: &str, y: &[f64], yp: &[f64], p: &[f64]) -> Vec<f64> {
    let (x, yy, v, w, l) = (y[0], y[1], y[2], y[3], y[4]);
    let (xd, yd, vd, wd) = (yp[0], yp[1], yp[2], yp[3]);
    let (m, len, g) = (p[0], p[1], p[2]);
    let pos = -(x * x + yy * yy - len * len);
    let vel = -(2.0 * x * v + 2.0 * yy * w);
    let acc = -(2.0 * v * v + 2.0 * w * w - 2.0 * yy * g - 4.0 / m * (x * x + yy * yy) * l);
    let k1 = xd - v;
    let k2 = yd - w;
    let d1 = m * vd + 2.0 * x * l;
    let d2 = m * wd + 2.0 * yy * l + m * g;
    match name {
        "ori2" => vec![k1, k2, d1, d2, pos],
        "rcd1" => vec![k1, k2, d1, d2, vel],
        "rcd0" => vec![k1, k2, d1, d2, acc],
        "ovd1" => vec![k1, k2, d1, d2, pos, vel],
        "ovd0" => vec![k1, k2, d1, d2, pos, vel, acc],
        "ggl1" => {
            let eta = y[5];
            vec![
                xd - (v - 2.0 * x * eta),
                yd - (w - 2.0 * yy * eta),
                d1,
                d2,
                pos,
                vel,
            ]
        }
        "psi1" => vec![yy * xd - x * yd - (yy * v - x * w), d1, d2, pos, vel],
        "psi0" => vec![
            yy * xd - x * yd - (yy * v - x * w),
            m * (yy * vd - x * wd) - (yy * (-2.0 * x * l) - x * (-2.0 * yy * l - m * g)),
            pos,
            vel,
            acc,
        ],
        other => panic!("no paper rows for {other}"),
    }
}

#[test]
fn pendulum_rows_equal_paper_equations_4_to_10() {
    let model = InterpretedModel::from_str(PENDULUM).unwrap();
    let mut rng = Lcg(7);
    for name in dae_core::system::FORMULATION_NAMES {
        let sys = model.formulation(name).unwrap();
        let n = sys.info().unknowns();
        let mm = sys.info().equations();
        for _ in 0..20 {
            let y: Vec<f64> = (0..n).map(|_| rng.range(-2.0, 2.0)).collect();
            let yp: Vec<f64> = (0..n).map(|_| rng.range(-2.0, 2.0)).collect();
            let p = sys.parameter_values();
            let mut r = vec![0.0; mm];
            sys.residual(0.0, &y, &yp, &mut r);
            let paper = paper_rows(name, &y, &yp, &p);
            assert_eq!(paper.len(), mm, "{name}: row count");
            for (i, (a, b)) in r.iter().zip(&paper).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "{name} row {i}: {a} vs paper {b}"
                );
            }
        }
    }
}

#[test]
fn structural_numbers_match_spec_table() {
    // name, unknowns, equations, d-index, s-index, c-level (SPEC §2).
    type Row = (&'static str, usize, usize, Option<u8>, u8, u8);
    let table: [Row; 8] = [
        ("ori2", 5, 5, Some(3), 2, 2),
        ("rcd1", 5, 5, Some(2), 1, 1),
        ("rcd0", 5, 5, Some(1), 0, 0),
        ("ovd1", 5, 6, None, 1, 1),
        ("ovd0", 5, 7, None, 1, 0),
        ("ggl1", 6, 6, Some(2), 1, 1),
        ("psi1", 5, 5, Some(2), 1, 1),
        ("psi0", 5, 5, Some(1), 0, 0),
    ];
    let d = derive(PENDULUM);
    assert_eq!(d.formulations.len(), 8);
    for (name, n, m, di, si, ci) in table {
        let f = d.formulation(name).unwrap();
        assert_eq!(
            (f.vars.len(), f.rows.len(), f.d_index, f.s_index, f.c_level),
            (n, m, di, si, ci),
            "{name}"
        );
    }
    // Leading matrix: constant except for the projected formulations.
    for f in &d.formulations {
        assert_eq!(f.constant_leading, !f.name.starts_with("psi"), "{}", f.name);
    }
    // Error scaling indices of ori2: positions 1, velocities 2, λ 3.
    let ori2 = d.formulation("ori2").unwrap();
    assert_eq!(
        ori2.vars.iter().map(|v| v.index).collect::<Vec<_>>(),
        [1, 1, 2, 2, 3]
    );
}

#[test]
fn double_pendulum_hidden_constraints_match_hand_derivation() {
    let d = derive(DOUBLE);
    let c = &d.analysis.chains;
    assert_eq!(c.len(), 2);
    assert!(c.iter().all(|ch| ch.top() == 2));
    assert_same(&d, &c[0].levels[1], "2*x1*vx1 + 2*y1*vy1");
    assert_same(
        &d,
        &c[1].levels[1],
        "2*(x2 - x1)*(vx2 - vx1) + 2*(y2 - y1)*(vy2 - vy1)",
    );
    // Accelerations from the dynamics, by hand.
    let ax1 = "(-2*x1*lambda1 + 2*(x2 - x1)*lambda2)/m1";
    let ay1 = "(-2*y1*lambda1 + 2*(y2 - y1)*lambda2 - m1*g)/m1";
    let ax2 = "(-2*(x2 - x1)*lambda2)/m2";
    let ay2 = "(-2*(y2 - y1)*lambda2 - m2*g)/m2";
    assert_same(
        &d,
        &c[0].levels[2],
        &format!("2*vx1^2 + 2*vy1^2 + 2*x1*{ax1} + 2*y1*{ay1}"),
    );
    assert_same(
        &d,
        &c[1].levels[2],
        &format!("2*(vx2 - vx1)^2 + 2*(vy2 - vy1)^2 + 2*(x2 - x1)*({ax2} - {ax1}) + 2*(y2 - y1)*({ay2} - {ay1})"),
    );
    assert_eq!(
        d.formulations.len(),
        8,
        "all eight apply to the double pendulum"
    );
}

#[test]
fn spherical_pendulum_hidden_constraints_match_hand_derivation() {
    let d = derive(SPHERICAL);
    let c = &d.analysis.chains[0];
    assert_same(&d, &c.levels[1], "2*x*u + 2*y*v + 2*z*w");
    assert_same(
        &d,
        &c.levels[2],
        "2*(u^2 + v^2 + w^2) + 2*x*(-2*x*lambda/m) + 2*y*(-2*y*lambda/m) + 2*z*(-2*z*lambda/m - g)",
    );
    // The selector of psi1: S = [[z, 0, -x], [0, z, -y]] on the position rows.
    let psi1 = d.formulation("psi1").unwrap();
    let rows: Vec<String> = (0..psi1.rows.len())
        .map(|i| psi1.row_text(&d.model, i))
        .collect();
    assert_eq!(rows[0], "z*der(x) - x*der(z) = z*u - x*w");
    assert_eq!(rows[1], "z*der(y) - y*der(z) = z*v - y*w");
}

/// Central differences of every Jacobian the trait exposes, at random points.
fn check_jacobians(sys: &dyn DaeSystem, rng: &mut Lcg, label: &str) {
    let info = sys.info().clone();
    let (n, m, k) = (info.unknowns(), info.equations(), info.constraints.len());
    let mut worst: f64 = 0.0;
    for _ in 0..5 {
        let y: Vec<f64> = (0..n)
            .map(|_| rng.range(0.3, 1.3) * if rng.next() < 0.5 { -1.0 } else { 1.0 })
            .collect();
        let z: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let t = rng.range(0.0, 1.0);
        // ∂f/∂y
        let mut j = DMatrix::zeros(m, n);
        sys.rhs_jacobian(t, &y, &mut j);
        worst = worst.max(compare_fd(
            &j,
            &y,
            m,
            |yy, out| sys.rhs(t, yy, out),
            &format!("{label} ∂f/∂y"),
        ));
        // ∂(E z)/∂y
        let mut je = DMatrix::zeros(m, n);
        sys.leading_jacobian(&y, &z, &mut je);
        let ez = |yy: &[f64], out: &mut [f64]| {
            let mut e = DMatrix::zeros(m, n);
            sys.leading(yy, &mut e);
            let v = e * nalgebra::DVector::from_column_slice(&z);
            out.copy_from_slice(v.as_slice());
        };
        worst = worst.max(compare_fd(&je, &y, m, ez, &format!("{label} ∂(Ez)/∂y")));
        // ∂g/∂y for the whole chain
        let mut jg = DMatrix::zeros(k, n);
        sys.constraints_jacobian(t, &y, &mut jg);
        worst = worst.max(compare_fd(
            &jg,
            &y,
            k,
            |yy, out| sys.constraints(t, yy, out),
            &format!("{label} ∂g/∂y"),
        ));
        // residual = E yp − f
        let yp: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut r = vec![0.0; m];
        sys.residual(t, &y, &yp, &mut r);
        let mut e = DMatrix::zeros(m, n);
        sys.leading(&y, &mut e);
        let mut f = vec![0.0; m];
        sys.rhs(t, &y, &mut f);
        let ey = &e * nalgebra::DVector::from_column_slice(&yp);
        for i in 0..m {
            assert!(
                (r[i] - (ey[i] - f[i])).abs() < 1e-12 * (1.0 + f[i].abs()),
                "{label}: residual row {i}"
            );
        }
    }
    assert!(
        worst < 1e-7,
        "{label}: worst relative Jacobian error {worst:e}"
    );
}

fn compare_fd(
    j: &DMatrix<f64>,
    y: &[f64],
    rows: usize,
    f: impl Fn(&[f64], &mut [f64]),
    label: &str,
) -> f64 {
    let n = y.len();
    let mut worst: f64 = 0.0;
    let (mut fp, mut fm) = (vec![0.0; rows], vec![0.0; rows]);
    for c in 0..n {
        let h = 1e-6 * (1.0 + y[c].abs());
        let mut yp = y.to_vec();
        yp[c] += h;
        let mut ym = y.to_vec();
        ym[c] -= h;
        f(&yp, &mut fp);
        f(&ym, &mut fm);
        for r in 0..rows {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let scale = 1.0f64.max(fd.abs()).max(j[(r, c)].abs());
            let err = (fd - j[(r, c)]).abs() / scale;
            assert!(
                err < 1e-7,
                "{label}: entry ({r}, {c}) analytic {} vs central difference {fd}",
                j[(r, c)]
            );
            worst = worst.max(err);
        }
    }
    worst
}

#[test]
fn interpreted_jacobians_match_central_differences() {
    let mut rng = Lcg(42);
    for (label, src) in [
        ("pendulum", PENDULUM),
        ("double", DOUBLE),
        ("spherical", SPHERICAL),
    ] {
        let model = InterpretedModel::from_str(src).unwrap();
        for name in &model.model_info().formulations {
            let sys = model.formulation(name).unwrap();
            check_jacobians(&sys, &mut rng, &format!("{label}/{name}"));
        }
    }
}

#[test]
fn printed_expressions_reparse_to_themselves() {
    for src in [PENDULUM, DOUBLE, SPHERICAL] {
        let d = derive(src);
        for (_, _, e) in d.analysis.flat() {
            let text = d.model.text(e);
            let back = d.model.parse_expr(&text).unwrap();
            assert!(
                expr::sub(e, &back).is_zero(),
                "`{text}` does not re-parse to itself"
            );
        }
        for f in &d.formulations {
            for row in &f.rows {
                if f.extra_names.is_empty() {
                    let text = d.model.text(&row.f);
                    let back = d.model.parse_expr(&text).unwrap();
                    assert!(expr::sub(&row.f, &back).is_zero(), "`{text}`");
                }
            }
        }
    }
}

#[test]
fn row_kinds_and_levels() {
    let d = derive(PENDULUM);
    let ovd0 = d.formulation("ovd0").unwrap();
    let levels: Vec<Option<u8>> = ovd0.rows.iter().map(|r| r.kind.level()).collect();
    assert_eq!(levels, [None, None, None, None, Some(0), Some(1), Some(2)]);
    assert!(matches!(
        ovd0.rows[6].kind,
        RowKind::Constraint { source: 0, .. }
    ));
    let _ = Sym::Time;
}

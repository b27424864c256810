//! Forward sensitivities of the pendulum against the exact ones
//! (`data/pendulum_sensitivities.csv`: the Jacobi-elliptic closed form
//! differentiated in g and l by mpmath at 60 digits, written by
//! `scripts/pendulum_sensitivities.py` — independent of this project's
//! solvers), issue 25 done-when 2.

use dae_core::sensitivity::{Sensitivities, SensitivityError};
use dae_core::system::DaeSystem;
use dae_solvers::init::{consistent, InitOptions};
use dae_solvers::{solver_by_name, Options, Problem};

fn repo(path: &str) -> String {
    let p = format!("{}/../{path}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

/// `(t, parameter, unknown, derivative)` rows of the reference.
fn exact() -> Vec<(f64, String, String, f64)> {
    repo("data/pendulum_sensitivities.csv")
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("t,"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse().unwrap(),
                f[1].into(),
                f[2].into(),
                f[4].parse().unwrap(),
            )
        })
        .collect()
}

/// The consistent start of the sensitivity system at the scene's release
/// (x = 1, y = 0, at rest; every sensitivity 0 before the projection).
fn start(sys: &dyn DaeSystem) -> Vec<f64> {
    let mut y0 = vec![0.0; sys.info().unknowns()];
    y0[0] = 1.0;
    consistent(sys, 0.0, &y0, &InitOptions::default())
        .expect("consistent start")
        .y
}

#[test]
fn initial_sensitivities_are_the_horizontal_release_at_every_length() {
    let model = Sensitivities::from_str(&repo("scenes/pendulum.dae"), &["g", "l"]).unwrap();
    for f in ["rcd0", "ggl1", "rcd1", "ori2"] {
        let sys = model.formulation(f).unwrap();
        let y = start(&sys);
        let name = |k: usize| sys.info().variables[k].name.clone();
        let at = |n: &str| y[(0..y.len()).find(|&k| name(k) == n).unwrap()];
        assert!(
            (at("dx/dl") - 1.0).abs() < 1e-12,
            "{f}: dx/dl = {}",
            at("dx/dl")
        );
        for n in [
            "dy/dl", "dv/dl", "dw/dl", "dx/dg", "dy/dg", "dv/dg", "dw/dg",
        ] {
            assert!(at(n).abs() < 1e-12, "{f}: {n} = {}", at(n));
        }
    }
}

#[test]
fn sensitivities_match_the_closed_form() {
    let model = Sensitivities::from_str(&repo("scenes/pendulum.dae"), &["g", "l"]).unwrap();
    let reference = exact();
    let tol = 1e-10;
    for solver in ["radau5", "bdf"] {
        for f in ["ggl1", "rcd0"] {
            let sys = model.formulation(f).unwrap();
            let y0 = start(&sys);
            let options = Options {
                output_times: vec![2.0, 4.0, 20.0],
                ..Options::with_tol(tol)
            };
            let problem = Problem {
                system: &sys,
                t0: 0.0,
                y0: &y0,
                t_end: 20.0,
            };
            let sol = solver_by_name(solver)
                .unwrap()
                .solve(&problem, &options)
                .unwrap();
            let index = |n: &str| {
                sys.info()
                    .variables
                    .iter()
                    .position(|v| v.name == n)
                    .unwrap()
            };
            for &t in &[2.0, 4.0, 20.0] {
                let k = sol.t.iter().position(|&s| s == t).unwrap();
                for p in ["g", "l"] {
                    let rows: Vec<_> = reference.iter().filter(|r| r.0 == t && r.1 == p).collect();
                    // At whole periods most derivatives are zero to 1e-9:
                    // compare against the largest one of the parameter.
                    let scale = rows.iter().map(|r| r.3.abs()).fold(0.0, f64::max);
                    for r in rows {
                        let got = sol.y[k][index(&format!("d{}/d{p}", r.2))];
                        let err = (got - r.3).abs() / scale;
                        assert!(
                            err < 1e-6,
                            "{solver}({f}) at t = {t}: d{}/d{p} = {got}, exact {} (rel. {err:.1e})",
                            r.2,
                            r.3
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn bad_requests_are_typed() {
    let src = repo("scenes/pendulum.dae");
    assert!(matches!(
        Sensitivities::from_str(&src, &["gravity"]),
        Err(SensitivityError::UnknownParameter { ref name, ref known }) if name == "gravity" && known.contains('g')
    ));
    assert!(matches!(
        Sensitivities::from_str(&src, &["g", "g"]),
        Err(SensitivityError::Duplicate { .. })
    ));
    let model = Sensitivities::from_str(&src, &["g"]).unwrap();
    for f in ["psi0", "mex0"] {
        assert!(
            matches!(
                model.formulation(f),
                Err(SensitivityError::Formulation { .. })
            ),
            "{f}"
        );
    }
    // m multiplies der(v): the leading matrix would depend on it.
    let model = Sensitivities::from_str(&src, &["m"]).unwrap();
    assert!(matches!(
        model.formulation("rcd0"),
        Err(SensitivityError::Formulation { .. })
    ));
}

//! `mex0`, the minimally extended formulation with dummy derivatives
//! (issue 23, done-when 2): every constraint level is kept as a row, so the
//! position and velocity residuals stay at the tolerance's level at every
//! accepted step; the dummies are chosen at run time and switch between
//! `x` and `y` during the pendulum's swings; on S01 it is accurate wherever
//! `rcd0` is, with `radau5`, `bdf` and `gauss`.

use dae::dae_core::dummy::DummyDerivatives;
use dae::dae_core::interp::InterpretedModel;
use dae::dae_core::system::{DaeSystem, Model};
use dae::dae_core::Derived;
use dae::dae_solvers::{init, solver_by_name, Options, Problem, SolveError, Tolerances};
use dae::inputs::inputs;
use dae::runner;
use dae::scene::Scene;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// The interpreted model of `scenes/<name>.dae` with its scene's
/// parameters, and the scene.
fn model(name: &str, scene: &str) -> (InterpretedModel, Scene) {
    let path = scenes_dir().join(format!("{name}.dae"));
    let text = std::fs::read_to_string(&path).unwrap();
    let derived = Derived::from_str(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut m = InterpretedModel::new(&derived);
    let scene = Scene::load(scenes_dir().join(format!("{scene}.toml"))).unwrap();
    for p in &scene.parameters {
        m.set_parameter(&p.name, p.value).unwrap();
    }
    (m, scene)
}

/// Integrate `mex0` of `name` with `solver` at `tol` over the scene's
/// horizon, and return the largest residual of each constraint level over
/// every accepted step and 4 000 output times, with the wrapper's switch count and the dummies it
/// chose at the start.
fn residuals(name: &str, scene: &str, solver: &str, tol: f64) -> (Vec<f64>, usize, Vec<String>) {
    try_residuals(name, scene, solver, tol)
        .unwrap_or_else(|e| panic!("{name}: {solver}(mex0) at {tol:e}: {e}"))
}

/// [`residuals`], the run's typed error returned.
fn try_residuals(
    name: &str,
    scene: &str,
    solver: &str,
    tol: f64,
) -> Result<(Vec<f64>, usize, Vec<String>), SolveError> {
    let (m, scene) = model(name, scene);
    let inner = m.system("mex0").unwrap();
    let sys = DummyDerivatives::new(inner).unwrap();
    let info = sys.info().clone();
    let mut y0 = vec![0.0; info.unknowns()];
    for v in &scene.initial {
        y0[info.variable(&v.name).unwrap()] = v.value;
    }
    let (t0, t_end) = (scene.time.start, scene.time.end);
    let start = init::consistent(&sys, t0, &y0, &init::InitOptions::default()).unwrap();
    let first = {
        // The choice at the consistent start.
        let mut e = nalgebra::DMatrix::zeros(info.equations(), info.unknowns());
        sys.leading(t0, &start.y, &mut e);
        sys.dummies()
    };
    // Over the whole horizon, not only at the step points: 4 000 output
    // times between them (several per step where the steps are longest:
    // gauss takes 266 on Andrews at 1e-7 and 1 324 on S01 at 1e-8).
    let samples: Vec<f64> = (0..=4000)
        .map(|i| t0 + (t_end - t0) * f64::from(i) / 4000.0)
        .collect();
    let options = Options {
        tol: Tolerances::uniform(tol),
        record_steps: true,
        output_times: samples,
        ..Options::default()
    };
    let problem = Problem {
        system: &sys,
        t0,
        y0: &start.y,
        t_end,
    };
    let sol = solver_by_name(solver).unwrap().solve(&problem, &options)?;
    assert!(!sol.steps.is_empty());
    let k = info.constraints.len();
    let levels = info.constraints.iter().map(|c| c.level).max().unwrap() as usize + 1;
    let mut worst = vec![0.0f64; levels];
    let mut g = vec![0.0; k];
    let points = sol.steps.iter().map(|(t, y)| (*t, y.as_slice()));
    let outputs = sol.t.iter().copied().zip(sol.y.iter().map(Vec::as_slice));
    for (t, y) in points.chain(outputs) {
        sys.constraints(t, y, &mut g);
        for (c, gi) in info.constraints.iter().zip(&g) {
            let l = c.level as usize;
            worst[l] = worst[l].max(gi.abs());
        }
    }
    Ok((worst, sys.switches(), first))
}

/// The pendulum over S01: positions and velocities on their constraints to
/// the tolerance's level at every step, and the dummies switching between
/// `x` and `y` (twice per swing; S01 holds about nine swings).
#[test]
fn pendulum_keeps_its_constraints_and_switches_dummies() {
    let tol = 1e-8;
    for solver in ["radau5", "bdf", "gauss"] {
        let (worst, switches, first) = residuals("pendulum", "s01", solver, tol);
        // Released horizontally: x is the dummy (∂g/∂y = 2y = 0 there).
        assert_eq!(first, ["x", "v"], "{solver}");
        // At the tolerance's level (see `mechanisms_keep_their_constraints`):
        // the velocity level `2xv + 2yw` with speeds up to 5.2 gives `bdf`
        // 14·tol.
        assert!(
            worst[0] <= 20.0 * tol && worst[1] <= 20.0 * tol,
            "{solver}: position/velocity residuals {worst:?} above 20·{tol:e}"
        );
        assert!(
            switches >= 20,
            "{solver}: the dummies switched {switches} times over S01"
        );
    }
}

/// The double and spherical pendulum and Andrews' squeezer: every
/// position and velocity residual at the tolerance's level at every step
/// and between the steps. (`gauss` on Andrews' squeezer: its collocation
/// polynomial missed the position constraint by 1.7e-5 between steps at
/// this tolerance until its dense output was projected as its end points
/// are, see `dae_solvers::gauss`.)
#[test]
fn mechanisms_keep_their_constraints() {
    let tol = 1e-7;
    let cases = [
        (
            "double_pendulum",
            "double_pendulum",
            &["radau5", "bdf", "gauss"][..],
        ),
        (
            "spherical_pendulum",
            "spherical_pendulum",
            &["radau5", "bdf", "gauss"][..],
        ),
        ("andrews", "andrews", &["radau5", "bdf", "gauss"][..]),
    ];
    for (name, scene, solvers) in cases {
        for &solver in solvers {
            let (worst, _, _) = residuals(name, scene, solver, tol);
            // "At the tolerance's level": the corrector stops when its
            // update is a fraction of the weighted tolerance (rtol·|y| +
            // atol per unknown), so a residual is that times the row's
            // sensitivity — the spherical pendulum's velocity level
            // `x u + y v + z w` with `bdf` reaches 11·tol at tol 1e-7
            // (`rcd0`, which drops the level, drifts to 4e-6 at 1e-8).
            assert!(
                worst[0] <= 20.0 * tol && worst[1] <= 20.0 * tol,
                "{name}: {solver}(mex0) position/velocity residuals {worst:?} above {tol:e}"
            );
        }
    }
}

/// Andrews' squeezer at the tight tolerances, where `gauss`'s Newton
/// iteration meets the problem's round-off (accelerations of 5·10⁵ beside
/// angles of 15): its increments stagnate near 10⁻⁶ weighted after a weak
/// first contraction (the predictor's error, corrected nonlinearly) and
/// strong later ones. Until the monitor looked at the strongest contraction
/// rather than the first, every attempt there was called divergent and the
/// run stopped at t ≈ 0.0204 (`newton_failure`, BENCHMARKS §11c). Every
/// solver reaches the end with the constraints at the tolerance's level —
/// but for radau5 at 1e-10, which sits on the round-off floor of `gaa`
/// near t = 0.0125 (its Newton increments stay at 0.31 of its tolerance
/// for every step from 1e-6 down to 1e-10): whether it passes is decided
/// by the last bits of the Newton norm. With DASSL's scaled sum it
/// finishes; with the plain sum radau5 takes since session 9 (BENCHMARKS
/// §12e) it stops with the typed `round_off_floor` naming `gaa`. Either
/// outcome is asserted there, nothing else.
#[test]
fn squeezer_at_tight_tolerances_keeps_its_constraints() {
    for tol in [1e-9, 1e-10] {
        for solver in ["radau5", "bdf", "gauss"] {
            let run = try_residuals("andrews", "andrews", solver, tol);
            if solver == "radau5" && tol == 1e-10 {
                if let Err(SolveError::RoundOffFloor { unknown, .. }) = &run {
                    assert_eq!(unknown, "gaa", "{run:?}");
                    continue;
                }
            }
            let (worst, _, _) =
                run.unwrap_or_else(|e| panic!("andrews: {solver}(mex0) at {tol:e}: {e}"));
            assert!(
                worst[0] <= 20.0 * tol && worst[1] <= 20.0 * tol,
                "andrews: {solver}(mex0) position/velocity residuals {worst:?} above 20·{tol:e}"
            );
        }
    }
}

/// On S01, `mex0` is accurate (err ≤ 100·tol) wherever `rcd0` is, with
/// `radau5`, `bdf` and `gauss`.
#[test]
fn s01_accurate_wherever_rcd0_is() {
    let scene = Scene::load(scenes_dir().join("s01.toml")).unwrap();
    let inputs = inputs(&scene).unwrap();
    let mut compared = 0;
    for solver in ["radau5", "bdf", "gauss"] {
        for tol in [1e-6, 1e-8, 1e-10] {
            let err = |f: &str| {
                let r = runner::run(&inputs.spec(&scene, solver, f, tol)).unwrap();
                assert_eq!(r.status, "ok", "{solver}({f}) at {tol:e}: {:?}", r.error);
                r.err.unwrap()
            };
            if err("rcd0") <= 100.0 * tol {
                compared += 1;
                let e = err("mex0");
                assert!(
                    e <= 100.0 * tol,
                    "{solver}(mex0) at {tol:e}: err {e:e} where rcd0 is accurate"
                );
            }
        }
    }
    // radau5 and gauss at every tolerance (bdf(rcd0) is accurate on S01
    // only at the loosest tolerances, if at all).
    assert!(
        compared >= 6,
        "only {compared} accurate rcd0 runs to compare"
    );
}

/// A model whose dynamics rows couple derivatives is refused with the
/// reason, by `dae derive` and by `Model::formulation`.
#[test]
fn coupled_derivatives_are_refused_with_the_reason() {
    let text = std::fs::read_to_string(scenes_dir().join("mna_cv_loop.dae")).unwrap();
    let d = Derived::from_str(&text).unwrap();
    assert!(d.formulation("mex0").is_none());
    let report = dae::dae_core::report::text(&d);
    assert!(
        report.contains("mex0  not offered: `mex0` needs each dynamics row to hold one derivative"),
        "{report}"
    );
    let m = InterpretedModel::new(&d);
    let err = m.formulation("mex0").map(|_| ()).unwrap_err();
    assert!(
        err.to_string()
            .contains("does not provide formulation `mex0`"),
        "{err}"
    );
}

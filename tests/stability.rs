//! The reduced stability map: the shipped extreme cases that finish in
//! seconds, two solvers, one tolerance. The full map is
//! `dae sweep --extremes` (EXTREMES.md).

use dae::stability::{self, Class, MapOptions, StabilityMap};
use std::path::{Path, PathBuf};

fn case(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/extremes")
        .join(name)
}

fn reduced(files: &[&str], max_steps: usize) -> StabilityMap {
    let files: Vec<PathBuf> = files.iter().map(|f| case(f)).collect();
    let opts = MapOptions {
        jobs: 2,
        max_steps,
        solvers: Some(vec!["radau5".into(), "bdf".into()]),
        tolerances: Some(vec![1e-5]),
        progress: false,
        verdict: stability::Verdict::Accuracy,
    };
    stability::build(&files, &opts).expect("the options are valid")
}

fn cell<'a>(map: &'a StabilityMap, scene: &str, solver: &str, f: &str) -> &'a Class {
    let case = map
        .cases
        .iter()
        .find(|c| c.scene.as_deref() == Some(scene))
        .unwrap_or_else(|| panic!("no case {scene}"));
    &case
        .cells
        .iter()
        .find(|c| c.solver == solver && c.formulation == f)
        .unwrap_or_else(|| panic!("no cell {solver}({f}) in {scene}"))
        .class
}

#[test]
fn every_case_is_a_typed_outcome_and_the_wrong_answers_are_flagged() {
    let map = reduced(
        &[
            "bad_huge.toml",
            "bad_nan.toml",
            "tolerance_below_floor.toml",
            "zero_mass.toml",
            "loop.toml",
            "release_179_99deg.toml",
            "g_over_l_1e6.toml",
            "inconsistent_velocity.toml",
        ],
        stability::MAP_MAX_STEPS,
    );
    // Bad values are refused when the scene is read, naming the field.
    for (file, field) in [
        ("bad_huge.toml", "initial.x"),
        ("bad_nan.toml", "initial.x"),
        ("tolerance_below_floor.toml", "sweep.tolerances"),
    ] {
        let c = map.cases.iter().find(|c| c.file.ends_with(file)).unwrap();
        let r = c.refused.as_ref().unwrap_or_else(|| panic!("{file} ran"));
        assert_eq!(r.stage, "scene", "{file}");
        assert!(r.message.contains(field), "{file}: {}", r.message);
        assert!(!r.message.contains('\n'), "one line: {}", r.message);
    }
    // m = 0: every run fails with a typed error at t = 0, none panics.
    let zero = map
        .cases
        .iter()
        .find(|c| c.scene.as_deref() == Some("X-m-0"))
        .unwrap();
    assert!(!zero.cells.is_empty());
    for c in zero.cells.iter().filter(|c| c.tol.is_some()) {
        assert!(
            matches!(&c.class, Class::Failed { kind, .. } if !kind.is_empty()),
            "{}({}): {:?}",
            c.solver,
            c.formulation,
            c.class
        );
    }
    // The loop over the top has an exact reference and radau5 meets it.
    assert_eq!(*cell(&map, "X-loop", "radau5", "rcd1"), Class::Accurate);
    // The confident wrong answers of the issue are flagged, not "ok".
    for f in ["rcd0", "ggl1", "psi0"] {
        assert_eq!(
            *cell(&map, "X-release-179_99", "bdf", f),
            Class::Inaccurate,
            "bdf({f}) at 179.99°"
        );
        assert_eq!(
            *cell(&map, "X-g/l-1e6", "bdf", f),
            Class::Inaccurate,
            "bdf({f}) at g/l = 1e6"
        );
    }
    // An inconsistent start is projected, and the run is marked as having
    // no reference.
    assert!(matches!(
        cell(&map, "X-inconsistent-1", "radau5", "rcd1"),
        Class::Unverified | Class::Suspect
    ));
    let counts = map.counts();
    assert_eq!(counts.refused_cases, 3);
    let applicable: usize = map
        .cases
        .iter()
        .map(|c| c.cells.iter().filter(|c| c.tol.is_some()).count())
        .sum();
    assert_eq!(counts.runs, applicable);
    assert!(counts.runs >= 4 * 2 * 6, "{counts:?}");
    // Every output is written, as one set.
    let dir = std::env::temp_dir().join(format!("dae-stability-{}", std::process::id()));
    let files = stability::write(&map, &dir, None).unwrap();
    assert_eq!(files.len(), 4);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("map.json")).unwrap()).unwrap();
    assert_eq!(json["counts"]["runs"], counts.runs);
    assert!(std::fs::metadata(dir.join("map.png")).unwrap().len() > 1000);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_run_is_bounded_and_says_where_it_stopped() {
    let map = reduced(&["release_90deg.toml"], 50);
    let case = &map.cases[0];
    assert!(case.refused.is_none());
    for c in case.cells.iter().filter(|c| c.tol.is_some()) {
        match c.class {
            Class::StepLimit { t } => assert!(t > 0.0 && t < 20.0, "{t}"),
            // bdf refuses the index-3 ori2 before a step (variable step,
            // core::policy::variable_step_index3).
            Class::Failed { ref kind, .. }
                if kind == "not_applicable" && c.solver == "bdf" && c.formulation == "ori2" => {}
            ref other => panic!("{}({}): {other:?}", c.solver, c.formulation),
        }
    }
    assert!(stability::text(&map).contains("step limit at t = "));
}

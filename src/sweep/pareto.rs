//! The speed/accuracy trade in two summaries.
//!
//! **Error measure.** Both summaries use `err`: the maximum over the check
//! times of the largest pointwise error of the differential unknowns
//! (`x, y, v, w` for the pendulum) — the accuracy a user can rely on at any
//! check time, comparable between scenes with one or a thousand check
//! times. (`err_sum` grows with the number of check times; it is used only
//! to compare with the paper.)
//!
//! **Eligible runs.** A run is eligible when it succeeded
//! (`status = "ok"`), has an error (the scene has a reference) that is
//! finite, and a finite integration time.
//!
//! **Pareto front.** An eligible run `a` is *beaten* by an eligible run `b`
//! when `b` is at least as fast and at least as accurate and strictly
//! better in one of the two: `b.tsim ≤ a.tsim ∧ b.err ≤ a.err ∧ (b.tsim <
//! a.tsim ∨ b.err < a.err)`. The front is the set of eligible runs that no
//! eligible run beats, sorted by increasing time (hence decreasing error).
//! Runs, not pairs: a pair appears once per tolerance on the front.
//!
//! **Targets.** For a target error `e`, the fastest eligible run with
//! `err ≤ e` (ties: the smaller error, then sweep order). That run is
//! always on the Pareto front.

use crate::runner::RunRecord;
use serde::Serialize;
use std::borrow::Borrow;

/// The target errors of the summary: 1e-3 … 1e-10.
pub const TARGETS: [f64; 8] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];

/// One run, reduced to what the trade needs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Point {
    /// Solver.
    pub solver: String,
    /// Formulation.
    pub formulation: String,
    /// Tolerance.
    pub tol: f64,
    /// Integration time in seconds.
    pub tsim_s: f64,
    /// `err` of the run.
    pub err: f64,
}

impl Point {
    /// `solver(formulation)`.
    pub fn pair(&self) -> String {
        format!("{}({})", self.solver, self.formulation)
    }
}

/// The eligible runs as points, in sweep order.
pub fn eligible<R: Borrow<RunRecord>>(runs: &[R]) -> Vec<Point> {
    runs.iter()
        .map(Borrow::borrow)
        .filter(|r| r.status == "ok" && r.tsim_s.is_finite())
        .filter_map(|r| {
            let err = r.err.filter(|e| e.is_finite())?;
            Some(Point {
                solver: r.solver.clone(),
                formulation: r.formulation.clone(),
                tol: r.tol,
                tsim_s: r.tsim_s,
                err,
            })
        })
        .collect()
}

/// Whether `b` beats `a` (see the module documentation).
pub fn beats(b: &Point, a: &Point) -> bool {
    b.tsim_s <= a.tsim_s && b.err <= a.err && (b.tsim_s < a.tsim_s || b.err < a.err)
}

/// The Pareto front of the runs, by increasing time.
pub fn pareto_front<R: Borrow<RunRecord>>(runs: &[R]) -> Vec<Point> {
    let pts = eligible(runs);
    let mut front: Vec<Point> = pts
        .iter()
        .filter(|a| !pts.iter().any(|b| beats(b, a)))
        .cloned()
        .collect();
    front.sort_by(|a, b| a.tsim_s.total_cmp(&b.tsim_s).then(a.err.total_cmp(&b.err)));
    front
}

/// The fastest run that met one target error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Target {
    /// The target error.
    pub target: f64,
    /// The fastest run with `err ≤ target`, if any.
    pub best: Option<Point>,
}

/// For each target error, the fastest run that met it.
pub fn targets<R: Borrow<RunRecord>>(runs: &[R], targets: &[f64]) -> Vec<Target> {
    let pts = eligible(runs);
    targets
        .iter()
        .map(|&target| {
            let best = pts
                .iter()
                .filter(|p| p.err <= target)
                .min_by(|a, b| a.tsim_s.total_cmp(&b.tsim_s).then(a.err.total_cmp(&b.err)))
                .cloned();
            Target { target, best }
        })
        .collect()
}

//! The speed/accuracy trade in two summaries, ranked by a rule that calls
//! runs closer in time than the timing resolution a tie.
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
//! **Timing resolution.** A timing cannot order two runs closer than its
//! resolution: `tsim_s`, the least CPU time of a run's timings, still moves
//! between two sweeps of the same grid (BENCHMARKS.md §8b), so two runs
//! 0.1 % apart came out in either order. Two times are **tied** when the
//! larger is at most [`TIME_RESOLUTION`] (5 %) above the smaller
//! ([`tied`]). Error and the work counters are deterministic (the same
//! steps and the same floating-point operations in every sweep), so they,
//! not the clock, decide between tied runs.
//!
//! **The pick among candidates** (used by both summaries). Of a set of
//! eligible runs: take the least time `t_min`; every run with `tsim_s ≤
//! t_min·(1 + TIME_RESOLUTION)` is tied with the fastest; of these the one
//! with the smallest `err` wins, then the fewest steps, then the fewest
//! residual evaluations, then the name (solver, formulation, tolerance).
//! The other tied runs are reported beside it.
//!
//! **Targets.** For a target error `e`, the pick among the eligible runs
//! with `err ≤ e`: the fastest run that met the target, or a more accurate
//! one that is not slower beyond the resolution.
//!
//! **Pareto front.** The runs that are the pick for some error level: for
//! every eligible run's `err` taken as a target, the pick among the runs
//! with `err` at most that. Listed by increasing time, hence not increasing
//! `err`: each front run is strictly faster than every more accurate one
//! (the order follows the error levels, so it needs no timing comparison
//! finer than the resolution). So every run that met a target is on the
//! front, and every eligible run is *covered* by a front run at least as
//! accurate and not slower than it beyond the resolution ([`covers`]). With
//! no resolution (`resolution = 0`) this is the classic Pareto front: the
//! runs that no run beats on both time and error (of runs equal in both,
//! one).
//!
//! **Ties on the front.** In terms of [`beats`] — `b` beats `a` when `b` is
//! not slower beyond the resolution and no less accurate, and strictly
//! better in one (faster beyond the resolution, or a smaller error; when
//! both tie, fewer steps, then fewer evaluations, then the name) — every
//! eligible run off the front is beaten. But "within the resolution" is not
//! transitive: in a chain `a`, `b`, `c` of runs each within the resolution
//! of the next, more accurate along the chain, with `c` slower than `a`
//! beyond it, `b` beats `a` and `c` beats `b`, yet nothing beats `a` but
//! `b`. The front then keeps `b` (the pick for `a`'s error: it ties `a`,
//! the fastest, and is more accurate) *and* `c` (the pick for its own),
//! whatever the order of the runs in the sweep. Such neighbours are within
//! the resolution of each other; the tables mark the slower of them `≈`
//! ([`tied`] between neighbours of the front).

use crate::runner::RunRecord;
use serde::Serialize;
use std::borrow::Borrow;
use std::cmp::Ordering;

/// The target errors of the summary: 1e-3 … 1e-10.
///
/// ```
/// assert_eq!(dae::sweep::pareto::TARGETS[0], 1e-3);
/// ```
pub const TARGETS: [f64; 8] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];

/// The relative timing resolution of the ranking: two times within 5 % of
/// each other are tied.
///
/// Why 5 %: between two sweeps of the same grid (BENCHMARKS.md §8b, the
/// least CPU time over at least 50 timings or 0.25 s of them, taken in
/// rounds), 22 of 27 runs moved by at most 3 %, and the pair that swapped
/// was 0.1–1.4 % apart; the resolution must exceed that. It must stay
/// below the differences that reflect work: the nearest runs of the grid
/// with different step counts were 4.6 % apart (2.06 vs 1.97 ms, 4850 vs
/// 4816 steps: tied at 5 %, hence decided by error) and 12–13 % (radau5 on
/// rcd1 and rcd0, 2607 vs 2952 steps: ordered). Runs timed only a few times
/// (over about 20 ms) moved by up to 20–27 % between sweeps; their order is
/// safe only when they are that far apart, which they were.
///
/// ```
/// use dae::sweep::pareto::{tied, TIME_RESOLUTION};
/// assert_eq!(TIME_RESOLUTION, 0.05);
/// assert!(tied(1.00e-3, 1.04e-3, TIME_RESOLUTION));
/// assert!(!tied(1.00e-3, 1.06e-3, TIME_RESOLUTION));
/// ```
pub const TIME_RESOLUTION: f64 = 0.05;

/// The target rule in one paragraph, as the page and `results.json` state
/// it (the resolution written out: 5 % is [`TIME_RESOLUTION`]).
///
/// ```
/// assert!(dae::sweep::pareto::TARGET_RULE.contains("5 %"));
/// ```
pub const TARGET_RULE: &str = "Timing resolution 5 %: two times within 5 % of each other are tied, since a \
     timing cannot order runs closer than that (a run's least CPU time moves by a few per cent between sweeps, \
     BENCHMARKS.md §8b). Fastest run per target error: of the successful runs with err <= target, take the least \
     time; every run within 5 % of it is tied; of those the smallest err wins, then the fewest steps, then the \
     fewest residual evaluations, then the name (solver, formulation, tolerance). The runs it was tied with are \
     listed beside it.";

/// The front rule in one paragraph, as the page and `results.json` state
/// it.
///
/// ```
/// assert!(dae::sweep::pareto::FRONT_RULE.contains("≈"));
/// ```
pub const FRONT_RULE: &str = "Pareto front: the runs the target rule picks for some error level (each \
     successful run's err taken as a target), by increasing time; each is strictly faster than every more \
     accurate one, every run that met a target is on it, and every successful run is matched by a front run \
     at least as accurate and at most 5 % slower. Without the resolution it is the classic front (runs no run \
     beats on both tsim and err). A front run within 5 % of the time of the one before it is marked ≈: the two \
     are ordered by their errors, not by the clock (a chain of runs each within 5 % of the next).";

/// Whether two times are tied at a relative `resolution`: the larger is at
/// most `resolution` above the smaller. A negative or NaN resolution is
/// taken as 0 (only equal times tie).
///
/// ```
/// use dae::sweep::pareto::tied;
/// assert!(tied(2.0, 2.1, 0.05) && tied(2.1, 2.0, 0.05));
/// assert!(!tied(2.0, 2.2, 0.05));
/// assert!(tied(2.0, 2.0, 0.0) && !tied(2.0, 2.0001, 0.0));
/// ```
pub fn tied(a: f64, b: f64, resolution: f64) -> bool {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    hi <= lo || hi <= lo * factor(resolution)
}

/// `1 + resolution`, with a negative or NaN resolution taken as 0.
fn factor(resolution: f64) -> f64 {
    if resolution > 0.0 {
        1.0 + resolution
    } else {
        1.0
    }
}

/// One run, reduced to what the ranking needs.
///
/// ```
/// use dae::sweep::pareto::Point;
/// let p = Point {
///     solver: "bdf".into(),
///     formulation: "rcd0".into(),
///     tol: 1e-8,
///     tsim_s: 1.97e-3,
///     err: 8.2e-5,
///     steps: 5918,
///     evals: 12000,
/// };
/// assert_eq!(p.label(), "bdf(rcd0) 1e-8");
/// ```
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
    /// Accepted steps (first tie-break after the error).
    pub steps: usize,
    /// Residual evaluations (second tie-break).
    pub evals: usize,
}

impl Point {
    /// `solver(formulation)`.
    ///
    /// ```
    /// # use dae::sweep::pareto::Point;
    /// # let p = Point { solver: "bdf".into(), formulation: "rcd0".into(), tol: 1e-8,
    /// #     tsim_s: 1e-3, err: 1e-4, steps: 1, evals: 1 };
    /// assert_eq!(p.pair(), "bdf(rcd0)");
    /// ```
    pub fn pair(&self) -> String {
        format!("{}({})", self.solver, self.formulation)
    }

    /// `solver(formulation) tol`, the tolerance as the tables write it.
    ///
    /// ```
    /// # use dae::sweep::pareto::Point;
    /// # let p = Point { solver: "radau5".into(), formulation: "rcd1".into(), tol: 1e-6,
    /// #     tsim_s: 1e-3, err: 1e-4, steps: 1, evals: 1 };
    /// assert_eq!(p.label(), "radau5(rcd1) 1e-6");
    /// ```
    pub fn label(&self) -> String {
        format!("{} {}", self.pair(), super::table::tol_label(self.tol))
    }

    /// The deterministic order between runs tied in time and error: fewer
    /// steps first, then fewer residual evaluations, then solver,
    /// formulation and tolerance.
    ///
    /// ```
    /// # use dae::sweep::pareto::Point;
    /// # let p = Point { solver: "bdf".into(), formulation: "rcd0".into(), tol: 1e-8,
    /// #     tsim_s: 1e-3, err: 1e-4, steps: 100, evals: 300 };
    /// let q = Point { steps: 90, ..p.clone() };
    /// assert!(q.tie_break(&p).is_lt());
    /// ```
    pub fn tie_break(&self, other: &Point) -> Ordering {
        self.steps
            .cmp(&other.steps)
            .then(self.evals.cmp(&other.evals))
            .then_with(|| self.solver.cmp(&other.solver))
            .then_with(|| self.formulation.cmp(&other.formulation))
            .then(self.tol.total_cmp(&other.tol))
    }

    /// The order in which tied runs are preferred: smaller `err`, then
    /// [`Point::tie_break`]. Independent of time.
    ///
    /// ```
    /// # use dae::sweep::pareto::Point;
    /// # let p = Point { solver: "bdf".into(), formulation: "rcd0".into(), tol: 1e-8,
    /// #     tsim_s: 1e-3, err: 1e-4, steps: 100, evals: 300 };
    /// let q = Point { err: 1e-5, steps: 500, ..p.clone() };
    /// assert!(q.preference(&p).is_lt());
    /// ```
    pub fn preference(&self, other: &Point) -> Ordering {
        self.err
            .total_cmp(&other.err)
            .then_with(|| self.tie_break(other))
    }
}

/// The eligible runs as points, in sweep order.
///
/// ```
/// use dae::sweep::pareto::eligible;
/// assert!(eligible::<dae::runner::RunRecord>(&[]).is_empty());
/// ```
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
                steps: r.stats.steps,
                evals: r.stats.residual_evals,
            })
        })
        .collect()
}

/// Whether `b` beats `a` at a relative timing `resolution`: `b` is not
/// slower beyond the resolution and no less accurate, and strictly better
/// in one — faster beyond the resolution, or a smaller error, or (both
/// tied) first by [`Point::tie_break`]. Not transitive (see the module
/// documentation).
///
/// ```
/// use dae::sweep::pareto::{beats, Point, TIME_RESOLUTION};
/// let a = Point { solver: "bdf".into(), formulation: "rcd1".into(), tol: 1e-6,
///     tsim_s: 1.966e-3, err: 5.4e-3, steps: 4816, evals: 9000 };
/// let b = Point { formulation: "rcd0".into(), tol: 1e-8, tsim_s: 1.969e-3, err: 8.2e-5,
///     steps: 5918, ..a.clone() };
/// // 0.15 % slower but 66 times more accurate: b wins the tie.
/// assert!(beats(&b, &a, TIME_RESOLUTION) && !beats(&a, &b, TIME_RESOLUTION));
/// ```
pub fn beats(b: &Point, a: &Point, resolution: f64) -> bool {
    let f = factor(resolution);
    let not_slower = b.tsim_s <= a.tsim_s || b.tsim_s <= a.tsim_s * f;
    let faster = b.tsim_s * f < a.tsim_s;
    not_slower
        && b.err <= a.err
        && (faster || b.err < a.err || (b.err == a.err && b.tie_break(a).is_lt()))
}

/// Whether `b` covers `a` at a relative timing `resolution`: at least as
/// accurate and not slower beyond the resolution (a run covers itself).
/// Every eligible run is covered by a run of the Pareto front.
///
/// ```
/// use dae::sweep::pareto::{covers, Point};
/// let a = Point { solver: "bdf".into(), formulation: "rcd1".into(), tol: 1e-6,
///     tsim_s: 1.0, err: 1e-3, steps: 10, evals: 20 };
/// let b = Point { tsim_s: 1.04, err: 1e-4, ..a.clone() };
/// assert!(covers(&b, &a, 0.05) && !covers(&a, &b, 0.05) && !covers(&b, &a, 0.0));
/// ```
pub fn covers(b: &Point, a: &Point, resolution: f64) -> bool {
    b.err <= a.err && (b.tsim_s <= a.tsim_s || b.tsim_s <= a.tsim_s * factor(resolution))
}

/// The pick among candidates already sorted by [`Point::preference`]: the
/// first one tied in time with the fastest. `None` for no candidates.
fn pick<'a>(sorted: &[&'a Point], resolution: f64) -> Option<&'a Point> {
    let t_min = sorted.iter().map(|p| p.tsim_s).min_by(f64::total_cmp)?;
    sorted
        .iter()
        .copied()
        .find(|p| tied(p.tsim_s, t_min, resolution))
}

/// The points sorted by [`Point::preference`] (most accurate first).
fn by_preference(points: &[Point]) -> Vec<&Point> {
    let mut v: Vec<&Point> = points.iter().collect();
    v.sort_by(|a, b| a.preference(b));
    v
}

/// The Pareto front at [`TIME_RESOLUTION`], by decreasing error
/// (increasing time); see the module documentation.
///
/// ```
/// use dae::sweep::pareto::pareto_front;
/// assert!(pareto_front::<dae::runner::RunRecord>(&[]).is_empty());
/// ```
pub fn pareto_front<R: Borrow<RunRecord>>(runs: &[R]) -> Vec<Point> {
    front_of(&eligible(runs), TIME_RESOLUTION)
}

/// The Pareto front of eligible points at a relative timing `resolution`
/// (0: the classic front), by decreasing error; the same for any order of
/// `points`.
///
/// ```
/// use dae::sweep::pareto::{front_of, Point};
/// let p = |name: &str, t: f64, err: f64| Point { solver: name.into(),
///     formulation: "f".into(), tol: 1e-6, tsim_s: t, err, steps: 10, evals: 20 };
/// // b is 1 % slower than a and ten times more accurate: a tie that b wins.
/// let runs = [p("a", 1.00, 1e-3), p("b", 1.01, 1e-4), p("c", 2.0, 1e-6)];
/// let names = |f: Vec<Point>| f.into_iter().map(|p| p.solver).collect::<Vec<_>>();
/// assert_eq!(names(front_of(&runs, 0.05)), ["b", "c"]);
/// assert_eq!(names(front_of(&runs, 0.0)), ["a", "b", "c"]);
/// ```
pub fn front_of(points: &[Point], resolution: f64) -> Vec<Point> {
    let sorted = by_preference(points);
    let mut front: Vec<&Point> = Vec::new();
    // The pick for each error level: the candidates are a prefix of the
    // sorted points, ending with the last point of that error.
    for (i, p) in sorted.iter().enumerate() {
        if sorted.get(i + 1).is_some_and(|q| q.err == p.err) {
            continue;
        }
        if let Some(best) = pick(&sorted[..=i], resolution) {
            if !front.iter().any(|f| std::ptr::eq(*f, best)) {
                front.push(best);
            }
        }
    }
    // Picked from the most accurate level up: reverse for decreasing error.
    front.into_iter().rev().cloned().collect()
}

/// The run picked for one target error.
///
/// ```
/// use dae::sweep::pareto::Target;
/// let t = Target { target: 1e-6, best: None, tied: Vec::new() };
/// assert!(t.best.is_none());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Target {
    /// The target error.
    pub target: f64,
    /// The fastest run with `err ≤ target`, or a more accurate one tied
    /// with it in time; `None` when no run met the target.
    pub best: Option<Point>,
    /// The other runs that met the target and are tied in time with the
    /// fastest of them, in order of preference (the ones `best` won
    /// against on error, steps, evaluations or name).
    pub tied: Vec<Point>,
}

/// For each target error, the pick at [`TIME_RESOLUTION`] (see the module
/// documentation).
///
/// ```
/// use dae::sweep::pareto::targets;
/// let t = targets::<dae::runner::RunRecord>(&[], &[1e-6]);
/// assert_eq!((t.len(), t[0].best.is_none()), (1, true));
/// ```
pub fn targets<R: Borrow<RunRecord>>(runs: &[R], targets: &[f64]) -> Vec<Target> {
    targets_of(&eligible(runs), targets, TIME_RESOLUTION)
}

/// For each target error, the pick among the eligible `points` that met it
/// at a relative timing `resolution`; the same for any order of `points`.
///
/// ```
/// use dae::sweep::pareto::{targets_of, Point};
/// let p = |name: &str, t: f64, err: f64| Point { solver: name.into(),
///     formulation: "f".into(), tol: 1e-6, tsim_s: t, err, steps: 10, evals: 20 };
/// let runs = [p("a", 1.00, 1e-3), p("b", 1.01, 1e-4), p("c", 2.0, 1e-6)];
/// let t = targets_of(&runs, &[1e-2], 0.05);
/// let best = t[0].best.as_ref().map(|b| b.solver.as_str());
/// assert_eq!((best, t[0].tied[0].solver.as_str()), (Some("b"), "a"));
/// ```
pub fn targets_of(points: &[Point], targets: &[f64], resolution: f64) -> Vec<Target> {
    let sorted = by_preference(points);
    targets
        .iter()
        .map(|&target| {
            let met = sorted.partition_point(|p| p.err <= target);
            let candidates = &sorted[..met];
            let best = pick(candidates, resolution);
            let tied_with = match best {
                Some(b) => {
                    let t_min = candidates.iter().map(|p| p.tsim_s).fold(b.tsim_s, f64::min);
                    candidates
                        .iter()
                        .filter(|p| !std::ptr::eq(**p, b) && tied(p.tsim_s, t_min, resolution))
                        .map(|p| (*p).clone())
                        .collect()
                }
                None => Vec::new(),
            };
            Target {
                target,
                best: best.cloned(),
                tied: tied_with,
            }
        })
        .collect()
}

//! The step loop every method runs in.
//!
//! A method implements [`Method`]: it starts at `t₀` (consistent values
//! given), and [`Method::step`] advances by one *accepted* step, retrying
//! with smaller steps (or lower orders) inside, within the budgets of
//! [`super::control`]; it knows its dense output on the last step. The
//! driver does the rest, the same for every method: it steps until the
//! method reaches `t_end`, fills the output grid of [`super::output`] by
//! dense output as each step covers its times, records the step points when
//! asked, and assembles the [`Solution`] with the method's statistics.
//!
//! A method that needs starting values from another run — BDF with a
//! constant step takes its first `k − 1` values from an adaptive run — is
//! two runs of one integration: [`solve_with_startup`] runs the start-up
//! method, hands its values at the times the second run asks for to the
//! function that builds that run, and reports both as one solution.

use super::output::OutputGrid;
use crate::{Options, Solution, SolveError, Stats};

/// One method family's stepping, as the driver sees it.
pub(crate) trait Method {
    /// Current time: `t₀` before the first step, then the end of the last
    /// accepted step.
    fn t(&self) -> f64;
    /// The solution at [`Method::t`].
    fn y(&self) -> &[f64];
    /// Dense output of the last accepted step at `tau` (inside it) into
    /// `out`.
    fn dense(&self, tau: f64, out: &mut [f64]);
    /// Whether the end of the horizon has been reached.
    fn finished(&self) -> bool;
    /// Take one accepted step (failures retried inside; a typed error when
    /// a budget is exhausted).
    fn step(&mut self) -> Result<(), SolveError>;
    /// Work counters so far.
    fn stats(&self) -> Stats;
}

/// Step `method` to the end, calling `after_step` after every accepted
/// step.
pub(crate) fn drive<M: Method>(
    method: &mut M,
    mut after_step: impl FnMut(&M),
) -> Result<(), SolveError> {
    while !method.finished() {
        method.step()?;
        after_step(method);
    }
    Ok(())
}

/// What the driver reports of an integration: the output grid and, when
/// [`Options::record_steps`] asks for them, the step points.
struct Report {
    grid: OutputGrid,
    steps: Vec<(f64, Vec<f64>)>,
    record: bool,
}

impl Report {
    /// The output grid of `options` on `[t0, t_end]`, reporting `y0` at the
    /// times not after `t0`.
    fn new(options: &Options, t0: f64, t_end: f64, y0: &[f64]) -> Self {
        let mut grid = OutputGrid::new(&options.output_times, t0, t_end, y0.len());
        grid.start(t0, y0);
        Report {
            grid,
            steps: Vec::new(),
            record: options.record_steps,
        }
    }

    /// Fill the output grid up to the time of `method` by its dense output.
    fn fill<M: Method>(&mut self, method: &M) {
        self.grid
            .emit(method.t(), |tau, out| method.dense(tau, out));
    }

    /// After an accepted step of `method`: fill the grid, and record the
    /// step point if asked.
    fn step<M: Method>(&mut self, method: &M) {
        self.fill(method);
        if self.record {
            self.steps.push((method.t(), method.y().to_vec()));
        }
    }

    /// The [`Solution`] with the work counters `stats`.
    fn finish(self, stats: Stats) -> Solution {
        let (t, y) = self.grid.finish();
        Solution {
            t,
            y,
            steps: self.steps,
            stats,
        }
    }
}

/// Run `method` from `t0` (its current values) to `t_end` with the output
/// rule of [`OutputGrid`] and [`Options::record_steps`], and return the
/// [`Solution`].
pub(crate) fn solve<M: Method>(
    method: &mut M,
    options: &Options,
    t0: f64,
    t_end: f64,
) -> Result<Solution, SolveError> {
    let mut report = Report::new(options, t0, t_end, method.y());
    drive(method, |m| report.step(m))?;
    Ok(report.finish(method.stats()))
}

/// Run `startup` from `t0` (its current values) to its end, then the
/// method `build` makes of it and of its values at the `handover` times
/// (ascending, in the start-up run's horizon) on to `t_end` — or nothing,
/// when the start-up run has covered the horizon — as one integration.
/// Each run fills the output grid where it steps; the step points recorded
/// for the start-up run are the handover points, not its own steps; the
/// work counters are summed.
pub(crate) fn solve_with_startup<A: Method, B: Method>(
    startup: &mut A,
    handover: impl IntoIterator<Item = f64>,
    build: impl FnOnce(&A, &[Vec<f64>]) -> Option<B>,
    options: &Options,
    t0: f64,
    t_end: f64,
) -> Result<Solution, SolveError> {
    let mut report = Report::new(options, t0, t_end, startup.y());
    let mut start = OutputGrid::at(startup.y().len(), handover);
    drive(startup, |m| {
        start.emit(m.t(), |tau, out| m.dense(tau, out));
        report.fill(m);
    })?;
    if report.record {
        let points = start.times().iter().zip(start.values());
        report.steps.extend(points.map(|(t, y)| (*t, y.clone())));
    }
    let mut stats = startup.stats();
    if let Some(mut run) = build(startup, start.values()) {
        drive(&mut run, |m| report.step(m))?;
        stats += run.stats();
    }
    Ok(report.finish(stats))
}

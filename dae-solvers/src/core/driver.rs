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

/// What the driver does after each accepted step: fill the output grid up
/// to the new time by dense output, and record the step point if asked.
pub(crate) fn report<'a, M: Method>(
    grid: &'a mut OutputGrid,
    steps: &'a mut Vec<(f64, Vec<f64>)>,
    record: bool,
) -> impl FnMut(&M) + 'a {
    move |m: &M| {
        grid.emit(m.t(), |tau, out| m.dense(tau, out));
        if record {
            steps.push((m.t(), m.y().to_vec()));
        }
    }
}

/// Run `method` from `t0` (values `y0`) to `t_end` with the output rule of
/// [`OutputGrid`] and [`Options::record_steps`], and return the
/// [`Solution`].
pub(crate) fn solve<M: Method>(
    method: &mut M,
    options: &Options,
    t0: f64,
    t_end: f64,
) -> Result<Solution, SolveError> {
    let mut grid = OutputGrid::new(&options.output_times, t0, t_end, method.y().len());
    grid.start(t0, method.y());
    let mut steps = Vec::new();
    drive(method, report(&mut grid, &mut steps, options.record_steps))?;
    let (t, y) = grid.finish();
    Ok(Solution {
        t,
        y,
        steps,
        stats: method.stats(),
    })
}

//! The step loop every method runs in.
//!
//! A method implements [`Method`]: it starts at `t₀` (consistent values
//! given), and [`Method::step`] advances by one *accepted* step, retrying
//! with smaller steps (or lower orders) inside, within the budgets of
//! [`super::control`]; it knows its dense output on the last step. The
//! driver does the rest, the same for every method: the public stepper
//! [`crate::Integrator`] steps it, and after every accepted step [`Record`]
//! fills the output grid of [`super::output`] by dense output as the step
//! covers its times, records the step points when asked, and keeps the
//! step's dense output when asked; at the end it assembles the
//! [`Solution`] with the method's statistics. [`crate::Solver::solve`] is
//! that stepper run to `t_end`.
//!
//! A method that needs starting values from another run — BDF with a
//! constant step takes its first `k − 1` values from an adaptive run — is
//! two runs of one integration: [`Startup`] is one [`Method`] made of the
//! start-up method and the run that its values at the handover times
//! build, so the stepper and the records see one integration.
//!
//! A run that stops is reported from here too, once for every method:
//! [`crate::Integrator::run`] returns with the error the method's work
//! counters and its time and values ([`Method::t`], [`Method::y`]: the last
//! accepted step), so a method keeps its counters current through failed
//! attempts and leaves `t` and `y` at the last accepted step until it
//! accepts another.
//!
//! The contract on the leading matrix: a formulation whose
//! `FormulationInfo::constant_leading` is false gets `leading(t, y, e)`
//! evaluated at the start of the step attempts and before every iteration
//! matrix, at the point the attempt or the matrix is for — the numerical
//! selector (`dae_core::selector`) and run-time wrappers that re-choose a
//! selection do it there, so a method that cached `E` across steps would
//! integrate with a stale selection. Where each method keeps it: Radau IIA,
//! Gauss and odradau at every step point (the start of the attempts from
//! it, where the iteration matrix is also formed); bdf and odbdf with every
//! iteration matrix, at the predictor; mebdf and idec take only an `E`
//! that is constant (once the constraint rows that carry derivatives are
//! made algebraic) and refuse the others
//! (`NotApplicable::LeadingMatrixNotConstant`).

use super::output::OutputGrid;
use crate::solution::DenseOutput;
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
    /// The value reported at an output time `tau` inside the last accepted
    /// step: the dense output, unless the method corrects it (`gauss`
    /// projects it onto its algebraic rows as it projects its end points;
    /// the stored [`DenseOutput`] and event location keep the polynomial).
    fn output(&self, tau: f64, out: &mut [f64]) {
        self.dense(tau, out);
    }
    /// An upper bound of the degree of the dense output polynomial of
    /// every step of this run (what [`DenseOutput`] samples).
    fn dense_degree(&self) -> usize;
    /// Whether the end of the horizon has been reached.
    fn finished(&self) -> bool;
    /// Take one accepted step (failures retried inside; a typed error when
    /// a budget is exhausted).
    fn step(&mut self) -> Result<(), SolveError>;
    /// Work counters so far.
    fn stats(&self) -> Stats;
    /// The step points ([`Options::record_steps`]) the step just accepted
    /// adds: `(t, y)` of the step, unless the method says otherwise.
    fn step_points(&self, push: &mut dyn FnMut(f64, &[f64])) {
        push(self.t(), self.y());
    }
}

/// Step `method` to the end, calling `after_step` after every accepted
/// step.
pub(crate) fn drive<M: Method + ?Sized>(
    method: &mut M,
    mut after_step: impl FnMut(&M),
) -> Result<(), SolveError> {
    while !method.finished() {
        method.step()?;
        after_step(method);
    }
    Ok(())
}

/// What the driver keeps of an integration: the output grid, the step
/// points when [`Options::record_steps`] asks for them, and the dense
/// output when [`Options::dense_output`] does.
pub(crate) struct Record {
    grid: OutputGrid,
    steps: Vec<(f64, Vec<f64>)>,
    record_steps: bool,
    dense: Option<DenseOutput>,
}

impl Record {
    /// The output grid of `options` on `[t0, t_end]`, reporting `y0` at the
    /// times not after `t0`; dense output of degree `degree` if asked.
    pub(crate) fn new(options: &Options, t0: f64, t_end: f64, y0: &[f64], degree: usize) -> Self {
        let mut grid = OutputGrid::new(&options.output_times, t0, t_end, y0.len());
        grid.start(t0, y0);
        Record {
            grid,
            steps: Vec::new(),
            record_steps: options.record_steps,
            dense: options
                .dense_output
                .then(|| DenseOutput::new(degree, t0, y0)),
        }
    }

    /// After an accepted step of `method`: fill the output grid up to its
    /// time by its dense output, record the step points if asked, keep the
    /// step's dense output if asked.
    pub(crate) fn after_step<M: Method + ?Sized>(&mut self, method: &M) {
        self.grid
            .emit(method.t(), |tau, out| method.output(tau, out));
        if self.record_steps {
            let steps = &mut self.steps;
            method.step_points(&mut |t, y| steps.push((t, y.to_vec())));
        }
        if let Some(dense) = &mut self.dense {
            dense.push(method.t(), method.y(), |tau, out| method.dense(tau, out));
        }
    }

    /// After an accepted step of `method` cut at an event at `t` (inside
    /// the step) with the dense-output value `y` there: what
    /// [`Record::after_step`] does, for the step up to `t`.
    pub(crate) fn after_step_until<M: Method + ?Sized>(&mut self, method: &M, t: f64, y: &[f64]) {
        self.grid.emit(t, |tau, out| method.output(tau, out));
        if self.record_steps {
            self.steps.push((t, y.to_vec()));
        }
        if let Some(dense) = &mut self.dense {
            dense.push(t, y, |tau, out| method.dense(tau, out));
        }
    }

    /// The dense output kept so far.
    pub(crate) fn dense(&self) -> Option<&DenseOutput> {
        self.dense.as_ref()
    }

    /// The [`Solution`] with the work counters `stats` and the names of the
    /// unknowns.
    pub(crate) fn finish(self, stats: Stats, names: Vec<String>) -> Solution {
        let (t, y) = self.grid.finish();
        Solution {
            t,
            y,
            steps: self.steps,
            stats,
            names,
            dense: self.dense,
            events: Vec::new(),
        }
    }

    /// The [`Solution`] of a run cut at an event at `t`: the output times
    /// before `t`, then — when the run stops there (`stop`) — the event
    /// point `(t, y)` itself as the last point; after a reset the times
    /// from `t` on are the restarted run's.
    pub(crate) fn finish_cut(
        self,
        stats: Stats,
        names: Vec<String>,
        t_cut: f64,
        y_cut: &[f64],
        stop: bool,
    ) -> Solution {
        let (mut t, mut y) = self.grid.finish_before(t_cut);
        if stop {
            t.push(t_cut);
            y.push(y_cut.to_vec());
        }
        Solution {
            t,
            y,
            steps: self.steps,
            stats,
            names,
            dense: self.dense,
            events: Vec::new(),
        }
    }
}

/// Two runs of one integration as one [`Method`]: `startup` from `t₀` (its
/// current values) to its end, then the method `build` makes of it and of
/// its values at the `handover` times (ascending, in the start-up run's
/// horizon) on to `t_end` — or nothing, when the start-up run has covered
/// the horizon. Each run's steps are steps of the integration (output grid,
/// dense output); the step points recorded for the start-up run are the
/// handover points, not its own steps; the work counters are summed.
pub(crate) struct Startup<A, B, F> {
    startup: A,
    handover: OutputGrid,
    build: Option<F>,
    run: Option<B>,
    /// The run has taken a step: its dense output is the last step's.
    run_started: bool,
    degree: usize,
}

impl<A: Method, B: Method, F: FnOnce(&A, &[Vec<f64>]) -> Option<B>> Startup<A, B, F> {
    /// The integration of `startup`, then of what `build` makes of it; the
    /// dense output of both is of degree at most `degree`.
    pub(crate) fn new(
        startup: A,
        handover: impl IntoIterator<Item = f64>,
        build: F,
        degree: usize,
    ) -> Self {
        let n = startup.y().len();
        Startup {
            handover: OutputGrid::at(n, handover),
            startup,
            build: Some(build),
            run: None,
            run_started: false,
            degree,
        }
    }

    /// The method whose last step is the integration's last step.
    fn current(&self) -> &dyn Method {
        match &self.run {
            Some(run) if self.run_started => run,
            _ => &self.startup,
        }
    }
}

impl<A: Method, B: Method, F: FnOnce(&A, &[Vec<f64>]) -> Option<B>> Method for Startup<A, B, F> {
    fn t(&self) -> f64 {
        self.current().t()
    }
    fn y(&self) -> &[f64] {
        self.current().y()
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        self.current().dense(tau, out)
    }
    fn output(&self, tau: f64, out: &mut [f64]) {
        self.current().output(tau, out)
    }
    fn dense_degree(&self) -> usize {
        self.degree
    }
    fn finished(&self) -> bool {
        self.startup.finished() && self.build.is_none() && self.run.as_ref().is_none_or(B::finished)
    }
    fn step(&mut self) -> Result<(), SolveError> {
        if let Some(run) = &mut self.run {
            run.step()?;
            self.run_started = true;
            return Ok(());
        }
        let startup = &mut self.startup;
        startup.step()?;
        self.handover
            .emit(startup.t(), |tau, out| startup.dense(tau, out));
        if startup.finished() {
            if let Some(build) = self.build.take() {
                self.run = build(startup, self.handover.values());
            }
        }
        Ok(())
    }
    fn stats(&self) -> Stats {
        let mut stats = self.startup.stats();
        if let Some(run) = &self.run {
            stats += run.stats();
        }
        stats
    }
    fn step_points(&self, push: &mut dyn FnMut(f64, &[f64])) {
        if self.run_started {
            return self.current().step_points(push);
        }
        // The start-up run's last step: the handover points.
        if self.startup.finished() {
            for (t, y) in self.handover.times().iter().zip(self.handover.values()) {
                push(*t, y);
            }
        }
    }
}

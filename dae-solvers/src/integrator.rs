//! The step-by-step form of an integration: [`Integrator`], from
//! [`Solver::integrator`](crate::Solver::integrator).

use crate::core::driver::{Method, Record};
use crate::core::events::{Cut, Events};
use crate::{Event, Options, Problem, Solution, SolveError, Stats, Stopped};

/// Where a run restarts after a reset: the time, the consistent values,
/// and the events (positions) that fired there.
pub(crate) type Restart = (f64, Vec<f64>, Vec<usize>);

/// What one call of [`Integrator::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepOutcome {
    /// One step was accepted; it ends at `t`, before `t_end`.
    Accepted {
        /// End of the step.
        t: f64,
    },
    /// The integration is at `t_end`: the step just taken reached it, or
    /// it had been reached before and nothing was done.
    Finished {
        /// `t_end`.
        t: f64,
    },
    /// An event that stops the run or resets the state
    /// ([`crate::EventAction`]) cut the step just taken at `t`: the
    /// integration ends there ([`Integrator::t`] is `t`,
    /// [`Integrator::y`] the dense-output value there). After a reset,
    /// [`Integrator::restart`] gives the consistent values to go on from;
    /// [`Solver::run`](crate::Solver::run) does so with a fresh stepper.
    Event {
        /// Time of the event.
        t: f64,
    },
}

/// An integration in progress, advanced one accepted step at a time
/// ([`Integrator::step`]) or up to a time ([`Integrator::advance_to`]) —
/// the one-step mode of IDA and the `step!` of DifferentialEquations.jl.
/// [`Solver::solve`](crate::Solver::solve) is this run to `t_end`: stepping
/// to the end gives the same values and statistics, and
/// [`Integrator::finish`] the same [`Solution`].
///
/// ```
/// use dae::dae_solvers::{init, radau5::Radau5, StepOutcome};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().rcd1();
/// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
/// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 2.0 };
/// let options = Options::with_tol(1e-8);
/// let mut integ = Radau5.integrator(&problem, &options)?;
/// // Up to a time: the dense output there, never a step past t_end.
/// let x = integ.advance_to(1.0)?[0];
/// assert!((x + 1.0).abs() < 1e-6); // half a period: x = −1
/// assert!(integ.t() >= 1.0);
/// // One step at a time.
/// let mut steps = 0;
/// while let StepOutcome::Accepted { t } = integ.step()? {
///     assert!(t < 2.0);
///     steps += 1;
/// }
/// assert_eq!(integ.t(), 2.0);
/// let sol = integ.finish()?;
/// assert_eq!(sol, Radau5.solve(&problem, &options)?); // the same integration
/// assert!(steps < sol.stats.steps);
/// # Ok::<(), SolveError>(())
/// ```
pub struct Integrator<'a> {
    method: Box<dyn Method + 'a>,
    record: Record,
    names: Vec<String>,
    t0: f64,
    t_end: f64,
    /// Initial values (reported at `t₀`).
    y0: Vec<f64>,
    /// Start of the last accepted step (`t₀` before the first).
    t_prev: f64,
    /// The error a step ended with: every later call returns it.
    failed: Option<SolveError>,
    /// The value [`Integrator::advance_to`] returns.
    out: Vec<f64>,
    /// The event service, when the model has events.
    events: Option<Events<'a>>,
    /// The events located so far.
    log: Vec<Event>,
    /// The step cut at a stop or reset: the integration ends there.
    cut: Option<Cut>,
}

impl<'a> Integrator<'a> {
    /// The stepper of `method`, started at `problem`'s `t₀`, with the
    /// output rules of `options`.
    pub(crate) fn new(
        method: Box<dyn Method + 'a>,
        problem: &Problem<'a>,
        options: &Options,
    ) -> Self {
        let y0 = method.y().to_vec();
        // The rules were checked with the problem (`Problem::check`).
        let (events, failed) = match Events::new(problem.system, options, problem.t0, &y0) {
            Ok(events) => (events, None),
            Err(e) => (None, Some(e)),
        };
        let record = Record::new(
            options,
            problem.t0,
            problem.t_end,
            &y0,
            method.dense_degree(),
        );
        let names = problem
            .system
            .info()
            .variables
            .iter()
            .map(|v| v.name.clone())
            .collect();
        Integrator {
            record,
            names,
            t0: problem.t0,
            t_end: problem.t_end,
            t_prev: problem.t0,
            failed,
            out: vec![0.0; y0.len()],
            y0,
            method,
            events,
            log: Vec::new(),
            cut: None,
        }
    }

    /// Watch the events at positions `fired` only once they have left zero:
    /// a run restarted at their root after a reset.
    pub(crate) fn mask_events(&mut self, fired: &[usize]) {
        if let Some(events) = &mut self.events {
            events.mask(fired);
        }
    }

    /// The events located so far, in time order ([`crate::Event`]).
    pub fn events(&self) -> &[Event] {
        &self.log
    }

    /// After a reset event ended the integration
    /// ([`StepOutcome::Event`]): the time and the consistent values to
    /// restart from, which [`Solver::run`](crate::Solver::run) does with a
    /// fresh stepper. `None` otherwise.
    pub fn restart(&self) -> Option<(f64, &[f64])> {
        let cut = self.cut.as_ref()?;
        Some((cut.t, cut.restart.as_deref()?))
    }

    /// Current time: `t₀`, then the end of the last accepted step (or the
    /// event that cut it, [`StepOutcome::Event`]).
    pub fn t(&self) -> f64 {
        match &self.cut {
            Some(cut) => cut.t,
            None => self.method.t(),
        }
    }

    /// The solution at [`Integrator::t`].
    pub fn y(&self) -> &[f64] {
        match &self.cut {
            Some(cut) => &cut.y,
            None => self.method.y(),
        }
    }

    /// The horizon `[t₀, t_end]`.
    pub fn horizon(&self) -> (f64, f64) {
        (self.t0, self.t_end)
    }

    /// Names of the unknowns, in the order of [`Integrator::y`].
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Work counters so far.
    pub fn stats(&self) -> Stats {
        self.method.stats()
    }

    /// Whether `t_end` has been reached, or an event ended the run.
    pub fn finished(&self) -> bool {
        self.cut.is_some() || self.method.finished()
    }

    /// Take one accepted step (rejected attempts are retried inside, as in
    /// [`Solver::solve`](crate::Solver::solve)). After `t_end` it does
    /// nothing and says [`StepOutcome::Finished`]; after a failure it
    /// returns the same error again.
    pub fn step(&mut self) -> Result<StepOutcome, SolveError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        if let Some(cut) = &self.cut {
            return Ok(StepOutcome::Event { t: cut.t });
        }
        if !self.method.finished() {
            let t_prev = self.method.t();
            if let Err(e) = self.method.step() {
                self.failed = Some(e.clone());
                return Err(e);
            }
            self.t_prev = t_prev;
            let cut = match &mut self.events {
                Some(events) => match events.after_step(&*self.method, t_prev, &mut self.log) {
                    Ok(cut) => cut,
                    Err(e) => {
                        self.failed = Some(e.clone());
                        return Err(e);
                    }
                },
                None => None,
            };
            if let Some(cut) = cut {
                self.record.after_step_until(&*self.method, cut.t, &cut.y);
                let t = cut.t;
                self.cut = Some(cut);
                return Ok(StepOutcome::Event { t });
            }
            self.record.after_step(&*self.method);
        }
        let t = self.method.t();
        Ok(if self.method.finished() {
            StepOutcome::Finished { t }
        } else {
            StepOutcome::Accepted { t }
        })
    }

    /// Step until the integration covers `t`, and return the solution at
    /// `t` by the dense output of the step that covers it (the value
    /// [`Solution::y`] has at an output time `t`). Steps are never
    /// shortened for `t` and never go past `t_end`.
    ///
    /// A time already passed is answered from the last step, or from the
    /// recorded dense output ([`Options::dense_output`]); without it, a
    /// time before the start of the last step is [`SolveError::OutOfReach`],
    /// as is any time outside `[t₀, t_end]`, or after an event that ended
    /// the run.
    pub fn advance_to(&mut self, t: f64) -> Result<&[f64], SolveError> {
        let to = self.t_end;
        let reach = |from: f64| SolveError::OutOfReach { t, from, to };
        if !(t >= self.t0 && t <= self.t_end) {
            return Err(reach(self.t0));
        }
        while self.t() < t && !self.finished() {
            self.step()?;
        }
        if t > self.t() {
            return Err(SolveError::OutOfReach {
                t,
                from: self.t0,
                to: self.t(),
            });
        }
        if t == self.t0 {
            self.out.copy_from_slice(&self.y0);
        } else if t > self.t_prev {
            self.method.output(t, &mut self.out);
        } else if let Some(dense) = self.record.dense() {
            dense
                .at_into(t, &mut self.out)
                .map_err(|_| reach(self.t0))?;
        } else if t == self.t_prev {
            // The start of the last step.
            self.method.output(t, &mut self.out);
        } else {
            return Err(reach(self.t_prev));
        }
        Ok(&self.out)
    }

    /// Run to `t_end` and return the [`Solution`]: the output times of
    /// [`Options::output_times`], the step points and dense output when
    /// asked, and the work counters — what
    /// [`Solver::solve`](crate::Solver::solve) returns, unless a reset
    /// event ([`EventAction::Reset`](crate::EventAction::Reset)) fires: one
    /// stepper integrates up to the reset and stops there, while
    /// `Solver::solve` starts a new stepper from the reset values and goes
    /// on to `t_end`.
    pub fn finish(self) -> Result<Solution, SolveError> {
        self.run().map_err(|stopped| stopped.error)
    }

    /// Run to `t_end` as [`Integrator::finish`] does, and when the run stops
    /// before it, return with the error the work done until then: the work
    /// counters (the failed attempts included) and the time and values of
    /// the last accepted step ([`Stopped`]) — what
    /// [`Solver::run`](crate::Solver::run) returns.
    ///
    /// ```
    /// use dae::dae_solvers::radau5::Radau5;
    /// use dae::models::builtin::Pendulum;
    /// use dae::prelude::*;
    ///
    /// let sys = Pendulum::default().rcd0();
    /// let y0 = [1.0, 0.0, 0.0, 0.0, 0.0];
    /// let problem = Problem { system: &sys, t0: 0.0, y0: &y0, t_end: 20.0 };
    /// let options = Options { max_steps: 30, ..Options::with_tol(1e-8) };
    /// let stopped = Radau5.integrator(&problem, &options)?.run().unwrap_err();
    /// assert!(matches!(stopped.error, SolveError::StepLimit { max_steps: 30, .. }));
    /// // Thirty attempts allowed: the accepted ones are counted.
    /// assert!(stopped.stats.steps > 0 && stopped.stats.steps <= 30);
    /// assert!(stopped.t > 0.0 && stopped.t < 20.0);
    /// assert_eq!(stopped.y.len(), 5);
    /// # Ok::<(), SolveError>(())
    /// ```
    pub fn run(mut self) -> Result<Solution, Box<Stopped>> {
        loop {
            match self.step() {
                Ok(StepOutcome::Accepted { .. }) => {}
                Ok(StepOutcome::Finished { .. } | StepOutcome::Event { .. }) => break,
                Err(error) => {
                    return Err(Box::new(Stopped {
                        error,
                        stats: self.method.stats(),
                        t: self.t(),
                        y: self.y().to_vec(),
                    }))
                }
            }
        }
        let stats = self.method.stats();
        let mut solution = match &self.cut {
            Some(cut) => {
                let stop = cut.restart.is_none();
                self.record
                    .finish_cut(stats, self.names, cut.t, &cut.y, stop)
            }
            None => self.record.finish(stats, self.names),
        };
        solution.events = self.log;
        Ok(solution)
    }

    /// [`Integrator::run`], and the restart a reset asks for: the time,
    /// the consistent values and the events to mask there.
    pub(crate) fn run_segment(mut self) -> Result<(Solution, Option<Restart>), Box<Stopped>> {
        // Step to the end or the cut (an error is returned again by `run`).
        while let Ok(StepOutcome::Accepted { .. }) = self.step() {}
        let restart = self.cut.as_ref().and_then(|cut| {
            let y = cut.restart.as_ref()?;
            Some((cut.t, y.clone(), cut.fired.clone()))
        });
        self.run().map(|solution| (solution, restart))
    }
}

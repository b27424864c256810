//! Events: the zero crossings of the model's event functions
//! ([`DaeSystem::events`], a model's `events { … }` section), located along
//! the solution for every method alike.
//!
//! After every accepted step `[t_{n−1}, t_n]` the driver evaluates the
//! event functions at `t_n`. A function that changed sign in a direction
//! its [`EventSpec`] admits has a root in the step: it is located on the
//! method's own dense output of that step (its `Method::dense`) by the
//! Illinois variant of regula falsi (the bracketing secant method of
//! DASRT and IDA, Dahlquist & Björck §6.2.2), to a bracket of four
//! rounding units of `t`; the reported time is the bracket's end where the
//! function has its new sign (or is zero). The earliest root of a step that
//! stops the run or resets the state wins: the step is cut there, and
//! every event within `100 ε (|t| + |h|)` of it (IDA's rule) is reported
//! with it, as happening at one time.
//!
//! * [`EventAction::Record`]: reported in [`crate::Solution::events`], the
//!   integration goes on.
//! * [`EventAction::Stop`]: the run ends at the event; the solution's last
//!   point is the event point (the dense-output value there).
//! * [`EventAction::Reset`]: the named unknowns get new values at the event
//!   (`w = −0.8 w`: [`Reset::Scale`]), the start is made consistent again
//!   by the consistent initialisation ([`crate::init::consistent`]:
//!   projection onto the constraint chain, the algebraic unknowns
//!   recomputed; reported in [`Event::reset`]), and
//!   [`crate::Solver::run`] restarts the integration there with a fresh
//!   instance of the method.
//!
//! A function that is zero where a run starts or restarts (the one that
//! fired the reset, typically) is watched only once it has left zero: at
//! the end of a step where it is non-zero, its sign is taken as the new
//! reference (IDA's rule for a root at the initial time). A crossing within
//! the first step after the restart of the function that just fired is
//! therefore not seen.

use super::driver::Method;
use crate::{init, Options, SolveError};
use dae_core::system::{DaeSystem, VarKind};
use serde::Serialize;

/// Which sign changes of an event function count ([`EventSpec::direction`]).
///
/// ```
/// use dae_solvers::{Crossing, Direction};
///
/// assert!(Direction::Both.admits(Crossing::Rising));
/// assert!(!Direction::Falling.admits(Crossing::Rising));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Both ways (the default).
    #[default]
    Both,
    /// From negative to non-negative.
    Rising,
    /// From positive to non-positive.
    Falling,
}

impl Direction {
    /// Whether a crossing `c` counts.
    pub fn admits(self, c: Crossing) -> bool {
        match self {
            Direction::Both => true,
            Direction::Rising => c == Crossing::Rising,
            Direction::Falling => c == Crossing::Falling,
        }
    }

    /// `"both"`, `"rising"` or `"falling"`.
    ///
    /// ```
    /// assert_eq!(dae_solvers::Direction::Rising.name(), "rising");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Direction::Both => "both",
            Direction::Rising => "rising",
            Direction::Falling => "falling",
        }
    }
}

/// The way an event function crossed zero ([`Event::direction`]).
///
/// ```
/// assert_eq!(dae_solvers::Crossing::Falling.name(), "falling");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Crossing {
    /// From negative to non-negative.
    Rising,
    /// From positive to non-positive.
    Falling,
}

impl Crossing {
    /// `"rising"` or `"falling"`.
    pub fn name(self) -> &'static str {
        match self {
            Crossing::Rising => "rising",
            Crossing::Falling => "falling",
        }
    }
}

/// The new value of one unknown at a reset ([`EventAction::Reset`]).
///
/// ```
/// use dae_solvers::Reset;
///
/// assert_eq!(Reset::Scale(-0.8).apply(2.0), -1.6); // restitution
/// assert_eq!(Reset::Value(0.0).apply(2.0), 0.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reset {
    /// `u = c · u` (an impact with restitution: `c = −e`).
    Scale(f64),
    /// `u = c`.
    Value(f64),
}

impl Reset {
    /// The new value of an unknown whose value was `u`.
    pub fn apply(self, u: f64) -> f64 {
        match self {
            Reset::Scale(c) => c * u,
            Reset::Value(c) => c,
        }
    }
}

/// What an event does ([`EventSpec::action`]).
///
/// ```
/// use dae_solvers::{EventAction, Reset};
///
/// let bounce = EventAction::Reset(vec![("v".into(), Reset::Scale(-0.8)), ("w".into(), Reset::Scale(-0.8))]);
/// assert_eq!(bounce.kind(), "reset");
/// assert_eq!(EventAction::default(), EventAction::Record);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventAction {
    /// Report it and go on (every event of the model not named in
    /// [`Options::events`]).
    #[default]
    Record,
    /// End the run at the event.
    Stop,
    /// New values for the named unknowns, made consistent again, and a
    /// restart there.
    Reset(Vec<(String, Reset)>),
}

impl EventAction {
    /// `"record"`, `"stop"` or `"reset"`.
    pub fn kind(&self) -> &'static str {
        match self {
            EventAction::Record => "record",
            EventAction::Stop => "stop",
            EventAction::Reset(_) => "reset",
        }
    }
}

/// How one of the model's events is treated ([`Options::events`]).
///
/// ```
/// use dae_solvers::{Direction, EventAction, EventSpec, Options, Reset};
///
/// let options = Options {
///     events: vec![
///         EventSpec::stop("ground"),
///         EventSpec::reset("wall", [("v", Reset::Scale(-0.8))]).direction(Direction::Falling),
///     ],
///     ..Options::with_tol(1e-8)
/// };
/// assert_eq!(options.events[1].action.kind(), "reset");
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EventSpec {
    /// The event function's name in the model's `events { … }`.
    pub name: String,
    /// Which sign changes count.
    pub direction: Direction,
    /// What the event does.
    pub action: EventAction,
}

impl EventSpec {
    /// Report the event (both directions).
    pub fn record(name: impl Into<String>) -> Self {
        EventSpec {
            name: name.into(),
            direction: Direction::Both,
            action: EventAction::Record,
        }
    }

    /// End the run at the event (both directions).
    pub fn stop(name: impl Into<String>) -> Self {
        EventSpec {
            action: EventAction::Stop,
            ..EventSpec::record(name)
        }
    }

    /// Reset the named unknowns at the event (both directions).
    pub fn reset<S: Into<String>>(
        name: impl Into<String>,
        assignments: impl IntoIterator<Item = (S, Reset)>,
    ) -> Self {
        EventSpec {
            action: EventAction::Reset(
                assignments
                    .into_iter()
                    .map(|(u, r)| (u.into(), r))
                    .collect(),
            ),
            ..EventSpec::record(name)
        }
    }

    /// The same with `direction`.
    pub fn direction(self, direction: Direction) -> Self {
        EventSpec { direction, ..self }
    }
}

/// What a reset did ([`Event::reset`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResetReport {
    /// The values the reset rules made (before the projection).
    pub assigned: Vec<f64>,
    /// The consistent values the integration restarts from.
    pub y: Vec<f64>,
    /// The largest change the projection made to a differential unknown,
    /// `max_i |y_i − assigned_i|` (the algebraic unknowns are recomputed
    /// from the constraints: a multiplier changes with the speed).
    pub moved: f64,
    /// Gauss–Newton iterations of the projection.
    pub projection_iterations: usize,
}

/// One located event ([`crate::Solution::events`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Event {
    /// The event function's name.
    pub name: String,
    /// Its position in the model's events ([`DaeSystem::event_names`]).
    #[serde(skip)]
    pub index: usize,
    /// Time of the crossing.
    pub t: f64,
    /// Which way the function crossed.
    pub direction: Crossing,
    /// What it did: `"record"`, `"stop"` or `"reset"`.
    pub action: &'static str,
    /// The solution at `t` (dense output; before a reset).
    #[serde(skip)]
    pub y: Vec<f64>,
    /// For a reset: the values assigned and the consistent restart values.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reset: Option<ResetReport>,
}

/// The largest number of restarts one run makes ([`crate::Solver::run`]):
/// a chattering or Zeno reset ends in [`SolveError::TooManyResets`].
pub const MAX_RESETS: usize = 100_000;

/// An event function's action, resolved to positions.
#[derive(Clone, Debug)]
enum Act {
    Record,
    Stop,
    Reset(Vec<(usize, Reset)>),
}

/// A step that ends in a stop or reset: it is cut at `t`.
#[derive(Clone, Debug)]
pub(crate) struct Cut {
    /// Time of the event(s).
    pub t: f64,
    /// The dense-output value there.
    pub y: Vec<f64>,
    /// For a reset: the consistent values to restart from.
    pub restart: Option<Vec<f64>>,
    /// The events (positions) that fire at `t`: watched only once they
    /// have left zero after the restart.
    pub fired: Vec<usize>,
}

/// The event service of one run: the model's event functions, the
/// options' rules for them, and their values at the last step point.
pub(crate) struct Events<'a> {
    system: &'a dyn DaeSystem,
    names: Vec<String>,
    direction: Vec<Direction>,
    act: Vec<Act>,
    /// Values at the start of the next step (the last step point).
    left: Vec<f64>,
    /// Watched only once non-zero at a step end.
    masked: Vec<bool>,
    right: Vec<f64>,
    g: Vec<f64>,
    y: Vec<f64>,
}

impl<'a> Events<'a> {
    /// The service for `system`'s events under `options`, started at
    /// `(t0, y0)`; `None` when the model has no events. A rule naming an
    /// event the model does not have, or a reset naming an unknown that
    /// is not one, is a typed error.
    pub(crate) fn new(
        system: &'a dyn DaeSystem,
        options: &Options,
        t0: f64,
        y0: &[f64],
    ) -> Result<Option<Self>, SolveError> {
        let names = system.event_names().to_vec();
        let k = names.len();
        let mut direction = vec![Direction::Both; k];
        let mut act: Vec<Act> = (0..k).map(|_| Act::Record).collect();
        let unknowns: Vec<String> = system
            .info()
            .variables
            .iter()
            .map(|v| v.name.clone())
            .collect();
        for spec in &options.events {
            let Some(i) = names.iter().position(|n| *n == spec.name) else {
                return Err(SolveError::UnknownEvent {
                    name: spec.name.clone(),
                    suggestion: dae_core::names::did_you_mean(&spec.name, &names)
                        .map(str::to_string),
                    known: names.clone(),
                });
            };
            direction[i] = spec.direction;
            act[i] = match &spec.action {
                EventAction::Record => Act::Record,
                EventAction::Stop => Act::Stop,
                EventAction::Reset(rules) => {
                    let mut resolved = Vec::with_capacity(rules.len());
                    for (u, r) in rules {
                        let Some(j) = unknowns.iter().position(|n| n == u) else {
                            return Err(SolveError::UnknownResetTarget {
                                event: spec.name.clone(),
                                name: u.clone(),
                                suggestion: dae_core::names::did_you_mean(u, &unknowns)
                                    .map(str::to_string),
                                known: unknowns.clone(),
                            });
                        };
                        resolved.push((j, *r));
                    }
                    Act::Reset(resolved)
                }
            };
        }
        if k == 0 {
            return Ok(None);
        }
        let mut left = vec![0.0; k];
        system.events(t0, y0, &mut left);
        Ok(Some(Events {
            system,
            masked: left.iter().map(|&g| g == 0.0).collect(),
            names,
            direction,
            act,
            left,
            right: vec![0.0; k],
            g: vec![0.0; k],
            y: vec![0.0; y0.len()],
        }))
    }

    /// Watch the events `fired` only once they have left zero (after a
    /// restart at their root).
    pub(crate) fn mask(&mut self, fired: &[usize]) {
        for &i in fired {
            if let Some(m) = self.masked.get_mut(i) {
                *m = true;
            }
        }
    }

    /// Event function `i` on the dense output of `method`'s last step.
    fn at(&mut self, method: &dyn Method, t: f64, i: usize) -> f64 {
        method.dense(t, &mut self.y);
        self.system.events(t, &self.y, &mut self.g);
        self.g[i]
    }

    /// After `method` accepted the step from `t_prev`: the events of the
    /// step, in time order, appended to `log`, and the cut when one stops
    /// the run or resets the state (the events after it are not reported).
    pub(crate) fn after_step(
        &mut self,
        method: &dyn Method,
        t_prev: f64,
        log: &mut Vec<Event>,
    ) -> Result<Option<Cut>, SolveError> {
        let t_n = method.t();
        self.system.events(t_n, method.y(), &mut self.right);
        let mut found: Vec<(f64, usize, Crossing)> = Vec::new();
        for i in 0..self.left.len() {
            let (a, b) = (self.left[i], self.right[i]);
            if self.masked[i] {
                continue;
            }
            let crossing = if a < 0.0 && b >= 0.0 {
                Crossing::Rising
            } else if a > 0.0 && b <= 0.0 {
                Crossing::Falling
            } else {
                continue;
            };
            if !self.direction[i].admits(crossing) {
                continue;
            }
            let t = self.locate(method, i, t_prev, a, t_n, b);
            found.push((t, i, crossing));
        }
        found.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let together = 100.0 * f64::EPSILON * (t_n.abs() + (t_n - t_prev).abs());
        let cut_at = found
            .iter()
            .find(|(_, i, _)| !matches!(self.act[*i], Act::Record))
            .map(|(t, _, _)| *t);
        let mut cut: Option<Cut> = None;
        for &(t, i, crossing) in &found {
            if let Some(tc) = cut_at {
                if t > tc + together {
                    break;
                }
            }
            let mut y = vec![0.0; self.y.len()];
            if t == t_n {
                y.copy_from_slice(method.y());
            } else {
                method.dense(t, &mut y);
            }
            log.push(Event {
                name: self.names[i].clone(),
                index: i,
                t,
                direction: crossing,
                action: match self.act[i] {
                    Act::Record => "record",
                    Act::Stop => "stop",
                    Act::Reset(_) => "reset",
                },
                y: y.clone(),
                reset: None,
            });
            if let Some(tc) = cut_at {
                if t + together >= tc {
                    let c = cut.get_or_insert_with(|| Cut {
                        t: tc,
                        y: y.clone(),
                        restart: None,
                        fired: Vec::new(),
                    });
                    c.fired.push(i);
                }
            }
        }
        let Some(mut cut) = cut else {
            // No cut: the step end is the next step's start.
            for i in 0..self.left.len() {
                let b = self.right[i];
                if self.masked[i] {
                    self.masked[i] = b == 0.0;
                } else if b == 0.0 {
                    // A root at the step end, reported: watched again
                    // once it has left zero.
                    self.masked[i] = true;
                }
                self.left[i] = b;
            }
            return Ok(None);
        };
        // The resets of every event at the cut, in the order of the model.
        let first = log.len() - cut.fired.len();
        let mut assigned = cut.y.clone();
        let mut resets = false;
        for &i in &cut.fired {
            if let Act::Reset(rules) = &self.act[i] {
                resets = true;
                for &(j, r) in rules {
                    assigned[j] = r.apply(assigned[j]);
                }
            }
        }
        let stops = cut.fired.iter().any(|&i| matches!(self.act[i], Act::Stop));
        if resets && !stops {
            let name = cut
                .fired
                .iter()
                .find(|&&i| matches!(self.act[i], Act::Reset(_)))
                .map(|&i| self.names[i].clone())
                .unwrap_or_default();
            let fail = |source: SolveError| SolveError::ResetInconsistent {
                event: name.clone(),
                t: cut.t,
                source: Box::new(source),
            };
            if assigned.iter().any(|v| !v.is_finite()) {
                return Err(fail(SolveError::NonFinite {
                    t: cut.t,
                    what: "values a reset assigned",
                }));
            }
            let consistent =
                init::consistent(self.system, cut.t, &assigned, &init::InitOptions::default())
                    .map_err(fail)?;
            let info = self.system.info();
            let moved = consistent
                .y
                .iter()
                .zip(&assigned)
                .zip(&info.variables)
                .filter(|(_, v)| v.kind == VarKind::Differential)
                .map(|((a, b), _)| (a - b).abs())
                .fold(0.0, f64::max);
            let report = ResetReport {
                assigned,
                y: consistent.y.clone(),
                moved,
                projection_iterations: consistent.report.projection_iterations,
            };
            for e in &mut log[first..] {
                if e.action == "reset" {
                    e.reset = Some(report.clone());
                }
            }
            cut.restart = Some(consistent.y);
        }
        Ok(Some(cut))
    }

    /// The root of event function `i` in `[a, b]` (`ga`, `gb` of opposite
    /// signs, `gb` possibly zero) on `method`'s dense output, by the
    /// Illinois method: regula falsi whose retained end's value is halved
    /// when the same end is kept twice, with a bisection step whenever the
    /// secant point falls outside the bracket, until the bracket is four
    /// rounding units of `t` wide. Returns the end where the function has
    /// its new sign (or is zero).
    fn locate(&mut self, method: &dyn Method, i: usize, a: f64, ga: f64, b: f64, gb: f64) -> f64 {
        let (mut lo, mut glo, mut hi, mut ghi) = (a, ga, b, gb);
        // Which end was kept last: −1 the left, +1 the right.
        let mut kept = 0;
        // Enough for bisection alone to reach round-off from any bracket.
        for _ in 0..200 {
            if ghi == 0.0 {
                break;
            }
            let width = hi - lo;
            if width <= 4.0 * f64::EPSILON * lo.abs().max(hi.abs()) {
                break;
            }
            let mut c = hi - ghi * width / (ghi - glo);
            if !(c > lo && c < hi) {
                c = lo + 0.5 * width;
            }
            if !(c > lo && c < hi) {
                break; // no float between the ends
            }
            let gc = self.at(method, c, i);
            if gc == 0.0 || gc.signum() == ghi.signum() {
                hi = c;
                ghi = gc;
                if kept == -1 {
                    glo *= 0.5;
                }
                kept = -1;
            } else {
                lo = c;
                glo = gc;
                if kept == 1 {
                    ghi *= 0.5;
                }
                kept = 1;
            }
        }
        hi
    }
}

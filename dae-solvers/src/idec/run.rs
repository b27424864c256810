//! The IDeC integrator as the driver sees it: one accepted interval per
//! [`Method::step`], constant steps (the seed's scheme) or error-controlled
//! ones.

use super::sweep::Sweep;
use super::{Idec, FAC, RATIO_MAX, RATIO_MIN};
use crate::core::attempt::{self, Attempts, Outcome, Policy, Retry, Steps};
use crate::core::control::{self, Failure};
use crate::core::driver::Method;
use crate::core::eliminate::Formulation;
use crate::core::weights::Weights;
use crate::{Options, Problem, SolveError, Stats};

/// State of one IDeC integration.
pub(super) struct Integrator<'a> {
    sys: Formulation<'a>,
    /// Unknowns `N`, degree `m`, corrections `J`.
    n: usize,
    m: usize,
    corrections: usize,
    t0: f64,
    t_end: f64,
    /// The interval workspace.
    pub(super) sweep: Sweep,
    weights: Weights,
    stats: Stats,
    /// The attempt loop's state (its steps are intervals of `m` Euler
    /// steps).
    steps: Steps,
    /// Constant Euler step, if any.
    fixed: Option<f64>,
    /// Intervals of the constant step accepted so far: their end is
    /// `t₀ + count · m h`, not a running sum (which drifts by round-off
    /// over the 10⁵ intervals of a long run and then makes the last
    /// interval look shorter than `m h`, a restart).
    fixed_count: u64,
    /// End of the last accepted interval and the best value there.
    t: f64,
    y: Vec<f64>,
    /// Euler step of the next attempt.
    h: f64,
    /// Start and Euler step of the last accepted interval, and the best
    /// level at its nodes (dense output).
    t_prev: f64,
    h_prev: f64,
    dense_nodes: Vec<f64>,
    /// Scratch for the error estimate.
    diff: Vec<f64>,
    /// The next interval reaches `t_end`; `t_end` reached; the Jacobian
    /// at `t` is evaluated; the last attempt was rejected.
    last: bool,
    done: bool,
    have_jacobian: bool,
    reject: bool,
}

impl Method for Integrator<'_> {
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        let theta = (tau - self.t_prev) / self.h_prev;
        let n = self.n;
        let nodes = |l: usize| &self.dense_nodes[l * n..(l + 1) * n];
        self.sweep.nodes.evaluate(theta, nodes, out);
    }
    fn dense_degree(&self) -> usize {
        self.m
    }
    fn finished(&self) -> bool {
        self.done
    }
    fn step(&mut self) -> Result<(), SolveError> {
        attempt::step(self)
    }
    fn stats(&self) -> Stats {
        self.stats
    }
}

impl Attempts for Integrator<'_> {
    fn steps(&mut self) -> &mut Steps {
        &mut self.steps
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.stats
    }
    /// The interval `m h` is the loop's step.
    fn point(&self) -> (f64, f64) {
        (self.t, self.m as f64 * self.h)
    }
    fn set_step(&mut self, interval: f64, last: bool) {
        // An interval that differs from the current one by round-off only
        // (the last, brought to `t_end`) keeps its step: a constant step
        // keeps its factorisation and carries its levels over.
        let round_off = 100.0 * f64::EPSILON * self.t.abs().max(self.t_end.abs());
        let lands = last && (interval - self.m as f64 * self.h).abs() <= round_off;
        if !lands {
            self.h = interval / self.m as f64;
        }
        self.last = last;
    }
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        match self.fixed {
            Some(_) => self.attempt_fixed(),
            None => self.attempt_adaptive(),
        }
    }
}

impl<'a> Integrator<'a> {
    /// The integrator of `problem` with `idec`'s parameters at `t₀`: `E`
    /// evaluated, buffers allocated, the first step chosen.
    pub(super) fn new(
        idec: &Idec,
        sys: Formulation<'a>,
        problem: &Problem<'_>,
        options: &Options,
    ) -> Result<Self, SolveError> {
        let info = sys.info();
        let n = info.unknowns();
        let (m, corrections) = (idec.m, idec.j);
        let span = problem.t_end - problem.t0;
        let mut sweep = Sweep::new(info, corrections, m);
        // `E` is constant in `t` and `y` (`eliminate::constant_leading`):
        // evaluated once, at the start.
        sys.leading(problem.t0, problem.y0, &mut sweep.matrix.lead);
        if sweep.matrix.lead.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                t: problem.t0,
                what: "leading matrix",
            });
        }
        sweep.restart_at(problem.y0);
        // Constant steps carry every level over the whole horizon: its
        // running sums are compensated (`Sweep::compensated`).
        sweep.compensated = options.fixed_step.is_some();
        // Error control samples the defect at the end of each Euler step
        // (module documentation, "Variable steps").
        sweep.at_end = options.fixed_step.is_none();
        // Error control takes index 1 only: no index scaling.
        let weights = Weights::new(&options.tol, |_| 1.0, vec![true; n], vec![0; n]);
        let h_max = options.h_max.unwrap_or(span).min(span / m as f64);
        let steps = Steps::new(
            Policy::HALVE,
            options.max_steps,
            problem.t_end,
            span,
            m as f64 * h_max,
            options.fixed_step.is_some(),
        );
        let h = match options.fixed_step {
            Some(h) => h,
            None => control::first_step(options.h0, h_max, problem.t0, span),
        };
        Ok(Integrator {
            sys: sys.clone(),
            n,
            m,
            corrections,
            t0: problem.t0,
            t_end: problem.t_end,
            sweep,
            weights,
            stats: Stats::default(),
            steps,
            fixed: options.fixed_step,
            fixed_count: 0,
            t: problem.t0,
            y: problem.y0.to_vec(),
            h,
            t_prev: problem.t0,
            h_prev: h,
            dense_nodes: vec![0.0; (m + 1) * n],
            diff: vec![0.0; n],
            last: false,
            done: false,
            have_jacobian: false,
            reject: false,
        })
    }

    /// `J = ∂f/∂y` at `(t, y)`, counted.
    fn jacobian(&mut self, t: f64) -> Result<(), SolveError> {
        let matrix = &mut self.sweep.matrix;
        if matrix.jacobian(&*self.sys, &mut self.stats, t, &self.y) {
            Ok(())
        } else {
            Err(SolveError::NonFinite {
                t,
                what: "Jacobian",
            })
        }
    }

    /// Factorise `E − hJ` (unless it is for this `h` and Jacobian) and run
    /// one interval from `t`.
    fn interval(&mut self, t: f64, h: f64) -> Result<(), Failure> {
        self.sweep.factor(&mut self.stats, h)?;
        self.sweep.run(&*self.sys, &mut self.stats, t, h)
    }

    /// Record the interval just computed as accepted.
    fn accept(&mut self, t: f64, h: f64) {
        self.stats.steps += self.m;
        self.t_prev = t;
        self.h_prev = h;
        let best = self.corrections;
        for k in 0..=self.m {
            let dst = &mut self.dense_nodes[k * self.n..(k + 1) * self.n];
            dst.copy_from_slice(self.sweep.node(best, k));
        }
        self.y.copy_from_slice(self.sweep.node(best, self.m));
        self.t = if self.last {
            self.t_end
        } else if self.fixed == Some(h) {
            self.fixed_count += 1;
            self.t0 + self.fixed_count as f64 * self.m as f64 * h
        } else {
            t + self.m as f64 * h
        };
        self.done = self.last;
    }

    /// Constant steps: the seed's scheme, the Jacobian evaluated once at
    /// `t₀`, every level and neighbouring problem carried from interval to
    /// interval.
    fn attempt_fixed(&mut self) -> Result<Outcome, SolveError> {
        let (t, h) = (self.t, self.h);
        if !self.have_jacobian {
            self.jacobian(t)?;
            self.have_jacobian = true;
        }
        if let Err(failure) = self.interval(t, h) {
            return Ok(Outcome::Failed {
                failure,
                retry: Retry::Policy,
                iterations: 0,
            });
        }
        self.accept(t, h);
        if !self.done {
            let (interval, last) = self.steps.toward_end(self.t, self.m as f64 * h);
            self.set_step(interval, last);
        }
        if self.h == h {
            self.sweep.carry_over();
        } else {
            // A shorter last interval: the levels carried over hold the
            // error expansion of the old step, which a new step would mix
            // with its own (the index-2 unknowns go wrong by O(1)); it
            // starts afresh from the best value instead.
            self.sweep.restart_at(&self.y);
            self.have_jacobian = false;
        }
        Ok(Outcome::Accepted)
    }

    /// Error control: the Jacobian at the start of each interval, every
    /// level started from the accepted value, the difference of the last
    /// two corrections at the end of the interval as error estimate.
    fn attempt_adaptive(&mut self) -> Result<Outcome, SolveError> {
        let order = self.corrections.min(self.m) as f64;
        let (t, h) = (self.t, self.h);
        if !self.have_jacobian {
            self.jacobian(t)?;
            self.have_jacobian = true;
        }
        self.sweep.restart_at(&self.y);
        let outcome = self.interval(t, h);
        let err = match outcome {
            Ok(()) => self.error_norm(h),
            Err(_) => f64::NAN,
        };
        if !err.is_finite() {
            self.reject = true;
            return Ok(Outcome::Failed {
                failure: outcome.err().unwrap_or(Failure::NonFinite("solution")),
                retry: Retry::Policy,
                iterations: 0,
            });
        }
        let ratio = if err == 0.0 {
            RATIO_MAX
        } else {
            (FAC * err.powf(-1.0 / (order + 1.0))).clamp(RATIO_MIN, RATIO_MAX)
        };
        let m = self.m as f64;
        if err > 1.0 {
            self.reject = true;
            return Ok(Outcome::ErrorTest { h: m * h * ratio });
        }
        self.accept(t, h);
        if !self.done {
            let ratio = if self.reject { ratio.min(1.0) } else { ratio };
            self.reject = false;
            self.have_jacobian = false;
            self.h = (h * ratio).min(self.steps.h_max / m);
        }
        Ok(Outcome::Accepted)
    }

    /// `‖η^[J] − η^[J−1]‖` at the end of the interval, weighted at the
    /// interval's start value.
    fn error_norm(&mut self, h: f64) -> f64 {
        let (jj, m, n) = (self.corrections, self.m, self.n);
        // Index scaling is 1 (index 1); the floor of the weights is the
        // core's.
        self.weights.update_scaled(&self.y, m as f64 * h);
        let (best, prev) = (self.sweep.node(jj, m), self.sweep.node(jj - 1, m));
        for ((d, a), b) in self.diff[..n].iter_mut().zip(best).zip(prev) {
            *d = a - b;
        }
        self.weights.norm(&self.diff)
    }

    /// All levels at the end of the last interval (constant steps: the
    /// seed's tables).
    pub(super) fn levels(&self) -> Vec<Vec<f64>> {
        (0..=self.corrections)
            .map(|l| self.sweep.node(l, self.m).to_vec())
            .collect()
    }
}

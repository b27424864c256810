//! The IDeC integrator as the driver sees it: one accepted interval per
//! [`Method::step`], constant steps (the seed's scheme) or error-controlled
//! ones.

use super::sweep::Sweep;
use super::{Idec, FAC, RATIO_MAX, RATIO_MIN};
use crate::core::attempt::{self, Attempts, Outcome, Steps};
use crate::core::control::{Budget, Failure};
use crate::core::driver::Method;
use crate::core::eliminate::Formulation;
use crate::core::onestep::OneStep;
use crate::core::weights::Weights;
use crate::linalg::small;
use crate::{Options, Problem, SolveError, Stats};

/// State of one IDeC integration.
pub(super) struct Integrator<'a> {
    sys: Formulation<'a>,
    /// Unknowns `N`, degree `m`, corrections `J`.
    n: usize,
    m: usize,
    corrections: usize,
    /// The interval workspace.
    pub(super) sweep: Sweep,
    weights: Weights,
    stats: Stats,
    /// The step point and the attempt loop's state; its steps are
    /// intervals of `m` Euler steps, its constant steps summed with
    /// compensation (over the 10⁵ intervals of a long run a plain sum
    /// drifts and makes the last interval look shorter than `m h`, a
    /// restart).
    one: OneStep,
    /// Euler step of the next attempt.
    h: f64,
    /// The best value at the end of the last accepted interval.
    y: Vec<f64>,
    /// Start of the last accepted interval, and the best level at its
    /// nodes (dense output).
    t_prev: f64,
    dense_nodes: Vec<f64>,
    /// Scratch for the error estimate.
    diff: Vec<f64>,
    /// The Jacobian for the next attempt is evaluated.
    have_jacobian: bool,
}

impl Method for Integrator<'_> {
    fn t(&self) -> f64 {
        self.one.t
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn dense(&self, tau: f64, out: &mut [f64]) {
        let theta = (tau - self.t_prev) / (self.one.h_old / self.m as f64);
        let n = self.n;
        let nodes = |l: usize| &self.dense_nodes[l * n..(l + 1) * n];
        self.sweep.nodes.evaluate(theta, nodes, out);
    }
    fn dense_degree(&self) -> usize {
        self.m
    }
    fn finished(&self) -> bool {
        self.one.done
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
        &mut self.one.steps
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.stats
    }
    /// The interval `m h` is the loop's step.
    fn point(&self) -> (f64, f64) {
        (self.one.t, self.one.h)
    }
    fn set_step(&mut self, interval: f64, last: bool) {
        // An interval that differs from the current one by round-off only
        // (the last, brought to `t_end`) keeps its step: a constant step
        // keeps its factorisation and carries its levels over.
        let one = &mut self.one;
        let round_off = 100.0 * f64::EPSILON * one.t.abs().max(one.steps.t_end.abs());
        if !last || (interval - self.m as f64 * self.h).abs() > round_off {
            let h = interval / self.m as f64;
            if one.fixed.is_some() && h != self.h {
                // A shorter last interval of constant steps: the levels
                // carried over hold the error expansion of the old step,
                // which a new step would mix with its own (the index-2
                // unknowns go wrong by O(1)); it starts afresh from the
                // best value instead.
                self.sweep.restart_at(&self.y);
                self.have_jacobian = false;
            }
            (one.h, self.h) = (interval, h);
        }
        one.last = last;
    }
    /// Constant steps: the seed's scheme, the Jacobian evaluated once at
    /// `t₀`, every level and neighbouring problem carried from interval to
    /// interval. Error control: the Jacobian at the start of each
    /// interval, every level started from the accepted value, the
    /// difference of the last two corrections at the end of the interval as
    /// error estimate.
    fn attempt(&mut self) -> Result<Outcome, SolveError> {
        let (t, h, fixed) = (self.one.t, self.h, self.one.fixed.is_some());
        if !self.have_jacobian {
            let matrix = &mut self.sweep.matrix;
            (matrix.checked_jacobian(&*self.sys, &mut self.stats, t, &self.y))
                .map_err(|failure| Budget::error(failure, t, h, 0))?;
            self.have_jacobian = true;
        }
        if !fixed {
            self.sweep.restart_at(&self.y);
        }
        let outcome = (self.sweep.matrix.factor(1.0, h, &mut self.stats))
            .and_then(|_| self.sweep.run(&*self.sys, &mut self.stats, t, h));
        let err = match outcome {
            Ok(()) if fixed => 0.0,
            Ok(()) => self.error_norm(h),
            Err(_) => f64::NAN,
        };
        if !err.is_finite() {
            self.one.reject = true;
            let failure = outcome.err().unwrap_or(Failure::NonFinite("solution"));
            return Ok(Outcome::failed(failure, 0));
        }
        let order = self.corrections.min(self.m) as f64;
        let ratio = if err == 0.0 {
            RATIO_MAX
        } else {
            (FAC * err.powf(-1.0 / (order + 1.0))).clamp(RATIO_MIN, RATIO_MAX)
        };
        let m = self.m as f64;
        if err > 1.0 {
            self.one.reject = true;
            return Ok(Outcome::ErrorTest { h: m * h * ratio });
        }
        // Accepted: the best level is the solution, its nodes the dense
        // output.
        self.stats.steps += self.m;
        self.t_prev = t;
        let best = self.corrections;
        for k in 0..=self.m {
            let dst = &mut self.dense_nodes[k * self.n..(k + 1) * self.n];
            dst.copy_from_slice(self.sweep.node(best, k));
        }
        self.y.copy_from_slice(self.sweep.node(best, self.m));
        self.one.accept(self.one.h);
        if fixed {
            self.sweep.carry_over();
        } else if !self.one.done {
            let h_next = self.one.after_accept(h, h * ratio);
            self.have_jacobian = false;
            self.h = h_next.min(self.one.steps.h_max / m);
            self.one.h = m * self.h;
        }
        Ok(Outcome::Accepted)
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
        let fixed = options.fixed_step.is_some();
        let mut sweep = Sweep::new(info, corrections, m, fixed);
        // `E` is constant in `t` and `y` (`eliminate::constant_leading`):
        // evaluated once, at the start.
        sweep.matrix.leading(&*sys, problem.t0, problem.y0)?;
        sweep.restart_at(problem.y0);
        // Error control takes index 1 only: no index scaling.
        let weights = Weights::new(&options.tol, |_| 1.0, vec![true; n], vec![0; n]);
        let one = OneStep {
            compensated: fixed,
            ..OneStep::new(problem, options, m as f64)
        };
        Ok(Integrator {
            sys: sys.clone(),
            n,
            m,
            corrections,
            sweep,
            weights,
            stats: Stats::default(),
            h: one.h / m as f64,
            one,
            y: problem.y0.to_vec(),
            t_prev: problem.t0,
            dense_nodes: vec![0.0; (m + 1) * n],
            diff: vec![0.0; n],
            have_jacobian: false,
        })
    }

    /// `‖η^[J] − η^[J−1]‖` at the end of the interval, weighted at the
    /// interval's start value.
    fn error_norm(&mut self, h: f64) -> f64 {
        let (jj, m, n) = (self.corrections, self.m, self.n);
        // Index scaling is 1 (index 1); the floor of the weights is the
        // core's.
        self.weights.update_scaled(&self.y, m as f64 * h);
        let (best, prev) = (self.sweep.node(jj, m), self.sweep.node(jj - 1, m));
        small::difference(&mut self.diff[..n], best, prev);
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

//! The runs of an integration: one error-controlled run, or — with a
//! constant step — the adaptive start-up run that computes the `k − 1`
//! starting values and the constant-step run of order `k` it feeds, both
//! handed to the driver.

use super::step::{Config, Integrator};
use super::MAX_ORDER;
use crate::core::matrix::Corrector;
use crate::core::{control, driver};
use crate::{Options, Solution, SolveError, Stats};
use dae_core::system::DaeSystem;

/// Everything a run needs, and what the driver is asked to do with it.
pub(super) struct Run<'a> {
    /// The formulation.
    pub(super) sys: &'a dyn DaeSystem,
    /// The caller's options.
    pub(super) options: &'a Options,
    /// Components in the error test and the Newton norm.
    pub(super) in_test: &'a [bool],
    /// Start of the horizon.
    pub(super) t0: f64,
    /// End of the horizon.
    pub(super) t_end: f64,
    /// Consistent initial values.
    pub(super) y0: &'a [f64],
    /// The initial derivative.
    pub(super) yp0: &'a [f64],
    /// Work before the first step (the initial derivative and the
    /// consistency check), counted with the first run.
    pub(super) spent: Stats,
}

impl<'a> Run<'a> {
    /// An integrator with settings `cfg` whose work counters start at
    /// `stats`.
    fn integrator<L: Corrector>(&self, cfg: Config, stats: Stats) -> Integrator<'a, L> {
        let mut integ = Integrator::<L>::new(self.sys, &self.options.tol, self.in_test, cfg);
        integ.stats = stats;
        integ
    }

    /// Error-controlled integration over `[t0, t_end]`.
    pub(super) fn adaptive<L: Corrector>(&self) -> Result<Solution, SolveError> {
        let opts = self.options;
        let span = self.t_end - self.t0;
        let (max_order, fixed_order) = match opts.fixed_order {
            Some(k) => (k, true),
            None => (opts.max_order, false),
        };
        let cfg = Config {
            max_order,
            fixed_order,
            fixed_step: false,
            hmax: opts.h_max.unwrap_or(span),
            max_steps: opts.max_steps,
            t_end: self.t_end,
            span,
        };
        let mut integ = self.integrator::<L>(cfg, self.spent);
        let h0 = match opts.h0 {
            // Clipped before φ_2 = h y'₀ is formed, which could overflow.
            Some(h) => h.min(cfg.hmax).min(span),
            None => integ.initial_step(self.y0, self.yp0),
        };
        integ.start(self.t0, self.y0, self.yp0, h0);
        driver::solve(&mut integ, opts, self.t0, self.t_end)
    }

    /// Constant step size, order `k`, no error control; the `k−1` starting
    /// values come from an adaptive run at the caller's tolerances, which
    /// the driver runs first ([`driver::solve_with_startup`]).
    pub(super) fn fixed<L: Corrector>(&self, h_request: f64) -> Result<Solution, SolveError> {
        let opts = self.options;
        let span = self.t_end - self.t0;
        let k = opts.fixed_order.unwrap_or(opts.max_order);
        let (nsteps, h) = control::constant_grid(span, h_request, opts.max_steps, self.t0)?;
        let grid = |j: usize| {
            if j == nsteps {
                self.t_end
            } else {
                self.t0 + j as f64 * h
            }
        };
        // The constant-step run, within what is left of the step budget
        // after the work `spent` before it.
        let constant = |spent: Stats| Config {
            max_order: k,
            fixed_order: true,
            fixed_step: true,
            hmax: h,
            max_steps: opts.max_steps.saturating_sub(spent.steps + spent.rejected),
            t_end: self.t_end,
            span,
        };

        // Starting values y(t0 + j h), j = 1 … m.
        let m = (k - 1).min(nsteps);
        if m == 0 {
            // Order one starts from y₀ and y'₀ alone.
            let mut integ = self.integrator::<L>(constant(self.spent), self.spent);
            integ.start(self.t0, self.y0, self.yp0, h);
            return driver::solve(&mut integ, opts, self.t0, self.t_end);
        }
        let cfg = Config {
            max_order: MAX_ORDER,
            fixed_order: false,
            fixed_step: false,
            hmax: span,
            max_steps: opts.max_steps,
            t_end: grid(m),
            span,
        };
        let mut startup = self.integrator::<L>(cfg, self.spent);
        let h0 = startup.initial_step(self.y0, self.yp0).min(h);
        startup.start(self.t0, self.y0, self.yp0, h0);
        let build = |startup: &Integrator<'a, L>, values: &[Vec<f64>]| {
            if m == nsteps {
                return None;
            }
            let mut integ = self.integrator::<L>(constant(startup.stats), Stats::default());
            // Values at t0, …, t0 + (k−1) h, oldest first.
            let mut history: Vec<&[f64]> = Vec::with_capacity(k);
            history.push(self.y0);
            history.extend(values.iter().map(|v| v.as_slice()));
            integ.start_from_history(grid(k - 1), &history, h);
            Some(integ)
        };
        driver::solve_with_startup(
            &mut startup,
            (1..=m).map(grid),
            build,
            opts,
            self.t0,
            self.t_end,
        )
    }
}

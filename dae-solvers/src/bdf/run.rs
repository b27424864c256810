//! The runs of an integration: one error-controlled run, or — with a
//! constant step — the adaptive start-up run that computes the `k − 1`
//! starting values and the constant-step run of order `k` it feeds, as one
//! [`Method`] for the driver ([`Startup`]).

use super::step::{Config, Integrator};
use super::MAX_ORDER;
use crate::core::control;
use crate::core::driver::{Method, Startup};
use crate::core::eliminate::Formulation;
use crate::core::matrix::Corrector;
use crate::{Options, SolveError, Stats};

/// Everything a run needs.
pub(super) struct Run<'a> {
    /// The formulation.
    pub(super) sys: Formulation<'a>,
    /// The caller's options.
    pub(super) options: &'a Options,
    /// Components in the error test and the Newton norm.
    pub(super) in_test: Vec<bool>,
    /// Start of the horizon.
    pub(super) t0: f64,
    /// End of the horizon.
    pub(super) t_end: f64,
    /// Consistent initial values.
    pub(super) y0: &'a [f64],
    /// The initial derivative.
    pub(super) yp0: Vec<f64>,
    /// Work before the first step (the initial derivative and the
    /// consistency check), counted with the first run.
    pub(super) spent: Stats,
}

impl<'a> Run<'a> {
    /// An integrator with settings `cfg` whose work counters start at
    /// `stats`.
    fn integrator<L: Corrector>(&self, cfg: Config, stats: Stats) -> Integrator<'a, L> {
        let mut integ =
            Integrator::<L>::new(self.sys.clone(), &self.options.tol, &self.in_test, cfg);
        integ.stats = stats;
        integ
    }

    /// Error-controlled integration over `[t0, t_end]`, started.
    pub(super) fn adaptive<L: Corrector + 'a>(&self) -> Box<dyn Method + 'a> {
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
            None => integ.initial_step(self.y0, &self.yp0),
        };
        integ.start(self.t0, self.y0, &self.yp0, h0);
        Box::new(integ)
    }

    /// Constant step size, order `k`, no error control, started; the
    /// `k−1` starting values come from an adaptive run at the caller's
    /// tolerances, which runs first ([`Startup`]).
    pub(super) fn fixed<L: Corrector + 'a>(
        self,
        h_request: f64,
    ) -> Result<Box<dyn Method + 'a>, SolveError> {
        let opts = self.options;
        let (t0, t_end) = (self.t0, self.t_end);
        let span = t_end - t0;
        let k = opts.fixed_order.unwrap_or(opts.max_order);
        let (nsteps, h) = control::constant_grid(span, h_request, opts.max_steps, t0)?;
        let grid = move |j: usize| {
            if j == nsteps {
                t_end
            } else {
                t0 + j as f64 * h
            }
        };
        // The constant-step run, within what is left of the step budget
        // after the work `spent` before it.
        let constant = move |spent: Stats| Config {
            max_order: k,
            fixed_order: true,
            fixed_step: true,
            hmax: h,
            max_steps: opts.max_steps.saturating_sub(spent.steps + spent.rejected),
            t_end,
            span,
        };

        // Starting values y(t0 + j h), j = 1 … m.
        let m = (k - 1).min(nsteps);
        if m == 0 {
            // Order one starts from y₀ and y'₀ alone.
            let mut integ = self.integrator::<L>(constant(self.spent), self.spent);
            integ.start(self.t0, self.y0, &self.yp0, h);
            return Ok(Box::new(integ));
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
        let h0 = startup.initial_step(self.y0, &self.yp0).min(h);
        startup.start(self.t0, self.y0, &self.yp0, h0);
        let build = move |startup: &Integrator<'a, L>, values: &[Vec<f64>]| {
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
        // Both runs' dense output is of degree at most MAX_ORDER.
        Ok(Box::new(Startup::new(
            startup,
            (1..=m).map(grid),
            build,
            MAX_ORDER,
        )))
    }
}

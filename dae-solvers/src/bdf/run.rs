//! The runs of an integration: one error-controlled run, or — with a
//! constant step — the adaptive start-up run that computes the `k − 1`
//! starting values and the constant-step run of order `k` it feeds, as one
//! [`Method`] for the driver ([`startup::constant_step`]).

use super::step::{Config, Integrator};
use super::MAX_ORDER;
use crate::core::driver::Method;
use crate::core::eliminate::Formulation;
use crate::core::matrix::Corrector;
use crate::core::startup;
use crate::{Options, SolveError, Stats};

/// Everything a run needs.
#[derive(Clone)]
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
    /// tolerances, which runs first ([`startup::constant_step`]).
    pub(super) fn fixed<L: Corrector + 'a>(
        self,
        h_request: f64,
    ) -> Result<Box<dyn Method + 'a>, SolveError> {
        let opts = self.options;
        let (t0, t_end) = (self.t0, self.t_end);
        let span = t_end - t0;
        let k = opts.fixed_order.unwrap_or(opts.max_order);
        // The constant-step run, within what is left of the step budget
        // after the work `spent` before it.
        let constant = move |spent: Stats, h: f64| Config {
            max_order: k,
            fixed_order: true,
            fixed_step: true,
            hmax: h,
            max_steps: opts.max_steps.saturating_sub(spent.steps + spent.rejected),
            t_end,
            span,
        };
        let startup = |t_end: f64, h: f64| {
            let cfg = Config {
                max_order: MAX_ORDER,
                fixed_order: false,
                fixed_step: false,
                hmax: span,
                max_steps: opts.max_steps,
                t_end,
                span,
            };
            let mut startup = self.integrator::<L>(cfg, self.spent);
            let h0 = startup.initial_step(self.y0, &self.yp0).min(h);
            startup.start(t0, self.y0, &self.yp0, h0);
            startup
        };
        // Order one starts from y₀ and y'₀ alone.
        let from_start = |h: f64| {
            let mut integ = self.integrator::<L>(constant(self.spent, h), self.spent);
            integ.start(t0, self.y0, &self.yp0, h);
            integ
        };
        let run = self.clone();
        let from_history =
            move |startup: &Integrator<'a, L>, t: f64, history: &[&[f64]], h: f64| {
                let mut integ = run.integrator::<L>(constant(startup.stats, h), Stats::default());
                integ.start_from_history(t, history, h);
                integ
            };
        // Both runs' dense output is of degree at most MAX_ORDER.
        startup::constant_step(
            t0,
            t_end,
            h_request,
            opts.max_steps,
            k - 1,
            self.y0,
            from_start,
            startup,
            from_history,
            MAX_ORDER,
        )
    }
}

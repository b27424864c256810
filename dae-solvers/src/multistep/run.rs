//! A multistep run from the problem: the initial derivative and the
//! consistency check ([`Setup`]), then one error-controlled run started
//! with DASSL's initial step, or — with a constant step — the adaptive
//! start-up run that computes the starting values and the constant-step
//! run it feeds, as one [`Method`] for the driver
//! ([`startup::constant_step`]).

use super::{Config, Family};
use crate::core::driver::Method;
use crate::core::eliminate::Formulation;
use crate::core::startup;
use crate::init::{check_residuals, initial_derivative_with, DerivativeRule};
use crate::{Options, Problem, SolveError, Stats};
use dae_core::system::DaeSystem;

/// Everything a run needs beyond the family's integrator.
struct Setup<'a> {
    /// The caller's options.
    options: &'a Options,
    /// Start of the horizon.
    t0: f64,
    /// End of the horizon.
    t_end: f64,
    /// Consistent initial values.
    y0: &'a [f64],
    /// The initial derivative.
    yp0: Vec<f64>,
    /// Work before the first step (the initial derivative and the
    /// consistency check), counted with the first run.
    spent: Stats,
}

impl<'a> Setup<'a> {
    /// The initial derivative of `sys` (the formulation the family
    /// integrates) at the problem's initial values, which are then checked
    /// (see the [module documentation](super)).
    fn new(
        sys: &dyn DaeSystem,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<Self, SolveError> {
        let (t0, y0) = (problem.t0, problem.y0);
        let mut spent = Stats::default();
        let yp0 = initial_derivative_with(sys, t0, y0, &DerivativeRule::SOLVER)?;
        spent.residual_evals += 1; // its f(t0, y0)
        check_residuals(sys, &options.tol, t0, y0, &yp0, &mut spent)?;
        Ok(Setup {
            options,
            t0,
            t_end: problem.t_end,
            y0,
            yp0,
            spent,
        })
    }
}

/// How a family counts orders.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Orders {
    /// The method's order for the options' order `k`
    /// ([`Options::max_order`], [`Options::fixed_order`]).
    pub(crate) of_option: fn(usize) -> usize,
    /// The number of steps of the formula of an order: a constant-step
    /// run needs one fewer starting values beyond `y₀`.
    pub(crate) formula_steps: fn(usize) -> usize,
    /// The highest order of the start-up run of a constant-step run.
    pub(crate) startup: usize,
}

/// The integration of `problem` by a family in the formulation `sys`, for
/// the driver: the initial derivative and the check ([`Setup`]), then the
/// run ([`integrate`]) with the family's integrators built by `make` from
/// the formulation and the settings of each run.
pub(crate) fn integrator<'a, F: Family + 'a>(
    sys: Formulation<'a>,
    problem: &Problem<'a>,
    options: &'a Options,
    orders: Orders,
    make: impl Fn(Formulation<'a>, Config) -> F + Clone + 'a,
) -> Result<crate::Integrator<'a>, SolveError> {
    let setup = Setup::new(&*sys, problem, options)?;
    let method = integrate(setup, orders, move |cfg| make(sys.clone(), cfg))?;
    Ok(crate::Integrator::new(method, problem, options))
}

/// The run of a family on `setup`: its integrators built by `make` (with
/// the settings of each run, counters zero), error-controlled or — with
/// [`Options::fixed_step`] — at a constant step after a start-up; started.
fn integrate<'a, F: Family + 'a>(
    setup: Setup<'a>,
    orders: Orders,
    make: impl Fn(Config) -> F + Clone + 'a,
) -> Result<Box<dyn Method + 'a>, SolveError> {
    let Setup {
        options,
        t0,
        t_end,
        y0,
        yp0,
        spent,
    } = setup;
    let span = t_end - t0;
    let order = (orders.of_option)(options.fixed_order.unwrap_or(options.max_order));
    let cfg = Config {
        max_order: order,
        fixed_order: options.fixed_order.is_some(),
        fixed_step: false,
        hmax: options.h_max.unwrap_or(span),
        max_steps: options.max_steps,
        t_end,
        span,
    };
    let build = move |cfg: Config, stats: Stats| {
        let mut integ = make(cfg);
        integ.ms_mut().stats = stats;
        integ
    };
    let Some(h_request) = options.fixed_step else {
        let mut integ = build(cfg, spent);
        let h0 = match options.h0 {
            // Clipped before `h y'₀` is formed, which could overflow.
            Some(h) => h.min(cfg.hmax).min(span),
            None => integ.ms_mut().initial_step(y0, &yp0),
        };
        integ.start(t0, y0, &yp0, h0);
        return Ok(Box::new(integ));
    };

    // The constant-step run, within what is left of the step budget after
    // the work `spent` before it.
    let constant = move |spent: Stats, h: f64| Config {
        fixed_order: true,
        fixed_step: true,
        hmax: h,
        max_steps: options
            .max_steps
            .saturating_sub(spent.steps + spent.rejected),
        ..cfg
    };
    let yp0 = &yp0;
    let startup = |t_end: f64, h: f64| {
        let cfg = Config {
            max_order: orders.startup,
            fixed_order: false,
            t_end,
            ..cfg
        };
        let mut startup = build(cfg, spent);
        let h0 = startup.ms_mut().initial_step(y0, yp0).min(h);
        startup.start(t0, y0, yp0, h0);
        startup
    };
    // The lowest orders start from y₀ and y'₀ alone.
    let from_start = |h: f64| {
        let mut integ = build(constant(spent, h), spent);
        integ.start(t0, y0, yp0, h);
        integ
    };
    let make = build.clone();
    let from_history = move |startup: &F, t: f64, history: &[&[f64]], h: f64| {
        let mut integ = make(constant(startup.ms().stats, h), Stats::default());
        integ.start_from_history(t, history, h);
        integ
    };
    // Both runs' dense output is of degree at most the higher order bound.
    startup::constant_step(
        t0,
        t_end,
        h_request,
        options.max_steps,
        (orders.formula_steps)(order) - 1,
        y0,
        from_start,
        startup,
        from_history,
        order.max(orders.startup),
    )
}

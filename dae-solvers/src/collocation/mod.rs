//! The collocation engine: three-stage collocation methods on RADAU5's
//! linear algebra, shared by [`crate::radau5`], [`crate::gauss`] and
//! [`crate::odradau`].
//!
//! A method is described to the engine by values (see [`tableau`]): its
//! [`tableau::Tableau`] (coefficients, the transformation of `A⁻¹`, the
//! embedded error estimate, and whether the step ends at the last stage or
//! at a projected end value), its [`tableau::Policy`] (step-size rule,
//! Newton stopping rule, Jacobian reuse, tolerance map) and, per run, the
//! stage solve ([`StageSolveKind`]: square LU, or the projected least
//! squares of an overdetermined formulation). The engine owns everything
//! else, written once:
//!
//! - `stages`: the buffers of the step loop, the Jacobian and the two
//!   factorised iteration matrices, the starting values, the embedded error
//!   estimate, the end-point and output projections of a method that is not
//!   stiffly accurate, and the new collocation polynomial of a step;
//! - `stagger`: the simplified Newton iteration in the transformed
//!   unknowns (HW IV.8), plain or staggered for a state and its
//!   sensitivities;
//! - `kernels`: its per-unknown loops, instantiated for small sizes;
//! - `slopes`: the slopes at the step points of a method that is not
//!   stiffly accurate, for its dense output of the step points' order
//!   (`core::hermite`);
//! - `control`: the step-size controller state, RADAU5's classical and
//!   predictive quotients and the held step of a symmetric method;
//! - `step`: the integrator — the start at `t₀`, the one step attempt the
//!   shared attempt loop of `core::attempt` calls (retries, budgets and the
//!   end of the horizon are that loop's), and the dense output.
//!
//! The numerics are documented with the methods: [`crate::radau5`] for the
//! discretisation, the Newton iteration, the error estimate and the
//! step-size control; [`crate::gauss`] for the held step, the iteration to
//! round-off and the projections; [`crate::odradau`] for the least-squares
//! stage solve.

mod control;
mod kernels;
mod slopes;
mod solve;
mod stages;
mod stagger;
mod step;
pub(crate) mod tableau;

pub(crate) use solve::StageSolveKind;

use crate::options::Options;
use crate::{Problem, SolveError};
use step::Integrator;
use tableau::Collocation;

/// The stepper of the three-stage collocation method `K`, its stage
/// systems solved as `solve` says, started at `t₀`; the caller has checked
/// that its solver accepts the formulation.
pub(crate) fn integrator<'a, K: Collocation>(
    problem: &Problem<'a>,
    options: &'a Options,
    solve: StageSolveKind,
) -> Result<crate::Integrator<'a>, SolveError> {
    problem.check(problem.system.info().unknowns(), options)?;
    let sys = crate::core::eliminate::algebraic_rows(problem);
    let mut integrator = Integrator::<K>::new(sys, problem, options, solve);
    integrator.start()?;
    Ok(crate::Integrator::new(
        Box::new(integrator),
        problem,
        options,
    ))
}

// ---------------------------------------------------------------------------
// Tuning: RADAU5's defaults, for every method
// ---------------------------------------------------------------------------

/// Maximal Newton iterations per step with a fixed step size, which cannot
/// be reduced instead.
const NIT_FIXED: usize = 30;
/// Safety factor of the step-size controller.
const SAFE: f64 = 0.9;
/// Keep the step size and the factorisation when `h_new/h ∈ [QUOT1, QUOT2]`.
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
/// Step ratios are bounded by `1/FACL ≤ h_new/h ≤ 1/FACR`.
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;
/// Unit round-off.
const UROUND: f64 = f64::EPSILON * 0.5;

/// From this tolerance down (the smallest relative tolerance, or absolute
/// where all relative ones are zero) the integration is run for the last
/// digits: the updates of `t` and `y` are summed with compensation (a
/// rounding of `u|y|` per step is no longer small against the error after
/// 10⁵–10⁷ steps), and the Newton iteration stops at [`TIGHT_NEWTON`] times
/// RADAU5's bound (an iteration stopped at RADAU5's bound leaves an error
/// of one sign step after step). Measured in BENCHMARKS.md §6b; above it
/// nothing changes, bit for bit.
pub(crate) const TIGHT_TOL: f64 = 1e-10;

/// The factor on RADAU5's Newton bound at tight tolerances.
pub(crate) const TIGHT_NEWTON: f64 = 0.01;

/// The smallest relative tolerance, or the smallest absolute one where all
/// relative tolerances are zero: the one number RADAU5's rules of thumb
/// (the Newton bound, [`TIGHT_TOL`]) read.
fn smallest_tolerance(rtol: impl Iterator<Item = f64>, atol: impl Iterator<Item = f64>) -> f64 {
    let r = rtol.fold(f64::INFINITY, f64::min);
    if r > 0.0 {
        r
    } else {
        atol.fold(f64::INFINITY, f64::min)
    }
}

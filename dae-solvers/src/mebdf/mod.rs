//! Modified extended BDF (MEBDF) of Cash, variable step and variable order
//! 1–8, for square DAEs `E y' = f(t, y)` with a constant leading matrix `E`
//! — the method of the MEBDF/MEBDFDAE codes. A model with a constant mass
//! matrix is taken in rcd0 too, whose acceleration rows keep `G(q)·v'`:
//! [`Solver::solve`] makes those rows algebraic first, which leaves `E`
//! constant.
//!
//! # The method
//!
//! J. R. Cash, *On the integration of stiff systems of ODEs using extended
//! backward differentiation formulae*, Numer. Math. 34 (1980) 235–246;
//! *The integration of stiff initial value problems in ODEs using modified
//! extended backward differentiation formulae*, Comp. & Maths. with Appls.
//! 9 (1983) 645–657; the DAE code: T. J. Abdulla, J. R. Cash and
//! M. T. Diamantakis, *An MEBDF package for the numerical solution of large
//! sparse systems of stiff initial value problems*, Comp. & Maths. with
//! Appls. 42 (2001) 121–129; Hairer & Wanner, *Solving ODEs II*, V.3.
//!
//! A step of order `p = k + 1` from `t_n` to `t_{n+1}` is made of three
//! stages ([`stages`](self) explains them): a `k`-step BDF step to `t_{n+1}`,
//! a second one to `t_{n+2}`, and the `k`-step extended BDF — order `k + 1`
//! with the derivative at the future point `t_{n+2}` — modified so that its
//! coefficient of `f(y_{n+1})` is the BDF's `β`. All three stages are
//! `E (y + c) = hβ f(t, y)` with different known parts `c`, so they share
//! one iteration matrix `E/(hβ) − J`. Order one is the implicit Euler step
//! alone. The coefficients are those of constant steps, solved from the
//! order conditions ([`coeffs`](self)).
//!
//! **Variable step by interpolation** (as Cash's code, which keeps a table
//! of backward differences): the past values are held as backward
//! differences on an equally spaced grid; when the step size changes, the
//! polynomial of the current order through them is evaluated on the new
//! grid (a Nordsieck-style rescaling) — the constant-step formulas then
//! apply unchanged.
//!
//! **Restart from a stale value** (not in Cash's code): when the error test
//! keeps rejecting order-one attempts and the estimate stops falling with
//! the step, the estimate measures the last accepted value, whose algebraic
//! unknowns miss their equations. The attempt is then accepted and the
//! method starts afresh from it, at most once every 20 steps
//! (the engine's `multistep::stale`; on Andrews' squeezer in rcd0 at 1e-5 this
//! turned `step_size_too_small` at t = 0.021 into a run to the end).
//!
//! **Error estimate and order selection** (see [`control`](self)): the local
//! error of order `p` is `|C_p| ‖y_{n+1} − P_p(t_{n+1})‖` with the predictor
//! of degree `p`, `≈ C_p h^(p+1) y^(p+1)`; the neighbouring orders are
//! estimated the same way, and after `p + 1` steps of constant size the
//! order with the largest admissible step is taken (biases 1.3 / 1.2 / 1.4
//! for `p − 1, p, p + 1`, as in Gear- and LSODE-type codes). The start is
//! order one with DASSL's initial step.
//!
//! **The propagated estimate** ([`Options::estimate`], not in Cash's
//! code; the engine's `multistep::propagate`): the difference
//! `y_{n+1} − P_q(t_{n+1})` of an algebraic unknown measures how its own
//! history extrapolates, not the error the constraints carry into it from
//! the differential unknowns. The difference is therefore also carried
//! through the factored `E/(hβ) − J`, `ṽ = (E/(hβ) − J)⁻¹ (E/(hβ) v)`,
//! and the norm taken of `max(|v_i|, |ṽ_i|)`. By default the error test
//! compares the two norms at its first call after each new Jacobian or
//! rejected step, and once the carried one is ten times the own the run
//! uses it for the error test and the order selection to its end. On the
//! IVP Test Set's transistor amplifier at 1e-9 the own estimate crawled
//! (275 027 steps, half of the attempts rejected); checked, 5 146 steps
//! to 8.5 digits. On the pendulum the check never fires (BENCHMARKS.md
//! §18b).
//!
//! **Higher index**: the error of a differential index-2 unknown
//! ([`VarInfo::index`]; the velocities of an index-3 mechanism) is scaled
//! by `h` (as RADAU5 and MEBDFDAE, `core::weights`); the *algebraic*
//! unknowns of index 2 (the multiplier of `rcd1`, the current of a CV
//! loop, Jay's `z`) and every unknown of index 3 and above (the multiplier
//! of `ori2`) are **left out of the error estimate** (as DASPK does,
//! `core::policy::index_scaled_error_test` gives the measurements for the
//! algebraic index-2 unknowns), but stay in the norm of the Newton
//! increments, scaled by `h^(k−1)`. [`Options::index2_in_error_test`] is
//! not used. An algebraic index-2 unknown then carries the error of the
//! stage BDFs' derivative, `O(h^(p−1))` at order `p`: one order below the
//! differential unknowns (EXTREMES.md "ms14").
//!
//! *The Newton norm keeps the index scaling.* DASPK's Newton norm, every
//! index-2 unknown at full weight with a round-off floor
//! (`multistep::newton_norm`, which made `bdf(ori2)` accurate on the CV
//! loop), was tried (session 14): on the CV loop nothing changed (a linear
//! problem, one exact Newton step), on Jay's problem the steps grew
//! ×2.4 … ×15 (1e-5 … 1e-9; 1e-4 failed), and on the pendulum `ori2`
//! (S01) ×5 … ×1 000 (1e-10: 2 660 → 2 738 538 steps), the velocities at
//! full weight beside the `h²`-scaled multiplier.
//!
//! *Why the multiplier is left out* (measured on the pendulum `ori2`, S01,
//! tol 1e-12, with every rejected attempt printed: `h`, order, the weighted
//! components of the estimate, Newton iterations). With `λ` in the test,
//! scaled by `h²`, 5,877 of 37,117 attempts were rejected and 31,240 steps
//! taken; 2,226 rejections were at order 3 with `λ` the dominant component,
//! typically right after the order was raised from 2 (the `λ` component
//! went from 0.2 at order 2 to 25 at order 3 with the same step), and the
//! third failure on one step fell back to order one, where the position
//! error estimate at `h ≈ 5·10⁻⁶` is 10²–10³ times the tolerance: 2,341
//! further rejections at order one and the cycle 1 → 2 → 3 → fail repeated
//! (6,971 attempts at order one, 16,531 at order two). The Newton
//! iterations converged in 1–4 iterations throughout; tightening `κ` to
//! 10⁻⁴ or dropping DASSL's round-off exit changed the rejections by under
//! 10 %. The `λ` differences `∇^(p+1) λ` do not behave like
//! `h^(p+1) λ^(p+1)`: the BDF multiplier of an index-3 problem carries
//! errors that are not smooth from step to step (Hairer & Wanner VII.3,
//! Brenan–Campbell–Petzold 5.4), so the `h²` scaling does not make the
//! estimate asymptotically correct, and at tight tolerances it dictates
//! the order. Leaving `λ` out: 6,717 steps, 741 rejected at 1e-12; S02
//! `ori2` at 1e-12, which stopped with `step_size_too_small` at t = 262.09,
//! reaches t = 2000. `λ` remains accurate, being determined by the positions
//! and velocities through the constraints. Leaving the index-2 velocities
//! out as well was tried and is not robust (S01 at 1e-10 collapses the step
//! at t = 3.1).
//!
//! What is left of the rejections at 1e-12 (order 6, velocity components):
//! they occur on the second to fourth step after a change of step size
//! (in a run with 792 rejections: 490, 193 and 101 on the second, third and
//! fourth step after the change, none later), i.e. they come from the
//! interpolated history, whose position values differ from the method's
//! own values by the interpolation error and enter the velocities divided
//! by `h`. A larger threshold for step increases (1.5, 2) did not remove
//! them without costing the index-1/2 formulations.
//!
//! [`VarInfo::index`]: dae_core::system::VarInfo
//!
//! # Options
//!
//! - [`Options::max_order`] and [`Options::fixed_order`] count the *steps*
//!   `k` of the formulas: order `k + 1`. `max_order = k` bounds the order
//!   by `k + 1`, `k ≤ 7`: the library default `max_order = 5` (chosen for
//!   the BDF methods) therefore gives orders 1–6 here, and `max_order = 7`
//!   orders up to 8 ([`coeffs::MAX_ORDER`](self)); `k = 0` or `k > 7` is
//!   [`SolveError::InvalidInput`] naming the field and the range `1..=7`;
//!   `fixed_order = k` raises the order to `k + 1` as the history allows
//!   and never lowers it by order selection (only the emergency fall-back to
//!   order one after three error-test failures on one step).
//! - [`Options::h0`] replaces the initial step, [`Options::h_max`] bounds
//!   every step, [`Options::max_steps`] counts step attempts; a step below
//!   `4 ε max(|t|, ε (t_end − t₀))` is [`SolveError::StepSizeTooSmall`].
//! - [`Options::fixed_step`]: a constant step `h` on the grid
//!   `t₀ + j h` and no error test, order `k + 1` with `k` from
//!   `fixed_order` (else `max_order`); the `k − 1` starting values beyond
//!   `y₀` come from an adaptive run at the caller's tolerances (as for
//!   [`crate::bdf`]). For convergence studies.
//! - [`Options::output_times`]: dense output by the polynomial of the last
//!   step's order through the last values.
//!
//! # Example
//!
//! ```
//! use dae_core::system::DaeSystem;
//! use dae_solvers::mebdf::Mebdf;
//! use dae_solvers::{Options, Problem, Solver};
//! # fn run(sys: &dyn DaeSystem, y0: &[f64]) -> Result<(), dae_solvers::SolveError> {
//! let problem = Problem { system: sys, t0: 0.0, y0, t_end: 2.0 };
//! let solution = Mebdf.solve(&problem, &Options::with_tol(1e-8))?;
//! println!("y(2) = {:?} after {} steps", solution.last(), solution.stats.steps);
//! # Ok(())
//! # }
//! ```
//!
//! # Initial derivative, fixed step size, resources
//!
//! As every multistep family: the engine's (`multistep`) initial
//! derivative and consistency check, constant-step run with its adaptive
//! start-up, and buffers allocated before the step loop.

mod coeffs;
mod control;
mod stages;
mod step;

use crate::core::policy;
use crate::multistep::run::{self, Orders};
use crate::{NotApplicable, Options, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;
use step::Integrator;

/// Cash's modified extended BDF, orders 1–8, variable step by
/// interpolation. See the [module documentation](self).
pub struct Mebdf;

impl Solver for Mebdf {
    fn name(&self) -> &'static str {
        "mebdf"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::square(info)?;
        policy::constant_leading_once_eliminated(info)
    }

    fn integrator<'a>(
        &self,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<crate::Integrator<'a>, SolveError> {
        self.accepts(problem.system.info())?;
        policy::hessenberg(problem.system, problem.t0, problem.y0, options)?;
        problem.check(problem.system.info().unknowns(), options)?;
        let sys = crate::core::eliminate::constant_leading(problem)?;
        // The options count steps k: order k + 1 ≤ MAX_ORDER.
        options.check_orders(
            coeffs::MAX_ORDER - 1,
            "mebdf (the step number k, order k + 1)",
        )?;
        let orders = Orders {
            // The options count steps k: order k + 1.
            of_option: |k| (k + 1).min(coeffs::MAX_ORDER),
            formula_steps: Integrator::steps_of,
            startup: coeffs::MAX_ORDER.min(6),
        };
        run::integrator(sys, problem, options, orders, move |sys, cfg| {
            Integrator::new(sys, options, cfg)
        })
    }
}

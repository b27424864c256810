//! The constant-step start-up of a multistep method (BDF, MEBDF), once for
//! both: a `k`-step formula at constant step needs `k − 1` values beyond
//! `y₀`; an adaptive run of the same method computes them at the grid
//! times, and the constant-step run starts from them ([`Startup`]).

use super::control;
use super::driver::{Method, Startup};
use crate::SolveError;

/// The constant-step integration of a `starting + 1`-step formula on
/// `[t0, t_end]` with the step request `h_request` (made to divide the
/// horizon, [`control::constant_grid`]), as one [`Method`]:
///
/// - no starting values needed (`starting == 0`): `from_start(h)`, the
///   constant-step run from `y₀` and `y'₀` alone;
/// - else `startup(t, h)`: the adaptive run to the grid time `t` of the
///   last starting value, its steps at most `h`; then
///   `from_history(startup, t, values, h)`: the constant-step run from the
///   values at `t₀, t₀ + h, …, t` (oldest first, `y₀` first) — not built
///   when the start-up run has covered the horizon.
///
/// The dense output of both runs is of degree at most `degree`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn constant_step<'a, A, B>(
    t0: f64,
    t_end: f64,
    h_request: f64,
    max_steps: usize,
    starting: usize,
    y0: &'a [f64],
    from_start: impl FnOnce(f64) -> B,
    startup: impl FnOnce(f64, f64) -> A,
    from_history: impl FnOnce(&A, f64, &[&[f64]], f64) -> B + 'a,
    degree: usize,
) -> Result<Box<dyn Method + 'a>, SolveError>
where
    A: Method + 'a,
    B: Method + 'a,
{
    let span = t_end - t0;
    let (nsteps, h) = control::constant_grid(span, h_request, max_steps, t0)?;
    let grid = move |j: usize| {
        if j == nsteps {
            t_end
        } else {
            t0 + j as f64 * h
        }
    };
    let m = starting.min(nsteps);
    if m == 0 {
        return Ok(Box::new(from_start(h)));
    }
    let run = startup(grid(m), h);
    let build = move |startup: &A, values: &[Vec<f64>]| {
        if m == nsteps {
            return None;
        }
        let mut history: Vec<&[f64]> = Vec::with_capacity(starting + 1);
        history.push(y0);
        history.extend(values.iter().map(|v| v.as_slice()));
        Some(from_history(startup, grid(starting), &history, h))
    };
    Ok(Box::new(Startup::new(
        run,
        (1..=m).map(grid),
        build,
        degree,
    )))
}

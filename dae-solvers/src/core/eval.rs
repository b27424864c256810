//! Counted evaluations of a formulation: every evaluation of `F` or `f`
//! an attempt makes is counted in [`Stats`] and checked, a non-finite
//! value being the attempt's typed [`Failure`] (retried smaller by the
//! attempt loop, `core::attempt`). Used by the multistep correctors
//! (`bdf`, `odbdf`, `mebdf`) and IDeC's Euler steps; the collocation
//! stages evaluate through their own staggered forms.

use super::control::Failure;
use crate::linalg::all_finite;
use crate::Stats;
use dae_core::system::DaeSystem;

/// `F(t, y, y')` into `out`, counted; [`Failure::NonFinite`] naming the
/// residual when an entry is not finite.
#[inline]
pub(crate) fn residual(
    sys: &dyn DaeSystem,
    stats: &mut Stats,
    (t, y, yp): (f64, &[f64], &[f64]),
    out: &mut [f64],
) -> Result<(), Failure> {
    sys.residual(t, y, yp, out);
    stats.residual_evals += 1;
    finite(out)
}

/// `f(t, y)` into `out`, counted as a residual evaluation; non-finite as
/// [`residual`].
#[inline]
pub(crate) fn rhs(
    sys: &dyn DaeSystem,
    stats: &mut Stats,
    t: f64,
    y: &[f64],
    out: &mut [f64],
) -> Result<(), Failure> {
    sys.rhs(t, y, out);
    stats.residual_evals += 1;
    finite(out)
}

/// [`Failure::NonFinite`] naming the residual unless every entry of `v`
/// is finite.
#[inline]
fn finite(v: &[f64]) -> Result<(), Failure> {
    if all_finite(v) {
        Ok(())
    } else {
        Err(Failure::NonFinite("residual"))
    }
}

//! Defaults a formulation implies, decided here and nowhere else: the
//! library, `dae run` and `dae sweep` give the same run for the same inputs.
//!
//! - **Which unknowns enter a BDF error test.** For an index-2 unknown (the
//!   multiplier of `rcd1`, `ggl1`, `psi1`, `ovd1`; both multipliers of
//!   `ori2`'s index-3 structure) the difference between corrector and
//!   predictor is not an estimate of a local error that shrinks like
//!   `h^(k+1)`: kept in the test it drives the step size to zero (DASPK's
//!   `INFO(16)`; Brenan, Campbell & Petzold ch. 3 and 5). Unless
//!   [`Options::index2_in_error_test`] says otherwise, BDF-type methods
//!   leave unknowns of index ≥ 2 out of the error test and the Newton norm.
//!   Radau-type methods keep every unknown and scale index-`k` components by
//!   `h^(k−1)` instead (Hairer & Wanner VII.8).
//! - **What a method accepts**: [`square`], [`overdetermined`],
//!   [`constant_leading`], [`max_index`] — the typed reasons of
//!   [`crate::Solver::accepts`].

use crate::error::NotApplicable;
use crate::Options;
use dae_core::system::FormulationInfo;

/// Components in the error test of a BDF-type method: all, except the
/// unknowns of index ≥ 2 unless [`Options::index2_in_error_test`] is
/// `Some(true)`. If that would leave none, all.
pub fn bdf_error_test(info: &FormulationInfo, options: &Options) -> Vec<bool> {
    let keep_index2 = options.index2_in_error_test.unwrap_or(false);
    let mask: Vec<bool> = info
        .variables
        .iter()
        .map(|v| keep_index2 || v.index < 2)
        .collect();
    if mask.iter().any(|&b| b) {
        mask
    } else {
        vec![true; mask.len()]
    }
}

/// A method for square systems: `M = N ≥ 1`.
pub fn square(info: &FormulationInfo) -> Result<(), NotApplicable> {
    let (m, n) = (info.equations(), info.unknowns());
    if n == 0 {
        return Err(NotApplicable::NoUnknowns);
    }
    if m > n {
        return Err(NotApplicable::Overdetermined {
            equations: m,
            unknowns: n,
        });
    }
    if m < n {
        return Err(NotApplicable::Underdetermined {
            equations: m,
            unknowns: n,
        });
    }
    Ok(())
}

/// A least-squares method for `M ≥ N ≥ 1` whose formulation leaves out no
/// hidden constraint above level `max_c_level`.
pub fn overdetermined(info: &FormulationInfo, max_c_level: u8) -> Result<(), NotApplicable> {
    let (m, n) = (info.equations(), info.unknowns());
    if n == 0 {
        return Err(NotApplicable::NoUnknowns);
    }
    if m < n {
        return Err(NotApplicable::Underdetermined {
            equations: m,
            unknowns: n,
        });
    }
    if info.c_level > max_c_level {
        return Err(NotApplicable::ConstraintLevel {
            c_level: info.c_level,
            max: max_c_level,
        });
    }
    Ok(())
}

/// A method whose formulas need a constant leading matrix `E`.
pub fn constant_leading(info: &FormulationInfo) -> Result<(), NotApplicable> {
    if info.constant_leading {
        Ok(())
    } else {
        Err(NotApplicable::LeadingMatrixNotConstant)
    }
}

/// A method whose formulas need a constant `E`, and that also takes a
/// formulation whose `E` is constant once its constraint rows that carry
/// derivatives are made algebraic (`constant_differential_leading`: a model
/// with a constant mass matrix, in rcd0). The solver makes them algebraic
/// before it starts.
pub fn constant_leading_once_eliminated(info: &FormulationInfo) -> Result<(), NotApplicable> {
    if info.constant_leading || info.constant_differential_leading {
        Ok(())
    } else {
        Err(NotApplicable::LeadingMatrixNotConstant)
    }
}

/// A method for unknowns of index at most `max`.
pub fn max_index(info: &FormulationInfo, max: u8) -> Result<(), NotApplicable> {
    let index = info.max_index();
    if index > max {
        Err(NotApplicable::IndexTooHigh { index, max })
    } else {
        Ok(())
    }
}

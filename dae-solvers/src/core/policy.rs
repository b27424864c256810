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
//! - **Which formulation a solver is given when the user names none**:
//!   [`preferred_formulations`], the order `dae run` tries.

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

/// The formulations `solver` is best given, best first: what `dae run`
/// takes when no formulation is named (the first one the model provides and
/// the solver accepts). `None` for a name that is not a solver
/// ([`crate::SOLVER_NAMES`]).
///
/// The order is measured, not assumed: `dae run` on the paper's S01 (a
/// pendulum read from a `.dae` file, errors at t = 20 against the closed
/// form) at tolerances 1e-6 and 1e-8, every solver × formulation, with the
/// sweeps of BENCHMARKS.md §2–§2g (S02, Andrews' squeezer, the double,
/// spherical and driven pendulums) for robustness. A run is *accurate*
/// when its error is at most `100 · tol`.
///
/// | solver | order | why (S01 error at 1e-8; 100 · tol = 1e-6) |
/// |---|---|---|
/// | `radau5` | ggl1 rcd1 rcd0 psi1 psi0 ori2 | ggl1 3.4e-9 keeps position and velocity constraints to round-off (\|g0\| 2e-15); rcd1 3.5e-9, rcd0 1.2e-9 drift off the position constraint (2e-11, 5e-11); the index-3 ori2 2.2e-6 is *inaccurate* (224 · tol) |
/// | `bdf` | psi0 ggl1 rcd1 psi1 rcd0 ori2 | no formulation is accurate at 1e-8 (BDF leaves index-2 unknowns out of its error test); psi0 is the closest, 3.9e-5, with every constraint level kept, and the most accurate on S02 too; ggl1 1.1e-4, rcd1 4.3e-5 (drifts 5e-7), rcd0 8.2e-5 (drifts 9e-6, and 5.7 on S02 at 1e-6), ori2 2.9e-3 |
/// | `odradau` | ovd0 ovd1 ggl1 rcd1 rcd0 psi1 psi0 | ovd0 1.4e-9 and ovd1 7.0e-10 keep every constraint (ovd0 the acceleration level too, index 1); the square formulations as for radau5 |
/// | `odbdf` | ovd0 psi0 rcd0 | ovd0 6.4e-6 and psi0 1.0e-5 keep the position constraint (2e-11); rcd0 1.0e-4 drifts 1e-5 |
/// | `mebdf` | ggl1 rcd1 ori2 rcd0 | ggl1 5.9e-5, rcd1 6.0e-5; ori2 1.8e-3; rcd0 1.2e-3 drifts 1.4e-4 (0.15 at 1e-6) |
/// | `idec` | rcd0 ggl1 rcd1 | rcd0 is the only form where its error control behaves like its order (accurate at 1e-6 in 7 596 steps); on the index-2 ggl1 and rcd1 it runs at order 2 (957 212 and 654 708 steps at 1e-8) |
/// | `gauss` | rcd0 psi0 | accurate at every tolerance 1e-5 … 1e-12 on both (8.1e-9, 7.2e-9 at 1e-8); rcd0 needs no selector |
///
/// The projected `psi1`/`psi0` come after the formulations that need no
/// selector except where they are measurably better (bdf, odbdf, gauss);
/// a model without a symbolic selector then falls through to the next one.
///
/// ```
/// use dae_solvers::core::policy::preferred_formulations;
///
/// assert_eq!(preferred_formulations("radau5").unwrap()[0], "ggl1");
/// assert_eq!(preferred_formulations("bdf").unwrap()[0], "psi0");
/// assert!(preferred_formulations("radua5").is_none());
/// ```
pub fn preferred_formulations(solver: &str) -> Option<&'static [&'static str]> {
    Some(match solver {
        "radau5" => &["ggl1", "rcd1", "rcd0", "psi1", "psi0", "ori2"],
        "bdf" => &["psi0", "ggl1", "rcd1", "psi1", "rcd0", "ori2"],
        "odradau" => &["ovd0", "ovd1", "ggl1", "rcd1", "rcd0", "psi1", "psi0"],
        "odbdf" => &["ovd0", "psi0", "rcd0"],
        "mebdf" => &["ggl1", "rcd1", "ori2", "rcd0"],
        "idec" => &["rcd0", "ggl1", "rcd1"],
        "gauss" => &["rcd0", "psi0"],
        _ => return None,
    })
}

#[cfg(test)]
mod preference_tests {
    use super::preferred_formulations;
    use dae_core::system::FORMULATION_NAMES;

    /// Every solver has an order; each lists known formulations, once.
    #[test]
    fn every_solver_has_an_order_of_known_formulations() {
        for solver in crate::SOLVER_NAMES {
            let order = preferred_formulations(solver).unwrap_or_else(|| panic!("{solver}"));
            assert!(!order.is_empty(), "{solver}");
            for (i, f) in order.iter().enumerate() {
                assert!(FORMULATION_NAMES.contains(f), "{solver}: {f}");
                assert!(!order[..i].contains(f), "{solver}: {f} twice");
            }
        }
    }
}

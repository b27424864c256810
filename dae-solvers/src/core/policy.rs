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
//!   leave unknowns of index ≥ 2 out of the error test; `bdf` keeps them
//!   in its Newton norm (DASPK; `crate::bdf`, index-2 formulations).
//!   Radau-type methods keep every unknown of a state and scale index-`k`
//!   components by `h^(k−1)` instead (Hairer & Wanner VII.8) — but not the
//!   index-2 unknowns of its forward sensitivities ([`collocation_error_test`]).
//! - **What a method accepts**: [`square`], [`overdetermined`],
//!   [`constant_leading`], [`max_index`] — the typed reasons of
//!   [`crate::Solver::accepts`] — and, from the problem and the options,
//!   [`hessenberg`], [`leading_constant_in_time`], [`free_directions`],
//!   [`variable_step_index3`] (variable-step BDF on index 3).
//! - **Which formulation a solver is given when the user names none**:
//!   [`preferred_formulations`], the order `dae run` tries.

use crate::core::matrix::algebraic_combinations;
use crate::error::NotApplicable;
use crate::{Options, Problem};
use dae_core::system::{Blocks, DaeSystem, FormulationInfo, RowKind, VarKind};
use nalgebra::DMatrix;

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

/// Components in the error estimate of `mebdf`, which scales the error of
/// an index-2 unknown by `h` (as RADAU5): the unknowns of index ≤ 1 and the
/// *differential* unknowns of index 2 (the velocities of an index-3
/// mechanism). Left out: every unknown of index ≥ 3 (the multipliers of
/// `ori2`, `crate::mebdf` has the measurements) and the *algebraic* unknowns
/// of index 2, as DASPK leaves them out (`INFO(16)`).
///
/// An algebraic index-2 unknown `z` of a Hessenberg system is fixed at
/// each step by the differences of `y` alone (it enters no recursion), so
/// its error is the error of the formula's derivative: for MEBDF of order
/// `p` that of the BDF stages of step number `k = p − 1`, `O(h^(p−1))`,
/// smooth while `h` is constant. Its difference to the predictor sees that
/// error only where it jumps, at each change of step size (measured on
/// `scenes/literature/mna_cv_loop.toml`, `ori2` at 1e-10: the current's
/// weighted estimate `+0.49, −1.46, +1.46, −0.49` over the four steps after
/// a doubling at order 3 — the fourth difference of a step — and the
/// order held at 3 with a rejected step every few steps, 929 steps, the
/// current 1e-6 off; out of the test: 188 steps, orders up to 6, 7e-8 off).
/// On Jay's index-2 problem the same estimate ended at the step limit
/// at 1e-10 (EXTREMES.md "ms14").
pub(crate) fn index_scaled_error_test(info: &FormulationInfo) -> Vec<bool> {
    let estimated = |v: &dae_core::system::VarInfo| match v.index {
        0 | 1 => true,
        2 => v.kind == VarKind::Differential,
        _ => false,
    };
    info.variables.iter().map(estimated).collect()
}

/// A formulation as written (`ori2`) with an *algebraic* unknown of index
/// 2 (a Hessenberg index-2 multiplier `z` of `y' = f(y, z)`, `0 = g(y)`),
/// where the multistep families check their error estimate against the
/// propagated one at a lower ratio
/// ([`crate::multistep::propagate::MISSED_INDEX2_AS_WRITTEN`]).
///
/// Such a `z` is out of a BDF error test (DASPK's `INFO(16)`, as
/// [`bdf_error_test`]), so the test sees `y` alone. But `y`'s local error
/// is the truncation error `τ` carried through the constraint, `P τ` with
/// `P = I − f_z (g_y f_z)⁻¹ g_y` (the step's `z` absorbs the part of `τ`
/// across the constraint and hands it back to `y` through `f_z`), and
/// DASSL's estimate approximates `τ`. In the index-2 forms derived from a
/// mechanical system (`rcd1`, `ggl1`, `psi1`) the multiplier enters as
/// `f_z = −M⁻¹Gᵀ` beside `g_y = G`: `P` is the `M`-orthogonal projection and
/// the estimate misses nothing (S01 checks at tol 1e-5 … 1e-12: the
/// propagated estimate at most 2.97 times DASSL's). A model as written has
/// no such structure: on Jay's index-2 problem `P` is oblique
/// (`g_y f_z = 1` beside `|g_y| |f_z| ≈ 8`) and the local error of the
/// implicit Euler steps 5.5 h² and 11 h² (relative, `y1`, `y2`) where
/// DASSL's estimate says h²/2 and 2 h² (EXTREMES.md "jay15").
pub(crate) fn index2_as_written(info: &FormulationInfo) -> bool {
    info.name == "ori2"
        && info
            .variables
            .iter()
            .any(|v| v.index == 2 && v.kind == VarKind::Algebraic)
}

/// Components in the error test of a collocation (Radau-type) method:
/// all, except for a state and its forward sensitivities
/// ([`DaeSystem::blocks`]) the sensitivities' unknowns of index ≥ 2
/// unless [`Options::index2_in_error_test`] is `Some(true)` — and every
/// sensitivity when they are out of the error test
/// ([`Blocks::error_control`](dae_core::system::Blocks)).
///
/// Why the sensitivities' index-2 unknowns leave the test where the
/// state's stay: a sensitivity grows along the run (the pendulum's
/// `∂x/∂l` like `t`, its phase drifting), and the estimate of each of its
/// components grows with it; a differential component's weight grows too
/// (`rtol |sᵢ|`), but a multiplier whose exact sensitivity is zero — the
/// GGL multiplier `μ ≡ 0` of `ggl1`, and so `∂μ/∂p ≡ 0` — is measured
/// against `atol` alone. On the pendulum (S01, tol 1e-8, radau5(ggl1)) the
/// weighted estimate of `∂μ/∂l` grew from 1.0 to 3.6 (mean square) over
/// t ∈ [0, 20], dominated the error norm at 8 803 of 11 287 steps and took
/// the run from the plain 6 601 steps to 11 269 (BENCHMARKS.md §13g). The
/// sensitivities' accuracy is that of their differential unknowns, which
/// stay in the test (as a BDF method leaves every index-2 unknown out:
/// [`bdf_error_test`]).
pub fn collocation_error_test(
    info: &FormulationInfo,
    blocks: Option<Blocks>,
    options: &Options,
) -> Vec<bool> {
    let mut mask = crate::core::block::in_error_test(info.unknowns(), blocks);
    let keep_index2 = options.index2_in_error_test == Some(true);
    if let Some(b) = blocks.filter(|b| b.error_control && b.unknowns() == mask.len()) {
        for (m, v) in mask[b.size..].iter_mut().zip(&info.variables[b.size..]) {
            *m &= keep_index2 || v.index < 2;
        }
    }
    mask
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

/// The system whose structure a policy reads: `sys` itself, or for a
/// state with its sensitivities the state's own formulation; `None` when a
/// block system does not offer its state alone.
fn state_of(sys: &dyn DaeSystem) -> Option<&dyn DaeSystem> {
    match (sys.blocks(), sys.first_block()) {
        (None, _) => Some(sys),
        (Some(_), state) => state,
    }
}

/// A BDF-type method (its error test leaves unknowns of index ≥ 2 out, see
/// [`bdf_error_test`]) on a formulation of index 2 or 3: refused unless its
/// constraints have the Hessenberg structure that rule was made for — in
/// every chain of the model's constraints, the levels below the top one
/// (the one that determines the chain's algebraic unknowns, as the
/// acceleration level determines a mechanical system's multipliers) depend
/// on differential unknowns only. Refused with
/// [`NotApplicable::NotHessenberg`], naming the first constraint level and
/// the algebraic unknown that break it. Index-1 formulations, and a caller
/// that keeps the index-2 unknowns in the test
/// ([`Options::index2_in_error_test`] `= Some(true)`), pass.
///
/// BDF's convergence results for index 2 and 3 (Brenan, Campbell &
/// Petzold 1996, §3.2) are for the Hessenberg forms, `y' = f(y, z)`,
/// `0 = g(y)` (and its index-3 analogue), where the unknowns the test keeps
/// carry the dynamics. In a chain whose lower levels already fix an
/// algebraic unknown, the unknowns left out are states that nothing
/// controls. The dependence is read from `∂g/∂y` of the chain at `(t, y)`
/// ([`DaeSystem::constraints_jacobian`]); an entry that happens to vanish
/// there lets the formulation pass.
///
/// Measured (EXTREMES.md §5, session 8): `bdf` and `mebdf` on Pantelides'
/// reactor (`cstr`: `C = u(t)`, whose first derivative already holds the
/// rate `R`) in `ori2` and `rcd1` "finished" with errors up to 10⁶⁸, the
/// temperature (left out of the test) drifting away.
///
/// ```
/// use dae::dae_solvers::core::policy::hessenberg;
/// use dae::dae_solvers::Options;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// // The pendulum's position constraint: positions at level 0, velocities
/// // at level 1, the multiplier only at level 2.
/// let sys = Pendulum::default().ori2();
/// let y = [1.0, 0.0, 0.0, 0.0, 0.0];
/// assert!(hessenberg(&sys, 0.0, &y, &Options::default()).is_ok());
/// ```
pub fn hessenberg(
    sys: &dyn DaeSystem,
    t: f64,
    y: &[f64],
    options: &Options,
) -> Result<(), NotApplicable> {
    let Some(sys) = state_of(sys) else {
        return Ok(());
    };
    let info = sys.info();
    let (k, n) = (info.constraints.len(), info.unknowns());
    if info.max_index() < 2 || options.index2_in_error_test == Some(true) || k == 0 || y.len() < n {
        // (A wrong length of `y` is the caller's error, which
        // `Problem::check` reports.)
        return Ok(());
    }
    let mut jac = DMatrix::zeros(k, n);
    sys.constraints_jacobian(t, &y[..n], &mut jac);
    let top = |source: u16| {
        info.constraints
            .iter()
            .filter(|c| c.source == source)
            .map(|c| c.level)
            .max()
            .unwrap_or(0)
    };
    for (row, c) in info.constraints.iter().enumerate() {
        if c.level >= top(c.source) {
            continue;
        }
        for (col, v) in info.variables.iter().enumerate() {
            if v.kind == VarKind::Algebraic && jac[(row, col)].abs() > 0.0 {
                return Err(NotApplicable::NotHessenberg {
                    constraint: c.source,
                    level: c.level,
                    top: top(c.source),
                    unknown: v.name.clone(),
                    d_index: info.max_index(),
                });
            }
        }
    }
    Ok(())
}

/// `solver` (`bdf`, `radau5`, `odradau`) on a formulation of index 2 or 3
/// whose leading matrix `E` depends on `t` (probed at `t` and
/// `t + span/2`, at `y`): refused with
/// [`NotApplicable::TimeDependentLeading`]. Index-1 formulations, a
/// constant `E` and an `E(y)` that does not depend on `t` pass.
///
/// radau5 and odradau (measured, session 8: `newton_failure` after 3–4
/// steps at t ≈ 6e-5 … 4e-4 at every tolerance): their simplified Newton
/// iteration takes `E` and `∂f/∂y` at `t_n` for all three stages (the
/// Kronecker form needs one matrix). On Gear–Hsu–Petzold the index-2
/// unknown `y2` is fixed by the constraint `y1 + ηt y2 = f1` differentiated
/// in time, and the differentiated coefficient `η y2` is what the frozen
/// matrix lacks: it solves for `y2` with the coefficient `1 + η` where the
/// stage equations have `1`, an O(1) error in the matrix, whatever `h`.
///
/// Measured (EXTREMES.md §5, session 8): on Gear, Hsu & Petzold's
/// `y1 + ηt y2 = f1`, `y1' + ηt y2' + (1 + η) y2 = f2` (η = 1, a regular
/// pencil) in `ori2`, bdf's modified Newton iteration failed at every
/// tolerance 1e-4 … 1e-10, the step shrunk to 1e-15 … 1e-18 — also with
/// the iteration matrix formed afresh at every change of `c_J` (tried,
/// not kept: the failures moved, t = 0.14 → 1.19 at 1e-4, and stayed).
/// The iteration matrix `[[1, ηt], [c_J, c_J ηt + 1 + η]]` has entries
/// `O(1/h)` and determinant `1 + η`: its inverse multiplies the residual
/// of the first row by `c_J ηt/(1 + η)`, so the round-off of the residual
/// reaches `y1` magnified by `t/h`. Not verified as the cause. `mebdf` and
/// `idec` refuse every `E` that is not constant already.
///
/// ```
/// use dae::dae_solvers::core::policy::leading_constant_in_time;
/// use dae::dae_solvers::Problem;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().ori2();
/// let y = [1.0, 0.0, 0.0, 0.0, 0.0];
/// let problem = Problem { system: &sys, t0: 0.0, y0: &y, t_end: 1.0 };
/// assert!(leading_constant_in_time("bdf", &problem).is_ok());
/// ```
pub fn leading_constant_in_time(
    solver: &'static str,
    problem: &Problem<'_>,
) -> Result<(), NotApplicable> {
    let (t, span, y) = (problem.t0, problem.t_end - problem.t0, problem.y0);
    let Some(sys) = state_of(problem.system) else {
        return Ok(());
    };
    let info = sys.info();
    let (m, n) = (info.equations(), info.unknowns());
    let d_index = info.max_index();
    if info.constant_leading || d_index < 2 || y.len() < n {
        return Ok(());
    }
    let (mut e0, mut e1) = (DMatrix::zeros(m, n), DMatrix::zeros(m, n));
    sys.leading(t, &y[..n], &mut e0);
    sys.leading(t + 0.5 * span, &y[..n], &mut e1);
    if e0 == e1 {
        Ok(())
    } else {
        Err(NotApplicable::TimeDependentLeading { solver, d_index })
    }
}

/// A variable-step BDF method (`bdf`) on a formulation with unknowns of
/// index 3 or more (the index-3 `ori2` of a mechanical system, whose
/// multipliers have index 3): refused with
/// [`NotApplicable::VariableStepIndexThree`] unless
/// [`Options::fixed_step`] is set. Formulations of index at most 2 pass.
///
/// *The theory.* The convergence of `k`-step BDF (`k ≤ 6`) on index-3
/// Hessenberg systems is proved for a **constant** step (Lötstedt &
/// Petzold 1986; Brenan, Campbell & Petzold 1996, §3.2); with variable
/// steps it is not: on the chain `x = g(t)`, `y = x'`, `z = y'` the
/// implicit Euler step after a change from `h₋` to `h` gives
/// `z ≈ g''·(1 + h₋/h)/2`, an O(1) error whatever the step (Petzold,
/// "Differential/algebraic equations are not ODE's", SIAM J. Sci. Stat.
/// Comput. 3 (1982): "a further class of problems cannot be solved at all
/// with such codes, because changing the stepsize causes large errors").
/// `bdf` moreover leaves the index-2/3 unknowns out of its error test
/// ([`bdf_error_test`], DASSL/DASPK's practice), so nothing controls the
/// velocities and multipliers of `ori2`. DASSL-type codes are documented
/// for index ≤ 1 (with DASPK's `INFO(16)` for Hessenberg index 2). With a
/// fixed step (a convergence study) the constant-step theory applies and
/// the formulation is taken.
///
/// *Measured* (EXTREMES.md §5, idx10; `dae run … --solver bdf
/// --formulation ori2`, tol 1e-4 … 1e-10): the car axis −1.5 … 2.6
/// correct digits, Andrews' squeezer −1.0 … 4.8, the pendulum −0.8 … 4.1,
/// where the map asks for `−log₁₀(tol) − 2`. `mebdf` (Cash's MEBDFDAE is
/// run on these index-3 problems by the IVP Test Set) and `radau5` take
/// them.
///
/// ```
/// use dae::dae_solvers::core::policy::variable_step_index3;
/// use dae::dae_solvers::{NotApplicable, Options};
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let (ori2, rcd0) = (Pendulum::default().ori2(), Pendulum::default().rcd0());
/// let adaptive = Options::with_tol(1e-6);
/// assert!(matches!(
///     variable_step_index3("bdf", ori2.info(), &adaptive),
///     Err(NotApplicable::VariableStepIndexThree { d_index: 3, .. })
/// ));
/// assert!(variable_step_index3("bdf", rcd0.info(), &adaptive).is_ok());
/// let fixed = Options { fixed_step: Some(1e-3), ..Options::with_tol(1e-6) };
/// assert!(variable_step_index3("bdf", ori2.info(), &fixed).is_ok());
/// ```
pub fn variable_step_index3(
    solver: &'static str,
    info: &FormulationInfo,
    options: &Options,
) -> Result<(), NotApplicable> {
    let d_index = info.max_index();
    if d_index < 3 || options.fixed_step.is_some() {
        Ok(())
    } else {
        Err(NotApplicable::VariableStepIndexThree { solver, d_index })
    }
}

/// A least-squares method (`odradau`) on an overdetermined formulation
/// (`M > N`) with a direction left free: refused with
/// [`NotApplicable::NoFreeDirection`] when, at `t₀`, the constraint rows
/// whose row of `E` is zero and the algebraic combinations of the other
/// rows (`core::matrix::algebraic_combinations`) number `N` or more.
///
/// Its stage solve holds both exactly and tests the differential rows on
/// what they leave free, and its error estimate is that solve's: with
/// nothing free, the estimate is the residual of the constraints at `y_n`,
/// round-off, whatever the step. The step points are then exact (each is
/// an algebraic solve) but the step grows unchecked, and the collocation
/// polynomial between the points, the dense output, is not controlled:
/// Gear–Hsu–Petzold's `ovd0` (its constraint and the hidden
/// `y2 = f2 − f1'` fix `y1` and `y2`) had step points exact to 10⁻¹⁶ and
/// errors of 10⁻⁶ … 10⁻³ at the check times between them (EXTREMES.md §5,
/// lit9). Square formulations and those with a free direction pass.
///
/// ```
/// use dae::dae_solvers::core::policy::free_directions;
/// use dae::dae_solvers::Problem;
/// use dae::models::builtin::Pendulum;
/// use dae::prelude::*;
///
/// let sys = Pendulum::default().ovd0();
/// let y = [1.0, 0.0, 0.0, 0.0, 0.0];
/// let problem = Problem { system: &sys, t0: 0.0, y0: &y, t_end: 1.0 };
/// assert!(free_directions("odradau", &problem).is_ok());
/// ```
pub fn free_directions(solver: &'static str, problem: &Problem<'_>) -> Result<(), NotApplicable> {
    let Some(sys) = state_of(problem.system) else {
        return Ok(());
    };
    let info = sys.info();
    let (m, n) = (info.equations(), info.unknowns());
    if m <= n || problem.y0.len() < n {
        return Ok(());
    }
    let mut e = DMatrix::zeros(m, n);
    sys.leading(problem.t0, &problem.y0[..n], &mut e);
    let (exact, rows): (Vec<usize>, Vec<usize>) = (0..m).partition(|&i| {
        matches!(info.rows[i].kind, RowKind::Constraint { .. }) && (0..n).all(|c| e[(i, c)] == 0.0)
    });
    let e_d: Vec<f64> = rows
        .iter()
        .flat_map(|&i| (0..n).map(move |c| (i, c)))
        .map(|(i, c)| e[(i, c)])
        .collect();
    let combinations = algebraic_combinations(&e_d, n, rows.len(), &mut Vec::new());
    if exact.len() + combinations >= n {
        Err(NotApplicable::NoFreeDirection {
            solver,
            constraints: exact.len(),
            combinations,
            unknowns: n,
        })
    } else {
        Ok(())
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
/// | `bdf` | psi0 ggl1 rcd1 psi1 rcd0 | no formulation is accurate at 1e-8 (BDF leaves index-2 unknowns out of its error test); psi0 3.9e-5 keeps every constraint level and is the most accurate at 1e-12 (9.2e-11, S02 2.2e-5); since index-2 unknowns stay in bdf's Newton norm (session 13) ggl1 4.7e-6, rcd1 1.3e-5 and psi1 3.0e-5 are closer at 1e-8 in about half psi0's steps, and ggl1 is the most accurate on S02 at 1e-7 … 1e-10, but not at 1e-12 (2.7e-8, 3.7e-8, 4.8e-9); rcd0 8.2e-5 (drifts 9e-6, and 5.7 on S02 at 1e-6); the index-3 ori2 (2.9e-3) is refused with a variable step ([`variable_step_index3`]) |
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
        "bdf" => &["psi0", "ggl1", "rcd1", "psi1", "rcd0"],
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

#[cfg(test)]
mod error_test_tests {
    use super::collocation_error_test;
    use crate::Options;
    use dae_core::sensitivity::Sensitivities;
    use dae_core::system::DaeSystem;

    /// The pendulum's `ggl1` (`x, y, v, w` differential, `λ, μ` of index
    /// 2) with the sensitivities of `l`: the state's unknowns all in the
    /// test; the sensitivities' differential ones in, their index-2 ones
    /// out unless the option keeps them; every sensitivity out when they
    /// leave the error test.
    #[test]
    fn collocation_leaves_the_sensitivities_index2_unknowns_out() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/pendulum.dae");
        let src = std::fs::read_to_string(path).unwrap();
        let mut sys = Sensitivities::from_str(&src, &["l"])
            .unwrap()
            .formulation("ggl1")
            .unwrap();
        let index2: Vec<bool> = sys.info().variables.iter().map(|v| v.index >= 2).collect();
        assert_eq!(index2[..6], [false, false, false, false, true, true]);
        let mask = |sys: &dyn DaeSystem, options: &Options| {
            collocation_error_test(sys.info(), sys.blocks(), options)
        };
        let plain = Options::default();
        let want: Vec<bool> = (0..12).map(|i| i < 6 || !index2[i]).collect();
        assert_eq!(mask(&sys, &plain), want);
        let keep = Options {
            index2_in_error_test: Some(true),
            ..Options::default()
        };
        assert_eq!(mask(&sys, &keep), [true; 12]);
        sys.set_error_control(false);
        let off: Vec<bool> = (0..12).map(|i| i < 6).collect();
        assert_eq!(mask(&sys, &plain), off);
        assert_eq!(mask(&sys, &keep), off);
    }
}

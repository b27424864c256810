//! BDF for overdetermined quasi-linear DAEs, in the manner of ODASSL and
//! OVDBDF (Führer; Eich-Soellner & Führer, *Numerical Methods in Multibody
//! Dynamics*, §5.3).
//!
//! # The problem
//!
//! `E(t, y) y' = f(t, y)` with `M ≥ N` rows whose constraint rows include
//! every hidden constraint down to the level that fixes the algebraic
//! unknowns (constraint level 0): `ovd0` (the dynamics with position,
//! velocity and acceleration constraints), and the square `rcd0` and
//! `psi0`. These systems are of index one once the constraints are read as
//! an overdetermined, consistent set; the position and velocity constraints
//! are then invariants the numerical solution keeps to, instead of drifting
//! off them as it does with `rcd0`.
//!
//! # The method
//!
//! DASSL's variable-order, variable-step BDF in fixed-leading-coefficient
//! form ([`crate::bdf`]: predictor, corrector, error estimate, order and
//! step selection, dense output), with the corrector
//!
//! ```text
//!     F(t_{n+1}, y, y'⁽⁰⁾ + c_J (y − y⁽⁰⁾)) = 0        (M equations, N unknowns)
//! ```
//!
//! solved by a simplified Newton iteration whose steps are constrained
//! least-squares solutions of `G δ = F` (see `core::matrix`): the
//! constraint rows exactly, and with them the algebraic combinations of
//! the differential rows (a circuit's capacitor–source loop), the
//! differential rows in a weighted least-squares sense. The constraint rows hold only to the accuracy of
//! the iteration, and the error estimate carries what is left of it, so the
//! convergence test matters more than in DASSL. On formulations whose rows
//! keep an invariant (`ovd0`, `psi0`) it is ODASSL's: the contraction rate
//! is measured afresh in every step (`ρ/(1−ρ)‖δ‖ ≤ 0.33` with the rate
//! unknown at the first iterate, so a step ends after one iteration only
//! if `‖δ‖ ≤ 0.0033`). `odbdf` then takes the Fortran ODASSL's steps on the
//! pendulum (S02: psi0 within 0.4 %, ovd0 within 2.5 %; BENCHMARKS.md §3b).
//! On `rcd0`, which drifts, DASSL's rate carried from step to step with a
//! bound ten times tighter (0.033): ODASSL's rule lets rcd0 drift until
//! the step collapses on S02 at tol 1e-5 and 1e-6, as the Fortran ODASSL
//! does. The point a least-squares iteration converges to depends
//! on its matrix, so with constant steps the matrix is evaluated afresh at
//! every step. The iterate therefore lies on every constraint of
//! the formulation (to the Newton tolerance), and the differential rows
//! carry the discretisation's inconsistency, of the order of the local
//! error. Error control is on the unknowns, as in ODASSL, with index-2
//! unknowns (none in a c-level-0 formulation) left out of the test by the
//! same policy as [`crate::bdf`]. For a square formulation the least-squares
//! solve is the exact solve, and `odbdf` is DASSL up to round-off in a
//! different factorisation.
//!
//! # What it accepts
//!
//! `M ≥ N` and constraint level 0 (`ovd0`, `rcd0`, `psi0`); formulations
//! that leave out hidden constraints (`ovd1`, `ggl1`, `psi1`, `rcd1`,
//! `ori2`) are refused with [`NotApplicable::ConstraintLevel`], as ODASSL
//! asks for an index-1 overdetermined system.

use crate::core::matrix::LstsqCorrector;
use crate::core::policy;
use crate::{NotApplicable, Options, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;

/// BDF orders 1–5 with a least-squares corrector (see the
/// [module documentation](self)).
pub struct OdBdf;

/// Highest constraint level `odbdf` integrates.
pub const MAX_C_LEVEL: u8 = 0;

impl Solver for OdBdf {
    fn name(&self) -> &'static str {
        "odbdf"
    }

    fn accepts(&self, info: &FormulationInfo) -> Result<(), NotApplicable> {
        policy::overdetermined(info, MAX_C_LEVEL)
    }

    fn integrator<'a>(
        &self,
        problem: &Problem<'a>,
        options: &'a Options,
    ) -> Result<crate::Integrator<'a>, SolveError> {
        self.accepts(problem.system.info())?;
        crate::bdf::integrator::<LstsqCorrector>(problem, options)
    }
}

//! Radau IIA of order 5 for overdetermined quasi-linear DAEs, in the manner
//! of QUALIDAES and GEOMS (Steinbrecher).
//!
//! # The problem
//!
//! `E(t, y) y' = f(t, y)` with `M ≥ N` rows: the dynamics together with
//! constraints of several levels — e.g. `ovd1` (position and velocity
//! constraints, 6 equations for 5 unknowns in the pendulum) or `ovd0` (all
//! three levels, 7 equations). No square subsystem is singled out: the
//! solution keeps to every constraint the formulation carries, so nothing
//! drifts off the position or velocity level over long horizons.
//!
//! # The method
//!
//! The stage equations of [`crate::radau5`] — the collocation conditions
//! `E(Y_i) Y'_i − f(t_n + c_i h, Y_i) = 0`, `i = 1, 2, 3` — now have `3M`
//! rows for `3N` unknowns. The simplified Newton iteration keeps RADAU5's
//! transformation: because `(A⁻¹ ⊗ E)(T ⊗ I_N) = (T ⊗ I_M)(Λ ⊗ E)` holds for
//! a rectangular `E` too, the transformed system still splits into one real
//! `M × N` and one complex `M × N` system. Both are made square with the
//! same projection (see `core::matrix`): the constraint rows as they are —
//! every stage satisfies every constraint to the Newton tolerance — and the
//! differential rows tested against the directions of the real system's
//! weighted least-squares solve, fixed for the step. The converged stages
//! are then the collocation solution of one square system, and the method
//! keeps RADAU5's order 5 at the step points (order 4 when the two systems
//! were each solved in their own least-squares sense). For a square
//! formulation the projection is the exact solve, so `odradau` integrates
//! `rcd1`, `rcd0`, `ggl1`, `psi1`, `psi0` like `radau5` (up to round-off
//! in the different elimination).
//!
//! The error estimate is RADAU5's, `err = (γ/h E₀ − J)⁺ [f(t_n, y_n) +
//! E(y_n)(1/h) Σ d_i Z_i]`, with the same projected solve, measured on
//! the unknowns with the index scaling `h^(k−1)` of index-`k` components
//! (Hairer & Wanner VII.8). Step-size control, Jacobian reuse, dense output
//! and the tolerance map are those of [`crate::radau5`] (see there).
//!
//! # What it accepts
//!
//! `M ≥ N` and constraint level at most one (the velocity constraint must be
//! among the rows, or the formulation must have index ≤ 2): `ovd1`, `ovd0`,
//! `ggl1`, `psi1`, `psi0`, `rcd1`, `rcd0`. `ori2` (c-level 2) is refused
//! with [`NotApplicable::ConstraintLevel`]; `radau5` integrates it.
//!
//! Rows holding derivatives whose combination holds none (a dynamic row
//! beside the derivative of a constraint with the same row of `E`, as in a
//! circuit's loop of capacitors and a voltage source) are a condition on
//! the unknowns: the stage solve holds it exactly with the constraint rows
//! (`core::matrix`, "Algebraic conditions among the differential rows").
//! When those conditions and the constraint rows fix every unknown, no
//! direction is left for the differential rows, and the error estimate —
//! the same projected solve — has nothing to measure: such a formulation
//! is refused with [`NotApplicable::NoFreeDirection`] (see
//! [`policy::free_directions`]; Gear–Hsu–Petzold's and Pantelides'
//! reactor's `ovd0`).
//!
//! # Example
//!
//! ```
//! use dae_solvers::odradau::OdRadau;
//! use dae_solvers::{Solver, NotApplicable};
//! # use dae_core::system::FormulationInfo;
//! # fn info(name: &str, m: usize, c_level: u8) -> FormulationInfo {
//! #     use dae_core::system::*;
//! #     let var = |n: &str| VarInfo { name: n.into(), kind: VarKind::Differential, index: 1 };
//! #     let row = RowInfo { kind: RowKind::Differential, text: String::new() };
//! #     FormulationInfo { model: "M".into(), name: name.into(), variables: vec![var("x"), var("y")],
//! #         rows: vec![row; m], d_index: None, s_index: 0, c_level, constant_leading: true,
//! #         constant_differential_leading: true,
//! #         constraints: vec![], invariants: vec![], parameters: vec![] }
//! # }
//! assert!(OdRadau.accepts(&info("ovd1", 3, 1)).is_ok());
//! assert_eq!(
//!     OdRadau.accepts(&info("ori2", 2, 2)),
//!     Err(NotApplicable::ConstraintLevel { c_level: 2, max: 1 })
//! );
//! ```

use crate::collocation::{self, StageSolveKind};
use crate::core::policy;
use crate::radau5::tableau::RadauIIA;
use crate::{NotApplicable, Options, Problem, SolveError, Solver};
use dae_core::system::FormulationInfo;

/// Radau IIA 5 with projected least-squares stage equations (see the
/// [module documentation](self)).
pub struct OdRadau;

/// Highest constraint level `odradau` integrates.
pub const MAX_C_LEVEL: u8 = 1;

impl Solver for OdRadau {
    fn name(&self) -> &'static str {
        "odradau"
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
        policy::leading_constant_in_time(self.name(), problem)?;
        policy::free_directions(self.name(), problem)?;
        collocation::integrator::<RadauIIA>(problem, options, StageSolveKind::LeastSquares)
    }
}

//! Consistent starts of forward-sensitivity systems
//! ([`dae_core::sensitivity`]).

use crate::init::{consistent, Consistent, InitOptions};
use crate::SolveError;
use dae_core::sensitivity::SensitivitySystem;
use dae_core::system::DaeSystem;

/// The consistent start of `[y; s₁; …; s_P]` from `y0` (the state's
/// values as the user gives them, then the sensitivities' — zero unless
/// the start itself depends on a parameter): the state first, by the
/// state formulation's own initialisation (its report is the one
/// returned), then the sensitivities with the state frozen there
/// ([`SensitivitySystem::frozen`]): the least-change projection onto the
/// linearised constraints, the algebraic sensitivities from the highest
/// members.
///
/// ```
/// use dae_core::sensitivity::Sensitivities;
/// use dae_solvers::init::InitOptions;
/// use dae_solvers::sensitivity::consistent_start;
///
/// let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/pendulum.dae")).unwrap();
/// let sys = Sensitivities::from_str(&src, &["l"]).unwrap().formulation("rcd0").unwrap();
/// let mut y0 = vec![0.0; 10];
/// y0[0] = 1.0; // released at x = l = 1
/// let start = consistent_start(&sys, 0.0, &y0, &InitOptions::default()).unwrap();
/// assert_eq!(start.y[..4], [1.0, 0.0, 0.0, 0.0]); // the state as given
/// assert!((start.y[5] - 1.0).abs() < 1e-12); // dx/dl: x stays at l
/// ```
pub fn consistent_start(
    sys: &SensitivitySystem,
    t0: f64,
    y0: &[f64],
    opts: &InitOptions,
) -> Result<Consistent, SolveError> {
    let n = sys.state_unknowns();
    let mut state = consistent(sys.state(), t0, &y0[..n], opts)?;
    let frozen = sys.frozen(&state.y);
    let s = consistent(&frozen, t0, &y0[n..], opts)?;
    debug_assert_eq!(s.y.len(), sys.info().unknowns() - n);
    state.y.extend_from_slice(&s.y);
    Ok(state)
}

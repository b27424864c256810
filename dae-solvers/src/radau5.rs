//! Radau IIA, order 5 (to be written).
use crate::{Options, Problem, Solution, SolveError, Solver};
use dae_core::system::FormulationInfo;

/// 3-stage Radau IIA of order 5.
pub struct Radau5;

impl Solver for Radau5 {
    fn name(&self) -> &'static str {
        "radau5"
    }
    fn accepts(&self, info: &FormulationInfo) -> Result<(), String> {
        if info.is_overdetermined() {
            return Err("overdetermined: solver needs a square system".into());
        }
        Ok(())
    }
    fn solve(&self, _problem: &Problem<'_>, _options: &Options) -> Result<Solution, SolveError> {
        Err(SolveError::invalid("radau5 is not implemented yet"))
    }
}

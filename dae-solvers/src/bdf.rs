//! BDF (to be written).
use crate::{Options, Problem, Solution, SolveError, Solver};
use dae_core::system::FormulationInfo;

/// Variable-order BDF.
pub struct Bdf;

impl Solver for Bdf {
    fn name(&self) -> &'static str {
        "bdf"
    }
    fn accepts(&self, info: &FormulationInfo) -> Result<(), String> {
        if info.is_overdetermined() {
            return Err("overdetermined: solver needs a square system".into());
        }
        Ok(())
    }
    fn solve(&self, _problem: &Problem<'_>, _options: &Options) -> Result<Solution, SolveError> {
        Err(SolveError::invalid("bdf is not implemented yet"))
    }
}

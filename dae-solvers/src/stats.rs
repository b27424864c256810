//! Machine-independent work counters.

use serde::Serialize;
use std::ops::AddAssign;

/// What an integration cost, in counts that do not depend on the machine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps (error test or Newton failure).
    pub rejected: usize,
    /// Evaluations of the right-hand side / residual.
    pub residual_evals: usize,
    /// Evaluations of the Jacobians.
    pub jacobian_evals: usize,
    /// LU factorisations of iteration matrices (a complex one counts once).
    pub factorizations: usize,
    /// Newton iterations, summed over all attempted steps.
    pub newton_iterations: usize,
    /// The multistep methods (`bdf`, `odbdf`, `mebdf`) with the default
    /// checked error estimate ([`crate::options::Estimate::Checked`]): the
    /// number of accepted steps before the check switched the run to the
    /// propagated estimate, if it did (omitted from the JSON otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub propagated_from: Option<usize>,
}

impl AddAssign for Stats {
    /// Add the counters of `part`, e.g. of a second run within one
    /// integration.
    fn add_assign(&mut self, part: Stats) {
        if self.propagated_from.is_none() {
            self.propagated_from = part.propagated_from.map(|s| self.steps + s);
        }
        self.steps += part.steps;
        self.rejected += part.rejected;
        self.residual_evals += part.residual_evals;
        self.jacobian_evals += part.jacobian_evals;
        self.factorizations += part.factorizations;
        self.newton_iterations += part.newton_iterations;
    }
}

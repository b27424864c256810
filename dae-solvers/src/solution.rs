//! What a successful integration returns.

use crate::stats::Stats;

/// Solution values at the requested output times, plus statistics.
///
/// ```
/// use dae::prelude::*;
/// use dae::dae_solvers::radau5::Radau5;
///
/// dae! {
///     /// y' = −y, y(0) = 1, as a one-unknown DAE.
///     pub Decay {
///         parameters { k = 1.0 }
///         differential { y }
///         equations { der(y) = -k * y; }
///     }
/// }
///
/// let sys = Decay::default().ori2();
/// let options = Options { output_times: vec![0.5, 1.0], ..Options::with_tol(1e-10) };
/// let problem = Problem { system: &sys, t0: 0.0, y0: &[1.0], t_end: 2.0 };
/// let solution = Radau5.solve(&problem, &options).unwrap();
/// // The requested output times, then t_end.
/// assert_eq!(solution.t, [0.5, 1.0, 2.0]);
/// assert!((solution.y[1][0] - (-1.0f64).exp()).abs() < 1e-9);
/// assert_eq!(solution.last(), Some(&solution.y[2][..]));
/// assert!(solution.stats.steps > 0);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Solution {
    /// Output times (those of `Options::output_times` inside the horizon,
    /// and `t_end`), ascending.
    pub t: Vec<f64>,
    /// `y` at each output time (length N each).
    pub y: Vec<Vec<f64>>,
    /// Accepted step points `(t, y)` when `Options::record_steps` is set.
    pub steps: Vec<(f64, Vec<f64>)>,
    /// Work counters.
    pub stats: Stats,
}

impl Solution {
    /// The value at the last output time.
    pub fn last(&self) -> Option<&[f64]> {
        self.y.last().map(|v| v.as_slice())
    }
}

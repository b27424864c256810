//! What a successful integration returns.

use crate::stats::Stats;

/// Solution values at the requested output times, plus statistics.
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

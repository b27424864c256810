//! The output grid: one rule for every method.
//!
//! The solution is reported at the requested
//! [`Options::output_times`](crate::Options::output_times) that lie in
//! `[t₀, t_end]`, sorted and without repeats, and always at `t_end` (last).
//! A requested `t₀` is reported as the initial values. Every other time is
//! filled by the method's dense output during the step that covers it:
//! output times never shorten a step.

/// Output times and the values filled so far, allocated before the step
/// loop.
pub(crate) struct OutputGrid {
    times: Vec<f64>,
    values: Vec<Vec<f64>>,
    next: usize,
}

impl OutputGrid {
    /// The grid for `requested` times on `[t0, t_end]` and `n` unknowns.
    pub(crate) fn new(requested: &[f64], t0: f64, t_end: f64, n: usize) -> Self {
        let mut times = Vec::with_capacity(requested.len() + 1);
        times.extend(requested.iter().copied().filter(|&t| t >= t0 && t <= t_end));
        times.sort_by(f64::total_cmp);
        times.dedup();
        if times.last() != Some(&t_end) {
            times.push(t_end);
        }
        Self::at(n, times)
    }

    /// Output at exactly these (ascending) times.
    pub(crate) fn at(n: usize, times: impl IntoIterator<Item = f64>) -> Self {
        let times: Vec<f64> = times.into_iter().collect();
        let values = vec![vec![0.0; n]; times.len()];
        OutputGrid {
            times,
            values,
            next: 0,
        }
    }

    /// Report `y0` at every grid time not after `t0`.
    pub(crate) fn start(&mut self, t0: f64, y0: &[f64]) {
        while self.next < self.times.len() && self.times[self.next] <= t0 {
            self.values[self.next].copy_from_slice(y0);
            self.next += 1;
        }
    }

    /// Fill every pending time up to `t` with `dense(time, out)`.
    pub(crate) fn emit(&mut self, t: f64, mut dense: impl FnMut(f64, &mut [f64])) {
        while self.next < self.times.len() && self.times[self.next] <= t {
            dense(self.times[self.next], &mut self.values[self.next]);
            self.next += 1;
        }
    }

    /// Times and values (all filled once the integration reached `t_end`).
    pub(crate) fn finish(self) -> (Vec<f64>, Vec<Vec<f64>>) {
        (self.times, self.values)
    }

    /// The times before `t` and their values (all filled once the
    /// integration reached `t`): the output of a run cut at an event, the
    /// times from `t` on being another run's (after a reset) or none (after
    /// a stop).
    pub(crate) fn finish_before(mut self, t: f64) -> (Vec<f64>, Vec<Vec<f64>>) {
        let keep = self.times.partition_point(|&s| s < t).min(self.next);
        self.times.truncate(keep);
        self.values.truncate(keep);
        (self.times, self.values)
    }

    /// The values filled so far, by position.
    pub(crate) fn values(&self) -> &[Vec<f64>] {
        &self.values[..self.next]
    }

    /// Times of the grid.
    pub(crate) fn times(&self) -> &[f64] {
        &self.times
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_rule_for_t0_t_end_and_repeats() {
        let mut g = OutputGrid::new(&[2.0, 0.0, 5.0, 2.0, -1.0, 1.0], 0.0, 3.0, 1);
        assert_eq!(g.times(), &[0.0, 1.0, 2.0, 3.0]);
        g.start(0.0, &[7.0]);
        g.emit(2.5, |t, out| out[0] = t);
        assert_eq!(g.values(), &[vec![7.0], vec![1.0], vec![2.0]]);
        g.emit(3.0, |t, out| out[0] = t);
        let (t, y) = g.finish();
        assert_eq!(t.len(), 4);
        assert_eq!(y[3], vec![3.0]);
    }
}

//! What a successful integration returns: values at the output times, the
//! dense output of every accepted step, the names of the unknowns and the
//! work counters.

use crate::error::SolutionError;
use crate::stats::Stats;

/// Solution values at the requested output times, the dense output of the
/// whole horizon, and statistics.
///
/// * [`Solution::t`] and [`Solution::y`]: the values at
///   [`Options::output_times`](crate::Options::output_times) and `t_end`.
/// * [`Solution::at`] (and the allocation-free [`Solution::at_into`]): the
///   value at any time of `[t0, t_end]`, from the method's own dense output
///   kept for every accepted step ([`DenseOutput`]; on by default, see
///   [`Options::dense_output`](crate::Options::dense_output)).
/// * By name: [`Solution::value`] at any time, [`Solution::component`] at
///   the output times, [`Solution::index_of`] for the position.
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
/// // Any time of the horizon, after the solve, and by name.
/// let y = solution.at(0.3).unwrap();
/// assert!((y[0] - (-0.3f64).exp()).abs() < 1e-9);
/// assert_eq!(solution.value(0.3, "y").unwrap(), y[0]);
/// assert_eq!(solution.component("y").unwrap(), [solution.y[0][0], solution.y[1][0], solution.y[2][0]]);
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
    /// Names of the unknowns, in the order of `y` (the formulation's
    /// `info().variables`).
    pub names: Vec<String>,
    /// The dense output of every accepted step, when
    /// [`Options::dense_output`](crate::Options::dense_output) is on.
    pub dense: Option<DenseOutput>,
    /// The located events ([`crate::core::events`]), in time order: the
    /// zero crossings of the model's event functions that
    /// [`Options::events`](crate::Options::events) admits.
    pub events: Vec<crate::Event>,
}

impl Solution {
    /// Append the run that restarted at the end of this one after a reset
    /// (its output times, step points, dense output, events and work).
    pub(crate) fn append(&mut self, later: Solution) {
        self.t.extend(later.t);
        self.y.extend(later.y);
        self.steps.extend(later.steps);
        self.stats += later.stats;
        self.events.extend(later.events);
        let joined = match (&mut self.dense, &later.dense) {
            (Some(dense), Some(later)) => dense.append(later),
            _ => false,
        };
        if !joined {
            self.dense = None;
        }
    }

    /// The value at the last output time.
    pub fn last(&self) -> Option<&[f64]> {
        self.y.last().map(|v| v.as_slice())
    }

    /// The solution at any time `t` of the horizon, by the dense output of
    /// the step that covers it (see [`DenseOutput`] for what that
    /// reproduces). Allocates the returned vector only; see
    /// [`Solution::at_into`] for a caller's buffer.
    ///
    /// ```
    /// use dae::dae_solvers::{init, radau5::Radau5, SolutionError};
    /// use dae::models::builtin::Pendulum;
    /// use dae::prelude::*;
    ///
    /// let sys = Pendulum::default().rcd1();
    /// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
    /// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 2.0 };
    /// let sol = Radau5.solve(&problem, &Options::with_tol(1e-10))?;
    /// // Half a period (1 s at the paper's g): the other side, x = −1.
    /// let y = sol.at(1.0).unwrap();
    /// assert!((y[0] + 1.0).abs() < 1e-7 && y[1].abs() < 1e-6);
    /// // The start is the initial value; a step point the accepted value.
    /// assert_eq!(sol.at(0.0).unwrap(), start.y);
    /// let end = sol.at(2.0).unwrap();
    /// assert!(end.iter().zip(sol.last().unwrap()).all(|(a, b)| (a - b).abs() < 1e-12));
    /// // Outside the horizon: a typed error.
    /// assert!(matches!(sol.at(2.5), Err(SolutionError::OutsideHorizon { .. })));
    /// # Ok::<(), SolveError>(())
    /// ```
    pub fn at(&self, t: f64) -> Result<Vec<f64>, SolutionError> {
        let mut out = vec![0.0; self.names.len()];
        self.at_into(t, &mut out)?;
        Ok(out)
    }

    /// [`Solution::at`] into `out` (length N), without allocating: for
    /// sampling a trajectory in a loop.
    ///
    /// ```
    /// use dae::dae_solvers::{init, radau5::Radau5, SolutionError};
    /// use dae::models::builtin::Pendulum;
    /// use dae::prelude::*;
    ///
    /// let sys = Pendulum::default().rcd0();
    /// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
    /// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 2.0 };
    /// let sol = Radau5.solve(&problem, &Options::with_tol(1e-8))?;
    /// let mut y = [0.0; 5];
    /// for k in 0..=100 {
    ///     sol.at_into(2.0 * k as f64 / 100.0, &mut y).unwrap();
    ///     assert!((y[0] * y[0] + y[1] * y[1] - 1.0).abs() < 1e-6); // on the circle
    /// }
    /// let err = sol.at_into(1.0, &mut [0.0; 4]).unwrap_err();
    /// assert_eq!(err, SolutionError::LengthMismatch { expected: 5, got: 4 });
    /// # Ok::<(), SolveError>(())
    /// ```
    pub fn at_into(&self, t: f64, out: &mut [f64]) -> Result<(), SolutionError> {
        let dense = self.dense.as_ref().ok_or(SolutionError::NoDenseOutput)?;
        dense.at_into(t, out)
    }

    /// Position of the unknown `name` in `y`, or
    /// [`SolutionError::UnknownName`] with the closest name and the list.
    pub fn index_of(&self, name: &str) -> Result<usize, SolutionError> {
        index_of(&self.names, name)
    }

    /// The unknown `name` at time `t` (any time of the horizon, by dense
    /// output).
    ///
    /// ```
    /// use dae::dae_solvers::{init, bdf::Bdf};
    /// use dae::models::builtin::Pendulum;
    /// use dae::prelude::*;
    ///
    /// let sys = Pendulum::default().rcd0();
    /// let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
    /// let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 2.0 };
    /// let sol = Bdf.solve(&problem, &Options::with_tol(1e-8))?;
    /// assert_eq!(sol.names, ["x", "y", "v", "w", "lambda"]);
    /// let x = sol.value(0.7, "x").unwrap();
    /// assert_eq!(x, sol.at(0.7).unwrap()[sol.index_of("x").unwrap()]);
    /// // A misspelt name: the closest one and the list.
    /// let err = sol.value(0.7, "lamda").unwrap_err();
    /// assert_eq!(
    ///     err.to_string(),
    ///     "no unknown named `lamda` (did you mean `lambda`?); the unknowns are x, y, v, w, lambda"
    /// );
    /// # Ok::<(), SolveError>(())
    /// ```
    pub fn value(&self, t: f64, name: &str) -> Result<f64, SolutionError> {
        let i = self.index_of(name)?;
        let dense = self.dense.as_ref().ok_or(SolutionError::NoDenseOutput)?;
        dense.component_at(t, i)
    }

    /// The unknown `name` at each output time [`Solution::t`].
    pub fn component(&self, name: &str) -> Result<Vec<f64>, SolutionError> {
        let i = self.index_of(name)?;
        Ok(self.y.iter().map(|y| y[i]).collect())
    }
}

/// Position of `name` in `names`, or the typed error with the closest
/// name ([`dae_core::names::did_you_mean`]) and the list.
pub(crate) fn index_of(names: &[String], name: &str) -> Result<usize, SolutionError> {
    if let Some(i) = names.iter().position(|n| n == name) {
        return Ok(i);
    }
    let suggestion = dae_core::names::did_you_mean(name, names).map(str::to_string);
    Err(SolutionError::UnknownName {
        name: name.to_string(),
        suggestion,
        known: names.to_vec(),
    })
}

/// Largest number of nodes per step ([`DenseOutput::degree`]): the highest
/// degree of any method's dense polynomial (mebdf's order 8, idec's
/// `m ≤ 8`).
const MAX_DEGREE: usize = 8;

/// The dense output of a whole integration: the method's own dense
/// polynomial of every accepted step, sampled at `d + 1` Chebyshev–Lobatto
/// nodes `θ_j = (1 − cos(jπ/d))/2` of the step (`θ_0 = 0` its start,
/// `θ_d = 1` its end, where the accepted value is stored) and interpolated
/// there by the barycentric Lagrange formula (Berrut & Trefethen, SIAM
/// Review 46, 2004), the step found by binary search.
///
/// `d` is the degree of the method's dense polynomial
/// ([`DenseOutput::degree`]), so the interpolant *is* that polynomial, up
/// to rounding: [`crate::Solution::at`] returns what the method's own
/// dense output returned on that step, at any time, after the solve.
///
/// | solver | dense polynomial on a step | `d` |
/// |---|---|---|
/// | radau5, odradau | the collocation polynomial (RADAU5's `CONTR5`) | 3 |
/// | gauss | the Hermite polynomial through the last four step points' values and slopes (`core::hermite`; the algebraic unknowns of a split formulation keep the collocation polynomial, see [`crate::gauss`]) | 7 |
/// | bdf, odbdf | DASSL's interpolant through the last `k + 1` values | `max_order` (≤ 5) |
/// | mebdf | the interpolant of the last step's order through the last values | order bound (≤ 8) |
/// | idec | the degree-`m` polynomial on the interval's nodes | `m` |
///
/// With a constant step ([`Options::fixed_step`](crate::Options::fixed_step)),
/// bdf and mebdf first run an adaptive start-up integration: its steps are
/// kept like any other. The step ends are the accepted values exactly, so
/// `at` at a step point returns the step point (a time shared by two steps
/// is answered by the earlier one). Inside a step the value is the
/// method's polynomial, also at its start: that is the previous step
/// point up to rounding for every method but gauss's algebraic unknowns,
/// whose collocation polynomial is shifted by the step's end-point
/// correction.
///
/// Memory: `(d + 1) · N + 1` doubles per accepted step (`N` unknowns);
/// e.g. 21 per step for radau5 on the 5-unknown pendulum: 277 kB for the
/// 1 651 steps of one period of rcd1 at tolerance 1e-10.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DenseOutput {
    /// Unknowns `N`.
    n: usize,
    /// Nodes per step `d` (the interpolation degree).
    degree: usize,
    /// `t₀` and the end of every accepted step.
    t: Vec<f64>,
    /// The values at every node, `N` each: `y₀`, then `d + 1` per step
    /// (nodes `θ_0 … θ_d`), so node `j` of step `i` (1-based) starts at
    /// `N (1 + (i − 1)(d + 1) + j)`.
    values: Vec<f64>,
    /// Chebyshev–Lobatto nodes `θ_0 … θ_d` on `[0, 1]`.
    nodes: Vec<f64>,
    /// Their barycentric weights `(−1)^j δ_j`, `δ = 1/2` at the ends.
    weights: Vec<f64>,
}

impl DenseOutput {
    /// Dense output of degree `degree` (clamped to `1..=MAX_DEGREE`) for
    /// `y0.len()` unknowns starting at `(t0, y0)`.
    pub(crate) fn new(degree: usize, t0: f64, y0: &[f64]) -> Self {
        let d = degree.clamp(1, MAX_DEGREE);
        let nodes = (0..=d)
            .map(|j| 0.5 * (1.0 - (std::f64::consts::PI * j as f64 / d as f64).cos()))
            .collect();
        let weights = (0..=d)
            .map(|j| {
                let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
                if j == 0 || j == d {
                    0.5 * sign
                } else {
                    sign
                }
            })
            .collect();
        DenseOutput {
            n: y0.len(),
            degree: d,
            t: vec![t0],
            values: y0.to_vec(),
            nodes,
            weights,
        }
    }

    /// Append the steps of `later`, a run of the same method that starts
    /// where this one ends (after a reset: its first step starts from the
    /// reset values, and the time of the reset answers this run's value).
    /// `false` (nothing appended) when the two differ in size or degree.
    pub(crate) fn append(&mut self, later: &DenseOutput) -> bool {
        if later.n != self.n || later.degree != self.degree {
            return false;
        }
        self.t.extend_from_slice(&later.t[1..]);
        self.values.extend_from_slice(&later.values[self.n..]);
        true
    }

    /// Record the accepted step ending at `t` with value `y`, its interior
    /// nodes from `dense(time, out)`.
    pub(crate) fn push(&mut self, t: f64, y: &[f64], mut dense: impl FnMut(f64, &mut [f64])) {
        let start = self.t[self.t.len() - 1];
        let h = t - start;
        let n = self.n;
        for j in 0..self.degree {
            let at = self.values.len();
            self.values.resize(at + n, 0.0);
            dense(start + self.nodes[j] * h, &mut self.values[at..]);
        }
        self.values.extend_from_slice(y);
        self.t.push(t);
    }

    /// Number of unknowns `N`.
    pub fn unknowns(&self) -> usize {
        self.n
    }

    /// Nodes per step: the degree of the interpolant on each step.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// `t₀` and the end of every accepted step, ascending.
    pub fn step_ends(&self) -> &[f64] {
        &self.t
    }

    /// The horizon covered, `[t₀, t_end]`.
    pub fn horizon(&self) -> (f64, f64) {
        (self.t[0], self.t[self.t.len() - 1])
    }

    /// The step containing `t` (1-based: step `i` is `[t_{i−1}, t_i]`) and
    /// `θ = (t − t_{i−1})/h_i`, or the typed error outside the horizon.
    fn locate(&self, t: f64) -> Result<(usize, f64), SolutionError> {
        let (t0, t_end) = self.horizon();
        if !(t >= t0 && t <= t_end) {
            return Err(SolutionError::OutsideHorizon { t, t0, t_end });
        }
        if t == t0 || self.t.len() == 1 {
            // `y₀` itself.
            return Ok((0, 0.0));
        }
        let i = self.t.partition_point(|&s| s < t).max(1);
        let theta = (t - self.t[i - 1]) / (self.t[i] - self.t[i - 1]);
        Ok((i, theta))
    }

    /// Call `f(offset, c)` for every node of the step containing `t` with
    /// its normalised barycentric coefficient `c` (the values at that node
    /// start at `offset`).
    fn coefficients(&self, t: f64, mut f: impl FnMut(usize, f64)) -> Result<(), SolutionError> {
        let (i, theta) = self.locate(t)?;
        let n = self.n;
        if i == 0 {
            f(0, 1.0);
            return Ok(());
        }
        let first = 1 + (i - 1) * (self.degree + 1);
        if let Some(j) = self.nodes.iter().position(|&x| x == theta) {
            f((first + j) * n, 1.0);
            return Ok(());
        }
        let sum: f64 = (0..=self.degree)
            .map(|j| self.weights[j] / (theta - self.nodes[j]))
            .sum();
        for j in 0..=self.degree {
            f(
                (first + j) * n,
                self.weights[j] / (theta - self.nodes[j]) / sum,
            );
        }
        Ok(())
    }

    /// The solution at `t` into `out` (length `N`), without allocating.
    pub fn at_into(&self, t: f64, out: &mut [f64]) -> Result<(), SolutionError> {
        if out.len() != self.n {
            return Err(SolutionError::LengthMismatch {
                expected: self.n,
                got: out.len(),
            });
        }
        // Checked before the buffer is touched: no partial write.
        self.locate(t)?;
        out.fill(0.0);
        self.coefficients(t, |at, c| {
            for (o, v) in out.iter_mut().zip(&self.values[at..at + self.n]) {
                *o += c * v;
            }
        })
    }

    /// Unknown `i` at `t`.
    fn component_at(&self, t: f64, i: usize) -> Result<f64, SolutionError> {
        let mut v = 0.0;
        self.coefficients(t, |at, c| v += c * self.values[at + i])?;
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A polynomial of degree `d` in each component is reproduced to
    /// rounding on steps of unequal length, at the nodes and between them.
    #[test]
    fn polynomials_up_to_the_degree_are_reproduced() {
        for d in 1..=MAX_DEGREE {
            let p = |t: f64, k: usize| -> f64 {
                (0..=d)
                    .map(|e| (k as f64 + 1.0) * 0.3f64.powi(e as i32) * t.powi(e as i32))
                    .sum()
            };
            let y = |t: f64| vec![p(t, 0), p(t, 1)];
            let mut dense = DenseOutput::new(d, -1.0, &y(-1.0));
            for t in [-0.4, 0.1, 1.7, 2.0] {
                dense.push(t, &y(t), |s, out| out.copy_from_slice(&y(s)));
            }
            assert_eq!(dense.step_ends(), [-1.0, -0.4, 0.1, 1.7, 2.0]);
            let mut out = [0.0; 2];
            for k in 0..=300 {
                let t = -1.0 + 3.0 * k as f64 / 300.0;
                dense.at_into(t, &mut out).unwrap();
                let exact = y(t);
                for c in 0..2 {
                    assert!(
                        (out[c] - exact[c]).abs() < 1e-13 * (1.0 + exact[c].abs()),
                        "degree {d}, t = {t}: {} vs {}",
                        out[c],
                        exact[c]
                    );
                    assert_eq!(dense.component_at(t, c).unwrap(), out[c]);
                }
            }
            // Step ends exactly.
            dense.at_into(1.7, &mut out).unwrap();
            assert_eq!(out.to_vec(), y(1.7));
        }
    }

    #[test]
    fn typed_errors_and_no_partial_write() {
        let mut dense = DenseOutput::new(3, 0.0, &[1.0]);
        dense.push(1.0, &[2.0], |s, out| out[0] = 1.0 + s);
        let mut out = [7.0];
        assert_eq!(
            dense.at_into(1.5, &mut out),
            Err(SolutionError::OutsideHorizon {
                t: 1.5,
                t0: 0.0,
                t_end: 1.0
            })
        );
        assert!(dense.at_into(f64::NAN, &mut out).is_err());
        assert_eq!(out, [7.0]);
        assert_eq!(
            dense.at_into(0.5, &mut [0.0; 2]),
            Err(SolutionError::LengthMismatch {
                expected: 1,
                got: 2
            })
        );
        let names = vec!["x".to_string(), "lambda".to_string()];
        assert_eq!(index_of(&names, "lambda"), Ok(1));
        match index_of(&names, "lamdba") {
            Err(SolutionError::UnknownName { suggestion, .. }) => {
                assert_eq!(suggestion.as_deref(), Some("lambda"))
            }
            other => panic!("{other:?}"),
        }
        match index_of(&names, "velocity") {
            Err(SolutionError::UnknownName {
                suggestion, known, ..
            }) => {
                assert_eq!(suggestion, None);
                assert_eq!(known, names);
            }
            other => panic!("{other:?}"),
        }
    }
}

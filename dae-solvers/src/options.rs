//! Tolerances and solver options (the error weights and the norm are `core::weights`).

use crate::error::SolveError;

/// A tolerance: one value for every component or one per component.
#[derive(Clone, Debug, PartialEq)]
pub enum Tol {
    /// The same value for every component.
    Scalar(f64),
    /// One value per unknown.
    PerComponent(Vec<f64>),
}

impl Tol {
    fn get(&self, i: usize) -> f64 {
        match self {
            Tol::Scalar(v) => *v,
            Tol::PerComponent(v) => v[i],
        }
    }

    fn check(&self, name: &str, n: usize) -> Result<(), SolveError> {
        let values: &[f64] = match self {
            Tol::Scalar(v) => std::slice::from_ref(v),
            Tol::PerComponent(v) => {
                if v.len() != n {
                    return Err(SolveError::invalid(format!(
                        "{name} has {} components, the system has {n} unknowns",
                        v.len()
                    )));
                }
                v
            }
        };
        for (i, &v) in values.iter().enumerate() {
            if !v.is_finite() || v < 0.0 {
                return Err(SolveError::invalid(format!(
                    "{name}[{i}] = {v} must be finite and non-negative"
                )));
            }
        }
        Ok(())
    }
}

/// Relative and absolute tolerances. The error weight of component `i` is
/// `1 / (atol_i + rtol_i |y_i|)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance.
    pub rtol: Tol,
    /// Absolute tolerance.
    pub atol: Tol,
}

impl Tolerances {
    /// `RTOL = ATOL = tol` for every component, as in the paper.
    pub fn uniform(tol: f64) -> Self {
        Tolerances {
            rtol: Tol::Scalar(tol),
            atol: Tol::Scalar(tol),
        }
    }

    /// Check the tolerances against a system with `n` unknowns: every value
    /// finite and non-negative, lengths matching, and for each component
    /// `rtol + atol > 0`.
    pub fn validate(&self, n: usize) -> Result<(), SolveError> {
        self.rtol.check("rtol", n)?;
        self.atol.check("atol", n)?;
        for i in 0..n {
            if self.rtol.get(i) + self.atol.get(i) <= 0.0 {
                return Err(SolveError::invalid(format!(
                    "rtol[{i}] + atol[{i}] must be positive"
                )));
            }
        }
        Ok(())
    }

    /// Relative tolerance of component `i`.
    pub fn rtol(&self, i: usize) -> f64 {
        self.rtol.get(i)
    }

    /// Absolute tolerance of component `i`.
    pub fn atol(&self, i: usize) -> f64 {
        self.atol.get(i)
    }
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances::uniform(1e-6)
    }
}

/// Solver options. Tunables are fields with a [`Default`], so new options do
/// not break callers.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Error tolerances.
    pub tol: Tolerances,
    /// Initial step size; chosen by the solver when `None`.
    pub h0: Option<f64>,
    /// Largest step size; `t_end - t0` when `None`.
    pub h_max: Option<f64>,
    /// Maximum number of steps (accepted + rejected) before
    /// [`SolveError::StepLimit`].
    pub max_steps: usize,
    /// Times at which to report the solution (dense output). Times outside
    /// `[t0, t_end]` are ignored, repeats reported once; `t_end` is always
    /// reported last (see `core::output` for the one rule).
    pub output_times: Vec<f64>,
    /// Record every accepted step in [`crate::Solution::steps`].
    pub record_steps: bool,
    /// BDF-type methods only: include index-2 (and higher) unknowns in the
    /// error test. `None` (the default) leaves the decision to the
    /// formulation, in [`crate::core::policy::bdf_error_test`]: they are
    /// left out, DASPK's option that lets index-2 formulations run.
    pub index2_in_error_test: Option<bool>,
    /// Integrate with this constant step size and no error control
    /// (convergence studies).
    pub fixed_step: Option<f64>,
    /// BDF only: use this order only (1–5).
    pub fixed_order: Option<usize>,
    /// BDF only: largest order (1–5).
    pub max_order: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            tol: Tolerances::default(),
            h0: None,
            h_max: None,
            max_steps: 20_000_000,
            output_times: Vec::new(),
            record_steps: false,
            index2_in_error_test: None,
            fixed_step: None,
            fixed_order: None,
            max_order: 5,
        }
    }
}

impl Options {
    /// Options with uniform tolerance `tol`.
    pub fn with_tol(tol: f64) -> Self {
        Options {
            tol: Tolerances::uniform(tol),
            ..Options::default()
        }
    }

    /// Validate against a problem with `n` unknowns on `[t0, t_end]`.
    pub fn validate(&self, n: usize, t0: f64, t_end: f64) -> Result<(), SolveError> {
        self.tol.validate(n)?;
        if !t0.is_finite() || !t_end.is_finite() || t_end <= t0 {
            return Err(SolveError::invalid(format!(
                "time span [{t0}, {t_end}] must be finite with t_end > t0"
            )));
        }
        for (name, v) in [
            ("h0", self.h0),
            ("h_max", self.h_max),
            ("fixed_step", self.fixed_step),
        ] {
            if let Some(h) = v {
                if !h.is_finite() || h <= 0.0 {
                    return Err(SolveError::invalid(format!(
                        "{name} = {h} must be positive"
                    )));
                }
            }
        }
        if self.max_steps == 0 {
            return Err(SolveError::invalid("max_steps must be at least 1"));
        }
        if !(1..=5).contains(&self.max_order) {
            return Err(SolveError::invalid(format!(
                "max_order = {} must be in 1..=5",
                self.max_order
            )));
        }
        if let Some(k) = self.fixed_order {
            if !(1..=5).contains(&k) {
                return Err(SolveError::invalid(format!(
                    "fixed_order = {k} must be in 1..=5"
                )));
            }
        }
        if self.output_times.iter().any(|t| !t.is_finite()) {
            return Err(SolveError::invalid("output_times must be finite"));
        }
        Ok(())
    }
}

//! Tolerances and solver options (the error weights and the norm are `core::weights`).

use crate::error::SolveError;
use serde::Serialize;

/// A tolerance: one value for every component or one per component (the
/// two halves of [`Tolerances`]).
///
/// ```
/// use dae_solvers::{Options, Tol, Tolerances};
///
/// // Five unknowns (x, y, v, w, λ): relative 1e-8 on the positions and
/// // velocities, none on the multiplier λ, which gets an absolute 1e-6.
/// let tol = Tolerances {
///     rtol: Tol::PerComponent(vec![1e-8, 1e-8, 1e-8, 1e-8, 0.0]),
///     atol: Tol::PerComponent(vec![1e-10, 1e-10, 1e-10, 1e-10, 1e-6]),
/// };
/// assert!(tol.validate(5).is_ok());
/// assert_eq!((tol.rtol(4), tol.atol(4)), (0.0, 1e-6));
/// // A per-component tolerance must have one value per unknown.
/// assert!(tol.validate(6).is_err());
/// let options = Options { tol, ..Options::default() };
/// assert_eq!(options.tol.rtol(0), 1e-8);
/// ```
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

    fn check(&self, name: &'static str, n: usize) -> Result<(), SolveError> {
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
                    "{name}[{i}] = {v:e} must be finite and non-negative"
                )));
            }
            if name == "rtol" {
                if let Err(issue) = check_relative(v) {
                    return Err(SolveError::ToleranceOutOfRange {
                        name,
                        index: match self {
                            Tol::Scalar(_) => None,
                            Tol::PerComponent(_) => Some(i),
                        },
                        value: v,
                        issue,
                    });
                }
            }
        }
        Ok(())
    }
}

/// The smallest relative tolerance a solver accepts: `100 ε ≈ 2.2·10⁻¹⁴`.
///
/// A step's local error is estimated from differences of values near
/// `|y|`, each rounded to `ε|y|/2`; below about `100 ε` that estimate is
/// dominated by round-off, so a smaller tolerance cannot be met, only
/// chased: BDF at `1e-16` took 20 million ever smaller steps before its
/// step limit, and RADAU5 silently floored it to `100 ε`. Refusing it
/// says so instead. See [`Options`] for the whole rule.
pub const RTOL_MIN: f64 = 100.0 * f64::EPSILON;

/// Relative tolerances must be below this (exclusive): at 1 or more the
/// error test accepts an error as large as the solution itself, so a
/// "successful" run can be anything (tol 1e300 gave `x = −29.3` on a unit
/// pendulum).
pub const RTOL_MAX: f64 = 1.0;

/// Why a tolerance value is refused (see [`Options`] for the rule).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ToleranceIssue {
    /// NaN or infinite.
    #[error("is not a finite number")]
    NotFinite,
    /// Below zero.
    #[error("is negative")]
    Negative,
    /// Zero where a positive value is needed (a uniform tolerance).
    #[error("is zero")]
    Zero,
    /// Positive but below [`RTOL_MIN`].
    #[error(
        "is below 100·ε = 2.220446049250313e-14, the smallest relative tolerance double precision can honour"
    )]
    BelowRoundOff,
    /// At or above [`RTOL_MAX`].
    #[error("is not below 1: a relative tolerance of 100% or more controls nothing")]
    NotBelowOne,
}

/// The rule for one relative tolerance: `0` (a purely absolute tolerance
/// for that component) or `RTOL_MIN ≤ rtol < RTOL_MAX`.
///
/// ```
/// use dae_solvers::options::{check_relative, ToleranceIssue};
///
/// assert!(check_relative(1e-8).is_ok() && check_relative(0.0).is_ok());
/// assert_eq!(check_relative(1e-16), Err(ToleranceIssue::BelowRoundOff));
/// assert_eq!(check_relative(1.0), Err(ToleranceIssue::NotBelowOne));
/// ```
pub fn check_relative(rtol: f64) -> Result<(), ToleranceIssue> {
    if !rtol.is_finite() {
        Err(ToleranceIssue::NotFinite)
    } else if rtol < 0.0 {
        Err(ToleranceIssue::Negative)
    } else if rtol == 0.0 {
        Ok(())
    } else if rtol < RTOL_MIN {
        Err(ToleranceIssue::BelowRoundOff)
    } else if rtol >= RTOL_MAX {
        Err(ToleranceIssue::NotBelowOne)
    } else {
        Ok(())
    }
}

/// The rule for a uniform tolerance `RTOL = ATOL = tol` (the paper's
/// convention, used by `dae run --tol`, `dae sweep --tols` and scene
/// files): `RTOL_MIN ≤ tol < RTOL_MAX`. This is [`check_relative`] without
/// the purely absolute case, so [`Options::with_tol`] validates exactly
/// when this returns `Ok`.
///
/// ```
/// use dae_solvers::options::{check_uniform, ToleranceIssue};
///
/// assert!(check_uniform(1e-12).is_ok());
/// assert_eq!(check_uniform(0.0), Err(ToleranceIssue::Zero));
/// assert_eq!(check_uniform(2.0), Err(ToleranceIssue::NotBelowOne));
/// assert_eq!(check_uniform(f64::NAN), Err(ToleranceIssue::NotFinite));
/// ```
pub fn check_uniform(tol: f64) -> Result<(), ToleranceIssue> {
    if tol == 0.0 {
        return Err(ToleranceIssue::Zero);
    }
    check_relative(tol)
}

/// The accepted range of a uniform tolerance, for messages, its lower
/// bound written in full: a rounded bound (`2.2e-14`) would name a value
/// that is itself refused (issue 27, defect 9).
///
/// ```
/// use dae_solvers::options::{check_uniform, uniform_range, RTOL_MIN};
///
/// assert_eq!(uniform_range(), "[2.220446049250313e-14, 1)");
/// // The bound as written is the bound applied.
/// assert_eq!("2.220446049250313e-14".parse::<f64>(), Ok(RTOL_MIN));
/// assert!(check_uniform(2.220446049250313e-14).is_ok());
/// assert!(check_uniform(2.2e-14).is_err());
/// ```
pub fn uniform_range() -> String {
    format!("[{RTOL_MIN:e}, {RTOL_MAX})")
}

/// Relative and absolute tolerances. The error weight of component `i` is
/// `1 / (atol_i + rtol_i |y_i|)`. The values a solver accepts are stated
/// on [`Options`].
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

    /// Check the tolerances against a system with `n` unknowns: lengths
    /// matching, every value finite and non-negative, and for each
    /// component `rtol + atol > 0` ([`SolveError::InvalidInput`] otherwise);
    /// every relative tolerance `0` or in `[RTOL_MIN, RTOL_MAX)`
    /// ([`SolveError::ToleranceOutOfRange`] otherwise). See [`Options`].
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
///
/// # Tolerances
///
/// Every solver validates [`Options::tol`] before it starts, with one rule
/// (the command line and scene files apply the same rule to their uniform
/// `RTOL = ATOL = tol` through [`check_uniform`]):
///
/// * every `rtol_i` and `atol_i` finite and non-negative, their sum
///   `rtol_i + atol_i > 0`, lengths matching the system — else
///   [`SolveError::InvalidInput`];
/// * every `rtol_i` either `0` (a purely absolute tolerance for that
///   component) or in `[RTOL_MIN, RTOL_MAX)` = `[100 ε, 1)` ≈ `[2.2e-14,
///   1)` — else [`SolveError::ToleranceOutOfRange`], naming `rtol`, the
///   component (for per-component tolerances) and the value.
///
/// Tolerances are never clamped silently: below `100 ε` the error
/// estimate is round-off and cannot be met (BDF used to grind to its step
/// limit; RADAU5 floored the value without a word), and at `1` or more it
/// accepts anything. `atol_i` has the units of component `i`, so it has no
/// bound besides being finite; a purely absolute tolerance (`rtol_i = 0`)
/// below the round-off of the component's magnitude cannot be detected in
/// advance and is the caller's responsibility.
///
/// ```
/// use dae_solvers::{Options, SolveError};
///
/// assert!(Options::with_tol(1e-10).validate(5, 0.0, 1.0).is_ok());
/// for tol in [1e-16, 1.0, 1e300] {
///     let err = Options::with_tol(tol).validate(5, 0.0, 1.0).unwrap_err();
///     assert!(matches!(err, SolveError::ToleranceOutOfRange { name: "rtol", .. }));
///     assert!(err.to_string().contains(&format!("rtol = {tol:e}")));
/// }
/// ```
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
    /// Keep the dense output of every accepted step, so that
    /// [`crate::Solution::at`] answers at any time of the horizon after the
    /// solve (and [`crate::Integrator::advance_to`] at any earlier time).
    ///
    /// On by default: a user expects `solution.at(t)` to work, as it does
    /// in DifferentialEquations.jl (`sol(t)`) and diffsol. It costs
    /// `(d + 1) · N + 1` doubles per accepted step (`d` ≤ 8 the degree of
    /// the method's dense polynomial, see [`crate::solution::DenseOutput`])
    /// and `d` dense evaluations per step (no residual evaluations, no
    /// change in the steps taken). Long runs that need only the output
    /// times — the sweep, the benchmarks — switch it off.
    pub dense_output: bool,
    /// BDF-type methods: include index-2 (and higher) unknowns in the
    /// error test. `None` (the default) leaves the decision to the
    /// formulation, in [`crate::core::policy::bdf_error_test`]: they are
    /// left out, DASPK's option that lets index-2 formulations run.
    /// Radau-type methods keep a state's in any case and leave the
    /// index-2 unknowns of its forward sensitivities out unless this is
    /// `Some(true)` ([`crate::core::policy::collocation_error_test`]).
    pub index2_in_error_test: Option<bool>,
    /// Integrate with this constant step size and no error control
    /// (convergence studies).
    pub fixed_step: Option<f64>,
    /// Multistep methods only: use this order only. Its meaning and range
    /// are the method's: the BDF methods (`bdf`, `odbdf`) take the order
    /// `1..=5`; `mebdf` takes the step number `k` of its formulas, `1..=7`
    /// (order `k + 1`, up to 8). [`Options::validate`] checks only
    /// `1..=`[`ORDER_BOUND`]; a method refuses what it cannot do with
    /// [`SolveError::InvalidInput`] naming the field and its range. The
    /// Runge–Kutta methods (`radau5`, `odradau`) ignore it.
    pub fixed_order: Option<usize>,
    /// Multistep methods only: largest order, with the meaning and range of
    /// [`Options::fixed_order`]. The default 5 is order 5 for the BDF
    /// methods and step number 5 (orders up to 6) for `mebdf`;
    /// `max_order = 7` lets `mebdf` reach order 8.
    pub max_order: usize,
    /// How the model's events (its `events { … }` section,
    /// [`dae_core::system::DaeSystem::events`]) are treated: each rule
    /// names one event and says which crossings count and whether it
    /// stops the run or resets state ([`crate::EventSpec`]). Every event
    /// of the model is located and reported in
    /// [`crate::Solution::events`]; one not named here is recorded in both
    /// directions. A rule naming no event of the model is
    /// [`SolveError::UnknownEvent`]. See [`crate::core::events`].
    pub events: Vec<crate::EventSpec>,
    /// The multistep methods (`bdf`, `odbdf`, `mebdf`): how the local error
    /// is estimated ([`Estimate`]; the default checks the method's own
    /// estimate against the propagated one after each new iteration matrix
    /// or rejected step). Other methods ignore it.
    pub estimate: Estimate,
}

/// How the multistep methods estimate the local error of a step
/// ([`Options::estimate`]).
///
/// DASSL estimates it by the corrector's distance from the predictor,
/// `e = y − y⁽⁰⁾`, in every component. For a differential component that
/// is the error of the step; for an algebraic one (an unknown the
/// equations fix through `f`, not `E y'`) it is the error of extrapolating
/// that unknown's own history — its curvature — while the step's error in
/// it is the one the constraints carry over from the differential
/// components. The two differ where the constraints are strongly
/// nonlinear or amplify: on the IVP Test Set's transistor amplifier
/// DASSL's estimate of the amplifier's output misses by a factor of 20–30 at
/// equal steps, and its step control cycles at order one in bursts over
/// the rest of the run (1.4 M steps at 1e-10; BENCHMARKS.md §18). The iteration matrix
/// `G = ∂F/∂y + c_J E` carries the differential part of `e` onto the
/// algebraic components: `ẽ = G⁻¹ (c_J E e)`, RADAU5's filtered estimate
/// (Hairer & Wanner, *Solving ODEs II*, §IV.8; Shampine 1980 for stiff
/// ODEs), for an index-1 DAE the linearised constraints' image of the
/// differential components' estimate. The *propagated* estimate is, in
/// each component, the larger of `|e_i|` and `|ẽ_i|` — never below
/// DASSL's — and the order selection's terms are formed alike.
///
/// ```
/// use dae_solvers::{options::Estimate, Options};
///
/// assert_eq!(Options::default().estimate, Estimate::Checked);
/// // DASSL's own estimate: the port takes the Fortran DASSL's steps.
/// let dassl = Options { estimate: Estimate::Dassl, ..Options::with_tol(1e-8) };
/// assert_ne!(dassl.estimate, Options::default().estimate);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Estimate {
    /// The method's own (DASSL's) estimate, checked: the first error test
    /// after each new iteration matrix or rejected step also forms the
    /// propagated estimate of `e`, and once that exceeds DASSL's tenfold
    /// the run propagates every estimate to its end. A check costs one solve with the factored matrix. Where
    /// the check never fires (the pendulum's formulations) the run is
    /// DASSL's, step for step. Not applied to an ODE (`d_index = 0`).
    #[default]
    Checked,
    /// The propagated estimate at every step (one to four solves a step).
    /// Not applied to an ODE.
    Propagated,
    /// The method's own alone (DASSL's for `bdf`, ODASSL's for `odbdf`,
    /// Cash's for `mebdf`).
    Dassl,
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
            dense_output: true,
            index2_in_error_test: None,
            fixed_step: None,
            fixed_order: None,
            max_order: 5,
            events: Vec::new(),
            estimate: Estimate::Checked,
        }
    }
}

/// The largest [`Options::max_order`] and [`Options::fixed_order`] that
/// [`Options::validate`] lets through; each method has its own, smaller,
/// limit (see [`Options::fixed_order`]).
pub const ORDER_BOUND: usize = 16;

impl Options {
    /// [`Options::max_order`] and [`Options::fixed_order`] (when set) in
    /// `1..=limit`, else [`SolveError::InvalidInput`] naming the field, its
    /// value, the range and `method` (whose limit it is).
    pub(crate) fn check_orders(&self, limit: usize, method: &str) -> Result<(), SolveError> {
        let fields = [
            ("max_order", Some(self.max_order)),
            ("fixed_order", self.fixed_order),
        ];
        for (name, value) in fields {
            if let Some(v) = value {
                if !(1..=limit).contains(&v) {
                    return Err(SolveError::invalid(format!(
                        "{name} = {v} must be in 1..={limit} for {method}"
                    )));
                }
            }
        }
        Ok(())
    }

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
        self.check_orders(ORDER_BOUND, "any method")?;
        if self.output_times.iter().any(|t| !t.is_finite()) {
            return Err(SolveError::invalid("output_times must be finite"));
        }
        Ok(())
    }
}

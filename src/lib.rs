// The crate docs are the README, so its example is compiled and run as a doctest.
#![doc = include_str!("../README.md")]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![warn(missing_docs)]

extern crate self as dae;

pub use dae_core;
pub use dae_macros::dae;
pub use dae_solvers;

// The library (always built): the re-exports above, the prelude, the
// built-in models and the exact pendulum.
#[doc = include_str!("../docs/guide.md")]
pub mod guide {}
pub mod models;
pub mod reference;

// The command line and what only it needs (scene files, runs with their
// verdicts, sweeps, tables and figures): the `cli` feature, on by default.
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod cli;
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod ensemble;
#[cfg(feature = "cli")]
mod font;
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod inputs;
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod runner;
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod scene;
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod stability;
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod sweep;

/// Everything a user of the macro and the solvers needs.
///
/// ```
/// use dae::prelude::*;
///
/// // Separate relative and absolute tolerances, one value per unknown
/// // where it matters (the README's pendulum: x, y, v, w, λ).
/// let tol = Tolerances {
///     rtol: Tol::Scalar(1e-8),
///     atol: Tol::PerComponent(vec![1e-10, 1e-10, 1e-9, 1e-9, 1e-6]),
/// };
/// let options = Options { tol, ..Options::default() };
/// assert_eq!(options.tol.atol(4), 1e-6);
/// ```
pub mod prelude {
    pub use dae_core::system::{
        BoxedSystem, DaeSystem, FormulationInfo, Model, ModelInfo, RowKind, StaticSize, VarKind,
    };
    pub use dae_macros::dae;
    pub use dae_solvers::{
        Integrator, Options, Problem, Solution, SolutionError, SolveError, Solver, Stats,
        StepOutcome, Tol, Tolerances,
    };
}

/// Runtime support for macro-generated code. Not public API.
#[doc(hidden)]
pub mod __private {
    pub use dae_core::accel;
    pub use dae_core::dummy::boxed as dummy_boxed;
    pub use dae_core::system::{
        check_parameter, BoxedSystem, ConstraintInfo, DaeSystem, FormulationError, FormulationInfo,
        Model, ModelInfo, ParamInfo, ParameterError, RowInfo, RowKind, StaticSize, VarInfo,
        VarKind,
    };
    pub use nalgebra::DMatrix;
    pub use std::boxed::Box;
    pub use std::string::{String, ToString};
    pub use std::sync::OnceLock;
    pub use std::vec::Vec;
}

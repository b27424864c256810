//! # dae — constrained dynamics, every formulation, measured
//!
//! Write a constrained mechanical model once in a `dae! { … }` block; at
//! compile time the toolkit differentiates the constraints symbolically,
//! derives the hidden constraints, and emits every standard regularised
//! formulation of the DAE (`ori2`, `rcd1`, `rcd0`, `ovd1`, `ovd0`, `ggl1`,
//! `psi1`, `psi0`) with analytic Jacobians; the solvers of
//! [`dae_solvers`] integrate them.
//!
//! Crates: [`dae_core`] (model language, symbolic engine, index analysis,
//! formulations, the runtime trait), `dae-macros` (the [`dae!`] macro),
//! [`dae_solvers`] (integrators). This facade re-exports them and holds the
//! scene, reference and report code of the `dae` binary.

extern crate self as dae;

pub use dae_core;
pub use dae_macros::dae;
pub use dae_solvers;

pub mod cli;
pub mod models;
pub mod reference;
pub mod runner;
pub mod scene;
pub mod sweep;

/// Everything a user of the macro and the solvers needs.
pub mod prelude {
    pub use crate::dae;
    pub use dae_core::system::{
        BoxedSystem, DaeSystem, FormulationInfo, Model, ModelInfo, RowKind, StaticSize, VarKind,
    };
    pub use dae_solvers::{Options, Problem, Solution, SolveError, Solver, Stats, Tolerances};
}

/// Runtime support for macro-generated code. Not public API.
#[doc(hidden)]
pub mod __private {
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

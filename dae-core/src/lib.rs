//! Symbolic core of `dae`: the model language, canonical expressions,
//! structural index analysis, the eight formulations with analytic
//! Jacobians, and the runtime trait every solver consumes.
//!
//! The flow, left to right: [`dsl`] (text or tokens → syntax tree) →
//! [`model`] (checked IR) → [`index`] (hidden constraints) →
//! [`formulation`] (symbolic `E(y) y' = f`) → [`compile`] (tapes with the
//! Jacobians) → [`interp`] or the `dae!` macro → [`system::DaeSystem`].
#![warn(missing_docs)]

pub mod accel;
pub mod check;
pub mod compile;
pub mod derive;
pub mod dsl;
pub mod dummy;
pub mod expr;
pub mod formulation;
pub mod index;
pub mod interp;
pub mod lex;
pub mod model;
pub mod names;
pub mod print;
pub mod report;
pub mod selector;
pub mod sensitivity;
pub mod structure;
pub mod system;
pub mod tape;

pub use derive::Derived;

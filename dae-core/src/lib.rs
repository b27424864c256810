//! Symbolic core of `dae`.
pub mod system;

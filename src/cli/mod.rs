//! The `dae` command line: `derive`, `run`, `sweep`.

pub mod derive;
pub mod run;
pub mod sweep;

/// A failed command: the message and the exit code.
#[derive(Debug)]
pub struct Failure {
    /// Exit code: 2 for bad input, 3 for a solver failure.
    pub code: i32,
    /// What to print on stderr.
    pub message: String,
}

impl Failure {
    /// Bad input (scene, model, flags): exit code 2.
    pub fn input(message: impl Into<String>) -> Self {
        Failure {
            code: 2,
            message: message.into(),
        }
    }
}

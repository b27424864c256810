//! The `dae` command line: `derive`, `run`, `sweep`.

pub mod derive;
pub mod run;
pub mod sweep;

/// Exit code: bad input (flags, scene, model, an `--out` a sweep may not
/// replace); nothing was run or written.
pub const EXIT_INPUT: i32 = 2;
/// Exit code of `dae run`: the solver stopped before the end (or could not
/// start: the initialisation failed); the record is on stdout.
pub const EXIT_SOLVER: i32 = 3;
/// Exit code of `dae sweep`: the outputs could not be written (a full disk,
/// permissions, another sweep writing the same `--out`); the previous
/// output set is kept whole.
pub const EXIT_OUTPUT: i32 = 4;
/// Exit code after SIGINT (128 + 2): stopped before the new output set was
/// in place; the previous set is kept whole and no staging is left.
pub const EXIT_INTERRUPTED: i32 = 130;

/// A failed command: the message and the exit code.
#[derive(Debug)]
pub struct Failure {
    /// Exit code: [`EXIT_INPUT`], [`EXIT_SOLVER`] or [`EXIT_OUTPUT`].
    pub code: i32,
    /// What to print on stderr.
    pub message: String,
}

impl Failure {
    /// Bad input (scene, model, flags): exit code 2.
    pub fn input(message: impl Into<String>) -> Self {
        Failure {
            code: EXIT_INPUT,
            message: message.into(),
        }
    }

    /// Outputs that could not be written: exit code 4.
    ///
    /// ```
    /// assert_eq!(dae::cli::Failure::output("disk full").code, 4);
    /// ```
    pub fn output(message: impl Into<String>) -> Self {
        Failure {
            code: EXIT_OUTPUT,
            message: message.into(),
        }
    }

    /// A sweep's error with its exit code: an output it could not write
    /// (the disk, the lock on `--out`) is [`EXIT_OUTPUT`], anything else
    /// bad input.
    pub fn sweep(e: &crate::sweep::SweepError) -> Self {
        use crate::sweep::write::PublishError;
        use crate::sweep::SweepError;
        match e {
            SweepError::Write { .. }
            | SweepError::Figure { .. }
            | SweepError::Publish(PublishError::Busy { .. } | PublishError::Io { .. }) => {
                Failure::output(e.to_string())
            }
            _ => Failure::input(e.to_string()),
        }
    }
}

//! Ensembles: one computation over many variations (parameters, initial
//! values, anything the member describes), in parallel.
//!
//! [`Ensemble::run`] maps a function over a slice of members on a rayon
//! pool and returns one slot per member, **in the members' order**: the
//! member's result, or its failure as a typed [`MemberError`] — the
//! function's own error ([`MemberError::Failed`]) or a panic caught in the
//! member ([`MemberError::Panicked`]). One failing member never stops the
//! others. Each member is computed by one thread from its input alone, so
//! the results are the same, bit for bit, whatever the number of threads
//! (`tests/ensemble.rs` checks it with 1 and 2).
//!
//! A progress bar ([`Ensemble::progress`]) is drawn on stderr when it is a
//! terminal, plain lines otherwise (the sweep's reporter,
//! [`crate::sweep::progress::Progress`]).
//!
//! What every member needs is shared by reference (the function is `Fn +
//! Sync`): a model read at run time is derived once, and each member
//! clones it to set its own parameters (a clone shares the compiled
//! formulations):
//!
//! ```
//! use dae::dae_core::interp::InterpretedModel;
//! use dae::dae_solvers::{init, radau5::Radau5};
//! use dae::ensemble::Ensemble;
//! use dae::prelude::*;
//!
//! type Error = Box<dyn std::error::Error + Send + Sync>;
//! let model = InterpretedModel::from_str(dae::models::PENDULUM_SOURCE)?; // derived once
//! let lengths = [0.5, 1.0, 2.0];
//! let energy = Ensemble::new().run(&lengths, |&l| -> Result<f64, Error> {
//!     let mut m = model.clone();
//!     m.set_parameter("l", l)?;
//!     let sys = m.formulation("ggl1")?;
//!     let start = init::consistent(&*sys, 0.0, &[l, 0.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
//!     let problem = Problem { system: &*sys, t0: 0.0, y0: &start.y, t_end: 1.0 };
//!     let sol = Radau5.solve(&problem, &Options::with_tol(1e-8))?;
//!     let (v, w) = (sol.value(1.0, "v")?, sol.value(1.0, "w")?);
//!     Ok((v * v + w * w) / 2.0 + 13.7503716373294544 * sol.value(1.0, "y")?)
//! })?;
//! for e in &energy {
//!     assert!(e.as_ref().unwrap().abs() < 1e-6); // released at rest at y = 0
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The module is part of the `cli` feature, which brings rayon and
//! indicatif (and the sweep's progress reporter this module reuses); the
//! library without it (`default-features = false`) does not have it.
//!
//! ```
//! use dae::dae_solvers::{init, radau5::Radau5};
//! use dae::ensemble::{Ensemble, MemberError};
//! use dae::models::builtin::Pendulum;
//! use dae::prelude::*;
//!
//! // The pendulum at five values of g: x at t = 1 of each.
//! let gs = [1.0, 4.0, 9.81, 13.75, 20.0];
//! let results = Ensemble::new().threads(2).run(&gs, |&g| -> Result<f64, SolveError> {
//!     let sys = Pendulum { g, ..Pendulum::default() }.ggl1();
//!     let start = init::consistent(&sys, 0.0, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0], &Default::default())?;
//!     let problem = Problem { system: &sys, t0: 0.0, y0: &start.y, t_end: 1.0 };
//!     let sol = Radau5.solve(&problem, &Options::with_tol(1e-8))?;
//!     Ok(sol.last().map_or(f64::NAN, |y| y[0]))
//! })?;
//! assert_eq!(results.len(), 5);
//! assert!(results.iter().all(Result::is_ok));
//!
//! // A member that fails is an error in its own slot.
//! let results = Ensemble::new().run(&[1.0, -1.0, 4.0], |&a: &f64| {
//!     if a > 0.0 { Ok(a.sqrt()) } else { Err(format!("{a} < 0")) }
//! })?;
//! assert_eq!(results[0].as_ref().ok(), Some(&1.0));
//! assert!(matches!(&results[1], Err(MemberError::Failed { index: 1, .. })));
//! assert_eq!(results[2].as_ref().ok(), Some(&2.0));
//! # Ok::<(), dae::ensemble::EnsembleError>(())
//! ```

use crate::sweep::progress::Progress;
use rayon::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// How to run an ensemble: the number of threads and the progress bar.
///
/// ```
/// use dae::ensemble::Ensemble;
///
/// let squares = Ensemble::new().threads(2).run(&[1, 2, 3], |&k| Ok::<_, String>(k * k))?;
/// let squares: Vec<i32> = squares.into_iter().map(Result::unwrap).collect();
/// assert_eq!(squares, [1, 4, 9]);
/// # Ok::<(), dae::ensemble::EnsembleError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct Ensemble {
    threads: Option<usize>,
    progress: Option<String>,
}

/// Why one member of an ensemble has no result (its slot in
/// [`Ensemble::run`]'s output).
///
/// ```
/// use dae::ensemble::MemberError;
///
/// let e: MemberError<String> = MemberError::Failed { index: 3, error: "diverged".into() };
/// assert_eq!(e.to_string(), "ensemble member 3: diverged");
/// assert_eq!(e.index(), 3);
/// ```
#[derive(Debug, thiserror::Error)]
pub enum MemberError<E> {
    /// The member's function returned an error.
    #[error("ensemble member {index}: {error}")]
    Failed {
        /// The member's position in the input.
        index: usize,
        /// The function's error.
        error: E,
    },
    /// The member's function panicked; the panic was caught in the member
    /// (the default panic hook has printed its message on stderr).
    #[error("ensemble member {index} panicked: {message}")]
    Panicked {
        /// The member's position in the input.
        index: usize,
        /// The panic's message (`<no message>` when it was not a string).
        message: String,
    },
}

impl<E> MemberError<E> {
    /// The member's position in the input.
    ///
    /// ```
    /// use dae::ensemble::MemberError;
    ///
    /// let e = MemberError::<()>::Panicked { index: 7, message: "boom".into() };
    /// assert_eq!(e.index(), 7);
    /// ```
    pub fn index(&self) -> usize {
        match self {
            MemberError::Failed { index, .. } | MemberError::Panicked { index, .. } => *index,
        }
    }
}

/// An ensemble that could not run at all (no member was computed).
///
/// ```
/// use dae::ensemble::{Ensemble, EnsembleError};
///
/// let refused = Ensemble::new().threads(0).run(&[1.0], |&x: &f64| Ok::<_, String>(x));
/// assert!(matches!(refused, Err(EnsembleError::NoThreads)));
/// ```
#[derive(Debug, thiserror::Error)]
pub enum EnsembleError {
    /// [`Ensemble::threads`] was given 0.
    #[error("an ensemble needs at least one thread (threads = 0 given)")]
    NoThreads,
    /// The pool of worker threads could not be started.
    #[error("cannot start {threads} ensemble worker thread(s): {source}")]
    ThreadPool {
        /// Threads asked for (0: rayon's default, one per core).
        threads: usize,
        /// Rayon's error.
        source: rayon::ThreadPoolBuildError,
    },
}

impl Ensemble {
    /// One thread per core (rayon's default), no progress bar.
    ///
    /// ```
    /// let results = dae::ensemble::Ensemble::new().run(&[0.5], |&x: &f64| Ok::<_, String>(2.0 * x))?;
    /// assert_eq!(results[0].as_ref().ok(), Some(&1.0));
    /// # Ok::<(), dae::ensemble::EnsembleError>(())
    /// ```
    pub fn new() -> Self {
        Self::default()
    }

    /// Run on `threads` worker threads (0 is refused by [`Ensemble::run`]:
    /// [`EnsembleError::NoThreads`]).
    ///
    /// ```
    /// let one = dae::ensemble::Ensemble::new().threads(1);
    /// assert_eq!(one.run(&[3], |&k| Ok::<_, ()>(k + 1)).unwrap()[0].as_ref().ok(), Some(&4));
    /// ```
    pub fn threads(self, threads: usize) -> Self {
        Ensemble {
            threads: Some(threads),
            ..self
        }
    }

    /// Show the progress on stderr, labelled `label`: a bar when stderr is
    /// a terminal, a line every 5 % or 10 s otherwise
    /// ([`crate::sweep::progress`]).
    ///
    /// ```
    /// let e = dae::ensemble::Ensemble::new().progress("periods");
    /// assert!(e.run(&[1, 2], |&k| Ok::<_, ()>(k)).unwrap().iter().all(Result::is_ok));
    /// ```
    pub fn progress(self, label: impl Into<String>) -> Self {
        Ensemble {
            progress: Some(label.into()),
            ..self
        }
    }

    /// `f` of every member, in parallel: one slot per member in the
    /// members' order, `Ok` with `f`'s value or the member's
    /// [`MemberError`]. The results do not depend on the number of
    /// threads (each member is computed by one thread from its input
    /// alone; `f` must not depend on shared mutable state for that to
    /// hold).
    ///
    /// ```
    /// use dae::ensemble::{Ensemble, MemberError};
    ///
    /// let members: Vec<u32> = (0..10).collect();
    /// let out = Ensemble::new().threads(2).run(&members, |&k| {
    ///     if k == 4 { panic!("member four") }
    ///     Ok::<_, String>(k * 10)
    /// })?;
    /// assert_eq!(out[9].as_ref().ok(), Some(&90));
    /// assert!(matches!(&out[4], Err(MemberError::Panicked { index: 4, message }) if message == "member four"));
    /// # Ok::<(), dae::ensemble::EnsembleError>(())
    /// ```
    pub fn run<I, T, E, F>(
        &self,
        members: &[I],
        f: F,
    ) -> Result<Vec<Result<T, MemberError<E>>>, EnsembleError>
    where
        I: Sync,
        T: Send,
        E: Send,
        F: Fn(&I) -> Result<T, E> + Sync,
    {
        if self.threads == Some(0) {
            return Err(EnsembleError::NoThreads);
        }
        let mut builder =
            rayon::ThreadPoolBuilder::new().thread_name(|i| format!("dae-ensemble-{i}"));
        if let Some(threads) = self.threads {
            builder = builder.num_threads(threads);
        }
        let pool = builder
            .build()
            .map_err(|source| EnsembleError::ThreadPool {
                threads: self.threads.unwrap_or(0),
                source,
            })?;
        let label = self.progress.as_deref().unwrap_or("ensemble");
        let bar = Progress::new(label, members.len(), self.progress.is_some());
        let results = pool.install(|| {
            members
                .par_iter()
                .enumerate()
                .map(|(index, member)| {
                    let outcome = catch_unwind(AssertUnwindSafe(|| f(member)));
                    bar.inc();
                    match outcome {
                        Ok(Ok(value)) => Ok(value),
                        Ok(Err(error)) => Err(MemberError::Failed { index, error }),
                        Err(payload) => Err(MemberError::Panicked {
                            index,
                            message: panic_message(payload.as_ref()),
                        }),
                    }
                })
                .collect()
        });
        bar.finish();
        Ok(results)
    }
}

/// The text of a panic's payload (`panic!("…")` gives a `&str` or a
/// `String`).
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "<no message>".to_string()
    }
}

//! The integrator core: what every method family shares, each piece with one
//! reason to change.
//!
//! - `weights`: error weights from the tolerances, the index scaling of
//!   Radau-type methods, the mask of components in the error test — and the
//!   one weighted RMS norm every test and every Newton iteration uses.
//! - `newton`: the contraction monitor of a simplified Newton iteration.
//! - `matrix`: the linear systems of the Newton iterations — square LU for
//!   square formulations, constrained least squares for overdetermined ones —
//!   behind one interface, so that a method is written once for both.
//! - `eval`: counted evaluations of `F` and `f`, a non-finite value the
//!   attempt's typed failure.
//! - `shifted`: the iteration matrix `a E − b J` of a method on a constant
//!   leading matrix (MEBDF's stages, IDeC's Euler steps), factored when it
//!   changed.
//! - `control`: the smallest step and the failure budgets, the same for
//!   every method, and the typed errors they end in.
//! - `attempt`: the step-attempt loop — a family implements one attempt
//!   (`attempt::Attempts`) and says how it ended; the retries, the shrink
//!   factors of its policy, the budgets, the smallest step and the one
//!   end-of-horizon rule are there.
//! - `onestep`: the state a one-step method carries between its attempts
//!   (step point, steps, first/last/rejected, the loop's state), shared by
//!   the collocation engine and idec.
//! - `lagrange`: the Lagrange polynomial on equally spaced nodes of a
//!   step (its derivative at the nodes, its value anywhere).
//! - `hermite`: dense output of the step points' order, the Hermite
//!   polynomial through the last four step points' values and slopes
//!   (the collocation engine's, for a method not stiffly accurate).
//! - `output`: the output grid (one rule for `t0`, `t_end` and the times
//!   between) and dense output.
//! - `startup`: the constant-step start-up of a multistep method (its
//!   starting values from an adaptive run of the same method).
//! - `driver`: the step loop — a method implements `driver::Method`
//!   (start, one accepted step, dense output), the driver steps to the end,
//!   fills the output grid, records steps and assembles the solution — also
//!   for a start-up run feeding a second run (BDF with a constant step), so
//!   that no method assembles a solution itself.
//! - [`events`]: the zero crossings of the model's event functions,
//!   located on the dense output after every accepted step, for every
//!   method; stops and resets (a reset restarts with a fresh method).
//! - [`policy`]: the defaults a formulation implies (which unknowns enter the
//!   error test, square or least-squares linear algebra), decided in one
//!   place for the library and the command line alike.
//!
//! A method family (`radau5`, `bdf`, `odradau`, `odbdf`) keeps in its own
//! module only its coefficients, predictor, corrector sweep, error estimate,
//! step/order proposal and dense output; `radau5` and `bdf` are directory
//! modules, one file to each of these parts.

pub(crate) mod attempt;
pub(crate) mod block;
pub(crate) mod control;
pub(crate) mod driver;
pub(crate) mod eliminate;
pub(crate) mod eval;
pub mod events;
pub(crate) mod hermite;
pub(crate) mod lagrange;
pub(crate) mod matrix;
pub(crate) mod newton;
pub(crate) mod onestep;
pub(crate) mod output;
pub mod policy;
pub(crate) mod shifted;
pub(crate) mod startup;
pub(crate) mod weights;

//! Structural analysis of a DAE by Pryce's Σ-method: which equations are
//! differentiated how often, and to what order each unknown then appears.
//!
//! The method reads only the *signature matrix* Σ of a system
//! `F_i(t, y, y', …) = 0` of `n` equations in `n` unknowns: `σ_ij` is the
//! highest order of derivative of `y_j` in `F_i`, or −∞ when `y_j` does not
//! occur (Pryce, "A simple structural analysis method for DAEs", BIT 41
//! (2001); Nedialkov & Pryce, "Solving DAEs by Taylor series (I)", BIT 45
//! (2005)). Then:
//!
//! 1. A **highest-value transversal** `T`: one unknown `T(i)` per equation,
//!    all different, with `Val(Σ) = Σ_i σ_{i,T(i)}` as large as possible and
//!    finite. Without any finite transversal the system is structurally
//!    singular ([`Singular::NoTransversal`], with the Dulmage–Mendelsohn
//!    parts that say why).
//! 2. The **smallest offsets** `c_i, d_j ≥ 0` with `d_j − c_i ≥ σ_ij`
//!    everywhere and equality on `T`. Equation `i` is differentiated `c_i`
//!    times, and `d_j` is the highest derivative of `y_j` in the resulting
//!    system. The offsets do not depend on which highest-value transversal
//!    was found.
//! 3. The **system Jacobian** `J_ij = ∂F_i^{(c_i)} / ∂y_j^{(d_j)}` has its
//!    non-zeros where `σ_ij = d_j − c_i` ([`Structure::leading`]). If it is
//!    non-singular at a consistent point, the method succeeds there, the
//!    structural index `ν_S = max c_i + (1 if some d_j = 0)` bounds the
//!    differentiation index, and `Σ d_j − Σ c_i = Val(Σ)` is the number of
//!    degrees of freedom. Whether `J` is non-singular is a numerical
//!    question this module does not answer.
//!
//! # The pendulum
//!
//! With unknowns `x, y, u, v, λ`:
//!
//! ```text
//!                       x  y  u  v  λ     c_i
//!   0 = x' − u          1  ·  0  ·  ·      1
//!   0 = y' − v          ·  1  ·  0  ·      1
//!   0 = u' + λx         0  ·  1  ·  0      0
//!   0 = v' + λy + g     ·  0  ·  1  0      0
//!   0 = x² + y² − 1     0  0  ·  ·  ·      2
//!                 d_j   2  2  1  1  0
//! ```
//!
//! `Val(Σ) = 2` (the two degrees of freedom of a pendulum); the constraint is
//! differentiated twice, the position equations once, and
//! `ν_S = 2 + 1 = 3` because `λ` has `d = 0`.
//!
//! ```
//! use dae_core::structure::{analyse, SigmaMatrix};
//!
//! let (x, y, u, v, lambda) = (0, 1, 2, 3, 4);
//! let sigma = SigmaMatrix::from_rows(5, vec![
//!     vec![(x, 1), (u, 0)],
//!     vec![(y, 1), (v, 0)],
//!     vec![(x, 0), (u, 1), (lambda, 0)],
//!     vec![(y, 0), (v, 1), (lambda, 0)],
//!     vec![(x, 0), (y, 0)],
//! ])?;
//! let s = analyse(&sigma)?;
//! assert_eq!(s.c, [1, 1, 0, 0, 2]);
//! assert_eq!(s.d, [2, 2, 1, 1, 0]);
//! assert_eq!(s.value, 2);
//! assert_eq!(s.index(), 3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Cost
//!
//! Everything runs on the row patterns: a Hopcroft–Karp maximum matching
//! (O(√n · nnz)) to detect singularity, successive shortest augmenting paths
//! for the highest-value transversal (O(n · nnz · log n) at worst, local on
//! mechanical chains), the fixed-point iteration for the offsets on a
//! worklist (re-reading only rows whose offset rose), and
//! Tarjan's algorithm for the blocks (O(nnz)). No step recurses, so the
//! stack use does not grow with the model.

// `Singular::NoTransversal` carries the two Dulmage–Mendelsohn parts as
// six index lists (144 bytes), over clippy's 128-byte default for an error.
// It is returned at most once per analysis, on a cold path, and the lists are
// the point of the error, so the size is accepted rather than boxed away
// from the field names callers match on.
#![allow(clippy::result_large_err)]

mod assign;
mod blocks;
mod matching;
mod offsets;
mod pattern;

use std::fmt;

/// What the Σ-method reads of a system of equations `F_i(t, y, y', …) = 0`.
///
/// ```
/// use dae_core::structure::{analyse, Sigma};
///
/// /// The linear chain x1' = x2, x2' = x3, …, 0 = x1 − sin t.
/// struct Chain(usize);
///
/// impl Sigma for Chain {
///     fn size(&self) -> (usize, usize) {
///         (self.0, self.0)
///     }
///     fn sigma(&self, i: usize, j: usize) -> Option<u8> {
///         match (i + 1 == self.0, j) {
///             (true, 0) => Some(0),
///             (false, j) if j == i => Some(1),
///             (false, j) if j == i + 1 => Some(0),
///             _ => None,
///         }
///     }
///     fn row(&self, i: usize) -> Vec<usize> {
///         if i + 1 == self.0 { vec![0] } else { vec![i, i + 1] }
///     }
/// }
///
/// assert_eq!(analyse(&Chain(3))?.index(), 3);
/// assert_eq!(analyse(&Chain(40))?.index(), 40);
/// # Ok::<(), dae_core::structure::Singular>(())
/// ```
pub trait Sigma {
    /// (number of equations, number of unknowns)
    fn size(&self) -> (usize, usize);
    /// σ_ij: highest derivative order of unknown j in equation i (0 = the unknown
    /// itself), None when j does not occur (−∞). Called for the entries `row(i)` lists.
    fn sigma(&self, i: usize, j: usize) -> Option<u8>;
    /// The unknowns occurring in equation i, ascending (the sparse pattern): so the
    /// analysis is O(nonzeros), not O(n²).
    fn row(&self, i: usize) -> Vec<usize>;
}

/// A signature matrix held row by row: the simple owned [`Sigma`].
///
/// ```
/// use dae_core::structure::{Sigma, SigmaMatrix};
///
/// let mut s = SigmaMatrix::new(2, 2);
/// s.set(0, 1, 2)?;
/// s.set(0, 0, 0)?;
/// s.set(1, 0, 1)?;
/// assert_eq!(s.row(0), [0, 1]);
/// assert_eq!(s.sigma(0, 1), Some(2));
/// assert_eq!(s.sigma(1, 1), None);
/// assert!(s.set(2, 0, 0).is_err());
/// # Ok::<(), dae_core::structure::OutOfRange>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SigmaMatrix {
    unknowns: usize,
    /// Per equation: (unknown, σ), ascending in the unknown.
    rows: Vec<Vec<(usize, u8)>>,
}

/// An entry outside a [`SigmaMatrix`]'s size.
///
/// ```
/// use dae_core::structure::SigmaMatrix;
///
/// let e = SigmaMatrix::new(1, 1).set(0, 3, 1).unwrap_err();
/// assert_eq!(e.unknown, 3);
/// assert_eq!(e.to_string(), "entry (0, 3) outside the 1 × 1 signature matrix");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("entry ({equation}, {unknown}) outside the {equations} × {unknowns} signature matrix")]
pub struct OutOfRange {
    /// The entry's equation.
    pub equation: usize,
    /// The entry's unknown.
    pub unknown: usize,
    /// Number of equations of the matrix.
    pub equations: usize,
    /// Number of unknowns of the matrix.
    pub unknowns: usize,
}

impl SigmaMatrix {
    /// An `equations × unknowns` matrix with every entry −∞.
    ///
    /// ```
    /// use dae_core::structure::{Sigma, SigmaMatrix};
    ///
    /// let s = SigmaMatrix::new(3, 4);
    /// assert_eq!(s.size(), (3, 4));
    /// assert!(s.row(2).is_empty());
    /// ```
    pub fn new(equations: usize, unknowns: usize) -> SigmaMatrix {
        SigmaMatrix {
            unknowns,
            rows: vec![Vec::new(); equations],
        }
    }

    /// Sets `σ_ij = sigma`, replacing an earlier value.
    ///
    /// ```
    /// use dae_core::structure::{Sigma, SigmaMatrix};
    ///
    /// let mut s = SigmaMatrix::new(1, 1);
    /// s.set(0, 0, 1)?;
    /// s.set(0, 0, 2)?;
    /// assert_eq!(s.sigma(0, 0), Some(2));
    /// # Ok::<(), dae_core::structure::OutOfRange>(())
    /// ```
    pub fn set(&mut self, i: usize, j: usize, sigma: u8) -> Result<(), OutOfRange> {
        let equations = self.rows.len();
        let unknowns = self.unknowns;
        let error = OutOfRange {
            equation: i,
            unknown: j,
            equations,
            unknowns,
        };
        if j >= unknowns {
            return Err(error);
        }
        let row = self.rows.get_mut(i).ok_or(error)?;
        match row.binary_search_by_key(&j, |&(k, _)| k) {
            Ok(k) => row[k].1 = sigma,
            Err(k) => row.insert(k, (j, sigma)),
        }
        Ok(())
    }

    /// A matrix of `unknowns` columns from its rows, each a list of
    /// `(unknown, σ)` in any order; a repeated unknown keeps its last σ.
    ///
    /// ```
    /// use dae_core::structure::{Sigma, SigmaMatrix};
    ///
    /// let s = SigmaMatrix::from_rows(2, vec![vec![(1, 0), (0, 1)], vec![(0, 0)]])?;
    /// assert_eq!(s.size(), (2, 2));
    /// assert_eq!(s.row(0), [0, 1]);
    /// assert!(SigmaMatrix::from_rows(2, vec![vec![(2, 0)]]).is_err());
    /// # Ok::<(), dae_core::structure::OutOfRange>(())
    /// ```
    pub fn from_rows<R>(unknowns: usize, rows: R) -> Result<SigmaMatrix, OutOfRange>
    where
        R: IntoIterator,
        R::Item: IntoIterator<Item = (usize, u8)>,
    {
        let rows: Vec<Vec<(usize, u8)>> =
            rows.into_iter().map(|r| r.into_iter().collect()).collect();
        let mut s = SigmaMatrix::new(rows.len(), unknowns);
        for (i, row) in rows.into_iter().enumerate() {
            for (j, sigma) in row {
                s.set(i, j, sigma)?;
            }
        }
        Ok(s)
    }
}

impl Sigma for SigmaMatrix {
    fn size(&self) -> (usize, usize) {
        (self.rows.len(), self.unknowns)
    }

    fn sigma(&self, i: usize, j: usize) -> Option<u8> {
        let row = self.rows.get(i)?;
        row.binary_search_by_key(&j, |&(k, _)| k)
            .ok()
            .map(|k| row[k].1)
    }

    fn row(&self, i: usize) -> Vec<usize> {
        self.rows
            .get(i)
            .map_or_else(Vec::new, |r| r.iter().map(|&(j, _)| j).collect())
    }
}

/// The result of the Σ-method (see the [module documentation](self)).
///
/// ```
/// use dae_core::structure::{analyse, SigmaMatrix};
///
/// // x' = −x + z, 0 = z − x² : index 1, one degree of freedom.
/// let sigma = SigmaMatrix::from_rows(2, vec![vec![(0, 1), (1, 0)], vec![(0, 0), (1, 0)]])?;
/// let s = analyse(&sigma)?;
/// assert_eq!(s.transversal, [0, 1]);
/// assert_eq!((s.c.clone(), s.d.clone()), (vec![0, 0], vec![1, 0]));
/// assert_eq!(s.value, 1);
/// assert_eq!(s.index(), 1);
/// assert_eq!(s.blocks, [vec![0, 1]]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Structure {
    /// A highest-value transversal: equation `i` → unknown `transversal[i]`.
    pub transversal: Vec<usize>,
    /// Equation offsets: how often equation `i` is differentiated.
    pub c: Vec<u32>,
    /// Unknown offsets: highest derivative of `y_j` in the reduced system.
    pub d: Vec<u32>,
    /// `Val(Σ) = Σ σ_{i,T(i)}`, which equals `Σ d_j − Σ c_i`.
    pub value: i64,
    /// Block-triangular form: the strongly connected blocks of equations
    /// (equation `i` depends on the equation the transversal assigns to each
    /// unknown of `i`), each ascending, in an order where each block needs
    /// only earlier ones.
    pub blocks: Vec<Vec<usize>>,
}

impl Structure {
    /// The structural index `ν_S = max c_i + (1 if some d_j = 0 else 0)`.
    ///
    /// ```
    /// use dae_core::structure::{analyse, SigmaMatrix};
    ///
    /// // An ODE x' = f(x): index 0.
    /// let ode = SigmaMatrix::from_rows(1, vec![vec![(0, 1)]])?;
    /// assert_eq!(analyse(&ode)?.index(), 0);
    /// // An algebraic equation 0 = g(z): index 1.
    /// let algebraic = SigmaMatrix::from_rows(1, vec![vec![(0, 0)]])?;
    /// assert_eq!(analyse(&algebraic)?.index(), 1);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn index(&self) -> u32 {
        let top = self.c.iter().copied().max().unwrap_or(0);
        top + u32::from(self.d.contains(&0))
    }

    /// Whether `(i, j)` is an entry of the system Jacobian: `σ_ij = d_j − c_i`.
    /// False for indices out of range.
    ///
    /// ```
    /// use dae_core::structure::{analyse, SigmaMatrix};
    ///
    /// // x' = u, u' = −λx, 0 = x² − 1 (unknowns x, u, λ)
    /// let sigma = SigmaMatrix::from_rows(3, vec![
    ///     vec![(0, 1), (1, 0)],
    ///     vec![(0, 0), (1, 1), (2, 0)],
    ///     vec![(0, 0)],
    /// ])?;
    /// let s = analyse(&sigma)?;
    /// assert!(s.leading(2, 0, &sigma)); // x'' in the twice differentiated constraint
    /// assert!(!s.leading(1, 0, &sigma)); // x in u' = −λx is below x's top order
    /// assert!(!s.leading(7, 0, &sigma));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn leading(&self, i: usize, j: usize, s: &dyn Sigma) -> bool {
        let (Some(&c), Some(&d)) = (self.c.get(i), self.d.get(j)) else {
            return false;
        };
        let Some(order) = d.checked_sub(c).and_then(|k| u8::try_from(k).ok()) else {
            return false;
        };
        s.sigma(i, j) == Some(order)
    }

    /// Degrees of freedom `Σ d_j − Σ c_i` (equal to [`value`](Self::value)):
    /// how many initial values can be chosen freely.
    ///
    /// ```
    /// use dae_core::structure::{analyse, SigmaMatrix};
    ///
    /// // x'' = −λx, y'' = −λy − g, 0 = x² + y² − 1
    /// let sigma = SigmaMatrix::from_rows(3, vec![
    ///     vec![(0, 2), (2, 0)],
    ///     vec![(1, 2), (2, 0)],
    ///     vec![(0, 0), (1, 0)],
    /// ])?;
    /// assert_eq!(analyse(&sigma)?.degrees_of_freedom(), 2);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn degrees_of_freedom(&self) -> i64 {
        let d: i64 = self.d.iter().map(|&x| i64::from(x)).sum();
        let c: i64 = self.c.iter().map(|&x| i64::from(x)).sum();
        d - c
    }
}

/// Most equations [`analyse`] accepts: offsets are `u32` and can reach
/// `255 · n`.
pub const MAX_EQUATIONS: usize = (u32::MAX / 256) as usize;
pub(crate) const MAX_SIZE: usize = MAX_EQUATIONS;

/// Why [`analyse`] gives no [`Structure`]: the system is not square, is
/// structurally singular, or the [`Sigma`] given is inconsistent.
/// Equations and unknowns are 0-based indices.
///
/// ```
/// use dae_core::structure::{analyse, Singular, SigmaMatrix};
///
/// // Two equations in x only; y occurs nowhere.
/// let sigma = SigmaMatrix::from_rows(2, vec![vec![(0, 1)], vec![(0, 0)]])?;
/// match analyse(&sigma) {
///     Err(Singular::NoTransversal { equations, unknowns, underdetermined_unknowns, .. }) => {
///         assert_eq!((equations, unknowns), (vec![0, 1], vec![0]));
///         assert_eq!(underdetermined_unknowns, [1]);
///     }
///     other => panic!("{other:?}"),
/// }
/// # Ok::<(), dae_core::structure::OutOfRange>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Singular {
    /// Not as many equations as unknowns.
    #[error("{equations} equations for {unknowns} unknowns")]
    NotSquare {
        /// Number of equations.
        equations: usize,
        /// Number of unknowns.
        unknowns: usize,
    },
    /// No transversal: no assignment of a different unknown to each
    /// equation exists. The Dulmage–Mendelsohn coarse decomposition says
    /// why; its parts are the same for every maximum matching.
    #[error(
        "structurally singular: {}",
        parts(.equations, .unknowns, .underdetermined_unknowns, .underdetermined_equations)
    )]
    NoTransversal {
        /// The over-determined part: equations that compete for too few
        /// unknowns (all those reachable from an equation left without an
        /// unknown along alternating paths); empty if none.
        equations: Vec<usize>,
        /// The unknowns the over-determined `equations` compete for (fewer
        /// than them).
        unknowns: Vec<usize>,
        /// Equations left without an unknown by the maximum matching found
        /// (a subset of `equations`; which ones depends on the matching,
        /// how many does not).
        unmatched_equations: Vec<usize>,
        /// Unknowns left without an equation by the maximum matching found
        /// (a subset of `underdetermined_unknowns`; which ones depends on
        /// the matching, how many does not).
        unmatched_unknowns: Vec<usize>,
        /// The equations of the under-determined part: those involving its
        /// unknowns (fewer than them).
        underdetermined_equations: Vec<usize>,
        /// The under-determined part: unknowns that no equation can take
        /// without leaving another unknown undetermined; empty if none.
        underdetermined_unknowns: Vec<usize>,
    },
    /// A row lists an unknown beyond the number of unknowns.
    #[error("equation {equation} lists unknown {unknown}, but there are {unknowns} unknowns")]
    UnknownOutOfRange {
        /// The equation.
        equation: usize,
        /// The unknown listed.
        unknown: usize,
        /// Number of unknowns.
        unknowns: usize,
    },
    /// A row does not list its unknowns strictly ascending.
    #[error("equation {equation} lists unknown {unknown} after unknown {previous}: rows must be strictly ascending")]
    RowNotAscending {
        /// The equation.
        equation: usize,
        /// The unknown out of order.
        unknown: usize,
        /// The unknown listed before it.
        previous: usize,
    },
    /// A row lists an unknown whose σ is −∞.
    #[error("equation {equation} lists unknown {unknown}, but its σ is −∞ (None)")]
    MissingSigma {
        /// The equation.
        equation: usize,
        /// The unknown.
        unknown: usize,
    },
    /// More equations than [`MAX_EQUATIONS`].
    #[error("{equations} equations: the structural analysis takes at most {limit}")]
    TooLarge {
        /// Number of equations.
        equations: usize,
        /// [`MAX_EQUATIONS`].
        limit: usize,
    },
    /// Internal: the highest-value transversal found no augmenting path
    /// from this equation although a perfect matching exists. A bug in
    /// `dae-core`.
    #[error("internal error: no augmenting path from equation {equation} in the highest-value transversal (a bug in dae-core)")]
    AssignmentFailed {
        /// The equation.
        equation: usize,
    },
    /// Internal: the offset iteration still changed after this many
    /// updates (`n² + n`), which cannot happen for a highest-value
    /// transversal. A bug in `dae-core`.
    #[error("internal error: the offsets still changed after {steps} updates (a bug in dae-core)")]
    OffsetsDidNotConverge {
        /// Updates done.
        steps: usize,
    },
}

/// The two Dulmage–Mendelsohn parts in words: "equations 3, 4 compete for
/// unknown 2 (1 too many equations); nothing determines unknowns 5, 6
/// (only equation 1 for 2 unknowns)", each part only when not empty.
fn parts<'a>(
    equations: &'a [usize],
    unknowns: &'a [usize],
    under_unknowns: &'a [usize],
    under_equations: &'a [usize],
) -> impl fmt::Display + 'a {
    Phrase(move |f: &mut fmt::Formatter<'_>| {
        if !equations.is_empty() {
            write!(f, "{} compete for ", List("equation", equations))?;
            if unknowns.is_empty() {
                write!(f, "no unknown")?;
            } else {
                write!(f, "{}", List("unknown", unknowns))?;
            }
            let surplus = equations.len().saturating_sub(unknowns.len());
            write!(f, " ({surplus} too many equations)")?;
        }
        if !under_unknowns.is_empty() {
            if !equations.is_empty() {
                write!(f, "; ")?;
            }
            write!(f, "nothing determines {}", List("unknown", under_unknowns))?;
            if under_equations.is_empty() {
                let them = if under_unknowns.len() == 1 {
                    "it"
                } else {
                    "them"
                };
                write!(f, " (no equation involves {them})")?;
            } else {
                write!(
                    f,
                    " (only {} for {} {})",
                    List("equation", under_equations),
                    under_unknowns.len(),
                    if under_unknowns.len() == 1 {
                        "unknown"
                    } else {
                        "unknowns"
                    }
                )?;
            }
        }
        Ok(())
    })
}

struct Phrase<F>(F);

impl<F: Fn(&mut fmt::Formatter<'_>) -> fmt::Result> fmt::Display for Phrase<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        (self.0)(f)
    }
}

/// "equation 3" or "equations 3, 4".
struct List<'a>(&'a str, &'a [usize]);

impl fmt::Display for List<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let plural = if self.1.len() == 1 { "" } else { "s" };
        write!(f, "{}{plural} ", self.0)?;
        for (k, x) in self.1.iter().enumerate() {
            if k > 0 {
                write!(f, ", ")?;
            }
            write!(f, "{x}")?;
        }
        Ok(())
    }
}

/// Runs the Σ-method on a square signature matrix.
///
/// Rows must list unknowns in range, strictly ascending, each with a finite
/// σ; anything else is a typed error, never a panic. An empty system gives
/// an empty structure of index 0.
///
/// ```
/// use dae_core::structure::{analyse, SigmaMatrix};
///
/// // CSTR with prescribed output, unknowns C, T, R, TC:
/// // C' = k1(C0 − C) − R; T' = k1(T0 − T) + k2 R − k3(T − TC);
/// // 0 = R − k exp(−k4/T) C; 0 = C − u(t)
/// let sigma = SigmaMatrix::from_rows(4, vec![
///     vec![(0, 1), (2, 0)],
///     vec![(1, 1), (2, 0), (3, 0)],
///     vec![(0, 0), (1, 0), (2, 0)],
///     vec![(0, 0)],
/// ])?;
/// let s = analyse(&sigma)?;
/// assert_eq!(s.c, [1, 0, 1, 2]);
/// assert_eq!(s.d, [2, 1, 1, 0]);
/// assert_eq!(s.index(), 3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn analyse(s: &dyn Sigma) -> Result<Structure, Singular> {
    let p = pattern::Pattern::read(s)?;
    let n = p.n;
    let maximum = matching::maximum(&p);
    if maximum.size() < n {
        return Err(matching::no_transversal(&p, &maximum));
    }
    let t = assign::highest_value(&p)?.of_equation;
    let (c, d) = offsets::smallest(&p, &t)?;
    let value = (0..n).map(|i| p.sigma(i, t[i]).map_or(0, i64::from)).sum();
    let mut owner = vec![0usize; n];
    for (i, &j) in t.iter().enumerate() {
        owner[j] = i;
    }
    let blocks = blocks::blocks(&p, &owner);
    let narrow = |x: Vec<i64>| -> Result<Vec<u32>, Singular> {
        x.into_iter()
            .map(|v| {
                u32::try_from(v).map_err(|_| Singular::TooLarge {
                    equations: n,
                    limit: MAX_EQUATIONS,
                })
            })
            .collect()
    };
    Ok(Structure {
        transversal: t,
        c: narrow(c)?,
        d: narrow(d)?,
        value,
        blocks,
    })
}

//! The signature matrix read once from a [`Sigma`] into compressed rows,
//! checked on the way in.

use super::{Sigma, Singular};

/// Σ in compressed sparse rows: the entries of equation `i` are
/// `start[i]..start[i + 1]` of `unknown` and `order`.
#[derive(Clone, Debug)]
pub(crate) struct Pattern {
    pub(crate) n: usize,
    pub(crate) start: Vec<usize>,
    pub(crate) unknown: Vec<usize>,
    pub(crate) order: Vec<u8>,
}

impl Pattern {
    /// Reads a square Σ, checking that every row lists unknowns in range,
    /// strictly ascending, each with a finite σ.
    pub(crate) fn read(s: &dyn Sigma) -> Result<Pattern, Singular> {
        let (equations, unknowns) = s.size();
        if equations != unknowns {
            return Err(Singular::NotSquare {
                equations,
                unknowns,
            });
        }
        let n = equations;
        if n > super::MAX_SIZE {
            return Err(Singular::TooLarge {
                equations: n,
                limit: super::MAX_SIZE,
            });
        }
        let mut start = Vec::with_capacity(n + 1);
        let mut unknown = Vec::new();
        let mut order = Vec::new();
        start.push(0);
        for i in 0..n {
            let mut previous: Option<usize> = None;
            for j in s.row(i) {
                if j >= n {
                    return Err(Singular::UnknownOutOfRange {
                        equation: i,
                        unknown: j,
                        unknowns: n,
                    });
                }
                if let Some(p) = previous {
                    if j <= p {
                        return Err(Singular::RowNotAscending {
                            equation: i,
                            unknown: j,
                            previous: p,
                        });
                    }
                }
                previous = Some(j);
                let Some(sigma) = s.sigma(i, j) else {
                    return Err(Singular::MissingSigma {
                        equation: i,
                        unknown: j,
                    });
                };
                unknown.push(j);
                order.push(sigma);
            }
            start.push(unknown.len());
        }
        Ok(Pattern {
            n,
            start,
            unknown,
            order,
        })
    }

    /// The entry positions of equation `i`.
    pub(crate) fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i]..self.start[i + 1]
    }

    /// The unknowns of equation `i`, ascending.
    pub(crate) fn row(&self, i: usize) -> &[usize] {
        &self.unknown[self.range(i)]
    }

    /// σ_ij, or `None` when `j` does not occur in equation `i`.
    pub(crate) fn sigma(&self, i: usize, j: usize) -> Option<u8> {
        let r = self.range(i);
        self.unknown[r.clone()]
            .binary_search(&j)
            .ok()
            .map(|k| self.order[r.start + k])
    }

    /// For each unknown, the equations it occurs in, ascending.
    pub(crate) fn columns(&self) -> (Vec<usize>, Vec<usize>) {
        let mut count = vec![0usize; self.n + 1];
        for &j in &self.unknown {
            count[j + 1] += 1;
        }
        for j in 0..self.n {
            count[j + 1] += count[j];
        }
        let col_start = count.clone();
        let mut fill = count;
        let mut equation = vec![0usize; self.unknown.len()];
        for i in 0..self.n {
            for &j in self.row(i) {
                equation[fill[j]] = i;
                fill[j] += 1;
            }
        }
        (col_start, equation)
    }
}

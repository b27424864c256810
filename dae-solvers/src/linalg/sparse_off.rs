//! Without the `sparse` feature: the names of the sparse path with no
//! factorisation behind them. [`crate::core::matrix`] never takes that path
//! then (`SPARSE_FROM` is `usize::MAX`), so every matrix is factorised
//! dense; these only let it compile.

use super::Singular;
use std::marker::PhantomData;

/// No pattern is ever built.
pub(crate) struct Pattern {
    /// How many analyses were made (none).
    pub(crate) analyses: usize,
}

impl Pattern {
    /// Refused: no sparse factorisation is built in.
    pub(crate) fn new(
        _n: usize,
        _nonzero: impl Fn(usize, usize) -> bool,
    ) -> Result<Self, Singular> {
        Err(Singular)
    }

    /// Refused: no sparse factorisation is built in.
    pub(crate) fn from_compressed(
        _n: usize,
        _col_ptr: Vec<usize>,
        _row_idx: Vec<usize>,
    ) -> Result<Self, Singular> {
        Err(Singular)
    }

    /// Number of stored entries (none).
    pub(crate) fn nnz(&self) -> usize {
        self.analyses
    }

    /// Refused: no sparse factorisation is built in.
    pub(crate) fn cover(
        &mut self,
        _nonzero: impl Fn(usize, usize) -> bool,
    ) -> Result<(), Singular> {
        Err(Singular)
    }
}

/// No factorisation is ever made.
pub(crate) struct SparseFactor<T>(PhantomData<T>);

impl<T> SparseFactor<T> {
    /// Empty.
    pub(crate) fn new() -> Self {
        SparseFactor(PhantomData)
    }

    /// Refused: no sparse factorisation is built in.
    pub(crate) fn factor(
        &mut self,
        _p: &Pattern,
        _value: impl Fn(usize, usize) -> T,
    ) -> Result<(), Singular> {
        Err(Singular)
    }

    /// Refused: no sparse factorisation is built in.
    pub(crate) fn factor_indexed(
        &mut self,
        _p: &Pattern,
        _value: impl Fn(usize, usize, usize) -> T,
    ) -> Result<(), Singular> {
        Err(Singular)
    }

    /// Never called: [`SparseFactor::factor`] never succeeds.
    pub(crate) fn solve(&mut self, _p: &Pattern, _x: &mut [T]) {
        unreachable!("the sparse path is not taken without the `sparse` feature")
    }
}

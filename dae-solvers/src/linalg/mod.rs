//! Dense linear algebra in storage allocated once: the square LU
//! factorisation of the iteration matrices ([`lu`]) and the constrained
//! least-squares solver of the overdetermined methods ([`lstsq`]).

pub(crate) mod lstsq;
pub(crate) mod lu;

pub(crate) use lstsq::ConstrainedLstsq;
pub(crate) use lu::{DenseLu, Pivoting, Singular};

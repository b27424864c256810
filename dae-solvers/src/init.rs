//! Consistent initial values (to be written).

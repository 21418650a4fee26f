//! test double

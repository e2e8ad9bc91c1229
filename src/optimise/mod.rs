//! Optimisation over control sequences: the lower bound on the time ([`bound`]).

pub mod bound;

pub use bound::{lower_bound, LowerBound};

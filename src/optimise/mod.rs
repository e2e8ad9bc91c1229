//! Optimisation over control sequences: the lower bound on the time ([`bound`]), the planning model of
//! the minimal-time search ([`model`]), and the planners of scenes beyond air strafing: the Source jump
//! boost ([`jumps`]) and ground frames, jumps and the bunnyhop cap ([`hops`]).

mod after_contact;
mod airborne;
mod anchored;
mod baseline;
pub mod bound;
pub mod hillclimb;
pub mod hops;
pub mod jumps;
pub mod lagrangian;
pub mod model;
mod planner;
mod policy_run;
mod polish;
pub mod qp;
mod relaxed;
mod rounding;
pub mod scp;
pub mod search;
mod stagewise;
pub mod substep;
mod verify;

pub use baseline::GreedyGuide;
pub use bound::{lower_bound, LowerBound};
pub use policy_run::PolicyRun;
pub use relaxed::{RelaxedCertificate, CERTIFIED_CLEARANCE_UNITS};
pub use search::{
    solve, solve_cancellable, solve_with_progress, FinePolish, Outcome, Progress, Quality,
    SearchSettings, SearchStatus, StageSeconds,
};

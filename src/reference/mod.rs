//! External reference solvers (feature `reference`, DESIGN §5).
//!
//! [`ida`] wraps SUNDIALS IDA (sundials-sys); [`run::solve`] solves the
//! paper's three friction DAEs (friction-1d, friction-plane, friction-roller),
//! written here independently of the ANM models, in plain f64 with analytic
//! Jacobians and in global Cartesian coordinates ([`friction_1d`],
//! [`friction_plane`], [`friction_roller`]); [`output`] writes what
//! `anm reference ida` produces.

pub mod dae;
pub mod error;
pub mod friction_1d;
pub mod friction_plane;
pub mod friction_roller;
pub mod ida;
pub mod laws;
pub mod output;
pub mod run;

pub use error::IdaError;
pub use run::{IdaRun, solve};

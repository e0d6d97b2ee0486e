//! External reference solvers (DESIGN §5) for the paper's three friction
//! DAEs (friction-1d, friction-plane, friction-roller), written here
//! independently of the ANM models, in plain f64 with analytic Jacobians and
//! in global Cartesian coordinates ([`friction_1d`], [`friction_plane`],
//! [`friction_roller`]).
//!
//! Two solvers written by others run them through one time loop
//! ([`run::drive`]): SUNDIALS IDA ([`ida`], [`ida_run`]; feature `reference`,
//! a C library) and diffsol ([`diffsol`]: BDF and ESDIRK34 in mass-matrix
//! form, pure Rust, always built so that the default tests compare against
//! it). [`settings`] holds their tolerances and options, [`counters`] the
//! cost counters every time run reports under the same names, [`output`]
//! what `anm reference ida|diffsol` writes.

pub mod counters;
pub mod dae;
pub mod diffsol;
pub mod error;
pub mod friction_1d;
pub mod friction_plane;
pub mod friction_roller;
#[cfg(feature = "reference")]
pub mod ida;
#[cfg(feature = "reference")]
pub mod ida_run;
pub mod laws;
pub mod output;
pub mod run;
pub mod settings;
#[cfg(feature = "reference")]
pub mod shell_ida;

pub use error::IdaError;
#[cfg(feature = "reference")]
pub use ida_run::{IdaSettings, solve};
pub use run::IdaRun;

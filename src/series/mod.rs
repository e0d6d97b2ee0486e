//! The ANM engine. It knows nothing about shells or friction: a problem
//! supplies its residual, tangent and order-p right-hand side; the engine
//! supplies the series, step length, Padé extension, correction, singularity
//! detection and statistics.

pub mod continuation;
pub mod dae;
pub mod geometric;
pub mod newton;
pub mod pade;
pub mod stats;
pub mod tape;
pub mod tape_problem;
pub mod taylor;

pub use continuation::{ContinuationConfig, ContinuationProblem, PathStep};
pub use dae::{DaeConfig, DaeProblem, TimeStep};
pub use stats::Stats;
pub use tape::{Tape, TapeBuilder, Var};
pub use tape_problem::TapeProblem;

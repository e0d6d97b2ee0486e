//! The ANM engine. It knows nothing about shells or friction: a problem
//! supplies its residual, tangent and order-p right-hand side; the engine
//! supplies the series, step length, Padé extension, correction, singularity
//! detection and statistics.

pub mod bifurcation;
pub mod continuation;
pub mod correct;
pub mod dae;
pub mod events;
pub mod geometric;
pub mod kinks;
pub mod newton;
pub mod pade;
pub mod path;
pub mod rodas;
pub mod stats;
pub mod stop;
pub mod tape;
pub mod tape_problem;
pub mod taylor;
pub mod time_pade;

pub use continuation::{ContinuationConfig, ContinuationProblem, PathResult, PathStep};
pub use correct::{Metric, correct_at_lambda};
pub use dae::{DaeConfig, DaeProblem, TimeStep};
pub use path::{Checkpoint, Path};
pub use stats::Stats;
pub use stop::Stop;
pub use tape::{Tape, TapeBuilder, Var};
pub use tape_problem::TapeProblem;

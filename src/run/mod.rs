//! Scene -> problem -> engine loop -> recorder (DESIGN §1).
//!
//! - [`build`]: a shell scene into the assembled [`crate::shell::ShellModel`];
//! - [`probe`]: the scene's named outputs evaluated at a state;
//! - [`recorder`]: the output grid, the streamed CSV files, VTK, the
//!   checkpoint that `anm run --resume` continues from;
//! - [`shell`]: the run loop (ANM stepper, Newton baseline, linear solve);
//! - [`shell_time`]: a shell scene with `[friction]`, integrated in time;
//! - [`memory`]: a mesh too large for the machine refused before the run;
//! - [`penetration`]: nodes outside the contact group that end inside an
//!   obstacle, named in the run's notes.
//!
//! A run stops at the next step end after Ctrl-C or SIGTERM
//! ([`interrupt`]), with every file consistent with the last step.

pub mod along_strip;
pub mod build;
pub mod interrupt;
pub mod memory;
pub mod penetration;
pub mod probe;
pub mod recorder;
pub mod regularization;
pub mod section;
pub mod shell;
#[cfg(feature = "reference")]
pub mod shell_reference;
pub mod shell_time;
pub mod time_checkpoint;

pub use shell::{RunReport, Snapshot, run_loaded, run_scene};

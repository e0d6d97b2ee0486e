//! The run driver: units, interruption and resume, stability stress,
//! sweeps item by item.
//! One test binary per area (DESIGN §1): the files below are its modules.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/scratch.rs"]
#[allow(dead_code)]
mod scratch;

mod interrupt_resume;
mod node_tags;
mod numerical_stop;
mod reused_output;
mod stability;
mod summary_layout;
mod sweeps;
mod units;

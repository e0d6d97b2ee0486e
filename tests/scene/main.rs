//! Scene files: bad input, the key reference, mutated scenes.
//! One test binary per area (DESIGN §1): the files below are its modules.

mod bad_input;
mod built_in_mesh_input;
mod docs;
mod edited;
mod fuzz;
mod memory_gate;
#[path = "../common/scratch.rs"]
#[allow(dead_code)]
mod scratch;
mod shell_bad_input;
mod shell_friction_input;
mod strip_mesh_input;

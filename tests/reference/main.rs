//! Against external solvers: SUNDIALS IDA, dolfinx (feature `reference`).
//! One test binary per area (DESIGN §1): the files below are its modules.

#[path = "../common/mod.rs"]
mod common;
mod dolfinx_plate_cylinder;
mod ida;
#[path = "../common/scratch.rs"]
#[allow(dead_code)]
mod scratch;
mod shell_ida;

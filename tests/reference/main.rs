//! Against external solvers: SUNDIALS IDA, dolfinx (feature `reference`).
//! One test binary per area (DESIGN §1): the files below are its modules.

#[path = "../common/mod.rs"]
mod common;
mod dolfinx_plate_cylinder;
mod ida;
mod shell_ida;

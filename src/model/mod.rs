//! Assembly of a scene into the problems the series engine solves.

pub mod friction;
pub mod friction_run;

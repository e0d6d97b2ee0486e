//! The point-mass friction cases against closed forms (paper §3).
//! One test binary per area (DESIGN §1): the files below are its modules.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/scratch.rs"]
#[allow(dead_code)]
mod scratch;

mod diffsol_reference;
mod friction_1d_closed_form;
mod idler;
mod plane_closed_form;
mod reference_cli;
mod roller_breakdown;
mod shell_friction_law;
mod shell_in_time;
mod stiff_linear;
mod strip_conveying;

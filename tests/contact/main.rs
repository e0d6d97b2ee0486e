//! Shell contact with rigid obstacles (eq. 3).
//! One test binary per area (DESIGN §1): the files below are its modules.

#[path = "../common/scratch.rs"]
#[allow(dead_code)]
mod scratch;
#[path = "../common/shell.rs"]
mod shell_common;

mod event_spring;
mod obstacle_driven;
mod outside_the_group;
mod plate_cylinder;
mod propped_cantilever;
mod regularization_notes;
mod supported_strip;

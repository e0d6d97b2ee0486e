//! Shell element and verification cases (closed forms, published tables).
//! One test binary per area (DESIGN §1): the files below are its modules.

#[path = "../common/scratch.rs"]
#[allow(dead_code)]
mod scratch;
#[path = "../common/shell.rs"]
mod shell_common;

mod bifurcation;
mod closed_tube;
mod derivatives_fd;
mod linear_macneal_harder;
mod linear_reactions;
mod membrane_stress;
mod nonlinear_cantilevers;
mod patch_macneal_harder;
mod plate_buckling_dolfinx;
mod prepass;
mod sheet_wrinkling_dolfinx;
mod step_cost;
mod strip_wrinkling;
mod tiny_loads;
mod verification_scenes;

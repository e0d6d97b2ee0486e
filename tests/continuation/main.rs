//! The ANM path engine: closed forms, units, checkpoints.
//! One test binary per area (DESIGN §1): the files below are its modules.

mod arc_coordinates;
mod units;
mod von_mises_truss;

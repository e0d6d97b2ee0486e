//! TEMPORARY stub until the mesh branch merges.
#![allow(unused)]
use crate::mesh::Vec3;
pub fn line_load_forces(q: Vec3, a: Vec3, b: Vec3) -> [Vec3; 2] { unimplemented!() }

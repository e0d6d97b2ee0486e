//! TEMPORARY stub until the mesh branch merges.
#![allow(unused)]
use crate::mesh::Vec3;
pub fn follower_forces(p: f64, x: &[Vec3; 4]) -> [Vec3; 4] { unimplemented!() }
pub fn follower_bilinear(p: f64, x: &[Vec3; 4], y: &[Vec3; 4]) -> [Vec3; 4] { unimplemented!() }
pub fn follower_stiffness(p: f64, x: &[Vec3; 4]) -> [[f64; 12]; 12] { unimplemented!() }
pub fn dead_traction_forces(t: Vec3, x0: &[Vec3; 4]) -> [Vec3; 4] { unimplemented!() }
pub fn dead_pressure_forces(p: f64, x0: &[Vec3; 4]) -> [Vec3; 4] { unimplemented!() }

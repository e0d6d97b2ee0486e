//! TEMPORARY until the mesh branch merges.
#![allow(unused)]
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::path::Path;
impl Mesh {
    pub fn edges(&self, name: &str, scene: &Path, key: &str) -> Result<&[[usize; 2]]> {
        Err(Error::Invalid { file: scene.into(), key: key.into(), problem: format!("no edges {name}") })
    }
    pub fn surface(&self, name: &str, scene: &Path, key: &str) -> Result<&[usize]> {
        Err(Error::Invalid { file: scene.into(), key: key.into(), problem: format!("no surface {name}") })
    }
}
pub fn sphere_patch(r: f64, a: f64, b: f64, c: f64, d: f64, nx: usize, ny: usize) -> Mesh { unimplemented!() }
pub fn annulus(r: f64, a: f64, b: f64, c: f64, nx: usize, ny: usize) -> Mesh { unimplemented!() }

//! HDF5 field output (feature `hdf5`), readable by `h5dump`:
//!
//! ```text
//! /                       attrs: scene, kind, units
//! /step_0000/             attrs: lambda (or t), step
//!     coordinates  (n, 3) current mid-surface positions, m
//!     displacement (n, 3) m
//!     director     (n, 3) current director a3 (dimensionless)
//!     contact_force (n, 3) N
//!     contact_reaction (n, 1) normal reaction R of eq. (3), N
//! ```

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Writes one group per output step into a new HDF5 file.
pub struct FieldWriter {
    file: hdf5::File,
    path: PathBuf,
    next: usize,
}

fn err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::write(path, format!("HDF5: {e}"))
}

impl FieldWriter {
    /// Creates (truncates) the file and writes the root attributes.
    pub fn create(path: &Path, attributes: &[(&str, &str)]) -> Result<Self> {
        let file = hdf5::File::create(path).map_err(|e| err(path, e))?;
        for (name, value) in attributes {
            let v: hdf5::types::VarLenUnicode =
                value.parse().map_err(|e| err(path, format!("{e:?}")))?;
            file.new_attr::<hdf5::types::VarLenUnicode>()
                .create(*name)
                .and_then(|a| a.write_scalar(&v))
                .map_err(|e| err(path, e))?;
        }
        Ok(Self {
            file,
            path: path.to_path_buf(),
            next: 0,
        })
    }

    /// Writes identifiers (e.g. the mesh file's node tags, one per row of
    /// the fields) as a dataset of the root group.
    pub fn write_tags(&mut self, name: &str, tags: &[usize]) -> Result<()> {
        let v: Vec<u64> = tags.iter().map(|&t| t as u64).collect();
        self.file
            .new_dataset_builder()
            .with_data(&v)
            .create(name)
            .map(|_| ())
            .map_err(|e| err(&self.path, e))
    }

    /// Writes a step: scalar attributes and (name, columns, values) fields,
    /// row-major with `columns` values per node.
    pub fn write_step(
        &mut self,
        scalars: &[(&str, f64)],
        fields: &[(&str, usize, &[f64])],
    ) -> Result<()> {
        let p = self.path.clone();
        let g = self
            .file
            .create_group(&format!("step_{:04}", self.next))
            .map_err(|e| err(&p, e))?;
        for (name, value) in scalars {
            if !value.is_finite() {
                return Err(err(
                    &p,
                    format!("refusing to write non-finite `{name}` = {value}"),
                ));
            }
            g.new_attr::<f64>()
                .create(*name)
                .and_then(|a| a.write_scalar(value))
                .map_err(|e| err(&p, e))?;
        }
        for (name, columns, data) in fields {
            if *columns == 0 || data.len() % columns != 0 {
                return Err(err(
                    &p,
                    format!(
                        "field `{name}` has {} values, not rows of {columns}",
                        data.len()
                    ),
                ));
            }
            if let Some(bad) = data.iter().position(|x| !x.is_finite()) {
                return Err(err(
                    &p,
                    format!(
                        "refusing to write non-finite `{name}`[{bad}] = {}",
                        data[bad]
                    ),
                ));
            }
            let arr =
                ndarray::Array2::from_shape_vec((data.len() / columns, *columns), data.to_vec())
                    .map_err(|e| err(&p, e))?;
            g.new_dataset_builder()
                .with_data(&arr)
                .create(*name)
                .map_err(|e| err(&p, e))?;
        }
        self.next += 1;
        Ok(())
    }
}

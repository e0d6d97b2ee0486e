//! VTK output for ParaView: ASCII XML unstructured grids (.vtu) of
//! quadrilateral surfaces with point data, and a .pvd collection indexing
//! them by lambda (VTK file formats, Kitware, "VTK XML formats").

use crate::error::{Error, Result};
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::Path;

/// Point data of a .vtu file.
pub enum PointData<'a> {
    Scalar(&'a str, Vec<f64>),
    Vector(&'a str, Vec<Vector3<f64>>),
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::Io {
        file: path.to_path_buf(),
        source: e,
    }
}

/// Writes a quadrilateral surface (VTK_QUAD = 9) with point data.
pub fn write_vtu(
    path: &Path,
    points: &[Vector3<f64>],
    quads: &[[usize; 4]],
    data: &[PointData],
) -> Result<()> {
    write_vtu_cells(path, points, quads, data, &[])
}

/// The data arrays of one section (PointData or CellData).
fn data_arrays(s: &mut String, data: &[PointData]) {
    for d in data {
        match d {
            PointData::Scalar(name, v) => {
                let _ = writeln!(
                    s,
                    r#"<DataArray type="Float64" Name="{name}" format="ascii">"#
                );
                for x in v {
                    let _ = writeln!(s, "{:.10e}", finite(*x));
                }
            }
            PointData::Vector(name, v) => {
                let _ = writeln!(
                    s,
                    r#"<DataArray type="Float64" Name="{name}" NumberOfComponents="3" format="ascii">"#
                );
                for x in v {
                    let _ = writeln!(
                        s,
                        "{:.10e} {:.10e} {:.10e}",
                        finite(x[0]),
                        finite(x[1]),
                        finite(x[2])
                    );
                }
            }
        }
        let _ = writeln!(s, "</DataArray>");
    }
}

/// [`write_vtu`] with cell data too (one value per quadrilateral).
pub fn write_vtu_cells(
    path: &Path,
    points: &[Vector3<f64>],
    quads: &[[usize; 4]],
    data: &[PointData],
    cells: &[PointData],
) -> Result<()> {
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0"?>"#);
    let _ = writeln!(
        s,
        r#"<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">"#
    );
    let _ = writeln!(s, "<UnstructuredGrid>");
    let _ = writeln!(
        s,
        r#"<Piece NumberOfPoints="{}" NumberOfCells="{}">"#,
        points.len(),
        quads.len()
    );
    let _ = writeln!(s, "<PointData>");
    data_arrays(&mut s, data);
    let _ = writeln!(s, "</PointData>");
    if !cells.is_empty() {
        let _ = writeln!(s, "<CellData>");
        data_arrays(&mut s, cells);
        let _ = writeln!(s, "</CellData>");
    }
    let _ = writeln!(s, "<Points>");
    let _ = writeln!(
        s,
        r#"<DataArray type="Float64" NumberOfComponents="3" format="ascii">"#
    );
    for p in points {
        let _ = writeln!(
            s,
            "{:.12e} {:.12e} {:.12e}",
            finite(p[0]),
            finite(p[1]),
            finite(p[2])
        );
    }
    let _ = writeln!(s, "</DataArray>\n</Points>\n<Cells>");
    let _ = writeln!(
        s,
        r#"<DataArray type="Int64" Name="connectivity" format="ascii">"#
    );
    for q in quads {
        let _ = writeln!(s, "{} {} {} {}", q[0], q[1], q[2], q[3]);
    }
    let _ = writeln!(s, "</DataArray>");
    let _ = writeln!(
        s,
        r#"<DataArray type="Int64" Name="offsets" format="ascii">"#
    );
    for i in 0..quads.len() {
        let _ = writeln!(s, "{}", 4 * (i + 1));
    }
    let _ = writeln!(s, "</DataArray>");
    let _ = writeln!(s, r#"<DataArray type="UInt8" Name="types" format="ascii">"#);
    for _ in quads {
        let _ = writeln!(s, "9");
    }
    let _ = writeln!(
        s,
        "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>"
    );
    std::fs::write(path, s).map_err(io(path))
}

fn finite(x: f64) -> f64 {
    if x.is_finite() { x } else { 0.0 }
}

/// Writes a .pvd collection: (lambda, part, file name relative to the .pvd).
pub fn write_pvd(path: &Path, entries: &[(f64, usize, String)]) -> Result<()> {
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0"?>"#);
    let _ = writeln!(
        s,
        r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#
    );
    let _ = writeln!(s, "<Collection>");
    for (t, part, file) in entries {
        let _ = writeln!(
            s,
            r#"<DataSet timestep="{t:.10e}" group="" part="{part}" file="{file}"/>"#
        );
    }
    let _ = writeln!(s, "</Collection>\n</VTKFile>");
    std::fs::write(path, s).map_err(io(path))
}

/// A quadrilateral surface of a cylinder (for drawing obstacles): centre c,
/// unit axis a, radius r, length `len` centred on c, `n` facets around.
pub fn cylinder_surface(
    c: &Vector3<f64>,
    a: &Vector3<f64>,
    r: f64,
    len: f64,
    n: usize,
) -> (Vec<Vector3<f64>>, Vec<[usize; 4]>) {
    let helper = if a[0].abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = a.cross(&helper).normalize();
    let e2 = a.cross(&e1);
    let mut pts = Vec::with_capacity(2 * n);
    for k in 0..n {
        let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        let radial = (e1 * phi.cos() + e2 * phi.sin()) * r;
        pts.push(c + radial - a * (0.5 * len));
        pts.push(c + radial + a * (0.5 * len));
    }
    let quads = (0..n)
        .map(|k| {
            let j = (k + 1) % n;
            [2 * k, 2 * j, 2 * j + 1, 2 * k + 1]
        })
        .collect();
    (pts, quads)
}

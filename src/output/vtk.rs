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
    /// Identifiers (node or element tags of the mesh file), as integers.
    Tags(&'a str, &'a [usize]),
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
            PointData::Tags(name, v) => {
                let _ = writeln!(
                    s,
                    r#"<DataArray type="Int64" Name="{name}" format="ascii">"#
                );
                for x in *v {
                    let _ = writeln!(s, "{x}");
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
    if x.is_finite() { x + 0.0 } else { 0.0 }
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
    revolved_surface(c, a, &|_| r, len, n, 1)
}

/// A surface of revolution about the unit axis `a` through `c`: radius
/// r(s) at the axial coordinate s ∈ [−len/2, len/2], `n` facets around and
/// `rings` along (a crowned roll's profile needs more than one).
pub fn revolved_surface(
    c: &Vector3<f64>,
    a: &Vector3<f64>,
    r: &dyn Fn(f64) -> f64,
    len: f64,
    n: usize,
    rings: usize,
) -> (Vec<Vector3<f64>>, Vec<[usize; 4]>) {
    let helper = if a[0].abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = a.cross(&helper).normalize();
    let e2 = a.cross(&e1);
    let stations = rings + 1;
    let mut pts = Vec::with_capacity(stations * n);
    for k in 0..n {
        let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        let around = e1 * phi.cos() + e2 * phi.sin();
        for i in 0..stations {
            let s = len * (i as f64 / rings as f64 - 0.5);
            pts.push(c + around * r(s) + a * s);
        }
    }
    let mut quads = Vec::with_capacity(n * rings);
    for k in 0..n {
        let j = (k + 1) % n;
        for i in 0..rings {
            let (p, q) = (stations * k + i, stations * j + i);
            quads.push([p, q, q + 1, p + 1]);
        }
    }
    (pts, quads)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point of a crowned roll's drawing lies at r(s) from the axis,
    /// at its station s; one ring reproduces the straight cylinder.
    #[test]
    fn a_revolved_surface_follows_its_profile() {
        let c = Vector3::new(1.0, 2.0, 3.0);
        let a = Vector3::new(0.0, 1.0, 0.0);
        let r = |s: f64| 0.4 - 2e-3 * s * s;
        let (pts, quads) = revolved_surface(&c, &a, &r, 2.0, 12, 10);
        assert_eq!((pts.len(), quads.len()), (12 * 11, 12 * 10));
        for p in &pts {
            let s = (p - c).dot(&a);
            let radial = (p - c - a * s).norm();
            assert!(s.abs() <= 1.0 + 1e-15);
            assert!((radial - r(s)).abs() < 1e-15, "s = {s}: {radial}");
        }
        let (straight, q) = cylinder_surface(&c, &a, 0.4, 2.0, 12);
        assert_eq!((straight.len(), q.len()), (24, 12));
        assert!(q.iter().flatten().all(|&i| i < straight.len()));
    }
}

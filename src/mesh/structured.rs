//! Built-in structured meshers (tests and quick scenes): a map of the unit
//! square (s, t) ∈ [0, 1]² onto a surface with its exact unit normal.
//!
//! Node (i, j), i = 0..=nx along s, j = 0..=ny along t, has index
//! j (nx + 1) + i. Node sets: `s0`, `s1`, `t0`, `t1` (the four edges) and
//! `all`. Elements are ordered counterclockwise in (s, t), so the mapped
//! normal ∂x/∂s × ∂x/∂t must agree with the given one.

use super::{Mesh, Vec3};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Maps the unit square with `f(s, t) = (position, unit normal)`.
pub fn map(label: &str, nx: usize, ny: usize, f: impl Fn(f64, f64) -> (Vec3, Vec3)) -> Mesh {
    let mut nodes = Vec::new();
    let mut normals = Vec::new();
    let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, n) = f(i as f64 / nx as f64, j as f64 / ny as f64);
            let id = nodes.len();
            nodes.push(x);
            normals.push(n.normalize());
            for (name, on) in [
                ("s0", i == 0),
                ("s1", i == nx),
                ("t0", j == 0),
                ("t1", j == ny),
            ] {
                if on {
                    groups.entry(name.into()).or_default().push(id);
                }
            }
            groups.entry("all".into()).or_default().push(id);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut quads = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let ne = quads.len();
    Mesh {
        file: format!("<built-in {label} {nx}x{ny}>").into(),
        nodes,
        quads,
        quad_lines: vec![0; ne],
        quad_tags: (1..=ne).collect(),
        exact_normals: Some(normals),
        groups,
    }
}

/// Flat rectangle [x0, x1] × [y0, y1] in the plane z = 0, normal +z.
pub fn rectangle(x0: f64, x1: f64, y0: f64, y1: f64, nx: usize, ny: usize) -> Mesh {
    map("rectangle", nx, ny, |s, t| {
        (
            Vec3::new(x0 + s * (x1 - x0), y0 + t * (y1 - y0), 0.0),
            Vec3::z(),
        )
    })
}

/// Cylindrical panel of radius r about the x axis: x = x0 + s (x1 − x0),
/// angle φ = φ0 + t (φ1 − φ0) from +z toward +y, position
/// (x, r sin φ, r cos φ). The normal ∂x/∂s × ∂x/∂t is outward for φ1 > φ0.
pub fn cylinder_panel(
    r: f64,
    x0: f64,
    x1: f64,
    phi0: f64,
    phi1: f64,
    nx: usize,
    ny: usize,
) -> Mesh {
    map("cylinder", nx, ny, |s, t| {
        let x = x0 + s * (x1 - x0);
        let phi = phi0 + t * (phi1 - phi0);
        let radial = Vec3::new(0.0, phi.sin(), phi.cos());
        let n = if phi1 > phi0 { radial } else { -radial };
        (Vec3::new(x, r * phi.sin(), r * phi.cos()), n)
    })
}

/// Quarter hemisphere of radius r (x, y ≥ 0, z ≥ 0) with a hole of
/// half-angle `hole` (radians) at the pole: s runs over the longitude
/// 0..π/2 (from +x to +y), t from the equator to the hole edge. Normal
/// outward.
pub fn hemisphere_quarter(r: f64, hole: f64, n: usize) -> Mesh {
    map("hemisphere", n, n, |s, t| {
        let lon = s * PI / 2.0;
        let lat = t * (PI / 2.0 - hole);
        let d = Vec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin());
        (d * r, d)
    })
}

//! Built-in structured meshers (tests and quick scenes): a map of the unit
//! square (s, t) ∈ [0, 1]² onto a surface with its exact unit normal.
//!
//! Node (i, j), i = 0..=nx along s, j = 0..=ny along t, has index
//! j (nx + 1) + i; element (i, j) has index j nx + i. Groups:
//! - edge groups `s0`, `s1` (the sides s = 0, 1, edges oriented along
//!   increasing t) and `t0`, `t1` (the sides t = 0, 1, along increasing s);
//! - surface group `all` (every element);
//! - node sets: each of those five, and the corners `s0t0`, `s1t0`, `s0t1`,
//!   `s1t1` (one node each).
//!
//! Elements are ordered counterclockwise in (s, t), so the mapped normal
//! ∂x/∂s × ∂x/∂t must agree with the given one.

use super::{Mesh, Vec3};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Maps the unit square with `f(s, t) = (position, unit normal)`.
pub fn map(label: &str, nx: usize, ny: usize, f: impl Fn(f64, f64) -> (Vec3, Vec3)) -> Mesh {
    grid(label, nx, ny, |i, j| {
        f(i as f64 / nx as f64, j as f64 / ny as f64)
    })
}

/// The structured mesh of node (i, j) ↦ `f(i, j) = (position, unit
/// normal)`, i = 0..=nx, j = 0..=ny (layout and groups: module doc).
pub fn grid(label: &str, nx: usize, ny: usize, f: impl Fn(usize, usize) -> (Vec3, Vec3)) -> Mesh {
    let mut nodes = Vec::new();
    let mut normals = Vec::new();
    let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, n) = f(i, j);
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
    for (name, i, j) in [
        ("s0t0", 0, 0),
        ("s1t0", nx, 0),
        ("s0t1", 0, ny),
        ("s1t1", nx, ny),
    ] {
        groups.insert(name.into(), vec![id(i, j)]);
    }
    let mut edge_groups: BTreeMap<String, Vec<[usize; 2]>> = BTreeMap::new();
    edge_groups.insert(
        "s0".into(),
        (0..ny).map(|j| [id(0, j), id(0, j + 1)]).collect(),
    );
    edge_groups.insert(
        "s1".into(),
        (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect(),
    );
    edge_groups.insert(
        "t0".into(),
        (0..nx).map(|i| [id(i, 0), id(i + 1, 0)]).collect(),
    );
    edge_groups.insert(
        "t1".into(),
        (0..nx).map(|i| [id(i, ny), id(i + 1, ny)]).collect(),
    );
    let mut quads = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let ne = quads.len();
    let mut surface_groups = BTreeMap::new();
    surface_groups.insert("all".to_string(), (0..ne).collect());
    Mesh {
        file: format!("<built-in {label} {nx}x{ny}>").into(),
        node_tags: (1..=nodes.len()).collect(),
        nodes,
        quads,
        quad_lines: vec![0; ne],
        quad_tags: (1..=ne).collect(),
        exact_normals: Some(normals),
        groups,
        edge_groups,
        surface_groups,
        grid: Some(super::Grid { nx, ny }),
        notes: vec![],
        digest: None,
    }
}

/// `m` (from [`grid`]) closed along t: its last node row (t = 1) is
/// dropped and the elements that used it take the first row (t = 0), which
/// the map put at the same place (a full turn). The t0 and t1 groups are
/// then both the seam row; the mesh has no [`super::Grid`] (its rows no
/// longer follow the layout's numbering at the seam).
pub fn close_t(mut m: Mesh) -> Mesh {
    let g = m.grid.expect("a structured mesh");
    let (nx, ny) = (g.nx, g.ny);
    let last = ny * (nx + 1);
    let seam = |n: usize| if n >= last { n - last } else { n };
    for q in &mut m.quads {
        for n in q.iter_mut() {
            *n = seam(*n);
        }
    }
    m.nodes.truncate(last);
    m.node_tags.truncate(last);
    if let Some(normals) = &mut m.exact_normals {
        normals.truncate(last);
    }
    for nodes in m.groups.values_mut() {
        for n in nodes.iter_mut() {
            *n = seam(*n);
        }
        nodes.sort_unstable();
        nodes.dedup();
    }
    for edges in m.edge_groups.values_mut() {
        for e in edges.iter_mut() {
            *e = e.map(seam);
        }
    }
    m.grid = None;
    m.notes.push(format!(
        "closed along t: {} nodes on the seam joined",
        nx + 1
    ));
    m
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

/// Patch of the sphere of radius r about the origin: longitude
/// λ = λ0 + s (λ1 − λ0) (from +x toward +y), latitude
/// β = β0 + t (β1 − β0) (from the equator z = 0 toward +z), position
/// r (cos β cos λ, cos β sin λ, sin β). Angles in radians; keep |β| < π/2
/// on the patch (at a pole the elements collapse to triangles). The normal ∂x/∂s × ∂x/∂t is outward when
/// (λ1 − λ0)(β1 − β0) > 0 (the usual case), inward otherwise.
pub fn sphere_patch(
    r: f64,
    lon0: f64,
    lon1: f64,
    lat0: f64,
    lat1: f64,
    nx: usize,
    ny: usize,
) -> Mesh {
    let sign = ((lon1 - lon0) * (lat1 - lat0)).signum();
    map("sphere", nx, ny, |s, t| {
        let lon = lon0 + s * (lon1 - lon0);
        let lat = lat0 + t * (lat1 - lat0);
        let d = Vec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin());
        (d * r, d * sign)
    })
}

/// Flat ring sector in the plane z = 0: radius ρ = r_in + s (r_out − r_in)
/// (s along the radius, `nr` elements), angle θ = θ0 + t (θ1 − θ0) from +x
/// toward +y (t along the angle, `nt` elements), position (ρ cos θ, ρ sin θ, 0).
/// The normal ∂x/∂s × ∂x/∂t is +z when (r_out − r_in)(θ1 − θ0) > 0 (the usual
/// case), −z otherwise. r_in = 0 gives degenerate elements at the centre,
/// which [`Mesh::directors`] rejects.
pub fn annulus(r_in: f64, r_out: f64, theta0: f64, theta1: f64, nr: usize, nt: usize) -> Mesh {
    let n = Vec3::z() * ((r_out - r_in) * (theta1 - theta0)).signum();
    map("annulus", nr, nt, |s, t| {
        let rho = r_in + s * (r_out - r_in);
        let th = theta0 + t * (theta1 - theta0);
        (Vec3::new(rho * th.cos(), rho * th.sin(), 0.0), n)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Every element's normal agrees with the exact normals of its nodes
    /// (to within the faceting angle), and `directors` accepts the mesh.
    fn check_orientation(m: &Mesh, min_cos: f64) {
        let dirs = m.directors().expect("directors");
        let exact = m.exact_normals.as_ref().unwrap();
        for (e, q) in m.quads.iter().enumerate() {
            let x = m.element_nodes(e);
            let n = (x[2] - x[0]).cross(&(x[3] - x[1])).normalize();
            for &a in q {
                assert!((exact[a].norm() - 1.0).abs() < 1e-14);
                assert!(
                    n.dot(&exact[a]) > min_cos,
                    "{}: element {e} node {a}: {}",
                    m.file.display(),
                    n.dot(&exact[a])
                );
                assert_eq!(dirs[a], exact[a]);
            }
        }
    }

    /// The exact normal is the unit normal of the map: ∂x/∂s × ∂x/∂t by
    /// central differences, at every node away from the sides.
    fn check_exact_normal(f: impl Fn(f64, f64) -> Vec3, m: &Mesh, nx: usize, ny: usize) {
        let h = 1e-6;
        let exact = m.exact_normals.as_ref().unwrap();
        for j in 1..ny {
            for i in 1..nx {
                let (s, t) = (i as f64 / nx as f64, j as f64 / ny as f64);
                let xs = (f(s + h, t) - f(s - h, t)) / (2.0 * h);
                let xt = (f(s, t + h) - f(s, t - h)) / (2.0 * h);
                let n = xs.cross(&xt).normalize();
                let a = j * (nx + 1) + i;
                assert!((n - exact[a]).norm() < 1e-8, "{}", m.file.display());
                assert!((m.nodes[a] - f(s, t)).norm() < 1e-14);
            }
        }
    }

    #[test]
    fn sphere_patch_is_outward_and_on_the_sphere() {
        let (r, l0, l1, b0, b1) = (2.5, -0.3, 1.1, -0.7, 0.9);
        let m = sphere_patch(r, l0, l1, b0, b1, 7, 5);
        check_orientation(&m, 0.9);
        let exact = m.exact_normals.as_ref().unwrap();
        for (x, n) in m.nodes.iter().zip(exact) {
            assert!((x.norm() - r).abs() < 1e-14);
            assert!((x / r - n).norm() < 1e-14, "outward");
        }
        let f = |s: f64, t: f64| {
            let (lon, lat) = (l0 + s * (l1 - l0), b0 + t * (b1 - b0));
            r * Vec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin())
        };
        check_exact_normal(f, &m, 7, 5);
        // Reversed latitude range: the normal follows the orientation.
        let m = sphere_patch(r, l0, l1, b1, b0, 4, 4);
        check_orientation(&m, 0.9);
        assert!(m.exact_normals.as_ref().unwrap()[0].dot(&m.nodes[0]) < 0.0);
    }

    #[test]
    fn annulus_is_flat_with_normal_z() {
        let (a, b, t0, t1) = (0.5, 1.5, 0.2, 2.9);
        let m = annulus(a, b, t0, t1, 4, 9);
        check_orientation(&m, 1.0 - 1e-12);
        for (x, n) in m.nodes.iter().zip(m.exact_normals.as_ref().unwrap()) {
            assert_eq!(x.z, 0.0);
            assert_eq!(*n, Vec3::z());
            let rho = x.xy().norm();
            assert!(rho > a - 1e-14 && rho < b + 1e-14);
        }
        let f = |s: f64, t: f64| {
            let (rho, th) = (a + s * (b - a), t0 + t * (t1 - t0));
            Vec3::new(rho * th.cos(), rho * th.sin(), 0.0)
        };
        check_exact_normal(f, &m, 4, 9);
        // s runs along the radius: `s0` is the inner arc, `s1` the outer one.
        for &n in &m.groups["s0"] {
            assert!((m.nodes[n].norm() - a).abs() < 1e-14);
        }
        for &n in &m.groups["s1"] {
            assert!((m.nodes[n].norm() - b).abs() < 1e-14);
        }
        // Reversed angles: normal −z, still consistent.
        let m = annulus(a, b, t1, t0, 3, 3);
        check_orientation(&m, 1.0 - 1e-12);
        assert_eq!(m.exact_normals.as_ref().unwrap()[0], -Vec3::z());
        assert!(annulus(0.0, 1.0, 0.0, 1.0, 2, 2).directors().is_err());
    }

    #[test]
    fn builtin_meshes_orientation() {
        check_orientation(&rectangle(0.0, 2.0, -1.0, 1.0, 3, 2), 1.0 - 1e-12);
        check_orientation(&cylinder_panel(1.0, 0.0, 2.0, 0.0, 1.2, 3, 6), 0.9);
        check_orientation(&cylinder_panel(1.0, 0.0, 2.0, 1.2, 0.0, 3, 6), 0.9);
        check_orientation(&hemisphere_quarter(10.0, 0.3, 6), 0.9);
    }

    #[test]
    fn structured_groups() {
        let (nx, ny) = (3, 2);
        let m = rectangle(0.0, 3.0, 0.0, 2.0, nx, ny);
        let scene = Path::new("scene.toml");
        assert_eq!(m.surface("all", scene, "k").unwrap(), &[0, 1, 2, 3, 4, 5]);
        let corner = |name: &str| m.nodes[m.group(name, scene, "k").unwrap()[0]];
        assert_eq!(corner("s0t0"), Vec3::new(0.0, 0.0, 0.0));
        assert_eq!(corner("s1t0"), Vec3::new(3.0, 0.0, 0.0));
        assert_eq!(corner("s0t1"), Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(corner("s1t1"), Vec3::new(3.0, 2.0, 0.0));
        for (side, n, dir) in [
            ("s0", ny, Vec3::y()),
            ("s1", ny, Vec3::y()),
            ("t0", nx, Vec3::x()),
            ("t1", nx, Vec3::x()),
        ] {
            let e = m.edges(side, scene, "k").unwrap();
            assert_eq!(e.len(), n);
            // Oriented along the increasing parameter, chained, and
            // covering the node set of the side.
            let mut nodes: Vec<usize> = e.iter().flatten().copied().collect();
            for w in e.windows(2) {
                assert_eq!(w[0][1], w[1][0]);
            }
            for [a, b] in e {
                assert!((m.nodes[*b] - m.nodes[*a]).normalize().dot(&dir) > 1.0 - 1e-14);
            }
            nodes.sort_unstable();
            nodes.dedup();
            assert_eq!(nodes, m.groups[side]);
        }
        // Kind errors name the group, its kind and the groups of the kind.
        let err = m
            .surface("s0", scene, "pressure.group")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("`s0`") && err.contains("is an edge group"),
            "{err}"
        );
        assert!(err.contains("surface groups: all"), "{err}");
        assert!(
            err.contains("scene.toml") && err.contains("pressure.group"),
            "{err}"
        );
        let err = m.edges("all", scene, "k").unwrap_err().to_string();
        assert!(
            err.contains("is a surface group, not an edge group"),
            "{err}"
        );
        let err = m.edges("s0t0", scene, "k").unwrap_err().to_string();
        assert!(err.contains("is a node group, not an edge group"), "{err}");
        assert!(err.contains("edge groups: s0, s1, t0, t1"), "{err}");
        let err = m.surface("nope", scene, "k").unwrap_err().to_string();
        assert!(err.contains("not found") && err.contains("s1t1"), "{err}");
    }
}

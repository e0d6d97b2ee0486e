//! Line loads on 2-node edges (mesh edge groups, [`crate::mesh::Mesh::edges`]).
//!
//! A dead force per unit reference length q (a fixed vector, N/m) on the
//! straight edge from a to b of length L gives the consistent nodal forces
//! f_a = f_b = q L / 2: exact for linear shape functions and uniform q.
//! (Follower line loads and distributed moments are not provided.)

use super::Vec3;

/// Consistent nodal forces of the uniform line load `q` (force per unit
/// length) on the edge from `a` to `b`: q |b − a| / 2 at each end.
pub fn line_load_forces(q: Vec3, a: Vec3, b: Vec3) -> [Vec3; 2] {
    let f = q * (0.5 * (b - a).norm());
    [f, f]
}

/// Nodal forces of the line load `q` on every edge of `edges` (node indices
/// into `nodes`), one vector per node of `nodes`.
pub fn assemble_line_load(nodes: &[Vec3], edges: &[[usize; 2]], q: Vec3) -> Vec<Vec3> {
    let mut f = vec![Vec3::zeros(); nodes.len()];
    for &[a, b] in edges {
        let [fa, fb] = line_load_forces(q, nodes[a], nodes[b]);
        f[a] += fa;
        f[b] += fb;
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured;
    use std::path::Path;

    #[test]
    fn single_edge_halves() {
        let q = Vec3::new(1.0, -2.0, 3.0);
        let [fa, fb] = line_load_forces(q, Vec3::new(1.0, 1.0, 0.0), Vec3::new(4.0, 5.0, 0.0));
        assert_eq!(fa, q * 2.5);
        assert_eq!(fb, q * 2.5);
    }

    #[test]
    fn total_on_a_curved_chain_is_q_times_length() {
        // The curved side t1 of a cylinder panel: an arc of 8 chords.
        let m = structured::cylinder_panel(2.0, 0.0, 1.0, 0.1, 1.7, 3, 8);
        let edges = m.edges("s1", Path::new("s.toml"), "k").unwrap();
        let q = Vec3::new(0.3, -1.0, 2.0);
        let f = assemble_line_load(&m.nodes, edges, q);
        let length: f64 = edges
            .iter()
            .map(|&[a, b]| (m.nodes[b] - m.nodes[a]).norm())
            .sum();
        let total: Vec3 = f.iter().sum();
        assert!((total - q * length).norm() < 1e-14 * q.norm() * length);
        // The chord length tends to the arc length r Δφ.
        assert!((length - 2.0 * 1.6).abs() < 1e-2);
        // Only nodes of the edge group are loaded; interior ones get q L.
        let side = &m.groups["s1"];
        for (n, fn_) in f.iter().enumerate() {
            if !side.contains(&n) {
                assert_eq!(*fn_, Vec3::zeros());
            }
        }
        let mid = edges[3][1];
        let l = (m.nodes[edges[3][1]] - m.nodes[edges[3][0]]).norm()
            + (m.nodes[edges[4][1]] - m.nodes[edges[4][0]]).norm();
        assert!((f[mid] - q * (l / 2.0)).norm() < 1e-14);
    }
}

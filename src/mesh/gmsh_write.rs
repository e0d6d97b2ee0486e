//! Writer for gmsh .msh 4.1 ASCII quadrilateral meshes, the format
//! [`super::gmsh`] reads (gmsh manual §10.1): used to hand generated meshes
//! (e.g. the scaling benchmark's refinements) to scene files.
//!
//! [`write()`]: one surface entity holds every node and quadrilateral, physical
//! group `surface_group`; each edge group, given as a chain of nodes, becomes
//! a curve entity of 2-node lines through its nodes in the given order.
//!
//! [`write_mesh`] writes the mesh's own groups so that
//! [`super::gmsh::read`] gives them back: each edge group as a physical
//! curve (a curve entity of 2-node lines, the mesh's edges), the surface
//! groups as physical surfaces (one surface entity per distinct combination
//! of surface groups; quadrilaterals keep their order), and each node set
//! that is neither as a physical point (a point entity holding one point
//! element per node). Node sets of edge or surface groups are implied by
//! their elements and are not written separately.

use super::Mesh;
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Writes `mesh` to `path` with the named surface group and edge groups.
pub fn write(
    path: &Path,
    mesh: &Mesh,
    surface_group: &str,
    edge_groups: &[(&str, &[usize])],
) -> Result<()> {
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n");
    let _ = writeln!(s, "{}", edge_groups.len() + 1);
    for (i, (name, _)) in edge_groups.iter().enumerate() {
        let _ = writeln!(s, "1 {} \"{name}\"", i + 1);
    }
    let surface_tag = edge_groups.len() + 1;
    let _ = writeln!(s, "2 {surface_tag} \"{surface_group}\"\n$EndPhysicalNames");
    // Entities: bounding boxes are not read back; zeros keep the format.
    let _ = writeln!(s, "$Entities\n0 {} 1 0", edge_groups.len());
    for i in 0..edge_groups.len() {
        let _ = writeln!(s, "{} 0 0 0 0 0 0 1 {} 0", i + 1, i + 1);
    }
    let _ = writeln!(s, "1 0 0 0 0 0 0 1 {surface_tag} 0\n$EndEntities");
    let n = mesh.nodes.len();
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}");
    for i in 1..=n {
        let _ = writeln!(s, "{i}");
    }
    for x in &mesh.nodes {
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", x[0], x[1], x[2]);
    }
    s += "$EndNodes\n";
    let lines: usize = edge_groups
        .iter()
        .map(|(_, g)| g.len().saturating_sub(1))
        .sum();
    let total = lines + mesh.quads.len();
    let _ = writeln!(s, "$Elements\n{} {total} 1 {total}", edge_groups.len() + 1);
    let mut tag = 1;
    for (i, (_, g)) in edge_groups.iter().enumerate() {
        let _ = writeln!(s, "1 {} 1 {}", i + 1, g.len().saturating_sub(1));
        for w in g.windows(2) {
            let _ = writeln!(s, "{tag} {} {}", w[0] + 1, w[1] + 1);
            tag += 1;
        }
    }
    let _ = writeln!(s, "2 1 3 {}", mesh.quads.len());
    for q in &mesh.quads {
        let _ = writeln!(
            s,
            "{tag} {} {} {} {}",
            q[0] + 1,
            q[1] + 1,
            q[2] + 1,
            q[3] + 1
        );
        tag += 1;
    }
    s += "$EndElements\n";
    std::fs::write(path, s).map_err(|e| Error::Io {
        file: path.to_path_buf(),
        source: e,
    })
}

/// Writes `mesh` with all its groups (see the module documentation).
pub fn write_mesh(path: &Path, mesh: &Mesh) -> Result<()> {
    std::fs::write(path, format_mesh(mesh)).map_err(|e| Error::Io {
        file: path.to_path_buf(),
        source: e,
    })
}

/// The .msh 4.1 text that [`write_mesh`] writes.
pub fn format_mesh(mesh: &Mesh) -> String {
    let edge: Vec<(&String, &Vec<[usize; 2]>)> = mesh
        .edge_groups
        .iter()
        .filter(|(_, e)| !e.is_empty())
        .collect();
    let surf: Vec<&String> = mesh
        .surface_groups
        .iter()
        .filter(|(_, q)| !q.is_empty())
        .map(|(k, _)| k)
        .collect();
    let point: Vec<(&String, &Vec<usize>)> = mesh
        .groups
        .iter()
        .filter(|(k, v)| {
            !v.is_empty()
                && mesh.edge_groups.get(*k).is_none_or(Vec::is_empty)
                && mesh.surface_groups.get(*k).is_none_or(Vec::is_empty)
        })
        .collect();
    // Physical tags: points, then curves, then surfaces, numbered from 1.
    let surf_tag = |i: usize| point.len() + edge.len() + i + 1;
    // Surface groups of each quad (indices into `surf`).
    let mut of_quad: Vec<Vec<usize>> = vec![Vec::new(); mesh.quads.len()];
    for (i, name) in surf.iter().enumerate() {
        for &q in &mesh.surface_groups[*name] {
            of_quad[q].push(i);
        }
    }
    // One surface entity per distinct combination, tags from 1.
    let mut entity_of: BTreeMap<&[usize], usize> = BTreeMap::new();
    let mut entities: Vec<&[usize]> = Vec::new();
    for g in &of_quad {
        entity_of.entry(g.as_slice()).or_insert_with(|| {
            entities.push(g.as_slice());
            entities.len()
        });
    }
    if entities.is_empty() {
        entities.push(&[]);
    }
    // Element blocks of quads: runs of consecutive quads in one entity.
    let mut runs: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
    for (q, g) in of_quad.iter().enumerate() {
        let ent = entity_of[g.as_slice()];
        match runs.last_mut() {
            Some((e, r)) if *e == ent => r.end = q + 1,
            _ => runs.push((ent, q..q + 1)),
        }
    }

    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n");
    let _ = writeln!(s, "{}", point.len() + edge.len() + surf.len());
    for (i, (name, _)) in point.iter().enumerate() {
        let _ = writeln!(s, "0 {} \"{name}\"", i + 1);
    }
    for (i, (name, _)) in edge.iter().enumerate() {
        let _ = writeln!(s, "1 {} \"{name}\"", point.len() + i + 1);
    }
    for (i, name) in surf.iter().enumerate() {
        let _ = writeln!(s, "2 {} \"{name}\"", surf_tag(i));
    }
    s += "$EndPhysicalNames\n";
    // Entities: curve and surface bounding boxes are not read back; zeros
    // keep the format.
    let _ = writeln!(
        s,
        "$Entities\n{} {} {} 0",
        point.len(),
        edge.len(),
        entities.len()
    );
    for (i, (_, nodes)) in point.iter().enumerate() {
        let x = mesh.nodes[nodes[0]];
        let _ = writeln!(
            s,
            "{} {:.17e} {:.17e} {:.17e} 1 {}",
            i + 1,
            x[0],
            x[1],
            x[2],
            i + 1
        );
    }
    for i in 0..edge.len() {
        let _ = writeln!(s, "{} 0 0 0 0 0 0 1 {} 0", i + 1, point.len() + i + 1);
    }
    for (i, g) in entities.iter().enumerate() {
        let _ = write!(s, "{} 0 0 0 0 0 0 {}", i + 1, g.len());
        for &k in *g {
            let _ = write!(s, " {}", surf_tag(k));
        }
        s += " 0\n";
    }
    s += "$EndEntities\n";
    let n = mesh.nodes.len();
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}");
    for i in 1..=n {
        let _ = writeln!(s, "{i}");
    }
    for x in &mesh.nodes {
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", x[0], x[1], x[2]);
    }
    s += "$EndNodes\n";
    let total: usize = point.iter().map(|(_, v)| v.len()).sum::<usize>()
        + edge.iter().map(|(_, e)| e.len()).sum::<usize>()
        + mesh.quads.len();
    let _ = writeln!(
        s,
        "$Elements\n{} {total} 1 {total}",
        point.len() + edge.len() + runs.len()
    );
    let mut tag = 1;
    for (i, (_, nodes)) in point.iter().enumerate() {
        let _ = writeln!(s, "0 {} 15 {}", i + 1, nodes.len());
        for &a in *nodes {
            let _ = writeln!(s, "{tag} {}", a + 1);
            tag += 1;
        }
    }
    for (i, (_, edges)) in edge.iter().enumerate() {
        let _ = writeln!(s, "1 {} 1 {}", i + 1, edges.len());
        for [a, b] in *edges {
            let _ = writeln!(s, "{tag} {} {}", a + 1, b + 1);
            tag += 1;
        }
    }
    for (ent, r) in runs {
        let _ = writeln!(s, "2 {ent} 3 {}", r.len());
        for q in &mesh.quads[r] {
            let _ = writeln!(
                s,
                "{tag} {} {} {} {}",
                q[0] + 1,
                q[1] + 1,
                q[2] + 1,
                q[3] + 1
            );
            tag += 1;
        }
    }
    s += "$EndElements\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{gmsh, structured};

    #[test]
    fn written_mesh_reads_back() {
        let m = structured::rectangle(0.0, 2.0, -0.1, 0.1, 6, 2);
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let path = dir.join("strip.msh");
        write(&path, &m, "strip", &[("clamp", &m.groups["s0"])]).unwrap();
        // The reader numbers nodes in order of first use: compare positions.
        let back = gmsh::read(&path).unwrap();
        assert_eq!(back.nodes.len(), m.nodes.len());
        assert_eq!(back.quads.len(), m.quads.len());
        for (qa, qb) in back.quads.iter().zip(&m.quads) {
            for (a, b) in qa.iter().zip(qb) {
                assert_eq!(back.nodes[*a], m.nodes[*b]);
            }
        }
        let xs = |mesh: &crate::mesh::Mesh, g: &[usize]| {
            let mut v: Vec<[f64; 3]> = g.iter().map(|&i| mesh.nodes[i].into()).collect();
            v.sort_by(|a, b| a.partial_cmp(b).unwrap());
            v
        };
        let clamp = back.group("clamp", &path, "k").unwrap();
        assert_eq!(xs(&back, clamp), xs(&m, &m.groups["s0"]));
        assert_eq!(
            back.group("strip", &path, "k").unwrap().len(),
            m.nodes.len()
        );
    }

    #[test]
    fn all_groups_survive_a_round_trip() {
        let mut m = structured::annulus(0.5, 1.0, 0.0, 1.5, 3, 4);
        // An overlapping surface group that splits `all` into runs.
        m.surface_groups.insert("ring".into(), vec![3, 4, 5, 9]);
        let mut ring_nodes: Vec<usize> = [3, 4, 5, 9].iter().flat_map(|&q| m.quads[q]).collect();
        ring_nodes.sort_unstable();
        ring_nodes.dedup();
        m.groups.insert("ring".into(), ring_nodes);
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let path = dir.join("annulus.msh");
        write_mesh(&path, &m).unwrap();
        let back = gmsh::read(&path).unwrap();
        let at = |mesh: &crate::mesh::Mesh, n: usize| -> [f64; 3] { mesh.nodes[n].into() };
        assert_eq!(back.nodes.len(), m.nodes.len());
        assert_eq!(back.quads.len(), m.quads.len());
        for (qa, qb) in back.quads.iter().zip(&m.quads) {
            for (a, b) in qa.iter().zip(qb) {
                assert_eq!(at(&back, *a), at(&m, *b));
            }
        }
        assert_eq!(back.surface_groups, m.surface_groups);
        assert_eq!(
            back.edge_groups.keys().collect::<Vec<_>>(),
            m.edge_groups.keys().collect::<Vec<_>>()
        );
        for (name, edges) in &m.edge_groups {
            let eb = &back.edge_groups[name];
            assert_eq!(eb.len(), edges.len());
            for (x, y) in eb.iter().zip(edges) {
                assert_eq!(
                    [at(&back, x[0]), at(&back, x[1])],
                    [at(&m, y[0]), at(&m, y[1])]
                );
            }
        }
        assert_eq!(
            back.groups.keys().collect::<Vec<_>>(),
            m.groups.keys().collect::<Vec<_>>()
        );
        for (name, nodes) in &m.groups {
            let sorted = |mesh: &crate::mesh::Mesh, g: &[usize]| {
                let mut v: Vec<[f64; 3]> = g.iter().map(|&i| at(mesh, i)).collect();
                v.sort_by(|a, b| a.partial_cmp(b).unwrap());
                v
            };
            assert_eq!(
                sorted(&back, &back.groups[name]),
                sorted(&m, nodes),
                "{name}"
            );
            assert_eq!(back.group_kind(name), m.group_kind(name), "{name}");
        }
        back.directors().unwrap();
    }
}

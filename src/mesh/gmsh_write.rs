//! Writer for gmsh .msh 4.1 ASCII quadrilateral meshes, the format
//! [`super::gmsh`] reads (gmsh manual §10.1): used to hand generated meshes
//! (e.g. the scaling benchmark's refinements) to scene files.
//!
//! One surface entity holds every node and quadrilateral, physical group
//! `surface_group`; each edge group becomes a curve entity of 2-node lines
//! through its nodes in the given order.

use super::Mesh;
use crate::error::{Error, Result};
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{gmsh, structured};

    #[test]
    fn written_mesh_reads_back() {
        let m = structured::rectangle(0.0, 2.0, -0.1, 0.1, 6, 2);
        let dir = std::env::temp_dir().join(format!("anm-gmsh-write-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
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
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

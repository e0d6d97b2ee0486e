//! Reader for gmsh .msh 4.1 ASCII quadrilateral surface meshes
//! (format reference: gmsh manual §10.1 "MSH file format", version 4.1).
//!
//! Sections read: `$MeshFormat` (must be 4.1 ASCII), `$PhysicalNames`,
//! `$Entities` (physical tags of points, curves and surfaces), `$Nodes`,
//! `$Elements`. Surface elements must be 4-node quadrilaterals (type 3);
//! points (type 15) and 2-node lines (type 1) only define groups. Every
//! physical group becomes a node set named after it (the nodes of its
//! elements; unnamed groups are called `dim:tag`); in addition a physical
//! curve becomes an edge group (its 2-node lines, in file order) and a
//! physical surface a surface group (its quadrilaterals). Nodes not used by
//! any quadrilateral are dropped and the others renumbered in order of first
//! use; a group with a node outside every quadrilateral is an error, as are
//! a non-finite coordinate, a node tag given twice and a quadrilateral with
//! the nodes of another.

use super::{Mesh, Vec3};
use crate::error::{Error, Result};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

struct Lines<'a> {
    file: &'a Path,
    it: std::iter::Enumerate<std::str::Lines<'a>>,
    line: usize,
}

impl<'a> Lines<'a> {
    fn err(&self, problem: impl Into<String>) -> Error {
        Error::Mesh {
            file: self.file.to_path_buf(),
            line: self.line,
            problem: problem.into(),
        }
    }

    fn next(&mut self) -> Result<&'a str> {
        match self.it.next() {
            Some((i, l)) => {
                self.line = i + 1;
                Ok(l.trim())
            }
            None => Err(self.err("unexpected end of file")),
        }
    }

    fn numbers<T: std::str::FromStr>(&mut self, at_least: usize) -> Result<Vec<T>> {
        let l = self.next()?;
        let v: std::result::Result<Vec<T>, _> = l.split_whitespace().map(str::parse).collect();
        match v {
            Ok(v) if v.len() >= at_least => Ok(v),
            Ok(v) => Err(self.err(format!(
                "expected at least {at_least} numbers, found {}: `{l}`",
                v.len()
            ))),
            Err(_) => Err(self.err(format!("cannot parse numbers in `{l}`"))),
        }
    }
}

fn type_name(t: usize) -> &'static str {
    match t {
        1 => "2-node line",
        2 => "3-node triangle",
        3 => "4-node quadrilateral",
        8 => "3-node line",
        9 => "6-node triangle",
        10 => "9-node quadrilateral",
        15 => "point",
        16 => "8-node quadrilateral",
        _ => "unknown",
    }
}

/// Reads a .msh 4.1 ASCII file.
pub fn read(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io {
        file: path.to_path_buf(),
        source: e,
    })?;
    // A binary .msh is not text (review 17: meshio writes binary by
    // default, and the error was "stream did not contain valid UTF-8").
    let text = String::from_utf8(bytes).map_err(|_| Error::Mesh {
        file: path.to_path_buf(),
        line: 1,
        problem: "not text: a binary .msh (or another binary file); save it as gmsh 4.1 ASCII (gmsh: Mesh.Binary = 0; meshio: meshio.write(path, mesh, file_format=\"gmsh\", binary=False))".into(),
    })?;
    let mut mesh = parse(path, &text)?;
    mesh.digest = Some(super::digest(text.as_bytes()));
    Ok(mesh)
}

/// Parses .msh 4.1 text; `path` names the source in errors.
pub fn parse(path: &Path, text: &str) -> Result<Mesh> {
    let mut ln = Lines {
        file: path,
        it: text.lines().enumerate(),
        line: 0,
    };
    let mut names: HashMap<(usize, i64), String> = HashMap::new();
    // (dim, entity tag) -> physical tags.
    let mut entity_phys: HashMap<(usize, i64), Vec<i64>> = HashMap::new();
    let mut node_index: HashMap<usize, usize> = HashMap::new();
    let mut node_lines: HashMap<usize, usize> = HashMap::new();
    // The sorted nodes of each quadrilateral -> (tag, line): a repeated
    // element would count its stiffness and loads twice.
    let mut quad_seen: HashMap<[usize; 4], (usize, usize)> = HashMap::new();
    let mut nodes: Vec<Vec3> = Vec::new();
    let mut file_tags: Vec<usize> = Vec::new();
    let mut quads: Vec<[usize; 4]> = Vec::new();
    let mut quad_lines = Vec::new();
    let mut quad_tags = Vec::new();
    let mut group_nodes: BTreeMap<String, BTreeSet<usize>> = BTreeMap::new();
    let mut group_lines: BTreeMap<String, usize> = BTreeMap::new();
    // (entity dim, entity tag, element type, nodes, line in the file).
    let mut pending: Vec<(usize, i64, usize, Vec<usize>, usize)> = Vec::new();
    let mut seen_format = false;
    while let Some((i, l)) = ln.it.next() {
        ln.line = i + 1;
        match l.trim() {
            "$MeshFormat" => {
                let v: Vec<String> = ln.next()?.split_whitespace().map(String::from).collect();
                if v.len() < 3 || !v[0].starts_with("4.1") {
                    return Err(ln.err(format!(
                        "unsupported mesh format `{}`: version 4.1 needed",
                        v.join(" ")
                    )));
                }
                if v[1] != "0" {
                    return Err(
                        ln.err("binary .msh is not supported: save as ASCII (gmsh: Mesh.Binary = 0; meshio: binary=False)")
                    );
                }
                seen_format = true;
                ln.next()?;
            }
            "$PhysicalNames" => {
                let n: Vec<usize> = ln.numbers(1)?;
                for _ in 0..n[0] {
                    let l = ln.next()?;
                    let mut parts = l.splitn(3, char::is_whitespace);
                    let dim = parts.next().and_then(|s| s.parse().ok());
                    let tag = parts.next().and_then(|s| s.parse().ok());
                    let name = parts.next().map(|s| s.trim().trim_matches('"').to_string());
                    match (dim, tag, name) {
                        (Some(d), Some(t), Some(nm)) => {
                            names.insert((d, t), nm);
                        }
                        _ => return Err(ln.err(format!("bad physical name line `{l}`"))),
                    }
                }
                ln.next()?;
            }
            "$Entities" => {
                let counts: Vec<usize> = ln.numbers(4)?;
                for (dim, &count) in counts.iter().enumerate().take(4) {
                    for _ in 0..count {
                        let v: Vec<f64> = ln.numbers(1)?;
                        let tag = v[0] as i64;
                        // Points: tag x y z nphys ...; others: tag 6 box values nphys ...
                        let at = if dim == 0 { 4 } else { 7 };
                        let np =
                            *v.get(at).ok_or_else(|| ln.err("truncated entity line"))? as usize;
                        let phys: Vec<i64> = v
                            .get(at + 1..at + 1 + np)
                            .ok_or_else(|| ln.err("truncated entity line"))?
                            .iter()
                            .map(|&x| x as i64)
                            .collect();
                        entity_phys.insert((dim, tag), phys);
                    }
                }
                ln.next()?;
            }
            "$Nodes" => {
                let h: Vec<usize> = ln.numbers(4)?;
                for _ in 0..h[0] {
                    let b: Vec<usize> = ln.numbers(4)?;
                    let (param, count) = (b[2], b[3]);
                    let mut tags = Vec::with_capacity(count);
                    for _ in 0..count {
                        tags.push(ln.numbers::<usize>(1)?[0]);
                    }
                    for tag in tags {
                        let c: Vec<f64> = ln.numbers(3)?;
                        let _ = param;
                        // Rust parses "nan" and "inf": named here, not as
                        // a zero-area element later (review 5).
                        if let Some(k) = c[..3].iter().position(|x| !x.is_finite()) {
                            return Err(ln.err(format!(
                                "node {tag}: coordinate {} is not finite ({})",
                                ["x", "y", "z"][k],
                                c[k]
                            )));
                        }
                        if let Some(&first) = node_lines.get(&tag) {
                            return Err(ln.err(format!(
                                "node tag {tag} appears twice (first at line {first})"
                            )));
                        }
                        node_lines.insert(tag, ln.line);
                        node_index.insert(tag, nodes.len());
                        nodes.push(Vec3::new(c[0], c[1], c[2]));
                        file_tags.push(tag);
                    }
                }
                ln.next()?;
            }
            "$Elements" => {
                let h: Vec<usize> = ln.numbers(4)?;
                for _ in 0..h[0] {
                    let b: Vec<i64> = ln.numbers(4)?;
                    let (dim, etag, ty, count) =
                        (b[0] as usize, b[1], b[2] as usize, b[3] as usize);
                    let nn = match ty {
                        15 => 1,
                        1 => 2,
                        3 => 4,
                        _ => {
                            return Err(ln.err(format!(
                                "element type {ty} ({}) is not supported: 4-node quadrilaterals (type 3) for the surface, points and 2-node lines for groups (use Recombine and first-order elements)",
                                type_name(ty)
                            )));
                        }
                    };
                    for _ in 0..count {
                        let v: Vec<usize> = ln.numbers(nn + 1)?;
                        let mut idx = Vec::with_capacity(nn);
                        for t in &v[1..=nn] {
                            idx.push(*node_index.get(t).ok_or_else(|| {
                                ln.err(format!("element {} refers to unknown node {t}", v[0]))
                            })?);
                        }
                        if ty == 3 {
                            let mut key = [idx[0], idx[1], idx[2], idx[3]];
                            key.sort_unstable();
                            if let Some((tag, line)) = quad_seen.insert(key, (v[0], ln.line)) {
                                return Err(ln.err(format!(
                                    "element {} has the nodes of element {tag} (line {line}): a repeated element counts its stiffness and loads twice",
                                    v[0]
                                )));
                            }
                            quads.push([idx[0], idx[1], idx[2], idx[3]]);
                            quad_lines.push(ln.line);
                            quad_tags.push(v[0]);
                        }
                        pending.push((dim, etag, ty, idx, ln.line));
                    }
                }
                ln.next()?;
            }
            _ => {}
        }
    }
    if !seen_format {
        return Err(Error::Mesh {
            file: path.to_path_buf(),
            line: 1,
            problem: "no $MeshFormat section: not a gmsh .msh file".into(),
        });
    }
    if quads.is_empty() {
        return Err(Error::Mesh {
            file: path.to_path_buf(),
            line: ln.line,
            problem: "no 4-node quadrilateral elements (is there a Physical Surface?)".into(),
        });
    }
    // Edges (old node indices) and quads of the groups.
    let mut edge_old: BTreeMap<String, Vec<[usize; 2]>> = BTreeMap::new();
    let mut surface_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut quad_index = 0;
    for (dim, etag, ty, idx, line) in pending {
        for ptag in entity_phys.get(&(dim, etag)).into_iter().flatten() {
            let name = names
                .get(&(dim, *ptag))
                .cloned()
                .unwrap_or_else(|| format!("{dim}:{ptag}"));
            group_lines.entry(name.clone()).or_insert(line);
            match ty {
                1 => edge_old
                    .entry(name.clone())
                    .or_default()
                    .push([idx[0], idx[1]]),
                3 => surface_groups
                    .entry(name.clone())
                    .or_default()
                    .push(quad_index),
                _ => {}
            }
            group_nodes
                .entry(name)
                .or_default()
                .extend(idx.iter().copied());
        }
        if ty == 3 {
            quad_index += 1;
        }
    }
    for v in surface_groups.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    // Keep only nodes used by quadrilaterals.
    let mut used = vec![usize::MAX; nodes.len()];
    let mut kept = Vec::new();
    let mut node_tags = Vec::new();
    for q in &mut quads {
        for n in q.iter_mut() {
            if used[*n] == usize::MAX {
                used[*n] = kept.len();
                kept.push(nodes[*n]);
                node_tags.push(file_tags[*n]);
            }
            *n = used[*n];
        }
    }
    let mut groups = BTreeMap::new();
    for (name, set) in group_nodes {
        let mut v = Vec::with_capacity(set.len());
        for n in set {
            if used[n] == usize::MAX {
                return Err(Error::Mesh {
                    file: path.to_path_buf(),
                    line: group_lines[&name],
                    problem: format!(
                        "physical group `{name}` has a node outside every quadrilateral"
                    ),
                });
            }
            v.push(used[n]);
        }
        v.sort_unstable();
        groups.insert(name, v);
    }
    // Every node of an edge group is in its node set, checked above.
    let edge_groups = edge_old
        .into_iter()
        .map(|(name, e)| (name, e.iter().map(|&[a, b]| [used[a], used[b]]).collect()))
        .collect();
    Ok(Mesh {
        file: path.to_path_buf(),
        nodes: kept,
        node_tags,
        quads,
        quad_lines,
        quad_tags,
        exact_normals: None,
        groups,
        edge_groups,
        surface_groups,
        grid: None,
        notes: vec![],
        digest: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two quadrilaterals on [0, 2] × [0, 1] in two surface entities, a
    /// physical point, a physical curve (the bottom side), two physical
    /// surfaces (`plate`: both, `left`: the first) and an unused node 7.
    const MSH: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
4
0 10 "corner"
1 20 "bottom"
2 30 "plate"
2 31 "left"
$EndPhysicalNames
$Entities
1 1 2 0
1 0 0 0 1 10
1 0 0 0 2 0 0 1 20 2 1 -2
1 0 0 0 1 1 0 2 30 31 0
2 1 0 0 2 1 0 1 30 0
$EndEntities
$Nodes
1 7 1 7
2 1 0 7
1
2
3
4
5
6
7
0 0 0
1 0 0
2 0 0
0 1 0
1 1 0
2 1 0
5 5 0
$EndNodes
$Elements
4 5 1 5
0 1 15 1
1 1
1 1 1 2
2 1 2
3 2 3
2 1 3 1
4 1 2 5 4
2 2 3 1
5 2 3 6 5
$EndElements
"#;

    #[track_caller]
    fn refused(text: &str, line: usize, needles: &[&str]) {
        let e = parse(Path::new("bad.msh"), text)
            .expect_err("refused")
            .to_string();
        assert!(e.contains(&format!("bad.msh:{line}")), "{e}");
        for n in needles {
            assert!(e.contains(n), "`{n}` not in: {e}");
        }
    }

    /// Review 5: a NaN coordinate was reported as a zero-area element, a
    /// repeated node tag as an element's unknown node, and a repeated
    /// element was accepted with its stiffness and loads counted twice.
    #[test]
    fn non_finite_coordinates_repeated_tags_and_elements_are_named() {
        // Node 5 (line 32) at x = nan, then at x = inf.
        for (bad, word) in [("nan 1 0", "NaN"), ("inf 1 0", "inf")] {
            let text = MSH.replacen("1 1 0\n", &format!("{bad}\n"), 1);
            refused(&text, 32, &["node 5", "coordinate x is not finite", word]);
        }
        // Tag 2 given to the third node too (coordinates at lines 29, 30).
        let text = MSH.replacen("2\n3\n4\n", "2\n2\n4\n", 1);
        refused(&text, 30, &["node tag 2 appears twice", "line 29"]);
        // Element 5 given the nodes of element 4, in another order.
        let text = MSH.replacen("5 2 3 6 5", "5 5 4 1 2", 1);
        refused(
            &text,
            46,
            &["element 5 has the nodes of element 4", "line 44"],
        );
    }

    #[test]
    fn coincident_nodes_that_share_no_element_are_found() {
        let m = parse(Path::new("two.msh"), MSH).unwrap();
        assert_eq!(m.coincident_nodes(1e-9), None);
        // The second quad on its own copy of the middle column (tags 8, 9).
        let cut = MSH
            .replacen("1 7 1 7\n2 1 0 7\n", "1 9 1 9\n2 1 0 9\n", 1)
            .replacen("7\n0 0 0", "7\n8\n9\n0 0 0", 1)
            .replacen("5 5 0\n", "5 5 0\n1 0 0\n1 1 0\n", 1)
            .replacen("5 2 3 6 5", "5 8 3 6 9", 1);
        let m = parse(Path::new("cut.msh"), &cut).unwrap();
        let (a, b, d) = m.coincident_nodes(1e-9).expect("the cut");
        assert_eq!(d, 0.0);
        assert_eq!((at(&m, a), at(&m, b)).0, at(&m, b));
        assert_eq!(
            m.element_of(a).map(|e| e.0).unwrap() + m.element_of(b).map(|e| e.0).unwrap(),
            9
        );
    }

    fn at(m: &Mesh, n: usize) -> [f64; 3] {
        m.nodes[n].into()
    }

    #[test]
    fn three_kinds_of_groups() {
        let f = Path::new("two.msh");
        let m = parse(f, MSH).unwrap();
        let scene = Path::new("scene.toml");
        assert_eq!(m.nodes.len(), 6, "unused node dropped");
        assert_eq!(m.quads.len(), 2);
        assert_eq!(m.quad_tags, vec![4, 5]);
        // Node sets of every group.
        let corner = m.group("corner", scene, "k").unwrap();
        assert_eq!(corner.len(), 1);
        assert_eq!(at(&m, corner[0]), [0.0, 0.0, 0.0]);
        assert_eq!(m.group("bottom", scene, "k").unwrap().len(), 3);
        assert_eq!(m.group("plate", scene, "k").unwrap().len(), 6);
        assert_eq!(m.group("left", scene, "k").unwrap().len(), 4);
        // Edges of the physical curve, renumbered, in file order.
        let e = m.edges("bottom", scene, "k").unwrap();
        let pos: Vec<[[f64; 3]; 2]> = e.iter().map(|&[a, b]| [at(&m, a), at(&m, b)]).collect();
        assert_eq!(
            pos,
            vec![
                [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
                [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]
            ]
        );
        // Quads of the physical surfaces.
        assert_eq!(m.surface("plate", scene, "k").unwrap(), &[0, 1]);
        assert_eq!(m.surface("left", scene, "k").unwrap(), &[0]);
        // Wrong kinds are rejected with the kind and the candidates.
        let err = m
            .surface("bottom", scene, "load.group")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("`bottom`")
                && err.contains("is an edge group, not a surface group")
                && err.contains("surface groups: left, plate")
                && err.contains("scene.toml")
                && err.contains("load.group"),
            "{err}"
        );
        let err = m.edges("corner", scene, "k").unwrap_err().to_string();
        assert!(
            err.contains("is a node group, not an edge group (edge groups: bottom)"),
            "{err}"
        );
        let err = m.edges("top", scene, "k").unwrap_err().to_string();
        assert!(
            err.contains("not found") && err.contains("two.msh"),
            "{err}"
        );
        m.directors().unwrap();
    }

    #[test]
    fn line_off_the_surface_is_an_error() {
        let text = MSH.replace("3 2 3\n2 1 3 1", "3 3 7\n2 1 3 1");
        let err = parse(Path::new("bad.msh"), &text).unwrap_err().to_string();
        assert!(
            err.contains("physical group `bottom` has a node outside every quadrilateral"),
            "{err}"
        );
    }

    #[test]
    fn unsupported_elements_are_named() {
        let text = MSH.replace("2 1 3 1\n4 1 2 5 4", "2 1 2 1\n4 1 2 5");
        let err = parse(Path::new("tri.msh"), &text).unwrap_err().to_string();
        assert!(err.contains("3-node triangle"), "{err}");
    }
}

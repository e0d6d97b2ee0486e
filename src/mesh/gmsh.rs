//! Reader for gmsh .msh 4.1 ASCII quadrilateral surface meshes
//! (format reference: gmsh manual §10.1 "MSH file format", version 4.1).
//!
//! Sections read: `$MeshFormat` (must be 4.1 ASCII), `$PhysicalNames`,
//! `$Entities` (physical tags of points, curves and surfaces), `$Nodes`,
//! `$Elements`. Surface elements must be 4-node quadrilaterals (type 3);
//! points (type 15) and 2-node lines (type 1) only define node sets. Every
//! physical group becomes a node set named after it (the nodes of its
//! elements). Nodes not used by any quadrilateral are dropped.

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
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        file: path.to_path_buf(),
        source: e,
    })?;
    parse(path, &text)
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
    let mut nodes: Vec<Vec3> = Vec::new();
    let mut quads: Vec<[usize; 4]> = Vec::new();
    let mut quad_lines = Vec::new();
    let mut quad_tags = Vec::new();
    let mut group_nodes: BTreeMap<String, BTreeSet<usize>> = BTreeMap::new();
    let mut group_lines: BTreeMap<String, usize> = BTreeMap::new();
    let mut pending: Vec<(usize, i64, Vec<usize>, usize)> = Vec::new();
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
                        ln.err("binary .msh is not supported: save as ASCII (Mesh.Binary = 0)")
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
                        node_index.insert(tag, nodes.len());
                        nodes.push(Vec3::new(c[0], c[1], c[2]));
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
                            quads.push([idx[0], idx[1], idx[2], idx[3]]);
                            quad_lines.push(ln.line);
                            quad_tags.push(v[0]);
                        }
                        pending.push((dim, etag, idx, ln.line));
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
    for (dim, etag, idx, line) in pending {
        for ptag in entity_phys.get(&(dim, etag)).into_iter().flatten() {
            let name = names
                .get(&(dim, *ptag))
                .cloned()
                .unwrap_or_else(|| format!("{dim}:{ptag}"));
            group_lines.entry(name.clone()).or_insert(line);
            group_nodes
                .entry(name)
                .or_default()
                .extend(idx.iter().copied());
        }
    }
    // Keep only nodes used by quadrilaterals.
    let mut used = vec![usize::MAX; nodes.len()];
    let mut kept = Vec::new();
    for q in &mut quads {
        for n in q.iter_mut() {
            if used[*n] == usize::MAX {
                used[*n] = kept.len();
                kept.push(nodes[*n]);
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
    Ok(Mesh {
        file: path.to_path_buf(),
        nodes: kept,
        quads,
        quad_lines,
        quad_tags,
        exact_normals: None,
        groups,
    })
}

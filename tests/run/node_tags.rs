//! Nodes are named by their gmsh tags: in contact_final.csv, the VTK
//! snapshots and the messages, a node of a mesh file is the number the file
//! gives it, as elements are (review 5 found the outputs numbering nodes in
//! their order of first use, which a renumbered mesh did not match). The
//! answers do not depend on the numbering.

use crate::common::anm_run as run;
use crate::scratch::scratch;
use std::collections::BTreeMap;
use std::path::Path;

/// The new tag of old node tag t of plate-cylinder-20x2.msh (63 nodes):
/// reversed, spread out and offset, so that no tag keeps its number or
/// its order.
fn renumber(t: usize) -> usize {
    1000 + 7 * (64 - t)
}

/// plate-cylinder-20x2.msh with every node tag renumbered (in the $Nodes
/// blocks and in the elements' connectivity) and the elements of each block
/// in reverse order, and the coordinates per new tag.
fn renumbered_mesh() -> (String, BTreeMap<usize, [f64; 3]>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/plate-cylinder-20x2.msh");
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut out: Vec<String> = Vec::new();
    let mut coords = BTreeMap::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        out.push(line.to_string());
        i += 1;
        if line == "$Nodes" {
            let head: Vec<usize> = lines[i]
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            out.push(format!(
                "{} {} {} {}",
                head[0],
                head[1],
                renumber(head[3]),
                renumber(head[2])
            ));
            i += 1;
            for _ in 0..head[0] {
                out.push(lines[i].to_string());
                let count: usize = lines[i].split_whitespace().nth(3).unwrap().parse().unwrap();
                i += 1;
                let tags: Vec<usize> = (0..count)
                    .map(|k| lines[i + k].trim().parse().unwrap())
                    .collect();
                for &t in &tags {
                    out.push(renumber(t).to_string());
                }
                i += count;
                for &t in &tags {
                    let x: Vec<f64> = lines[i]
                        .split_whitespace()
                        .map(|x| x.parse().unwrap())
                        .collect();
                    coords.insert(renumber(t), [x[0], x[1], x[2]]);
                    out.push(lines[i].to_string());
                    i += 1;
                }
            }
        } else if line == "$Elements" {
            let head: Vec<usize> = lines[i]
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            out.push(lines[i].to_string());
            i += 1;
            for _ in 0..head[0] {
                out.push(lines[i].to_string());
                let count: usize = lines[i].split_whitespace().nth(3).unwrap().parse().unwrap();
                i += 1;
                let mut block: Vec<String> = (0..count)
                    .map(|k| {
                        let v: Vec<usize> = lines[i + k]
                            .split_whitespace()
                            .map(|x| x.parse().unwrap())
                            .collect();
                        let nodes: Vec<String> =
                            v[1..].iter().map(|&t| renumber(t).to_string()).collect();
                        format!("{} {}", v[0], nodes.join(" "))
                    })
                    .collect();
                // The quadrilaterals in reverse order: the solver's own
                // numbering of the nodes changes too.
                block.reverse();
                out.extend(block);
                i += count;
            }
        }
    }
    assert_eq!(coords.len(), 63, "every node renumbered");
    (out.join("\n") + "\n", coords)
}

/// plate-cylinder-coarse to lambda = 0.3, on `mesh`, with the cylinder's
/// centre at height `centre_z`.
fn scene(mesh: &Path, centre_z: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/plate-cylinder-coarse.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let edited = text
        .replace(
            "../meshes/plate-cylinder-20x2.msh",
            &mesh.display().to_string(),
        )
        .replace("lambda_end = 1.0", "lambda_end = 0.3")
        .replace(
            "snapshots = [0.05, 0.1, 0.2, 0.5, 1.0]",
            "snapshots = [0.1, 0.3]",
        )
        .replace(
            "centre = [1.0, 0.0, 0.5001]",
            &format!("centre = [1.0, 0.0, {centre_z}]"),
        );
    assert_ne!(edited, text);
    edited
}

/// Rows of a CSV file as strings, header first.
fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn nodes_are_named_by_their_gmsh_tags_and_the_answers_do_not_depend_on_them() {
    let dir = scratch("node-tags");
    let (text, coords) = renumbered_mesh();
    let mesh = dir.path().join("renumbered.msh");
    std::fs::write(&mesh, text).unwrap();
    let original = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/plate-cylinder-20x2.msh");
    let mut histories = vec![];
    let mut reactions = vec![];
    for (name, m) in [
        ("original", original.as_path()),
        ("renumbered", mesh.as_path()),
    ] {
        let s = dir.path().join(format!("{name}.toml"));
        std::fs::write(&s, scene(m, "0.5001")).unwrap();
        let out = dir.path().join(name);
        let r = run(&s, &out);
        assert_eq!(r.status.code(), Some(0), "{name}: {r:?}");
        histories.push(csv_rows(&out.join("history.csv")));
        // contact_final.csv: node, obstacle, X, Y, Z, gap, rn, ...; per
        // reference position, the tag and the reaction.
        let rows = csv_rows(&out.join("contact_final.csv"));
        assert_eq!(rows[0][..5], ["node", "obstacle", "X", "Y", "Z"]);
        let mut by_position = BTreeMap::new();
        for row in &rows[1..] {
            let tag: usize = row[0]
                .parse()
                .unwrap_or_else(|_| panic!("node `{}` is not an integer", row[0]));
            assert_eq!(row[1], "0", "obstacle written as an integer");
            let x: Vec<f64> = row[2..5].iter().map(|v| v.parse().unwrap()).collect();
            if name == "renumbered" {
                // The tag is the file's: its coordinates are the row's.
                assert_eq!(coords[&tag].to_vec(), x, "node {tag}");
            } else {
                assert!((1..=63).contains(&tag), "{tag}");
            }
            let key = format!("{:.6} {:.6}", x[0], x[1]);
            by_position.insert(key, row[6].parse::<f64>().unwrap());
        }
        reactions.push(by_position);
        // The snapshot's node array holds the tags.
        let vtu = std::fs::read_to_string(out.join("shell_final.vtu")).unwrap();
        let at = vtu
            .find(r#"Name="node""#)
            .expect("a node array in shell_final.vtu");
        let first: usize = vtu[at..].lines().nth(1).unwrap().trim().parse().unwrap();
        if name == "renumbered" {
            assert!(coords.contains_key(&first), "{first}");
        }
    }
    // Same answers to round-off: the history's columns and every reaction.
    let (a, b) = (&histories[0], &histories[1]);
    assert_eq!(a.len(), b.len());
    let mut worst = 0.0f64;
    for (ra, rb) in a[1..].iter().zip(&b[1..]) {
        for (x, y) in ra.iter().zip(rb) {
            let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
            worst = worst.max((x - y).abs() / x.abs().max(1e-6));
        }
    }
    let scale = reactions[0].values().fold(0.0f64, |m, r| m.max(r.abs()));
    let mut worst_rn = 0.0f64;
    assert_eq!(reactions[0].len(), reactions[1].len());
    for (k, r) in &reactions[0] {
        worst_rn = worst_rn.max((r - reactions[1][k]).abs() / scale);
    }
    println!("renumbered against original: history {worst:.2e}, reactions {worst_rn:.2e}");
    assert!(worst < 1e-6 && worst_rn < 1e-6, "{worst:e} {worst_rn:e}");

    // A message naming a node names its tag: the cylinder lowered so that
    // the row at x = 1 starts inside it.
    let s = dir.path().join("inside.toml");
    std::fs::write(&s, scene(&mesh, "0.4999")).unwrap();
    let r = run(&s, &dir.path().join("inside"));
    assert_ne!(r.status.code(), Some(0));
    let stderr = String::from_utf8_lossy(&r.stderr);
    let named: usize = stderr
        .split("contact node ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no node named: {stderr}"));
    assert!(
        (coords[&named][0] - 1.0).abs() < 1e-9,
        "node {named} at {:?}: {stderr}",
        coords[&named]
    );
}

//! Bad input for shell scenes and meshes: each case must stop with a clear
//! error naming the file and the key, element or line (never a panic).

use anm::Error;
use anm::scene::shell::load;
use std::path::{Path, PathBuf};

const MESH: &str = "meshes/plate-cylinder-20x2.msh";

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join("anm-shell-bad-input");
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// The default scene with `edits` (old, new) applied and the mesh `mesh`.
fn scene(name: &str, mesh: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string("scenes/plate-cylinder.toml").unwrap();
    text = text.replace("../meshes/plate-cylinder.msh", mesh.to_str().unwrap());
    for (old, new) in edits {
        assert!(text.contains(old), "edit `{old}` does not apply");
        text = text.replacen(old, new, 1);
    }
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn mesh_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(MESH)
}

/// The mesh with its first quadrilateral's node list rewritten by `f`;
/// returns the path and the 1-based line of that element.
fn edited_mesh(name: &str, f: impl Fn(&[&str]) -> Vec<String>) -> (PathBuf, usize) {
    let text = std::fs::read_to_string(mesh_path()).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Find the element block of type 3 and its first element.
    let mut at = None;
    for (i, l) in lines.iter().enumerate() {
        let v: Vec<&str> = l.split_whitespace().collect();
        if v.len() == 4 && v[0] == "2" && v[2] == "3" {
            at = Some(i + 1);
            break;
        }
    }
    let i = at.expect("quad block");
    let v: Vec<&str> = lines[i].split_whitespace().collect();
    let mut new = vec![v[0].to_string()];
    new.extend(f(&v[1..]));
    lines[i] = new.join(" ");
    let p = tmp(name);
    std::fs::write(&p, lines.join("\n") + "\n").unwrap();
    (p, i + 1)
}

#[track_caller]
fn expect_err(r: anm::Result<impl std::fmt::Debug>, parts: &[&str]) -> Error {
    let e = match r {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => e,
    };
    let msg = e.to_string();
    println!("{msg}");
    for p in parts {
        assert!(msg.contains(p), "message `{msg}` lacks `{p}`");
    }
    e
}

#[test]
fn inverted_element_is_reported_with_file_and_line() {
    let (m, line) = edited_mesh("inverted.msh", |n| {
        vec![n[0].into(), n[3].into(), n[2].into(), n[1].into()]
    });
    let s = scene("inverted.toml", &m, &[]);
    let e = expect_err(
        load(&s),
        &["inverted.msh", &format!(":{line}:"), "inverted"],
    );
    assert_eq!(e.kind(), "mesh");
}

#[test]
fn degenerate_element_is_reported_with_file_and_line() {
    let (m, line) = edited_mesh("degenerate.msh", |n| {
        vec![n[0].into(), n[0].into(), n[2].into(), n[3].into()]
    });
    let s = scene("degenerate.toml", &m, &[]);
    let e = expect_err(
        load(&s),
        &["degenerate.msh", &format!(":{line}:"), "degenerate"],
    );
    assert_eq!(e.kind(), "mesh");
}

#[test]
fn self_crossing_element_is_reported() {
    let (m, line) = edited_mesh("bowtie.msh", |n| {
        vec![n[0].into(), n[2].into(), n[1].into(), n[3].into()]
    });
    let s = scene("bowtie.toml", &m, &[]);
    expect_err(load(&s), &["bowtie.msh", &format!(":{line}:")]);
}

#[test]
fn zero_and_negative_thickness_are_rejected() {
    for (name, v) in [("zero.toml", "0.0"), ("neg.toml", "-8e-4")] {
        let s = scene(
            name,
            &mesh_path(),
            &[("thickness = 0.8e-3", &format!("thickness = {v}"))],
        );
        let e = expect_err(load(&s), &[name, "shell.thickness", "must be > 0"]);
        assert_eq!(e.kind(), "invalid_input");
    }
}

#[test]
fn missing_physical_group_is_named() {
    let s = scene(
        "nogroup.toml",
        &mesh_path(),
        &[("clamp = [\"clamp\"]", "clamp = [\"left_edge\"]")],
    );
    expect_err(
        load(&s),
        &[
            "nogroup.toml",
            "mesh.clamp[0]",
            "`left_edge`",
            "plate-cylinder-20x2.msh",
        ],
    );
    let s = scene(
        "nocontact.toml",
        &mesh_path(),
        &[("contact = \"strip\"", "contact = \"skin\"")],
    );
    expect_err(load(&s), &["mesh.contact", "`skin`"]);
}

#[test]
fn load_on_a_point_that_is_not_a_node_is_rejected() {
    let s = scene(
        "offnode.toml",
        &mesh_path(),
        &[("point = [2.0, 0.0, 0.0]", "point = [2.0, 0.03, 0.0]")],
    );
    let e = expect_err(load(&s), &["offnode.toml", "load[1].point", "not a node"]);
    assert_eq!(e.kind(), "invalid_input");
}

#[test]
fn unknown_key_and_binary_mesh_are_rejected() {
    let s = scene(
        "typo.toml",
        &mesh_path(),
        &[("thickness = 0.8e-3", "thicknes = 0.8e-3")],
    );
    expect_err(load(&s), &["typo.toml", "thicknes"]);
    let text = std::fs::read_to_string(mesh_path())
        .unwrap()
        .replacen("4.1 0 8", "4.1 1 8", 1);
    let p = tmp("binary.msh");
    std::fs::write(&p, text).unwrap();
    let s = scene("binary.toml", &p, &[]);
    expect_err(load(&s), &["binary.msh:2:", "binary"]);
}

#[test]
fn contact_row_without_nodes_is_rejected() {
    let s = scene(
        "rows.toml",
        &mesh_path(),
        &[(
            "contact_rows = [1.0, 1.1, 1.2]",
            "contact_rows = [1.0, 1.05, 1.2]",
        )],
    );
    expect_err(load(&s), &["output.contact_rows[1]", "no node row"]);
}

#[test]
fn triangle_mesh_is_rejected_with_the_element_type() {
    let text = std::fs::read_to_string(mesh_path()).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let i = lines
        .iter()
        .position(|l| {
            let v: Vec<&str> = l.split_whitespace().collect();
            v.len() == 4 && v[0] == "2" && v[2] == "3"
        })
        .unwrap();
    lines[i] = lines[i].replacen(" 3 ", " 2 ", 1);
    let p = tmp("triangles.msh");
    std::fs::write(&p, lines.join("\n") + "\n").unwrap();
    let s = scene("triangles.toml", &p, &[]);
    expect_err(
        load(&s),
        &[
            "triangles.msh",
            &format!(":{}:", i + 1),
            "type 2",
            "triangle",
        ],
    );
}

/// `anm audit` on plate-cylinder: friction options and bad values are
/// rejected before any run, naming the file and the option; no output.
#[test]
fn audit_rejects_friction_options_and_bad_values() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/plate-cylinder-coarse.toml");
    for (args, needles) in [
        (vec!["--omega", "0.1"], vec!["--omega", "frictionless"]),
        (
            vec!["--eta", "1e-6", "--zeta", "0.1"],
            vec!["--zeta", "frictionless"],
        ),
        (vec!["--eta=-1e-6"], vec!["--eta", "finite and > 0"]),
        (
            vec!["--penalty", "nan"],
            vec!["--penalty", "finite and > 0"],
        ),
        (
            vec!["--penalty", "1e-3"],
            vec!["--penalty", "below K delta"],
        ),
        (vec![], vec!["nothing to sweep", "--eta"]),
    ] {
        let out = tmp("audit-rejected");
        let _ = std::fs::remove_dir_all(&out);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_anm"))
            .arg("audit")
            .arg(&scene)
            .args(&args)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        println!("{args:?}: exit {:?}: {err}", o.status.code());
        assert_ne!(o.status.code(), Some(0), "{args:?} must fail");
        assert!(!err.contains("panicked"), "panic: {err}");
        assert!(
            err.contains(&scene.display().to_string()),
            "error does not name the file: {err}"
        );
        for n in needles {
            assert!(err.contains(n), "error does not mention `{n}`: {err}");
        }
        assert!(!out.exists(), "no output for rejected input");
    }
}

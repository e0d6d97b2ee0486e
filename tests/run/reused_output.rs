//! A run into the output directory of an earlier run: the earlier run's
//! files that the new one does not write (snapshots past its end, mode
//! shapes, a checkpoint) are removed, so that every file of an anm run in
//! the directory belongs to the last run; other files are kept; a scene
//! that fails to load leaves the earlier run whole.

use crate::common::anm_run as run;
use crate::scratch::scratch;
use std::path::Path;

/// The moving-plane verification scene with a VTK snapshot every step and
/// `lambda_end` as given.
fn scene(lambda_end: f64) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/verification/moving-plane.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.replace("lambda_end = 1.0", &format!("lambda_end = {lambda_end}"));
    let text = text.replace("vtk_every = 0", "vtk_every = 1");
    assert!(text.contains("vtk_every = 1") && text.contains(&format!("lambda_end = {lambda_end}")));
    text
}

/// The shell snapshots in `dir` (shell_NNNN.vtu), sorted.
fn snapshots(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.starts_with("shell_") && n != "shell_final.vtu")
        .collect();
    names.sort();
    names
}

#[test]
fn a_new_run_removes_the_files_of_an_earlier_run() {
    let dir = scratch("reused");
    let long = dir.path().join("long.toml");
    let short = dir.path().join("short.toml");
    std::fs::write(&long, scene(1.0)).unwrap();
    std::fs::write(&short, scene(0.2)).unwrap();
    let out = dir.path().join("out");

    let first = run(&long, &out);
    assert_eq!(first.status.code(), Some(0), "{first:?}");
    let long_snapshots = snapshots(&out);
    // Files an earlier run may leave that this scene does not write, and a
    // file of the user's.
    for name in ["mode_1.vtu", "checkpoint.json", "events.csv"] {
        std::fs::write(out.join(name), "earlier").unwrap();
    }
    std::fs::write(out.join("notes.txt"), "mine").unwrap();

    // A scene that does not load changes nothing.
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, scene(0.2).replace("young = 2e9", "young = -2e9")).unwrap();
    let refused = run(&bad, &out);
    assert_ne!(refused.status.code(), Some(0));
    assert_eq!(snapshots(&out), long_snapshots);
    assert!(out.join("mode_1.vtu").exists());

    let second = run(&short, &out);
    assert_eq!(second.status.code(), Some(0), "{second:?}");
    // A snapshot every step: the last step's and shell_final.vtu are one
    // state, listed once in shell.pvd.
    crate::common::unique_pvd_entries(&out);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(stderr.contains("files of an earlier run"), "{stderr}");
    let short_snapshots = snapshots(&out);
    println!(
        "snapshots: {} after the long run, {} after the short one",
        long_snapshots.len(),
        short_snapshots.len()
    );
    assert!(short_snapshots.len() < long_snapshots.len());
    // Every snapshot on disk is one of the new run's, listed in its index.
    let pvd = std::fs::read_to_string(out.join("shell.pvd")).unwrap();
    for name in &short_snapshots {
        assert!(pvd.contains(name.as_str()), "{name} not in shell.pvd");
    }
    for name in ["mode_1.vtu", "checkpoint.json", "events.csv"] {
        assert!(!out.join(name).exists(), "{name} left from the earlier run");
    }
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stop"]["reason"], "end");
    assert!((summary["stop"]["lambda"].as_f64().unwrap() - 0.2).abs() < 1e-12);
}

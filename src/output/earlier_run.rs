//! The files of an earlier run in a reused output directory.
//!
//! A run writes only the files its scene asks for: a shorter run, a run
//! without events or without moving obstacles would otherwise leave the
//! earlier run's snapshots, mode shapes or checkpoint beside its own, and
//! read as part of it (a stale checkpoint.json would even be resumed). A
//! new run therefore removes, before it writes, every file whose name is
//! one that a run writes; any other file in the directory is left alone. A
//! buckling analysis (`anm buckle -o DIR`) removes only its own earlier
//! files, so that it can share a directory with a run.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Names a run writes, whatever its scene.
const FIXED: &[&str] = &[
    "summary.json",
    "history.csv",
    "steps.csv",
    "events.csv",
    "contact_final.csv",
    "friction.csv",
    "along.csv",
    "checkpoint.json",
    "checkpoint.json.tmp",
    "fields.h5",
    "shell.pvd",
    "shell_final.vtu",
    "friction.vtu",
    "tangent.mtx",
    "plot.svg",
    "history.svg",
    "steps.svg",
    "friction.svg",
    "along.svg",
];

/// Numbered names: prefix, digits, then an optional `_` and a time with
/// digits and one dot (obstacle_K_T.vtu), then the suffix.
const NUMBERED: &[(&str, &str)] = &[("shell_", ".vtu"), ("mode_", ".vtu"), ("obstacle_", ".vtu")];

/// What `anm buckle -o DIR` writes (kept by a run, removed by a buckling
/// analysis: the two may share a directory).
const BUCKLING: &[&str] = &["buckle.json", "buckle.csv"];

/// Whether `name` is the name of a file a run writes.
pub fn is_run_output(name: &str) -> bool {
    FIXED.contains(&name) || NUMBERED.iter().any(|n| is_numbered(name, n))
}

/// Whether `name` is the name of a file a buckling analysis writes.
pub fn is_buckling_output(name: &str) -> bool {
    BUCKLING.contains(&name) || is_numbered(name, &("buckle_mode_", ".vtu"))
}

/// `name` = prefix, a numbered middle, suffix.
fn is_numbered(name: &str, (prefix, suffix): &(&str, &str)) -> bool {
    name.strip_prefix(prefix)
        .and_then(|rest| rest.strip_suffix(suffix))
        .is_some_and(numbered_middle)
}

/// `K` or `K_T`: K digits, T digits with at most one dot.
fn numbered_middle(middle: &str) -> bool {
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    match middle.split_once('_') {
        None => digits(middle),
        Some((k, t)) => {
            digits(k)
                && t.split_once('.')
                    .map_or(digits(t), |(a, b)| digits(a) && digits(b))
        }
    }
}

/// Removes the files of an earlier run from `dir` (nothing if `dir` does
/// not exist); returns the removed paths, sorted.
pub fn clear(dir: &Path) -> Result<Vec<PathBuf>> {
    remove_where(dir, is_run_output)
}

/// Removes the files of an earlier buckling analysis from `dir`.
pub fn clear_buckling(dir: &Path) -> Result<Vec<PathBuf>> {
    remove_where(dir, is_buckling_output)
}

/// Removes the files of `dir` whose names pass `named`.
fn remove_where(dir: &Path, named: fn(&str) -> bool) -> Result<Vec<PathBuf>> {
    let io = |file: &Path| {
        let file = file.to_path_buf();
        move |source| Error::Io { file, source }
    };
    super::folder_or_absent(dir)?;
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(vec![]),
        Err(e) => return Err(io(dir)(e)),
    };
    let mut removed = vec![];
    for entry in entries {
        let entry = entry.map_err(io(dir))?;
        let path = entry.path();
        let is_file = entry.file_type().map_err(io(&path))?.is_file();
        let name = entry.file_name();
        if is_file && name.to_str().is_some_and(named) {
            std::fs::remove_file(&path).map_err(io(&path))?;
            removed.push(path);
        }
    }
    removed.sort();
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_outputs_are_recognized_by_name() {
        for name in [
            "summary.json",
            "shell_0000.vtu",
            "shell_0240.vtu",
            "mode_3.vtu",
            "obstacle_0.vtu",
            "obstacle_1_1.000000.vtu",
            "checkpoint.json",
            // Review 23: a plate's tangent stayed beside an Euler column's run.
            "tangent.mtx",
        ] {
            assert!(is_run_output(name), "{name}");
        }
        for name in [
            "scene.toml",
            "mesh.msh",
            "notes.md",
            "shell_.vtu",
            "shell_a1.vtu",
            "obstacle_1_.vtu",
            "obstacle_1_2.3.4.vtu",
            "my_plot.svg",
            "history.csv.bak",
            "buckle.json",
            "buckle_mode_12.vtu",
            // Another run's lock is not an earlier run's file.
            "anm.lock",
        ] {
            assert!(!is_run_output(name), "{name}");
        }
        for name in ["buckle.json", "buckle.csv", "buckle_mode_12.vtu"] {
            assert!(is_buckling_output(name), "{name}");
        }
        assert!(!is_buckling_output("summary.json"));
    }

    #[test]
    fn clear_removes_only_run_outputs() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["summary.json", "shell_0120.vtu", "mode_1.vtu", "scene.toml"] {
            std::fs::write(dir.path().join(name), "x").unwrap();
        }
        std::fs::create_dir(dir.path().join("shell_0001.vtu")).unwrap();
        let removed = clear(dir.path()).unwrap();
        let names: Vec<_> = removed
            .iter()
            .map(|p| p.file_name().unwrap().to_str().unwrap().to_string())
            .collect();
        assert_eq!(names, ["mode_1.vtu", "shell_0120.vtu", "summary.json"]);
        assert!(dir.path().join("scene.toml").exists());
        assert!(dir.path().join("shell_0001.vtu").is_dir());
        assert!(clear(&dir.path().join("absent")).unwrap().is_empty());
    }
}

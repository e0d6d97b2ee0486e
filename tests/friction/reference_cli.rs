//! `anm reference diffsol` and `anm run` on friction scenes from the command
//! line (issue 16, items 4 and 5): every time run writes the same counter
//! names in summary.json, and bad tolerances or method names end with a
//! clear error naming the option, a non-zero exit and no panic.

use crate::scratch::ScratchFile;
use anm::reference::counters::Counters;
use std::path::Path;
use std::process::{Command, Output};

fn anm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("anm runs")
}

/// An output directory `name` for a run, in a temporary directory of its
/// own (not created: the run creates it).
fn scratch(name: &str) -> ScratchFile {
    ScratchFile::new("refcli", name)
}

fn counters(dir: &Path) -> serde_json::Map<String, serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    v["counters"]
        .as_object()
        .expect("a counters object")
        .clone()
}

/// Item 4: the ANM, diffsol BDF and diffsol ESDIRK write the same counter
/// names, each a non-negative integer, with steps > 0 and equal to the
/// number of rows of steps.csv.
#[test]
fn summaries_share_counter_names() {
    let scene = "scenes/friction-1d.toml";
    let runs = [
        ("anm", vec!["run", scene, "--quiet", "-o"]),
        (
            "bdf",
            vec!["reference", "diffsol", scene, "--method", "bdf", "-o"],
        ),
        (
            "esdirk",
            vec!["reference", "diffsol", scene, "--method", "esdirk", "-o"],
        ),
    ];
    for (name, mut args) in runs {
        let dir = scratch(name);
        let d = dir.display().to_string();
        args.push(&d);
        let o = anm(&args);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let c = counters(&dir);
        let mut keys: Vec<&str> = c.keys().map(String::as_str).collect();
        keys.sort();
        let mut want = Counters::NAMES.to_vec();
        want.sort();
        assert_eq!(keys, want, "{name}");
        assert!(c.values().all(|v| v.as_u64().is_some()), "{name}: {c:?}");
        let steps = c["steps"].as_u64().unwrap();
        let rows = std::fs::read_to_string(dir.join("steps.csv"))
            .expect("steps.csv")
            .lines()
            .count()
            - 1;
        println!("{name}: {c:?}; steps.csv rows {rows}");
        assert!(steps > 0);
        assert_eq!(steps as usize, rows, "{name}: steps vs steps.csv");
    }
}

/// Item 5: bad tolerances and method names.
#[test]
fn bad_reference_options_are_named() {
    let scene = "scenes/friction-1d.toml";
    let dir = scratch("bad");
    let d = dir.display().to_string();
    let cases: &[(&[&str], &str)] = &[
        (&["--rtol", "-1e-8"], "--rtol"),
        (&["--rtol", "0"], "--rtol"),
        (&["--rtol", "nan"], "--rtol"),
        (&["--rtol", "inf"], "--rtol"),
        (&["--atol", "-1"], "--atol"),
        (&["--atol", "0"], "--atol"),
        (&["--atol", "NaN"], "--atol"),
        (&["--atol-algebraic", "-1e-6"], "--atol-algebraic"),
        (&["--atol-algebraic", "inf"], "--atol-algebraic"),
        (&["--method", "rk4"], "--method"),
        (&["--method", "BDF2"], "--method"),
        (&["--friction-row", "steep"], "--friction-row"),
        (&["--fresh-jacobian", "maybe"], "--fresh-jacobian"),
        (
            &["--max-nonlinear-failures", "0"],
            "--max-nonlinear-failures",
        ),
    ];
    for (extra, option) in cases {
        let mut args = vec!["reference", "diffsol", scene, "-o", &d];
        args.extend_from_slice(extra);
        let o = anm(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        println!("{extra:?}: exit {:?}: {}", o.status.code(), err.trim());
        assert!(!o.status.success(), "{extra:?} accepted");
        assert!(!err.contains("panicked"), "{extra:?} panicked: {err}");
        assert!(
            err.contains(option),
            "{extra:?}: message does not name {option}: {err}"
        );
        assert!(
            !dir.join("summary.json").exists(),
            "{extra:?} wrote outputs"
        );
    }
}

//! A shell run in time stopped by numerical trouble keeps what it computed:
//! scenes/verification/capstan-breakaway.toml (coarsened to 16 elements)
//! stops where the strip breaks away, t* = T1 exp(f θ) / T2max, because
//! the quasi-static solution ceases there. `anm run` used to print the
//! diagnosis and write no file; it now writes every output up to the stop,
//! summary.json with `stop: {reason: <the error's kind>, t, node, message}`
//! (node: the node the diagnosis names), and exits with 2 (a failure, as a
//! static run's numerical stop).

use crate::scratch::scratch;
use std::path::Path;
use std::process::Command;

/// `anm run --quiet` on the scene `text` written as `dir/name`: its output
/// folder and the process's output.
fn run_text(dir: &Path, name: &str, text: &str) -> (std::path::PathBuf, std::process::Output) {
    let scene = dir.join(name);
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet"])
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    (out, run)
}

#[test]
fn a_run_in_time_stopped_by_numerical_trouble_writes_its_outputs() {
    let dir = scratch("numerical-stop");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/verification/capstan-breakaway.toml"),
    )
    .unwrap();
    let text = text.replace("divisions = [1, 64]", "divisions = [1, 16]");
    assert!(text.contains("divisions = [1, 16]"));
    let (out, run) = run_text(dir.path(), "breakaway.toml", &text);
    let stdout = String::from_utf8_lossy(&run.stdout);
    println!("{stdout}");
    assert_eq!(run.status.code(), Some(2), "{run:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let stop_t = summary["stop"]["t"].as_f64().unwrap();
    let message = summary["stop"]["message"].as_str().unwrap();
    assert_eq!(summary["stop"]["reason"], "time_steps", "{summary}");
    assert!(message.contains("may cease to exist"), "{message}");
    assert!(stdout.contains(message), "the diagnosis is printed");
    // The node the diagnosis names is summary.json's stop.node (its tag).
    let node = summary["stop"]["node"].as_u64().expect("stop.node") as usize;
    assert!(
        message.contains(&format!("node {node} ")),
        "{node} in {message}"
    );
    // f = 0.2, θ = π, T1 = 20 N, T2max = 150 N; the coarse arc's
    // discretization puts the stop 2.1e-3 from it.
    let closed = 20.0 * (0.2 * std::f64::consts::PI).exp() / 150.0;
    assert!((stop_t / closed - 1.0).abs() < 1e-2, "{stop_t} vs {closed}");
    // The history up to the stop, finite, nothing beyond.
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let rows: Vec<Vec<f64>> = history
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 10, "{} rows", rows.len());
    assert!(rows.iter().flatten().all(|x| x.is_finite()));
    let last_t = rows.last().unwrap()[0];
    assert!(
        last_t <= stop_t && stop_t - last_t < 0.011,
        "last row {last_t}, stop {stop_t}"
    );
    for file in ["friction.csv", "friction.vtu", "along.csv"] {
        assert!(out.join(file).exists(), "{file}");
    }
}

/// A static path that turns back and goes below its start says so (review
/// 10: a strip starting 0.1 m clear of its rollers reached λ = 2.85e-3,
/// then went down to λ = −54 until max_steps, with no word): the note's
/// two lambdas are steps.csv's furthest step end and summary.json's stop.
#[test]
fn a_path_that_turns_back_below_its_start_says_so() {
    let scene =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/strip-clear-of-rollers.toml");
    let dir = scratch("turned-back");
    let out = dir.path().join("out");
    let run = crate::common::anm_run(&scene, &out);
    assert_eq!(run.status.code(), Some(2), "{run:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stop"]["reason"], "max_steps", "{summary}");
    let stop = summary["stop"]["lambda"].as_f64().unwrap();
    let note = summary["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n.as_str())
        .find(|n| n.contains("turned back"))
        .unwrap_or_else(|| panic!("no note: {}", summary["notes"]));
    println!("{note}");
    let mut steps = csv::Reader::from_path(out.join("steps.csv")).unwrap();
    let head: Vec<String> = steps.headers().unwrap().iter().map(String::from).collect();
    let k = head.iter().position(|h| h == "lambda_end").unwrap();
    let reach = steps
        .records()
        .map(|r| r.unwrap()[k].parse::<f64>().unwrap())
        .fold(f64::MIN, f64::max);
    assert!(reach > 0.0 && stop < 0.0, "reach {reach}, stop {stop}");
    assert!(
        note.contains(&format!("reached lambda = {reach}")),
        "{note}"
    );
    assert!(note.contains(&format!("to lambda = {stop}")), "{note}");
}

/// A static run below its residual's round-off floor (reviews 14, 15 and
/// 16). The clamped arch at solver.residual_tol = 1e-9 stalls at
/// 4.3e-9 on its grid point lambda = 0.45: it used to exit 1 there with no
/// summary.json and a checkpoint that resumed into the same stop. A stall
/// no higher than the floor the run has already accepted is now accepted,
/// and the run ends with a note giving that floor; its answer is the
/// scene's own (residual_tol 1e-6). Without corrections (max_corrections =
/// 0) the first step cannot reach 1e-9: a numerical stop with summary.json,
/// exit 2, the message naming solver.residual_tol, no checkpoint left.
#[test]
fn a_run_below_its_round_off_floor_ends_with_a_note_or_stops_with_a_diagnosis() {
    let dir = scratch("round-off-floor");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/verification");
    let base = std::fs::read_to_string(src.join("clamped-arch-snap.toml")).unwrap();
    let summary = |out: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
    };
    let (out, run) = run_text(dir.path(), "arch.toml", &base);
    assert_eq!(run.status.code(), Some(0), "{run:?}");
    let w_default = summary(&out)["end"]["w_crown"].as_f64().unwrap();
    let text = base.replace("[solver]\n", "[solver]\nresidual_tol = 1e-9\n");
    assert!(text.contains("residual_tol = 1e-9"));
    let (out, run) = run_text(dir.path(), "tight.toml", &text);
    assert_eq!(run.status.code(), Some(0), "{run:?}");
    let s = summary(&out);
    let w = s["end"]["w_crown"].as_f64().unwrap();
    let notes = s["notes"].to_string();
    println!("w_crown(1): {w:e} (residual_tol 1e-6: {w_default:e}); {notes}");
    assert!(notes.contains("round-off floor"), "{notes}");
    assert!(
        (w - w_default).abs() <= 1e-6 * w_default.abs(),
        "{w} vs {w_default}"
    );
    let text = text.replace("[solver]\n", "[solver]\nmax_corrections = 0\n");
    let (out, run) = run_text(dir.path(), "no-corrections.toml", &text);
    println!("{}", String::from_utf8_lossy(&run.stdout));
    assert_eq!(run.status.code(), Some(2), "{run:?}");
    let s = summary(&out);
    assert_eq!(s["stop"]["reason"], "no_convergence", "{s}");
    let message = s["stop"]["message"].as_str().unwrap();
    assert!(message.contains("solver.residual_tol"), "{message}");
    assert!(!out.join("checkpoint.json").exists());
}

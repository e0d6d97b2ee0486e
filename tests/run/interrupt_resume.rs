//! Runs lose nothing when stopped: `anm run` streams history.csv and
//! steps.csv, SIGTERM (as Ctrl-C) ends the run at the next step end with
//! summary.json saying `interrupted` and every file consistent with it, and
//! `anm run --resume DIR` ends with the same results as an uninterrupted run
//! (1e-12 relative to each column's largest value).

use crate::scratch::ScratchFile;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// An output directory `name` in a temporary directory of its own (not
/// created: the run creates it).
fn tmp(name: &str) -> ScratchFile {
    ScratchFile::new("interrupt", name)
}

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/plate-cylinder.toml")
}

fn rows(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn sigterm_stops_at_a_step_end_and_resume_matches_an_uninterrupted_run() {
    let full = tmp("full");
    let st = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet"])
        .arg(scene())
        .arg("-o")
        .arg(&full)
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(0));

    let cut = tmp("cut");
    let mut child = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet"])
        .arg(scene())
        .arg("-o")
        .arg(&cut)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait until 40 steps are on disk, then send SIGTERM.
    let start = Instant::now();
    loop {
        let n = std::fs::read_to_string(cut.join("steps.csv"))
            .map(|t| t.lines().count())
            .unwrap_or(0);
        if n > 40 {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "run too slow");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it could be interrupted"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    // Review 23: a second run into the same folder removed the first's
    // files and wrote its own beside them; it is refused while the first
    // runs, and the first goes on.
    let second = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/verification/euler-column.toml"))
        .arg("-o")
        .arg(&cut)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&second.stderr);
    println!("{err}");
    assert_eq!(second.status.code(), Some(1), "{err}");
    assert!(err.contains("another run"), "{err}");
    assert!(child.try_wait().unwrap().is_none(), "the first run goes on");
    Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    let code = child.wait().unwrap().code();
    assert_eq!(code, Some(130), "exit code of an interrupted run");
    assert!(!cut.join("anm.lock").exists(), "the lock goes with the run");
    let s = summary(&cut);
    println!("interrupted: {}", s["stop"]);
    assert_eq!(s["stop"]["reason"], "interrupted");
    // scene.description names the run (review 23: it was in no output).
    assert_eq!(
        s["description"],
        "strip 2 m x 0.2 m x 0.8 mm, cylinder D = 1 m at (1, 0, 0.5001), axis y"
    );
    let lambda = s["stop"]["lambda"].as_f64().unwrap();
    let steps = rows(&cut.join("steps.csv"));
    let history = rows(&cut.join("history.csv"));
    assert!(lambda > 0.0 && lambda < 1.0, "stopped at lambda = {lambda}");
    // Files consistent with the stop: the last step ends at its lambda, the
    // history holds every grid value up to it and none beyond.
    assert_eq!(steps.last().unwrap()[2], lambda);
    assert_eq!(s["steps"].as_u64().unwrap() as usize, steps.len());
    let last = history.last().unwrap()[0];
    assert!(
        last <= lambda + 1e-12 && lambda - last < 0.01 + 1e-12,
        "last row {last}, stop {lambda}"
    );
    assert!(
        !cut.join("shell_final.vtu").exists() && !cut.join("contact_final.csv").exists(),
        "no final-state file for an interrupted run"
    );
    // The snapshots written so far are indexed for ParaView (review 7).
    assert!(crate::common::unique_pvd_entries(&cut) >= 1);

    // Review 23: a history.csv whose last row was cut mid-line passed the
    // row count, and the resumed run panicked at its end. A copy of the
    // folder with that row cut is refused before anything is solved.
    let damaged = tmp("damaged");
    std::fs::create_dir_all(&damaged).unwrap();
    for entry in std::fs::read_dir(&cut).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, damaged.join(path.file_name().unwrap())).unwrap();
    }
    let text = std::fs::read_to_string(damaged.join("history.csv")).unwrap();
    std::fs::write(damaged.join("history.csv"), &text[..text.len() - 20]).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet", "--resume"])
        .arg(&damaged)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("not a whole row") && !err.contains("panicked"),
        "{err}"
    );

    let st = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet", "--resume"])
        .arg(&cut)
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(0));
    assert_eq!(summary(&cut)["stop"]["reason"], "end");
    crate::common::unique_pvd_entries(&cut);
    let (a, b) = (
        rows(&full.join("history.csv")),
        rows(&cut.join("history.csv")),
    );
    assert_eq!(a.len(), b.len());
    let mut worst = 0.0f64;
    for k in 0..a[0].len() {
        let scale = a.iter().map(|r| r[k].abs()).fold(0.0, f64::max).max(1e-300);
        for (ra, rb) in a.iter().zip(&b) {
            worst = worst.max((ra[k] - rb[k]).abs() / scale);
        }
    }
    println!("resumed vs uninterrupted: max relative difference {worst:.2e}");
    assert!(worst <= 1e-12, "{worst:e}");
    assert_eq!(
        rows(&full.join("steps.csv")).len(),
        rows(&cut.join("steps.csv")).len()
    );
}

#[test]
fn resume_refuses_a_changed_scene_and_a_missing_checkpoint() {
    let dir = tmp("none");
    std::fs::create_dir_all(&dir).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet", "--resume"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("checkpoint.json") && !err.contains("panicked"));
}

/// A shell run in time (`[friction]`) also stops at a step end on SIGTERM,
/// with its outputs up to there and exit code 130 (it was killed with no
/// output at all). It cannot be resumed yet.
#[test]
fn sigterm_stops_a_shell_run_in_time_with_its_outputs() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/strip-conveying.toml");
    let out = tmp("in-time");
    let mut child = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet"])
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // The whole run takes about a minute; its first steps start within a
    // second (set-up, the state at rest).
    std::thread::sleep(Duration::from_secs(3));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the run ended before it could be interrupted"
    );
    Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    let start = Instant::now();
    let code = child.wait().unwrap().code();
    println!(
        "stopped {:.2} s after SIGTERM",
        start.elapsed().as_secs_f64()
    );
    assert_eq!(code, Some(130), "exit code of an interrupted run");
    let s = summary(&out);
    assert_eq!(s["stop"]["reason"], "interrupted");
    assert!(
        s["description"]
            .as_str()
            .is_some_and(|d| d.starts_with("steel strip over three rollers")),
        "{}",
        s["description"]
    );
    let t = s["stop"]["t"].as_f64().unwrap();
    assert!(t > 0.0 && t < 1.5, "stop.t = {t}");
    let history = rows(&out.join("history.csv"));
    assert!(!history.is_empty());
    assert!(
        history
            .iter()
            .all(|r| r[0] <= t && r.iter().all(|x| x.is_finite()))
    );
}

/// scenes/strip-conveying.toml coarsened (2 elements across, 0.1 m along,
/// 0.02 m on the arcs): about 5–9 s here.
fn coarse_conveying() -> crate::scratch::ScratchFile {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/strip-conveying.toml"),
    )
    .unwrap();
    let coarse = text
        .replace("divisions_across = 8", "divisions_across = 2")
        .replace("element_length = 0.05", "element_length = 0.1")
        .replace("arc_element_length = 0.01", "arc_element_length = 0.02");
    assert!(coarse.contains("divisions_across = 2") && coarse.contains("= 0.02"));
    crate::scratch::ScratchFile::with_text("in-time-resume", "conveying.toml", &coarse)
}

fn table(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let head = text
        .lines()
        .next()
        .unwrap()
        .split(',')
        .map(String::from)
        .collect();
    (head, rows(path))
}

#[test]
fn sigterm_then_resume_a_shell_run_in_time_matches_an_uninterrupted_run() {
    let scene = coarse_conveying();
    let run = |out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_anm"))
            .args(["run", "--quiet"])
            .arg(&*scene)
            .arg("-o")
            .arg(out)
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap()
    };
    let full = tmp("in-time-full");
    let start = Instant::now();
    assert_eq!(run(&full).wait().unwrap().code(), Some(0));
    let wall = start.elapsed();
    // Interrupted halfway (a later try waits longer if the stop came
    // before the third output time, 0.04 s).
    let cut = tmp("in-time-cut");
    let mut wait = wall / 2;
    let stop_t = loop {
        let mut child = run(&cut);
        std::thread::sleep(wait);
        Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .unwrap();
        let code = child.wait().unwrap().code();
        let s = summary(&cut);
        if code == Some(0) {
            // Ended before the signal: try earlier.
            wait /= 2;
            continue;
        }
        assert_eq!(code, Some(130));
        assert_eq!(s["stop"]["reason"], "interrupted");
        let t = s["stop"]["t"].as_f64().unwrap();
        if t >= 0.04 || wait > 4 * wall {
            break t;
        }
        wait += wall / 4;
    };
    assert!(cut.join("checkpoint.json").exists());
    let resumed = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet", "--resume"])
        .arg(&cut)
        .output()
        .unwrap();
    assert_eq!(resumed.status.code(), Some(0), "{resumed:?}");
    assert_eq!(summary(&cut)["stop"]["reason"], "end");
    assert!(
        !cut.join("checkpoint.json").exists(),
        "the ended run keeps no checkpoint"
    );
    // Again: the run has ended.
    let again = Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet", "--resume"])
        .arg(&cut)
        .output()
        .unwrap();
    assert_ne!(again.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&again.stderr).contains("already ended"));

    // The same history as the uninterrupted run, to the accuracy of the
    // integration: the resumed run restarts its step sequence at the last
    // output time before the stop. Forces compared at the scale of the
    // friction force (ft_x is round-off, 1e-8 N against 1.5e3 N).
    let (head, a) = table(&full.join("history.csv"));
    let (head_b, b) = table(&cut.join("history.csv"));
    assert_eq!(head, head_b);
    assert_eq!(a.len(), b.len());
    let col_max = |j: usize| a.iter().map(|r| r[j].abs()).fold(0.0, f64::max);
    let ft_scale = ["ft_x", "ft_y", "ft_z"]
        .iter()
        .map(|n| col_max(head.iter().position(|h| h == n).unwrap()))
        .fold(0.0, f64::max);
    let mut worst = (0.0f64, String::new());
    for (j, name) in head.iter().enumerate() {
        let scale = if name.starts_with("ft_") {
            ft_scale
        } else {
            col_max(j)
        };
        let d = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x[j] - y[j]).abs())
            .fold(0.0, f64::max);
        let rel = if scale > 0.0 { d / scale } else { d };
        if rel > worst.0 {
            worst = (rel, name.clone());
        }
    }
    println!(
        "interrupted at t = {stop_t:.4} s; resumed run vs uninterrupted: largest difference {:.2e} of the column's largest value ({})",
        worst.0, worst.1
    );
    assert!(worst.0 <= 1e-4, "{worst:?}");
}

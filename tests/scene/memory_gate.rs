//! A mesh too large for the machine's memory is refused before anything is
//! built (src/run/memory.rs), naming the scene, its size and the figures:
//! a reviewer's 1e6-element capstan (under the element cap) aborted after
//! 49 s on a failed allocation under `ulimit -v 6000000`, with no message.

use super::edited::edited;
use anm::run::memory::{check, estimate};
use anm::scene::shell::load;
use std::process::Command;

const PLATE: &str = "scenes/verification/plate-buckling.toml";

#[test]
fn the_estimate_follows_the_measured_figures() {
    let sc = load(std::path::Path::new(PLATE)).expect("scene");
    let e = estimate(&sc);
    assert_eq!(e.unknowns, 6 * 17 * 17);
    // Below every measured peak per unknown (7.0–7.3 kB in lambda).
    assert!(e.low < 7.0e3 * e.unknowns as f64 && e.typical >= 7.0e3 * e.unknowns as f64);
    // Refused below the lower bound, warned between, silent above.
    let refused = check(&sc, Some((0.5 * e.low, "test"))).expect_err("refused");
    let msg = refused.to_string();
    println!("{msg}");
    for part in [
        "plate-buckling.toml",
        "`mesh`",
        "1734 unknowns",
        "--ignore-memory",
    ] {
        assert!(msg.contains(part), "`{msg}` lacks `{part}`");
    }
    let warned = check(&sc, Some((0.5 * (e.low + e.typical), "test"))).expect("runs");
    assert!(warned.is_some_and(|w| w.contains("typically")));
    assert_eq!(
        check(&sc, Some((2.0 * e.typical, "test"))).expect("runs"),
        None
    );
    assert_eq!(check(&sc, None).expect("unknown memory"), None);
}

/// Under `ulimit -v` 4 GB, a 500 × 500 plate (1,506,006 unknowns, at least
/// 6.0 GB by the lower bound) stops at once with exit 1; `anm check` did
/// not finish such meshes in 30 s.
#[test]
fn a_mesh_beyond_the_address_space_limit_is_refused_before_the_build() {
    let p = edited(
        PLATE,
        "memory-gate",
        "plate-500.toml",
        &[("divisions = [16, 16]", "divisions = [500, 500]")],
    );
    for cmd in ["check", "run"] {
        let out = p.with_extension("out");
        let script = format!(
            "ulimit -v 4000000 && exec {} {cmd} {} {}",
            env!("CARGO_BIN_EXE_anm"),
            p.display(),
            if cmd == "run" {
                format!("-o {} --quiet", out.display())
            } else {
                String::new()
            }
        );
        let o = Command::new("sh").args(["-c", &script]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        println!("{cmd}: {:?}, {err}", o.status);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("plate-500.toml") && err.contains("ulimit -v"),
            "{err}"
        );
        assert!(!out.exists(), "no output for a refused scene");
    }
}

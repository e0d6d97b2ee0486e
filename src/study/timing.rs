//! Robust timing of friction solves: many interleaved repetitions summarized
//! by their minimum and median, and instruction counts under callgrind.
//!
//! Runs last a few milliseconds, so on a shared machine one median of three
//! can be off by 2x. The minimum of many repetitions approaches the unloaded
//! cost; interleaving the methods round by round exposes them to the same
//! load. Instruction counts (valgrind's callgrind, `Ir`) do not depend on the
//! load at all, though they weigh a cache miss like an add.

use super::bench::{Method, Solution, solve};
use crate::error::Result;
use crate::scene::friction::FrictionScene;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// One solve, the region callgrind counts (`--toggle-collect`); not inlined
/// so that the symbol exists.
#[inline(never)]
pub fn measured_solve(scene: &FrictionScene, method: &Method) -> Result<Solution> {
    solve(scene, method)
}

/// The symbol pattern of [`measured_solve`] for `--toggle-collect`.
pub const TOGGLE: &str = "*timing::measured_solve*";

/// Wall seconds of repeated runs.
#[derive(Clone, Debug, Default)]
pub struct Spread {
    pub samples: Vec<f64>,
}

impl Spread {
    fn sorted(&self) -> Vec<f64> {
        let mut v = self.samples.clone();
        v.sort_by(f64::total_cmp);
        v
    }
    /// The q-quantile (nearest rank), q in [0, 1]; NaN without samples.
    pub fn quantile(&self, q: f64) -> f64 {
        let v = self.sorted();
        if v.is_empty() {
            return f64::NAN;
        }
        v[((v.len() - 1) as f64 * q).round() as usize]
    }
    pub fn min(&self) -> f64 {
        self.quantile(0.0)
    }
    pub fn median(&self) -> f64 {
        self.quantile(0.5)
    }
}

/// A method's repeated runs: their wall times and the last solution.
pub struct Timed {
    pub spread: Spread,
    pub solution: Solution,
}

/// Wall time of each method's full solve (setup, integration and output
/// rows), `repeat` rounds after one warm-up round, every round running each
/// method once in turn. `repeat` = 0: the warm-up round only, timed.
pub fn interleaved(scene: &FrictionScene, methods: &[Method], repeat: usize) -> Result<Vec<Timed>> {
    let mut spreads = vec![Spread::default(); methods.len()];
    let mut last = Vec::with_capacity(methods.len());
    for round in 0..=repeat {
        last.clear();
        for (m, spread) in methods.iter().zip(spreads.iter_mut()) {
            let start = Instant::now();
            let sol = measured_solve(scene, m)?;
            let elapsed = start.elapsed().as_secs_f64();
            if round > 0 || repeat == 0 {
                spread.samples.push(elapsed);
            }
            last.push(sol);
        }
    }
    Ok(spreads
        .into_iter()
        .zip(last)
        .map(|(spread, solution)| Timed { spread, solution })
        .collect())
}

/// Instructions executed by one solve of `method` on the scene file, counted
/// by callgrind in a child `anm time` process (`anm_exe`: the `anm` binary);
/// None when valgrind is missing or the count cannot be read. The command,
/// for reproduction:
///   valgrind --tool=callgrind --callgrind-out-file=/dev/null \
///     --collect-atstart=no --toggle-collect='*timing::measured_solve*' \
///     anm time SCENE --method METHOD --repeat 0
pub fn instructions(anm_exe: &Path, scene_file: &Path, method: &Method) -> Option<u64> {
    let out = Command::new("valgrind")
        .args([
            "--tool=callgrind",
            "--callgrind-out-file=/dev/null",
            "--collect-atstart=no",
            &format!("--toggle-collect={TOGGLE}"),
        ])
        .arg(anm_exe)
        .arg("time")
        .arg(scene_file)
        .args(["--method", &method.spec(), "--repeat", "0"])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    // callgrind ends with "==pid== Collected : N" on stderr.
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .find_map(|l| l.split("Collected :").nth(1))
        .and_then(|n| n.trim().parse().ok())
}

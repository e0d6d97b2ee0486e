//! `anm factor`: one sparse matrix (MatrixMarket), one backend, measured as
//! the peers in reference/peers/ measure theirs: symbolic analysis apart, the
//! numeric factorization best of `repeat`, one solve, the factor's entries,
//! the backward error of the solve and the peak memory of the process. Run
//! one backend per process so that the peak memory is that backend's.

use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::linalg::{Choice, LinearSolver, matrix_market};

/// The measurements of one backend on one matrix.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FactorReport {
    pub matrix: String,
    pub n: usize,
    /// Stored entries of the assembled matrix (both triangles).
    pub entries: usize,
    pub backend: String,
    pub threads: usize,
    pub analysis_s: f64,
    /// Numeric factorization, best of `repeat`.
    pub factorization_s: f64,
    pub solve_s: f64,
    /// Entries of L (symmetric backends; None for LU, whose faer factor
    /// does not report its size).
    pub factor_entries: Option<usize>,
    pub backward_error: f64,
    pub negative_pivots: Option<usize>,
    pub peak_rss_bytes: Option<u64>,
}

/// Factors `path` `repeat` times with `choice` on `threads` threads.
pub fn run(path: &Path, choice: Choice, threads: usize, repeat: usize) -> Result<FactorReport> {
    let fail = |problem: String| Error::study("factor", path.display().to_string(), problem);
    let a = matrix_market::read(path).map_err(fail)?;
    let mut solver = LinearSolver::new(choice).with_threads(threads);
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let f = solver.factorize(&a).map_err(fail)?;
        best = best.min(f.numeric_seconds());
        last = Some(f);
    }
    let f = last.expect("at least one factorization");
    let b: Vec<f64> = (0..a.n).map(|i| 1.0 + (i % 10) as f64).collect();
    let t = Instant::now();
    let x = f.solve(&b);
    let solve_s = t.elapsed().as_secs_f64();
    if !x.iter().all(|v| v.is_finite()) {
        return Err(fail("the solve is not finite".into()));
    }
    let stats = solver.stats();
    Ok(FactorReport {
        matrix: path.display().to_string(),
        n: a.n,
        entries: stats.matrix_entries,
        backend: f.backend().name().to_string(),
        threads,
        analysis_s: stats.analysis_s,
        factorization_s: best,
        solve_s,
        factor_entries: Some(stats.factor_entries).filter(|&e| e > 0),
        backward_error: f.backward_error(),
        negative_pivots: f.inertia().map(|i| i.0),
        peak_rss_bytes: crate::output::peak_rss_bytes(),
    })
}

/// Runs `exe factor MATRIX --backend B --threads T` for each (B, T), each in
/// its own process (its own peak memory).
pub fn compare(exe: &Path, matrix: &Path, configs: &[(&str, usize)]) -> Result<Vec<FactorReport>> {
    let mut out = vec![];
    for &(backend, threads) in configs {
        let run = std::process::Command::new(exe)
            .arg("factor")
            .arg(matrix)
            .args(["--backend", backend, "--threads", &threads.to_string()])
            .output()
            .map_err(|source| Error::Io {
                file: exe.to_path_buf(),
                source,
            })?;
        let text = String::from_utf8_lossy(&run.stdout);
        // The child's own FactorReport, read back as written.
        let report: FactorReport = serde_json::from_str(text.trim()).map_err(|e| {
            Error::study(
                "factor",
                matrix.display().to_string(),
                format!(
                    "{backend} on {threads} threads: {e}; it printed: {}",
                    String::from_utf8_lossy(&run.stderr)
                ),
            )
        })?;
        out.push(report);
    }
    Ok(out)
}

/// The factorization table of one matrix.
pub fn markdown(rows: &[FactorReport]) -> String {
    let mut s = String::from(
        "| solver | threads | analysis (s) | factorization (s) | solve (s) | factor entries | backward error | peak memory of the process (MiB) |\n|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let entries = match r.factor_entries {
            Some(e) => format!("{:.3e}", e as f64),
            None => "–".into(),
        };
        s += &format!(
            "| {} | {} | {:.3} | {:.3} | {:.4} | {entries} | {:.1e} | {:.0} |\n",
            r.backend,
            r.threads,
            r.analysis_s,
            r.factorization_s,
            r.solve_s,
            r.backward_error,
            r.peak_rss_bytes.unwrap_or(0) as f64 / 1048576.0
        );
    }
    s
}

/// The peers of reference/peers/ (MKL Pardiso, MUMPS) on the same matrix,
/// when their venv is installed (`bash reference/peers/setup.sh`): one row
/// per successful (solver, kind, threads) run of factor_peers.py; `None`
/// when the venv is absent.
pub fn peers(matrix: &Path, threads: &str) -> Result<Option<Vec<FactorReport>>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("reference/peers");
    let python = root.join(".venv/bin/python");
    if !python.exists() {
        return Ok(None);
    }
    let json = matrix.with_extension("peers.json");
    let run = std::process::Command::new(&python)
        .arg(root.join("factor_peers.py"))
        .arg(matrix)
        .args(["--threads", threads, "--json"])
        .arg(&json)
        .output()
        .map_err(|source| Error::Io {
            file: python.clone(),
            source,
        })?;
    let text = std::fs::read_to_string(&json).map_err(|e| {
        Error::study(
            "factor",
            matrix.display().to_string(),
            format!(
                "factor_peers.py wrote no {} ({e}): {}",
                json.display(),
                String::from_utf8_lossy(&run.stderr)
            ),
        )
    })?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: json.clone(),
        message: e.to_string(),
    })?;
    let n = v["matrix"]["n"].as_u64().unwrap_or(0) as usize;
    let entries = v["matrix"]["stored_entries"].as_u64().unwrap_or(0) as usize;
    let rows = v["runs"]
        .as_array()
        .map(|runs| {
            runs.iter()
                .filter(|r| r["ok"].as_bool() == Some(true))
                .map(|r| {
                    let num = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
                    FactorReport {
                        matrix: matrix.display().to_string(),
                        n,
                        entries,
                        backend: format!(
                            "{} {} ({})",
                            r["solver"].as_str().unwrap_or("?"),
                            r["kind"].as_str().unwrap_or("?"),
                            r["ordering"].as_str().unwrap_or("?")
                        ),
                        threads: r["threads"].as_u64().unwrap_or(0) as usize,
                        analysis_s: num("analysis_s"),
                        factorization_s: num("factorization_s"),
                        solve_s: num("solve_s"),
                        factor_entries: r["factor_entries"].as_u64().map(|e| e as usize),
                        backward_error: num("backward_error"),
                        negative_pivots: r["negative_pivots"].as_u64().map(|k| k as usize),
                        peak_rss_bytes: r["peak_rss_MiB"].as_f64().map(|m| (m * 1048576.0) as u64),
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    Ok(Some(rows))
}

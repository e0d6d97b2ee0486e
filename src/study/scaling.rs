//! Scaling of the shell ANM with the number of unknowns: the plate-cylinder
//! scene on structured strip meshes nx × ny (6 nx (ny + 1) unknowns), each
//! run in its own process (`anm run`) so that its peak memory (VmHWM) is its
//! own, for a fixed number of steps from lambda = 0.
//!
//! Reported per size: time per step, total time, the per-step breakdown
//! (assembly, factorization, solves, series terms) and peak memory; the
//! exponents b of t = c n^b are fitted by least squares in log-log.

use super::factor::FactorReport;
use super::sweep::{self, Merged, Sweep};
use crate::error::{Error, Result};
use crate::mesh::{gmsh_write, structured};
use crate::output::create_dir;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One measured size.
#[derive(Clone, Debug)]
pub struct ScalingRow {
    pub nx: usize,
    pub ny: usize,
    pub dofs: usize,
    pub steps: usize,
    pub factorizations: usize,
    pub solves: usize,
    /// Truncation order N of the scene.
    pub order: usize,
    pub wall_s: f64,
    /// Wall time of the continuation loop (RunReport::path_s): the steps
    /// without the model set-up before them and the outputs after them.
    pub path_s: f64,
    /// Wall time in the engine's steps alone (Stats::step_s).
    pub engine_s: f64,
    /// Per accepted step: assembly, factorization, solves, series terms (s).
    pub per_step: [f64; 4],
    pub peak_rss_bytes: f64,
    pub stop: String,
}

impl ScalingRow {
    /// Wall time per step: the continuation loop over its steps (a run of
    /// 3 steps would otherwise carry the set-up of a whole model per step).
    pub fn step_s(&self) -> f64 {
        self.path_s / self.steps.max(1) as f64
    }

    /// Wall time per step in the engine alone: the step without the run's
    /// event checks, grid points and per-step outputs.
    pub fn engine_step_s(&self) -> f64 {
        self.engine_s / self.steps.max(1) as f64
    }

    /// Set-up before the first step and outputs after the last (s).
    pub fn setup_s(&self) -> f64 {
        self.wall_s - self.path_s
    }
}

fn io(file: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        file: file.to_path_buf(),
        source,
    }
}

/// The scene `template` (a plate-cylinder TOML) on the nx × ny strip mesh,
/// stopped after `steps` steps, without VTK or plots; written into `dir`.
/// Returns the scene file and its truncation order.
fn write_case(
    template: &Path,
    nx: usize,
    ny: usize,
    steps: usize,
    dir: &Path,
    write_matrix: bool,
) -> Result<(PathBuf, usize)> {
    let mesh = structured::rectangle(0.0, 2.0, -0.1, 0.1, nx, ny);
    let msh = dir.join(format!("strip-{nx}x{ny}.msh"));
    gmsh_write::write(&msh, &mesh, "strip", &[("clamp", &mesh.groups["s0"])])?;
    let text = std::fs::read_to_string(template).map_err(io(template))?;
    let mut scene: toml::Table = toml::from_str(&text).map_err(|e| Error::Invalid {
        file: template.to_path_buf(),
        key: "scene".into(),
        problem: e.to_string(),
    })?;
    let mut set = |table: &str, key: &str, value: toml::Value| {
        if let Some(t) = scene.get_mut(table).and_then(|t| t.as_table_mut()) {
            t.insert(key.into(), value);
        }
    };
    // The mesh sits beside the scene (paths in a scene are relative to it);
    // the template's [[fix]] group "clamp" and [contact] group "strip" name
    // the physical groups written above.
    set(
        "mesh",
        "file",
        toml::Value::String(format!("strip-{nx}x{ny}.msh")),
    );
    set("solver", "max_steps", toml::Value::Integer(steps as i64));
    set("output", "vtk_every", toml::Value::Integer(0));
    set("output", "plot", toml::Value::Boolean(false));
    set(
        "output",
        "tangent_matrix",
        toml::Value::Boolean(write_matrix),
    );
    let order = scene
        .get("solver")
        .and_then(|s| s.get("order"))
        .and_then(|o| o.as_integer())
        .unwrap_or(0) as usize;
    let path = dir.join(format!("scene-{nx}x{ny}.toml"));
    let out = toml::to_string(&scene).map_err(|e| Error::write(&path, e))?;
    std::fs::write(&path, out).map_err(io(&path))?;
    Ok((path, order))
}

/// The result of one size, the item of `anm bench --scaling ... --item K`:
/// the child run's summary.json verbatim, and what its row needs besides.
/// Everything measured per size belongs here (or in the summary), so that
/// the merged table is the table of the single-process run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SizeRun {
    pub nx: usize,
    pub ny: usize,
    /// Truncation order N of the scene.
    pub order: usize,
    /// The text of the child run's summary.json.
    pub summary: String,
    /// With --write-matrix: the initial tangent factored by each backend
    /// (`anm factor`, one process each).
    #[serde(default)]
    pub factor: Vec<FactorReport>,
}

/// Runs the nx × ny size in a child `exe run` process (scene, mesh and run
/// folder in `dir`) and reads its summary.json.
pub fn run_size(
    exe: &Path,
    template: &Path,
    (nx, ny): (usize, usize),
    steps: usize,
    dir: &Path,
    write_matrix: bool,
) -> Result<SizeRun> {
    create_dir(dir)?;
    let (scene, order) = write_case(template, nx, ny, steps, dir, write_matrix)?;
    let out = dir.join(format!("run-{nx}x{ny}"));
    let status = Command::new(exe)
        .arg("run")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .arg("--quiet")
        .output()
        .map_err(io(exe))?;
    let summary = out.join("summary.json");
    let text = std::fs::read_to_string(&summary).map_err(|e| {
        Error::study(
            "scaling",
            scene.display().to_string(),
            format!(
                "no summary ({e}); the run printed: {}",
                String::from_utf8_lossy(&status.stderr)
            ),
        )
    })?;
    let factor = if write_matrix {
        let mtx = out.join("tangent.mtx");
        eprintln!("{nx}x{ny}: factoring {} ...", mtx.display());
        let mut rows = super::factor::compare(exe, &mtx, FACTOR_CONFIGS)?;
        match super::factor::peers(&mtx, "1,2")? {
            Some(peers) => rows.extend(peers),
            None => eprintln!(
                "{nx}x{ny}: no peers (MKL Pardiso, MUMPS): bash reference/peers/setup.sh installs them"
            ),
        }
        rows
    } else {
        vec![]
    };
    Ok(SizeRun {
        nx,
        ny,
        order,
        summary: text,
        factor,
    })
}

/// The table row of one size, from its child run's summary.
pub fn row(size: &SizeRun) -> Result<ScalingRow> {
    let v: serde_json::Value = serde_json::from_str(&size.summary).map_err(|e| Error::Parse {
        file: PathBuf::from(format!("run-{}x{}/summary.json", size.nx, size.ny)),
        message: e.to_string(),
    })?;
    let num = |k: &str| v["stats"][k].as_f64().unwrap_or(f64::NAN);
    let steps_done = v["steps"].as_u64().unwrap_or(0) as usize;
    let per = |k: &str| num(k) / steps_done.max(1) as f64;
    Ok(ScalingRow {
        nx: size.nx,
        ny: size.ny,
        dofs: v["dofs"].as_u64().unwrap_or(0) as usize,
        steps: steps_done,
        factorizations: v["factorizations"].as_u64().unwrap_or(0) as usize,
        solves: v["solves"].as_u64().unwrap_or(0) as usize,
        order: size.order,
        wall_s: v["wall_s"].as_f64().unwrap_or(f64::NAN),
        path_s: v["path_s"].as_f64().unwrap_or(f64::NAN),
        engine_s: num("step_s"),
        per_step: [
            per("assembly_s"),
            per("factorization_s"),
            per("solve_s"),
            per("series_s"),
        ],
        peak_rss_bytes: v["peak_rss_bytes"].as_f64().unwrap_or(f64::NAN),
        stop: v["stop"]["reason"].as_str().unwrap_or("?").to_string(),
    })
}

/// The scaling study as a sweep (`anm bench --scaling`): one item per size,
/// run one after the other in one process (each measures time and peak
/// memory); the merge writes scaling.md.
pub struct ScalingSweep {
    pub exe: PathBuf,
    pub template: PathBuf,
    pub sizes: Vec<(usize, usize)>,
    pub steps: usize,
    pub write_matrix: bool,
}

/// Backends and threads by which `--write-matrix` factors each tangent.
const FACTOR_CONFIGS: &[(&str, usize)] = &[("ldlt", 1), ("ldlt", 2), ("lblt", 1), ("lu", 1)];

/// The factorization tables of the sizes factored with --write-matrix.
fn factor_markdown(sizes: &[SizeRun]) -> String {
    let mut text = String::new();
    for s in sizes.iter().filter(|s| !s.factor.is_empty()) {
        text += &format!(
            "\n### {}x{} strip: initial tangent, {} unknowns, {} stored entries (run-{}x{}/tangent.mtx)\n\n{}",
            s.nx,
            s.ny,
            s.factor[0].n,
            s.factor[0].entries,
            s.nx,
            s.ny,
            super::factor::markdown(&s.factor)
        );
    }
    text
}

/// The progress line of one size (stderr).
pub fn progress_line(r: &ScalingRow) -> String {
    format!(
        "{}x{}: {} unknowns, {} steps in {:.2} s, peak {:.0} MiB ({})",
        r.nx,
        r.ny,
        r.dofs,
        r.steps,
        r.wall_s,
        r.peak_rss_bytes / 1048576.0,
        r.stop
    )
}

impl Sweep for ScalingSweep {
    fn labels(&self) -> Vec<String> {
        self.sizes
            .iter()
            .map(|(nx, ny)| format!("{nx}x{ny}"))
            .collect()
    }
    fn inputs(&self) -> Vec<PathBuf> {
        vec![self.template.clone()]
    }
    fn concurrent(&self) -> bool {
        false
    }
    fn run_item(&self, k: usize, dir: Option<&Path>) -> Result<serde_json::Value> {
        let dir = dir.ok_or_else(|| {
            Error::study(
                "scaling",
                self.labels()[k].clone(),
                "needs an output folder",
            )
        })?;
        let size = run_size(
            &self.exe,
            &self.template,
            self.sizes[k],
            self.steps,
            dir,
            self.write_matrix,
        )?;
        eprintln!("{}", progress_line(&row(&size)?));
        sweep::encode(&size)
    }
    fn merge(&self, items: &[serde_json::Value], dir: Option<&Path>) -> Result<Merged> {
        let sizes: Vec<SizeRun> = sweep::decode_all(items)?;
        let rows = sizes.iter().map(row).collect::<Result<Vec<_>>>()?;
        let mut md = markdown(&rows);
        if let Some(dir) = dir {
            let file = dir.join("scaling.md");
            std::fs::write(&file, &md).map_err(io(&file))?;
        }
        let factored = factor_markdown(&sizes);
        if !factored.is_empty() {
            if let Some(dir) = dir {
                let file = dir.join("factor.md");
                std::fs::write(&file, &factored).map_err(io(&file))?;
            }
            md += &factored;
        }
        Ok(Merged {
            markdown: md,
            failed: false,
        })
    }
}

/// Least-squares slope b of log y = a + b log x.
pub fn exponent(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    if n < 2.0 {
        return f64::NAN;
    }
    let (sx, sy) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = logs.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    num / den
}

/// The scaling table with fitted exponents.
pub fn markdown(rows: &[ScalingRow]) -> String {
    let mut s = String::from(
        "| mesh | unknowns | steps | total (s) | set-up and outputs (s) | per step: engine / with events and outputs (s) | per step: assembly / factorization / solves / series (ms) | engine step / (factorization + N solves) | peak memory (MiB) | stop |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        // One factorization + N solves, at this run's mean cost of each.
        let factorization = r.per_step[1] * r.steps as f64 / r.factorizations.max(1) as f64;
        let solve = r.per_step[2] * r.steps as f64 / r.solves.max(1) as f64;
        let unit = factorization + r.order as f64 * solve;
        s += &format!(
            "| {}×{} | {} | {} | {:.2} | {:.2} | {:.4} / {:.4} | {:.2} / {:.2} / {:.2} / {:.2} | {:.2} | {:.0} | {} |\n",
            r.nx,
            r.ny,
            r.dofs,
            r.steps,
            r.wall_s,
            r.setup_s(),
            r.engine_step_s(),
            r.step_s(),
            1e3 * r.per_step[0],
            1e3 * r.per_step[1],
            1e3 * r.per_step[2],
            1e3 * r.per_step[3],
            r.engine_step_s() / unit,
            r.peak_rss_bytes / 1048576.0,
            r.stop
        );
    }
    let fit = |f: &dyn Fn(&ScalingRow) -> f64| {
        exponent(
            &rows
                .iter()
                .map(|r| (r.dofs as f64, f(r)))
                .collect::<Vec<_>>(),
        )
    };
    if rows.len() < 2 {
        return s;
    }
    s += &format!(
        "\nFitted exponents b in cost ∝ n^b (n unknowns): engine time per step {:.2}, factorization {:.2}, solves {:.2}, series terms {:.2}, assembly {:.2}, peak memory {:.2}.\n",
        fit(&|r| r.engine_step_s()),
        fit(&|r| r.per_step[1]),
        fit(&|r| r.per_step[2]),
        fit(&|r| r.per_step[3]),
        fit(&|r| r.per_step[0]),
        fit(&|r| r.peak_rss_bytes),
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [1e3, 1e4, 1e5]
            .iter()
            .map(|&n: &f64| (n, 3.0 * n.powf(1.5)))
            .collect();
        assert!((exponent(&pts) - 1.5).abs() < 1e-12);
    }
}

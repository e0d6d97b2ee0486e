//! The stability stress matrix: every run either meets its accuracy check or
//! stops with a diagnosis; never NaN or inf in the output, never a panic.
//!
//! Each axis varies one parameter of a canonical scene. A run is
//! - **met**: it ended (or stopped at a detected singularity) and its output
//!   solves the physical equations to [`TOLERANCE`] (friction:
//!   [`super::check`]; plate-cylinder: the full residual |R(U, lambda)| / |F|
//!   with every candidate node carrying eq. 3, re-evaluated from the output
//!   on every lambda of the grid, [`super::shell_check`]; and, where eta and
//!   K are at the scene's values, uz_A(1) within [`UZ_A_TOLERANCE`] of the
//!   scene's canonical figure);
//! - **diagnosed**: it stopped on an error or a step budget with a message
//!   naming what happened, and the output it did write solves the equations;
//! - **refused**: the scene's own checks refused the run before it started
//!   (an axis value outside what the scene accepts): no numerical stop;
//! - **failed**: a panic, a non-finite number in the output, or output that
//!   does not solve the equations (a wrong answer presented as valid).

use super::check::max_relative_residual;
use super::pool;
use super::shell_check::{check, with_grid_snapshots};
use super::sweep::{self, Merged, Sweep, exact};
use crate::error::{Error, Result};
use crate::model::friction_run::run;
use crate::output::create_dir;
use crate::run::run_loaded;
use crate::scene::Kind;
use crate::scene::friction::FrictionScene;
use crate::scene::shell::ShellScene;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Relative residual an output row may have.
pub const TOLERANCE: f64 = 1e-6;

/// How far (m) uz_A(1) may sit from the canonical figure, printed to 1e-6 m:
/// one unit of its last digit.
pub const UZ_A_TOLERANCE: f64 = 1e-6;

/// uz_A at lambda = 1 (m) of the canonical plate-cylinder scenes at their own
/// eta, K (README, "mesh convergence"), by scene file stem.
pub fn canonical_uz_a(name: &str) -> Option<f64> {
    match name {
        "plate-cylinder-coarse" => Some(0.705805),
        "plate-cylinder" => Some(0.704971),
        _ => None,
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    Met,
    Diagnosed,
    Refused,
    Failed,
}

/// One run of the matrix: also the result of one item of `anm stress --item K`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StressCase {
    pub scene: String,
    pub axis: String,
    #[serde(with = "exact")]
    pub value: f64,
    pub verdict: Verdict,
    pub stop: String,
    pub message: String,
    #[serde(with = "exact")]
    pub residual: f64,
    pub steps: usize,
    #[serde(with = "exact")]
    pub wall_s: f64,
    /// Further figures of the check (plate-cylinder: uz_A(1), the lambda of
    /// the largest residual, whether far candidates were skipped).
    pub detail: String,
}

/// The axes of the full matrix (issue 5, item 7; zeta and omega down to 1e-6,
/// issue 13).
pub fn full_axes() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("eta", vec![1e-8, 1e-6, 1e-4, 1e-2, 1.0]),
        ("K", vec![1e3, 1e6, 1e9, 1e12]),
        ("omega", vec![1e-6, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]),
        ("zeta", vec![1e-6, 1e-4, 1e-2, 1.0]),
        ("q", vec![0.01, 0.1, 0.5, 1.0]),
        ("order", vec![5.0, 10.0, 20.0, 30.0, 40.0]),
    ]
}

/// Whether an axis applies to a scene kind (friction-1d has no contact law).
fn applies(kind: Kind, axis: &str) -> bool {
    !(kind == Kind::Friction1d && matches!(axis, "eta" | "K" | "zeta"))
}

fn apply(scene: &FrictionScene, axis: &str, value: f64) -> FrictionScene {
    let mut s = scene.clone();
    match axis {
        "eta" => s.contact.as_mut().expect("applies() checked").eta = value,
        "K" => s.contact.as_mut().expect("applies() checked").k = value,
        "omega" => s.friction.omega = value,
        "zeta" => s.friction.zeta = Some(value),
        "q" => s.friction.q = value,
        "order" => s.order = value as usize,
        _ => unreachable!("known axes"),
    }
    s
}

/// One run of the matrix, ready to go.
#[derive(Clone, Debug)]
pub enum StressJob {
    Friction {
        scene: String,
        axis: &'static str,
        value: f64,
        run: Box<FrictionScene>,
    },
    Shell {
        scene: String,
        axis: &'static str,
        value: f64,
        run: Box<ShellScene>,
        /// uz_A(1) to meet (the canonical figure where eta and K are the scene's).
        uz_ref: Option<f64>,
    },
}

impl StressJob {
    /// `friction-plane/eta=1e-8`.
    pub fn label(&self) -> String {
        let (StressJob::Friction {
            scene, axis, value, ..
        }
        | StressJob::Shell {
            scene, axis, value, ..
        }) = self;
        format!("{scene}/{axis}={}", value_text(axis, *value))
    }
}

/// The runs of the matrix on friction scenes, in order (scene, axis, value).
pub fn friction_jobs(
    scenes: &[FrictionScene],
    axes: &[(&'static str, Vec<f64>)],
    max_steps: usize,
) -> Vec<StressJob> {
    let mut jobs = vec![];
    for sc in scenes {
        for (axis, values) in axes {
            if !applies(sc.kind, axis) {
                continue;
            }
            for &v in values {
                let mut s = apply(sc, axis, v);
                s.max_steps = s.max_steps.min(max_steps);
                jobs.push(StressJob::Friction {
                    scene: sc.kind.name().to_string(),
                    axis,
                    value: v,
                    run: Box::new(s),
                });
            }
        }
    }
    jobs
}

/// Runs one case and judges it; a panic is a failed case.
pub fn run_job(job: &StressJob) -> StressCase {
    let (StressJob::Friction {
        scene, axis, value, ..
    }
    | StressJob::Shell {
        scene, axis, value, ..
    }) = job;
    let failed = |panic: String| StressCase {
        scene: scene.clone(),
        axis: axis.to_string(),
        value: *value,
        verdict: Verdict::Failed,
        stop: "panic".into(),
        message: panic,
        residual: f64::NAN,
        steps: 0,
        wall_s: 0.0,
        detail: String::new(),
    };
    match job {
        StressJob::Friction { run: s, .. } => sweep::catch(|| run(s, None, false))
            .map_or_else(failed, |r| friction_case(scene.clone(), axis, *value, s, r)),
        StressJob::Shell { run: s, uz_ref, .. } => sweep::catch(|| {
            let report = run_loaded(s, None, false)?;
            let c = check(s, &report)?;
            Ok::<_, crate::Error>((report, c))
        })
        .map_or_else(failed, |r| {
            shell_case(scene.clone(), axis, *value, *uz_ref, s.units.length, r)
        }),
    }
}

/// A run that stopped with an error: diagnosed, with the error's kind, or
/// refused where the error is the input checks' (nothing was computed).
fn diagnosed(scene: String, axis: &str, value: f64, e: &crate::error::Error) -> StressCase {
    let input = matches!(
        e,
        Error::Invalid { .. } | Error::Parse { .. } | Error::Mesh { .. } | Error::Element { .. }
    );
    StressCase {
        scene,
        axis: axis.to_string(),
        value,
        verdict: match input {
            true => Verdict::Refused,
            false => Verdict::Diagnosed,
        },
        stop: e.kind().into(),
        message: e.to_string(),
        residual: 0.0,
        steps: 0,
        wall_s: 0.0,
        detail: String::new(),
    }
}

fn friction_case(
    scene: String,
    axis: &'static str,
    value: f64,
    s: &FrictionScene,
    r: Result<crate::model::friction_run::FrictionRun>,
) -> StressCase {
    match r {
        Err(e) => diagnosed(scene, axis, value, &e),
        Ok(run) => {
            let residual = max_relative_residual(s, &run.columns, &run.history);
            let finite = run.history.iter().flatten().all(|x| x.is_finite());
            let ok = finite && residual <= TOLERANCE;
            let normal = matches!(run.stop.reason.as_str(), "end" | "singularity");
            let verdict = match (ok, normal) {
                (true, true) => Verdict::Met,
                (true, false) if run.stop.message.is_some() => Verdict::Diagnosed,
                _ => Verdict::Failed,
            };
            StressCase {
                scene,
                axis: axis.to_string(),
                value,
                verdict,
                stop: run.stop.reason.clone(),
                message: run.stop.message.clone().unwrap_or_default(),
                residual,
                steps: run.stats.steps,
                wall_s: run.wall_s,
                detail: String::new(),
            }
        }
    }
}

/// Runs the matrix on the given scenes (in parallel), with a step budget per run.
pub fn stress(
    scenes: &[FrictionScene],
    axes: &[(&'static str, Vec<f64>)],
    max_steps: usize,
) -> Vec<StressCase> {
    run_jobs(&friction_jobs(scenes, axes, max_steps))
}

fn run_jobs(jobs: &[StressJob]) -> Vec<StressCase> {
    pool::map(jobs, run_job)
        .into_iter()
        .map(|r| r.expect("run_job catches panics"))
        .collect()
}

/// The axes of the plate-cylinder matrix (issue 5, item 7).
pub fn shell_axes() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("eta", vec![1e-8, 1e-6, 1e-4, 1e-2, 1.0]),
        ("K", vec![1e3, 1e6, 1e9, 1e12]),
        ("order", vec![5.0, 10.0, 20.0, 40.0]),
    ]
}

fn apply_shell(scene: &ShellScene, axis: &str, value: f64) -> Option<ShellScene> {
    let mut s = scene.clone();
    match axis {
        "eta" => s.contact.as_mut()?.eta = value,
        "K" => s.contact.as_mut()?.k = value,
        "order" => s.solver.order = value as usize,
        _ => return None,
    }
    Some(s)
}

/// The runs of the matrix on plate-cylinder scenes `(name, scene)`, in order;
/// axes other than eta, K and order do not apply to the frictionless shell
/// and are left out.
pub fn shell_jobs(
    scenes: &[(String, ShellScene)],
    axes: &[(&'static str, Vec<f64>)],
    max_steps: usize,
) -> Vec<StressJob> {
    let mut jobs = vec![];
    for (name, sc) in scenes {
        for (axis, values) in axes {
            for &v in values {
                let Some(mut s) = apply_shell(sc, axis, v) else {
                    continue;
                };
                s.solver.max_steps = s.solver.max_steps.min(max_steps);
                let at_scene_values = match *axis {
                    "eta" => sc.contact.as_ref().is_some_and(|c| v == c.eta),
                    "K" => sc.contact.as_ref().is_some_and(|c| v == c.k),
                    _ => true,
                };
                let uz_ref = canonical_uz_a(name).filter(|_| at_scene_values);
                jobs.push(StressJob::Shell {
                    scene: name.clone(),
                    axis,
                    value: v,
                    run: Box::new(with_grid_snapshots(&s)),
                    uz_ref,
                });
            }
        }
    }
    jobs
}

/// Runs the matrix on plate-cylinder scenes `(name, scene)` (in parallel),
/// with a step budget per run (see [`shell_jobs`]).
pub fn stress_shell(
    scenes: &[(String, ShellScene)],
    axes: &[(&'static str, Vec<f64>)],
    max_steps: usize,
) -> Vec<StressCase> {
    run_jobs(&shell_jobs(scenes, axes, max_steps))
}

fn shell_case(
    scene: String,
    axis: &'static str,
    value: f64,
    uz_ref: Option<f64>,
    length: &str,
    r: Result<(crate::run::RunReport, super::shell_check::ShellCheck)>,
) -> StressCase {
    match r {
        Err(e) => diagnosed(scene, axis, value, &e),
        Ok((run, c)) => {
            let finite = run.history.iter().flatten().all(|x| x.is_finite());
            let normal = run.stop.reason == "end";
            let uz1 = run.value_at("uz_A", 1.0);
            let mut problems = vec![];
            if !finite {
                problems.push("non-finite value in the output".to_string());
            }
            if !(c.max_residual <= TOLERANCE) {
                problems.push(format!(
                    "residual |R|/|R_lambda| = {:.2e} > {TOLERANCE:e} at lambda = {}",
                    c.max_residual, c.worst_lambda
                ));
            }
            if let (Some(want), true) = (uz_ref, normal) {
                let got = uz1.unwrap_or(f64::NAN);
                if !((got - want).abs() <= UZ_A_TOLERANCE) {
                    problems.push(format!(
                        "uz_A(1) = {got:.7} {length} differs from the canonical {want} {length} by more than {UZ_A_TOLERANCE:e} {length}"
                    ));
                }
            }
            let verdict = match (problems.is_empty(), normal) {
                (true, true) => Verdict::Met,
                (true, false) if run.stop.message.is_some() => Verdict::Diagnosed,
                _ => Verdict::Failed,
            };
            let mut message = run.stop.message.clone().unwrap_or_default();
            if !problems.is_empty() {
                if !message.is_empty() {
                    message += "; ";
                }
                message += &problems.join("; ");
            }
            StressCase {
                scene,
                axis: axis.to_string(),
                value,
                verdict,
                stop: run.stop.reason.clone(),
                message,
                residual: c.max_residual,
                steps: run.steps,
                wall_s: run.wall_s,
                detail: format!(
                    "uz_A(1) = {}{}; max residual at lambda = {} over {} grid points; {}",
                    match (uz1, run.columns.iter().any(|c| c == "uz_A")) {
                        (Some(u), _) => format!("{u:.7} {length}"),
                        // Review 19: a user's scene without plate-cylinder's
                        // probe read as a run that did not reach 1.
                        (None, false) => "– (no uz_A probe)".into(),
                        (None, true) => "not reached".into(),
                    },
                    uz_ref.map_or(String::new(), |u| format!(" (canonical {u} {length})")),
                    c.worst_lambda,
                    c.points,
                    match (run.far_nodes_skipped, run.skipped_pull_bound > 0.0) {
                        (true, true) => format!(
                            "far candidates skipped (pull <= {:.1e} N)",
                            run.skipped_pull_bound
                        ),
                        (true, false) => "no candidate beyond reach".into(),
                        (false, _) => "every candidate active".into(),
                    }
                ),
            }
        }
    }
}

/// The matrix as Markdown: one row per scene and axis, one cell per value.
pub fn markdown(cases: &[StressCase]) -> String {
    let mut s = String::new();
    let count = |v: Verdict| cases.iter().filter(|c| c.verdict == v).count();
    s += &format!(
        "{} runs: {} met, {} diagnosed stops, {} failed{}\n\n",
        cases.len(),
        count(Verdict::Met),
        count(Verdict::Diagnosed),
        count(Verdict::Failed),
        match count(Verdict::Refused) {
            0 => String::new(),
            n => format!(", {n} refused by the scene checks (not run)"),
        }
    );
    s += "| scene | axis | value: verdict (stop, steps, max relative residual) |\n|---|---|---|\n";
    let mut keys: Vec<(String, &str)> = cases
        .iter()
        .map(|c| (c.scene.clone(), c.axis.as_str()))
        .collect();
    keys.dedup();
    for (scene, axis) in keys {
        let cells: Vec<String> = cases
            .iter()
            .filter(|c| c.scene == scene && c.axis == axis)
            .map(|c| {
                let v = match c.verdict {
                    Verdict::Met => "met",
                    Verdict::Diagnosed => "diagnosed",
                    Verdict::Refused => "refused",
                    Verdict::Failed => "**FAILED**",
                };
                format!(
                    "{}: {v} ({}, {}, {:.1e})",
                    value_text(&c.axis, c.value),
                    c.stop,
                    c.steps,
                    c.residual
                )
            })
            .collect();
        s += &format!("| {scene} | {axis} | {} |\n", cells.join("; "));
    }
    let notes: Vec<&StressCase> = cases
        .iter()
        .filter(|c| c.verdict != Verdict::Met || !c.detail.is_empty())
        .collect();
    if !notes.is_empty() {
        s += "\n";
    }
    for c in notes {
        s += &format!(
            "- {} {} = {}: {:?}",
            c.scene,
            c.axis,
            value_text(&c.axis, c.value),
            c.verdict
        );
        if !c.message.is_empty() {
            s += &format!(": {}", c.message);
        }
        if !c.detail.is_empty() {
            s += &format!(" ({})", c.detail);
        }
        s += "\n";
    }
    s
}

/// A value of an axis as written: orders as integers (`order=40`, not
/// `4e1`), regularizations and stiffnesses in exponent form (`eta=1e-6`).
fn value_text(axis: &str, value: f64) -> String {
    if axis == "order" {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}

/// Writes stress.md and stress.csv into `dir`.
pub fn write(cases: &[StressCase], dir: &Path) -> Result<()> {
    create_dir(dir)?;
    let md_file = dir.join("stress.md");
    std::fs::write(&md_file, markdown(cases)).map_err(|e| Error::Io {
        file: md_file.clone(),
        source: e,
    })?;
    let file = dir.join("stress.csv");
    let out = |e: csv::Error| Error::write(dir.join("stress.csv"), e);
    let mut w = csv::Writer::from_path(&file).map_err(out)?;
    w.write_record([
        "scene",
        "axis",
        "value",
        "verdict",
        "stop",
        "steps",
        "max_relative_residual",
        "wall_s",
        "message",
        "detail",
    ])
    .map_err(out)?;
    for c in cases {
        w.write_record([
            c.scene.clone(),
            c.axis.to_string(),
            value_text(&c.axis, c.value),
            format!("{:?}", c.verdict),
            c.stop.clone(),
            c.steps.to_string(),
            format!("{:e}", c.residual),
            format!("{:e}", c.wall_s),
            c.message.clone(),
            c.detail.clone(),
        ])
        .map_err(out)?;
    }
    w.flush().map_err(|e| Error::Io { file, source: e })
}

/// The stress matrix as a sweep (`anm stress`): one item per run (friction
/// scenes first, then plate-cylinder scenes, each in --cases order); the
/// merge writes stress.md and stress.csv and fails when a run failed.
pub struct StressSweep {
    jobs: Vec<StressJob>,
    inputs: Vec<PathBuf>,
}

impl StressSweep {
    /// The matrix of the full axes on the scenes `DIR/CASE.toml`.
    pub fn new(scenes: &Path, cases: &[String], max_steps: usize) -> Result<Self> {
        let (mut friction, mut shells, mut inputs) = (vec![], vec![], vec![]);
        // A case given twice would run twice and print its rows twice
        // (review 19).
        if let Some(twice) = cases
            .iter()
            .enumerate()
            .find_map(|(i, c)| cases[..i].contains(c).then_some(c))
        {
            return Err(Error::Invalid {
                file: scenes.to_path_buf(),
                key: "--cases".into(),
                problem: format!("`{twice}` is given twice"),
            });
        }
        for name in cases {
            let path = scenes.join(format!("{name}.toml"));
            let text = crate::scene::read(&path)?;
            match crate::scene::kind(&path, &text)? {
                Kind::Shell => {
                    let shell = crate::scene::shell::load(&path)?;
                    if shell.friction.is_some() {
                        // Its axes (eta, K, order) vary the static path.
                        return Err(Error::Invalid {
                            file: path,
                            key: "friction".into(),
                            problem: "`anm stress` varies the static path in lambda of a shell scene (eta, K, order); a scene with [friction] runs in time: stress it with `anm audit` (its sweeps in time) or runs of its own".into(),
                        });
                    }
                    // The mesh file too: the merge refuses a changed one.
                    inputs.extend(sweep::scene_inputs(&shell).into_iter().skip(1));
                    shells.push((name.clone(), shell))
                }
                kind => friction.push(crate::scene::friction::load(&path, &text, kind)?),
            }
            inputs.push(path);
        }
        let mut jobs = friction_jobs(&friction, &full_axes(), max_steps);
        jobs.extend(shell_jobs(&shells, &shell_axes(), max_steps));
        Ok(StressSweep { jobs, inputs })
    }
}

impl Sweep for StressSweep {
    fn labels(&self) -> Vec<String> {
        self.jobs.iter().map(StressJob::label).collect()
    }
    fn inputs(&self) -> Vec<PathBuf> {
        self.inputs.clone()
    }
    fn run_item(&self, k: usize, _dir: Option<&Path>) -> Result<serde_json::Value> {
        sweep::encode(&run_job(&self.jobs[k]))
    }
    fn merge(&self, items: &[serde_json::Value], dir: Option<&Path>) -> Result<Merged> {
        let cases: Vec<StressCase> = sweep::decode_all(items)?;
        if let Some(dir) = dir {
            write(&cases, dir)?;
        }
        Ok(Merged {
            markdown: markdown(&cases),
            failed: cases.iter().any(|c| c.verdict == Verdict::Failed),
        })
    }
}

//! The stability stress matrix: every run either meets its accuracy check or
//! stops with a diagnosis; never NaN or inf in the output, never a panic.
//!
//! Each axis varies one parameter of a canonical scene. A run is
//! - **met**: it ended (or stopped at a detected singularity) and its output
//!   solves the physical equations ([`super::check`]) to `tolerance`;
//! - **diagnosed**: it stopped on an error or a step budget with a message
//!   naming what happened, and the output it did write solves the equations;
//! - **failed**: a panic, a non-finite number in the output, or output that
//!   does not solve the equations (a wrong answer presented as valid).

use super::check::max_relative_residual;
use super::pool;
use crate::model::friction_run::run;
use crate::scene::Kind;
use crate::scene::friction::FrictionScene;

/// Relative residual an output row may have.
pub const TOLERANCE: f64 = 1e-6;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Met,
    Diagnosed,
    Failed,
}

#[derive(Clone, Debug)]
pub struct StressCase {
    pub scene: String,
    pub axis: &'static str,
    pub value: f64,
    pub verdict: Verdict,
    pub stop: String,
    pub message: String,
    pub residual: f64,
    pub steps: usize,
    pub wall_s: f64,
}

/// The axes of the full matrix (issue 5, item 7).
pub fn full_axes() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("eta", vec![1e-8, 1e-6, 1e-4, 1e-2, 1.0]),
        ("K", vec![1e3, 1e6, 1e9, 1e12]),
        ("omega", vec![1e-4, 1e-3, 1e-2, 1e-1, 1.0]),
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

/// Runs the matrix on the given scenes (in parallel), with a step budget per run.
pub fn stress(
    scenes: &[FrictionScene],
    axes: &[(&'static str, Vec<f64>)],
    max_steps: usize,
) -> Vec<StressCase> {
    let mut jobs = vec![];
    for sc in scenes {
        for (axis, values) in axes {
            if !applies(sc.kind, axis) {
                continue;
            }
            for &v in values {
                let mut s = apply(sc, axis, v);
                s.max_steps = s.max_steps.min(max_steps);
                jobs.push((sc.kind.name().to_string(), *axis, v, s));
            }
        }
    }
    let results = pool::map(&jobs, |(_, _, _, s)| run(s, None, false));
    jobs.into_iter()
        .zip(results)
        .map(|((scene, axis, value, s), r)| match r {
            Err(panic) => StressCase {
                scene,
                axis,
                value,
                verdict: Verdict::Failed,
                stop: "panic".into(),
                message: panic,
                residual: f64::NAN,
                steps: 0,
                wall_s: 0.0,
            },
            Ok(Err(e)) => StressCase {
                scene,
                axis,
                value,
                verdict: Verdict::Diagnosed,
                stop: e.kind().into(),
                message: e.to_string(),
                residual: 0.0,
                steps: 0,
                wall_s: 0.0,
            },
            Ok(Ok(run)) => {
                let residual = max_relative_residual(&s, &run.columns, &run.history);
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
                    axis,
                    value,
                    verdict,
                    stop: run.stop.reason.clone(),
                    message: run.stop.message.clone().unwrap_or_default(),
                    residual,
                    steps: run.stats.steps,
                    wall_s: run.wall_s,
                }
            }
        })
        .collect()
}

/// The matrix as Markdown: one row per scene and axis, one cell per value.
pub fn markdown(cases: &[StressCase]) -> String {
    let mut s = String::new();
    let count = |v: Verdict| cases.iter().filter(|c| c.verdict == v).count();
    s += &format!(
        "{} runs: {} met, {} diagnosed stops, {} failed\n\n",
        cases.len(),
        count(Verdict::Met),
        count(Verdict::Diagnosed),
        count(Verdict::Failed)
    );
    s += "| scene | axis | value: verdict (stop, steps, max relative residual) |\n|---|---|---|\n";
    let mut keys: Vec<(String, &str)> = cases.iter().map(|c| (c.scene.clone(), c.axis)).collect();
    keys.dedup();
    for (scene, axis) in keys {
        let cells: Vec<String> = cases
            .iter()
            .filter(|c| c.scene == scene && c.axis == axis)
            .map(|c| {
                let v = match c.verdict {
                    Verdict::Met => "met",
                    Verdict::Diagnosed => "diagnosed",
                    Verdict::Failed => "**FAILED**",
                };
                format!(
                    "{:e}: {v} ({}, {}, {:.0e})",
                    c.value, c.stop, c.steps, c.residual
                )
            })
            .collect();
        s += &format!("| {scene} | {axis} | {} |\n", cells.join("; "));
    }
    s
}

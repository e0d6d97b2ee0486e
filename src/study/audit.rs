//! The regularization audit: how much omega (eq. 6), zeta (eq. 11), eta and
//! K (eq. 3) bend the answers, and what they cost.
//!
//! Each listed parameter is swept alone around the scene's values. For every
//! run we report the key output of the scene (friction-1d: the plateau u(t_end);
//! friction-plane: the slope of u_x over the last third of the run;
//! friction-roller: the located breakdown time), its deviation from the
//! unregularized reference — the closed form where one exists (friction-1d:
//! plateau f R_N (V/Vc)^q / k and the omega = 0 curve), otherwise the run with
//! the smallest value of that sweep — the deviation of the whole displacement
//! trajectory, and the cost (steps, factorizations, wall time).

use super::pool;
use super::sweep::{self, Merged, Sweep, exact, exact_opt, exact_rows};
use crate::error::{Error, Result};
use crate::model::friction_run::{FrictionRun, run};
use crate::output::create_dir;
use crate::output::plot::{Curve, Panel, draw};
use crate::scene::Kind;
use crate::scene::friction::{FrictionScene, Obstacle};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The values to sweep, per parameter.
#[derive(Clone, Debug, Default)]
pub struct Sweeps {
    pub omega: Vec<f64>,
    pub zeta: Vec<f64>,
    pub eta: Vec<f64>,
    pub penalty: Vec<f64>,
}

/// One audited run.
#[derive(Clone, Debug)]
pub struct AuditRow {
    pub parameter: &'static str,
    pub value: f64,
    pub stop: String,
    pub t_stop: f64,
    pub key_name: &'static str,
    pub key: f64,
    /// |key - reference| / |reference|.
    pub key_deviation: f64,
    /// What the key and the trajectory are compared with.
    pub reference: String,
    /// max_t |u - u_ref| / max_t |u_ref| over the displacement columns.
    pub trajectory_deviation: f64,
    pub steps: usize,
    pub factorizations: usize,
    pub wall_s: f64,
}

/// Applies one parameter value to a copy of the scene, with the scene's own
/// validation rules.
pub fn with_parameter(scene: &FrictionScene, parameter: &str, value: f64) -> Result<FrictionScene> {
    let bad = |problem: String| Error::Invalid {
        file: scene.file.clone(),
        key: format!("--{parameter}"),
        problem,
    };
    if !(value.is_finite() && value > 0.0) {
        return Err(bad(format!("values must be finite and > 0, got {value}")));
    }
    let mut s = scene.clone();
    match parameter {
        "omega" => s.friction.omega = value,
        "zeta" => match s.kind {
            Kind::Friction1d => {
                return Err(bad(
                    "friction-1d has a known normal force and no zeta".into()
                ));
            }
            _ => s.friction.zeta = Some(value),
        },
        "eta" | "penalty" => {
            let c = s
                .contact
                .as_mut()
                .ok_or_else(|| bad("friction-1d has no contact law".into()))?;
            if parameter == "eta" {
                c.eta = value;
            } else {
                c.k = value;
            }
            if c.eta >= c.k * c.delta {
                return Err(bad(format!(
                    "eta = {} must stay below K delta = {:e}",
                    c.eta,
                    c.k * c.delta
                )));
            }
        }
        _ => return Err(bad("unknown parameter".into())),
    }
    Ok(s)
}

/// What the audit keeps of one run: enough to rebuild every row, table and
/// plot (the item file of `anm audit --item K`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunRecord {
    pub kind: String,
    pub columns: Vec<String>,
    #[serde(with = "exact_rows")]
    pub history: Vec<Vec<f64>>,
    pub stop: String,
    #[serde(with = "exact_opt")]
    pub t_stop: Option<f64>,
    #[serde(with = "exact_opt")]
    pub t_singular_estimate: Option<f64>,
    pub steps: usize,
    pub factorizations: usize,
    #[serde(with = "exact")]
    pub wall_s: f64,
}

impl From<&FrictionRun> for RunRecord {
    fn from(r: &FrictionRun) -> Self {
        RunRecord {
            kind: r.kind.clone(),
            columns: r.columns.clone(),
            history: r.history.clone(),
            stop: r.stop.reason.clone(),
            t_stop: r.stop.t,
            t_singular_estimate: r.t_singular_estimate,
            steps: r.stats.steps,
            factorizations: r.stats.factorizations,
            wall_s: r.wall_s,
        }
    }
}

/// One item of the audit: a parameter value and its run (or why it failed).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AuditItem {
    pub parameter: String,
    #[serde(with = "exact")]
    pub value: f64,
    pub outcome: std::result::Result<RunRecord, String>,
}

/// The parameters in sweep order (the order of the items and the rows).
const PARAMETERS: [&str; 4] = ["omega", "zeta", "eta", "penalty"];

/// The items of the sweep, in order: each parameter's values in turn; every
/// value validated before any run.
pub fn jobs(
    scene: &FrictionScene,
    sweeps: &Sweeps,
) -> Result<Vec<(&'static str, f64, FrictionScene)>> {
    let mut jobs = vec![];
    for (name, values) in
        PARAMETERS
            .into_iter()
            .zip([&sweeps.omega, &sweeps.zeta, &sweeps.eta, &sweeps.penalty])
    {
        for &v in values {
            jobs.push((name, v, with_parameter(scene, name, v)?));
        }
    }
    Ok(jobs)
}

/// The label of an item: `omega=1e-1`.
pub fn label(parameter: &str, value: f64) -> String {
    format!("{parameter}={value:e}")
}

/// Runs one item (a panic becomes a recorded failure).
pub fn run_item(parameter: &str, value: f64, scene: &FrictionScene) -> AuditItem {
    let outcome = match sweep::catch(|| run(scene, None, false)) {
        Ok(Ok(r)) => Ok(RunRecord::from(&r)),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(format!("panicked: {panic}")),
    };
    AuditItem {
        parameter: parameter.to_string(),
        value,
        outcome,
    }
}

fn key_output(run: &RunRecord) -> (&'static str, f64) {
    let col = |name: &str| run.columns.iter().position(|c| c == name).expect("column");
    match run.kind.as_str() {
        "friction-1d" => (
            "plateau u(t_end)",
            run.history.last().map(|r| r[col("u")]).unwrap_or(f64::NAN),
        ),
        "friction-plane" => {
            let (t, u) = (col("t"), col("ux"));
            let n = run.history.len();
            if n < 3 {
                return ("slope of u_x", f64::NAN);
            }
            let (a, b) = (&run.history[2 * n / 3], &run.history[n - 1]);
            ("slope of u_x", (b[u] - a[u]) / (b[t] - a[t]))
        }
        _ => (
            "breakdown time t*",
            run.t_singular_estimate.or(run.t_stop).unwrap_or(f64::NAN),
        ),
    }
}

/// max_t |u - u_ref| / max_t |u_ref| over the displacement columns, on the
/// output times both runs reached.
fn trajectory_deviation(run: &RunRecord, reference: &[(f64, Vec<f64>)]) -> f64 {
    let cols: Vec<usize> = run
        .columns
        .iter()
        .enumerate()
        .filter(|(_, c)| matches!(c.as_str(), "u" | "ux" | "uy"))
        .map(|(j, _)| j)
        .collect();
    let scale = reference
        .iter()
        .flat_map(|(_, r)| cols.iter().map(|&j| r[j].abs()).collect::<Vec<_>>())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut worst: f64 = 0.0;
    for (row, (t_ref, r_ref)) in run.history.iter().zip(reference) {
        debug_assert!((row[0] - t_ref).abs() < 1e-9);
        for &j in &cols {
            worst = worst.max((row[j] - r_ref[j]).abs() / scale);
        }
    }
    worst
}

/// The omega = 0 curve of friction-1d (q > 0): du/dt = V - Vc (k u / (f R_N))^(1/q),
/// by classical RK4 with 1e-5 s steps, on the run's output times; rows shaped
/// like the run's history (t, u, v, rt).
fn friction_1d_unregularized(scene: &FrictionScene) -> Option<Vec<(f64, Vec<f64>)>> {
    let Obstacle::Plane { v } = scene.obstacle else {
        return None;
    };
    let (k, f, rn, vc, q) = (
        scene.k,
        scene.friction.f,
        scene.normal_force,
        scene.friction.vc,
        scene.friction.q,
    );
    if q <= 0.0 {
        return None;
    }
    let rate = |u: f64| v - vc * (k * u / (f * rn)).max(0.0).powf(1.0 / q);
    let (mut t, mut u) = (0.0, scene.u0);
    let mut out = vec![];
    for tg in scene.output_times() {
        while t < tg - 1e-15 {
            let h = 1e-5f64.min(tg - t);
            let k1 = rate(u);
            let k2 = rate(u + 0.5 * h * k1);
            let k3 = rate(u + 0.5 * h * k2);
            let k4 = rate(u + h * k3);
            u += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            t += h;
        }
        out.push((tg, vec![tg, u, rate(u), k * u]));
    }
    Some(out)
}

/// Runs the sweeps (in parallel) and returns one row per run.
pub fn audit(scene: &FrictionScene, sweeps: &Sweeps) -> Result<Vec<AuditRow>> {
    let jobs = jobs(scene, sweeps)?;
    let items: Vec<AuditItem> = pool::map(&jobs, |(name, v, s)| run_item(name, *v, s))
        .into_iter()
        .zip(&jobs)
        .map(|(r, (name, v, _))| {
            r.unwrap_or_else(|panic| AuditItem {
                parameter: name.to_string(),
                value: *v,
                outcome: Err(format!("panicked: {panic}")),
            })
        })
        .collect();
    rows(scene, &items)
}

/// The rows from the items' results (in sweep order): deviations from each
/// sweep's reference. A failed run fails the audit, naming it.
pub fn rows(scene: &FrictionScene, items: &[AuditItem]) -> Result<Vec<AuditRow>> {
    let mut rows = vec![];
    for name in PARAMETERS {
        let group: Vec<(f64, &RunRecord)> = items
            .iter()
            .filter(|it| it.parameter == name)
            .map(|it| match &it.outcome {
                Ok(run) => Ok((it.value, run)),
                Err(e) => Err(Error::study("audit", format!("{name} = {}", it.value), e)),
            })
            .collect::<Result<_>>()?;
        if group.is_empty() {
            continue;
        }
        // The least regularized run: the smallest omega, zeta, eta, but the
        // largest penalty K (eq. 3 tends to the exact law as K grows).
        let least = |a: &&(f64, &RunRecord), b: &&(f64, &RunRecord)| {
            if name == "penalty" {
                b.0.total_cmp(&a.0)
            } else {
                a.0.total_cmp(&b.0)
            }
        };
        // Review 26: a run that stopped short (non-finite values at t = 0,
        // its step budget) was the reference, and every finished run was
        // 1e308 or 1.75e-2 off it. The reference is the least regularized
        // run that reached its answer (t_end, or the roller's breakdown);
        // a run that stopped short gets NaN deviations.
        let completed = |r: &RunRecord| matches!(r.stop.as_str(), "end" | "singularity");
        let finished: Vec<&(f64, &RunRecord)> =
            group.iter().filter(|(_, r)| completed(r)).collect();
        let least_finished = finished.iter().copied().min_by(least);
        // Unregularized reference: closed forms where the problem has them.
        let exact_curve = (scene.kind == Kind::Friction1d && name == "omega")
            .then(|| friction_1d_unregularized(scene))
            .flatten();
        let (ref_name, ref_key, ref_traj): (String, f64, Vec<(f64, Vec<f64>)>) =
            match (&exact_curve, scene.obstacle, least_finished) {
                (Some(curve), Obstacle::Plane { v }, _) => (
                    "closed form (omega = 0)".into(),
                    scene.friction.f
                        * scene.normal_force
                        * (v / scene.friction.vc).powf(scene.friction.q)
                        / scene.k,
                    curve.clone(),
                ),
                (_, _, Some((least_value, smallest))) => (
                    format!("run with {name} = {least_value:e}"),
                    key_output(smallest).1,
                    smallest.history.iter().map(|r| (r[0], r.clone())).collect(),
                ),
                (_, _, None) => ("none (no run reached its answer)".into(), f64::NAN, vec![]),
            };
        for (v, r) in group {
            let (key_name, key) = key_output(r);
            let (key_deviation, trajectory) = if completed(r) && !ref_key.is_nan() {
                (
                    super::time_audit::deviation(key, ref_key),
                    trajectory_deviation(r, &ref_traj),
                )
            } else {
                (f64::NAN, f64::NAN)
            };
            rows.push(AuditRow {
                parameter: name,
                value: v,
                stop: r.stop.clone(),
                t_stop: r.t_stop.unwrap_or(f64::NAN),
                key_name,
                key,
                key_deviation,
                reference: ref_name.clone(),
                trajectory_deviation: trajectory,
                steps: r.steps,
                factorizations: r.factorizations,
                wall_s: r.wall_s,
            });
        }
    }
    Ok(rows)
}

/// The audit as a sweep (`anm audit`, friction scenes): one item per
/// parameter value; the merge writes audit.csv, audit.md, audit.svg.
pub struct FrictionAudit {
    pub scene: FrictionScene,
    jobs: Vec<(&'static str, f64, FrictionScene)>,
}

impl FrictionAudit {
    /// Validates every value; an error when there is nothing to sweep.
    pub fn new(scene: FrictionScene, sweeps: &Sweeps) -> Result<Self> {
        let jobs = jobs(&scene, sweeps)?;
        if jobs.is_empty() {
            return Err(Error::Invalid {
                file: scene.file.clone(),
                key: "audit".into(),
                problem: "nothing to sweep: give at least one of --omega, --zeta, --eta, --penalty"
                    .into(),
            });
        }
        Ok(FrictionAudit { scene, jobs })
    }
}

impl Sweep for FrictionAudit {
    fn labels(&self) -> Vec<String> {
        self.jobs.iter().map(|(n, v, _)| label(n, *v)).collect()
    }
    fn inputs(&self) -> Vec<PathBuf> {
        vec![self.scene.file.clone()]
    }
    fn run_item(&self, k: usize, _dir: Option<&Path>) -> Result<serde_json::Value> {
        let (name, v, s) = &self.jobs[k];
        sweep::encode(&run_item(name, *v, s))
    }
    fn merge(&self, items: &[serde_json::Value], dir: Option<&Path>) -> Result<Merged> {
        let items: Vec<AuditItem> = sweep::decode_all(items)?;
        let rows = rows(&self.scene, &items)?;
        if let Some(dir) = dir {
            write(&self.scene, &rows, dir)?;
        }
        Ok(Merged {
            markdown: markdown(&self.scene, &rows),
            failed: false,
        })
    }
}

const HEADER: [&str; 11] = [
    "parameter",
    "value",
    "stop",
    "t_stop",
    "key",
    "key_value",
    "key_deviation",
    "trajectory_deviation",
    "steps",
    "factorizations",
    "wall_s",
];

/// The table as Markdown.
pub fn markdown(scene: &FrictionScene, rows: &[AuditRow]) -> String {
    let mut s = format!(
        "Regularization audit of `{}` ({})\n\n",
        scene.file.display(),
        scene.kind.name()
    );
    s += "| parameter | value | stop | t_stop (s) | key output | value | deviation | trajectory deviation | steps | factorizations | wall (s) | reference |\n";
    s += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        s += &format!(
            "| {} | {:.3e} | {} | {:.6} | {} | {:.9} | {:.2e} | {:.2e} | {} | {} | {:.3} | {} |\n",
            r.parameter,
            r.value,
            r.stop,
            r.t_stop,
            r.key_name,
            r.key,
            r.key_deviation,
            r.trajectory_deviation,
            r.steps,
            r.factorizations,
            r.wall_s,
            r.reference
        );
    }
    s
}

/// The unit of a swept parameter.
fn unit(parameter: &str) -> &'static str {
    match parameter {
        "omega" => "-",
        "zeta" | "eta" => "N",
        "penalty" => "N/m",
        _ => "?",
    }
}

/// The x label of the audit plot: "omega (-)" for one swept parameter,
/// "parameter value (omega: -, eta: N)" for several.
fn parameter_axis(params: &[&str]) -> String {
    match params {
        [p] => format!("{} ({})", if *p == "penalty" { "K" } else { p }, unit(p)),
        _ => format!(
            "parameter value ({})",
            params
                .iter()
                .map(|p| format!("{}: {}", if *p == "penalty" { "K" } else { p }, unit(p)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Writes audit.csv, audit.md and audit.svg into `dir` (`anm audit -o DIR`;
/// without it the table only goes to stdout).
pub fn write(scene: &FrictionScene, rows: &[AuditRow], dir: &Path) -> Result<()> {
    create_dir(dir)?;
    let io = |e: std::io::Error| Error::Io {
        file: dir.to_path_buf(),
        source: e,
    };
    let mut w = csv::Writer::from_path(dir.join("audit.csv"))
        .map_err(|e| Error::write(dir.join("audit.csv"), e))?;
    w.write_record(HEADER)
        .map_err(|e| Error::write(dir.join("audit.csv"), e))?;
    for r in rows {
        w.write_record([
            r.parameter.to_string(),
            format!("{:e}", r.value),
            r.stop.clone(),
            format!("{:e}", r.t_stop),
            r.key_name.to_string(),
            format!("{:.17e}", r.key),
            format!("{:e}", r.key_deviation),
            format!("{:e}", r.trajectory_deviation),
            r.steps.to_string(),
            r.factorizations.to_string(),
            format!("{:e}", r.wall_s),
        ])
        .map_err(|e| Error::write(dir.join("audit.csv"), e))?;
    }
    w.flush().map_err(io)?;
    std::fs::write(dir.join("audit.md"), markdown(scene, rows)).map_err(io)?;
    let params: Vec<&str> = ["omega", "zeta", "eta", "penalty"]
        .into_iter()
        .filter(|p| rows.iter().any(|r| r.parameter == *p))
        .collect();
    let curves = |f: &dyn Fn(&AuditRow) -> f64| -> Vec<Curve> {
        params
            .iter()
            .map(|p| Curve {
                label: p,
                points: rows
                    .iter()
                    .filter(|r| r.parameter == *p)
                    .map(|r| (r.value, f(r)))
                    .collect(),
            })
            .collect()
    };
    let title = format!(
        "{}: deviation of the key output from the unregularized reference",
        scene.kind.name()
    );
    let x_label = parameter_axis(&params);
    draw(
        &dir.join("audit.svg"),
        &[
            Panel {
                title: &title,
                x_label: &x_label,
                y_label: "deviation (relative)",
                curves: curves(&|r| r.key_deviation),
                log: (true, true),
            },
            Panel {
                title: "deviation of the displacement trajectory",
                x_label: &x_label,
                y_label: "max |u - u_ref| / max |u_ref| (-)",
                curves: curves(&|r| r.trajectory_deviation),
                log: (true, true),
            },
            Panel {
                title: "cost",
                x_label: &x_label,
                y_label: "steps (-)",
                curves: curves(&|r| r.steps as f64),
                log: (true, true),
            },
        ],
    )?;
    Ok(())
}

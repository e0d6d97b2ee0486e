//! The regularization audit of a shell scene in time (a `[friction]`
//! table; issue 10 item 5): how much omega, zeta (the friction law, eqs. 6
//! and 11) and eta, K (the normal law, eq. 3) bend the scene's key probe
//! (its first), the total normal reaction (rn_total) and the slip zone
//! (slip_area) at t_end, and what they cost.
//!
//! Each parameter is swept alone around the scene's values. For every run:
//! the stop, both outputs at t_end, their deviation from the least
//! regularized run of the sweep (smallest omega, zeta, eta; largest K), the
//! largest deviation of the key probe over the output times, and the cost
//! (steps, factorizations, wall time). A run that stops before t_end is a
//! row with its diagnosis: which regularization the solver cannot reach is
//! part of the answer.

use super::audit::{Sweeps, label};
use super::sweep::{self, Merged, Sweep, exact, exact_rows};
use crate::error::{Error, Result};
use crate::output::create_dir;
use crate::run::shell_time;
use crate::scene::shell::ShellScene;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What the audit keeps of one run in time (the item file of
/// `anm audit --item K`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TimeRunRecord {
    #[serde(with = "exact_rows")]
    pub history: Vec<Vec<f64>>,
    pub stop: String,
    pub steps: usize,
    pub factorizations: usize,
    #[serde(with = "exact")]
    pub max_residual: f64,
    #[serde(with = "exact")]
    pub wall_s: f64,
    /// The run's notes (sticking friction, cut ramps ...): the audit
    /// shows them under its table (review 13: an idler's omega sweep
    /// ranked the runs against the one farthest from physics, and none of
    /// the runs' notes on the friction left from the ramp reached it).
    #[serde(default)]
    pub notes: Vec<String>,
    /// The diagnosis of a stop before t_end (review 19: the audit showed
    /// an empty message for runs stopped by numerical trouble).
    #[serde(default)]
    pub stop_message: Option<String>,
    /// The time the run stopped (t_end at the end): on a breakaway scene
    /// the answer itself (review 18: every audit row was NaN there).
    #[serde(default)]
    pub stop_t: Option<f64>,
}

/// One item: a parameter value and its run, or the error that stopped it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TimeAuditItem {
    pub parameter: String,
    #[serde(with = "exact")]
    pub value: f64,
    pub outcome: std::result::Result<TimeRunRecord, String>,
}

/// One row of the table.
#[derive(Clone, Debug)]
pub struct TimeAuditRow {
    pub parameter: String,
    pub value: f64,
    /// "end", "singularity", or "error" (the message says why).
    pub stop: String,
    /// When the run stopped (NaN for an error before any step).
    pub t_stop: f64,
    pub message: Option<String>,
    /// The key probe and rn_total at t_end (NaN if not reached).
    pub key: f64,
    pub key_deviation: f64,
    pub contact: f64,
    pub contact_deviation: f64,
    /// The slip zone at t_end: the tributary area of the slipping friction
    /// nodes (history.csv's slip_area, m²), and its deviation.
    pub slip_area: f64,
    pub slip_area_deviation: f64,
    /// max over the output times of |key − key_ref| / max |key_ref|.
    pub trajectory_deviation: f64,
    pub reference: String,
    pub steps: usize,
    pub factorizations: usize,
    pub max_residual: f64,
    pub wall_s: f64,
}

/// Applies one value to a copy of the scene: omega and zeta on the friction
/// law, eta and penalty (K) on the normal law (with its own checks).
pub fn with_parameter(scene: &ShellScene, parameter: &str, value: f64) -> Result<ShellScene> {
    let bad = |problem: String| Error::Invalid {
        file: scene.file.clone(),
        key: format!("--{parameter}"),
        problem,
    };
    if parameter == "eta" && value == 0.0 {
        // As `anm check` says it (review 13: the audit's help calls 0 the
        // penalty law, which holds for frictionless scenes only).
        return Err(bad(
            "0 (the penalty law) is for frictionless scenes: with [friction], contact.eta must be > 0".into(),
        ));
    }
    if !(value.is_finite() && value > 0.0) {
        return Err(bad(format!("values must be finite and > 0, got {value}")));
    }
    match parameter {
        "omega" | "zeta" => {
            let mut s = scene.clone();
            let fr = s
                .friction
                .as_mut()
                .ok_or_else(|| bad("the scene has no [friction]".into()))?;
            if parameter == "omega" {
                fr.law.omega = value;
            } else {
                fr.law.zeta = Some(value);
            }
            Ok(s)
        }
        _ => super::shell_audit::with_parameter(scene, parameter, value),
    }
}

/// The items of the sweep, in order (omega, zeta, eta, K values); every
/// value is validated before any run.
pub fn jobs(scene: &ShellScene, sweeps: &Sweeps) -> Result<Vec<(&'static str, f64, ShellScene)>> {
    let mut jobs = vec![];
    for (name, values) in [
        ("omega", &sweeps.omega),
        ("zeta", &sweeps.zeta),
        ("eta", &sweeps.eta),
        ("penalty", &sweeps.penalty),
    ] {
        for &v in values {
            jobs.push((name, v, with_parameter(scene, name, v)?));
        }
    }
    Ok(jobs)
}

/// Runs one item (an error or a panic becomes a recorded failure).
pub fn run_item(parameter: &str, value: f64, scene: &ShellScene) -> TimeAuditItem {
    let outcome = match sweep::catch(|| shell_time::run(scene, None)) {
        Ok(Ok(r)) => Ok(TimeRunRecord {
            history: r.history,
            stop: r.stop.reason,
            steps: r.steps,
            factorizations: r.factorizations,
            max_residual: r.max_residual,
            wall_s: r.wall_s,
            notes: r.notes,
            stop_message: r.stop.message.map(|m| match r.stop.t {
                Some(t) => format!("stop at t = {t:e} s: {m}"),
                None => m,
            }),
            stop_t: r.stop.t,
        }),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(format!("panicked: {panic}")),
    };
    TimeAuditItem {
        parameter: parameter.to_string(),
        value,
        outcome,
    }
}

/// Columns of the key probe (the first), rn_total and slip_area in
/// history.csv of a run in time (t, lambda, the probes, rn_total, ft_x,
/// ft_y, ft_z, max_slip, slip_area).
fn columns(scene: &ShellScene) -> (usize, usize, usize) {
    (2, 2 + scene.probes.len(), 7 + scene.probes.len())
}

/// The rows from the items' results, in sweep order.
pub fn rows(scene: &ShellScene, items: &[TimeAuditItem]) -> Vec<TimeAuditRow> {
    let (key_col, contact_col, slip_col) = columns(scene);
    let t_end = scene.friction.as_ref().map_or(f64::NAN, |f| f.t_end);
    let mut rows = vec![];
    for name in ["omega", "zeta", "eta", "penalty"] {
        let group: Vec<&TimeAuditItem> = items.iter().filter(|it| it.parameter == name).collect();
        if group.is_empty() {
            continue;
        }
        // The least regularized run that reached t_end.
        let reference = group
            .iter()
            .filter(|it| matches!(&it.outcome, Ok(r) if r.stop == "end"))
            .min_by(|a, b| {
                if name == "penalty" {
                    b.value.total_cmp(&a.value)
                } else {
                    a.value.total_cmp(&b.value)
                }
            });
        let at_end = |r: &TimeRunRecord, col: usize| {
            r.history
                .last()
                .filter(|row| (row[0] - t_end).abs() <= 1e-9 * t_end.abs().max(1.0))
                .map_or(f64::NAN, |row| row[col])
        };
        let (ref_record, ref_label) = match reference {
            Some(it) => (
                it.outcome.as_ref().ok(),
                format!("run with {}", label(name, it.value)),
            ),
            None => (None, "none (no run reached t_end)".to_string()),
        };
        let (key_ref, contact_ref, slip_ref) =
            ref_record.map_or((f64::NAN, f64::NAN, f64::NAN), |r| {
                (
                    at_end(r, key_col),
                    at_end(r, contact_col),
                    at_end(r, slip_col),
                )
            });
        for it in group {
            let row = match &it.outcome {
                Ok(r) => {
                    let (key, contact, slip) = (
                        at_end(r, key_col),
                        at_end(r, contact_col),
                        at_end(r, slip_col),
                    );
                    // A run that stopped before t_end has no trajectory
                    // to compare (review 19: its t = 0 row alone gave 0).
                    let trajectory = ref_record
                        .filter(|_| r.stop == "end")
                        .map_or(f64::NAN, |rr| {
                            super::shell_audit::grid_deviation(&r.history, &rr.history, key_col)
                        });
                    TimeAuditRow {
                        parameter: name.to_string(),
                        value: it.value,
                        stop: r.stop.clone(),
                        t_stop: r.stop_t.unwrap_or(f64::NAN),
                        message: {
                            let parts: Vec<String> =
                                r.stop_message.iter().chain(&r.notes).cloned().collect();
                            (!parts.is_empty()).then(|| parts.join("; "))
                        },
                        key,
                        key_deviation: deviation(key, key_ref),
                        contact,
                        contact_deviation: deviation(contact, contact_ref),
                        slip_area: slip,
                        slip_area_deviation: deviation(slip, slip_ref),
                        trajectory_deviation: trajectory,
                        reference: ref_label.clone(),
                        steps: r.steps,
                        factorizations: r.factorizations,
                        max_residual: r.max_residual,
                        wall_s: r.wall_s,
                    }
                }
                Err(e) => TimeAuditRow {
                    parameter: name.to_string(),
                    value: it.value,
                    stop: "error".into(),
                    t_stop: f64::NAN,
                    message: Some(e.clone()),
                    key: f64::NAN,
                    key_deviation: f64::NAN,
                    contact: f64::NAN,
                    contact_deviation: f64::NAN,
                    slip_area: f64::NAN,
                    slip_area_deviation: f64::NAN,
                    trajectory_deviation: f64::NAN,
                    reference: ref_label.clone(),
                    steps: 0,
                    factorizations: 0,
                    max_residual: f64::NAN,
                    wall_s: f64::NAN,
                },
            };
            rows.push(row);
        }
    }
    rows
}

/// The key probe's name.
fn key_name(scene: &ShellScene) -> String {
    scene
        .probes
        .first()
        .map_or("key".into(), |p| p.name.clone())
}

/// The table as Markdown; the runs that stopped are listed below it.
pub fn markdown(scene: &ShellScene, rows: &[TimeAuditRow]) -> String {
    let key = key_name(scene);
    let (law, t_end) = scene
        .friction
        .as_ref()
        .map_or((None, f64::NAN), |f| (Some(f.law), f.t_end));
    let mut s = format!(
        "Regularization audit in time of `{}` (scene omega = {:e}, zeta = {}; deviations from the least regularized run of each sweep that reached t_end)\n\n",
        scene.file.display(),
        law.map_or(f64::NAN, |l| l.omega),
        law.and_then(|l| l.zeta)
            .map_or("none".into(), |z| format!("{z:e} N")),
    );
    s += &format!(
        "| parameter | value | stop | t_stop (s) | {key}({t_end}) | deviation | rn_total({t_end}) (N) | deviation | slip_area({t_end}) (m²) | deviation | trajectory deviation | steps | factorizations | max residual | wall (s) | reference |\n"
    );
    s += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        s += &format!(
            "| {} | {:e} | {} | {:.9e} | {:.9e} | {:.2e} | {:.9e} | {:.2e} | {:.6e} | {:.2e} | {:.2e} | {} | {} | {:.1e} | {:.3} | {} |\n",
            r.parameter,
            r.value,
            r.stop,
            r.t_stop,
            r.key,
            r.key_deviation,
            r.contact,
            r.contact_deviation,
            r.slip_area,
            r.slip_area_deviation,
            r.trajectory_deviation,
            r.steps,
            r.factorizations,
            r.max_residual,
            r.wall_s,
            r.reference
        );
    }
    for r in rows.iter().filter(|r| r.message.is_some()) {
        s += &format!(
            "\n{} = {:e}: {}\n",
            r.parameter,
            r.value,
            r.message.as_deref().unwrap_or_default()
        );
    }
    s
}

/// Writes audit.md, audit.csv and audit.svg into `dir`.
pub fn write(scene: &ShellScene, rows: &[TimeAuditRow], dir: &Path) -> Result<()> {
    create_dir(dir)?;
    let md = dir.join("audit.md");
    std::fs::write(&md, markdown(scene, rows)).map_err(|source| Error::Io {
        file: md.clone(),
        source,
    })?;
    let file = dir.join("audit.csv");
    let fail = |e: csv::Error| Error::Write {
        file: file.clone(),
        problem: e.to_string(),
    };
    let mut w = csv::Writer::from_path(&file).map_err(fail)?;
    w.write_record([
        "parameter",
        "value",
        "stop",
        "t_stop",
        "key",
        "key_deviation",
        "rn_total",
        "rn_total_deviation",
        "slip_area",
        "slip_area_deviation",
        "trajectory_deviation",
        "steps",
        "factorizations",
        "max_residual",
        "wall_s",
        "message",
    ])
    .map_err(fail)?;
    for r in rows {
        w.write_record([
            r.parameter.clone(),
            format!("{:e}", r.value),
            r.stop.clone(),
            format!("{:e}", r.t_stop),
            format!("{:e}", r.key),
            format!("{:e}", r.key_deviation),
            format!("{:e}", r.contact),
            format!("{:e}", r.contact_deviation),
            format!("{:e}", r.slip_area),
            format!("{:e}", r.slip_area_deviation),
            format!("{:e}", r.trajectory_deviation),
            r.steps.to_string(),
            r.factorizations.to_string(),
            format!("{:e}", r.max_residual),
            format!("{:e}", r.wall_s),
            r.message.clone().unwrap_or_default(),
        ])
        .map_err(fail)?;
    }
    w.flush().map_err(|source| Error::Io {
        file: file.clone(),
        source,
    })?;
    plot(scene, rows, &dir.join("audit.svg"))
}

/// audit.svg: per swept parameter, the deviations at t_end and over the
/// trajectory, and the steps and factorizations, against its value (runs
/// that did not reach t_end left out).
fn plot(scene: &ShellScene, rows: &[TimeAuditRow], path: &Path) -> Result<()> {
    use crate::output::plot::{Curve, draw};
    let stem = scene
        .file
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let key = key_name(scene);
    let labels = [
        format!("{key}(t_end)"),
        "rn_total(t_end)".to_string(),
        "slip_area(t_end)".to_string(),
        format!("{key} trajectory (max over t)"),
        "steps".to_string(),
        "factorizations".to_string(),
    ];
    let swept: Vec<(&str, String, String, String)> = ["omega", "zeta", "eta", "penalty"]
        .into_iter()
        .filter(|p| rows.iter().any(|r| r.parameter == *p))
        .map(|p| {
            let unit = match p {
                "omega" => "omega (-)".to_string(),
                "penalty" => format!("K ({}/{})", scene.units.force, scene.units.length),
                other => format!("{other} ({})", scene.units.force),
            };
            (
                p,
                format!("{stem}: deviation from the least regularized run, {p} swept"),
                format!("{stem}: cost, {p} swept"),
                unit,
            )
        })
        .collect();
    let mut panels = vec![];
    for (p, dev_title, cost_title, unit) in &swept {
        let curve = |k: usize, f: &dyn Fn(&TimeAuditRow) -> f64| Curve {
            label: &labels[k],
            points: rows
                .iter()
                .filter(|r| r.parameter == *p && r.stop != "error")
                .map(|r| (r.value, f(r)))
                .filter(|(_, y)| y.is_finite())
                .collect(),
        };
        panels.extend(super::shell_audit::swept_panels(
            (dev_title, cost_title),
            unit,
            vec![
                curve(0, &|r| r.key_deviation),
                curve(1, &|r| r.contact_deviation),
                curve(2, &|r| r.slip_area_deviation),
                curve(3, &|r| r.trajectory_deviation),
            ],
            vec![
                curve(4, &|r| r.steps as f64),
                curve(5, &|r| r.factorizations as f64),
            ],
        ));
    }
    if panels.is_empty() {
        return Ok(());
    }
    draw(path, &panels)
}

/// The audit in time as a sweep (`anm audit` on a shell scene with
/// `[friction]`): one item per value; the merge writes audit.md, audit.csv.
pub struct TimeAudit {
    pub scene: ShellScene,
    jobs: Vec<(&'static str, f64, ShellScene)>,
}

impl TimeAudit {
    /// Validates every value; an error when there is nothing to sweep or
    /// no probe to audit.
    pub fn new(scene: ShellScene, sweeps: &Sweeps) -> Result<Self> {
        let jobs = jobs(&scene, sweeps)?;
        let invalid = |problem: &str| Error::Invalid {
            file: scene.file.clone(),
            key: "audit".into(),
            problem: problem.into(),
        };
        if jobs.is_empty() {
            return Err(invalid(
                "nothing to sweep: give at least one of --omega, --zeta, --eta, --penalty",
            ));
        }
        if scene.probes.is_empty() {
            return Err(invalid(
                "the audit needs at least one [[probe]] (the first is the key output)",
            ));
        }
        Ok(TimeAudit { scene, jobs })
    }
}

impl Sweep for TimeAudit {
    fn labels(&self) -> Vec<String> {
        self.jobs.iter().map(|(n, v, _)| label(n, *v)).collect()
    }
    fn inputs(&self) -> Vec<PathBuf> {
        sweep::scene_inputs(&self.scene)
    }
    fn run_item(&self, k: usize, _dir: Option<&Path>) -> Result<serde_json::Value> {
        let (name, v, s) = &self.jobs[k];
        sweep::encode(&run_item(name, *v, s))
    }
    fn merge(&self, items: &[serde_json::Value], dir: Option<&Path>) -> Result<Merged> {
        let items: Vec<TimeAuditItem> = sweep::decode_all(items)?;
        let rows = rows(&self.scene, &items);
        if let Some(dir) = dir {
            write(&self.scene, &rows, dir)?;
        }
        Ok(Merged {
            markdown: markdown(&self.scene, &rows),
            failed: false,
        })
    }
}

/// |a − b| / |b|; |a − b| where the reference b is 0 (review 13: an idler's
/// slip area, 0 in every run, gave 0/0 = NaN in audit.md and audit.csv;
/// review 26: the point-mass audit's division by a zero reference gave
/// 1.04e308).
pub(crate) fn deviation(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        (a - b).abs()
    } else {
        (a - b).abs() / b.abs()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_zero_reference_gives_the_absolute_deviation() {
        assert_eq!(super::deviation(0.0, 0.0), 0.0);
        assert_eq!(super::deviation(0.25, 0.0), 0.25);
        assert_eq!(super::deviation(1.5, 2.0), 0.25);
    }
}

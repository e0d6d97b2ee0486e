//! Runs a friction scene with the Taylor DAE engine and writes its outputs:
//! history.csv on the scene's uniform time grid (evaluated from the series,
//! not interpolated), steps.csv at the step ends, summary.json, history.svg.

use super::friction::{FrictionModel, build};
use crate::error::Result;
use crate::output::plot::{Curve, Panel, draw};
use crate::output::{CsvStream, Stop, create_dir, write_json};
use crate::scene::friction::{FrictionScene, InitMode};
use crate::series::Stats;
use crate::series::dae::{self, DaeConfig, Initialization};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Everything a friction run produced.
#[derive(Debug)]
pub struct FrictionRun {
    pub scene: String,
    pub kind: String,
    pub columns: Vec<String>,
    /// Rows on the output grid (up to the stop).
    pub history: Vec<Vec<f64>>,
    /// Step ends: step, t, h (length), end residual, slip velocity,
    /// geometric-series distance (0: none), the history columns, then 1 for
    /// an implicit step (0: explicit).
    pub steps: Vec<Vec<f64>>,
    pub order: usize,
    pub eps: f64,
    pub init: String,
    /// |F| at the initial point actually used.
    pub initial_residual: f64,
    pub stats: Stats,
    pub wall_s: f64,
    pub stop: Stop,
    /// For a singular stop: the located singular point (geometric-series
    /// test), or where the step lengths extrapolate to zero
    /// (a_k ≈ c (t* - t_k) fitted on the last steps).
    pub t_singular_estimate: Option<f64>,
    /// Steps whose series revealed a singular point: (t0, located t*).
    pub singular_events: Vec<(f64, f64)>,
    /// The accepted steps' series (u, v, z), for checks and dense output.
    pub series: Vec<crate::series::TimeStep>,
    /// `solver.time_step` and what the implicit steps cost.
    pub time_step: &'static str,
    pub implicit: crate::series::dae::ImplicitCounts,
}

/// The regularization omega from which [`start_in_omega`] continues.
const OMEGA_START: f64 = 1.0;
/// Its stages: omega divided by this factor per stage.
const OMEGA_FACTOR: f64 = 3.0;

/// The starting guess of the Newton initialization, continued in omega where
/// Newton does not converge from it at the scene's omega. A steep law (q
/// below 1, small omega: |v_s|^(q-1) with |v_s| ~ omega Vc) leaves damped
/// Newton in a minimum of |F| that is not a root (friction-plane, zeta =
/// omega = 1e-2, q = 0.5: |F| = 2.0e-3 after 100 iterations). From omega =
/// `OMEGA_START`, where the law is smooth, each stage solves at omega /
/// `OMEGA_FACTOR` from the last stage's root, down to the scene's omega;
/// the run's own Newton then starts from that root. Returns the root at
/// the scene's omega (0 stages) where Newton converges from the guess, and
/// the guess unchanged where a stage fails (the run then reports its own
/// failure).
fn start_in_omega(
    scene: &FrictionScene,
    model: &dyn FrictionModel,
    v: Vec<f64>,
    z: Vec<f64>,
) -> (Vec<f64>, Vec<f64>, usize) {
    let u0 = model.u0();
    let nd = v.len();
    let solve = |m: &dyn FrictionModel, vz: &mut Vec<f64>| {
        dae::consistent(m, &u0, vz, 0.0, scene.newton_tol).is_ok()
    };
    // Solved at the scene's omega: its root (the run's Newton, the same
    // iteration, then stops at once).
    let mut vz = [v.clone(), z.clone()].concat();
    if solve(model, &mut vz) {
        return (vz[..nd].to_vec(), vz[nd..].to_vec(), 0);
    }
    if scene.friction.omega >= OMEGA_START {
        return (v, z, 0);
    }
    let mut vz = [v.clone(), z.clone()].concat();
    let mut omega = OMEGA_START;
    let mut stages = 0;
    loop {
        let mut at = scene.clone();
        at.friction.omega = omega;
        if !solve(build(&at).as_ref(), &mut vz) {
            return (v, z, 0);
        }
        stages += 1;
        if omega <= scene.friction.omega {
            return (vz[..nd].to_vec(), vz[nd..].to_vec(), stages);
        }
        omega = (omega / OMEGA_FACTOR).max(scene.friction.omega);
    }
}

/// Speeds above this multiple of the scene's speed scale
/// ([`FrictionScene::speed_scale`]) are a jump, not a quasi-static motion
/// (`DaeConfig::speed_limit`). Measured: quasi-static runs stay below 3
/// times the scale; friction-roller's jumps past its breakdown reach
/// 110–15,965 times it (review 12).
pub const JUMP: f64 = 30.0;

/// The run's start: its initial values (Newton from the guess, through
/// omega stages where needed, or the exact ones, checked), a note on how
/// they were found, and the series' settings.
fn start(
    scene: &FrictionScene,
    model: &dyn FrictionModel,
) -> Result<(Initialization, String, DaeConfig)> {
    let mut init_note = format!("{:?}", scene.init).to_lowercase();
    let init = match scene.init {
        InitMode::Newton => {
            let (mut v, z) = model.guess();
            if let Some(v0) = scene.v0 {
                v = model.exact_start(v0).0;
            }
            let (v, z, stages) = start_in_omega(scene, model, v, z);
            if stages > 0 {
                init_note = format!("newton, from omega = {OMEGA_START} in {stages} stages");
            }
            Initialization::Newton { v, z }
        }
        InitMode::Exact => {
            let (v, z) = model.exact_start(scene.v0.expect("validated: exact mode has v0"));
            Initialization::Exact { v, z }
        }
    };
    let cfg = DaeConfig {
        order: scene.order,
        eps: scene.eps,
        t0: 0.0,
        t_end: scene.t_end,
        max_steps: scene.max_steps,
        newton_tol: scene.newton_tol,
        correct: scene.correct,
        residual_tol: scene.residual_tol,
        min_step: scene.min_step,
        stop_at_singularity: scene.stop_at_singularity,
        stepping: scene.stepping,
        output_times: scene.output_times(),
        speed_limit: JUMP * scene.speed_scale(),
    };
    if let Initialization::Exact { .. } = &init {
        // "exact" values are checked before anything is written: a wrong
        // v0 ran to the end with every row off equilibrium (review 3, D1).
        let none = DaeConfig {
            max_steps: 0,
            output_times: vec![],
            ..cfg.clone()
        };
        let r0 = dae::run(model, &model.u0(), &init, &none, |_, _| Ok(())).initial_residual;
        if !(r0 <= scene.residual_tol) {
            return Err(crate::Error::Invalid {
                file: scene.file.clone(),
                key: "initial.v0".into(),
                problem: format!(
                    "initial.mode = \"exact\" but the initial values leave a residual of {r0:.3e} (solver.residual_tol = {:.1e}): give the exact v0, or use mode = \"newton\"",
                    scene.residual_tol
                ),
            });
        }
    }
    Ok((init, init_note, cfg))
}

/// `anm check` of a point-mass scene: its start (initial values, checked
/// as a run checks them) and its first step, without output.
pub fn check_start(scene: &FrictionScene) -> Result<()> {
    let model = build(scene);
    let model: &dyn FrictionModel = model.as_ref();
    let (init, _, cfg) = start(scene, model)?;
    let first = DaeConfig {
        max_steps: 1,
        output_times: vec![],
        ..cfg
    };
    match dae::run(model, &model.u0(), &init, &first, |_, _| Ok(())).error {
        Some(crate::Error::StepCollapse { length, .. }) => Err(crate::Error::Invalid {
            file: scene.file.clone(),
            key: "solver.min_step".into(),
            problem: first_step_below_floor(length, scene.min_step),
        }),
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The diagnosis of a first step shorter than the step floor (no shrinking
/// steps lead there: not a singular point).
fn first_step_below_floor(length: f64, min_step: f64) -> String {
    format!(
        "the first step's series reaches only {length:.3e} s, below solver.min_step = {min_step:.3e} s (1e-13 t_end unless given): the scene's fastest time scale lies below it; lower solver.min_step or t_end"
    )
}

/// Solves the scene; writes the outputs into `out_dir` when given.
pub fn run(scene: &FrictionScene, out_dir: Option<&Path>, progress: bool) -> Result<FrictionRun> {
    let model = build(scene);
    let model: &dyn FrictionModel = model.as_ref();
    let start_time = Instant::now();
    let (init, init_note, cfg) = start(scene, model)?;
    let grid = scene.output_times();
    let mut next = 0;
    let mut history = Vec::with_capacity(grid.len());
    let mut steps = Vec::new();
    let mut series = Vec::new();
    let bar = progress_bar(progress, scene.t_end);
    // history.csv and steps.csv are streamed: a stopped run keeps its rows.
    let mut streams = match out_dir {
        Some(dir) => {
            create_dir(dir)?;
            Some((
                CsvStream::create(&dir.join("history.csv"), model.columns())?,
                CsvStream::create(&dir.join("steps.csv"), &step_columns(model))?.with_ids(1),
            ))
        }
        None => None,
    };
    let result = dae::run(model, &model.u0(), &init, &cfg, |step, stats| {
        let t1 = step.t0 + step.length;
        while next < grid.len() && grid[next] <= t1 + 1e-12 * scene.t_end {
            let tg = grid[next];
            let row = model.row(tg, &step.eval(tg), &derivative(&step, tg));
            if let Some((h, _)) = &mut streams {
                h.row(&row)?;
            }
            history.push(row);
            next += 1;
        }
        let y = step.eval(t1);
        let mut row = vec![
            // 1-based, as the shell runs' steps.csv (review 7).
            (step.index + 1) as f64,
            t1,
            step.length,
            step.end_residual,
            model.slip(&y),
            step.geometric.unwrap_or(0.0),
        ];
        row.extend(
            model
                .row(t1, &y, &derivative(&step, t1))
                .into_iter()
                .skip(1),
        );
        row.push(f64::from(u8::from(step.implicit)));
        if let Some((_, s)) = &mut streams {
            s.row(&row)?;
        }
        steps.push(row);
        if let Some(b) = &bar {
            b.set_position((1000.0 * t1 / scene.t_end) as u64);
            b.set_message(format!(
                "t = {t1:.4} s, step {}, h = {:.2e}",
                stats.steps, step.length
            ));
        }
        // The other root of eq. (3): the mass through the obstacle (IDA
        // stops there too, `off_branch`).
        if let Some(g) = model.contact_branch(&y)
            && !(g > 0.0)
        {
            return Err(crate::Error::OffPath {
                step: step.index + 1,
                param: "t",
                at: t1,
                what: format!(
                    "the solution left the contact law's physical root: 2 R_N / K + h = {g:.3e} <= 0 with R_N = {:.3e} N, the mass through the obstacle (a root of eq. 3 that is not the contact); contact.eta = {:e} is below what the arithmetic resolves against K delta^2 = {:.3e}: raise contact.eta",
                    y[3],
                    scene.contact.map_or(f64::NAN, |c| c.eta),
                    scene.contact.map_or(f64::NAN, |c| c.k * c.delta * c.delta),
                ),
            });
        }
        series.push(step);
        // Ctrl-C or SIGTERM: stop at this step end (no resume for the DAE).
        if crate::run::interrupt::requested() {
            return Err(crate::Error::Interrupted { param: "t", at: t1 });
        }
        Ok(())
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let wall_s = start_time.elapsed().as_secs_f64();
    let t_singular_estimate = match result.stop.as_str() {
        "singularity" => result
            .t_singular
            .or_else(|| extrapolate_singularity(&steps)),
        _ => None,
    };
    let stop = Stop {
        reason: result.stop.clone(),
        t: Some(result.t),
        lambda: None,
        node: None,
        message: match (&result.error, result.stop.as_str()) {
            (Some(crate::Error::StepCollapse { length, .. }), _) if result.stats.steps == 0 => {
                Some(first_step_below_floor(*length, scene.min_step))
            }
            (Some(e), _) => Some(e.to_string()),
            (None, "singularity") => Some(match (result.jump, result.t_singular) {
                (Some((at, speed)), None) => format!(
                    "the path leaves the quasi-static regime after t = {:.9} s: a speed of {speed:.3e} m/s at t = {at:.9} s, {:.0} times the scene's speed scale {:.3e} m/s (the largest of Vc, the obstacle's speed and the load rate over k), is the regularized dynamics jumping across the end of the quasi-static solution",
                    result.t,
                    speed / scene.speed_scale(),
                    scene.speed_scale(),
                ),
                (Some((at, speed)), Some(ts)) => format!(
                    "at t = {:.9} s the series became geometric (Cochelin-Medale test): a singular point at t* = {ts:.9} s ends the smooth quasi-static solution (followed on without output, the path jumps: {speed:.3e} m/s at t = {at:.9} s, {:.0} times the scene's speed scale {:.3e} m/s)",
                    result.t,
                    speed / scene.speed_scale(),
                    scene.speed_scale(),
                ),
                (None, Some(ts)) => format!(
                    "at t = {:.9} s the series became geometric (Cochelin-Medale test): a singular point at t* = {ts:.9} s ends the smooth quasi-static solution{}",
                    result.t,
                    match result.collapse_ahead {
                        Some(at) => format!(
                            " (followed on without output to see whether it gets past the point, the path's step fell below solver.min_step = {:.3e} s at t = {at:.9} s)",
                            scene.min_step
                        ),
                        None => String::new(),
                    }
                ),
                (None, None) => format!(
                    "the series step length fell below solver.min_step = {:.3e} s at t = {:.9} s: the solution stops being smooth there",
                    scene.min_step, result.t
                ),
            }),
            (None, "max_steps") => Some(format!(
                "solver.max_steps = {} reached at t = {}",
                scene.max_steps, result.t
            )),
            _ => None,
        },
    };
    let run = FrictionRun {
        scene: scene.file.display().to_string(),
        kind: scene.kind.name().into(),
        columns: model.columns().iter().map(|s| s.to_string()).collect(),
        history,
        steps,
        order: scene.order,
        eps: scene.eps,
        init: init_note,
        initial_residual: result.initial_residual,
        stats: result.stats,
        wall_s,
        stop,
        t_singular_estimate,
        singular_events: result.events.clone(),
        series,
        time_step: scene.stepping.name(),
        implicit: result.implicit,
    };
    if let Some(dir) = out_dir {
        write_outputs(&run, model, scene, dir)?;
    }
    Ok(run)
}

/// dy/dt of every series of the step at time t.
fn derivative(step: &crate::series::TimeStep, t: f64) -> Vec<f64> {
    step.eval_derivative(t)
}

/// Fits a_k = c (t* - t_k) on the last five steps (least squares on a vs t)
/// and returns t*, when the step lengths are indeed decreasing.
fn extrapolate_singularity(steps: &[Vec<f64>]) -> Option<f64> {
    let tail: Vec<(f64, f64)> = steps
        .iter()
        .rev()
        .take(5)
        .map(|r| (r[1] - r[2], r[2]))
        .collect();
    if tail.len() < 3 {
        return None;
    }
    let n = tail.len() as f64;
    let (st, sa) = tail
        .iter()
        .fold((0.0, 0.0), |(x, y), (t, a)| (x + t, y + a));
    let (mt, ma) = (st / n, sa / n);
    let (sxy, sxx) = tail.iter().fold((0.0, 0.0), |(xy, xx), (t, a)| {
        (xy + (t - mt) * (a - ma), xx + (t - mt).powi(2))
    });
    let slope = sxy / sxx;
    (slope < 0.0).then(|| mt - ma / slope)
}

fn progress_bar(show: bool, t_end: f64) -> Option<indicatif::ProgressBar> {
    if !show {
        return None;
    }
    let bar = crate::output::progress_bar();
    bar.set_message(format!("t = 0 / {t_end} s"));
    Some(bar)
}

/// Columns of steps.csv.
fn step_columns(model: &dyn FrictionModel) -> Vec<&'static str> {
    let mut cols = vec![
        "step",
        "t",
        "h",
        "end_residual",
        "slip",
        "geometric_distance",
    ];
    cols.extend(model.columns().iter().skip(1));
    cols.push("implicit");
    cols
}

/// summary.json and the plot (history.csv and steps.csv are streamed).
fn write_outputs(
    run: &FrictionRun,
    model: &dyn FrictionModel,
    scene: &FrictionScene,
    dir: &Path,
) -> Result<()> {
    let cols = model.columns();
    write_json(&dir.join("summary.json"), &Summary::from(run))?;
    if scene.plot && !run.history.is_empty() && run.stop.reason != "interrupted" {
        plot(run, cols, &dir.join("history.svg"))?;
    }
    Ok(())
}

/// summary.json: the counters at the top level, the common counters of
/// every time run ([`crate::reference::counters`], also written by `anm
/// reference ida|diffsol`), then the run's settings.
#[derive(Serialize)]
struct Summary<'a> {
    tool: &'static str,
    method: &'static str,
    counters: crate::reference::counters::Counters,
    steps: usize,
    factorizations: usize,
    solves: usize,
    wall_s: f64,
    stop: &'a Stop,
    /// The columns of history.csv at its last row (as in every run's
    /// summary.json).
    end: indexmap::IndexMap<&'a str, f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    t_singular_estimate: Option<f64>,
    /// (t0, t*) of every step whose series was geometric.
    singular_events: &'a [(f64, f64)],
    scene: &'a str,
    kind: &'a str,
    columns: &'a [String],
    order: usize,
    eps: f64,
    /// `solver.time_step`, and the implicit steps among `steps`.
    time_step: &'a str,
    implicit: crate::series::dae::ImplicitCounts,
    init: &'a str,
    initial_residual: f64,
    output_rows: usize,
    stats: &'a Stats,
}

impl<'a> From<&'a FrictionRun> for Summary<'a> {
    fn from(run: &'a FrictionRun) -> Self {
        Self {
            tool: "anm",
            method: "anm",
            counters: crate::reference::counters::Counters::from_anm(&run.stats),
            steps: run.stats.steps,
            factorizations: run.stats.factorizations,
            solves: run.stats.solves,
            wall_s: run.wall_s,
            stop: &run.stop,
            end: run
                .columns
                .iter()
                .map(String::as_str)
                .zip(run.history.last().into_iter().flatten().map(|x| x + 0.0))
                .collect(),
            t_singular_estimate: run.t_singular_estimate,
            singular_events: &run.singular_events,
            scene: &run.scene,
            kind: &run.kind,
            columns: &run.columns,
            order: run.order,
            eps: run.eps,
            time_step: run.time_step,
            implicit: run.implicit,
            init: &run.init,
            initial_residual: run.initial_residual,
            output_rows: run.history.len(),
            stats: &run.stats,
        }
    }
}

fn plot(run: &FrictionRun, cols: &[&str], path: &Path) -> Result<()> {
    let col = |name: &str| cols.iter().position(|c| *c == name);
    let series = |name: &str| -> Vec<(f64, f64)> {
        let j = col(name).expect("column exists");
        run.history.iter().map(|r| (r[0], r[j])).collect()
    };
    let title = format!(
        "{} — stop: {} at t = {:.4} s",
        run.kind,
        run.stop.reason,
        run.stop.t.unwrap_or(f64::NAN)
    );
    let mut panels = Vec::new();
    if col("u").is_some() {
        panels.push(Panel {
            title: &title,
            x_label: "t (s)",
            y_label: "u (m)",
            curves: vec![Curve {
                label: "u",
                points: series("u"),
            }],
            log: (false, false),
        });
        panels.push(Panel {
            title: "velocity and friction force",
            x_label: "t (s)",
            y_label: "v (m/s), R_T (N)",
            curves: vec![
                Curve {
                    label: "v",
                    points: series("v"),
                },
                Curve {
                    label: "R_T",
                    points: series("rt"),
                },
            ],
            log: (false, false),
        });
    } else {
        let traj: Vec<(f64, f64)> = run.history.iter().map(|r| (r[1], r[2])).collect();
        panels.push(Panel {
            title: &title,
            x_label: "t (s)",
            y_label: "u (m)",
            curves: vec![
                Curve {
                    label: "u_x",
                    points: series("ux"),
                },
                Curve {
                    label: "u_y",
                    points: series("uy"),
                },
            ],
            log: (false, false),
        });
        panels.push(Panel {
            title: "trajectory of the mass",
            x_label: "u_x (m)",
            y_label: "u_y (m)",
            curves: vec![Curve {
                label: "(u_x, u_y)",
                points: traj,
            }],
            log: (false, false),
        });
        panels.push(Panel {
            title: "contact reactions",
            x_label: "t (s)",
            y_label: "R (N)",
            curves: vec![
                Curve {
                    label: "R_N",
                    points: series("rn"),
                },
                Curve {
                    label: "R_T",
                    points: series("rt"),
                },
            ],
            log: (false, false),
        });
    }
    draw(path, &panels)
}

//! The run loop of a shell scene: the ANM stepper driven step by step (or the
//! Newton-Raphson baseline, or one linear solve), each accepted step handed to
//! the [`Recorder`]: output grid points evaluated from the step's series and
//! held to the residual test (corrected at fixed lambda when above it), VTK
//! every `output.vtk_every` steps, a checkpoint. Ctrl-C or SIGTERM ends the
//! run at the next step end; `--resume` continues from the checkpoint.

use super::build::build_model;
use super::interrupt;
use super::probe::State;
pub use super::recorder::Snapshot;
use super::recorder::{EventRecord, Recorder, RecorderState, StepRow};
use crate::contact::{Obstacle, search};
use crate::error::{Error, Result};
use crate::linalg::LinearSolver;
use crate::output::plot::{Curve, Panel, draw};
use crate::output::vtk::{cylinder_surface, revolved_surface, write_pvd, write_vtu};
use crate::output::{Stop, write_csv_ids, write_json};
use crate::run::{penetration, regularization};
use crate::scene::shell::{Branch, Method, ShellScene, load};
use crate::series::bifurcation::{self, Event};
use crate::series::correct::Metric;
use crate::series::path::{Checkpoint, Path as AnmPath};
use crate::series::stop::Stop as PathStop;
use crate::series::{ContinuationProblem, PathStep, Stats, correct};
use crate::shell::ShellModel;
use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Summary of a run (summary.json).
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub scene: String,
    /// `scene.description`, to tell runs apart (review 23: documented as
    /// shown in outputs, it was in none).
    pub description: Option<String>,
    /// The scene's kind ("shell"), as every summary.json has it.
    pub kind: &'static str,
    pub mesh: String,
    pub nodes: usize,
    pub elements: usize,
    /// Distinct element maps (shell::geometric_map::share): 1 on a
    /// structured strip, up to `elements` on a distorted mesh.
    pub element_maps: usize,
    pub dofs: usize,
    pub contact_candidates: usize,
    pub method: String,
    pub steps: usize,
    /// The engine's factorizations plus those of the grid corrections.
    pub factorizations: usize,
    /// Output grid points corrected by Newton at fixed lambda.
    pub grid_corrections: usize,
    pub solves: usize,
    pub corrections: usize,
    pub wall_s: f64,
    /// Wall time of the continuation loop alone (this process): the steps
    /// with their grid points, events and per-step outputs, without the
    /// model set-up before it and the final outputs after it.
    pub path_s: f64,
    pub stats: Stats,
    pub step_cost: StepCost,
    pub stop: Stop,
    /// Probe values at the last history row.
    pub end: IndexMap<String, f64>,
    /// Largest sum, over all steps, of the bounds on the contact forces of the
    /// candidates left out of the active set (DESIGN §3), N.
    pub skipped_pull_bound: f64,
    /// Mean number of candidate nodes carrying contact terms per ANM step.
    pub mean_active_contacts: Option<f64>,
    /// Peak resident memory of the process so far (Linux VmHWM), bytes.
    pub peak_rss_bytes: Option<u64>,
    /// Whether candidates beyond contact.search_distance were left out.
    pub far_nodes_skipped: bool,
    /// Step at which this run was resumed, if it was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resumed_at_step: Option<usize>,
    /// Critical points of the path (limit points, bifurcations, geometric
    /// series), in path order.
    pub events: Vec<EventRecord>,
    /// Tangent factorizations spent on critical points (inertia at the
    /// path's end, location; not in `factorizations`).
    pub event_factorizations: usize,
    /// With solver.branch = "secondary": lambda of the bifurcation where
    /// the path left for the bifurcated branch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub switched_at: Option<f64>,
    /// What the user should know of the path beyond its events: a
    /// secondary branch asked for and not found; the critical points a
    /// Newton run's steps bracket by their inertia (not located).
    /// Always present, empty when there is nothing to say (review 18: a
    /// stopped run's summary.json had no `notes` key).
    pub notes: Vec<String>,
    /// Contact pairs that changed side of their law's switch between step
    /// ends, summed over the run (steps.csv `contact_switches`): a row of
    /// nodes touching counts its nodes.
    pub contact_switches: usize,
    /// history.csv: column names (lambda, then the probes).
    pub columns: Vec<String>,
    #[serde(skip)]
    pub history: Vec<Vec<f64>>,
    #[serde(skip)]
    pub snapshots: Vec<Snapshot>,
}

impl RunReport {
    /// (lambda, value) of a history column by name.
    pub fn curve(&self, name: &str) -> Option<Vec<(f64, f64)>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.history.iter().map(|r| (r[0], r[k])).collect())
    }

    /// A column's value at a grid lambda (nearest row within 1e-9).
    pub fn value_at(&self, name: &str, lambda: f64) -> Option<f64> {
        let k = self.columns.iter().position(|c| c == name)?;
        self.history
            .iter()
            .find(|r| (r[0] - lambda).abs() < 1e-9)
            .map(|r| r[k])
    }
}

/// What an ANM step costs on average over the run, from the engine's
/// counters (milliseconds), against one factorization + N solves.
#[derive(Clone, Debug, Serialize)]
pub struct StepCost {
    pub assembly_per_step_ms: f64,
    pub factorization_ms: f64,
    pub solve_ms: f64,
    pub series_term_ms: f64,
    pub step_ms: f64,
    /// step_ms / (factorization_ms + N solve_ms).
    pub ratio: f64,
}

impl StepCost {
    pub fn new(s: &Stats, order: usize) -> Self {
        let per = |t: f64, n: usize| 1e3 * t / n.max(1) as f64;
        let factorization_ms = per(s.factorization_s, s.factorizations);
        let solve_ms = per(s.solve_s, s.solves);
        let step_ms = per(
            s.assembly_s + s.factorization_s + s.solve_s + s.series_s,
            s.steps,
        );
        Self {
            assembly_per_step_ms: per(s.assembly_s, s.steps),
            factorization_ms,
            solve_ms,
            series_term_ms: per(s.series_s, s.series_terms),
            step_ms,
            ratio: step_ms / (factorization_ms + order as f64 * solve_ms),
        }
    }
}

/// checkpoint.json: where `anm run --resume DIR` continues from.
#[derive(Serialize, Deserialize)]
struct RunCheckpoint {
    /// The scene file (absolute) and its text: a resume refuses a changed scene.
    scene_file: PathBuf,
    scene_text: String,
    /// ShellScene::mesh_digest at the start.
    #[serde(default)]
    mesh_digest: Option<String>,
    path: Checkpoint,
    recorder: RecorderState,
}

/// Runs a scene file into `out_dir`.
pub fn run_scene(scene_path: &Path, out_dir: &Path, progress: bool) -> Result<RunReport> {
    let scene = load(scene_path)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    run_loaded(&scene, Some(out_dir), progress)
}

/// Continues the interrupted run in `out_dir` from its checkpoint.json.
pub fn resume(out_dir: &Path, progress: bool) -> Result<RunReport> {
    let file = out_dir.join("checkpoint.json");
    // A run that reached its end removed its checkpoint: say so, rather
    // than that the file cannot be read.
    let finished = || -> Option<String> {
        let text = std::fs::read_to_string(out_dir.join("summary.json")).ok()?;
        let v: serde_json::Value = serde_json::from_str(&text).ok()?;
        let stop = &v["stop"];
        // A run in time writes `stop.t` (review 6: "lambda = null"); a
        // point-mass friction run takes milliseconds and is not resumable.
        let (reason, at) = match v["kind"].as_str() {
            Some("shell") if stop["t"].is_number() => {
                (stop["reason"].as_str()?, format!("t = {}", stop["t"]))
            }
            _ if stop["t"].is_number() => (
                stop["reason"].as_str()?,
                format!(
                    "t = {}; a {} run is not resumable, run it again",
                    stop["t"],
                    v["kind"].as_str().unwrap_or("point-mass friction")
                ),
            ),
            _ => (
                stop["reason"].as_str()?,
                format!("lambda = {}", stop["lambda"]),
            ),
        };
        (reason != "interrupted").then(|| {
            format!("the run there has already ended (stop: {reason} at {at}): nothing to resume")
        })
    };
    let text = match std::fs::read_to_string(&file) {
        Ok(t) => t,
        Err(source) => {
            return Err(match finished() {
                Some(problem) => Error::Resume {
                    file: out_dir.to_path_buf(),
                    problem,
                },
                None => Error::Io {
                    file: file.clone(),
                    source,
                },
            });
        }
    };
    let cp: RunCheckpoint = serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: file.clone(),
        message: e.to_string(),
    })?;
    let now = crate::scene::read(&cp.scene_file)?;
    if now != cp.scene_text {
        return Err(Error::Invalid {
            file: cp.scene_file.clone(),
            key: "scene".into(),
            problem: format!(
                "changed since the run in {} started: a resumed run must solve the same scene",
                out_dir.display()
            ),
        });
    }
    let scene = load(&cp.scene_file)?;
    scene.check_mesh_digest(&cp.mesh_digest)?;
    run_inner(&scene, Some(out_dir), progress, Some(cp))
}

/// Runs a loaded scene; `out_dir` None writes nothing (tests, studies).
pub fn run_loaded(scene: &ShellScene, out_dir: Option<&Path>, progress: bool) -> Result<RunReport> {
    run_inner(scene, out_dir, progress, None)
}

fn progress_bar(progress: bool) -> Option<indicatif::ProgressBar> {
    progress.then(crate::output::progress_bar)
}

/// The state of an accepted step at lambda = g: on the series where it
/// reaches g; between the series end and the corrected end point by linear
/// interpolation of the correction.
fn state_at(step: &crate::series::PathStep, g: f64) -> Option<Vec<f64>> {
    if (g - step.lambda_end).abs() < 1e-12 {
        return Some(step.u_end.clone());
    }
    if let Some(a) = step.a_at_lambda(g) {
        return Some(step.eval(a).0);
    }
    let (u_s, l_s) = step.eval(step.length);
    let frac = (g - l_s) / (step.lambda_end - l_s);
    (frac.is_finite() && (0.0..=1.0).contains(&frac)).then(|| {
        u_s.iter()
            .zip(&step.u_end)
            .map(|(a, b)| a + frac * (b - a))
            .collect()
    })
}

/// The output grid values met by an accepted step, in path order, with the
/// path parameter a and the state there: between the step's start and end
/// lambda where lambda is monotone over the step; every crossing of every
/// grid value where the step turns back through a limit point.
fn grid_points(
    rec: &Recorder,
    step: &crate::series::PathStep,
) -> Result<Vec<(f64, f64, Vec<f64>)>> {
    let off = |g: f64| Error::OffPath {
        step: step.index,
        param: "lambda",
        at: g,
        what: format!(
            "output grid value in [{}, {}] on neither the series nor its correction",
            step.lambda[0], step.lambda_end
        ),
    };
    if step.lambda_is_monotone() {
        return rec
            .grid_between(step.lambda[0], step.lambda_end)
            .into_iter()
            .map(|g| {
                let u = state_at(step, g).ok_or_else(|| off(g))?;
                Ok((step.a_at_lambda(g).unwrap_or(step.length), g, u))
            })
            .collect();
    }
    // Turning back: the range of lambda over the step, every crossing.
    let samples: Vec<f64> = (0..=32)
        .map(|i| step.lambda_at(step.length * i as f64 / 32.0))
        .collect();
    let lo = samples.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = samples.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut points = vec![];
    for g in rec.grid_between(lo - 1e-300, hi) {
        for a in step.a_at_lambda_all(g) {
            points.push((a, g, step.eval(a).0));
        }
    }
    points.sort_by(|x, y| x.0.total_cmp(&y.0));
    Ok(points)
}

/// The relative uncertainty of the linear solution u of K u = −r_λ: one
/// step of iterative refinement, du = K⁻¹ (−r_λ − K u), and |du|∞ / |u|∞.
/// Where the error is the conditioning's (a thin shell: the membrane
/// stiffness (L/t)² times the bending's), the step estimates it without
/// removing it (review 5: a clamped plate at t = 1e-6, 1e-7, 1e-8 L,
/// deflection off by 2.3e-4, 1.9e-2, 0.28; the estimate 1.6e-4, 4.0e-3,
/// 0.41; at 1e-5 L, 3.8e-7 for an error below 5e-7).
fn refinement_step(
    k: &crate::linalg::SparseMatrix,
    f: &crate::linalg::Factorization,
    r_lambda: &[f64],
    u: &[f64],
) -> f64 {
    let ku = k.mul_vec(u);
    let residual: Vec<f64> = ku.iter().zip(r_lambda).map(|(a, b)| -(a + b)).collect();
    let du = f.solve(&residual);
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    largest(&du) / largest(u).max(f64::MIN_POSITIVE)
}

/// Scaled length of a chord (du, dlambda): displacements against the
/// model's characteristic length, lambda against its range.
fn chord(model: &ShellModel, du: &[f64], dl: f64, lambda_scale: f64) -> f64 {
    let parts: Vec<f64> = du
        .iter()
        .zip(model.scales())
        .map(|(d, s)| d / s)
        .chain([dl / lambda_scale])
        .collect();
    // Scaled by its largest part where the squares would overflow.
    crate::linalg::norm(&parts)
}

fn run_inner(
    scene: &ShellScene,
    out_dir: Option<&Path>,
    progress: bool,
    resumed: Option<RunCheckpoint>,
) -> Result<RunReport> {
    if scene.friction.is_some() {
        // A scene with [friction] is a problem in time (run::shell_time):
        // refuse the static path, which would drop the friction.
        return Err(Error::Invalid {
            file: scene.file.clone(),
            key: "friction".into(),
            problem: "a shell scene with [friction] is a problem in time: `anm run` solves it (run::shell_time); the static path in lambda does not take friction, nor do `anm bench` and `anm stress` (`anm audit` and `anm buckle --time` have forms in time)".into(),
        });
    }
    let start = Instant::now();
    let mut model = build_model(scene)?;
    model.contact_arclength = scene.contact_arclength;
    let n_dof = model.ndof();
    let mut cfg = scene.solver.clone();
    cfg.lambda_scale = cfg.lambda_end.abs();
    let resumed_at_step = resumed.as_ref().map(|c| c.path.index);
    let (path_cp, rec_state) = match resumed {
        Some(c) => (Some(c.path), Some(c.recorder)),
        None => (None, None),
    };
    let fresh = rec_state.is_none();
    let mut rec = Recorder::new(scene, out_dir, rec_state)?;
    // Wall time spent before a resume (0 for a fresh run).
    let wall_before = rec.state.wall_s_before;
    let scene_file = std::fs::canonicalize(&scene.file).unwrap_or(scene.file.clone());
    let scene_text = &scene.text;
    let mesh_digest = scene.mesh_digest();
    let bar = progress_bar(progress);
    let show = |lambda: f64, stats: &Stats, what: &str| {
        if let Some(b) = &bar {
            let frac = (lambda / cfg.lambda_end).clamp(0.0, 1.0);
            b.set_position((frac * 1000.0) as u64);
            b.set_message(format!(
                "{what}lambda {lambda:.4}  steps {}  factorizations {}",
                stats.steps, stats.factorizations
            ));
        }
    };
    let zero = vec![0.0; n_dof];
    if fresh {
        let full0 = model.expand(&zero, 0.0);
        rec.record(
            &model,
            &State {
                full: &full0,
                lambda: 0.0,
                arclength: 0.0,
                residual: None,
                linear: None,
            },
        )?;
        rec.vtk(&model, &full0, 0.0, "shell_0000.vtu")?;
        if let (true, Some(d)) = (scene.output.tangent_matrix, out_dir) {
            write_tangent(&mut model, &d.join("tangent.mtx"))?;
        }
    }
    let mut grid_lu = LinearSolver::new(cfg.linear);
    // Grid points are held to |R| / |R_lambda(0)| <= residual_tol in the
    // engine's unit-free residual norm (Metric::residual_norm).
    let metric = Metric::for_problem(&model, cfg.lambda_scale)?;
    let f_norm = {
        let (_, rl) = model.tangent(&zero, 0.0)?;
        correct::force_scale(&model, &metric, &rl)
    };
    let mut grid_stats = Stats::default();
    let far_skipped = model.search_distance.is_finite() && !model.pairs.is_empty();
    let method_name;
    let mut newton_brackets: Vec<String> = vec![];
    let mut event_factorizations = 0;
    let path_start = Instant::now();
    let (stop, stats, last): (PathStop, Stats, (Vec<f64>, f64)) = match &scene.method {
        Method::Anm => {
            method_name = "anm";
            let mut path = match path_cp {
                Some(cp) => AnmPath::resume(&mut model, cp, cfg.clone()),
                None => AnmPath::new(&mut model, zero.clone(), 0.0, cfg.clone()),
            };
            // The step before the current one: its end inertia is the
            // current step's start inertia (critical points, DESIGN §8).
            let mut pending: Option<PathStep> = None;
            // Steps in a row that advance the path by almost nothing.
            let (mut crawl, mut first_length) = (0usize, None::<f64>);
            // Negative pivots of the tangent at the path's end, when factored.
            let mut end_pivots: Option<Option<usize>> = None;
            let secondary = match scene.branch {
                Branch::Secondary { direction } => Some(direction),
                Branch::Primary => None,
            };
            let mut event_lu = LinearSolver::new(cfg.linear);
            let locate = bifurcation::Settings {
                lambda_scale: cfg.lambda_scale,
                ..Default::default()
            };
            let stop = 'path: loop {
                if interrupt::requested() {
                    break PathStop::Interrupted {
                        lambda: path.state().1,
                    };
                }
                let step = match path.step() {
                    Ok(s) => s,
                    Err(stop) => break stop,
                };
                let stats = path.stats().clone();
                let first = *first_length.get_or_insert(step.length);
                crawl = if step.length < CRAWL * first {
                    crawl + 1
                } else {
                    0
                };
                if crawl >= CRAWL_STEPS {
                    break PathStop::Failed(Error::Stalled {
                        param: "lambda",
                        at: step.lambda_end,
                        what: crawl_diagnosis(scene, &step, first, crawl),
                    });
                }
                let model: &mut ShellModel = path.problem();
                if far_skipped {
                    let active = model.active_pairs().len();
                    rec.state.active_sum += active;
                    let skipped: f64 = skipped_bound(model);
                    rec.state.skipped_pull_bound = rec.state.skipped_pull_bound.max(skipped);
                } else {
                    rec.state.active_sum += model.pairs.len();
                }
                let arc0 = rec.state.arclength;
                // solver.branch = "secondary", before the switch: this
                // step's critical points now (one more factorization per
                // step), so that the path leaves at the first bifurcation.
                let mut events = vec![];
                let mut switch: Option<Event> = None;
                if secondary.is_some() && rec.state.switched_at.is_none() {
                    let n1 = step_end_inertia(model, &mut event_lu, &step)?;
                    events = critical_points(model, &mut event_lu, &step, n1, None, &locate)?;
                    switch = events
                        .iter()
                        .find(|e| e.kind == bifurcation::Kind::Bifurcation)
                        .cloned();
                }
                let a_max = switch.as_ref().map_or(f64::INFINITY, |e| e.a);
                // Points past the switch lie on the primary path the run
                // leaves there (review 4: reported as events of the run).
                events.retain(|e| e.a <= a_max);
                let points: Vec<_> = grid_points(&rec, &step)?
                    .into_iter()
                    .filter(|p| p.0 <= a_max)
                    .collect();
                for (a, g, u) in points {
                    let before = grid_stats.factorizations;
                    // A grid point that cannot be corrected is numerical
                    // trouble like a step's: the run stops with its
                    // diagnosis in summary.json (exit 2), not as an error
                    // without one (reviews 14 and 16).
                    let (u, iterations) = match correct::correct_at_lambda(
                        model,
                        u,
                        g,
                        cfg.residual_tol,
                        f_norm,
                        &metric,
                        cfg.max_corrections,
                        &mut grid_lu,
                        &mut grid_stats,
                        step.index,
                    ) {
                        Ok(c) => c,
                        Err(e) if e.is_numerical() => break 'path PathStop::Failed(e),
                        Err(e) => return Err(e),
                    };
                    if iterations > 0 {
                        rec.state.grid_corrections += 1;
                    }
                    rec.state.grid_factorizations += grid_stats.factorizations - before;
                    let full = model.expand(&u, g);
                    rec.record(
                        model,
                        &State {
                            full: &full,
                            lambda: g,
                            arclength: arc0 + a,
                            residual: None,
                            linear: None,
                        },
                    )?;
                }
                rec.state.arclength = arc0 + step.length.min(a_max);
                if let Some(prev) = pending.take() {
                    events.extend(critical_points(
                        model,
                        &mut event_lu,
                        &prev,
                        step.negative_pivots,
                        Some(step.lambda[1]),
                        &locate,
                    )?);
                }
                if let Some(g) = step.geometric {
                    // A singular point estimated past lambda_end lies where
                    // the run does not go (an Euler column ending at 1.2
                    // reported one at 102 before its bifurcation at 1.03).
                    let e = bifurcation::geometric(&step, &g);
                    // The same point seen ahead by the steps that close in
                    // on it is one event (review 17: a rolled strip listed
                    // lambda = 0.8106399 four times, steps 21-24).
                    let seen = rec.state.events.last().is_some_and(|p| {
                        p.kind == bifurcation::Kind::Geometric.name()
                            && (p.lambda - e.lambda).abs()
                                <= SAME_POINT * e.lambda.abs().max(cfg.lambda_end.abs())
                    });
                    if (e.lambda - cfg.lambda_end) * cfg.lambda_end.signum() <= 0.0 && !seen {
                        events.push(e);
                    }
                }
                if secondary.is_some() && rec.state.switched_at.is_none() {
                    // Found above.
                } else if path_at_end(&step, &cfg) {
                    let n1 = step_end_inertia(model, &mut event_lu, &step)?;
                    end_pivots = Some(n1);
                    events.extend(critical_points(
                        model,
                        &mut event_lu,
                        &step,
                        n1,
                        None,
                        &locate,
                    )?);
                } else {
                    pending = Some(step.clone());
                }
                let events: Vec<EventRecord> = events
                    .into_iter()
                    .map(|e| record_event(&mut rec, model, e))
                    .collect::<Result<_>>()?;
                if step.index == 0 && step.lambda_end != 0.0 {
                    let full = model.expand(&step.u_end, step.lambda_end);
                    let moved = model.largest_translation(&full);
                    let rate =
                        moved / model.length_scale * (cfg.lambda_end / step.lambda_end).abs();
                    rec.state.first_rate = Some((rate, step.lambda_end));
                }
                let g = model.events(&step.u_end, step.lambda_end)?;
                rec.state.reach = rec
                    .state
                    .reach
                    .max(step.lambda_end * cfg.lambda_end.signum());
                if !scene.obstacles.is_empty() {
                    let full = model.expand(&step.u_end, step.lambda_end);
                    let obstacles = model.obstacles_at(step.lambda_end);
                    rec.state.penetration = penetration::deeper(
                        rec.state.penetration,
                        penetration::inside(model, &obstacles, &full, step.lambda_end),
                    );
                }
                let contact_switches = rec.state.contact.update(&g);
                rec.step(&StepRow {
                    step: step.index + 1,
                    lambda_start: step.lambda[0],
                    lambda_end: step.lambda_end,
                    length: step.length,
                    pade: step.pade.is_some(),
                    end_residual: step.end_residual,
                    geometric: step.geometric.is_some(),
                    factorizations: stats.factorizations,
                    solves: stats.solves,
                    negative_pivots: step.negative_pivots,
                    events,
                    contact_switches,
                })?;
                let every = scene.output.vtk_every;
                if every > 0 && (step.index + 1).is_multiple_of(every) {
                    let full = model.expand(&step.u_end, step.lambda_end);
                    rec.vtk(
                        model,
                        &full,
                        step.lambda_end,
                        &format!("shell_{:04}.vtu", step.index + 1),
                    )?;
                }
                rec.state.wall_s_before = wall_before + start.elapsed().as_secs_f64();
                rec.checkpoint(&RunCheckpointRef {
                    scene_file: &scene_file,
                    scene_text,
                    mesh_digest: &mesh_digest,
                    path: &path.checkpoint(),
                    recorder: &rec.state,
                })?;
                show(step.lambda_end, &stats, "");
                if let (Some(e), Some(direction)) = (switch, secondary) {
                    let model: &mut ShellModel = path.problem();
                    let (u, lambda, dir) =
                        secondary_start(model, &step, &e, direction, &cfg, &metric, &mut event_lu)?;
                    rec.state.switched_at = Some(e.lambda);
                    let cp = Checkpoint {
                        index: step.index + 1,
                        u,
                        lambda,
                        prev_dir: Some((dir, 0.0)),
                        prev_length: None,
                        stats: path.stats().clone(),
                    };
                    let model = path.into_problem();
                    path = AnmPath::resume(model, cp, cfg.clone());
                }
            };
            // A path stopped before its end: the last step's critical
            // points against the tangent at its end (summary.json only).
            if let Some(prev) = pending.take() {
                let (u, l) = path.state();
                let (u, l) = (u.to_vec(), l);
                let model: &mut ShellModel = path.problem();
                let n1 = match prev.negative_pivots {
                    Some(_) => end_inertia(model, &mut event_lu, &u, l, prev.index)?,
                    None => None,
                };
                end_pivots = Some(n1);
                for e in critical_points(model, &mut event_lu, &prev, n1, None, &locate)? {
                    record_event(&mut rec, model, e)?;
                }
            }
            let (u, l) = path.state();
            let ls = event_lu.stats();
            event_factorizations = ls.ldlt + ls.lblt + ls.lu + ls.mumps;
            let mut stats = path.stats().clone();
            // The inertia at the path's end, where it was factored (review
            // 14: the last step's start said 0 on a column past P_cr).
            if let Some(n) = end_pivots {
                stats.linear.negative_pivots = n;
            }
            (stop, stats, (u.to_vec(), l))
        }
        Method::Newton(ncfg) => {
            method_name = "newton";
            // The grid up to lambda_end, and lambda_end where it is off the
            // grid (review 16: a lambda_step beyond lambda_end put a target
            // past it, and the run followed the path there).
            let mut grid = rec.grid_between(0.0, ncfg.lambda_end);
            if grid
                .last()
                .is_none_or(|g| (g - ncfg.lambda_end).abs() > 1e-12)
            {
                grid.push(ncfg.lambda_end);
            }
            let mut prev = (zero.clone(), 0.0);
            let mut count = 0usize;
            let mut inertia: Option<usize> = None;
            // Displacement per unit load of the last increment, and whether
            // a turning back was noted (review 5: a load-controlled Newton
            // jumped over the arch's snap-through silently, and an
            // arclength one followed it while history.csv kept each lambda
            // once).
            let mut last_rate: Option<f64> = None;
            let mut turned = false;
            let load_control = ncfg.control == crate::series::newton::Control::Load;
            let brackets = &mut newton_brackets;
            // The engine holds the model; probes read a second instance.
            let view = build_model(scene)?;
            let m = &view;
            let result = crate::series::newton::run(
                &mut model,
                zero.clone(),
                0.0,
                ncfg,
                &grid,
                |u, lambda, stats| {
                    if interrupt::requested() {
                        return Err(Error::Interrupted {
                            param: "lambda",
                            at: lambda,
                        });
                    }
                    let du: Vec<f64> = u.iter().zip(&prev.0).map(|(a, b)| a - b).collect();
                    let dl = lambda - prev.1;
                    let length = chord(m, &du, dl, ncfg.lambda_end.abs());
                    rec.state.arclength += length;
                    count += 1;
                    // The inertia brackets critical points between steps
                    // (review 4: steps.csv showed 1 negative pivot past
                    // P_cr and the run said nothing).
                    let now = stats.linear.negative_pivots;
                    if let (Some(a), Some(b)) = (inertia, now)
                        && a != b
                    {
                        brackets.push(format!(
                            "negative pivots {a} -> {b} between the increment ends at lambda = {:.6e} and {lambda:.6e}: a critical point the Newton steps bracket along the path but do not locate (a limit point's lambda can lie beyond both ends; solver.method = \"anm\" or `anm buckle` locates it)",
                            prev.1
                        ));
                    }
                    inertia = now.or(inertia);
                    let rate =
                        chord(m, &du, 0.0, ncfg.lambda_end.abs()) / dl.abs().max(f64::MIN_POSITIVE);
                    if load_control
                        && let Some(r) = last_rate
                        && rate > crate::study::critical_cost::SNAP * r
                    {
                        brackets.push(format!(
                            "between lambda = {:.6e} and {lambda:.6e} the displacements moved {:.0} times faster per unit load than in the increment before: a jump, as past a limit point under load control; the path between is not followed (solver.newton_control = \"arclength\" or the ANM follows it)",
                            prev.1,
                            rate / r
                        ));
                    }
                    last_rate = Some(rate);
                    if !turned && dl * ncfg.lambda_end.signum() < 0.0 {
                        turned = true;
                        brackets.push(format!(
                            "the path turns back at lambda = {:.6e} (a limit point): history.csv holds each output lambda once, at its first crossing (the ANM records every crossing); steps.csv has every increment",
                            prev.1
                        ));
                    }
                    let contact_switches = rec.state.contact.update(&m.events(u, lambda)?);
                    rec.step(&StepRow {
                        step: count,
                        lambda_start: prev.1,
                        lambda_end: lambda,
                        length,
                        pade: false,
                        end_residual: 0.0,
                        geometric: false,
                        factorizations: stats.factorizations,
                        solves: stats.solves,
                        negative_pivots: stats.linear.negative_pivots,
                        events: vec![],
                        contact_switches,
                    })?;
                    if let Some(&g) = grid.iter().find(|g| (*g - lambda).abs() < 1e-12) {
                        let full = m.expand(u, lambda);
                        rec.record(
                            m,
                            &State {
                                full: &full,
                                lambda: g,
                                arclength: rec.state.arclength,
                                residual: None,
                                linear: None,
                            },
                        )?;
                    }
                    prev = (u.to_vec(), lambda);
                    show(lambda, stats, "Newton: ");
                    Ok(())
                },
            );
            let stop = match result.stop {
                PathStop::Failed(Error::Interrupted { at, .. }) => {
                    PathStop::Interrupted { lambda: at }
                }
                other => other,
            };
            (stop, result.stats, (result.u_end, result.lambda_end))
        }
        Method::Linear => {
            method_name = "linear";
            let mut stats = Stats::default();
            let clock = Instant::now();
            let (k, rl) = model.tangent(&zero, 0.0)?;
            stats.assembly_s += clock.elapsed().as_secs_f64();
            let f = crate::series::continuation::factorize(&mut grid_lu, &k, &mut stats, 0, 0.0)?;
            let clock = Instant::now();
            let u1 = f.solve(&rl.iter().map(|x| -x).collect::<Vec<_>>());
            stats.solve_s += clock.elapsed().as_secs_f64();
            stats.solves += 1;
            stats.steps = 1;
            if let Some(i) = u1.iter().position(|x| !x.is_finite()) {
                return Err(Error::SingularMatrix {
                    step: 0,
                    param: "lambda",
                    at: 0.0,
                    detail: format!("non-finite linear solution at free dof {i}"),
                });
            }
            let clock = Instant::now();
            let uncertainty = refinement_step(&k, &f, &rl, &u1);
            stats.solve_s += clock.elapsed().as_secs_f64();
            stats.solves += 1;
            if !(uncertainty <= cfg.residual_tol) {
                let ratio = scene.thickness / scene.mesh.size();
                return Err(Error::SingularMatrix {
                    step: 0,
                    param: "lambda",
                    at: 0.0,
                    detail: format!(
                        "ill-conditioned to round-off: one step of iterative refinement moves the linear solution by {uncertainty:.1e} of its largest value, above solver.residual_tol = {:.1e} (thickness / model size = {ratio:.1e}: the bending stiffness is (t/L)² = {:.1e} of the membrane's; thicken or rescale, or raise solver.residual_tol to accept that uncertainty)",
                        cfg.residual_tol,
                        ratio * ratio
                    ),
                });
            }
            let l_end = cfg.lambda_end;
            let u_end: Vec<f64> = u1.iter().map(|x| x * l_end).collect();
            // Arclength per unit of lambda.
            let scale = chord(&model, &u_end, l_end, l_end.abs()) / l_end.abs();
            // Support reactions of the linear model, not of the shell's
            // nonlinear residual at the linear solution (which, off
            // equilibrium, did not balance the loads: 1.0031 N of reaction
            // for a 1 N tip load on a cantilever rotated 0.03 rad).
            // (Only where a probe reads reactions.)
            let reactions = scene
                .probes
                .iter()
                .any(|p| matches!(p.quantity, crate::scene::shell::Quantity::Reaction { .. }));
            let linear = match reactions {
                true => Some(super::probe::linear_residual(&model, &u1, l_end)?),
                false => None,
            };
            // The grid, and lambda_end where it is off the grid (recorded
            // here, with the linear reactions, not as the path's last point).
            let mut points = rec.grid_between(0.0, l_end);
            if points.last().is_none_or(|g| (g - l_end).abs() > 1e-12) {
                points.push(l_end);
            }
            for g in points {
                let u: Vec<f64> = u1.iter().map(|x| x * g).collect();
                let full = model.expand(&u, g);
                let residual: Option<Vec<f64>> = linear
                    .as_ref()
                    .map(|(r0, r1)| r0.iter().zip(r1).map(|(a, b)| a + g * b).collect());
                rec.record(
                    &model,
                    &State {
                        full: &full,
                        lambda: g,
                        arclength: scale * g.abs(),
                        residual: residual.as_deref(),
                        linear: Some((&u1, l_end)),
                    },
                )?;
            }
            rec.state.arclength = scale * l_end.abs();
            rec.state.contact.update(&model.events(&zero, 0.0)?);
            let contact_switches = rec.state.contact.update(&model.events(&u_end, l_end)?);
            rec.step(&StepRow {
                step: 1,
                lambda_start: 0.0,
                lambda_end: l_end,
                length: rec.state.arclength,
                pade: false,
                end_residual: 0.0,
                geometric: false,
                factorizations: 1,
                solves: 1,
                negative_pivots: stats.linear.negative_pivots,
                events: vec![],
                contact_switches,
            })?;
            (PathStop::End { lambda: l_end }, stats, (u_end, l_end))
        }
    };
    let path_s = path_start.elapsed().as_secs_f64();
    if let Some(b) = &bar {
        b.finish();
    }
    let (u_last, lambda_last) = last;
    // A path that ends on its last grid value ends in the state recorded
    // there, corrected to solver.residual_tol in the force norm (review 24).
    let full_last = match (&stop, rec.last_full.take()) {
        (PathStop::End { .. }, Some((l, full))) if (l - lambda_last).abs() <= 1e-12 => full,
        _ => model.expand(&u_last, lambda_last),
    };
    // The final point when it is off the grid (a stop between grid values).
    // (A run that reaches lambda_end ends on it exactly: the engine
    // corrects its last step at that load.)
    let last_row = rec.state.history.last().map(|r| r[0]);
    if last_row.is_none_or(|l| (l - lambda_last).abs() > 1e-12)
        && matches!(stop, PathStop::End { .. })
    {
        rec.record(
            &model,
            &State {
                full: &full_last,
                lambda: lambda_last,
                arclength: rec.state.arclength,
                residual: None,
                linear: None,
            },
        )?;
    }
    let message = match &stop {
        PathStop::Failed(e) => Some(e.to_string()),
        // Newton counts every increment it tries, the cut ones too (review
        // 16: "0 steps" and max_steps reached).
        PathStop::MaxSteps { steps, lambda } if method_name == "newton" => Some(format!(
            "solver.max_steps = {steps} increments tried (accepted and cut) at lambda = {lambda}"
        )),
        PathStop::MaxSteps { steps, lambda } => Some(format!(
            "solver.max_steps = {steps} reached at lambda = {lambda}"
        )),
        // Only the ANM writes a checkpoint (review 16: a Newton run was told
        // to resume and had nothing to resume from).
        PathStop::Interrupted { lambda } if method_name == "anm" => Some(format!(
            "interrupted (Ctrl-C or SIGTERM) at the step end lambda = {lambda}; continue with `anm run --resume DIR`"
        )),
        PathStop::Interrupted { lambda } => Some(format!(
            "interrupted (Ctrl-C or SIGTERM) at the increment end lambda = {lambda}; a {method_name} run writes no checkpoint: run it again"
        )),
        PathStop::End { .. } => None,
    };
    let stop_out = Stop {
        reason: stop.reason().to_string(),
        t: None,
        lambda: Some(stop.lambda().unwrap_or(lambda_last)),
        node: None,
        message,
    };
    let factorizations = stats.factorizations + rec.state.grid_factorizations;
    let end: IndexMap<String, f64> = rec
        .state
        .history
        .last()
        // + 0.0: no −0 in summary.json and the console (review 5).
        .map(|r| {
            rec.columns
                .iter()
                .cloned()
                .zip(r.iter().map(|x| x + 0.0))
                .collect()
        })
        .unwrap_or_default();
    let interrupted = matches!(stop, PathStop::Interrupted { .. });
    if out_dir.is_some() {
        finish_files(&mut rec, &model, &full_last, lambda_last, !interrupted)?;
    }
    if let (Some(d), PathStop::End { .. } | PathStop::Failed(_)) = (out_dir, &stop) {
        // A finished run has nothing to resume, and one stopped by
        // numerical trouble would meet it again from there (review 14:
        // `--resume` repeated the same stop).
        let _ = std::fs::remove_file(d.join("checkpoint.json"));
    }
    let report = RunReport {
        description: scene.description.clone(),
        kind: "shell",
        scene: scene.file.display().to_string(),
        mesh: scene.mesh.file.display().to_string(),
        nodes: scene.mesh.nodes.len(),
        elements: scene.mesh.quads.len(),
        element_maps: model.distinct_maps(),
        dofs: n_dof,
        contact_candidates: model.pairs.len(),
        method: method_name.to_string(),
        steps: stats.steps,
        factorizations,
        grid_corrections: rec.state.grid_corrections,
        solves: stats.solves + grid_stats.solves,
        corrections: stats.corrections,
        wall_s: wall_before + start.elapsed().as_secs_f64(),
        path_s,
        step_cost: StepCost::new(&stats, cfg.order),
        stats: stats.clone(),
        stop: stop_out,
        end,
        skipped_pull_bound: rec.state.skipped_pull_bound,
        mean_active_contacts: (method_name == "anm" && stats.steps > 0 && !model.pairs.is_empty())
            .then(|| rec.state.active_sum as f64 / stats.steps as f64),
        peak_rss_bytes: crate::output::peak_rss_bytes(),
        far_nodes_skipped: far_skipped,
        resumed_at_step,
        events: rec.state.events.clone(),
        switched_at: rec.state.switched_at,
        notes: {
            let mut notes = newton_brackets;
            if matches!(scene.branch, Branch::Secondary { .. }) && rec.state.switched_at.is_none() {
                notes.push("solver.branch = \"secondary\", but the path crossed no bifurcation: it is the primary path".into());
            }
            let last = penetration::inside(
                &model,
                &model.obstacles_at(lambda_last),
                &full_last,
                lambda_last,
            );
            if let Some(p) = penetration::deeper(rec.state.penetration, last) {
                notes.push(penetration::note(&model, &p, &scene.obstacles, "lambda"));
            }
            let ended = matches!(stop, PathStop::End { .. });
            notes.extend(turned_back(
                ended,
                lambda_last,
                rec.state.reach,
                cfg.lambda_end,
            ));
            notes.extend(without_inertia(stats.linear.symmetric_without_inertia));
            // Review 21: a column run past its buckling load ended on the
            // unstable straight branch with exit 0 and no word.
            // (Newton's runs name the pivots their increments bracket.)
            if let (true, Some(n)) = (ended, stats.linear.negative_pivots)
                && n > 0
                && method_name == "anm"
                && rec.state.switched_at.is_none()
            {
                notes.push(format!(
                    "the state at lambda_end has {n} negative pivots: it is unstable (the path went on along its branch past a bifurcation or a limit point, see events); a real structure leaves it there: solver.branch = \"secondary\" follows the bifurcated branch"
                ));
            }
            // Review 21: E = 2e3 in a scene in m gave 32 % strain, unnoted
            // (right for that input, but a unit slip most likely).
            let linear = matches!(scene.method, Method::Linear);
            let strain =
                super::section::membrane_stresses(&model, &full_last, scene.thickness, linear)
                    .iter()
                    .map(|m| m.min.abs().max(m.max.abs()))
                    .fold(0.0, f64::max)
                    / scene.material.young;
            if strain > LARGE_STRAIN {
                notes.push(format!(
                    "membrane strains reach about {:.0} % (stress / young): the material law (St Venant–Kirchhoff) is meant for moderate strains; if these are not intended, check the units of material.young and of the loads",
                    100.0 * strain
                ));
            }
            // Review 21: at t = 1e-6 L the ANM stopped on "no convergence"
            // and nothing pointed to the thickness.
            let slender = scene.thickness / scene.mesh.size();
            if matches!(stop, PathStop::Failed(_)) && slender < THIN {
                notes.push(format!(
                    "thickness / model size = {slender:.1e}: the bending stiffness is (t/L)² = {:.1e} of the membrane's, near the round-off of the residual, which may be why the run stopped; a thicker shell (or a smaller model) is better conditioned",
                    slender * slender
                ));
            }
            let near_start = rec
                .state
                .events
                .iter()
                .filter(|e| e.lambda.abs() <= NEAR_START * cfg.lambda_end.abs())
                .count();
            if near_start > CROWD {
                notes.push(format!(
                    "{near_start} of the {} critical points lie within {NEAR_START:e} of lambda_end from the unloaded state: the path wanders about lambda = 0, where the shell is held by little more than eq. (3)'s regularization (a mechanism, or a load that pulls it off its obstacles); the events and the stop there say nothing of the shell's stability: hold the shell, or check that the loads press it onto the obstacles",
                    rec.state.events.len()
                ));
            }
            if rec.state.events.len() > MODE_FILES {
                notes.push(format!(
                    "{} critical points: mode_K.vtu is written for the first {MODE_FILES}",
                    rec.state.events.len()
                ));
            }
            // Review 15: a free plate held only by penalty-law candidates
            // (eta = 0: no force before they touch) fell through its gap
            // at lambda = 4e-13 and rocked, reporting two "bifurcations".
            if let Some((rate, l1)) = rec.state.first_rate
                && rate > MECHANISM
            {
                notes.push(format!(
                    "the first step moved the shell {rate:.1e} times the model's size per unit of lambda_end (to lambda = {l1:.3e}): at lambda = 0 it is not held (a mechanism, e.g. a shell held only by contact candidates, which the penalty law, contact.eta = 0, leaves free until they touch); what the path does at such loads, events included, is that rigid motion settling; hold the shell or use contact.eta > 0"
                ));
            }
            // Review 15: every step of a strip on a plane was accepted at the
            // floor (1.2e-5 against 1e-6) with only summary.json saying so.
            if stats.round_off_stops > 0 {
                // Review 17: "0.53 relative" read as a loose answer; it was
                // the residual over loads near 0 (a punch's approach).
                let share = (stats.round_off_lambda / cfg.lambda_end).abs();
                let small = if share < 0.1 {
                    format!(
                        " to the forces at lambda = {:.3e}, {share:.1e} of lambda_end, where the forces may be small: before a contact or under small loads",
                        stats.round_off_lambda
                    )
                } else {
                    format!(" to the forces at lambda = {:.3e}", stats.round_off_lambda)
                };
                notes.push(format!(
                    "{} corrections stopped at the round-off floor of the residual, above solver.residual_tol = {:e} (the largest accepted: {:.2e} relative{small}): the answers there are as accurate as that floor (summary.json stats.round_off_stops, round_off_residual, round_off_lambda)",
                    stats.round_off_stops, cfg.residual_tol, stats.round_off_residual
                ));
            }
            // Review 17: E in MPa in an m scene gave the linear method a
            // 65.7 m deflection of a 1 m plate, unnoted.
            let moved = model.largest_translation(&full_last);
            if method_name == "linear" && moved > LINEAR_RANGE * model.length_scale {
                notes.push(format!(
                    "the linear method's largest displacement, {moved:.3e}, is {:.1} times the model's size: far outside the small displacements it assumes; check the units (e.g. young in MPa in a scene in m) or follow the path with method = \"anm\"",
                    moved / model.length_scale
                ));
            }
            notes.extend(regularization::pull_note(&model, &full_last, lambda_last));
            notes.extend(regularization::sink_note(
                &model,
                &model.obstacles_at(lambda_last),
                &scene.obstacles,
                &full_last,
                lambda_last,
            ));
            notes
        },
        contact_switches: rec.state.contact.switches,
        event_factorizations,
        columns: rec.columns.clone(),
        history: rec.state.history.clone(),
        snapshots: rec.state.snapshots.clone(),
    };
    if let Some(d) = out_dir {
        write_json(&d.join("summary.json"), &report)?;
        // Interrupted too: the snapshots passed so far (review 23: the
        // file appeared only after --resume, which rewrites it whole).
        if scene.output.hdf5 {
            write_fields(&d.join("fields.h5"), scene, &report.snapshots)?;
        }
        // Interrupted too: the curves up to the last row (review 7).
        if scene.output.plot && report.history.len() > 1 {
            probe_plot(&d.join("plot.svg"), scene, "lambda (-)", &report.history, 1)?;
        }
    }
    Ok(report)
}

/// Mode amplitude of the first point on the secondary branch: its largest
/// displacement is this fraction of the model's length scale.
const BRANCH_OFFSET: f64 = 1e-3;

/// The first point of the secondary branch at the bifurcation `e` of
/// `step` (docs/bifurcation.md): from the located point (U_c, lambda_c)
/// moved along the mode phi, U_c + delta phi (largest displacement
/// BRANCH_OFFSET × length scale, sign `direction` of the mode whose
/// largest displacement is positive), Newton-corrected on the hyperplane
/// <U − U_c − delta phi, phi>~ = 0 (fixed mode amplitude, lambda free),
/// which the primary path leaves and the bifurcated branch crosses.
/// Returns the point and the direction (phi, 0) that orients the next step.
fn secondary_start(
    model: &mut ShellModel,
    step: &PathStep,
    e: &Event,
    direction: f64,
    cfg: &crate::series::ContinuationConfig,
    metric: &Metric,
    lu: &mut LinearSolver,
) -> Result<(Vec<f64>, f64, Vec<f64>)> {
    let (uc, lc) = step.eval(e.a);
    let full = model.expand(&e.mode, 0.0);
    let n = model.n_nodes();
    let mut big = 0.0f64;
    for i in 0..n {
        for k in 0..3 {
            let v = full[crate::fe::dof::index(i, k)];
            if v.abs() > big.abs() {
                big = v;
            }
        }
    }
    if big == 0.0 {
        return Err(Error::SingularMatrix {
            step: step.index,
            param: "lambda",
            at: e.lambda,
            detail: "the bifurcation mode has no displacement: no branch to switch to".into(),
        });
    }
    let delta = direction * BRANCH_OFFSET * model.length_scale / big;
    let phi: Vec<f64> = e.mode.iter().map(|v| delta * v).collect();
    let start: Vec<f64> = uc.iter().zip(&phi).map(|(u, p)| u + p).collect();
    let mut stats = Stats::default();
    let settings = correct::Settings {
        tol: cfg.residual_tol,
        max_iter: 30,
        jacobian: correct::Jacobian::Fresh,
        max_residual: f64::INFINITY,
        line_search: false,
        step: step.index,
    };
    let constraint = correct::Constraint::Arclength {
        t_u: &phi,
        t_lambda: 0.0,
        reference: None,
    };
    let end = correct::correct(
        model,
        start,
        lc,
        &constraint,
        &settings,
        metric,
        lu,
        &mut stats,
    )?;
    Ok((end.u, end.lambda, phi))
}

/// A step shorter than this share of the run's first step advances the
/// path by almost nothing.
const CRAWL: f64 = 1e-12;

/// Such steps in a row stop the run (review 19: the penalty law at K =
/// 1e9 N/mm took 20,000 steps of 1e-14 at the contact's first touch, 75 s,
/// and ended on max_steps with no hint).
const CRAWL_STEPS: usize = 50;

/// Why the path stalled, and the key that likely lets it go on.
fn crawl_diagnosis(scene: &ShellScene, step: &PathStep, first: f64, steps: usize) -> String {
    let hint = match &scene.contact {
        Some(ct) if ct.eta == 0.0 => format!(
            "; under the penalty law (contact.eta = 0) with contact.k = {:e}, K times the round-off of a gap exceeds the force tolerance at the law's kink, where a node first touches: contact.eta > 0 (its switch is smooth) lets the path past; another contact.k may too, in no simple direction (review 21: on one cantilever 1e8 N/mm stalled where 3e8 and 1e9 ran, on another 1e9 stalled where 1e8 ran)",
            ct.k
        ),
        _ => "; the path may be at a point it cannot pass at this solver.residual_tol (a larger one may), or at a kink of a law".into(),
    };
    format!(
        "the path stalled: {steps} steps in a row each advanced by less than {CRAWL:e} of the first step's length ({:.3e} against {first:.3e}), the last ending with a relative residual of {:.3e}{hint}",
        step.length, step.end_residual
    )
}

/// A path stopped (not ended) below its start after reaching `reach`
/// (times lambda_end's sign) says it turned back (review 10: a strip
/// starting clear of its rollers turned back at a limit point and went down
/// to lambda = -54 until max_steps, with no word).
fn turned_back(ended: bool, lambda_last: f64, reach: f64, lambda_end: f64) -> Option<String> {
    let low = lambda_last * lambda_end.signum();
    (!ended && low < 0.0 && reach > 0.0).then(|| format!(
        "the path turned back: it reached lambda = {}, then went back past its start to lambda = {lambda_last} where it stopped: on this path the load is carried up to the first only (a limit point, see events; after a snap-through the path may come back), or the shell is not held where it starts (e.g. a strip clear of its rollers)",
        reach * lambda_end.signum()
    ))
}

/// The note for `blind` symmetric tangents factored without inertia
/// (review 9: with the LU, the Euler column crossed its bifurcation without
/// a word).
fn without_inertia(blind: usize) -> Option<String> {
    (blind > 0).then(|| format!(
        "{blind} symmetric tangents were factored by the LU, which gives no inertia (solver.linear_solver = \"lu\", or the symmetric backends failed their check): a bifurcation or limit point on those steps is not seen by a change of negative pivots, only by the geometric-series test; linear_solver = \"auto\" factors them by LDLT"
    ))
}

/// Whether the step reached the path's target (it is the last one).
fn path_at_end(step: &PathStep, cfg: &crate::series::ContinuationConfig) -> bool {
    let forward = if cfg.lambda_end >= step.lambda[0] {
        1.0
    } else {
        -1.0
    };
    (step.lambda_end - cfg.lambda_end) * forward >= -1e-14 * cfg.lambda_end.abs().max(1.0)
}

/// Largest translation of the first step per unit of lambda_end, in model
/// sizes, above which the shell is taken as not held at the start.
const MECHANISM: f64 = 1e6;

/// [`end_inertia`] at the end of `step`, when its start tangent had an
/// inertia (None otherwise).
fn step_end_inertia(
    model: &mut ShellModel,
    lu: &mut LinearSolver,
    step: &PathStep,
) -> Result<Option<usize>> {
    match step.negative_pivots {
        Some(_) => end_inertia(model, lu, &step.u_end, step.lambda_end, step.index),
        None => Ok(None),
    }
}

/// Negative pivots of the tangent at (u, lambda) (None when it is not
/// symmetric): the inertia at the end of step `step` (called only when
/// the step's start tangent had an inertia: one more factorization per
/// run, or per step with solver.branch = "secondary" before the switch).
/// A tangent that lost its symmetry on the step (a follower load) has no
/// inertia, also for a backend that needs symmetry (review 9: `ldlt` threw
/// away a finished path there, or hid the error that stopped it).
fn end_inertia(
    model: &mut ShellModel,
    lu: &mut LinearSolver,
    u: &[f64],
    lambda: f64,
    step: usize,
) -> Result<Option<usize>> {
    let (k, _) = model.tangent(u, lambda)?;
    match lu.factorize(&k) {
        Ok(f) => Ok(f.inertia().map(|i| i.0)),
        Err(_) if lu.last_check_symmetric() == Some(false) => Ok(None),
        Err(detail) => Err(Error::SingularMatrix {
            step,
            param: "lambda",
            at: lambda,
            detail: format!("tangent at the end of step {step}: {detail}"),
        }),
    }
}

/// The critical points that `step` crosses, given the negative pivots `n1`
/// and lambda_1 `next_l1` at its end (series::bifurcation): located on the
/// step's series when the inertia changes; a limit point from dlambda/da
/// when only lambda_1 changes sign (non-symmetric tangents).
fn critical_points(
    model: &mut ShellModel,
    lu: &mut LinearSolver,
    step: &PathStep,
    n1: Option<usize>,
    next_l1: Option<f64>,
    settings: &bifurcation::Settings,
) -> Result<Vec<Event>> {
    match (step.negative_pivots, n1) {
        (Some(n0), Some(n1)) if n0 != n1 => bifurcation::locate(model, step, n0, n1, lu, settings),
        (Some(_), Some(_)) => Ok(vec![]),
        _ => {
            // No inertia: a geometric series flags the step; the tangent's
            // real eigenvalue nearest zero locates the point.
            // A failed location (e.g. a complex pair nearest zero) leaves
            // the geometric estimate as the step's only event.
            if step.geometric.is_some()
                && let Ok(Some(e)) = bifurcation::locate_unsymmetric(model, step, lu, settings)
            {
                return Ok(vec![e]);
            }
            Ok(match next_l1 {
                Some(l1) if l1.signum() != step.lambda[1].signum() => {
                    vec![bifurcation::limit_point(step)]
                }
                _ => vec![],
            })
        }
    }
}

/// Membrane strains above this are outside the material law's range.
const LARGE_STRAIN: f64 = 0.1;

/// A thickness below this share of the model's size makes the bending
/// stiffness (t/L)² ≤ 1e-9 of the membrane's.
const THIN: f64 = 3e-5;

/// Displacements above this share of the model's size are outside the
/// linear method's range.
const LINEAR_RANGE: f64 = 0.1;

/// Geometric estimates of consecutive steps this close (relative) are one
/// point.
const SAME_POINT: f64 = 1e-6;

/// Mode files a run writes at most (review 17: a path wandering about a
/// mechanism wrote 292, 9 MB).
const MODE_FILES: usize = 50;

/// Events within this share of lambda_end of the start, more than
/// [`CROWD`] of them, are a path wandering about the unloaded state.
const NEAR_START: f64 = 1e-6;
const CROWD: usize = 20;

/// Records an event: its mode as `mode_K.vtu` (K counts the run's events
/// from 1, the first [`MODE_FILES`]) and its dominant wavelength.
fn record_event(rec: &mut Recorder, model: &ShellModel, e: Event) -> Result<EventRecord> {
    let k = rec.state.events.len() + 1;
    let full = model.expand(&e.mode, 0.0);
    let wave = crate::output::mode::wavelength(&model.x0, &model.a30, &model.quads(), &full);
    let mode = match &rec.dir {
        Some(d) if k <= MODE_FILES => {
            let name = format!("mode_{k}.vtu");
            crate::output::mode::write(&d.join(&name), &model.x0, &rec.scene.mesh.quads, &full)?;
            Some(name)
        }
        _ => None,
    };
    let r = EventRecord {
        kind: e.kind.name().to_string(),
        lambda: e.lambda,
        step: e.step + 1,
        a: e.a,
        negative_pivots: e.negative_pivots,
        bracket: e.bracket,
        kappa: e.kappa.is_finite().then_some(e.kappa),
        factorizations: e.factorizations,
        mode,
        wavelength: wave.map(|w| w.wavelength),
        half_waves: wave.map(|w| w.half_waves),
        wave_direction: wave.map(|w| w.direction.to_string()),
        branch: if rec.state.switched_at.is_some() {
            "secondary"
        } else {
            "primary"
        }
        .into(),
    };
    rec.event(r.clone())?;
    Ok(r)
}

/// Borrowed form of [`RunCheckpoint`] for writing.
#[derive(Serialize)]
struct RunCheckpointRef<'a> {
    scene_file: &'a Path,
    scene_text: &'a str,
    mesh_digest: &'a Option<String>,
    path: &'a Checkpoint,
    recorder: &'a RecorderState,
}

/// Sum of the force bounds of the candidates outside the active set.
fn skipped_bound(model: &ShellModel) -> f64 {
    let mut is_active = vec![false; model.pairs.len()];
    for &i in model.active_pairs() {
        is_active[i] = true;
    }
    model
        .pairs
        .iter()
        .zip(&is_active)
        .filter(|(_, a)| !**a)
        .map(|(p, _)| search::skipped_force_bound(p, model.search_distance))
        .sum()
}

/// Files written once a run stops: the obstacles and the .pvd index of the
/// snapshots written; at its end (`finished`; not when interrupted, which
/// `--resume` continues) also the last VTK and the per-node contact forces
/// at the last point.
fn finish_files(
    rec: &mut Recorder,
    model: &ShellModel,
    full: &[f64],
    lambda: f64,
    finished: bool,
) -> Result<()> {
    let Some(d) = rec.dir.clone() else {
        return Ok(());
    };
    if finished {
        rec.vtk(model, full, lambda, "shell_final.vtu")?;
    }
    let scene = rec.scene;
    let size = scene.mesh.size();
    let mut pvd = rec.state.pvd.clone();
    // shell_final.vtu and the last step's snapshot, when that step's number
    // is a multiple of output.vtk_every, are one state: indexed once, by the
    // snapshot of the series (review 7).
    if let [.., a, b] = pvd.as_slice()
        && a.0 == b.0
        && a.1 == b.1
    {
        pvd.pop();
    }
    let times: Vec<f64> = pvd.iter().map(|e| e.0).collect();
    for (k, ob) in model.obstacles.iter().enumerate() {
        let (pts, quads) = match ob {
            Obstacle::Cylinder {
                centre,
                axis,
                radius,
                crown,
            } => {
                let len = 1.5 * size.min(4.0 * radius);
                // A crowned roll drawn with its profile r(s) = R − κ s².
                let rings = if *crown == 0.0 { 1 } else { 40 };
                let r = |s: f64| radius - crown * s * s;
                revolved_surface(centre, axis, &r, len, 96, rings)
            }
            Obstacle::Plane { point, normal } => {
                cylinder_surface(point, normal, 0.5 * size, 0.0, 4)
            }
        };
        let name = format!("obstacle_{k}.vtu");
        write_vtu(&d.join(&name), &pts, &quads, &[])?;
        // The obstacle at each time of the collection: moved by its motion.
        for &t in &times {
            let shift = model.motions[k].shift(t);
            if shift.norm() == 0.0 {
                pvd.push((t, k + 1, name.clone()));
            } else {
                let moved: Vec<_> = pts.iter().map(|p| p + shift).collect();
                let name_t = format!("obstacle_{k}_{:.6}.vtu", t);
                write_vtu(&d.join(&name_t), &moved, &quads, &[])?;
                pvd.push((t, k + 1, name_t));
            }
        }
    }
    write_pvd(&d.join("shell.pvd"), &pvd)?;
    if !finished {
        return Ok(());
    }
    let mut rows = vec![];
    for c in super::probe::contacts(model, full, lambda) {
        let x0 = model.x0[c.node];
        rows.push(vec![
            model.node_tag(c.node) as f64,
            c.obstacle as f64,
            x0[0],
            x0[1],
            x0[2],
            c.gap,
            c.r,
            c.r * c.normal[0],
            c.r * c.normal[1],
            c.r * c.normal[2],
        ]);
    }
    if !rows.is_empty() {
        write_csv_ids(
            &d.join("contact_final.csv"),
            &[
                "node", "obstacle", "X", "Y", "Z", "gap", "rn", "fx", "fy", "fz",
            ],
            2,
            &rows,
        )?;
    }
    Ok(())
}

/// plot.svg: one panel per probe unit (lengths, forces, dimensionless),
/// against the history's first column (`x_label`); probe i is the
/// history's column `first + i`.
pub(crate) fn probe_plot(
    path: &Path,
    scene: &ShellScene,
    x_label: &str,
    history: &[Vec<f64>],
    first: usize,
) -> Result<()> {
    let stem = scene
        .file
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut groups: Vec<(&str, Vec<usize>)> = vec![];
    for (i, p) in scene.probes.iter().enumerate() {
        if matches!(p.quantity, crate::scene::shell::Quantity::Lambda) {
            continue;
        }
        match groups.iter_mut().find(|(u, _)| *u == p.unit) {
            Some((_, v)) => v.push(i),
            None => groups.push((p.unit, vec![i])),
        }
    }
    if groups.is_empty() {
        return Ok(());
    }
    let titles: Vec<String> = groups
        .iter()
        .map(|(u, _)| {
            let what = match *u {
                "m" => "lengths",
                "N" => "forces",
                _ => "dimensionless",
            };
            format!("{stem}: {what}")
        })
        .collect();
    let ylabels: Vec<String> = groups
        .iter()
        .map(|(u, _)| format!("value ({})", scene.units.of(u)))
        .collect();
    let panels: Vec<Panel> = groups
        .iter()
        .enumerate()
        .map(|(g, (_, idx))| Panel {
            title: &titles[g],
            x_label,
            y_label: &ylabels[g],
            curves: idx
                .iter()
                .map(|&i| Curve {
                    label: &scene.probes[i].name,
                    points: history.iter().map(|r| (r[0], r[first + i])).collect(),
                })
                .collect(),
            log: (false, false),
        })
        .collect();
    draw(path, &panels)
}

/// fields.h5: one group per snapshot (feature `hdf5`).
#[cfg(feature = "hdf5")]
fn write_fields(path: &Path, scene: &ShellScene, snapshots: &[Snapshot]) -> Result<()> {
    let mut w = crate::output::hdf5::FieldWriter::create(
        path,
        &[
            ("scene", &scene.file.display().to_string()),
            ("kind", "shell"),
            ("units", "scene units; director dimensionless"),
        ],
    )?;
    w.write_tags("node_tags", &scene.mesh.node_tags)?;
    let flat = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<f64>>();
    for s in snapshots {
        let coords: Vec<[f64; 3]> =
            s.x0.iter()
                .zip(&s.displacement)
                .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
                .collect();
        w.write_step(
            &[("lambda", s.lambda)],
            &[
                ("reference_coordinates", 3, &flat(&s.x0)),
                ("coordinates", 3, &flat(&coords)),
                ("displacement", 3, &flat(&s.displacement)),
                ("director", 3, &flat(&s.director)),
                ("contact_force", 3, &flat(&s.force)),
                ("contact_reaction", 1, &s.reaction),
            ],
        )?;
    }
    Ok(())
}

#[cfg(not(feature = "hdf5"))]
fn write_fields(_path: &Path, _scene: &ShellScene, _snapshots: &[Snapshot]) -> Result<()> {
    unreachable!("scene validation rejects output.hdf5 without the hdf5 feature")
}

/// The initial tangent (lambda = 0, free unknowns) as MatrixMarket.
fn write_tangent(model: &mut ShellModel, path: &Path) -> Result<()> {
    let zero = vec![0.0; model.ndof()];
    let (k, _) = model.tangent(&zero, 0.0)?;
    let (s, values) = k.compressed(None).map_err(|e| Error::write(path, e))?;
    let symmetric = crate::linalg::is_symmetric(&s, &values);
    crate::linalg::matrix_market::write(path, &s, &values, symmetric).map_err(|source| Error::Io {
        file: path.to_path_buf(),
        source,
    })
}

/// The initial tangent's factorization: a cheap check that a scene is not
/// singular (used by `anm check`).
pub fn check_factorizes(scene: &ShellScene) -> Result<()> {
    let mut m = build_model(scene)?;
    let zero = vec![0.0; m.ndof()];
    let (k, _) = m.tangent(&zero, 0.0)?;
    LinearSolver::default()
        .factorize(&k)
        .map(|_| ())
        .map_err(|detail| Error::SingularMatrix {
            step: 0,
            param: "lambda",
            at: 0.0,
            detail: format!("initial tangent of {}: {detail}", scene.file.display()),
        })
}

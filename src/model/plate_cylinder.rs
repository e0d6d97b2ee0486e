//! The plate-cylinder case (paper §2.2, DESIGN §4): a clamped strip pushed
//! by dead end forces around a fixed rigid cylinder, frictionless contact by
//! the regularized law (eq. 3), ANM continuation in lambda.
//!
//! [`run_scene`] reads the scene, builds the shell model, follows the path
//! and writes, in the output directory:
//! - `history.csv`: `lambda,uz_A,ux_A,rn_B,rn_C,rn_D,rn_total` on the uniform
//!   lambda grid of the scene, each row evaluated from the series of the step
//!   that contains it (PathStep::a_at_lambda + eval) and held to the
//!   engine's residual test (corrected at fixed lambda when above it,
//!   GridFix); rn_B, rn_C, rn_D are the
//!   sums of the nodal normal reactions R over the node rows at the scene's
//!   `contact_rows` x, rn_total over all contact nodes;
//! - `summary.json`: the [`RunReport`] (steps, factorizations, solves, wall
//!   time, the cost of a step part by part ([`StepCost`]), stop reason and
//!   lambda);
//! - `plot.svg`: uz_A and the contact forces versus lambda;
//! - `contact_final.csv`: per-node gap, reaction R and force R n of the
//!   active contact nodes at the last point (node numbers 1-based);
//! - `shell_NNNN.vtu` (deformed mid-surface, displacement, director, nodal
//!   contact force) every `vtk_every` steps and at the end,
//!   `obstacle_K.vtu`, and `plate-cylinder.pvd` indexing them by lambda.

use crate::contact::Obstacle;
use crate::contact::search;
use crate::error::{Error, Result};
use crate::linalg::{SparseLu, norm};
use crate::mesh::Vec3;
use crate::output::plot::{Curve, Panel, draw};
use crate::output::vtk::{PointData, cylinder_surface, write_pvd, write_vtu};
use crate::output::{Stop, create_dir, write_csv, write_json};
use crate::scene::shell::{ShellScene, load};
use crate::series::continuation::{PathResult, PathStep, run};
use crate::series::{ContinuationConfig, ContinuationProblem, Stats};
use crate::shell::ShellModel;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Summary of a run (summary.json).
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub scene: String,
    pub mesh: String,
    pub nodes: usize,
    pub elements: usize,
    pub dofs: usize,
    pub contact_candidates: usize,
    pub steps: usize,
    /// The engine's factorizations (`stats`) plus those of the grid
    /// corrections.
    pub factorizations: usize,
    /// Output grid points corrected by Newton at fixed lambda (GridFix).
    pub grid_corrections: usize,
    pub solves: usize,
    pub corrections: usize,
    pub wall_s: f64,
    pub stats: Stats,
    pub step_cost: StepCost,
    pub stop: Stop,
    /// uz at the probe at the last accepted point.
    pub uz_a_end: f64,
    /// Largest sum, over all steps, of the bounds on the contact forces of the
    /// candidates left out of the active set (DESIGN §3;
    /// [`search::skipped_force_bound`]), N.
    pub skipped_pull_bound: f64,
    /// Mean number of candidate nodes carrying contact terms per ANM step
    /// (those within `contact.search_distance` of an obstacle).
    pub mean_active_contacts: Option<f64>,
    /// Peak resident memory of the process so far (Linux VmHWM), bytes.
    pub peak_rss_bytes: Option<u64>,
    /// Whether candidates beyond contact.search_distance were left out
    /// ([`far_nodes_may_be_skipped`]); false: every candidate was active.
    pub far_nodes_skipped: bool,
    /// history.csv rows: lambda, uz_A, ux_A, rn_B, rn_C, rn_D, rn_total.
    #[serde(skip)]
    pub history: Vec<[f64; 7]>,
    /// Full mid-surface fields at the scene's snapshot lambdas.
    #[serde(skip)]
    pub snapshots: Vec<Snapshot>,
}

/// What an ANM step costs on average over the run, from the engine's
/// counters (milliseconds), against the target step <= 1.5 x (one
/// factorization + N solves).
#[derive(Clone, Debug, Serialize)]
pub struct StepCost {
    /// Tangents and residuals assembled, per step.
    pub assembly_per_step_ms: f64,
    pub factorization_ms: f64,
    pub solve_ms: f64,
    pub series_term_ms: f64,
    /// All timed work (assembly, factorizations, solves, series) per step.
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

/// The mid-surface at one lambda: per node, reference position, displacement,
/// current director, normal reaction R and contact force R n.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub lambda: f64,
    pub x0: Vec<[f64; 3]>,
    pub displacement: Vec<[f64; 3]>,
    pub director: Vec<[f64; 3]>,
    pub reaction: Vec<f64>,
    pub force: Vec<[f64; 3]>,
    /// The state itself, 6 per node (v, w; zeros at clamped dofs): what the
    /// fields above are computed from, for checks that re-evaluate the
    /// equations (`study::shell_check`) without the rounding of x - x0.
    pub state: Vec<f64>,
}

impl Snapshot {
    /// [x_lo, x_hi]: smallest and largest initial x of the nodes with R > threshold.
    pub fn contact_zone(&self, threshold: f64) -> Option<(f64, f64)> {
        let xs: Vec<f64> = self
            .x0
            .iter()
            .zip(&self.reaction)
            .filter(|(_, r)| **r > threshold)
            .map(|(x, _)| x[0])
            .collect();
        (!xs.is_empty()).then(|| {
            (
                xs.iter().copied().fold(f64::INFINITY, f64::min),
                xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        })
    }
}

impl RunReport {
    /// uz_A at a grid value of lambda (nearest row within 1e-9).
    pub fn uz_at(&self, lambda: f64) -> Option<f64> {
        self.history
            .iter()
            .find(|r| (r[0] - lambda).abs() < 1e-9)
            .map(|r| r[1])
    }
}

/// Builds the shell model of a scene: elements, clamps, loads, contact.
pub fn build_model(scene: &ShellScene) -> Result<ShellModel> {
    let mut m = ShellModel::new(
        scene.mesh.nodes.clone(),
        scene.directors.clone(),
        &scene.mesh.quads,
        scene.thickness,
        scene.material,
    )
    .map_err(|e| match e {
        crate::Error::Element { element, problem } => crate::Error::Mesh {
            file: scene.mesh.file.clone(),
            line: scene.mesh.quad_lines[element],
            problem: format!("element {}: {problem}", scene.mesh.quad_tags[element]),
        },
        other => other,
    })?;
    let fixed: Vec<(usize, usize)> = scene
        .clamped
        .iter()
        .flat_map(|&n| (0..6).map(move |k| (n, k)))
        .collect();
    m.set_constraints(&fixed);
    for l in &scene.loads {
        for k in 0..3 {
            m.dead[6 * l.node + k] += l.force[k];
        }
    }
    if !scene.contact_nodes.is_empty() {
        m.set_contact(
            scene.obstacles.clone(),
            &scene.contact_nodes,
            scene.contact_k,
            scene.contact_eta,
            scene.search_distance,
        )
        .map_err(|(node, ob, h0)| crate::Error::Invalid {
            file: scene.file.clone(),
            key: format!("obstacle[{ob}]"),
            problem: format!(
                "contact node {} at {:?} has initial gap {h0:e}: eq. (3) needs delta = h0 > 0",
                node + 1,
                scene.mesh.nodes[node].as_slice()
            ),
        })?;
        if !far_nodes_may_be_skipped(&m, scene.solver.residual_tol) {
            m.search_distance = f64::INFINITY;
            let rest = vec![0.0; 6 * m.n_nodes()];
            m.update_active(&rest);
        }
    }
    Ok(m)
}

/// |F|: the 2-norm of the dead load pattern on the free dofs (N), the
/// scale of the engine's residual test |R| / |R_lambda| <= solver.residual_tol.
pub fn load_norm(m: &ShellModel) -> f64 {
    m.dead
        .iter()
        .zip(&m.free)
        .filter(|(_, f)| f.is_some())
        .map(|(x, _)| x * x)
        .sum::<f64>()
        .sqrt()
}

/// DESIGN §3: far candidates may be left out of the active set only where
/// their forces are below the accuracy asked for. A pair left out at gap
/// h >= s (the search distance) would carry at most
/// [`search::skipped_force_bound`] (a pull of up to eta, or a push of about
/// eta (delta - h) / h for a node that started farther than s), so all of
/// them together change the residual by at most the 2-norm of those bounds;
/// skipping is allowed while that stays within solver.residual_tol |F|.
/// Otherwise every candidate carries its term: a node entering the active
/// set would add its force to the residual at once, a jump the steps cannot
/// follow (eta = 1e-2 N with the 0.05 m search distance stalled at lambda =
/// 0.117 after 7383 factorizations), and the skipped forces would bend the
/// answer unnoticed. On the canonical scenes (eta = 1e-6 N) the bound is
/// 4.6e-5 N (0.1 m mesh) to 1.5e-4 N (0.025 m) against residual_tol |F| =
/// 1.7e-5 N: every candidate is active (same uz_A(1) to 1e-6 m and the same
/// steps as with the 0.05 m search distance).
pub fn far_nodes_may_be_skipped(m: &ShellModel, residual_tol: f64) -> bool {
    let bound = m
        .pairs
        .iter()
        .map(|p| search::skipped_force_bound(p, m.search_distance).powi(2))
        .sum::<f64>()
        .sqrt();
    bound <= residual_tol * load_norm(m)
}

/// Runs a plate-cylinder scene file and writes the outputs into `out_dir`.
pub fn run_scene(scene_path: &Path, out_dir: &Path, progress: bool) -> Result<RunReport> {
    let scene = load(scene_path)?;
    run_loaded(&scene, Some(out_dir), progress)
}

/// Outputs evaluated from a state: what history.csv and the VTK files need.
struct Probe<'a> {
    scene: &'a ShellScene,
    x0: Vec<Vec3>,
    free: Vec<Option<usize>>,
    pairs: Vec<search::ContactPair>,
    obstacles: Vec<Obstacle>,
    distance: f64,
}

impl Probe<'_> {
    fn expand(&self, u: &[f64]) -> Vec<f64> {
        self.free.iter().map(|f| f.map_or(0.0, |i| u[i])).collect()
    }

    fn positions(&self, full: &[f64]) -> Vec<Vec3> {
        (0..self.x0.len())
            .map(|i| self.x0[i] + Vec3::new(full[6 * i], full[6 * i + 1], full[6 * i + 2]))
            .collect()
    }

    /// Per-node reaction R and force R n for the active pairs.
    fn reactions(&self, full: &[f64], active: &[usize]) -> (Vec<f64>, Vec<Vec3>) {
        let x = self.positions(full);
        let mut r = vec![0.0; self.x0.len()];
        let mut f = vec![Vec3::zeros(); self.x0.len()];
        for &ip in active {
            let p = &self.pairs[ip];
            if let Some(g) = self.obstacles[p.obstacle].gap(&x[p.node]) {
                let rn = p.law.force(g.h);
                r[p.node] += rn;
                f[p.node] += g.n * rn;
            }
        }
        (r, f)
    }

    fn row(&self, lambda: f64, full: &[f64], active: &[usize]) -> [f64; 7] {
        let (r, _) = self.reactions(full, active);
        let a = self.scene.probe;
        let sum = |rows: &[usize]| rows.iter().map(|&n| r[n]).sum::<f64>();
        [
            lambda,
            full[6 * a + 2],
            full[6 * a],
            sum(&self.scene.rows[0]),
            sum(&self.scene.rows[1]),
            sum(&self.scene.rows[2]),
            r.iter().sum(),
        ]
    }
}

/// The state of an accepted step at lambda = g: on the series where it
/// reaches g; between the series end and the corrected end point (the step
/// end correction moves lambda by a residual-sized amount) by linear
/// interpolation of that correction.
fn state_at(step: &PathStep, g: f64) -> Option<Vec<f64>> {
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

/// Grid points of history.csv that had to be corrected, and the cost.
struct GridFix {
    /// A second instance of the model (the engine holds the first).
    model: ShellModel,
    load_norm: f64,
    lu: SparseLu,
    points: usize,
    factorizations: usize,
}

impl GridFix {
    /// A grid point inside a step comes from the step's series, which the
    /// engine checks at the step end only: when that end needed correction,
    /// the series inside the step is off the path by up to the end's
    /// uncorrected residual (plate-cylinder, 0.1 m mesh: up to 5.4e-4 |F| at
    /// lambda = 0.49, a state error of 4.8e-7 m). The point is held to the
    /// engine's own test, |R| / |F| <= solver.residual_tol, and corrected by
    /// Newton at fixed lambda when above it.
    fn correct(
        &mut self,
        u: Vec<f64>,
        lambda: f64,
        start_full: &[f64],
        cfg: &ContinuationConfig,
        step: usize,
    ) -> Result<Vec<f64>> {
        let m = &mut self.model;
        // The active set of the step (from its start, as the engine's model).
        m.update_active(start_full);
        let mut u = u;
        let mut r = m.residual(&u, lambda)?;
        let mut res = norm(&r) / self.load_norm;
        if res <= cfg.residual_tol {
            return Ok(u);
        }
        self.points += 1;
        let mut it = 0;
        while res > cfg.residual_tol || !res.is_finite() {
            if it >= cfg.max_corrections || !res.is_finite() {
                return Err(Error::NoConvergence {
                    step,
                    param: "lambda",
                    at: lambda,
                    iterations: it,
                    residual: res,
                    tolerance: cfg.residual_tol,
                });
            }
            let (k, _) = m.tangent(&u, lambda)?;
            let f = self
                .lu
                .factorize(&k)
                .map_err(|detail| Error::SingularMatrix {
                    step,
                    param: "lambda",
                    at: lambda,
                    detail: format!("correcting the output grid point: {detail}"),
                })?;
            self.factorizations += 1;
            let du = f.solve(&r.iter().map(|x| -x).collect::<Vec<_>>());
            for (x, d) in u.iter_mut().zip(&du) {
                *x += d;
            }
            r = m.residual(&u, lambda)?;
            res = norm(&r) / self.load_norm;
            it += 1;
        }
        Ok(u)
    }
}

/// Runs a loaded scene; `out_dir` None writes nothing (tests).
pub fn run_loaded(scene: &ShellScene, out_dir: Option<&Path>, progress: bool) -> Result<RunReport> {
    let start = Instant::now();
    let mut model = build_model(scene)?;
    if let Some(d) = out_dir {
        create_dir(d)?;
    }
    let probe = Probe {
        scene,
        x0: model.x0.clone(),
        free: model.free.clone(),
        pairs: model.pairs.clone(),
        obstacles: model.obstacles.clone(),
        distance: model.search_distance,
    };
    let n_dof = model.ndof();
    let mut fix = GridFix {
        model: build_model(scene)?,
        load_norm: load_norm(&model),
        lu: SparseLu::new(),
        points: 0,
        factorizations: 0,
    };
    let cfg = scene.solver.clone();
    let bar = progress.then(|| {
        let b = indicatif::ProgressBar::new(1000);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {percent:>3}% {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let mut history: Vec<[f64; 7]> = vec![];
    let mut next_grid = 0usize;
    let mut pvd: Vec<(f64, usize, String)> = vec![];
    let mut pull_bound = 0.0f64;
    let mut active_sum = 0usize;
    let mut last: Option<(Vec<f64>, f64, Vec<usize>)> = None;
    let mut snapshots: Vec<Snapshot> = vec![];
    let snapshot = |lambda: f64, full: &[f64], active: &[usize]| {
        let x = probe.positions(full);
        let (r, f) = probe.reactions(full, active);
        let arr = |v: Vec3| [v[0], v[1], v[2]];
        Snapshot {
            lambda,
            x0: probe.x0.iter().map(|v| arr(*v)).collect(),
            displacement: (0..x.len()).map(|i| arr(x[i] - probe.x0[i])).collect(),
            director: (0..x.len())
                .map(|i| {
                    arr(scene.directors[i]
                        + Vec3::new(full[6 * i + 3], full[6 * i + 4], full[6 * i + 5]))
                })
                .collect(),
            reaction: r,
            force: f.into_iter().map(arr).collect(),
            state: full.to_vec(),
        }
    };
    let write_shell = |file: &str, full: &[f64], active: &[usize]| -> Result<()> {
        let Some(d) = out_dir else { return Ok(()) };
        let x = probe.positions(full);
        let n = x.len();
        let disp: Vec<Vec3> = (0..n).map(|i| x[i] - probe.x0[i]).collect();
        let dir: Vec<Vec3> = (0..n)
            .map(|i| {
                scene.directors[i] + Vec3::new(full[6 * i + 3], full[6 * i + 4], full[6 * i + 5])
            })
            .collect();
        let (r, f) = probe.reactions(full, active);
        write_vtu(
            &d.join(file),
            &x,
            &scene.mesh.quads,
            &[
                PointData::Vector("displacement", disp),
                PointData::Vector("director", dir),
                PointData::Vector("contact_force", f),
                PointData::Scalar("contact_reaction", r),
            ],
        )
    };
    let result = if let Some(ncfg) = &scene.newton {
        run_newton(
            &mut model,
            &probe,
            scene,
            ncfg,
            n_dof,
            &mut history,
            &mut snapshots,
            &mut last,
            &bar,
            &snapshot,
        )
    } else {
        run(
            &mut model,
            vec![0.0; n_dof],
            0.0,
            &cfg,
            |step: &PathStep, stats: &Stats| {
                let full0 = probe.expand(&step.u[0]);
                let active = search::active(
                    &probe.pairs,
                    &probe.positions(&full0),
                    &probe.obstacles,
                    probe.distance,
                );
                if active.len() < probe.pairs.len() {
                    let mut is_active = vec![false; probe.pairs.len()];
                    for &i in &active {
                        is_active[i] = true;
                    }
                    let skipped: f64 = probe
                        .pairs
                        .iter()
                        .zip(&is_active)
                        .filter(|(_, a)| !**a)
                        .map(|(p, _)| search::skipped_force_bound(p, probe.distance))
                        .sum();
                    pull_bound = pull_bound.max(skipped);
                }
                active_sum += active.len();
                if step.index == 0 {
                    history.push(probe.row(step.lambda[0], &full0, &active));
                    next_grid = 1;
                    write_shell("shell_0000.vtu", &full0, &active)?;
                    pvd.push((step.lambda[0], 0, "shell_0000.vtu".into()));
                }
                loop {
                    let g = next_grid as f64 * scene.lambda_step;
                    if g > step.lambda_end + 1e-12 || g > cfg.lambda_end + 1e-12 {
                        break;
                    }
                    let u = state_at(step, g).ok_or_else(|| {
                        crate::Error::Output(format!(
                            "step {}: lambda grid value {g} lies in [{}, {}] but on neither the series nor its correction",
                            step.index, step.lambda[0], step.lambda_end
                        ))
                    })?;
                    let u = fix.correct(u, g, &full0, &cfg, step.index)?;
                    let full = probe.expand(&u);
                    history.push(probe.row(g, &full, &active));
                    if scene.snapshots.iter().any(|s| (s - g).abs() < 1e-9) {
                        snapshots.push(snapshot(g, &full, &active));
                    }
                    next_grid += 1;
                }
                let full_end = probe.expand(&step.u_end);
                if scene.vtk_every > 0 && (step.index + 1).is_multiple_of(scene.vtk_every) {
                    let name = format!("shell_{:04}.vtu", step.index + 1);
                    write_shell(&name, &full_end, &active)?;
                    pvd.push((step.lambda_end, 0, name));
                }
                last = Some((full_end, step.lambda_end, active));
                if let Some(b) = &bar {
                    let frac = (step.lambda_end / cfg.lambda_end).clamp(0.0, 1.0);
                    b.set_position((frac * 1000.0) as u64);
                    b.set_message(format!(
                        "lambda {:.4}  steps {}  factorizations {}",
                        step.lambda_end, stats.steps, stats.factorizations
                    ));
                }
                Ok(())
            },
        )
    };
    if let Some(b) = &bar {
        b.finish();
    }
    let (stop, uz_end) = {
        let reason = result.stop.clone();
        let message = match (&result.error, result.stop.as_str()) {
            (Some(e), _) => Some(e.to_string()),
            (None, "max_steps") => Some(format!(
                "solver.max_steps = {} reached at lambda = {}",
                cfg.max_steps, result.lambda_end
            )),
            _ => None,
        };
        (
            Stop {
                reason,
                t: None,
                lambda: Some(result.lambda_end),
                message,
            },
            if result.u_end.is_empty() {
                0.0
            } else {
                probe.expand(&result.u_end)[6 * scene.probe + 2]
            },
        )
    };
    if let (Some(d), Some((full, lam, active))) = (out_dir, &last) {
        let name = "shell_final.vtu".to_string();
        write_shell(&name, full, active)?;
        pvd.push((*lam, 0, name));
        // Obstacles: one file each, shown at every time of the collection.
        let size = scene.mesh.size();
        let times: Vec<f64> = pvd.iter().map(|e| e.0).collect();
        for (k, ob) in scene.obstacles.iter().enumerate() {
            let (pts, quads) = match ob {
                Obstacle::Cylinder {
                    centre,
                    axis,
                    radius,
                } => cylinder_surface(centre, axis, *radius, 1.5 * size.min(4.0 * radius), 96),
                Obstacle::Plane { point, normal } => {
                    let (p, q) = cylinder_surface(point, normal, 0.5 * size, 0.0, 4);
                    (p, q)
                }
            };
            let name = format!("obstacle_{k}.vtu");
            write_vtu(&d.join(&name), &pts, &quads, &[])?;
            for &t in &times {
                pvd.push((t, k + 1, name.clone()));
            }
        }
        write_pvd(&d.join("plate-cylinder.pvd"), &pvd)?;
        write_csv(
            &d.join("history.csv"),
            &["lambda", "uz_A", "ux_A", "rn_B", "rn_C", "rn_D", "rn_total"],
            &history.iter().map(|r| r.to_vec()).collect::<Vec<_>>(),
        )?;
        // Per-node contact forces at the last accepted point.
        let x = probe.positions(full);
        let mut rows = vec![];
        for &ip in active {
            let p = &probe.pairs[ip];
            if let Some(g) = probe.obstacles[p.obstacle].gap(&x[p.node]) {
                let r = p.law.force(g.h);
                let x0 = probe.x0[p.node];
                rows.push(vec![
                    (p.node + 1) as f64,
                    p.obstacle as f64,
                    x0[0],
                    x0[1],
                    x0[2],
                    g.h,
                    r,
                    r * g.n[0],
                    r * g.n[1],
                    r * g.n[2],
                ]);
            }
        }
        write_csv(
            &d.join("contact_final.csv"),
            &[
                "node", "obstacle", "X", "Y", "Z", "gap", "rn", "fx", "fy", "fz",
            ],
            &rows,
        )?;
    }
    let stats = result.stats.clone();
    let report = RunReport {
        scene: scene.file.display().to_string(),
        mesh: scene.mesh.file.display().to_string(),
        nodes: scene.mesh.nodes.len(),
        elements: scene.mesh.quads.len(),
        dofs: n_dof,
        contact_candidates: probe.pairs.len(),
        steps: stats.steps,
        factorizations: stats.factorizations + fix.factorizations,
        grid_corrections: fix.points,
        solves: stats.solves,
        corrections: stats.corrections,
        wall_s: start.elapsed().as_secs_f64(),
        step_cost: StepCost::new(&stats, cfg.order),
        stats,
        stop,
        uz_a_end: uz_end,
        skipped_pull_bound: pull_bound,
        peak_rss_bytes: crate::output::peak_rss_bytes(),
        mean_active_contacts: (scene.newton.is_none() && result.stats.steps > 0)
            .then(|| active_sum as f64 / result.stats.steps as f64),
        far_nodes_skipped: probe.distance.is_finite(),
        history,
        snapshots,
    };
    if let Some(d) = out_dir {
        write_json(&d.join("summary.json"), &report)?;
        if scene.hdf5 {
            write_fields(&d.join("fields.h5"), scene, &report.snapshots)?;
        }
        if scene.plot && report.history.len() > 1 {
            let col = |k: usize| {
                report
                    .history
                    .iter()
                    .map(|r| (r[0], r[k]))
                    .collect::<Vec<_>>()
            };
            draw(
                &d.join("plot.svg"),
                &[
                    Panel {
                        title: "plate-cylinder: deflection at A",
                        x_label: "lambda (-)",
                        y_label: "uz_A (m)",
                        curves: vec![Curve {
                            label: "uz_A",
                            points: col(1),
                        }],
                        log: (false, false),
                    },
                    Panel {
                        title: "plate-cylinder: normal contact forces",
                        x_label: "lambda (-)",
                        y_label: "R (N)",
                        curves: vec![
                            Curve {
                                label: "rn_B (x = 1.0)",
                                points: col(3),
                            },
                            Curve {
                                label: "rn_C (x = 1.1)",
                                points: col(4),
                            },
                            Curve {
                                label: "rn_D (x = 1.2)",
                                points: col(5),
                            },
                            Curve {
                                label: "rn_total",
                                points: col(6),
                            },
                        ],
                        log: (false, false),
                    },
                ],
            )?;
        }
    }
    Ok(report)
}

/// fields.h5: one group per snapshot (feature `hdf5`).
#[cfg(feature = "hdf5")]
fn write_fields(path: &Path, scene: &ShellScene, snapshots: &[Snapshot]) -> Result<()> {
    let mut w = crate::output::hdf5::FieldWriter::create(
        path,
        &[
            ("scene", &scene.file.display().to_string()),
            ("kind", "plate-cylinder"),
            ("units", "m, N; director dimensionless"),
        ],
    )?;
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

/// Takes a snapshot of the mid-surface at (lambda, full state, active pairs).
type SnapshotFn<'a> = dyn Fn(f64, &[f64], &[usize]) -> Snapshot + 'a;

/// The Newton-Raphson baseline on the same model (`solver.method = "newton"`):
/// it lands exactly on every lambda of the output grid, where history rows and
/// snapshots are taken.
#[allow(clippy::too_many_arguments)]
fn run_newton(
    model: &mut ShellModel,
    probe: &Probe,
    scene: &ShellScene,
    cfg: &crate::series::newton::NewtonConfig,
    n_dof: usize,
    history: &mut Vec<[f64; 7]>,
    snapshots: &mut Vec<Snapshot>,
    last: &mut Option<(Vec<f64>, f64, Vec<usize>)>,
    bar: &Option<indicatif::ProgressBar>,
    snapshot: &SnapshotFn,
) -> PathResult {
    let n_grid = (cfg.lambda_end / scene.lambda_step).round() as usize;
    let grid: Vec<f64> = (1..=n_grid).map(|i| i as f64 * scene.lambda_step).collect();
    let full0 = vec![0.0; probe.x0.len() * 6];
    history.push(probe.row(0.0, &full0, &[]));
    crate::series::newton::run(
        model,
        vec![0.0; n_dof],
        0.0,
        cfg,
        &grid,
        |u, lambda, stats| {
            let full = probe.expand(u);
            let active = search::active(
                &probe.pairs,
                &probe.positions(&full),
                &probe.obstacles,
                probe.distance,
            );
            if grid.iter().any(|g| (g - lambda).abs() < 1e-12) {
                let g = (lambda / scene.lambda_step).round() * scene.lambda_step;
                history.push(probe.row(g, &full, &active));
                if scene.snapshots.iter().any(|s| (s - g).abs() < 1e-9) {
                    snapshots.push(snapshot(g, &full, &active));
                }
            }
            *last = Some((full, lambda, active));
            if let Some(b) = bar {
                b.set_position(((lambda / cfg.lambda_end).clamp(0.0, 1.0) * 1000.0) as u64);
                b.set_message(format!(
                    "Newton: lambda {lambda:.4}  steps {}  factorizations {}",
                    stats.steps, stats.factorizations
                ));
            }
            Ok(())
        },
    )
}

//! Shell work-precision: the ANM against the Newton-Raphson baseline on the
//! same shell model (same residual, tangent, element and sparse LU), at
//! several orders, tolerances and step sizes.
//!
//! Error = max over the output grid of |q - q_ref| / max |q_ref| for the
//! scene's key probe q (its first [[probe]]; uz_A on plate-cylinder), against the tightest ANM run (order 20,
//! eps 1e-12, step-end residual the first of [`REFERENCE_RESIDUALS`] that
//! it reaches the end with); the Newton run at
//! that residual is measured against it too, as the floor of what the table
//! resolves. Both methods report on the same λ grid
//! (`output.lambda_step`, 0.05 here): Newton must converge at each grid
//! value, the ANM evaluates its series there.

use super::bench::{BenchRow, median};
use crate::error::Result;
use crate::run::{RunReport, run_loaded};
use crate::scene::shell::Method;
use crate::scene::shell::ShellScene;
use crate::series::newton::{Control, NewtonConfig};

/// Output grid of the benchmark runs.
pub const LAMBDA_STEP: f64 = 0.05;
/// Errors at which the speed targets are compared.
pub const TARGET_ERRORS: [f64; 2] = [1e-4, 1e-6];
/// ANM / Newton wall time and factorizations at each target error (issue
/// 12, item 4).
const TARGET_WALL: f64 = 0.2;
const TARGET_FACTORIZATIONS: f64 = 0.1;
/// The step-end and grid-point residual tolerances |R| / |F| of the ANM
/// settings besides the scene's own, as Newton's `tol` is swept: a looser
/// one leaves the step ends uncorrected.
pub const ANM_RESIDUAL_TOLS: [f64; 1] = [1e-4];

/// A solver and its accuracy setting.
#[derive(Clone, Debug, PartialEq)]
pub enum ShellMethod {
    Anm {
        order: usize,
        eps: f64,
        pade: bool,
        /// `solver.residual_tol` (`None`: the scene's).
        residual_tol: Option<f64>,
    },
    Newton {
        control: Control,
        max_step: f64,
        tol: f64,
        /// Backtracking on |R| after each correction (NewtonConfig).
        line_search: bool,
    },
}

impl ShellMethod {
    pub fn label(&self) -> String {
        match self {
            ShellMethod::Anm { order, pade, .. } => {
                format!("ANM N={order}{}", if *pade { " Padé" } else { "" })
            }
            ShellMethod::Newton {
                control,
                line_search,
                ..
            } => format!(
                "Newton {}{}",
                match control {
                    Control::Load => "load",
                    Control::Arclength => "arclength",
                },
                if *line_search { " + line search" } else { "" }
            ),
        }
    }

    pub fn setting(&self) -> String {
        match self {
            ShellMethod::Anm {
                eps, residual_tol, ..
            } => match residual_tol {
                None => format!("eps={eps:.0e}"),
                Some(r) => format!("eps={eps:.0e} tol={r:.0e}"),
            },
            ShellMethod::Newton { max_step, tol, .. } => {
                format!("step<={max_step} tol={tol:.0e}")
            }
        }
    }

    /// The scene with this method's settings and the benchmark's output grid.
    pub fn configure(&self, scene: &ShellScene) -> ShellScene {
        let mut s = scene.clone();
        s.output.lambda_step = LAMBDA_STEP * s.solver.lambda_end.abs();
        s.output.plot = false;
        match self {
            ShellMethod::Anm {
                order,
                eps,
                pade,
                residual_tol,
            } => {
                s.solver.order = *order;
                s.solver.eps = *eps;
                s.solver.pade = *pade;
                if let Some(r) = residual_tol {
                    s.solver.residual_tol = *r;
                }
                s.method = Method::Anm;
            }
            ShellMethod::Newton {
                control,
                max_step,
                tol,
                line_search,
            } => {
                s.method = Method::Newton(NewtonConfig {
                    control: *control,
                    line_search: *line_search,
                    initial_step: max_step.min(0.01),
                    max_step: *max_step,
                    tol: *tol,
                    lambda_end: s.solver.lambda_end,
                    max_steps: s.solver.max_steps,
                    ..NewtonConfig::default()
                });
            }
        }
        s
    }
}

/// Solves the scene with a method (no files written).
pub fn solve(scene: &ShellScene, method: &ShellMethod) -> Result<RunReport> {
    run_loaded(&method.configure(scene), None, false)
}

/// The benchmark matrix: ANM N = 10, 15, 20 x eps 1e-4 … 1e-10, with
/// and without Padé, at the scene's residual tolerance and at each of
/// [`ANM_RESIDUAL_TOLS`]; Newton by load control (increments up to 0.005 …
/// 0.05) and arclength control, at |R| / |F| <= 1e-3 … 1e-7, and
/// arclength control with a line search.
pub fn methods() -> Vec<ShellMethod> {
    let mut m = vec![];
    let tols = std::iter::once(None).chain(ANM_RESIDUAL_TOLS.map(Some));
    for residual_tol in tols {
        for pade in [false, true] {
            for order in [10, 15, 20] {
                for eps in [1e-4, 1e-6, 1e-8, 1e-10] {
                    m.push(ShellMethod::Anm {
                        order,
                        eps,
                        pade,
                        residual_tol,
                    });
                }
            }
        }
    }
    for max_step in [0.005, 0.01, 0.025, 0.05] {
        for tol in [1e-3, 1e-4, 1e-6, 1e-7] {
            m.push(ShellMethod::Newton {
                control: Control::Load,
                max_step,
                tol,
                line_search: false,
            });
        }
    }
    for line_search in [false, true] {
        for max_step in [0.1, 1.0] {
            for tol in [1e-4, 1e-6] {
                m.push(ShellMethod::Newton {
                    control: Control::Arclength,
                    max_step,
                    tol,
                    line_search,
                });
            }
        }
    }
    m
}

/// The reference run and how far an independent tight run is from it.
pub struct ShellReference {
    pub report: RunReport,
    pub name: String,
    /// Error of the tightest Newton run against the reference.
    pub floor: f64,
    /// The step-end residual |R|/|F| both runs were held to.
    pub residual: f64,
}

/// Solves the tightest ANM and Newton runs of the scene, at the first of
/// [`REFERENCE_RESIDUALS`] that both reach the end with.
pub fn reference(scene: &ShellScene) -> Result<ShellReference> {
    let mut failure = None;
    for &tol in &REFERENCE_RESIDUALS {
        match reference_at(scene, tol) {
            Ok(r) => return Ok(r),
            Err(e) => failure = Some(e),
        }
    }
    Err(failure.expect("REFERENCE_RESIDUALS is not empty"))
}

/// The reference runs at step-end residual `tol`.
fn reference_at(scene: &ShellScene, tol: f64) -> Result<ShellReference> {
    let anm = ShellMethod::Anm {
        order: 20,
        eps: 1e-12,
        pade: false,
        residual_tol: Some(tol),
    };
    let tight = anm.configure(scene);
    let report = complete(run_loaded(&tight, None, false)?)?;
    let newton = ShellMethod::Newton {
        control: Control::Load,
        max_step: 0.01,
        tol,
        line_search: false,
    };
    let check = complete(solve(scene, &newton)?)?;
    let floor = uz_error(&check, &report);
    Ok(ShellReference {
        report,
        name: format!(
            "{} {} (tol: the step-end |R|/|F|)",
            anm.label(),
            anm.setting()
        ),
        floor,
        residual: tol,
    })
}

/// Step-end residuals the reference runs try, tightest first. Below about
/// 1e-8 |F| the residual of the shell sits at its round-off floor near
/// lambda = 0 (both methods stop there: measured 1.3e-8 and 6e-9 at lambda
/// ~ 1e-10 on the 0.1 m mesh), and the floor rises with the mesh: on the
/// 0.05 m mesh the ANM reference stops at 2e-8 (a residual of 2.6e-8 to
/// 3.0e-8 near lambda = 1e-4), and the 0.025 m mesh reaches the end at 1e-7.
pub const REFERENCE_RESIDUALS: [f64; 3] = [2e-8, 1e-7, 5e-7];

/// A reference run must reach the end of the grid.
fn complete(report: RunReport) -> Result<RunReport> {
    if report.stop.reason == "end" {
        Ok(report)
    } else {
        Err(crate::Error::study(
            "bench",
            report.scene.clone(),
            format!(
                "the reference run stopped early: {}",
                report
                    .stop
                    .message
                    .as_deref()
                    .unwrap_or(&report.stop.reason)
            ),
        ))
    }
}

/// max over the grid of |q - q_ref| / max |q_ref| for the key probe q (the
/// first probe, column 1); infinite when the run did not reach the end of
/// the grid.
pub fn uz_error(run: &RunReport, reference: &RunReport) -> f64 {
    if reference.columns.len() < 2 {
        return f64::INFINITY;
    }
    let scale = reference
        .history
        .iter()
        .map(|r| r[1].abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    if run.history.len() != reference.history.len() {
        return f64::INFINITY;
    }
    run.history
        .iter()
        .zip(&reference.history)
        .map(|(a, b)| {
            if (a[0] - b[0]).abs() > 1e-9 {
                f64::INFINITY
            } else {
                (a[1] - b[1]).abs() / scale
            }
        })
        .fold(0.0, f64::max)
}

/// Cost of one ANM step against the unit "one factorization + N solves".
#[derive(Clone, Debug)]
pub struct StepCost {
    pub method: String,
    pub setting: String,
    /// Seconds per accepted step, everything included (wall / steps).
    pub step_s: f64,
    pub factorization_s: f64,
    pub solve_s: f64,
    pub order: usize,
    /// Per step: assembly, factorization, solves, series terms (s).
    pub breakdown: [f64; 4],
}

impl StepCost {
    /// step cost / (one factorization + N solves).
    pub fn ratio(&self) -> f64 {
        self.step_s / (self.factorization_s + self.order as f64 * self.solve_s)
    }
}

/// Runs every method `repeat` times and measures it against the reference.
pub fn work_precision(
    case: &str,
    scene: &ShellScene,
    methods: &[ShellMethod],
    reference: &RunReport,
    repeat: usize,
    mut progress: impl FnMut(&ShellMethod, &BenchRow),
) -> (Vec<BenchRow>, Vec<StepCost>) {
    let mut rows = vec![];
    let mut costs = vec![];
    for m in methods {
        let mut walls = vec![];
        // repeat >= 1, so the loop sets it.
        let mut last: std::result::Result<RunReport, String> = Err(String::new());
        for _ in 0..repeat.max(1) {
            match solve(scene, m) {
                Ok(r) if r.stop.reason == "end" => {
                    walls.push(r.wall_s);
                    last = Ok(r);
                }
                Ok(r) => {
                    last = Err(r.stop.reason);
                    break;
                }
                Err(e) => {
                    last = Err(e.kind().to_string());
                    break;
                }
            }
        }
        let row = match last {
            Ok(r) => {
                let st = &r.stats;
                let per = |x: f64| x / st.steps.max(1) as f64;
                let breakdown = [
                    per(st.assembly_s),
                    per(st.factorization_s),
                    per(st.solve_s),
                    per(st.series_s),
                ];
                let wall_min_s = walls.iter().copied().fold(f64::INFINITY, f64::min);
                let wall_s = median(walls);
                if let ShellMethod::Anm { order, .. } = m {
                    costs.push(StepCost {
                        method: m.label(),
                        setting: m.setting(),
                        step_s: wall_s / st.steps.max(1) as f64,
                        factorization_s: st.factorization_s / st.factorizations.max(1) as f64,
                        solve_s: st.solve_s / st.solves.max(1) as f64,
                        order: *order,
                        breakdown,
                    });
                }
                BenchRow {
                    case: case.into(),
                    method: m.label(),
                    setting: m.setting(),
                    error: uz_error(&r, reference),
                    wall_s,
                    wall_min_s,
                    steps: st.steps,
                    factorizations: st.factorizations,
                    solves: st.solves,
                    breakdown,
                    stop: r.stop.reason.clone(),
                }
            }
            Err(stop) => BenchRow::failed(case, m.label(), m.setting(), stop),
        };
        progress(m, &row);
        rows.push(row);
    }
    (rows, costs)
}

/// The targets, read off the table: at each of [`TARGET_ERRORS`],
/// the fastest ANM and Newton settings reaching it, their time and
/// factorization ratios; then the step-cost ratios.
pub fn targets(rows: &[BenchRow], costs: &[StepCost], probe: &str) -> String {
    let mut s = String::new();
    for target in TARGET_ERRORS {
        let best = |newton: bool| {
            rows.iter()
                .filter(|r| r.method.starts_with("Newton") == newton)
                .filter(|r| r.error <= target && r.wall_s.is_finite())
                .min_by(|a, b| a.wall_s.total_cmp(&b.wall_s))
        };
        s += &format!("\nTargets at error <= {target:.0e} on {probe}:\n\n");
        match (best(false), best(true)) {
            (Some(a), Some(n)) => {
                s += &format!(
                    "- fastest ANM: {} {}: {:.3} s, {} factorizations (error {:.1e})\n",
                    a.method, a.setting, a.wall_s, a.factorizations, a.error
                );
                s += &format!(
                    "- fastest Newton: {} {}: {:.3} s, {} factorizations (error {:.1e})\n",
                    n.method, n.setting, n.wall_s, n.factorizations, n.error
                );
                let tr = a.wall_s / n.wall_s;
                let fr = a.factorizations as f64 / n.factorizations.max(1) as f64;
                let verdict = |met: bool| if met { "met" } else { "missed" };
                s += &format!(
                    "- ANM / Newton wall time {tr:.3} (target <= {TARGET_WALL}: {}), factorizations {fr:.3} (target <= {TARGET_FACTORIZATIONS}: {})\n",
                    verdict(tr <= TARGET_WALL),
                    verdict(fr <= TARGET_FACTORIZATIONS),
                );
            }
            _ => s += "- a method has no setting reaching the target error\n",
        }
    }
    s += "\nANM step cost against one factorization + N solves (target <= 1.5):\n\n";
    s += "| method | setting | step (ms) | factorization (ms) | solve (ms) | ratio | per step: assembly / factorization / solves / series (ms) |\n|---|---|---|---|---|---|---|\n";
    for c in costs {
        s += &format!(
            "| {} | {} | {:.3} | {:.3} | {:.4} | {:.2} | {:.3} / {:.3} / {:.3} / {:.3} |\n",
            c.method,
            c.setting,
            1e3 * c.step_s,
            1e3 * c.factorization_s,
            1e3 * c.solve_s,
            c.ratio(),
            1e3 * c.breakdown[0],
            1e3 * c.breakdown[1],
            1e3 * c.breakdown[2],
            1e3 * c.breakdown[3],
        );
    }
    s
}

/// One variant of the "skip what a scene doesn't need" measurement.
#[derive(Clone, Debug)]
pub struct SkipRow {
    pub variant: &'static str,
    pub unknowns: usize,
    pub velocity_unknowns: usize,
    pub candidates: usize,
    pub mean_contact_terms: f64,
    pub steps: usize,
    pub wall_s: f64,
    /// The key probe at the last history row.
    pub key_end: f64,
}

/// Measures what skipping saves on a shell scene (ANM, scene settings):
/// contact terms only for candidates near an obstacle against every
/// candidate active; no output files against the scene's outputs (VTK every
/// `vtk_every` steps, CSV, plot) and against VTK at every step. The shell is
/// frictionless: it has no velocity unknowns and follows the static path.
pub fn skip_study(scene: &ShellScene, out_dir: &std::path::Path) -> Result<Vec<SkipRow>> {
    let base = ShellMethod::Anm {
        order: scene.solver.order,
        eps: scene.solver.eps,
        pade: scene.solver.pade,
        residual_tol: None,
    };
    let lean = base.configure(scene);
    let mut all_active = lean.clone();
    if let Some(c) = all_active.contact.as_mut() {
        c.search_distance = 1e6;
    }
    let mut outputs = lean.clone();
    outputs.output.plot = true;
    let mut every = outputs.clone();
    every.output.vtk_every = 1;
    let runs: [(&'static str, &ShellScene, Option<std::path::PathBuf>); 4] = [
        (
            "candidates within search_distance (where the skip bound allows), no files",
            &lean,
            None,
        ),
        ("every candidate active, no files", &all_active, None),
        (
            "scene outputs (CSV, plot, VTK every vtk_every steps)",
            &outputs,
            Some(out_dir.join("skip-outputs")),
        ),
        (
            "VTK at every step",
            &every,
            Some(out_dir.join("skip-vtk-every-step")),
        ),
    ];
    let mut rows = vec![];
    for (variant, s, dir) in runs {
        let r = run_loaded(s, dir.as_deref(), false)?;
        rows.push(SkipRow {
            variant,
            unknowns: r.dofs,
            velocity_unknowns: 0,
            candidates: r.contact_candidates,
            mean_contact_terms: r.mean_active_contacts.unwrap_or(f64::NAN),
            steps: r.steps,
            wall_s: r.wall_s,
            key_end: r
                .history
                .last()
                .and_then(|row| row.get(1))
                .copied()
                .unwrap_or(f64::NAN),
        });
    }
    Ok(rows)
}

pub fn skip_markdown(rows: &[SkipRow]) -> String {
    let mut s = String::from(
        "\nSkip what a scene doesn't need (ANM, scene settings):\n\n| variant | unknowns | velocity unknowns | contact candidates | contact terms per step (mean) | steps | wall (s) | key probe (end) |\n|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.1} | {} | {:.3} | {:.9} |\n",
            r.variant,
            r.unknowns,
            r.velocity_unknowns,
            r.candidates,
            r.mean_contact_terms,
            r.steps,
            r.wall_s,
            r.key_end
        );
    }
    s
}

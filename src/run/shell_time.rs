//! `anm run` on a shell scene with `[friction]`: the path in time
//! ([`crate::shell::time_path`]) and its files.
//!
//! - history.csv: t, lambda (the load ramp), the scene's probes, then
//!   rn_total (Σ R_N of the friction nodes), ft_x, ft_y, ft_z (Σ R_T),
//!   max_slip (largest |v_s|) and slip_area (the tributary area of the
//!   nodes that slip, |v_s| > 10 ω Vc: the slip zone);
//! - friction.csv: per friction node at t_end (or the stop): gap, R_N,
//!   R_T, v_s, |v_s| and `slip` (|v_s| > 10 omega Vc) or `stick`;
//! - summary.json: counters, the stop and the last row;
//! - friction.vtu (ParaView): the last state's mid-surface with the
//!   displacement, R_N, the contact pressure (R_N over the node's
//!   tributary area), R_T, v_s, |v_s| and stick (1) / slip (0) per node,
//!   and the membrane stresses per element (along and across its η
//!   direction, shear, principal min and max; run::section);
//! - friction.svg: rn_total and ft_x, ft_y, ft_z, and max_slip against t;
//! - along.csv, along.svg (built-in meshes): per node row of constant t,
//!   the tension, pressure, slip and membrane stresses (run::along_strip).

use super::along_strip;
use super::build::build_model;
use super::probe::{self, State};
use super::time_checkpoint::TimeCheckpoint;
use crate::contact::Motion;
use crate::error::{Error, Result};
use crate::output::plot::{Curve, Panel, draw};
use crate::output::vtk::{PointData, write_vtu_cells};
use crate::output::{Stop, csv_number, mode};
use crate::scene::shell::{
    FrictionSpec, ShellScene, TIME_FORCE_COLUMNS, TIME_STABILITY_COLUMNS, Units,
};
use crate::series::ContinuationProblem;
use crate::shell::friction_dae::{FrictionDae, TimeLaws, TimeState};
use crate::shell::stability::{self, TimeEvent};
use crate::shell::time_path::{self, NodeFriction, TimeConfig, TimeRun, TimeSample, TimeStop};
use indexmap::IndexMap;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// What a run in time reports.
#[derive(Clone, Debug, Serialize)]
pub struct TimeReport {
    pub scene: String,
    /// `scene.description`, to tell runs apart (review 23: documented as
    /// shown in outputs, it was in none).
    pub description: Option<String>,
    /// The scene's kind ("shell") and the method ("anm"), as every
    /// summary.json has them.
    pub kind: &'static str,
    pub method: &'static str,
    pub dofs: usize,
    pub friction_nodes: usize,
    /// Contact nodes left without friction (a fixed translation), 1-based.
    pub nodes_without_friction: Vec<usize>,
    pub steps: usize,
    /// `solver.time_step` and the steps taken by the implicit step.
    pub time_step: String,
    pub implicit_steps: usize,
    /// Of those, the backward Euler steps solved by Newton (where the
    /// Rosenbrock step failed three times, and the 4 steps after).
    pub newton_steps: usize,
    /// Implicit trials rejected (error test or end residual).
    pub rejected: usize,
    pub factorizations: usize,
    pub corrections: usize,
    pub max_residual: f64,
    pub wall_s: f64,
    /// The cost counters under the names every time run uses (IDA's
    /// and the point-mass runs' summary.json `counters`).
    pub counters: crate::reference::counters::Counters,
    /// `reason`: "end", "singularity", "interrupted", or the kind of the
    /// numerical trouble that stopped the run (e.g. "time_steps"); `t`;
    /// `node`: the mesh tag of a singularity's node, or of the node a
    /// numerical stop's diagnosis names; `message`: that diagnosis. The
    /// same object as a static run's `stop` (with `t` for `lambda`).
    pub stop: Stop,
    /// The columns of history.csv at its last row.
    pub end: IndexMap<String, f64>,
    /// history.csv's header (summary.json `columns`, as in every run).
    #[serde(rename = "columns")]
    pub header: Vec<String>,
    /// history.csv's rows (not in summary.json).
    #[serde(skip)]
    pub history: Vec<Vec<f64>>,
    /// Critical points between output times (`friction.stability`).
    pub events: Vec<TimeEvent>,
    /// What the user should know about the answers (e.g. friction nodes
    /// whose stick/slip state the regularization decides).
    /// Always present, empty when there is nothing to say (review 18: a
    /// stopped run's summary.json had no `notes` key).
    pub notes: Vec<String>,
}

/// The model and laws of a friction scene, ready to integrate.
pub fn problem(scene: &ShellScene) -> Result<FrictionDae> {
    let fr = scene.friction.as_ref().ok_or_else(|| Error::Invalid {
        file: scene.file.clone(),
        key: "friction".into(),
        problem: "a run in time needs [friction]".into(),
    })?;
    let mut model = build_model(scene)?;
    // The obstacles keep their place (scene::shell checks that a
    // translation keeps the surface in place); their motion enters the
    // surface velocity only.
    let motions: Vec<Motion> = scene.obstacles.iter().map(|o| o.motion).collect();
    model.set_motions(vec![Motion::Fixed; motions.len()]);
    let extra_loads = fr
        .load_ramps
        .iter()
        .map(|&(i, ramp)| {
            let full = super::build::dead_pattern(scene, &scene.loads[i]).unwrap_or_default();
            (ramp, model.reduce(&full))
        })
        .collect();
    let laws = TimeLaws {
        law: fr.law,
        load: fr.load,
        motion: fr.motion,
        motions,
        extra_loads,
    };
    Ok(FrictionDae::new(model, laws, scene.solver.order))
}

/// The settings of the scene's `[solver]` and `[friction]` tables.
pub fn config(scene: &ShellScene) -> TimeConfig {
    let fr = scene.friction.as_ref().expect("a friction scene");
    let rows = (fr.t_end / fr.output_step).round().max(1.0) as usize;
    let mut outputs: Vec<f64> = (1..=rows)
        .map(|i| (i as f64 * fr.output_step).min(fr.t_end))
        .collect();
    if outputs.last().is_none_or(|&t| t < fr.t_end) {
        outputs.push(fr.t_end);
    }
    outputs.dedup();
    TimeConfig {
        order: scene.solver.order,
        eps: scene.solver.eps,
        t_end: fr.t_end,
        max_steps: scene.solver.max_steps,
        residual_tol: scene.solver.residual_tol,
        max_corrections: scene.solver.max_corrections,
        min_step: scene.solver.min_step * fr.t_end,
        outputs,
        stepping: fr.stepping,
    }
}

/// Solves a friction scene in time (no files).
pub fn solve(scene: &ShellScene) -> Result<(TimeRun, FrictionDae)> {
    solve_with(scene, false, Keep::No)
}

/// Step 0 of a friction scene (time_path::check_start), with the same
/// diagnosis as a run that fails there.
pub fn check_start(scene: &ShellScene) -> Result<()> {
    let mut dae = problem(scene)?;
    time_path::check_start(&mut dae, &config(scene)).map_err(|e| at_rest(scene, e))
}

/// How [`solve_with`] treats numerical trouble, and where it starts.
enum Keep {
    /// Any failure is an error; the run starts at rest.
    No,
    /// Numerical trouble after the start ends the run with what it computed
    /// ([`time_path::run_keeping`]), from rest or from the given state.
    From(Option<TimeState>),
}

fn solve_with(scene: &ShellScene, progress: bool, keep: Keep) -> Result<(TimeRun, FrictionDae)> {
    let mut dae = problem(scene)?;
    let cfg = config(scene);
    let bar = progress.then(crate::output::progress_bar);
    let t_end = cfg.t_end;
    let mut show = |t: f64, steps: usize| {
        if let Some(b) = &bar {
            b.set_position((1000.0 * t / t_end) as u64);
            b.set_message(format!("t = {t:.4e} s, {steps} steps"));
        }
    };
    let run = match keep {
        Keep::No => time_path::run(&mut dae, &cfg, &mut show),
        Keep::From(start) => {
            let start = start.unwrap_or_else(|| time_path::at_rest(&dae));
            time_path::run_keeping(&mut dae, &cfg, &mut show, start)
        }
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    Ok((run.map_err(|e| at_rest(scene, e))?, dae))
}

/// The run starts at rest (U = 0) and first brings that state to
/// equilibrium: where this fails with loads already on at t = 0, say so and
/// name the key that ramps them, rather than a bare "no convergence".
pub(crate) fn at_rest(scene: &ShellScene, e: Error) -> Error {
    let fr = scene.friction.as_ref().expect("a friction scene");
    match e {
        Error::NoConvergence {
            step: 0,
            at,
            iterations,
            residual,
            ..
        } if at == 0.0 && fr.load.value(0.0) > 0.0 && !scene.loads.is_empty() => Error::Invalid {
            file: scene.file.clone(),
            key: "friction.load_ramp".into(),
            problem: format!(
                "the loads are full at t = 0 (load_ramp = [{}, {}]; [0, 0] when absent) and the state at rest could not be brought to equilibrium under them (relative residual {residual:.3e} after {iterations} corrections): ramp them from 0, e.g. load_ramp = [0, {}]",
                fr.load.start,
                fr.load.end,
                fr.t_end / 10.0
            ),
        },
        other => other,
    }
}

/// Columns of history.csv after t and lambda: the probes, then the
/// friction totals.
pub(crate) fn row(
    dae: &FrictionDae,
    scene: &ShellScene,
    areas: &[f64],
    s: &TimeSample,
) -> Result<Vec<f64>> {
    let state = State {
        full: &s.full,
        lambda: s.lambda,
        arclength: f64::NAN,
        residual: None,
        linear: None,
    };
    let mut v = vec![s.t, s.lambda];
    v.extend(probe::evaluate(&dae.model, &scene.probes, &state)?);
    let rn: f64 = s.friction.iter().map(|f| f.rn).sum();
    let ft = s
        .friction
        .iter()
        .fold(nalgebra::Vector3::zeros(), |a, f| a + f.force);
    let slip = s.friction.iter().map(|f| f.slip.norm()).fold(0.0, f64::max);
    let law = dae.laws.law;
    let slip_area: f64 = s
        .friction
        .iter()
        .filter(|f| f.slip.norm() > slip_threshold(&law))
        .map(|f| areas[f.node])
        // fold from +0: an empty f64 sum is −0, printed "-0.0".
        .fold(0.0, |a, x| a + x);
    v.extend([rn, ft[0], ft[1], ft[2], slip, slip_area]);
    Ok(v)
}

/// The slip speed above which a friction node slips (friction.csv, the
/// stick/slip map, slip_area): 10 ω Vc, ten times the regularization's.
pub fn slip_threshold(law: &crate::contact::FrictionLaw) -> f64 {
    10.0 * law.omega * law.vc
}

/// A friction node's state by its slip speed: `slip` above 10 ω Vc,
/// `stick` up to ω Vc, and `transition` between. In that range the
/// regularized law cannot tell a node that sticks (it creeps at
/// ω Vc m / sqrt(1 − m²) for a mobilisation m: 3.3 ω Vc at m = 0.958)
/// from one that slips at a speed the kinematics sets (review 5: a plate
/// held on a plane moving at V = 3.3 ω Vc was labelled `stick` on every
/// node). Returns the label and the VTU `stick` value (1, 0.5, 0).
pub fn friction_state(law: &crate::contact::FrictionLaw, speed: f64) -> (&'static str, f64) {
    if speed > slip_threshold(law) {
        ("slip", 0.0)
    } else if speed > law.omega * law.vc {
        ("transition", 0.5)
    } else {
        ("stick", 1.0)
    }
}

pub(crate) fn header(scene: &ShellScene) -> Vec<String> {
    let mut h = vec!["t".to_string(), "lambda".to_string()];
    h.extend(scene.probes.iter().map(|p| p.name.clone()));
    h.extend(TIME_FORCE_COLUMNS.map(String::from));
    h
}

pub(crate) fn write_err(file: &Path) -> impl Fn(String) -> Error + '_ {
    move |problem| Error::Write {
        file: file.to_path_buf(),
        problem,
    }
}

/// events.csv and one mode_K.vtu per critical point (named in `events`).
fn write_events(
    dir: &Path,
    dae: &FrictionDae,
    quads: &[[usize; 4]],
    events: &mut [TimeEvent],
) -> Result<()> {
    let file = dir.join("events.csv");
    let mut w = csv::Writer::from_path(&file).map_err(|e| write_err(&file)(e.to_string()))?;
    w.write_record([
        "tangent",
        "detected_by",
        "t",
        "lambda",
        "t_before",
        "t_after",
        "bracket_start",
        "bracket_end",
        "restarts",
        "negative_pivots_before",
        "negative_pivots_after",
        "kappa_before",
        "kappa_after",
        "dip",
        "wavelength",
        "half_waves",
        "direction",
        "mode",
    ])
    .map_err(|e| write_err(&file)(e.to_string()))?;
    for (k, e) in events.iter_mut().enumerate() {
        let name = format!("mode_{}.vtu", k + 1);
        mode::write(
            &dir.join(&name),
            &dae.model.x0,
            quads,
            &dae.model.expand(&e.vector, 0.0),
        )?;
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.9e}"));
        w.write_record([
            e.tangent.to_string(),
            e.detected_by.to_string(),
            csv_number(e.t),
            csv_number(e.lambda),
            csv_number(e.outputs[0]),
            csv_number(e.outputs[1]),
            csv_number(e.bracket[0]),
            csv_number(e.bracket[1]),
            e.restarts.to_string(),
            e.negative_pivots[0].to_string(),
            e.negative_pivots[1].to_string(),
            format!("{:.9e}", e.kappa[0]),
            format!("{:.9e}", e.kappa[1]),
            opt(e.dip),
            opt(e.wavelength),
            opt(e.half_waves),
            e.wave_direction.clone().unwrap_or_default(),
            name.clone(),
        ])
        .map_err(|e| write_err(&file)(e.to_string()))?;
        e.mode = Some(name);
    }
    w.flush().map_err(|e| write_err(&file)(e.to_string()))
}

/// Runs a friction scene in time; writes its files into `out_dir`.
pub fn run(scene: &ShellScene, out_dir: Option<&Path>) -> Result<TimeReport> {
    run_with(scene, out_dir, false)
}

/// [`run`] with a progress bar on stderr.
pub fn run_with(scene: &ShellScene, out_dir: Option<&Path>, progress: bool) -> Result<TimeReport> {
    let start = Instant::now();
    let (run, dae) = solve_with(scene, progress, Keep::From(None))?;
    report(scene, run, dae, out_dir, start.elapsed().as_secs_f64())
}

/// Continues the interrupted shell run in time in `out_dir` from its
/// checkpoint.json (run::time_checkpoint): from the state of the last
/// output time written, to the end, with the same files as a run that was
/// not interrupted.
pub fn resume(out_dir: &Path, progress: bool) -> Result<TimeReport> {
    let start = Instant::now();
    let cp = TimeCheckpoint::read(out_dir)?;
    let scene = cp.scene()?;
    let from = cp.samples.last().map(|s| s.state.clone());
    let (mut run, dae) = solve_with(&scene, progress, Keep::From(from))?;
    // The resumed run's first sample is the checkpoint's last one.
    let mut samples = cp.samples;
    samples.extend(run.samples.drain(..).skip(1));
    run.samples = samples;
    run.stats = cp.stats.merged(&run.stats);
    report(
        &scene,
        run,
        dae,
        Some(out_dir),
        cp.wall_s + start.elapsed().as_secs_f64(),
    )
}

/// The report and files of a run (`wall_before`: seconds spent before the
/// outputs, by this process and by the run it resumes).
fn report(
    scene: &ShellScene,
    run: TimeRun,
    mut dae: FrictionDae,
    out_dir: Option<&Path>,
    wall_before: f64,
) -> Result<TimeReport> {
    let start = Instant::now();
    let mut head = header(scene);
    let areas = scene.mesh.node_areas();
    let mut rows: Vec<Vec<f64>> = run
        .samples
        .iter()
        .map(|s| row(&dae, scene, &areas, s))
        .collect::<Result<_>>()?;
    let monitored = scene.friction.as_ref().is_some_and(|f| f.stability);
    let stable = if monitored {
        let law = dae.laws.law;
        stability::monitor(&mut dae.model, &run.samples, &law, scene.solver.linear)?
    } else {
        vec![]
    };
    if monitored {
        // −1: a non-symmetric tied tangent (follower loads) has no inertia.
        head.extend(TIME_STABILITY_COLUMNS.map(String::from));
        let count = |n: Option<usize>| n.map_or(-1.0, |n| n as f64);
        for (r, st) in rows.iter_mut().zip(&stable) {
            r.extend([
                count(st.free.negative_pivots),
                st.free.kappa,
                count(st.tied.negative_pivots),
                st.tied.kappa,
                st.sticking as f64,
            ]);
        }
    }
    let mut events = stability::events(&stable);
    let cfg = config(scene);
    for e in events
        .iter_mut()
        .filter(|e| e.detected_by == "negative pivots")
    {
        let tied = e.tangent == "tied";
        let [a, b] = e.samples;
        let inertia = |k: usize| {
            let st = &stable[k];
            if tied { &st.tied } else { &st.free }
        };
        let a_end = (&run.samples[a], inertia(a));
        let b_end = (&run.samples[b], inertia(b));
        if let Some(l) = stability::locate(&mut dae, &cfg, a_end, b_end, tied, scene.solver.linear)?
        {
            e.t = l.t;
            e.lambda = l.lambda;
            e.bracket = l.bracket;
            e.restarts = l.restarts;
            e.vector = l.mode;
        }
    }
    if monitored {
        events.extend(stability::kink_events(
            &mut dae,
            &cfg,
            &run.samples,
            &stable,
            scene.solver.linear,
        )?);
        events.sort_by(|a, b| a.t.total_cmp(&b.t));
    }
    for e in &mut events {
        let full = dae.model.expand(&e.vector, 0.0);
        if let Some(w) = mode::wavelength(&dae.model.x0, &dae.model.a30, &dae.model.quads(), &full)
        {
            e.wavelength = Some(w.wavelength);
            e.half_waves = Some(w.half_waves);
            e.wave_direction = Some(w.direction.to_string());
        }
    }
    let wall_s = wall_before + start.elapsed().as_secs_f64();
    if let Some(r) = rows.iter().flatten().find(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            step: run.stats.steps,
            param: "t",
            at: run.samples.last().map_or(0.0, |s| s.t),
            what: format!("an output value ({r})"),
        });
    }
    let last = run.samples.last().expect("the sample at t = 0");
    let (reason, stop_t, node, message) = match &run.stop {
        TimeStop::End => ("end", last.t, None, None),
        TimeStop::Singularity { t, node } => ("singularity", *t, Some(*node), None),
        TimeStop::Interrupted { t } => ("interrupted", *t, None, None),
        TimeStop::Failed {
            t,
            kind,
            node,
            message,
        } => (*kind, *t, *node, Some(message.clone())),
    };
    let mut report = TimeReport {
        description: scene.description.clone(),
        scene: scene.file.display().to_string(),
        kind: "shell",
        method: "anm",
        dofs: dae.model.ndof(),
        friction_nodes: last.friction.len(),
        nodes_without_friction: run.skipped.iter().map(|&n| dae.model.node_tag(n)).collect(),
        steps: run.stats.steps,
        time_step: scene
            .friction
            .as_ref()
            .map_or("explicit", |f| f.stepping.name())
            .to_string(),
        implicit_steps: run.stats.implicit,
        newton_steps: run.stats.newton,
        rejected: run.stats.rejected,
        factorizations: run.stats.factorizations,
        corrections: run.stats.corrections,
        max_residual: run.stats.max_residual,
        wall_s,
        counters: crate::reference::counters::Counters::from_shell_time(&run.stats),
        stop: Stop {
            reason: reason.into(),
            t: Some(stop_t),
            lambda: None,
            node,
            message,
        },
        end: head
            .iter()
            .cloned()
            .zip(
                rows.last()
                    .cloned()
                    .unwrap_or_default()
                    .iter()
                    .map(|x| x + 0.0),
            )
            .collect(),
        header: head.clone(),
        history: rows.clone(),
        events,
        notes: vec![],
    };
    // Review 25: holding uy for a planar motion left "0 friction nodes"
    // and no tied stability check, without a word.
    let partly_held = run
        .skipped
        .iter()
        .filter(|&&n| (0..3).any(|c| dae.model.free[crate::fe::dof::index(n, c)].is_some()))
        .count();
    if partly_held > 0 {
        report.notes.push(format!(
            "{partly_held} contact nodes have one or two of their translations held and carry no friction at all (summary.json nodes_without_friction: {} nodes without friction, {} with): friction acts only at contact nodes whose three translations are free, and the tied tangent of the stability monitor holds none of these; hold such nodes through another group, or leave them out of contact.group",
            run.skipped.len(),
            report.friction_nodes
        ));
    }
    if let Some(p) =
        super::penetration::inside(&dae.model, &dae.model.obstacles_at(0.0), &last.full, last.t)
    {
        report.notes.push(super::penetration::note(
            &dae.model,
            &p,
            &scene.obstacles,
            "t",
        ));
    }
    report.notes.extend(
        scene
            .friction
            .as_ref()
            .filter(|_| report.stop.reason == "end")
            .and_then(|f| cut_ramp(f, stop_t)),
    );
    // The strip's rows along its path: along.csv, and the compression
    // note of a run without the stability monitor.
    let along = match (&scene.mesh.grid, &scene.friction) {
        (Some(grid), Some(f)) => Some(along_strip::rows(
            &dae.model,
            grid,
            &scene.mesh.quads,
            scene.thickness,
            &last.full,
            &last.friction,
            slip_threshold(&f.law),
        )),
        _ => None,
    };
    if !monitored && let Some(along) = &along {
        report.notes.extend(unmonitored_compression(along, stop_t));
    }
    if let Some((amplitude, s, [lo, hi], mean)) =
        along.as_deref().and_then(along_strip::pressure_alternation)
        && amplitude > along_strip::ALTERNATION
    {
        report.notes.push(format!(
            "the contact pressure alternates from row to row inside a contact zone at t = {} (s = {:.4} to {:.4}, away from its edges): {lo:.4e} to {hi:.4e} around a mean of {mean:.4e}, up to ±{:.0} % of it (along.csv, friction.csv, friction.vtu); per-node pressures there are not resolved, while totals, tensions and two-row means are: read the pressure as two-row means; the directors there zigzag about the obstacle's normal (friction.vtu `director`), a mode that node contact does not hold (docs/shell-friction.md, a strip carried along its path)",
            last.t,
            s[0],
            s[1],
            100.0 * amplitude
        ));
    }
    if let Some(law) = scene.friction.as_ref().map(|f| f.law) {
        // Review 10: an idler roller (its surface at the strip's speed)
        // kept the friction the load ramp had put on it; the exit tension
        // then moved with the tension and with omega (10 % off the
        // Coulomb answer at omega = 1e-3), and friction.csv only said
        // `stick`.
        // The law's capacity f |R_N|_reg (eq. 5): an unpressed node holds
        // f zeta (review 25: f R_N = 0 made a share of 6.2e306).
        let capacity = |rn: f64| law.f * rn.hypot(law.zeta.unwrap_or(0.0));
        let held: Vec<&NodeFriction> = last
            .friction
            .iter()
            .filter(|f| friction_state(&law, f.slip.norm()).0 == "stick")
            .filter(|f| f.force.norm() > 0.01 * capacity(f.rn))
            .collect();
        if let Some(most) = held
            .iter()
            .max_by(|a, b| a.force.norm().total_cmp(&b.force.norm()))
        {
            report.notes.push(format!(
                "{} of {} friction nodes stick at t = {} while carrying friction (up to {:.3e} at node {}, {:.2} of the law's capacity f |R_N|_reg there): a sticking contact keeps the friction the load history put on it and sheds it only by the regularized creep, so these forces, and the tensions they hold, depend on friction.load_ramp and on friction.omega (docs/shell-friction.md); where this friction is not meant to hold them (an idler roller that should pass the tension unchanged), the roller's surface speed must differ from the strip's, or omega and t_end must let the creep finish",
                held.len(),
                last.friction.len(),
                last.t,
                most.force.norm(),
                dae.model.node_tag(most.node),
                most.force.norm() / capacity(most.rn).max(f64::MIN_POSITIVE)
            ));
        }
        let speeds: Vec<f64> = last
            .friction
            .iter()
            .map(|f| f.slip.norm())
            .filter(|&v| friction_state(&law, v).0 == "transition")
            .collect();
        // At a breakaway the creep speeds grow without bound on their way
        // to slip: no omega separates them (review 13).
        let breakaway = report.stop.reason == "singularity";
        if let Some(fastest) = speeds
            .iter()
            .copied()
            .reduce(f64::max)
            .filter(|_| !breakaway)
        {
            report.notes.push(format!(
                "{} of {} friction nodes at t = {} slip at speeds between omega Vc = {:.3e} and 10 omega Vc = {:.3e} (up to {fastest:.3e}): `transition` in friction.csv (0.5 in friction.vtu's stick), where the regularization, not the mechanics, decides stick or slip; a friction.omega below {:.1e} separates them",
                speeds.len(),
                last.friction.len(),
                last.t,
                law.omega * law.vc,
                slip_threshold(&law),
                fastest / (10.0 * law.vc)
            ));
        }
    }
    if let Some(dir) = out_dir {
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            file: dir.to_path_buf(),
            source,
        })?;
        let file = dir.join("history.csv");
        let mut w = csv::Writer::from_path(&file).map_err(|e| write_err(&file)(e.to_string()))?;
        w.write_record(&head)
            .map_err(|e| write_err(&file)(e.to_string()))?;
        for r in &rows {
            // csv_number writes a negative zero (an empty slip area) as 0.
            w.write_record(r.iter().map(|&v| csv_number(v)))
                .map_err(|e| write_err(&file)(e.to_string()))?;
        }
        w.flush().map_err(|e| write_err(&file)(e.to_string()))?;
        write_friction_csv(&dir.join("friction.csv"), &dae, &last.friction)?;
        write_fields(&dir.join("friction.vtu"), scene, &dae, last)?;
        plot(&dir.join("friction.svg"), scene.units, &head, &rows)?;
        // The probes, as a static run plots them (columns t, lambda, then
        // the probes).
        if scene.output.plot && rows.len() > 1 {
            super::shell::probe_plot(&dir.join("plot.svg"), scene, "t (s)", &rows, 2)?;
        }
        if let Some(along) = &along {
            along_strip::write_csv(&dir.join("along.csv"), along)?;
            along_strip::plot(&dir.join("along.svg"), scene.units, along)?;
        }
        if monitored {
            write_events(dir, &dae, &scene.mesh.quads, &mut report.events)?;
        }
        let file = dir.join("summary.json");
        let text =
            serde_json::to_string_pretty(&report).map_err(|e| write_err(&file)(e.to_string()))?;
        std::fs::write(&file, text).map_err(|source| Error::Io { file, source })?;
        // Interrupted: what `--resume` continues from; else no checkpoint
        // (a resumed run that ends removes it).
        if matches!(run.stop, TimeStop::Interrupted { .. }) {
            TimeCheckpoint::new(scene, &run, wall_s)?.write(dir)?;
        } else {
            TimeCheckpoint::remove(dir)?;
        }
    }
    Ok(report)
}

/// friction.csv: per friction node of a sample, the gap, R_N, R_T, v_s,
/// |v_s| and the stick/slip state.
pub(crate) fn write_friction_csv(
    file: &Path,
    dae: &FrictionDae,
    friction: &[NodeFriction],
) -> Result<()> {
    let mut w = csv::Writer::from_path(file).map_err(|e| write_err(file)(e.to_string()))?;
    let law = dae.laws.law;
    w.write_record([
        "node",
        "obstacle",
        "gap",
        "rn",
        "ft_x",
        "ft_y",
        "ft_z",
        "vs_x",
        "vs_y",
        "vs_z",
        "slip_speed",
        "state",
    ])
    .map_err(|e| write_err(file)(e.to_string()))?;
    for f in friction {
        let speed = f.slip.norm();
        let (state, _) = friction_state(&law, speed);
        let mut rec = vec![
            dae.model.node_tag(f.node).to_string(),
            f.obstacle.to_string(),
        ];
        rec.extend(
            [
                f.gap, f.rn, f.force[0], f.force[1], f.force[2], f.slip[0], f.slip[1], f.slip[2],
                speed,
            ]
            .map(csv_number),
        );
        rec.push(state.into());
        w.write_record(&rec)
            .map_err(|e| write_err(file)(e.to_string()))?;
    }
    w.flush().map_err(|e| write_err(file)(e.to_string()))?;
    Ok(())
}

/// The last state as a VTK surface with the friction fields per node.
fn write_fields(path: &Path, scene: &ShellScene, dae: &FrictionDae, s: &TimeSample) -> Result<()> {
    let n = dae.model.n_nodes();
    let v3 = |node: usize| {
        let i = crate::fe::dof::index(node, 0);
        nalgebra::Vector3::new(s.full[i], s.full[i + 1], s.full[i + 2])
    };
    let displacement: Vec<_> = (0..n).map(v3).collect();
    let x: Vec<_> = (0..n).map(|i| dae.model.x0[i] + displacement[i]).collect();
    let director = dae.model.directors(&s.full);
    let mut rn = vec![0.0; n];
    let mut force = vec![nalgebra::Vector3::zeros(); n];
    let mut slip = vec![nalgebra::Vector3::zeros(); n];
    // −1: no friction at the node (not a candidate, or held), which 0 would
    // paint as slipping (review 7).
    let mut stick = vec![-1.0; n];
    let law = dae.laws.law;
    for f in &s.friction {
        rn[f.node] += f.rn;
        force[f.node] += f.force;
        slip[f.node] = f.slip;
        stick[f.node] = friction_state(&law, f.slip.norm()).1;
    }
    let speed = slip.iter().map(|v| v.norm()).collect();
    let areas = scene.mesh.node_areas();
    let pressure = rn.iter().zip(&areas).map(|(r, a)| r / a).collect();
    let mut cells = vec![PointData::Tags("element", &scene.mesh.quad_tags)];
    cells.extend(super::section::stress_cells(
        &dae.model,
        &s.full,
        scene.thickness,
        false,
    ));
    write_vtu_cells(
        path,
        &x,
        &scene.mesh.quads,
        &[
            PointData::Vector("displacement", displacement),
            PointData::Vector("director", director),
            PointData::Scalar("contact_reaction", rn),
            PointData::Scalar("contact_pressure", pressure),
            PointData::Vector("friction_force", force),
            PointData::Vector("slip_velocity", slip),
            PointData::Scalar("slip_speed", speed),
            PointData::Scalar("stick", stick),
            PointData::Tags("node", &scene.mesh.node_tags),
        ],
        &cells,
    )
}

/// The friction totals and the largest slip speed against t.
pub(crate) fn plot(path: &Path, units: Units, head: &[String], rows: &[Vec<f64>]) -> Result<()> {
    let col = |name: &str| {
        head.iter()
            .position(|h| h == name)
            .expect("a history column")
    };
    let curve = |name: &'static str| Curve {
        label: name,
        points: rows.iter().map(|r| (r[0], r[col(name)])).collect(),
    };
    let force = format!("force ({})", units.force);
    let speed = format!("|v_s| ({}/s)", units.length);
    draw(
        path,
        &[
            Panel {
                title: "normal and friction forces on the shell",
                x_label: "t (s)",
                y_label: &force,
                curves: vec![
                    curve("rn_total"),
                    curve("ft_x"),
                    curve("ft_y"),
                    curve("ft_z"),
                ],
                log: (false, false),
            },
            Panel {
                title: "largest slip speed",
                x_label: "t (s)",
                y_label: &speed,
                curves: vec![curve("max_slip")],
                log: (false, false),
            },
        ],
    )
}

/// A note when the run ends inside a ramp of its loads or of its
/// obstacles' motions: the scene's values were never reached (review 13:
/// t_end = 0.25 s inside a motion ramp over [0.2, 0.3] s left the roller at
/// half its speed, without a word).
fn cut_ramp(f: &FrictionSpec, t_end: f64) -> Option<String> {
    let ramps = [
        ("friction.load_ramp", f.load),
        ("friction.motion_ramp", f.motion),
    ]
    .into_iter()
    .map(|(k, r)| (k.to_string(), r))
    .chain(
        f.load_ramps
            .iter()
            .map(|(i, r)| (format!("load[{i}].ramp"), *r)),
    );
    let cut: Vec<String> = ramps
        .filter(|(_, r)| t_end < r.end)
        .map(|(k, r)| {
            format!(
                "{k} [{}, {}] at {:.3} of its full value",
                r.start,
                r.end,
                r.value(t_end)
            )
        })
        .collect();
    (!cut.is_empty()).then(|| {
        format!(
            "the run ends at t = {t_end} inside its ramps ({}): the scene's loads or speeds were not all reached",
            cut.join("; ")
        )
    })
}

/// A note when a strip run without `friction.stability` ends compressed
/// across its width (review 13: the crowned roll's strip at −0.81 MPa
/// across, near its wrinkling onset, and not a word that wrinkling was not
/// checked). Compression below 1 % of the largest stress along the strip
/// is left out.
fn unmonitored_compression(along: &[along_strip::AlongRow], t: f64) -> Option<String> {
    let largest = along
        .iter()
        .map(|r| r.stress_along.abs())
        .fold(0.0, f64::max);
    let least = along
        .iter()
        .min_by(|a, b| a.stress_across_min.total_cmp(&b.stress_across_min))?;
    (least.stress_across_min < -0.01 * largest).then(|| {
        format!(
            "the strip ends compressed across its width (down to {:.3e} at s = {:.4}, t = {t}; {:.2} of the largest stress along it): friction.stability is off, so a wrinkling onset was not looked for; set it to true to locate one",
            least.stress_across_min,
            least.s,
            -least.stress_across_min / largest.max(f64::MIN_POSITIVE)
        )
    })
}

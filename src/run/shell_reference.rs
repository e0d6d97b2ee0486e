//! `anm reference ida` on a shell scene with `[friction]` (feature
//! `reference`): SUNDIALS IDA on the residual `anm run` integrates
//! ([`crate::reference::shell_ida`]), from the same start (the state at
//! rest brought to equilibrium at t = 0), so that a user checks a run of
//! their own scene against an integrator we did not write. The files are
//! those of `anm run` a comparison needs:
//!
//! - history.csv: the same columns as `anm run`'s (t, lambda, the probes,
//!   the friction totals) on the same output times, from t = 0;
//! - friction.csv: per friction node at the last output time reached;
//! - friction.svg: the friction totals and max_slip against t;
//! - summary.json: the tool and its settings, the common `counters`
//!   ([`crate::reference::counters`]), the stop, `columns` and `end`.
//!
//! IDA's linear algebra is dense here: scenes up to
//! [`shell_ida::MAX_UNKNOWNS`] unknowns (coarse meshes, as references are).

use super::shell_time;
use crate::reference::counters::Counters;
use crate::reference::ida::sundials_version;
use crate::reference::run::IdaStop;
use crate::reference::shell_ida::{self, ShellIda};
use crate::scene::shell::ShellScene;
use crate::shell::time_path;
use anyhow::{Context, bail};
use indexmap::IndexMap;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Newton iterations per step attempt on the shell (IDASetMaxNonlinIters;
/// IDA's own is 4, the point-mass references' 20). Measured on the capstan
/// of scenes/strip-capstan.toml (90°, 8 elements): with 4 and 10 IDA reaches
/// t_end at rtol 1e-10 and 1e-12; with 20 it stops with IDA_CONV_FAIL (t =
/// 0.95 s, h = 3e-12 s at 1e-10; t = 0.547 s at 1e-12), where the longer
/// iteration on a Jacobian several steps old wanders off instead of
/// failing early into a fresh Jacobian. With 4 the same capstan at rtol
/// 1e-12 failed on a one-ulp change of the element stiffness
/// (reference::shell_ida::ShellIda::with_max_nonlin_iters).
pub const MAX_NONLIN_ITERS: usize = 10;

/// Internal steps IDA may take between two output times (IDASetMaxNumSteps
/// counts per call). Review 20: a 120-unknown plate pulled below f N ran
/// more than 10 minutes at rtol 1e-10 with no file (10,000,000 allowed);
/// `anm run` takes 0.12 s there.
const MAX_STEPS: i64 = 20_000;

/// The settings of `anm reference ida` on a shell scene.
#[derive(Clone, Copy, Debug)]
pub struct ShellIdaSettings {
    pub rtol: f64,
    /// Absolute tolerance of the translations, in the scene's length unit
    /// (None: rtol × the model's length scale, so that rtol is relative to
    /// the scene's size in any unit).
    pub atol: Option<f64>,
    /// Newton iterations per step attempt (IDASetMaxNonlinIters).
    pub max_nonlin_iters: usize,
}

/// summary.json of the run.
#[derive(Clone, Debug, Serialize)]
pub struct ShellReferenceReport {
    pub tool: &'static str,
    pub version: String,
    pub method: &'static str,
    pub scene: String,
    pub kind: &'static str,
    pub rtol: f64,
    /// atol of the translations (scene length unit).
    pub atol: f64,
    /// The algebraic unknowns (the rotations, the normal translations of
    /// free nodes, the tangential velocities w) are out of the local error
    /// test (IDASetSuppressAlg), as in every IDA run of `anm`.
    pub algebraic: &'static str,
    pub options: BTreeMap<&'static str, String>,
    /// Shell dofs and friction unknowns (2 per friction node).
    pub unknowns: usize,
    pub dofs: usize,
    pub friction_nodes: usize,
    /// Contact candidates with a fixed translation (no friction), 1-based
    /// mesh tags, as in `anm run`'s summary.json.
    pub nodes_without_friction: Vec<usize>,
    pub counters: Counters,
    pub wall_s: f64,
    /// `reason`: "end" or IDA's failure (its flag name); `t` reached.
    pub stop: IdaStop,
    pub columns: Vec<String>,
    pub output_rows: usize,
    pub end: IndexMap<String, f64>,
    /// Always present, empty when there is nothing to say (review 18: a
    /// stopped run's summary.json had no `notes` key).
    pub notes: Vec<String>,
}

/// Runs IDA on the scene and writes its files into `out`.
pub fn ida(
    scene: &ShellScene,
    settings: &ShellIdaSettings,
    out: &Path,
) -> anyhow::Result<ShellReferenceReport> {
    let file = scene.file.display();
    let Some(friction) = &scene.friction else {
        bail!(
            "{file}: IDA integrates a shell scene in time, which needs a [friction] table (a static shell scene has no time to integrate: `anm run` follows its path)"
        );
    };
    crate::reference::settings::Tolerances::new(settings.rtol, settings.atol)?;
    if settings.max_nonlin_iters == 0 {
        bail!("--max-nonlin-iters must be at least 1");
    }
    let cfg = shell_time::config(scene);
    let mut dae = shell_time::problem(scene)?;
    let start =
        time_path::start_state(&mut dae, &cfg).map_err(|e| shell_time::at_rest(scene, e))?;
    let candidates = dae.model.pairs.len();
    let ida = ShellIda::from_state(dae, start.clone())
        .with_context(|| format!("IDA set-up on {file}"))?
        .with_max_nonlin_iters(settings.max_nonlin_iters as i32);
    let unknowns = crate::reference::dae::Dae::dim(&ida);
    if unknowns > shell_ida::MAX_UNKNOWNS {
        bail!(
            "{file}: {unknowns} unknowns; IDA's linear algebra is dense here and takes scenes up to {} unknowns (a reference on a coarser mesh of the same scene: fewer mesh.divisions)",
            shell_ida::MAX_UNKNOWNS
        );
    }
    // Candidates with no friction unknowns: a fixed translation
    // (`skipped`), or out of the contact search at t = 0.
    let (friction_nodes, without_friction, out_of_search) = {
        let dae = ida.dae();
        let held: Vec<usize> = dae.skipped.iter().map(|&n| dae.model.node_tag(n)).collect();
        let out = candidates - dae.n_pairs() - held.len();
        (dae.n_pairs(), held, out)
    };
    let length = ida.dae().model.length_scale;
    let atol = settings.atol.unwrap_or(settings.rtol * length);
    let mut kinks = ida.dae().laws.kinks();
    kinks.retain(|&k| k > 0.0 && k < cfg.t_end);
    let run = ida
        .solve_keeping(&cfg.outputs, &kinks, settings.rtol, atol, MAX_STEPS)
        .with_context(|| format!("IDA on {file}"))?;

    let dae = ida.dae();
    let areas = scene.mesh.node_areas();
    let mut samples = vec![time_path::sample(&dae, &start, 0.0)?];
    for s in &run.states {
        samples.push(time_path::sample(&dae, s, s.t)?);
    }
    let columns = shell_time::header(scene);
    let rows: Vec<Vec<f64>> = samples
        .iter()
        .map(|s| shell_time::row(&dae, scene, &areas, s))
        .collect::<crate::Result<_>>()?;
    let last = samples.last().expect("the start");
    let stop = match &run.stop {
        None => IdaStop {
            reason: "end".into(),
            t: last.t,
            message: None,
        },
        Some(e) => IdaStop {
            reason: e.reason(),
            t: e.time().unwrap_or(last.t),
            message: Some(e.to_string()),
        },
    };
    let mut notes = vec![];
    // Review 20: IDA failed at t = 0 at rtol 1e-12 on pulled plates and at
    // 1e-10 on a sliding one where 1e-8 ran; its raw message gave no hint.
    if let Some(e) = &run.stop {
        notes.push(format!(
            "IDA stopped ({}) at rtol {:e}: on these penalty contacts its Newton test can meet the residual's round-off at tight tolerances (and the step budget of {MAX_STEPS} steps between output times is spent where the regularized law is steep); a looser --rtol (1e-8) may run, and the difference between two rtols that run is IDA's error; the files hold the output times reached",
            e.reason(),
            settings.rtol
        ));
    }
    if out_of_search > 0 {
        let reach = scene
            .contact
            .as_ref()
            .map_or(f64::INFINITY, |c| c.search_distance);
        notes.push(format!(
            "IDA keeps the friction nodes of t = 0: {out_of_search} of the {candidates} contact candidates lie beyond contact.search_distance = {reach} and take no part in the whole run, where `anm run` takes them in when they come near; a comparison needs a contact.search_distance that covers every candidate"
        ));
    }
    if friction.stability {
        notes.push(
            "friction.stability: the stability monitor is `anm run`'s; IDA's history.csv has no stability columns".into(),
        );
    }
    let report = ShellReferenceReport {
        tool: "SUNDIALS IDA",
        version: sundials_version(),
        method: "bdf",
        scene: scene.file.display().to_string(),
        kind: "shell",
        rtol: settings.rtol,
        atol,
        algebraic: "suppress",
        options: BTreeMap::from([("max_nonlin_iters", settings.max_nonlin_iters.to_string())]),
        unknowns,
        dofs: crate::series::ContinuationProblem::ndof(&dae.model),
        friction_nodes,
        nodes_without_friction: without_friction,
        counters: run.counters,
        wall_s: run.wall_s,
        stop,
        end: columns
            .iter()
            .cloned()
            .zip(rows.last().expect("the start").iter().map(|x| x + 0.0))
            .collect(),
        columns: columns.clone(),
        output_rows: rows.len(),
        notes,
    };
    crate::output::create_dir(out)?;
    let head: Vec<&str> = columns.iter().map(String::as_str).collect();
    crate::output::write_csv(&out.join("history.csv"), &head, &rows)?;
    shell_time::write_friction_csv(&out.join("friction.csv"), &dae, &last.friction)?;
    shell_time::plot(&out.join("friction.svg"), scene.units, &columns, &rows)?;
    crate::output::write_json(&out.join("summary.json"), &report)?;
    Ok(report)
}

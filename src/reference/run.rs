//! Solves a friction scene with IDA: consistent initial values by IDACalcIC,
//! then IDA_ONE_STEP steps up to t_end (IDASetStopTime), recording every
//! internal step (t, h, slip speed, order), interpolating the scene's output
//! grid with IDAGetDky, and locating by bisection on the dense output the
//! first times |v_s| reaches Vc and 10 Vc.

use super::dae::FrictionDae;
use super::error::IdaError;
use super::friction_1d::Friction1d;
use super::friction_plane::FrictionPlane;
use super::friction_roller::{BAUMGARTE_ALPHA, FrictionRoller};
use super::ida::{Counters, Ida, Task, sundials_version};
use super::laws::{Contact, Friction};
use crate::scene::Kind;
use crate::scene::friction::{FrictionScene, Obstacle};
use std::time::Instant;

/// One internal IDA step.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct StepRecord {
    /// Time at the end of the step.
    pub t: f64,
    /// Its size (IDAGetLastStep).
    pub h: f64,
    /// Slip speed v_s at t.
    pub slip: f64,
    /// BDF order used (IDAGetLastOrder).
    pub order: i32,
}

/// A time where |v_s| first reaches `level` after having been below it.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Crossing {
    pub level: f64,
    pub t: f64,
}

/// How the run ended.
#[derive(Clone, Debug, serde::Serialize)]
pub struct IdaStop {
    /// "end", or the name of the flag IDA failed with (e.g. IDA_CONV_FAIL).
    pub reason: String,
    /// The time reached.
    pub t: f64,
    pub message: Option<String>,
}

/// Everything an IDA run of a friction scene produced.
#[derive(Clone, Debug)]
pub struct IdaRun {
    pub scene: String,
    pub kind: String,
    pub version: String,
    pub rtol: f64,
    pub atol: f64,
    pub columns: Vec<String>,
    /// Rows on the scene's output grid up to the time reached.
    pub history: Vec<Vec<f64>>,
    /// Every internal step.
    pub steps: Vec<StepRecord>,
    /// Consistent initial values found by IDACalcIC.
    pub y0: Vec<f64>,
    pub yp0: Vec<f64>,
    pub counters: Counters,
    pub wall_s: f64,
    pub stop: IdaStop,
    /// Up-crossings of |v_s| through Vc and 10 Vc, in time order.
    pub crossings: Vec<Crossing>,
    /// Vc of the scene's friction law.
    pub vc: f64,
    /// Largest |position-level constraint residual| seen at the steps (N m;
    /// the roller's contact law, enforced in differentiated form).
    pub max_constraint_drift: f64,
}

impl IdaRun {
    /// The smallest step taken after t_from, with its time.
    pub fn min_step_after(&self, t_from: f64) -> Option<StepRecord> {
        self.steps
            .iter()
            .filter(|s| s.t >= t_from)
            .min_by(|a, b| a.h.total_cmp(&b.h))
            .copied()
    }

    /// The window [t(|v_s| = Vc), t(|v_s| = 10 Vc)]: the first up-crossing of
    /// 10 Vc and the last up-crossing of Vc before it.
    pub fn surge_window(&self) -> Option<(f64, f64)> {
        let t10 = self
            .crossings
            .iter()
            .find(|c| c.level >= 10.0 * self.vc * (1.0 - 1e-12))
            .map(|c| c.t)?;
        let t1 = self
            .crossings
            .iter()
            .rev()
            .find(|c| c.level < 10.0 * self.vc * (1.0 - 1e-12) && c.t <= t10)
            .map(|c| c.t)?;
        Some((t1, t10))
    }
}

/// The IDA model of a friction scene, written independently of
/// [`crate::model::friction`] (global Cartesian coordinates).
pub fn model(scene: &FrictionScene) -> Result<Box<dyn FrictionDae>, IdaError> {
    let law = Friction::from_law(&scene.friction);
    let contact = || {
        scene
            .contact
            .as_ref()
            .map(Contact::from_law)
            .ok_or_else(|| {
                IdaError::Input(format!("{} scene without a contact law", scene.kind.name()))
            })
    };
    Ok(match (scene.kind, scene.obstacle) {
        (Kind::Friction1d, Obstacle::Plane { v }) => Box::new(Friction1d {
            k: scene.k,
            law,
            v_plane: v,
            rn: scene.normal_force,
            u0: scene.u0,
        }),
        (Kind::FrictionPlane, Obstacle::Plane { v }) => Box::new(FrictionPlane {
            k: scene.k,
            law,
            contact: contact()?,
            v_plane: v,
            load_rate: scene.load_rate,
        }),
        (Kind::FrictionRoller, Obstacle::Roller { r, omega }) => Box::new(FrictionRoller {
            k: scene.k,
            law,
            contact: contact()?,
            radius: r,
            spin: omega,
            load_rate: scene.load_rate,
            alpha: BAUMGARTE_ALPHA,
        }),
        (kind, _) => {
            return Err(IdaError::Input(format!(
                "no IDA model for a `{}` scene",
                kind.name()
            )));
        }
    })
}

/// Internal steps allowed per IDASolve call (one call per step here, so this
/// only bounds the steps between stop-time returns).
const MAX_STEPS: i64 = 10_000_000;
/// Step-collapse diagnosis: this many consecutive steps with
/// h <= COLLAPSE_H max(|t|, t_end).
const COLLAPSE_STEPS: usize = 1000;
const COLLAPSE_H: f64 = 1e-13;
/// Internal steps allowed in a whole run.
const MAX_TOTAL_STEPS: usize = 2_000_000;

/// Solves the scene with IDA at tolerances (rtol, atol).
///
/// Errors are returned for failures before the first step (setup, initial
/// conditions); a failure during the integration ends the run with
/// `stop.reason` = the flag name and the rows reached so far.
pub fn solve(scene: &FrictionScene, rtol: f64, atol: f64) -> Result<IdaRun, IdaError> {
    let dae = model(scene)?;
    solve_model(scene, dae.as_ref(), rtol, atol)
}

/// As [`solve`], with a given model (e.g. a modified formulation).
pub fn solve_model(
    scene: &FrictionScene,
    dae: &dyn FrictionDae,
    rtol: f64,
    atol: f64,
) -> Result<IdaRun, IdaError> {
    let start = Instant::now();
    let grid = scene.output_times();
    let t_end = scene.t_end;
    let vc = scene.friction.vc;
    let levels = [vc, 10.0 * vc];
    let (y0, yp0) = dae.initial_guess();
    let mut ida = Ida::new(dae, 0.0, &y0, &yp0, rtol, atol)?;
    ida.set_max_num_steps(MAX_STEPS)?;
    ida.set_stop_time(t_end)?;
    let (y0, yp0) = ida.calc_ic(grid.get(1).copied().unwrap_or(t_end))?;

    let mut history = vec![dae.row(0.0, &y0)];
    let mut next = 1;
    let mut steps = Vec::new();
    let mut crossings = Vec::new();
    let mut prev = (0.0, dae.slip(0.0, &y0).abs());
    let mut drift = dae.constraint_drift(0.0, &y0).abs();
    let mut stop = IdaStop {
        reason: "end".into(),
        t: t_end,
        message: None,
    };
    let mut tiny = 0;
    let result: Result<(), IdaError> = (|| {
        while ida.t() < t_end {
            if steps.len() >= MAX_TOTAL_STEPS {
                stop = IdaStop {
                    reason: "max_steps".into(),
                    t: ida.t(),
                    message: Some(format!(
                        "{MAX_TOTAL_STEPS} internal steps reached at t = {:.12e} s (last step {:.3e} s)",
                        ida.t(),
                        ida.last_step()
                    )),
                };
                return Ok(());
            }
            let t = ida.solve(t_end, Task::OneStep)?;
            let y = ida.y().to_vec();
            let slip = dae.slip(t, &y);
            let h = ida.last_step();
            steps.push(StepRecord {
                t,
                h,
                slip,
                order: ida.last_order(),
            });
            // A step size at round-off level for many steps in a row: IDA
            // cannot advance (it would only stop at max_steps).
            if h <= COLLAPSE_H * t.abs().max(t_end) {
                tiny += 1;
            } else {
                tiny = 0;
            }
            if tiny >= COLLAPSE_STEPS {
                stop = IdaStop {
                    reason: "step_collapse".into(),
                    t,
                    message: Some(format!(
                        "IDA's step size collapsed: {COLLAPSE_STEPS} steps in a row below {COLLAPSE_H:e} t_end, last h = {h:.3e} s at t = {t:.12e} s, slip speed {slip:.6e} m/s (BDF order {})",
                        ida.last_order()
                    )),
                };
                return Ok(());
            }
            drift = drift.max(dae.constraint_drift(t, &y).abs());
            // Output rows within this step, from IDA's interpolant.
            let t_prev = prev.0;
            while next < grid.len() && grid[next] <= t + 1e-12 * t_end {
                let tg = grid[next].min(t);
                let yg = if tg == t { y.clone() } else { ida.dky(tg, 0)? };
                history.push(dae.row(grid[next], &yg));
                next += 1;
            }
            // Up-crossings of |v_s| through the levels, refined on the interpolant.
            for &level in &levels {
                if prev.1 < level && slip.abs() >= level {
                    let (mut a, mut b) = (t_prev, t);
                    for _ in 0..200 {
                        let m = 0.5 * (a + b);
                        if m <= a || m >= b {
                            break;
                        }
                        if dae.slip(m, &ida.dky(m, 0)?).abs() >= level {
                            b = m;
                        } else {
                            a = m;
                        }
                    }
                    crossings.push(Crossing { level, t: b });
                }
            }
            prev = (t, slip.abs());
        }
        Ok(())
    })();
    if let Err(e) = result {
        stop = IdaStop {
            reason: e.reason(),
            t: e.time().unwrap_or(ida.t()),
            message: Some(e.to_string()),
        };
    } else if stop.reason == "end" {
        stop.t = ida.t();
    }
    Ok(IdaRun {
        scene: scene.file.display().to_string(),
        kind: scene.kind.name().into(),
        version: sundials_version(),
        rtol,
        atol,
        columns: dae.columns().iter().map(|s| s.to_string()).collect(),
        history,
        steps,
        y0,
        yp0,
        counters: ida.counters(),
        wall_s: start.elapsed().as_secs_f64(),
        stop,
        crossings,
        vc,
        max_constraint_drift: drift,
    })
}

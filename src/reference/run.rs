//! The time loop shared by the reference solvers (IDA, diffsol): from the
//! consistent initial values, one internal step at a time up to t_end,
//! recording every step (t, h, slip speed, order), the scene's output grid
//! from the solver's own interpolant, the first times |v_s| reaches Vc and
//! 10 Vc (bisection on the interpolant), and which unknown dominates the
//! local error estimate. A solver plugs in through [`Stepper`].

use super::counters::Counters;
use super::dae::FrictionDae;
use super::error::IdaError;
use super::friction_1d::Friction1d;
use super::friction_plane::FrictionPlane;
use super::friction_roller::{BAUMGARTE_ALPHA, FrictionRoller};
use super::laws::{Contact, Friction, RowForm};
use crate::scene::Kind;
use crate::scene::friction::{FrictionScene, Obstacle};
use std::time::Instant;

/// One internal step.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct StepRecord {
    /// Time at the end of the step.
    pub t: f64,
    /// Its size.
    pub h: f64,
    /// Slip speed v_s at t.
    pub slip: f64,
    /// Order of the method on this step (BDF order; 3 for ESDIRK34).
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
    /// "end", "max_steps", "step_collapse", or the solver's failure (IDA's
    /// flag name, e.g. IDA_CONV_FAIL; diffsol's error kind).
    pub reason: String,
    /// The time reached.
    pub t: f64,
    pub message: Option<String>,
}

/// What a solver run in the loop of [`drive`] must offer.
pub trait Stepper {
    /// One internal step, not beyond `t_end`; returns the time reached.
    fn step(&mut self, t_end: f64) -> Result<f64, IdaError>;
    /// The solution at the time last reached.
    fn y(&self) -> Vec<f64>;
    /// The size of the last step.
    fn last_step(&self) -> f64;
    /// The order of the last step.
    fn order(&self) -> i32;
    /// The solver's dense output at t within the last step.
    fn interpolate(&mut self, t: f64) -> Result<Vec<f64>, IdaError>;
    /// Each unknown's share of the weighted local error estimate of the last
    /// step, when the solver exposes it (the largest is the unknown that
    /// limits the step).
    fn weighted_local_errors(&mut self) -> Option<Vec<f64>> {
        None
    }
    /// The common counters so far.
    fn counters(&self) -> Counters;
}

/// Everything a reference run of a friction scene produced.
#[derive(Clone, Debug)]
pub struct IdaRun {
    pub scene: String,
    pub kind: String,
    /// "SUNDIALS IDA" or "diffsol".
    pub tool: String,
    pub version: String,
    /// The integrator, e.g. "bdf" (IDA's variable-order BDF), "esdirk".
    pub method: String,
    pub rtol: f64,
    pub atol: f64,
    /// How the algebraic unknowns enter the error test ("suppress" or their atol).
    pub algebraic: String,
    /// Every other setting that departs from the library's defaults.
    pub options: Vec<(String, String)>,
    pub columns: Vec<String>,
    /// Rows on the scene's output grid up to the time reached.
    pub history: Vec<Vec<f64>>,
    /// Every internal step.
    pub steps: Vec<StepRecord>,
    /// Consistent initial values.
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
    /// Names of the unknowns, in the solver's order.
    pub unknowns: Vec<String>,
    /// For each unknown, the accepted steps on which it had the largest
    /// weighted local error estimate (empty when the solver does not expose it).
    pub dominant_error: Vec<usize>,
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

    /// Steps taken at order 1.
    pub fn order_one_steps(&self) -> usize {
        self.steps.iter().filter(|s| s.order == 1).count()
    }

    /// The step of largest |v_s| (the jump of the regularized dynamics past
    /// the roller's breakdown), if any step was recorded.
    pub fn slip_peak(&self) -> Option<&StepRecord> {
        self.steps
            .iter()
            .max_by(|x, y| x.slip.abs().total_cmp(&y.slip.abs()))
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
    model_with(scene, RowForm::Product)
}

/// As [`model`], with the friction row written in `form`.
pub fn model_with(scene: &FrictionScene, form: RowForm) -> Result<Box<dyn FrictionDae>, IdaError> {
    let law = Friction {
        form,
        ..Friction::from_law(&scene.friction)
    };
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

/// Step-collapse diagnosis: this many consecutive steps with
/// h <= COLLAPSE_H max(|t|, t_end).
const COLLAPSE_STEPS: usize = 1000;
const COLLAPSE_H: f64 = 1e-13;
/// Internal steps allowed in a whole run.
pub const MAX_TOTAL_STEPS: usize = 2_000_000;

/// Who ran: the tool, its version, method and settings (for [`IdaRun`]).
pub struct Label {
    pub tool: &'static str,
    pub version: String,
    pub method: String,
    pub rtol: f64,
    pub atol: f64,
    pub algebraic: String,
    pub options: Vec<(String, String)>,
}

/// Runs `stepper` (already at its consistent initial values (y0, yp0) at
/// t = 0) over the scene's time span. A failure during the integration ends
/// the run with `stop.reason` = the failure and the rows reached so far.
pub fn drive(
    scene: &FrictionScene,
    dae: &dyn FrictionDae,
    stepper: &mut dyn Stepper,
    y0: Vec<f64>,
    yp0: Vec<f64>,
    label: Label,
    start: Instant,
) -> IdaRun {
    let grid = scene.output_times();
    let t_end = scene.t_end;
    let vc = scene.friction.vc;
    let levels = [vc, 10.0 * vc];
    let n = y0.len();
    let mut history = vec![dae.row(0.0, &y0)];
    let mut next = 1;
    let mut steps = Vec::new();
    let mut crossings = Vec::new();
    let mut prev = (0.0, dae.slip(0.0, &y0).abs());
    let mut drift = dae.constraint_drift(0.0, &y0).abs();
    let mut dominant = vec![0usize; n];
    let mut have_dominant = false;
    let mut stop = IdaStop {
        reason: "end".into(),
        t: t_end,
        message: None,
    };
    let mut t_now = 0.0;
    let mut tiny = 0;
    let result: Result<(), IdaError> = (|| {
        while t_now < t_end {
            if steps.len() >= MAX_TOTAL_STEPS {
                stop = IdaStop {
                    reason: "max_steps".into(),
                    t: t_now,
                    message: Some(format!(
                        "{MAX_TOTAL_STEPS} internal steps reached at t = {t_now:.12e} s (last step {:.3e} s)",
                        stepper.last_step()
                    )),
                };
                return Ok(());
            }
            let t = stepper.step(t_end)?;
            t_now = t;
            let y = stepper.y();
            if let Some(i) = y.iter().position(|v| !v.is_finite()) {
                return Err(IdaError::NonFinite {
                    what: format!("y[{i}]"),
                    t,
                });
            }
            let slip = dae.slip(t, &y);
            let h = stepper.last_step();
            let order = stepper.order();
            steps.push(StepRecord { t, h, slip, order });
            if let Some((i, _)) = stepper.weighted_local_errors().and_then(|e| {
                e.iter()
                    .copied()
                    .enumerate()
                    .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            }) {
                dominant[i] += 1;
                have_dominant = true;
            }
            // A step size at round-off level for many steps in a row: the
            // solver cannot advance (it would only stop at max_steps).
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
                        "the step size collapsed: {COLLAPSE_STEPS} steps in a row below {COLLAPSE_H:e} t_end, last h = {h:.3e} s at t = {t:.12e} s, slip speed {slip:.6e} m/s (order {order})"
                    )),
                };
                return Ok(());
            }
            drift = drift.max(dae.constraint_drift(t, &y).abs());
            // The other root of the contact law: a solution that satisfies
            // the equations with the mass through the obstacle (review 6:
            // IDA with the algebraic unknowns out of its error test ended
            // friction-plane at q = 0, K = 1e8 N/m, eta = 1e-8 N with u_y =
            // -3 m for a plane at -1 m, R_N = -1.5e-8 N, exit 0).
            if let Some(g) = dae.contact_branch(t, &y)
                && !(g > 0.0)
            {
                stop = IdaStop {
                    reason: "off_branch".into(),
                    t,
                    message: Some(format!(
                        "at t = {t:.12e} s the solution left the contact law's physical root: 2 R_N / K + h = {g:.3e} <= 0, the mass through the obstacle{} (a root of eq. 3 that is not the contact); with the algebraic unknowns out of the error test (--atol-algebraic suppress) nothing stops the step there: give them a tolerance (e.g. --atol-algebraic 1e-8)",
                        dae.columns().iter().position(|c| *c == "rn").map_or(
                            String::new(),
                            |i| format!(" with R_N = {:.3e} N", dae.row(t, &y)[i])
                        )
                    )),
                };
                return Ok(());
            }
            // Output rows within this step, from the solver's interpolant.
            let t_prev = prev.0;
            while next < grid.len() && grid[next] <= t + 1e-12 * t_end {
                let tg = grid[next].min(t);
                let yg = if tg == t {
                    y.clone()
                } else {
                    stepper.interpolate(tg)?
                };
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
                        if dae.slip(m, &stepper.interpolate(m)?).abs() >= level {
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
            t: e.time().unwrap_or(t_now),
            message: Some(e.to_string()),
        };
    } else if stop.reason == "end" {
        stop.t = t_now;
    }
    IdaRun {
        scene: scene.file.display().to_string(),
        kind: scene.kind.name().into(),
        tool: label.tool.into(),
        version: label.version,
        method: label.method,
        rtol: label.rtol,
        atol: label.atol,
        algebraic: label.algebraic,
        options: label.options,
        columns: dae.columns().iter().map(|s| s.to_string()).collect(),
        history,
        steps,
        y0,
        yp0,
        counters: stepper.counters(),
        wall_s: start.elapsed().as_secs_f64(),
        stop,
        crossings,
        vc,
        max_constraint_drift: drift,
        unknowns: dae.unknowns().iter().map(|s| s.to_string()).collect(),
        dominant_error: if have_dominant { dominant } else { vec![] },
    }
}

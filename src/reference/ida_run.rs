//! Solves a friction scene with SUNDIALS IDA (feature `reference`):
//! consistent initial values by IDACalcIC, then IDA_ONE_STEP steps up to
//! t_end (IDASetStopTime) in the loop of [`super::run::drive`].
//!
//! ## Set-up (issue 16: IDA at its best on our DAEs)
//! - Algebraic unknowns out of the local error test by default
//!   (IDASetSuppressAlg with the id vector, [`AlgebraicControl::Suppress`]).
//!   The IDA user guide discourages this for index-1 systems (it encourages
//!   it for index 2 and higher), so here is the argument and its price.
//!   Our algebraic unknowns are functions of the positions, solved by Newton
//!   at every step (its convergence test still weighs every unknown); their
//!   local error is phi_u times that of u, and phi_u of the slip velocity
//!   reaches 5e6 s^-1 where the friction capacity is small (see
//!   [`AlgebraicControl`]): tested at u's tolerance they pin IDA at order 1
//!   (44,440 steps against 222 on friction-plane at zeta = 1e-2 N, rtol
//!   1e-8). The price: the velocity columns carry that amplified error (at
//!   rtol 1e-10, 9.2e-7 of max |v_x| on friction-plane against 3.1e-8 for
//!   the positions), and an event seen only by algebraic unknowns can be
//!   stepped over (a 1e-8 s contact transition with K = 1e8 N/m, eta =
//!   1e-8 N; tests/reference/ida.rs keeps them in the test there).
//!   `--atol-algebraic VALUE` keeps them in the test with their own atol
//!   (IDASVtolerances), the per-component alternative.
//! - The friction law in product form ([`RowForm::Product`], see
//!   [`super::laws::Friction::product_row`]): not steep in the slip
//!   velocity, so Newton converges from IDA's predictor.
//! - Up to [`MAX_NONLIN_ITERS`] Newton iterations per step attempt
//!   (IDASetMaxNonlinIters; see there why).
//! - atol follows rtol by default (`anm reference ida`): the differential
//!   unknowns are positions of order 0.1-1 m.
//! - Dense direct linear solver with the analytic Jacobian (IDASetJacFn),
//!   IDACalcIC (IDA_YA_YDP_INIT) from the exact initial positions.
//!   Everything else is IDA's default (maximum order 5, nonlinear
//!   convergence coefficient 0.33 (0.01 and 0.001 improved neither steps nor
//!   errors), initial step from IDA's heuristic).

use super::dae::FrictionDae;
use super::error::IdaError;
use super::ida::{Ida, Task, sundials_version};
use super::laws::RowForm;
use super::run::{IdaRun, Label, Stepper, drive, model_with};
use super::settings::{AlgebraicControl, Tolerances};
use crate::reference::counters::Counters;
use crate::scene::friction::FrictionScene;
use std::time::Instant;

/// The settings of an IDA run.
#[derive(Clone, Debug, PartialEq)]
pub struct IdaSettings {
    pub tol: Tolerances,
    /// Default: [`AlgebraicControl::Suppress`].
    pub algebraic: AlgebraicControl,
    /// Default: [`RowForm::Product`].
    pub friction_row: RowForm,
    /// Newton iterations per step attempt (IDASetMaxNonlinIters); default
    /// [`MAX_NONLIN_ITERS`], IDA's own is 4.
    pub max_nonlin_iters: usize,
}

/// IDA's own limit on Newton iterations per step attempt.
pub const IDA_MAX_NONLIN_ITERS: usize = 4;

/// Our default limit on Newton iterations per step attempt. At the
/// stick-slip transitions (width omega Vc, 1e-6 m/s at omega = 1e-6) the
/// Jacobian changes by a factor up to 1/q = 20 within a step, and IDA's
/// modified Newton iteration, which keeps the Jacobian of an earlier step,
/// converges only linearly there: with 4 iterations it is declared failed,
/// the step is cut, and IDA gives up at h ~ 1e-8 s (IDA_CONV_FAIL on the
/// roller at omega = 1e-6 N, zeta = 1e-4 and 1e-6 N, t = 1.78 s and 2.72 s).
/// With 20 every cell of issue 16 runs to the end; where 4 suffice the
/// extra iterations are never taken.
pub const MAX_NONLIN_ITERS: usize = 20;

impl IdaSettings {
    /// rtol, atol = rtol, algebraic unknowns out of the error test.
    pub fn new(rtol: f64) -> Result<Self, IdaError> {
        Ok(Self {
            tol: Tolerances::new(rtol, None)?,
            algebraic: AlgebraicControl::Suppress,
            friction_row: RowForm::Product,
            max_nonlin_iters: MAX_NONLIN_ITERS,
        })
    }

    /// IDA's own defaults on the paper's equations: every unknown in the
    /// error test with one atol, the friction law as written (how a new user
    /// calls it; the set-up issue 16 measured).
    pub fn library_default(rtol: f64, atol: f64) -> Result<Self, IdaError> {
        let tol = Tolerances::new(rtol, Some(atol))?;
        Ok(Self {
            algebraic: AlgebraicControl::Atol(tol.atol),
            tol,
            friction_row: RowForm::Direct,
            max_nonlin_iters: IDA_MAX_NONLIN_ITERS,
        })
    }
}

/// IDA as a [`Stepper`].
struct IdaStepper<'a> {
    ida: Ida<'a>,
    /// Which unknowns the local error test covers.
    in_test: Vec<bool>,
}

impl Stepper for IdaStepper<'_> {
    fn step(&mut self, t_end: f64) -> Result<f64, IdaError> {
        self.ida.solve(t_end, Task::OneStep)
    }
    fn y(&self) -> Vec<f64> {
        self.ida.y().to_vec()
    }
    fn last_step(&self) -> f64 {
        self.ida.last_step()
    }
    fn order(&self) -> i32 {
        self.ida.last_order()
    }
    fn interpolate(&mut self, t: f64) -> Result<Vec<f64>, IdaError> {
        self.ida.dky(t, 0)
    }
    fn weighted_local_errors(&mut self) -> Option<Vec<f64>> {
        let mut e = self.ida.weighted_local_errors().ok()?;
        for (e, &t) in e.iter_mut().zip(&self.in_test) {
            if !t {
                *e = 0.0;
            }
        }
        Some(e)
    }
    fn counters(&self) -> Counters {
        self.ida.counters().common()
    }
}

/// Internal steps allowed per IDASolve call (one call per step here, so this
/// only bounds the steps between stop-time returns).
const MAX_STEPS: i64 = 10_000_000;

/// Solves the scene with IDA.
///
/// Errors are returned for failures before the first step (setup, initial
/// conditions); a failure during the integration ends the run with
/// `stop.reason` = the flag name and the rows reached so far.
pub fn solve(scene: &FrictionScene, settings: &IdaSettings) -> Result<IdaRun, IdaError> {
    let dae = model_with(scene, settings.friction_row)?;
    solve_model(scene, dae.as_ref(), settings)
}

/// As [`solve`], with a given model (e.g. a modified formulation).
pub fn solve_model(
    scene: &FrictionScene,
    dae: &dyn FrictionDae,
    settings: &IdaSettings,
) -> Result<IdaRun, IdaError> {
    if settings.max_nonlin_iters == 0 {
        return Err(IdaError::Input(
            "--max-nonlin-iters must be at least 1".into(),
        ));
    }
    let start = Instant::now();
    let grid = scene.output_times();
    let t_end = scene.t_end;
    let tol = &settings.tol;
    let (y0, yp0) = dae.initial_guess();
    let mut ida = Ida::new(dae, 0.0, &y0, &yp0, tol.rtol, tol.atol)?;
    let differential = dae.differential();
    let atol_alg = settings.algebraic.atol(tol.atol);
    if atol_alg != tol.atol {
        let atol: Vec<f64> = differential
            .iter()
            .map(|&d| if d { tol.atol } else { atol_alg })
            .collect();
        ida.set_vector_tolerances(tol.rtol, &atol)?;
    }
    ida.set_suppress_alg(settings.algebraic == AlgebraicControl::Suppress)?;
    ida.set_max_num_steps(MAX_STEPS)?;
    if settings.max_nonlin_iters != IDA_MAX_NONLIN_ITERS {
        ida.set_max_nonlin_iters(settings.max_nonlin_iters as i32)?;
    }
    ida.set_stop_time(t_end)?;
    let (y0, yp0) = ida.calc_ic(grid.get(1).copied().unwrap_or(t_end))?;
    let label = Label {
        tool: "SUNDIALS IDA",
        version: sundials_version(),
        method: "bdf".into(),
        rtol: tol.rtol,
        atol: tol.atol,
        algebraic: settings.algebraic.to_string(),
        options: vec![
            ("friction_row".into(), settings.friction_row.name().into()),
            (
                "max_nonlin_iters".into(),
                settings.max_nonlin_iters.to_string(),
            ),
        ],
    };
    let suppress = settings.algebraic == AlgebraicControl::Suppress;
    let in_test = differential.iter().map(|&d| d || !suppress).collect();
    let mut stepper = IdaStepper { ida, in_test };
    Ok(drive(scene, dae, &mut stepper, y0, yp0, label, start))
}

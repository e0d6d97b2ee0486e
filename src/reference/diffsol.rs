//! Solves a friction scene with diffsol (pure Rust; Robinson et al.,
//! <https://github.com/martinjrobins/diffsol>), a second implicit solver
//! written by others, independent of SUNDIALS: variable-order BDF or the
//! ESDIRK34 Runge-Kutta method, dense faer LU.
//!
//! ## Mass-matrix form
//! diffsol solves M y' = f(t, y). Our DAEs ([`FrictionDae`]) are written as
//! F(t, y, y') = 0 with F linear in y' with unit coefficient on the
//! differential rows (F_i = y'_i - v_i) and without y' on the algebraic
//! rows, so M = diag(1 on differential unknowns, 0 on algebraic ones) and
//! f(t, y) = -F(t, y, 0), df/dy = -dF/dy (the analytic Jacobian at cj = 0).
//! A semi-explicit index-1 DAE is what diffsol's singular mass matrix
//! supports; its consistent initialization solves the algebraic rows for the
//! algebraic unknowns at the exact initial positions.
//!
//! ## Settings that depart from diffsol's defaults (each a CLI option)
//! - Per-unknown atol (`--atol-algebraic`, default [`ATOL_ALGEBRAIC`]):
//!   diffsol's error norm covers every unknown and has no suppress-alg; with
//!   one atol the slip velocity's steep dependence on u_x (see
//!   [`super::settings::AlgebraicControl`]) pins BDF at order 1 (issue 16:
//!   6,113 steps at zeta = 1e-4 N, failure at 1e-6 N).
//! - `--fresh-jacobian` (default [`FRESH_JACOBIAN`]): df/dy at every step
//!   and after every Newton failure (see there why).
//! - `--max-nonlinear-failures` (default [`MAX_NONLINEAR_FAILURES`]; diffsol's
//!   own is 50): diffsol counts Newton convergence failures over the whole
//!   run, not per step as IDA does, so a long run with a few failures per
//!   sharp transition would abort for no fault of the step.
//!
//! The Jacobian is the analytic one, assembled by diffsol column by column
//! from J v products; a one-entry cache evaluates it once per (t, y).

use super::counters::Counters;
use super::dae::{Dense, FrictionDae};
use super::error::IdaError;
use super::laws::RowForm;
use super::run::{IdaRun, Label, Stepper, drive, model_with};
use super::settings::{DiffsolMethod, Tolerances, positive};
use crate::scene::friction::FrictionScene;
use diffsol::{
    FaerLU, FaerMat, OdeBuilder, OdeEquations, OdeSolverMethod, OdeSolverProblem,
    OdeSolverStopReason, Vector,
};
use std::cell::{Cell, RefCell};
use std::time::Instant;

/// Default absolute tolerance of the algebraic unknowns (velocities m/s,
/// forces N, and u_y on the plane, m).
pub const ATOL_ALGEBRAIC: f64 = 1e-6;

/// Default limit on Newton convergence failures over a whole run.
pub const MAX_NONLINEAR_FAILURES: usize = 100_000;

/// Default of [`DiffsolSettings::fresh_jacobian`]. diffsol re-evaluates
/// df/dy only every 50 steps (`update_rhs_jacobian_after_steps`), and after a
/// Newton convergence failure only if the step changed by less than 20%
/// (`threshold_to_update_rhs_jacobian`); it refactors M - h gamma J with the
/// old J otherwise. Across a stick-slip transition (width omega Vc) df/dy
/// changes by up to 1/q = 20. With diffsol's defaults (and our other
/// settings) BDF stopped in 5 of the 27 cells of issue 16 at rtol 1e-8: 3 by
/// 40 error-test failures in one step (friction-plane, t = 0.67-0.88 s), 2 by
/// a step below diffsol's minimum of 1e-13 s (roller, omega = 1e-6, t = 2.17
/// s and 2.73 s). With `true` (update_rhs_jacobian_after_steps = 1,
/// threshold_to_update_rhs_jacobian infinite) it ends in all 27; n = 6, so J
/// costs little. (diffsol evaluates J at the step's start, not at the
/// predicted end as IDA does.)
pub const FRESH_JACOBIAN: bool = true;

/// The settings of a diffsol run.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffsolSettings {
    pub method: DiffsolMethod,
    /// rtol, and atol of the differential unknowns.
    pub tol: Tolerances,
    /// atol of the algebraic unknowns.
    pub atol_algebraic: f64,
    pub max_nonlinear_failures: usize,
    /// df/dy evaluated at every step and after every Newton convergence
    /// failure (default true; false: diffsol's defaults, see [`FRESH_JACOBIAN`]).
    pub fresh_jacobian: bool,
    /// How the DAE writes the friction law (default [`RowForm::Product`]).
    pub friction_row: RowForm,
}

impl DiffsolSettings {
    /// The defaults at rtol (atol = rtol).
    pub fn new(method: DiffsolMethod, rtol: f64) -> Result<Self, IdaError> {
        Ok(Self {
            method,
            tol: Tolerances::new(rtol, None)?,
            atol_algebraic: ATOL_ALGEBRAIC,
            max_nonlinear_failures: MAX_NONLINEAR_FAILURES,
            fresh_jacobian: FRESH_JACOBIAN,
            friction_row: RowForm::Product,
        })
    }

    fn check(&self) -> Result<(), IdaError> {
        positive("rtol", self.tol.rtol)?;
        positive("atol", self.tol.atol)?;
        positive("atol-algebraic", self.atol_algebraic)?;
        if self.max_nonlinear_failures == 0 {
            return Err(IdaError::Input(
                "--max-nonlinear-failures must be at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// The diffsol version this crate was built with.
pub const VERSION: &str = "0.18";

type M = FaerMat<f64>;
type LS = FaerLU<f64>;

/// Counts of our callbacks (diffsol does not count residuals per se).
#[derive(Default)]
struct Calls {
    residuals: Cell<u64>,
    jacobians: Cell<u64>,
}

/// The analytic Jacobian df/dy at the last (t, y) asked for.
struct JacobianCache {
    t: f64,
    y: Vec<f64>,
    /// Column-major n x n.
    j: Vec<f64>,
}

/// Solves the scene with diffsol.
///
/// Errors are returned for bad settings and failures before the first step;
/// a failure during the integration ends the run with `stop.reason` =
/// "diffsol_error" and the rows reached so far.
pub fn solve(scene: &FrictionScene, settings: &DiffsolSettings) -> Result<IdaRun, IdaError> {
    let dae = model_with(scene, settings.friction_row)?;
    solve_model(scene, dae.as_ref(), settings)
}

/// As [`solve`], with a given model.
pub fn solve_model(
    scene: &FrictionScene,
    dae: &dyn FrictionDae,
    settings: &DiffsolSettings,
) -> Result<IdaRun, IdaError> {
    settings.check()?;
    let start = Instant::now();
    let n = dae.dim();
    let differential = dae.differential();
    let (y_guess, _) = dae.initial_guess();
    let calls = Calls::default();
    let cache = RefCell::new(JacobianCache {
        t: f64::NAN,
        y: vec![f64::NAN; n],
        j: vec![0.0; n * n],
    });
    let zero = vec![0.0; n];
    let rhs = |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| {
        calls.residuals.set(calls.residuals.get() + 1);
        dae.residual(t, x, &zero, y);
        for v in y.iter_mut() {
            *v = -*v;
        }
    };
    let jac = |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
        let mut c = cache.borrow_mut();
        if c.t != t || c.y != x {
            calls.jacobians.set(calls.jacobians.get() + 1);
            c.t = t;
            c.y.copy_from_slice(x);
            c.j.fill(0.0);
            dae.jacobian(t, 0.0, x, &zero, &mut Dense { n, data: &mut c.j });
        }
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = -(0..n).map(|k| c.j[k * n + i] * v[k]).sum::<f64>();
        }
    };
    let mass = |v: &[f64], _p: &[f64], _t: f64, beta: f64, y: &mut [f64]| {
        for i in 0..n {
            let m = if differential[i] { v[i] } else { 0.0 };
            y[i] = m + beta * y[i];
        }
    };
    let init = |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y_guess);
    // Differential unknowns at atol, algebraic ones at atol_algebraic. (Also
    // measured: every position at atol, the plane's algebraic u_y included.
    // It cut the plane's u_x error at rtol 1e-8 from 1e-8..9e-8 to
    // 3e-9..9e-8, but BDF then failed to start at zeta = omega = 1e-6:
    // Newton diverged at the stick-slip transition, t = 1.4e-7 s.)
    let atol: Vec<f64> = differential
        .iter()
        .map(|&d| {
            if d {
                settings.tol.atol
            } else {
                settings.atol_algebraic
            }
        })
        .collect();
    let mut problem = OdeBuilder::<M>::new()
        .t0(0.0)
        .rtol(settings.tol.rtol)
        .atol(atol)
        .rhs_implicit(rhs, jac)
        .mass(mass)
        .init(init, n)
        .build()
        .map_err(|e| IdaError::Diffsol {
            message: format!("building the problem: {e}"),
            t: 0.0,
        })?;
    problem.ode_options.max_nonlinear_solver_failures = settings.max_nonlinear_failures;
    if settings.fresh_jacobian {
        problem.ode_options.update_rhs_jacobian_after_steps = 1;
        problem.ode_options.threshold_to_update_rhs_jacobian = f64::INFINITY;
    }
    let label = Label {
        tool: "diffsol",
        version: VERSION.into(),
        method: settings.method.name().into(),
        rtol: settings.tol.rtol,
        atol: settings.tol.atol,
        algebraic: format!("{:e}", settings.atol_algebraic),
        options: vec![
            (
                "max_nonlinear_failures".into(),
                settings.max_nonlinear_failures.to_string(),
            ),
            ("fresh_jacobian".into(), settings.fresh_jacobian.to_string()),
            ("friction_row".into(), settings.friction_row.name().into()),
        ],
    };
    let fail = |e: diffsol::error::DiffsolError| IdaError::Diffsol {
        message: format!("consistent initialization: {e}"),
        t: 0.0,
    };
    match settings.method {
        DiffsolMethod::Bdf => {
            let solver = problem.bdf::<LS>().map_err(fail)?;
            run_solver(scene, dae, &problem, solver, &calls, label, start)
        }
        DiffsolMethod::Esdirk => {
            let solver = problem.esdirk34::<LS>().map_err(fail)?;
            run_solver(scene, dae, &problem, solver, &calls, label, start)
        }
    }
}

fn run_solver<'a, Eqn, S>(
    scene: &FrictionScene,
    dae: &dyn FrictionDae,
    _problem: &'a OdeSolverProblem<Eqn>,
    mut solver: S,
    calls: &Calls,
    label: Label,
    start: Instant,
) -> Result<IdaRun, IdaError>
where
    Eqn: OdeEquations<T = f64, M = M> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    solver
        .set_stop_time(scene.t_end)
        .map_err(|e| IdaError::Diffsol {
            message: format!("set_stop_time: {e}"),
            t: 0.0,
        })?;
    let y0 = solver.state().y.clone_as_vec();
    let yp0 = solver.state().dy.clone_as_vec();
    let mut stepper = DiffsolStepper {
        solver,
        calls,
        t_prev: 0.0,
        h: 0.0,
        reached_stop: false,
        _eqn: std::marker::PhantomData,
    };
    Ok(drive(scene, dae, &mut stepper, y0, yp0, label, start))
}

struct DiffsolStepper<'a, 'c, Eqn, S> {
    solver: S,
    calls: &'c Calls,
    t_prev: f64,
    h: f64,
    reached_stop: bool,
    _eqn: std::marker::PhantomData<&'a Eqn>,
}

impl<'a, Eqn, S> Stepper for DiffsolStepper<'a, '_, Eqn, S>
where
    Eqn: OdeEquations<T = f64, M = M> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    fn step(&mut self, t_end: f64) -> Result<f64, IdaError> {
        let t0 = self.solver.state().t;
        if self.reached_stop {
            return Ok(t_end);
        }
        match self.solver.step() {
            Ok(reason) => {
                let t = self.solver.state().t;
                self.t_prev = t0;
                self.h = t - t0;
                if matches!(reason, OdeSolverStopReason::TstopReached) {
                    self.reached_stop = true;
                    return Ok(t_end.max(t));
                }
                Ok(t)
            }
            Err(e) => Err(IdaError::Diffsol {
                message: e.to_string(),
                t: t0,
            }),
        }
    }
    fn y(&self) -> Vec<f64> {
        self.solver.state().y.clone_as_vec()
    }
    fn last_step(&self) -> f64 {
        self.h
    }
    fn order(&self) -> i32 {
        self.solver.order() as i32
    }
    fn interpolate(&mut self, t: f64) -> Result<Vec<f64>, IdaError> {
        if t >= self.solver.state().t {
            return Ok(self.y());
        }
        self.solver
            .interpolate(t)
            .map(|v| v.clone_as_vec())
            .map_err(|e| IdaError::Diffsol {
                message: format!("interpolate: {e}"),
                t,
            })
    }
    fn counters(&self) -> Counters {
        let s = self.solver.get_statistics();
        Counters {
            steps: s.number_of_steps as u64,
            residual_evaluations: self.calls.residuals.get(),
            jacobian_evaluations: self.calls.jacobians.get(),
            factorizations: s.number_of_linear_solver_setups as u64,
            linear_solves: s.number_of_nonlinear_solver_iterations as u64,
            nonlinear_iterations: s.number_of_nonlinear_solver_iterations as u64,
            error_test_failures: s.number_of_error_test_failures as u64,
            convergence_failures: s.number_of_nonlinear_solver_fails as u64,
        }
    }
}

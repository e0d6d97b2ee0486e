//! SUNDIALS IDA on the shell with friction (issue 10 item 3c, feature
//! `reference`): the same residual as the ANM's
//! ([`crate::shell::friction_dae`]) in IDA's implicit form F(t, y, y') = 0,
//! y = (U, w):
//!
//!   E(U, w, t) = 0                          (equilibrium, n rows)
//!   t_a(x_i) · ẋ_i − w_i,a = 0              (kinematics, 2 per friction node)
//!
//! with ẋ_i the node's translation rates from y'. Its Jacobian is analytic:
//! ∂E/∂(U, w) from the ANM's linearization, and for the kinematic rows
//! (∂t_a/∂x)ᵀ ẋ on x, −1 on w_a and cj t_a on ẋ. The translations of the
//! friction nodes are differential (y' enters), everything else algebraic
//! and, as for the point-mass references (`ida_run`), out of the local error
//! test (IDASetSuppressAlg: w is the steep unknown in saturated slip).
//! Dense linear algebra: for coarse scenes only (a few hundred unknowns).
//! The friction pairs are those active at t = 0 (the scene's
//! `contact.search_distance` must cover every candidate for the whole run).
//! `anm reference ida` on a shell scene with `[friction]` runs it
//! ([`crate::run::shell_reference`]).

use super::counters::Counters;
use super::dae::{Dae, Dense};
use super::error::IdaError;
use super::ida::{Ida, Task};
use crate::shell::friction_dae::{FrictionDae, TimeState};
use std::cell::{Ref, RefCell};

/// Largest system the dense linear algebra is offered: one factorization
/// costs (2/3) n³ flops, about 2 s at n = 2,500 on a laptop core, and IDA
/// refactors every few steps.
pub const MAX_UNKNOWNS: usize = 2_500;

/// The shell DAE in IDA's form.
pub struct ShellIda {
    dae: RefCell<FrictionDae>,
    n: usize,
    /// Model pair index and node of each friction pair, in unknown order.
    pairs: Vec<(usize, usize)>,
    dofs: Vec<[usize; 3]>,
    n_model_pairs: usize,
    /// IDASetMaxNonlinIters, when set (IDA's default is 4).
    max_nonlin_iters: Option<i32>,
    /// The consistent state IDA starts from (y' = 0: at rest).
    start: Vec<f64>,
}

/// IDA's solution at the output times.
pub struct ShellIdaRun {
    /// (t, full dof vector) at each output time.
    pub samples: Vec<(f64, Vec<f64>)>,
    pub wall_s: f64,
    /// The DAE's state at each output time (aligned with `samples`).
    pub states: Vec<TimeState>,
    /// IDA's counters under the common names (`summary.json`).
    pub counters: Counters,
    /// The failure that ended the integration before the last output time
    /// ([`ShellIda::solve_keeping`]; `solve` returns it as its error).
    pub stop: Option<IdaError>,
}

impl ShellIda {
    /// From a DAE at rest at t = 0 (U = 0, w = 0, consistent).
    pub fn new(dae: FrictionDae) -> Result<Self, IdaError> {
        let rest = crate::shell::time_path::at_rest(&dae);
        Self::from_state(dae, rest)
    }

    /// From a consistent state at t = 0 with w = 0 (the ANM's start:
    /// [`crate::shell::time_path::start_state`]), y' = 0.
    pub fn from_state(mut dae: FrictionDae, start: TimeState) -> Result<Self, IdaError> {
        let n = crate::series::ContinuationProblem::ndof(&dae.model);
        let n_model_pairs = dae.model.pairs.len();
        dae.prepare(&start)
            .map_err(|e| IdaError::Input(e.to_string()))?;
        let pairs: Vec<(usize, usize)> = dae.step_pairs().collect();
        let dofs = (0..pairs.len()).map(|i| dae.pair_dofs(i)).collect();
        let mut y0 = start.u.clone();
        for &(p, _) in &pairs {
            y0.extend(start.w[p]);
        }
        Ok(Self {
            dae: RefCell::new(dae),
            n,
            pairs,
            dofs,
            n_model_pairs,
            max_nonlin_iters: None,
            start: y0,
        })
    }

    /// IDA's absolute tolerance per unknown from that of the translations
    /// (`atol`, scene length unit): the rotations atol / L (radians), the
    /// tangential velocities w atol / t_end, with L the model's length scale
    /// and t_end the last output time, so that one atol means the same in
    /// m and in mm. The rotations and w are algebraic, out of the local
    /// error test: these enter IDA's Newton test only. Measured on
    /// scenes/strip-capstan.toml: at rtol 1e-10 IDA reaches t_end with 4,
    /// 10 and 20 Newton iterations, 5.9e-7 off the ANM on the positions
    /// (as with one scalar atol); at rtol 1e-12 it reaches t_end with 10
    /// (2e-9 off), where one scalar atol stopped with IDA_CONV_FAIL at
    /// t = 0.54 s, and it still stops with 4 and 20 (t = 0.54 s, 0.60 s):
    /// near 1e-12 IDA's Newton test meets the round-off of this residual.
    fn absolute_tolerances(&self, atol: f64, outputs: &[f64]) -> Vec<f64> {
        let dae = self.dae.borrow();
        let length = dae.model.length_scale;
        let t_end = outputs.last().copied().unwrap_or(1.0);
        let mut tol = vec![atol / t_end; self.dim()];
        for (full, free) in dae.model.free.iter().enumerate() {
            if let Some(k) = free {
                tol[*k] = if full % crate::fe::dof::PER_NODE < 3 {
                    atol
                } else {
                    atol / length
                };
            }
        }
        tol
    }

    /// The DAE (e.g. to evaluate outputs at the states of a run).
    pub fn dae(&self) -> Ref<'_, FrictionDae> {
        self.dae.borrow()
    }

    fn state(&self, t: f64, y: &[f64]) -> TimeState {
        let mut w = vec![[0.0; 2]; self.n_model_pairs];
        for (i, (p, _)) in self.pairs.iter().enumerate() {
            w[*p] = [y[self.n + 2 * i], y[self.n + 2 * i + 1]];
        }
        TimeState {
            t,
            u: y[..self.n].to_vec(),
            w,
        }
    }

    /// Newton iterations per step attempt (IDASetMaxNonlinIters). A
    /// reference run at rtol 1e-12 needs more than IDA's default 4: its
    /// corrections sit at round-off, and with 4 the coarse capstan stopped
    /// with IDA_CONV_FAIL at t = 0.549988 s when the element's stiffness
    /// map was scaled by 1 ± 2.2e-16 (it passed unscaled); with 10 it
    /// passed in all three cases.
    pub fn with_max_nonlin_iters(mut self, iters: i32) -> Self {
        self.max_nonlin_iters = Some(iters);
        self
    }

    /// Integrates to each output time with IDA at rtol (atol = rtol × the
    /// scene's length scale on the translations); IDASetStopTime at every
    /// kink of the ramps. A failure during the integration is the error.
    pub fn solve(
        &self,
        outputs: &[f64],
        kinks: &[f64],
        rtol: f64,
        max_steps: i64,
    ) -> Result<ShellIdaRun, IdaError> {
        let atol = rtol * self.dae.borrow().model.length_scale;
        let mut run = self.solve_keeping(outputs, kinks, rtol, atol, max_steps)?;
        match run.stop.take() {
            Some(e) => Err(e),
            None => Ok(run),
        }
    }

    /// As [`Self::solve`] with the absolute tolerance of the translations
    /// given (in the scene's length unit); a failure after the set-up ends
    /// the run with the output times reached and the failure in `stop`.
    pub fn solve_keeping(
        &self,
        outputs: &[f64],
        kinks: &[f64],
        rtol: f64,
        atol: f64,
        max_steps: i64,
    ) -> Result<ShellIdaRun, IdaError> {
        let start = std::time::Instant::now();
        let dim = self.dim();
        let mut ida = Ida::new(self, 0.0, &self.start, &vec![0.0; dim], rtol, atol)?;
        ida.set_suppress_alg(true)?;
        ida.set_vector_tolerances(rtol, &self.absolute_tolerances(atol, outputs))?;
        ida.set_max_num_steps(max_steps)?;
        if let Some(iters) = self.max_nonlin_iters {
            ida.set_max_nonlin_iters(iters)?;
        }
        let mut samples = vec![];
        let mut states = vec![];
        let mut stop = None;
        'outputs: for &tout in outputs {
            loop {
                let next = kinks
                    .iter()
                    .copied()
                    .filter(|&k| k > ida.t() * (1.0 + 1e-14))
                    .fold(tout, f64::min);
                let reached = ida
                    .set_stop_time(next)
                    .and_then(|_| ida.solve(next, Task::Normal));
                match reached {
                    Ok(t) if t >= tout * (1.0 - 1e-14) => break,
                    Ok(_) => {}
                    Err(e) => {
                        stop = Some(e);
                        break 'outputs;
                    }
                }
            }
            let dae = self.dae.borrow();
            let full = dae
                .model
                .expand(&ida.y()[..self.n], dae.laws.load.value(tout));
            samples.push((tout, full));
            states.push(self.state(tout, ida.y()));
        }
        let c = ida.counters();
        Ok(ShellIdaRun {
            samples,
            wall_s: start.elapsed().as_secs_f64(),
            states,
            counters: c.common(),
            stop,
        })
    }
}

impl Dae for ShellIda {
    fn dim(&self) -> usize {
        self.n + 2 * self.pairs.len()
    }

    fn differential(&self) -> Vec<bool> {
        let mut d = vec![false; self.dim()];
        for dofs in &self.dofs {
            for &k in dofs {
                d[k] = true;
            }
        }
        d
    }

    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let mut dae = self.dae.borrow_mut();
        let s = self.state(t, y);
        match dae.residual(&s) {
            Ok(e) => r[..self.n].copy_from_slice(&e),
            Err(_) => {
                r.iter_mut().for_each(|v| *v = f64::NAN);
                return;
            }
        }
        for (i, dofs) in self.dofs.iter().enumerate() {
            let (t_a, _) = dae.frame(i);
            for a in 0..2 {
                let rate: f64 = (0..3).map(|c| t_a[a][c] * yp[dofs[c]]).sum();
                r[self.n + 2 * i + a] = rate - y[self.n + 2 * i + a];
            }
        }
    }

    fn jacobian(&self, t: f64, cj: f64, y: &[f64], yp: &[f64], j: &mut Dense) {
        let mut dae = self.dae.borrow_mut();
        let s = self.state(t, y);
        if dae.prepare(&s).is_err() {
            j.data.iter_mut().for_each(|v| *v = f64::NAN);
            return;
        }
        for &(r, c, v) in dae.equilibrium_rows() {
            j.add(r, c, v);
        }
        for (i, dofs) in self.dofs.iter().enumerate() {
            let (t_a, dt) = dae.frame(i);
            for a in 0..2 {
                let row = self.n + 2 * i + a;
                for c in 0..3 {
                    let curvature: f64 = (0..3).map(|k| dt[a][k][c] * yp[dofs[k]]).sum();
                    j.add(row, dofs[c], curvature + cj * t_a[a][c]);
                }
                j.add(row, row, -1.0);
            }
        }
    }
}

/// Largest |u_a − u_b| over the translations of full dof vectors at the
/// same times, relative to the largest |u_b| (the ANM's trajectory against
/// IDA's).
pub fn trajectory_difference(a: &[(f64, Vec<f64>)], b: &[(f64, Vec<f64>)]) -> f64 {
    let mut diff = 0.0f64;
    let mut size = 0.0f64;
    for ((_, ua), (_, ub)) in a.iter().zip(b) {
        for (k, (x, y)) in ua.iter().zip(ub).enumerate() {
            if k % crate::fe::dof::PER_NODE < 3 {
                diff = diff.max((x - y).abs());
                size = size.max(y.abs());
            }
        }
    }
    diff / size
}

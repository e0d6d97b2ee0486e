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

use super::dae::{Dae, Dense};
use super::error::IdaError;
use super::ida::{Ida, Task};
use crate::shell::friction_dae::{FrictionDae, TimeState};
use std::cell::RefCell;

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
}

/// IDA's solution at the output times.
pub struct ShellIdaRun {
    /// (t, full dof vector) at each output time.
    pub samples: Vec<(f64, Vec<f64>)>,
    pub steps: i64,
    pub residual_evals: i64,
    pub jacobian_evals: i64,
    pub error_test_fails: i64,
    pub nonlinear_conv_fails: i64,
    pub wall_s: f64,
}

impl ShellIda {
    /// From a DAE at rest at t = 0 (U = 0, w = 0, consistent).
    pub fn new(mut dae: FrictionDae) -> Result<Self, IdaError> {
        let n = crate::series::ContinuationProblem::ndof(&dae.model);
        let n_model_pairs = dae.model.pairs.len();
        let rest = TimeState {
            t: 0.0,
            u: vec![0.0; n],
            w: vec![[0.0; 2]; n_model_pairs],
        };
        dae.prepare(&rest)
            .map_err(|e| IdaError::Input(e.to_string()))?;
        let pairs: Vec<(usize, usize)> = dae.step_pairs().collect();
        let dofs = (0..pairs.len()).map(|i| dae.pair_dofs(i)).collect();
        Ok(Self {
            dae: RefCell::new(dae),
            n,
            pairs,
            dofs,
            n_model_pairs,
            max_nonlin_iters: None,
        })
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
    /// kink of the ramps.
    pub fn solve(
        &self,
        outputs: &[f64],
        kinks: &[f64],
        rtol: f64,
        max_steps: i64,
    ) -> Result<ShellIdaRun, IdaError> {
        let start = std::time::Instant::now();
        let dim = self.dim();
        let length = self.dae.borrow().model.length_scale;
        let mut ida = Ida::new(
            self,
            0.0,
            &vec![0.0; dim],
            &vec![0.0; dim],
            rtol,
            rtol * length,
        )?;
        ida.set_suppress_alg(true)?;
        ida.set_max_num_steps(max_steps)?;
        if let Some(iters) = self.max_nonlin_iters {
            ida.set_max_nonlin_iters(iters)?;
        }
        let mut samples = vec![];
        for &tout in outputs {
            loop {
                let stop = kinks
                    .iter()
                    .copied()
                    .filter(|&k| k > ida.t() * (1.0 + 1e-14))
                    .fold(tout, f64::min);
                ida.set_stop_time(stop)?;
                let t = ida.solve(stop, Task::Normal)?;
                if t >= tout * (1.0 - 1e-14) {
                    break;
                }
            }
            let dae = self.dae.borrow();
            let full = dae
                .model
                .expand(&ida.y()[..self.n], dae.laws.load.value(tout));
            samples.push((tout, full));
        }
        let c = ida.counters();
        Ok(ShellIdaRun {
            samples,
            steps: c.steps,
            residual_evals: c.residual_evals,
            jacobian_evals: c.jacobian_evals,
            error_test_fails: c.error_test_fails,
            nonlinear_conv_fails: c.nonlinear_conv_fails,
            wall_s: start.elapsed().as_secs_f64(),
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

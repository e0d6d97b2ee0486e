//! The shell with regularized friction: an index-1 DAE in time (issue 10
//! item 2, DESIGN §7), expanded in Taylor series with one sparse
//! factorization per step.
//!
//! Unknowns: the free dofs U(t) of the shell and, at each friction node i
//! (an active contact pair; one obstacle per node, the nearest: run::build), w_i = (t_1·ẋ_i, t_2·ẋ_i),
//! its velocity in the obstacle's tangent frame ([`super::friction_pair`]):
//!
//!   E(U, w, t) = R(U, λ(t)) − Σ_j ρ_j(t) F_j − Σ_i R_T,i(x_i, w_i, m(t)) = 0   (equilibrium)
//!   t_a(x_i)·ẋ_i − w_i,a = 0,  a = 1, 2                        (kinematics)
//!
//! with R the static residual of [`super::model`] (elements, loads, the normal
//! law of eq. 3), λ(t) the load ramp, m(t) the motion ramp and F_j the dead
//! loads with their own ramps ρ_j (`load.ramp`). The normal
//! position of a contact node is algebraic (the normal law), its tangential
//! position differential; dR_T/dw is invertible wherever |R_N|_reg > 0
//! (zeta > 0), so the DAE has index 1.
//!
//! Series in a = t − t0 (U = Σ U_k a^k, w = Σ w_k a^k). Order k ≥ 1 of the
//! equilibrium and order k − 1 of the kinematics give, with J the Jacobian
//! at the step start (one factorization for every order):
//!
//!   [K − ∂R_T/∂x   −∂R_T/∂w] [U_k]   [−R_λ λ_k − S_k + R̃_T,k                       ]
//!   [  T_0 S           0   ] [w_k] = [(w_{k−1} − Σ_{j=1}^{k−1} T_j·(k−j) x_{k−j}) / k]
//!
//! S_k = ContinuationProblem::series_rhs (order k of R with U_k = λ_k = 0),
//! R̃_T,k = order k of R_T with x_k = w_k = 0 (the tape), T_j the series of
//! the frame rows and S the node's translation dofs. The kinematic rows are
//! scaled by a typical diagonal entry of K.

use super::chart::{Chart, ChartValue};
use super::friction_pair::{self, FrictionPair};
use super::model::ShellModel;
use super::ramp::Ramp;
use crate::contact::{FrictionLaw, Motion};
use crate::error::{Error, Result};
use crate::fe::dof::index as dof;
use crate::linalg::{Factorization, LinearSolver, SparseMatrix, norm};
use crate::series::ContinuationProblem;
use nalgebra::Vector3;

/// The time functions and the friction law of a run.
#[derive(Clone, Debug)]
pub struct TimeLaws {
    pub law: FrictionLaw,
    /// Scales loads and prescribed values (the static model's lambda).
    pub load: Ramp,
    /// Scales the obstacles' surface velocities.
    pub motion: Ramp,
    /// The obstacles' motions at full ramp (m/s, rad/s).
    pub motions: Vec<Motion>,
    /// Dead loads with their own time function: (ramp, force F on the free
    /// dofs); E carries − ramp(t) F each.
    pub extra_loads: Vec<(Ramp, Vec<f64>)>,
}

impl TimeLaws {
    /// Every time where a load or motion factor has a kink.
    pub fn kinks(&self) -> Vec<f64> {
        let mut k = self.load.kinks();
        k.extend(self.motion.kinks());
        for (r, _) in &self.extra_loads {
            k.extend(r.kinks());
        }
        k
    }
}

/// The state at a step start: t, the free dofs and the tangential velocity
/// unknowns of every contact pair of the model (zero where inactive).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TimeState {
    pub t: f64,
    pub u: Vec<f64>,
    pub w: Vec<[f64; 2]>,
}

/// The series of one step: U_k and, per friction pair of the step, w_k.
pub struct StepSeries {
    pub u: Vec<Vec<f64>>,
    /// w[k][2 i + a].
    pub w: Vec<Vec<f64>>,
}

pub struct FrictionDae {
    pub model: ShellModel,
    pub laws: TimeLaws,
    order: usize,
    solver: LinearSolver,
    /// Friction nodes of the current step.
    pairs: Vec<FrictionPair>,
    /// Free translation dofs of each friction node.
    node_dofs: Vec<[usize; 3]>,
    rl: Vec<f64>,
    /// The equilibrium rows of the augmented matrix at the step start.
    equilibrium_rows: Vec<(usize, usize, f64)>,
    /// ∂E/∂t at the step start (the ramps' rates), free dofs.
    e_t: Vec<f64>,
    /// Tangential coordinates of each friction node (the implicit step)
    /// and their values at the step start.
    charts: Vec<Chart>,
    chart_start: Vec<ChartValue>,
    factor: Option<Factorization>,
    row_scale: f64,
    /// Contact nodes left without friction (a fixed translation).
    pub skipped: Vec<usize>,
    pub factorizations: usize,
    /// Triangular solves with the factorization (series orders, Newton
    /// and quasi-Newton corrections): summary.json `counters`.
    pub solves: std::cell::Cell<usize>,
    /// Evaluations of the equilibrium residual E(U, w, t).
    pub residual_evaluations: usize,
}

impl FrictionDae {
    /// The model must hold its obstacles fixed (their motion only enters the
    /// surface velocity: `laws.motions`).
    pub fn new(model: ShellModel, laws: TimeLaws, order: usize) -> Self {
        Self {
            model,
            laws,
            order,
            solver: LinearSolver::default(),
            pairs: vec![],
            node_dofs: vec![],
            rl: vec![],
            equilibrium_rows: vec![],
            e_t: vec![],
            charts: vec![],
            chart_start: vec![],
            factor: None,
            row_scale: 1.0,
            skipped: vec![],
            factorizations: 0,
            solves: std::cell::Cell::new(0),
            residual_evaluations: 0,
        }
    }

    pub fn n_pairs(&self) -> usize {
        self.pairs.len()
    }

    /// The friction pairs of the current step (model pair index, node).
    pub fn step_pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.pairs.iter().map(|p| (p.pair, p.node))
    }

    fn lambda(&self, t: f64) -> [f64; 2] {
        [self.laws.load.value(t), self.laws.load.rate(t)]
    }

    fn motion_factor(&self, t: f64) -> [f64; 2] {
        [self.laws.motion.value(t), self.laws.motion.rate(t)]
    }

    /// Linearizes at the state: the static tangent, the friction tapes of
    /// the active pairs, the augmented matrix and its factorization. Errors
    /// name the node of a problem.
    pub fn linearize(&mut self, s: &TimeState) -> Result<()> {
        self.prepare(s)?;
        self.factor_rows(None, s.t)
    }

    /// The linearization of [`FrictionDae::linearize`] without its
    /// factorization (the implicit step factorizes its own matrix).
    pub fn prepare(&mut self, s: &TimeState) -> Result<()> {
        let [lam0, lam1] = self.lambda(s.t);
        let [m0, m1] = self.motion_factor(s.t);
        let (k, rl) = self.model.tangent(&s.u, lam0)?;
        self.rl = rl;
        let full = self.model.expand(&s.u, lam0);
        self.pairs.clear();
        self.node_dofs.clear();
        self.skipped.clear();
        self.charts.clear();
        self.chart_start.clear();
        for &ip in self.model.active_pairs() {
            let pair = &self.model.pairs[ip];
            let free: Vec<Option<usize>> =
                (0..3).map(|c| self.model.free[dof(pair.node, c)]).collect();
            if free.iter().any(|f| f.is_none()) {
                self.skipped.push(pair.node);
                continue;
            }
            let ob = &self.model.obstacles[pair.obstacle];
            let x = self.model.position(&full, pair.node);
            let h0 = ob.gap(&x).map(|g| g.h).ok_or_else(|| Error::NonFinite {
                step: 0,
                param: "t",
                at: s.t,
                what: format!(
                    "contact gap of node {} (on the obstacle axis)",
                    self.model.node_tag(pair.node)
                ),
            })?;
            let mut fp = FrictionPair::new(
                ip,
                pair.node,
                pair.obstacle,
                ob,
                &self.laws.motions[pair.obstacle],
                &pair.law,
                &self.laws.law,
                h0,
                self.order,
            );
            let w = s.w[ip];
            fp.tape.eval(&[x[0], x[1], x[2], w[0], w[1], m0]);
            self.charts
                .push(Chart::new(ob, &x).ok_or_else(|| Error::NonFinite {
                    step: 0,
                    param: "t",
                    at: s.t,
                    what: format!(
                        "node {} lies on the obstacle axis",
                        self.model.node_tag(pair.node)
                    ),
                })?);
            self.chart_start
                .push(self.charts[self.charts.len() - 1].eval(&x, w));
            self.node_dofs
                .push(std::array::from_fn(|c| free[c].expect("checked free")));
            self.pairs.push(fp);
        }
        let n = self.model.ndof();
        let mut rows = Vec::new();
        let mut diag = 0.0f64;
        for (r, c, v) in k.entries() {
            rows.push((r, c, v));
            if r == c {
                diag = diag.max(v.abs());
            }
        }
        self.row_scale = if diag > 0.0 { diag } else { 1.0 };
        // ∂E/∂t = R_λ λ'(t) − Σ ∂R_T/∂m m'(t) (the ramps are linear
        // between their kinks, which no step crosses).
        self.e_t = self.rl.iter().map(|r| r * lam1).collect();
        for (ramp, f) in &self.laws.extra_loads {
            let rate = ramp.rate(s.t);
            for (e, fi) in self.e_t.iter_mut().zip(f) {
                *e -= rate * fi;
            }
        }
        for (i, fp) in self.pairs.iter().enumerate() {
            let jac = fp.tape.jacobian(&[
                0,
                1,
                2,
                friction_pair::W,
                friction_pair::W + 1,
                friction_pair::M,
            ]);
            let dofs = self.node_dofs[i];
            for r in 0..3 {
                for c in 0..3 {
                    rows.push((dofs[r], dofs[c], -jac[friction_pair::FORCE + r][c]));
                }
                for c in 0..2 {
                    rows.push((
                        dofs[r],
                        n + 2 * i + c,
                        -jac[friction_pair::FORCE + r][3 + c],
                    ));
                }
                self.e_t[dofs[r]] -= jac[friction_pair::FORCE + r][5] * m1;
            }
        }
        self.equilibrium_rows = rows;
        Ok(())
    }

    /// Factorizes the augmented matrix: the equilibrium rows of the last
    /// linearization and the kinematic rows, those of the series
    /// (`hg` = None: row_scale T_0 S, 0) or of the implicit step (`hg` =
    /// h γ: row_scale [(dC/dx − h γ ∂(D w)/∂x) S, −h γ D], module doc of
    /// [`super::implicit_step`]).
    fn factor_rows(&mut self, hg: Option<f64>, t: f64) -> Result<()> {
        let n = self.model.ndof();
        let np = self.pairs.len();
        let mut a = SparseMatrix::new(n + 2 * np);
        for &(r, c, v) in &self.equilibrium_rows {
            a.add(r, c, v);
        }
        for (i, fp) in self.pairs.iter().enumerate() {
            let dofs = self.node_dofs[i];
            for row in 0..2 {
                let coef = match hg {
                    None => fp.out3([friction_pair::T1, friction_pair::T2][row], 0),
                    Some(hg) => {
                        let v = &self.chart_start[i];
                        a.add(
                            n + 2 * i + row,
                            n + 2 * i + row,
                            -self.row_scale * hg * v.d[row],
                        );
                        v.dc[row] - v.ddw[row] * hg
                    }
                };
                for c in 0..3 {
                    a.add(n + 2 * i + row, dofs[c], self.row_scale * coef[c]);
                }
            }
        }
        let hint = if self.laws.law.zeta.is_none() {
            "; without friction.zeta a node with R_N = 0 has no friction capacity, so its tangential velocity is undetermined: set friction.zeta > 0"
        } else {
            ""
        };
        let f = self
            .solver
            .factorize(&a)
            .map_err(|e| Error::SingularMatrix {
                step: 0,
                param: "t",
                at: t,
                detail: format!("tangent of the shell with friction: {e}{hint}"),
            })?;
        self.factorizations += 1;
        self.factor = Some(f);
        Ok(())
    }

    /// Re-linearizes at `s` for a Newton iteration of the backward Euler
    /// step ([`super::implicit_step::newton_trial`]) and factorizes
    /// M/hg − J there (`hg` its h), keeping the charts of the last
    /// [`FrictionDae::prepare`] (the step's z is measured in them). False,
    /// with nothing factorized, where the set of friction pairs changed
    /// (the contact search moved a pair in or out: the step must be
    /// shorter).
    pub fn relinearize_in_charts(&mut self, s: &TimeState, hg: f64) -> Result<bool> {
        let pairs: Vec<usize> = self.pairs.iter().map(|p| p.pair).collect();
        let charts = std::mem::take(&mut self.charts);
        self.prepare(s)?;
        if self.pairs.iter().map(|p| p.pair).ne(pairs.iter().copied()) {
            return Ok(false);
        }
        let xs = self.pair_positions(&s.u, s.t);
        self.chart_start = charts
            .iter()
            .zip(&xs)
            .zip(&pairs)
            .map(|((c, x), &ip)| c.eval(x, s.w[ip]))
            .collect();
        self.charts = charts;
        self.factor_rows(Some(hg), s.t)?;
        Ok(true)
    }

    /// Refactorizes the last linearization for an implicit step of
    /// M/(h γ) − J with `hg` = h γ.
    pub fn factor_implicit(&mut self, hg: f64, t: f64) -> Result<()> {
        self.factor_rows(Some(hg), t)
    }

    /// Equilibrium residual E(U, w, t) on the free dofs at the state (the
    /// tapes of the last linearization are re-evaluated at it).
    pub fn residual(&mut self, s: &TimeState) -> Result<Vec<f64>> {
        self.residual_evaluations += 1;
        let [lam0, _] = self.lambda(s.t);
        let [m0, _] = self.motion_factor(s.t);
        let mut r = self.model.residual(&s.u, lam0)?;
        for (ramp, f) in &self.laws.extra_loads {
            let v = ramp.value(s.t);
            for (ri, fi) in r.iter_mut().zip(f) {
                *ri -= v * fi;
            }
        }
        let full = self.model.expand(&s.u, lam0);
        let xs: Vec<Vector3<f64>> = self
            .pairs
            .iter()
            .map(|fp| self.model.position(&full, fp.node))
            .collect();
        for (i, fp) in self.pairs.iter_mut().enumerate() {
            let x = xs[i];
            let w = s.w[fp.pair];
            let out = fp.tape.eval(&[x[0], x[1], x[2], w[0], w[1], m0]);
            for c in 0..3 {
                r[self.node_dofs[i][c]] -= out[friction_pair::FORCE + c];
            }
        }
        Ok(r)
    }

    /// Scale of the residual test: |R_λ| (loads and prescribed values) plus
    /// the sum of the normal reactions of the friction nodes.
    pub fn force_scale(&self) -> f64 {
        let rn: f64 = self
            .pairs
            .iter()
            .map(|fp| fp.tape.output(friction_pair::RN, 0).abs())
            .sum();
        norm(&self.rl)
            + self
                .laws
                .extra_loads
                .iter()
                .map(|(_, f)| norm(f))
                .sum::<f64>()
            + rn
    }

    /// The Newton direction at fixed tangential positions,
    /// [J] [δU; δw] = [−E; 0], applied to `s` with the factor `alpha`.
    pub fn newton_direction(&self, s: &TimeState, residual: &[f64]) -> Result<Vec<f64>> {
        let n = self.model.ndof();
        let mut rhs = vec![0.0; n + 2 * self.pairs.len()];
        for (r, e) in rhs.iter_mut().zip(residual) {
            *r = -e;
        }
        self.solve(&rhs, s.t)
    }

    /// `s` moved by alpha times a direction of [`FrictionDae::newton_direction`].
    pub fn moved(&self, s: &TimeState, d: &[f64], alpha: f64) -> TimeState {
        let n = self.model.ndof();
        let mut out = s.clone();
        for (u, du) in out.u.iter_mut().zip(d) {
            *u += alpha * du;
        }
        for (i, fp) in self.pairs.iter().enumerate() {
            out.w[fp.pair][0] += alpha * d[n + 2 * i];
            out.w[fp.pair][1] += alpha * d[n + 2 * i + 1];
        }
        out
    }

    /// A Newton direction d = (δU, δw) at y with its w part taken through
    /// the law's inverse (q = 0 only; otherwise d unchanged): per friction
    /// node, the linearized friction force R_T + ∂R_T/∂x δx + ∂R_T/∂w δw,
    /// over the cap f |R_N|_reg, is φ; where |φ| < 1 the new slip is the one
    /// the law maps to it, v_a = −ω Vc φ_a / √(1 − |φ|²); a node not yet
    /// saturated whose |φ| ≥ 1 goes to |φ| = 0.999 along it. Why: the law is
    /// a sigmoid of the slip of width ω Vc; a node that leaves saturation
    /// or enters it crosses that width, where the Newton step in w
    /// overshoots by orders of magnitude and the line search must shrink
    /// the whole step with it (measured: the conveying strip at ω = 1e-5
    /// stalled at α ≈ 1e-6), while the force it should carry is what the
    /// linearization gets right.
    pub fn law_space_direction(&mut self, y: &TimeState, d: &[f64]) -> Vec<f64> {
        let mut out = d.to_vec();
        let law = self.laws.law;
        if law.q != 0.0 {
            return out;
        }
        let n = self.model.ndof();
        let eps_v = law.omega * law.vc;
        let [m0, _] = self.motion_factor(y.t);
        let xs = self.pair_positions(&y.u, y.t);
        for (i, fp) in self.pairs.iter_mut().enumerate() {
            let x = xs[i];
            let w = y.w[fp.pair];
            let v = fp.tape.eval(&[x[0], x[1], x[2], w[0], w[1], m0]);
            let jac = fp
                .tape
                .jacobian(&[0, 1, 2, friction_pair::W, friction_pair::W + 1]);
            let dofs = self.node_dofs[i];
            let dx = [d[dofs[0]], d[dofs[1]], d[dofs[2]]];
            let dw = [d[n + 2 * i], d[n + 2 * i + 1]];
            let cap = law.f * law.normal_magnitude(v[friction_pair::RN]);
            let frame = [friction_pair::T1, friction_pair::T2]
                .map(|slot| Vector3::new(v[slot], v[slot + 1], v[slot + 2]));
            let force = |lin: bool| -> Vector3<f64> {
                Vector3::from_fn(|r, _| {
                    let mut f = v[friction_pair::FORCE + r];
                    if lin {
                        f += (0..3)
                            .map(|c| jac[friction_pair::FORCE + r][c] * dx[c])
                            .sum::<f64>()
                            + (0..2)
                                .map(|c| jac[friction_pair::FORCE + r][3 + c] * dw[c])
                                .sum::<f64>();
                    }
                    f
                })
            };
            let phi_of = |f: Vector3<f64>| frame.map(|t| t.dot(&f) / cap);
            let now = phi_of(force(false));
            let mut target = phi_of(force(true));
            let size = |p: [f64; 2]| (p[0] * p[0] + p[1] * p[1]).sqrt();
            let (size_now, size_target) = (size(now), size(target));
            if !(cap > 0.0 && size_target.is_finite()) {
                continue;
            }
            if size_target >= 1.0 {
                if size_now >= 0.999 {
                    continue; // saturated now and after: the law is flat, d is right
                }
                target = target.map(|p| p * 0.999 / size_target);
            }
            let root = (1.0 - size(target).powi(2)).sqrt();
            let slip = Vector3::new(
                v[friction_pair::SLIP],
                v[friction_pair::SLIP + 1],
                v[friction_pair::SLIP + 2],
            );
            for a in 0..2 {
                let v_new = -eps_v * target[a] / root;
                out[n + 2 * i + a] = v_new - frame[a].dot(&slip);
            }
        }
        out
    }

    /// The friction node whose residual force is the largest multiple of
    /// its friction cap f |R_N|_reg, and that multiple, for the residual
    /// `r` of [`FrictionDae::residual`] (its tapes at the same state).
    /// Above 1, no slip velocity balances that node with its tangential
    /// position held: the state is off the DAE's solution set.
    pub fn worst_cap_ratio(&self, r: &[f64]) -> Option<(usize, f64)> {
        let law = &self.laws.law;
        self.pairs
            .iter()
            .zip(&self.node_dofs)
            .map(|(fp, dofs)| {
                let force = dofs.iter().map(|&k| r[k] * r[k]).sum::<f64>().sqrt();
                let cap = law.f * law.normal_magnitude(fp.tape.output(friction_pair::RN, 0));
                (fp.node, force / cap)
            })
            .filter(|(_, q)| q.is_finite())
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// Free dofs of friction pair i's translations.
    pub fn pair_dofs(&self, i: usize) -> [usize; 3] {
        self.node_dofs[i]
    }

    /// The chart of friction pair i and its value at the step start.
    pub fn chart(&self, i: usize) -> (&Chart, &ChartValue) {
        (&self.charts[i], &self.chart_start[i])
    }

    /// ∂E/∂(U, w) at the last [`FrictionDae::prepare`] (columns n + 2 i + a
    /// for w of friction pair i).
    pub fn equilibrium_rows(&self) -> &[(usize, usize, f64)] {
        &self.equilibrium_rows
    }

    /// The frame t_a of friction pair i at the state of the last tape
    /// evaluation, and ∂t_a/∂x (row k, column c: ∂t_a,k/∂x_c).
    pub fn frame(&self, i: usize) -> ([Vector3<f64>; 2], [[[f64; 3]; 3]; 2]) {
        let fp = &self.pairs[i];
        let jac = fp.tape.jacobian(&[0, 1, 2]);
        let t = [fp.out3(friction_pair::T1, 0), fp.out3(friction_pair::T2, 0)];
        let dt = [friction_pair::T1, friction_pair::T2]
            .map(|slot| std::array::from_fn(|k| std::array::from_fn(|c| jac[slot + k][c])));
        (t, dt)
    }

    /// Scale of the kinematic rows of the augmented matrix.
    pub fn row_scale(&self) -> f64 {
        self.row_scale
    }

    /// ∂E/∂t at the step start.
    pub fn e_t(&self) -> &[f64] {
        &self.e_t
    }

    /// Positions of the friction pairs' nodes for the free dofs u at time t.
    pub fn pair_positions(&self, u: &[f64], t: f64) -> Vec<Vector3<f64>> {
        let full = self.model.expand(u, self.laws.load.value(t));
        self.pairs
            .iter()
            .map(|fp| self.model.position(&full, fp.node))
            .collect()
    }

    /// The w of the step's pairs, flat (2 i + a).
    pub fn gather_w(&self, w: &[[f64; 2]]) -> Vec<f64> {
        self.pairs.iter().flat_map(|fp| w[fp.pair]).collect()
    }

    /// Solves with the last factorization.
    pub fn solve(&self, rhs: &[f64], t: f64) -> Result<Vec<f64>> {
        let f = self.factor.as_ref().expect("linearize before solving");
        self.solves.set(self.solves.get() + 1);
        let x = f.solve(rhs);
        if x.iter().all(|v| v.is_finite()) {
            Ok(x)
        } else {
            Err(Error::SingularMatrix {
                step: 0,
                param: "t",
                at: t,
                detail: "the solve of the shell with friction gave non-finite values".into(),
            })
        }
    }

    /// The Taylor series of U and w at the linearized state, orders 0..=N.
    pub fn series(&mut self, s: &TimeState) -> Result<StepSeries> {
        let n = self.model.ndof();
        let np = self.pairs.len();
        let order = self.order;
        let lam = {
            let [l0, l1] = self.lambda(s.t);
            let mut v = vec![0.0; order + 1];
            v[0] = l0;
            if order >= 1 {
                v[1] = l1;
            }
            v
        };
        let [_, m1] = self.motion_factor(s.t);
        let mut us = vec![s.u.clone()];
        let mut ws = vec![
            (0..np)
                .flat_map(|i| s.w[self.pairs[i].pair])
                .collect::<Vec<f64>>(),
        ];
        // Full vectors of the orders (prescribed values at λ_k).
        let mut fulls = vec![self.model.expand(&s.u, lam[0])];
        for k in 1..=order {
            let mut rhs = vec![0.0; n + 2 * np];
            let sk = if k >= 2 {
                self.model.series_rhs(k, &us, &lam[..k])?
            } else {
                vec![0.0; n]
            };
            for i in 0..n {
                rhs[i] = -self.rl[i] * lam[k] - sk[i];
            }
            if k == 1 {
                // The own-ramp loads are linear within a step: order 1 only.
                for (ramp, f) in &self.laws.extra_loads {
                    let rate = ramp.rate(s.t);
                    for (r, fi) in rhs.iter_mut().zip(f) {
                        *r += rate * fi;
                    }
                }
            }
            for (i, fp) in self.pairs.iter_mut().enumerate() {
                for c in 0..5 {
                    fp.tape.set_input(c, k, 0.0);
                }
                fp.tape
                    .set_input(friction_pair::M, k, if k == 1 { m1 } else { 0.0 });
                fp.tape.propagate(k);
                let f = fp.out3(friction_pair::FORCE, k);
                for c in 0..3 {
                    rhs[self.node_dofs[i][c]] += f[c];
                }
                for (row, slot) in [friction_pair::T1, friction_pair::T2]
                    .into_iter()
                    .enumerate()
                {
                    let mut known = ws[k - 1][2 * i + row];
                    for j in 1..k {
                        let t = fp.out3(slot, j);
                        let xf = &fulls[k - j];
                        let x = Vector3::new(
                            xf[dof(fp.node, 0)],
                            xf[dof(fp.node, 1)],
                            xf[dof(fp.node, 2)],
                        );
                        known -= t.dot(&x) * (k - j) as f64;
                    }
                    rhs[n + 2 * i + row] = self.row_scale * known / k as f64;
                }
            }
            let z = self.solve(&rhs, s.t)?;
            let uk = z[..n].to_vec();
            let wk = z[n..].to_vec();
            let full_k = self.model.expand(&uk, lam[k]);
            for (i, fp) in self.pairs.iter_mut().enumerate() {
                for c in 0..3 {
                    fp.tape.set_input(c, k, full_k[dof(fp.node, c)]);
                }
                fp.tape.set_input(friction_pair::W, k, wk[2 * i]);
                fp.tape.set_input(friction_pair::W + 1, k, wk[2 * i + 1]);
                fp.tape.propagate(k);
            }
            us.push(uk);
            ws.push(wk);
            fulls.push(full_k);
        }
        Ok(StepSeries { u: us, w: ws })
    }

    /// Writes the w of the step's pairs from a flat per-step vector into
    /// the per-model-pair state.
    pub fn scatter_w(&self, flat: &[f64], w: &mut [[f64; 2]]) {
        for (i, fp) in self.pairs.iter().enumerate() {
            w[fp.pair] = [flat[2 * i], flat[2 * i + 1]];
        }
    }
}

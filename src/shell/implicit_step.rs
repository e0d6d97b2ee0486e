//! The implicit step of the shell with friction (issue 13 items 1 and 4,
//! issue 10): a RODAS4 step ([`crate::series::rodas`]) of the index-1 DAE
//! of [`super::friction_dae`], one factorization and 6 solves, L-stable.
//!
//! Why not the series: in full slip the regularized Coulomb law barely
//! depends on the slip speed (dR_T/dv_s ≈ f R_N (ω Vc)² / |v_s|³ along the
//! slip), so a node's tangential position relaxes against the membrane
//! stiffness with a time constant ∝ ω², and the explicit series' step is a
//! few of those time constants (docs/shell-friction.md). The two-point
//! Hermite–Obreshkov step that serves the point mass needs the consistent
//! state at the step end at given tangential positions, which in saturated
//! slip may not exist (the law caps |R_T| at f |R_N|): its Newton stalled.
//! A Rosenbrock step needs no nonlinear solve at all, only J at the step
//! start, and its L-stability damps the fast relaxation at any h.
//!
//! The DAE in the form M y' = f(t, y) with a constant M: y = (U, w, z), z
//! the tangential coordinates C(x) of the friction nodes
//! ([`super::chart`]):
//!
//!   0 = −E(U, w, t)        (equilibrium, n rows)
//!   0 = C(x(U)) − z        (2 per node)
//!   ż = D(x) w             (2 per node, M = I)
//!
//! whose algebraic part has the Jacobian of the series' augmented matrix
//! (index 1). Eliminating the z increment k_z = r_c + (dC/dx) S k_U of the
//! stage system (M/(h γ) − J) k = r leaves, on (U, w),
//!
//!   [K − ∂R_T/∂x                 −∂R_T/∂w ] [k_U]   [r_E                ]
//!   [(dC/dx − h γ ∂(D w)/∂x) S   −h γ D   ] [k_w] = [h γ r_z − r_c      ]
//!
//! (second block scaled by the kinematic row scale): the series' matrix
//! with h γ terms, so the step reuses its assembly.
//!
//! A Rosenbrock step linearizes the law once, at the step start. In
//! saturated slip at small ω and ζ that is not enough: its stages leave a
//! friction node off its slow manifold by an amount ∝ h, loaded several
//! times beyond its friction cap f |R_N|_reg, and the step collapses
//! (the conveying strip at ζ = ω = 1e-4 N: t = 3.1e-8 s on the coarse
//! mesh). Where trials keep failing, [`newton_trial`] takes the step as
//! backward Euler solved by Newton, re-linearized at every iterate: the
//! iterates may move those nodes along their obstacle as far as the
//! equilibrium needs (measured there: 4–30 iterations, the slipping
//! region growing by a node or two per iteration).
//!
//! The error estimate (k_6) is measured on the translations of the friction
//! nodes only, whose tangential parts are the differential unknowns (their
//! normal parts, on the stiff contact law, stay in the test: without them a
//! plate landing on a plane took a first step past the law's bend), much as
//! IDA suppresses its algebraic variables (IDASetSuppressAlg). The other
//! unknowns follow through the equilibrium, which the step loop checks at
//! the step end (solver.residual_tol):
//! - w is, in saturated slip, extremely sensitive to U, so an error test on
//!   it cannot pass at any step (the lesson of IDA on the point mass,
//!   README "Fair baselines");
//! - the translations of the nodes without friction (a free span of strip
//!   between rollers) sit on soft bending modes: the settle's residual
//!   tolerance alone moves them by more than the error test allows near
//!   t = 0, where the displacements are tiny, so a test on them rejects
//!   every step however short (measured on scenes/strip-conveying.toml:
//!   the step collapsed to 2e-13 s at t = 1.6e-7 s).

use super::friction_dae::{FrictionDae, TimeState};
use crate::error::Result;
use crate::series::rodas::{ERROR_ORDER, RODAS4, STAGES};

/// One attempted step.
pub struct Trial {
    pub end: TimeState,
    /// The largest error estimate of the friction nodes' translations (m).
    pub error: f64,
    /// A free dof of the node with the largest error.
    pub worst_dof: usize,
    /// The order in h of the error estimate (the step rule's exponent).
    pub error_order: f64,
}

/// Attempts a step of length h from s; the DAE must be prepared at s
/// ([`FrictionDae::prepare`]) and M/(h γ) − J factorized
/// ([`FrictionDae::factor_implicit`]). The error estimate covers the
/// translations of the friction nodes (module doc).
pub fn trial(dae: &mut FrictionDae, s: &TimeState, h: f64) -> Result<Trial> {
    let tab = &RODAS4;
    let n = s.u.len();
    let np = dae.n_pairs();
    let hg = h * tab.gamma;
    let rs = dae.row_scale();
    let e_t = dae.e_t().to_vec();
    let w0 = dae.gather_w(&s.w);
    let z0: Vec<f64> = (0..np).flat_map(|i| dae.chart(i).1.c).collect();
    let mut ku: Vec<Vec<f64>> = Vec::with_capacity(STAGES);
    let mut kw: Vec<Vec<f64>> = Vec::with_capacity(STAGES);
    let mut kz: Vec<Vec<f64>> = Vec::with_capacity(STAGES);
    for i in 0..STAGES {
        let ui = combine(&s.u, &ku, &tab.a[i]);
        let wi = combine(&w0, &kw, &tab.a[i]);
        let zi = combine(&z0, &kz, &tab.a[i]);
        let ti = s.t + tab.alpha[i] * h;
        let mut w_all = s.w.clone();
        dae.scatter_w(&wi, &mut w_all);
        let e = dae.residual(&TimeState {
            t: ti,
            u: ui.clone(),
            w: w_all,
        })?;
        let mut rhs = vec![0.0; n + 2 * np];
        for r in 0..n {
            rhs[r] = -e[r] - tab.gamma_i[i] * h * e_t[r];
        }
        let xs = dae.pair_positions(&ui, ti);
        let mut r_c = vec![0.0; 2 * np];
        for p in 0..np {
            let v = dae.chart(p).0.eval(&xs[p], [wi[2 * p], wi[2 * p + 1]]);
            for a in 0..2 {
                let q = 2 * p + a;
                r_c[q] = v.c[a] - zi[q];
                let r_z = v.d[a] * wi[q]
                    + kz.iter()
                        .zip(&tab.c[i])
                        .map(|(k, c)| c / h * k[q])
                        .sum::<f64>();
                rhs[n + q] = rs * (hg * r_z - r_c[q]);
            }
        }
        let sol = dae.solve(&rhs, ti)?;
        let mut kzi = r_c;
        for p in 0..np {
            let dofs = dae.pair_dofs(p);
            let start = dae.chart(p).1;
            for a in 0..2 {
                kzi[2 * p + a] += (0..3).map(|c| start.dc[a][c] * sol[dofs[c]]).sum::<f64>();
            }
        }
        ku.push(sol[..n].to_vec());
        kw.push(sol[n..].to_vec());
        kz.push(kzi);
    }
    let u1 = combine(&s.u, &ku, &tab.m);
    let w1 = combine(&w0, &kw, &tab.m);
    let err = combine(&vec![0.0; n], &ku, &tab.e);
    let (worst_dof, worst) = (0..np)
        .flat_map(|p| dae.pair_dofs(p))
        .fold((0, 0.0f64), |b, k| {
            if err[k].abs() > b.1 {
                (k, err[k].abs())
            } else {
                b
            }
        });
    let mut w = s.w.clone();
    dae.scatter_w(&w1, &mut w);
    Ok(Trial {
        end: TimeState {
            t: s.t + h,
            u: u1,
            w,
        },
        error: worst,
        worst_dof,
        error_order: ERROR_ORDER,
    })
}

/// base + Σ_j coef[j] k[j] over the stages computed so far.
fn combine(base: &[f64], k: &[Vec<f64>], coef: &[f64; STAGES]) -> Vec<f64> {
    let mut v = base.to_vec();
    for (kj, &c) in k.iter().zip(coef) {
        if c != 0.0 {
            for (vi, ki) in v.iter_mut().zip(kj) {
                *vi += c * ki;
            }
        }
    }
    v
}

/// Brings a step start back onto the equilibrium manifold: up to 3
/// Newton iterations with the step's matrix M/(h γ) − J (linearized at
/// the start), rhs [−E; 0], which relax the fast (stiff) components as the
/// DAE would over h γ and leave the slow ones in place. With
/// `relinearize = Some(h γ)`, up to 5 iterations re-linearized at the
/// current state instead (the DAE is left prepared and factorized there,
/// as the trial needs): the step loop's remedy when trials keep failing
/// from a start the first settle left off the manifold. Stops once the
/// relative residual is below `target` or stops falling; returns it.
pub fn settle(
    dae: &mut FrictionDae,
    end: &mut TimeState,
    target: f64,
    relinearize: Option<f64>,
) -> Result<f64> {
    let n = end.u.len();
    let np = dae.n_pairs();
    let scale = dae.force_scale().max(f64::MIN_POSITIVE);
    let mut r = dae.residual(end)?;
    let mut rel = crate::linalg::norm(&r) / scale;
    let iterations = if relinearize.is_some() { 5 } else { 3 };
    for _ in 0..iterations {
        if rel <= target {
            break;
        }
        if let Some(hg) = relinearize {
            // Newton proper, re-linearized at the current state (a node on
            // the bend of the law, where its slip is steep in the force,
            // stalls the iteration with the start's matrix).
            dae.prepare(end)?;
            dae.factor_implicit(hg, end.t)?;
        }
        let mut rhs = vec![0.0; n + 2 * np];
        for (b, e) in rhs.iter_mut().zip(&r) {
            *b = -e;
        }
        let d = dae.solve(&rhs, end.t)?;
        // Backtracking: the law is a sigmoid of the slip, on which a full
        // Newton step from a state near its bend overshoots.
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..8 {
            let next = dae.moved(end, &d, alpha);
            let r_next = dae.residual(&next)?;
            let rel_next = crate::linalg::norm(&r_next) / scale;
            if rel_next < rel {
                accepted = Some((next, r_next, rel_next));
                break;
            }
            alpha *= 0.5;
        }
        let Some((next, r_next, rel_next)) = accepted else {
            dae.residual(end)?;
            break;
        };
        *end = next;
        r = r_next;
        rel = rel_next;
    }
    Ok(rel)
}

/// Newton iterations of [`newton_trial`].
const NEWTON_ITERATIONS: usize = 30;

/// A fully implicit (backward Euler) step of length h from the consistent
/// state s, solved by damped Newton re-linearized at every iterate:
///
///   E(U_1, w_1, t + h) = 0,   C(x(U_1)) − z_0 − h D(x_1) w_1 = 0,
///
/// so that the step end satisfies the equilibrium to `tol` (relative to
/// the force scale) and the kinematics to `kin_tol` (m). The step loop's
/// fallback where the Rosenbrock stages keep failing: in saturated slip
/// they leave a friction node off its slow manifold by an amount ∝ h (a
/// force several times its friction cap; README, "Stiffness in time",
/// item 4), which Newton moves back.
///
/// Why one stage: a second, as in a two-stage SDIRK (Alexander's, order 2,
/// tried), starts from z_0 + (1 − γ)/γ (z_1 − z_0), 2.4 times the first
/// stage's relaxation, so the slip of every relaxing node reverses between
/// the stages and its Newton must cross the law's steep part at each of
/// them (measured: on scenes/strip-conveying.toml at ζ = ω = 1e-4 N its
/// second stage stalled at t = 4.05e-7 s, a node at 2.3 times its cap).
///
/// Error estimate (variable-step BDF1, as DASSL's): h / (h + h_prev) times
/// the distance of the end from the linear predictor through the previous
/// step's start `prev` = (U, h_prev), on the friction nodes' tangential
/// coordinates; without a previous step, half the step's increment.
/// None where Newton did not converge.
pub fn newton_trial(
    dae: &mut FrictionDae,
    s: &TimeState,
    h: f64,
    prev: Option<(&[f64], f64)>,
    tol: f64,
    kin_tol: f64,
) -> Result<Option<Trial>> {
    dae.prepare(s)?;
    let z0: Vec<f64> = (0..dae.n_pairs()).flat_map(|i| dae.chart(i).1.c).collect();
    let guess = TimeState {
        t: s.t + h,
        ..s.clone()
    };
    let Some(end) = newton_stage(dae, guess, &z0, h, tol, kin_tol)? else {
        return Ok(None);
    };
    let (weight, predictor): (f64, Vec<f64>) = match prev {
        Some((u_prev, h_prev)) if h_prev > 0.0 => (
            h / (h + h_prev),
            s.u.iter()
                .zip(u_prev)
                .map(|(a, b)| a + h / h_prev * (a - b))
                .collect(),
        ),
        _ => (0.5, s.u.clone()),
    };
    // On the tangential coordinates dC/dx·Δx, the differential unknowns:
    // a node's normal position is algebraic (the contact law), and its
    // distance from the predictor is the start's residual corrected, not a
    // truncation error (measured: with it, the sliding plate's steps
    // collapsed to 6e-17 s at its start).
    let (mut worst_dof, mut error) = (0, 0.0f64);
    for p in 0..dae.n_pairs() {
        let dofs = dae.pair_dofs(p);
        let dc = dae.chart(p).1.dc;
        for g in dc {
            let e = weight
                * (0..3)
                    .map(|c| g[c] * (end.u[dofs[c]] - predictor[dofs[c]]))
                    .sum::<f64>()
                    .abs();
            if e > error {
                (worst_dof, error) = (dofs[0], e);
            }
        }
    }
    Ok(Some(Trial {
        end,
        error,
        worst_dof,
        error_order: 2.0,
    }))
}

/// The Newton iteration of [`newton_trial`] from `y` (its time the step
/// end's) on E = 0, C(x) − ẑ − hg D w = 0: the converged state, or None.
fn newton_stage(
    dae: &mut FrictionDae,
    mut y: TimeState,
    zhat: &[f64],
    hg: f64,
    tol: f64,
    kin_tol: f64,
) -> Result<Option<TimeState>> {
    for _ in 0..NEWTON_ITERATIONS {
        let Ok(r) = stage_residual(dae, &y, zhat, hg) else {
            return Ok(None);
        };
        if r.converged(tol, kin_tol) {
            return Ok(Some(y));
        }
        if !dae.relinearize_in_charts(&y, hg)? {
            return Ok(None);
        }
        let rs = dae.row_scale();
        let rhs: Vec<f64> =
            r.e.iter()
                .map(|e| -e)
                .chain(r.kin.iter().map(|k| -rs * k))
                .collect();
        let d = dae.solve(&rhs, y.t)?;
        // Backtracking on |E|² + (row_scale |kinematics|)², along the
        // direction with its slips through the law's inverse first
        // ([`FrictionDae::law_space_direction`]), then along Newton's own.
        let merit = r.merit(rs);
        let law_space = dae.law_space_direction(&y, &d);
        let mut next = None;
        'directions: for dir in [&law_space, &d] {
            let mut alpha = 1.0;
            for _ in 0..20 {
                let trial = dae.moved(&y, dir, alpha);
                if let Ok(rt) = stage_residual(dae, &trial, zhat, hg)
                    && rt.merit(rs) < merit
                {
                    next = Some(trial);
                    break 'directions;
                }
                alpha *= 0.5;
            }
        }
        match next {
            Some(t) => y = t,
            None => return Ok(None),
        }
    }
    let r = stage_residual(dae, &y, zhat, hg)?;
    Ok(r.converged(tol, kin_tol).then_some(y))
}

/// The residuals of [`newton_trial`]'s equations at y.
struct StageResidual {
    e: Vec<f64>,
    kin: Vec<f64>,
    /// The force scale of the residual test.
    scale: f64,
}

impl StageResidual {
    fn converged(&self, tol: f64, kin_tol: f64) -> bool {
        crate::linalg::norm(&self.e) <= tol * self.scale
            && self.kin.iter().all(|k| k.abs() <= kin_tol)
    }

    fn merit(&self, rs: f64) -> f64 {
        self.e.iter().map(|e| e * e).sum::<f64>()
            + self.kin.iter().map(|k| (rs * k).powi(2)).sum::<f64>()
    }
}

fn stage_residual(
    dae: &mut FrictionDae,
    y: &TimeState,
    zhat: &[f64],
    hg: f64,
) -> Result<StageResidual> {
    let e = dae.residual(y)?;
    if !e.iter().all(|v| v.is_finite()) {
        return Err(crate::error::Error::NonFinite {
            step: 0,
            param: "t",
            at: y.t,
            what: "equilibrium residual of an implicit stage".into(),
        });
    }
    let xs = dae.pair_positions(&y.u, y.t);
    let pairs: Vec<usize> = dae.step_pairs().map(|(p, _)| p).collect();
    let mut kin = vec![0.0; 2 * dae.n_pairs()];
    for p in 0..dae.n_pairs() {
        let w = y.w[pairs[p]];
        let v = dae.chart(p).0.eval(&xs[p], w);
        for a in 0..2 {
            kin[2 * p + a] = v.c[a] - zhat[2 * p + a] - hg * v.d[a] * w[a];
        }
    }
    Ok(StageResidual {
        e,
        kin,
        scale: dae.force_scale().max(f64::MIN_POSITIVE),
    })
}

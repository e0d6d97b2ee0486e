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
use crate::series::rodas::{RODAS4, STAGES};

/// One attempted step.
pub struct Trial {
    pub end: TimeState,
    /// The largest error estimate of the friction nodes' translations (m).
    pub error: f64,
    /// A free dof of the node with the largest error.
    pub worst_dof: usize,
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

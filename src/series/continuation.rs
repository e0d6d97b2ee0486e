//! Arclength ANM continuation for R(U, lambda) = 0 (DESIGN §2; Cochelin,
//! Damil, Potier-Ferry, Rev. Eur. Eléments Finis 3 (1994) 281–297).
//!
//! U(a) = U0 + sum a^p U_p, lambda(a) = lambda0 + sum a^p lambda_p, with the
//! pseudo-arclength a = <U - U0, U1> + (lambda - lambda0) lambda1.
//!   order 1: Kt U1 + R_lambda lambda1 = 0, |U1|^2 + lambda1^2 = 1;
//!   order p: Kt U_p + R_lambda lambda_p + rhs_p = 0, <U_p, U1> + lambda_p lambda1 = 0,
//! where rhs_p is coefficient p of R along the series with U_p = lambda_p = 0.
//! One factorization of Kt per step: Ut = -Kt^-1 R_lambda once, then per order
//! Ub = -Kt^-1 rhs_p, lambda_p = -<Ub, U1> / (<Ut, U1> + lambda1), U_p = lambda_p Ut + Ub.

use super::geometric::{self, GeometricSeries};
use super::pade;
use super::stats::{Stats, charge};
use crate::error::{Error, Result};
use crate::linalg::{Factorization, SparseLu, SparseMatrix, dot, norm};
use std::time::Instant;

/// What a static problem supplies to the engine.
pub trait ContinuationProblem {
    fn ndof(&self) -> usize;
    /// R(U, lambda); zero on the equilibrium path.
    fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>>;
    /// Tangent dR/dU and dR/dlambda at (U, lambda). Called once at the start
    /// of every step, before the `series_rhs` calls of that step.
    fn tangent(&mut self, u: &[f64], lambda: f64) -> Result<(SparseMatrix, Vec<f64>)>;
    /// Coefficient p >= 2 of R(U(a), lambda(a)) with U_p = 0 and lambda_p = 0,
    /// given the complete `u[0..p]`, `lambda[0..p]` of the current step. Called
    /// for p = 2, 3, ... in order.
    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], lambda: &[f64]) -> Result<Vec<f64>>;
}

/// Numerical settings of a continuation run.
#[derive(Clone, Debug)]
pub struct ContinuationConfig {
    /// Truncation order N.
    pub order: usize,
    /// Tolerance eps of the step-length rule.
    pub eps: f64,
    /// Stop when lambda reaches this value.
    pub lambda_end: f64,
    pub max_steps: usize,
    /// Extend steps with Padé approximants.
    pub pade: bool,
    /// Relative residual |R| / |R_lambda| above which a Newton correction runs.
    pub residual_tol: f64,
    /// Run Newton corrections when the residual check fails (else stop with an error).
    pub correct: bool,
    pub max_corrections: usize,
    /// Smallest admissible step length before the run stops as collapsed.
    pub min_step: f64,
}

impl Default for ContinuationConfig {
    fn default() -> Self {
        Self {
            order: 15,
            eps: 1e-8,
            lambda_end: 1.0,
            max_steps: 10_000,
            pade: false,
            residual_tol: 1e-6,
            correct: true,
            max_corrections: 10,
            min_step: 1e-12,
        }
    }
}

/// One accepted step: the series and the length used.
#[derive(Clone, Debug)]
pub struct PathStep {
    pub index: usize,
    /// U_0..U_N.
    pub u: Vec<Vec<f64>>,
    /// lambda_0..lambda_N.
    pub lambda: Vec<f64>,
    /// Step length a actually taken.
    pub length: f64,
    /// Validity range of the polynomial series, a_max.
    pub a_poly: f64,
    /// Evaluate with Padé instead of the polynomial.
    pub pade: Option<pade::Pade>,
    /// Geometric series found in the last terms (Cochelin-Medale test).
    pub geometric: Option<GeometricSeries>,
    /// Relative residual at the step end, before any correction.
    pub end_residual: f64,
    /// End point after correction.
    pub u_end: Vec<f64>,
    pub lambda_end: f64,
}

impl PathStep {
    /// (U(a), lambda(a)) from the step's representation (polynomial or Padé).
    pub fn eval(&self, a: f64) -> (Vec<f64>, f64) {
        match &self.pade {
            Some(p) => {
                let terms = stack_terms(&self.u, &self.lambda);
                let inc = p.eval(&terms, a);
                let n = self.u[0].len();
                let u = self.u[0].iter().zip(&inc).map(|(x, d)| x + d).collect();
                (u, self.lambda[0] + inc[n])
            }
            None => {
                let n = self.u[0].len();
                let mut u = vec![0.0; n];
                for (i, ui) in u.iter_mut().enumerate() {
                    *ui = self.u.iter().rev().fold(0.0, |acc, t| acc * a + t[i]);
                }
                (u, super::taylor::eval(&self.lambda, a))
            }
        }
    }

    /// Path parameter a at which lambda(a) = target, if it lies in [0, length]
    /// (Newton on the series, started by bisection-safe bracketing).
    pub fn a_at_lambda(&self, target: f64) -> Option<f64> {
        // lambda alone where the representation allows (the polynomial):
        // bisection evaluates it 100 times.
        let f = |a: f64| match &self.pade {
            Some(_) => self.eval(a).1 - target,
            None => super::taylor::eval(&self.lambda, a) - target,
        };
        let (f0, f1) = (f(0.0), f(self.length));
        if f0 == 0.0 {
            return Some(0.0);
        }
        if f0.signum() == f1.signum() {
            return None;
        }
        let (mut lo, mut hi) = (0.0, self.length);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if f(mid).signum() == f0.signum() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }
}

fn stack_terms(u: &[Vec<f64>], lambda: &[f64]) -> Vec<Vec<f64>> {
    u.iter()
        .zip(lambda)
        .map(|(up, &lp)| {
            let mut t = up.clone();
            t.push(lp);
            t
        })
        .collect()
}

/// Result of a continuation run.
#[derive(Debug)]
pub struct PathResult {
    pub stats: Stats,
    /// Why the run stopped: "end", "max_steps", or an error kind.
    pub stop: String,
    pub error: Option<Error>,
    pub u_end: Vec<f64>,
    pub lambda_end: f64,
}

/// Follows the path from (u0, lambda0) toward `cfg.lambda_end`. `on_step` is
/// called with every accepted step (outputs, progress); returning an error
/// from it stops the run.
pub fn run<P: ContinuationProblem>(
    problem: &mut P,
    u0: Vec<f64>,
    lambda0: f64,
    cfg: &ContinuationConfig,
    mut on_step: impl FnMut(&PathStep, &Stats) -> Result<()>,
) -> PathResult {
    let mut stats = Stats::default();
    let mut u = u0;
    let mut lambda = lambda0;
    let mut prev_dir: Option<(Vec<f64>, f64)> = None;
    let forward = if cfg.lambda_end >= lambda0 { 1.0 } else { -1.0 };
    let mut lu = SparseLu::new();
    let finish =
        |stats: Stats, stop: &str, error: Option<Error>, u: Vec<f64>, lambda: f64| PathResult {
            stats,
            stop: error
                .as_ref()
                .map(|e| e.kind().to_string())
                .unwrap_or_else(|| stop.to_string()),
            error,
            u_end: u,
            lambda_end: lambda,
        };
    for index in 0..cfg.max_steps {
        let step = match series_step(
            problem, &u, lambda, index, cfg, &prev_dir, forward, &mut lu, &mut stats,
        ) {
            Ok(s) => s,
            Err(e) => return finish(stats, "", Some(e), u, lambda),
        };
        stats.steps += 1;
        u = step.u_end.clone();
        lambda = step.lambda_end;
        prev_dir = Some((step.u[1].clone(), step.lambda[1]));
        if let Err(e) = on_step(&step, &stats) {
            return finish(stats, "", Some(e), u, lambda);
        }
        if (lambda - cfg.lambda_end) * forward >= -1e-14 * cfg.lambda_end.abs().max(1.0) {
            return finish(stats, "end", None, u, lambda);
        }
    }
    finish(stats, "max_steps", None, u, lambda)
}

/// Factorizes a tangent, counting and timing it; a failure becomes a
/// singular-matrix error at (step, lambda).
pub(crate) fn factorize(
    lu: &mut SparseLu,
    k: &SparseMatrix,
    stats: &mut Stats,
    step: usize,
    lambda: f64,
) -> Result<Factorization> {
    let t = Instant::now();
    let f = lu.factorize(k).map_err(|detail| Error::SingularMatrix {
        step,
        param: "lambda",
        at: lambda,
        detail,
    })?;
    stats.factorizations += 1;
    charge(&mut stats.factorization_s, t);
    Ok(f)
}

#[allow(clippy::too_many_arguments)]
fn series_step<P: ContinuationProblem>(
    problem: &mut P,
    u0: &[f64],
    lambda0: f64,
    index: usize,
    cfg: &ContinuationConfig,
    prev_dir: &Option<(Vec<f64>, f64)>,
    forward: f64,
    lu: &mut SparseLu,
    stats: &mut Stats,
) -> Result<PathStep> {
    let n_ord = cfg.order;
    let t = Instant::now();
    let (kt, r_lambda) = problem.tangent(u0, lambda0)?;
    charge(&mut stats.assembly_s, t);
    let fact = factorize(lu, &kt, stats, index, lambda0)?;
    let solve = |b: &[f64], stats: &mut Stats, what: &str| -> Result<Vec<f64>> {
        let t = Instant::now();
        let neg: Vec<f64> = b.iter().map(|x| -x).collect();
        let x = Factorization::solve(&fact, &neg);
        stats.solves += 1;
        charge(&mut stats.solve_s, t);
        if x.iter().all(|v| v.is_finite()) {
            Ok(x)
        } else {
            Err(Error::SingularMatrix {
                step: index,
                param: "lambda",
                at: lambda0,
                detail: format!("non-finite solution of the {what} system"),
            })
        }
    };
    // Order 1: U1 = lambda1 Ut with |U1|^2 + lambda1^2 = 1; orientation follows
    // the previous step (or increasing |lambda - lambda0| toward the target).
    let ut = solve(&r_lambda, stats, "order-1")?;
    let mut l1 = 1.0 / (1.0 + dot(&ut, &ut)).sqrt();
    let orient = match prev_dir {
        Some((pu, pl)) => l1 * (dot(&ut, pu) + pl),
        None => l1 * forward,
    };
    if orient < 0.0 {
        l1 = -l1;
    }
    let mut us = vec![u0.to_vec(), ut.iter().map(|x| l1 * x).collect::<Vec<_>>()];
    let mut ls = vec![lambda0, l1];
    let denom = dot(&ut, &us[1]) + l1;
    for p in 2..=n_ord {
        let t = Instant::now();
        let rhs = problem.series_rhs(p, &us, &ls)?;
        stats.series_terms += 1;
        charge(&mut stats.series_s, t);
        let ub = solve(&rhs, stats, "order-p")?;
        let lp = -dot(&ub, &us[1]) / denom;
        us.push(ub.iter().zip(&ut).map(|(b, t)| b + lp * t).collect());
        ls.push(lp);
    }
    // Step length: ratio rule on the combined vector (U, lambda).
    let terms = stack_terms(&us, &ls);
    let n1 = norm(&terms[1]);
    let nn = norm(&terms[n_ord]);
    if !(n1.is_finite() && nn.is_finite()) {
        return Err(Error::NonFinite {
            step: index,
            param: "lambda",
            at: lambda0,
            what: format!("series terms (|U_1| = {n1:e}, |U_{n_ord}| = {nn:e})"),
        });
    }
    let cap = 1e15f64.powf(1.0 / n_ord as f64);
    let a_poly = if nn > 0.0 {
        (cfg.eps * n1 / nn)
            .powf(1.0 / (n_ord as f64 - 1.0))
            .min(cap)
    } else {
        cap
    };
    let geometric = geometric::detect(&terms);
    let mut step = PathStep {
        index,
        u: us,
        lambda: ls,
        length: a_poly,
        a_poly,
        pade: None,
        geometric,
        end_residual: 0.0,
        u_end: vec![],
        lambda_end: 0.0,
    };
    if cfg.pade
        && let Some(a) = pade::range(&terms, n_ord, cfg.eps, a_poly, cap.min(10.0 * a_poly))
        && a > a_poly
    {
        step.pade = pade::Pade::new(&terms, n_ord);
        step.length = a;
    }
    if step.length < cfg.min_step {
        return Err(Error::StepCollapse {
            step: index,
            param: "lambda",
            at: lambda0,
            length: step.length,
        });
    }
    // Do not overshoot the target load.
    let (_, l_end) = step.eval(step.length);
    if (l_end - cfg.lambda_end) * forward > 0.0
        && let Some(a) = step.a_at_lambda(cfg.lambda_end)
    {
        step.length = a;
    }
    // Step end: accept when the residual is small; correct when it is
    // moderately large; otherwise (or when the correction fails) the step
    // length overestimated the series' validity (e.g. a contact node closing
    // within the step): halve it. Halving costs residual evaluations only;
    // correcting from far off the path can converge onto another branch.
    let scale = norm(&r_lambda).max(f64::MIN_POSITIVE);
    let mut first = true;
    loop {
        let (u_end, mut l_end) = step.eval(step.length);
        if (l_end - cfg.lambda_end) * forward > 0.0 && (l_end - cfg.lambda_end).abs() < 1e-9 {
            l_end = cfg.lambda_end;
        }
        let attempt = end_point(
            problem, &step, &fact, &ut, denom, u_end, l_end, scale, cfg, lu, stats,
        );
        if first {
            step.end_residual = attempt.as_ref().map_or(f64::INFINITY, |e| e.residual);
            first = false;
        }
        match attempt {
            Ok(end) if end.u.iter().all(|x| x.is_finite()) && end.lambda.is_finite() => {
                step.u_end = end.u;
                step.lambda_end = end.lambda;
                return Ok(step);
            }
            Ok(_) => {}
            Err(e) if e.is_numerical() => {
                if step.length * 0.5 < cfg.min_step || !cfg.correct {
                    return Err(e);
                }
            }
            Err(e) => return Err(e),
        }
        // Padé first falls back to the polynomial, then the length halves.
        if step.pade.is_some() {
            step.pade = None;
            step.length = step.length.min(step.a_poly);
        } else {
            step.length *= 0.5;
        }
        stats.step_cuts += 1;
        if step.length < cfg.min_step {
            return Err(Error::StepCollapse {
                step: index,
                param: "lambda",
                at: lambda0,
                length: step.length,
            });
        }
    }
}

/// A step's corrected end point.
struct EndPoint {
    u: Vec<f64>,
    lambda: f64,
    /// Relative residual before correction.
    residual: f64,
}

/// Residual check at (u_end, l_end), then arclength-constrained Newton
/// corrections <dU, U1> + dl l1 = 0: modified Newton with the step's
/// factorization while it contracts by 10x per iteration, else refactorized
/// at the current point (full Newton). A start residual above
/// [`CORRECTABLE`] is not corrected (`NoConvergence` with 0 iterations).
#[allow(clippy::too_many_arguments)]
fn end_point<P: ContinuationProblem>(
    problem: &mut P,
    step: &PathStep,
    fact: &Factorization,
    ut: &[f64],
    denom: f64,
    mut u_end: Vec<f64>,
    mut l_end: f64,
    scale: f64,
    cfg: &ContinuationConfig,
    lu: &mut SparseLu,
    stats: &mut Stats,
) -> Result<EndPoint> {
    let index = step.index;
    let t = Instant::now();
    let mut r = problem.residual(&u_end, l_end)?;
    stats.residual_evaluations += 1;
    charge(&mut stats.assembly_s, t);
    let mut res = norm(&r) / scale;
    let start = res;
    let mut it = 0;
    let mut current: Option<(Factorization, Vec<f64>, f64)> = None;
    while res > cfg.residual_tol || !res.is_finite() {
        if !cfg.correct || it >= cfg.max_corrections || !(res <= CORRECTABLE) {
            return Err(Error::NoConvergence {
                step: index,
                param: "lambda",
                at: l_end,
                iterations: it,
                residual: res,
                tolerance: cfg.residual_tol,
            });
        }
        let t = Instant::now();
        let neg: Vec<f64> = r.iter().map(|x| -x).collect();
        let (f, ut_c, den): (&Factorization, &[f64], f64) = match &current {
            None => (fact, ut, denom),
            Some((f, ut_c, den)) => (f, ut_c, *den),
        };
        let ub = f.solve(&neg);
        stats.solves += 1;
        charge(&mut stats.solve_s, t);
        let dl = -dot(&ub, &step.u[1]) / den;
        for ((x, b), t) in u_end.iter_mut().zip(&ub).zip(ut_c) {
            *x += b + dl * t;
        }
        l_end += dl;
        let t = Instant::now();
        r = problem.residual(&u_end, l_end)?;
        stats.residual_evaluations += 1;
        charge(&mut stats.assembly_s, t);
        let new_res = norm(&r) / scale;
        it += 1;
        stats.corrections += 1;
        if new_res > 0.1 * res && new_res > cfg.residual_tol {
            let t = Instant::now();
            let (k, rl) = problem.tangent(&u_end, l_end)?;
            charge(&mut stats.assembly_s, t);
            let f = factorize(lu, &k, stats, index, l_end)?;
            let t = Instant::now();
            let ut_c: Vec<f64> = f.solve(&rl.iter().map(|x| -x).collect::<Vec<_>>());
            stats.solves += 1;
            charge(&mut stats.solve_s, t);
            let den = dot(&ut_c, &step.u[1]) + step.lambda[1];
            current = Some((f, ut_c, den));
        }
        res = new_res;
    }
    Ok(EndPoint {
        u: u_end,
        lambda: l_end,
        residual: start,
    })
}

/// Relative residual |R| / |R_lambda| above which a step end is not corrected
/// but the step shortened: a point this far off the path is outside the
/// series' validity, and Newton from it may land on another branch.
const CORRECTABLE: f64 = 1.0;

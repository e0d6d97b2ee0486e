//! Newton-Raphson path following, the baseline the ANM is compared with
//! (Abaqus-style incremental-iterative stepping; Crisfield, *Non-linear Finite
//! Element Analysis of Solids and Structures*, vol. 1, 1991, §9.3).
//!
//! It uses the problem's own residual, tangent and linear solver (the same
//! [`ContinuationProblem`] as the ANM), so a comparison measures the method,
//! not the implementation. Each step: predictor along the last secant (the
//! tangent on the first step), then full Newton corrections, each with a fresh
//! tangent and factorization (optionally backtracked on |R|:
//! `NewtonConfig::line_search`), on
//!   load control:      R(U, lambda) = 0 with lambda fixed,
//!   arclength control: R(U, lambda) = 0 and <U - U_p, t_U> + (lambda - lambda_p) t_l = 0
//! (a hyperplane through the predictor, orthogonal to the prediction).
//! The increment grows after fast convergence and is halved on failure. Steps
//! are cut so that every requested lambda in `targets` is hit exactly.
//!
//! Lengths are those of the ANM ([`super::correct::Metric`]): the arclength
//! increment, the unit tangent and secant, and the hyperplane are measured in
//! u_i / s_i ([`ContinuationProblem::unknown_scale`]) and
//! lambda / `lambda_scale`, so that `initial_step`, `max_step` and `min_step`
//! (arclength control) do not depend on the problem's units. The corrections
//! are those of [`super::correct::correct`] in its full-Newton mode.

use super::continuation::{ContinuationProblem, PathResult, factorize};
use super::correct::{self, Constraint, Jacobian, Metric, Settings};
use super::stats::{Stats, charge};
use super::stop::Stop;
use crate::error::{Error, Result};
use crate::linalg::{Choice, LinearSolver};
use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    Load,
    Arclength,
}

#[derive(Clone, Debug)]
pub struct NewtonConfig {
    pub control: Control,
    /// First increment: of lambda (load control) or of the arclength.
    pub initial_step: f64,
    pub max_step: f64,
    pub min_step: f64,
    /// Converged when |R| / |R_lambda| <= tol.
    pub tol: f64,
    pub max_iterations: usize,
    /// Iterations at or below which the increment grows by 1.5.
    pub easy_iterations: usize,
    pub lambda_end: f64,
    pub max_steps: usize,
    /// Characteristic range Lambda of lambda in the arclength (as
    /// `ContinuationConfig::lambda_scale`); default 1.
    pub lambda_scale: f64,
    /// Linear-solver backend (as `ContinuationConfig::linear`).
    pub linear: Choice,
    /// Backtracking on |R| after each correction
    /// ([`super::correct::Settings::line_search`]).
    pub line_search: bool,
}

impl Default for NewtonConfig {
    fn default() -> Self {
        Self {
            control: Control::Arclength,
            initial_step: 0.05,
            max_step: 1.0,
            min_step: 1e-10,
            tol: 1e-8,
            max_iterations: 12,
            easy_iterations: 4,
            lambda_end: 1.0,
            max_steps: 100_000,
            lambda_scale: 1.0,
            linear: Choice::Auto,
            line_search: false,
        }
    }
}

/// How a Newton run ended: the same record as an ANM run.
pub type NewtonResult = PathResult;

/// Follows the path from (u0, lambda0) to `cfg.lambda_end`; `on_point` gets
/// every converged point (U, lambda), including each of `targets` exactly.
pub fn run<P: ContinuationProblem>(
    problem: &mut P,
    u0: Vec<f64>,
    lambda0: f64,
    cfg: &NewtonConfig,
    targets: &[f64],
    mut on_point: impl FnMut(&[f64], f64, &Stats) -> Result<()>,
) -> NewtonResult {
    let mut stats = Stats::default();
    let mut lu = LinearSolver::new(cfg.linear);
    let metric = match Metric::for_problem(&*problem, cfg.lambda_scale) {
        Ok(m) => m,
        Err(e) => {
            return NewtonResult {
                stats,
                stop: Stop::Failed(e),
                u_end: u0,
                lambda_end: lambda0,
            };
        }
    };
    let mut u = u0;
    let mut lambda = lambda0;
    let forward = if cfg.lambda_end >= lambda0 { 1.0 } else { -1.0 };
    let mut step = cfg.initial_step;
    // Direction of the last increment (secant), unit in (U, lambda).
    let mut dir: Option<(Vec<f64>, f64)> = None;
    let mut pending: Vec<f64> = targets
        .iter()
        .copied()
        .filter(|t| (t - lambda0) * forward > 0.0)
        .collect();
    pending.sort_by(|a, b| (a * forward).total_cmp(&(b * forward)));
    if !pending
        .iter()
        .any(|t| (t - cfg.lambda_end).abs() <= 1e-14 * cfg.lambda_end.abs().max(1.0))
    {
        pending.push(cfg.lambda_end);
    }
    let done = |stats: Stats, stop: Stop, u: Vec<f64>, l: f64| NewtonResult {
        stop,
        stats,
        u_end: u,
        lambda_end: l,
    };
    // Attempts, accepted or halved; errors name the step by the accepted
    // steps before it (as the ANM path and summary.json's `steps` count).
    // The last correction that failed numerically since the last accepted
    // increment.
    let mut last_failure: Option<Error> = None;
    for _attempt in 0..cfg.max_steps {
        if pending.is_empty() {
            return done(stats, Stop::End { lambda }, u, lambda);
        }
        let index = stats.steps;
        // Predictor direction: previous secant, or the tangent at the start.
        let (du, dl) = match &dir {
            Some(d) => d.clone(),
            None => {
                match tangent_direction(
                    problem, &u, lambda, forward, &metric, &mut lu, &mut stats, index,
                ) {
                    Ok(d) => d,
                    Err(e) => return done(stats, Stop::Failed(e), u, lambda),
                }
            }
        };
        // Predicted point; land on the next target by load control when it would be passed.
        let next = pending[0];
        let mut control = cfg.control;
        let (mut up, mut lp) = match control {
            Control::Load => {
                let dlam = forward * step;
                let lp = lambda + dlam;
                let scale = if dl.abs() > 1e-300 { dlam / dl } else { 0.0 };
                (
                    u.iter()
                        .zip(&du)
                        .map(|(x, d)| x + scale * d)
                        .collect::<Vec<_>>(),
                    lp,
                )
            }
            Control::Arclength => (
                u.iter()
                    .zip(&du)
                    .map(|(x, d)| x + step * d)
                    .collect::<Vec<_>>(),
                lambda + step * dl,
            ),
        };
        // A predictor or corrector within round-off of the next target has
        // reached it (else that target would be met again by the next
        // increment, and reported twice).
        let snap = 1e-12 * cfg.lambda_scale.max(next.abs());
        let mut hit_target = false;
        if (lp - next) * forward >= -snap {
            let frac = if (lp - lambda).abs() > 0.0 {
                (next - lambda) / (lp - lambda)
            } else {
                1.0
            };
            up = u.iter().zip(&up).map(|(a, b)| a + frac * (b - a)).collect();
            lp = next;
            control = Control::Load;
            hit_target = true;
        }
        let converged = match correct(
            problem, &up, lp, control, &du, dl, cfg, &metric, &mut lu, &mut stats, index,
        ) {
            // A corrector that converged onto the path behind us (the
            // increment turns back on the predictor direction) has lost the
            // path: it is retried with half the increment, like a failure.
            Ok((un, ln, _))
                if control == Control::Arclength
                    && turns_back(&un, ln, &u, lambda, &du, dl, &metric) =>
            {
                None
            }
            // One whose chord is longer than the largest increment allowed
            // (by more than JUMP) converged far from its predictor within
            // the hyperplane: it has left the path for another branch
            // (review 16: a cylindrical panel's increment of 1.2 for at
            // most 1.0 went from lambda = 0.25 to −0.58, and the run ended
            // on the other branch at lambda = 1, 31 % off, with exit 0). It
            // is retried with half the increment. (Against the increment
            // itself rather than its cap the test also refused the clamped
            // arch's pass of its fold, a chord of 1.72 increments, and
            // corrections within a loose tolerance's band at tiny steps.)
            Ok((un, ln, _))
                if control == Control::Arclength
                    && chord(&un, ln, &u, lambda, &metric) > JUMP * cfg.max_step =>
            {
                None
            }
            Ok(point) => Some(point),
            Err(e) if e.is_numerical() => {
                last_failure = Some(e);
                None
            }
            Err(e) => return done(stats, Stop::Failed(e), u, lambda),
        };
        // An arclength corrector may pass the next target: that target is
        // then solved for by load control from the interpolated point, so
        // that no output is skipped.
        let converged = match converged {
            Some((un, ln, iterations)) if !hit_target && (ln - next) * forward > -snap => {
                let frac = (next - lambda) / (ln - lambda);
                let start: Vec<f64> = u.iter().zip(&un).map(|(a, b)| a + frac * (b - a)).collect();
                hit_target = true;
                match correct(
                    problem,
                    &start,
                    next,
                    Control::Load,
                    &du,
                    dl,
                    cfg,
                    &metric,
                    &mut lu,
                    &mut stats,
                    index,
                ) {
                    Ok((ut, lt, it)) => Some((ut, lt, iterations + it)),
                    Err(e) if e.is_numerical() => {
                        last_failure = Some(e);
                        None
                    }
                    Err(e) => return done(stats, Stop::Failed(e), u, lambda),
                }
            }
            other => other,
        };
        match converged {
            Some((un, ln, iterations)) => {
                // Unit secant in the scaled metric: |inc|~^2 + (dln / Lambda)^2 = 1.
                let inc: Vec<f64> = un.iter().zip(&u).map(|(a, b)| a - b).collect();
                let dln = ln - lambda;
                let dls = metric.l(dln);
                let len = (metric.dot_u(&inc, &inc) + dls * dls).sqrt();
                stats.steps += 1;
                if len > 0.0 {
                    dir = Some((inc.iter().map(|x| x / len).collect(), dln / len));
                }
                u = un;
                lambda = ln;
                last_failure = None;
                if hit_target {
                    pending.remove(0);
                }
                if let Err(e) = on_point(&u, lambda, &stats) {
                    return done(stats, Stop::Failed(e), u, lambda);
                }
                if iterations <= cfg.easy_iterations && !hit_target {
                    step = (1.5 * step).min(cfg.max_step);
                }
            }
            None => step *= 0.5,
        }
        if step < cfg.min_step {
            // The last failed correction says why (review 16: "step length
            // collapsed" 11–16 % below the arch's limit point, where the
            // corrections stalled at 4.8e-9 against a tolerance of 1e-9).
            let collapse = last_failure.take().unwrap_or(Error::StepCollapse {
                step: index,
                param: "lambda",
                at: lambda,
                length: step,
            });
            return done(stats, Stop::Failed(collapse), u, lambda);
        }
    }
    let steps = cfg.max_steps;
    done(stats, Stop::MaxSteps { steps, lambda }, u, lambda)
}

/// Largest ratio of a converged arclength increment's chord to the largest
/// increment allowed (`NewtonConfig::max_step`).
const JUMP: f64 = 1.1;

/// The chord from (u, lambda) to (un, ln) in the scaled metric.
fn chord(un: &[f64], ln: f64, u: &[f64], lambda: f64, metric: &Metric) -> f64 {
    let inc: Vec<f64> = un.iter().zip(u).map(|(a, b)| a - b).collect();
    let dls = metric.l(ln - lambda);
    (metric.dot_u(&inc, &inc) + dls * dls).sqrt()
}

/// Whether the increment from (u, lambda) to (un, ln) points against the
/// predictor direction (du, dl): <un - u, du>~ + (ln - lambda) dl / Lambda^2 < 0.
fn turns_back(
    un: &[f64],
    ln: f64,
    u: &[f64],
    lambda: f64,
    du: &[f64],
    dl: f64,
    metric: &Metric,
) -> bool {
    let inc: Vec<f64> = un.iter().zip(u).map(|(a, b)| a - b).collect();
    let along = metric.dot_u(&inc, du);
    along + (ln - lambda) * dl * metric.lambda_weight() < 0.0
}

/// Unit tangent (U1, lambda1) at a point, |Ũ1|^2 + λ̃1^2 = 1: Kt Ut = -R_lambda,
/// λ̃1 = ±1 / sqrt(1 + Lambda^2 |Ut|~^2), lambda1 = Lambda λ̃1, U1 = lambda1 Ut,
/// oriented forward.
#[allow(clippy::too_many_arguments)]
fn tangent_direction<P: ContinuationProblem>(
    problem: &mut P,
    u: &[f64],
    lambda: f64,
    forward: f64,
    metric: &Metric,
    lu: &mut LinearSolver,
    stats: &mut Stats,
    index: usize,
) -> Result<(Vec<f64>, f64)> {
    let t = Instant::now();
    let (k, rl) = problem.tangent(u, lambda)?;
    charge(&mut stats.assembly_s, t);
    let f = factorize(lu, &k, stats, index, lambda)?;
    let t = Instant::now();
    let ut = f.solve(&rl.iter().map(|x| -x).collect::<Vec<_>>());
    stats.solves += 1;
    charge(&mut stats.solve_s, t);
    let big_l = metric.lambda_scale();
    let l1 = big_l * forward / (1.0 + metric.dot_u(&ut, &ut) * (big_l * big_l)).sqrt();
    Ok((ut.iter().map(|x| x * l1).collect(), l1))
}

/// Full Newton from the predictor (load control: lambda fixed; arclength:
/// on the hyperplane through the predictor orthogonal to (du, dl)), by
/// [`correct::correct`]; returns the converged point and the iterations used.
#[allow(clippy::too_many_arguments)]
fn correct<P: ContinuationProblem>(
    problem: &mut P,
    up: &[f64],
    lp: f64,
    control: Control,
    du: &[f64],
    dl: f64,
    cfg: &NewtonConfig,
    metric: &Metric,
    lu: &mut LinearSolver,
    stats: &mut Stats,
    index: usize,
) -> Result<(Vec<f64>, f64, usize)> {
    let constraint = match control {
        Control::Load => Constraint::FixedLambda,
        Control::Arclength => Constraint::Arclength {
            t_u: du,
            t_lambda: dl,
            reference: Some((up, lp)),
        },
    };
    let settings = Settings {
        tol: cfg.tol,
        max_iter: cfg.max_iterations,
        jacobian: Jacobian::Fresh,
        max_residual: f64::INFINITY,
        line_search: cfg.line_search,
        step: index,
    };
    let c = correct::correct(
        problem,
        up.to_vec(),
        lp,
        &constraint,
        &settings,
        metric,
        lu,
        stats,
    )?;
    Ok((c.u, c.lambda, c.iterations))
}

//! Events: narrow switches of a problem's behaviour that a step crosses by a
//! corrected jump instead of a train of short series steps.
//!
//! A problem names its events by scalar functions g_k(U, lambda)
//! ([`ContinuationProblem::events`]), scaled so that its behaviour switches
//! at g_k = 0 within a band |g_k| of order 1 (the regularized contact law of
//! paper eq. 3 in the dimensionless gap g = h / w, w = sqrt(eta delta / K):
//! its reaction r = R / (K w) solves r (r + g) = 1, whose branch points
//! g = ±2i sit at the switch). Near a switch the series of every unknown has
//! a radius of convergence of about the distance to it, |a_e - a|: steps
//! shrink geometrically toward the switch and grow back geometrically after
//! it (10 to 15 steps per contact event on plate-cylinder, README).
//!
//! The crossing (one step):
//! ```text
//! 1. locate: g_k(U(a), lambda(a)) on the step's own representation over
//!    [0, a_s] (a_s the step length of the step rules), continued beyond a_s
//!    by the tangent of the series at a_s up to HORIZON a_s; the event is the
//!    earliest a_e where a g_k that starts outside its band (|g_k| >= BAND)
//!    changes sign or enters |g_k| <= 1 (bisection).
//! 2. predict: from a_b = min(a_e, a_s), along the series' tangent t = U'(a_b):
//!    P = (U, lambda)(a_b) + (a_e + D - a_b) t, D = max(a_e, L_prev) past the
//!    switch (L_prev: the previous step's length, the path's scale where it
//!    is smooth), so that the next series starts at a distance of a
//!    smooth step's length from the switch instead of in its corner.
//! 3. correct: Newton on R = 0 with <U - P_U, t_U>~ + (lambda - P_lambda)
//!    t_lambda / Lambda^2 = 0 (super::correct), its tangent refactorized
//!    whenever an iteration contracts less than 10x; a failure halves D
//!    (JUMP_TRIES times), then the ordinary step is taken instead.
//! 4. the accepted step is the chord from the start to the corrected point
//!    (a first-order "series"), on which output grid points are corrected
//!    at their load like those of any step.
//! ```
//! Why it is off by default (`ContinuationConfig::events`; figures in the
//! README, "plate-cylinder: ANM against Newton-Raphson"): it pays where one
//! switch is crossed and Newton converges quadratically from the predictor
//! (one unknown against the law of eq. 3: 1 step instead of 30), but on a
//! shell many contact nodes rest inside their band, where Newton from a
//! predictor farther than the band width w from the solution converges
//! slowly; on plate-cylinder most jumps fail and cost more factorizations
//! than the short steps they replace.
//! A step whose end would pass `lambda_end` lands on it at fixed load.

use super::continuation::{ContinuationConfig, ContinuationProblem, PathStep};
use super::correct::{self, Constraint, Jacobian, Metric, Settings};
use super::stats::Stats;
use crate::error::Result;
use crate::linalg::LinearSolver;

/// Look-ahead of the event search, in step lengths a_s.
pub const HORIZON: f64 = 4.0;
/// An event function counts only from a start outside its band, |g| >=
/// BAND: one that starts inside stays near its switch (a contact node
/// resting on the obstacle with a small reaction), which the series
/// follows, and Newton from across its corner converges poorly.
pub const BAND: f64 = 10.0;
/// Samples of the event functions over [0, a_s].
const SAMPLES: usize = 16;
/// Predictions tried (D halved after each failure).
const JUMP_TRIES: usize = 2;

/// The earliest sign change of an event function on a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Index k of the event function.
    pub event: usize,
    /// Path parameter a_e of the switch (scaled arclength of the step).
    pub a: f64,
}

/// The state of a step at `a` and its derivative there: on the step's
/// representation for a <= `length`, on its tangent at `length` beyond.
fn state(step: &PathStep, a: f64) -> (Vec<f64>, f64) {
    if a <= step.length {
        return step.eval(a);
    }
    let (u, l) = step.eval(step.length);
    let (du, dl) = derivative(step, step.length);
    let s = a - step.length;
    (
        u.iter().zip(&du).map(|(x, d)| x + s * d).collect(),
        l + s * dl,
    )
}

/// d(U, lambda)/da of the step's representation at a (central difference
/// inside the step, one-sided at its ends).
fn derivative(step: &PathStep, a: f64) -> (Vec<f64>, f64) {
    let h = 1e-4 * step.length.max(f64::MIN_POSITIVE);
    let (lo, hi) = ((a - h).max(0.0), (a + h).min(step.length));
    let (u0, l0) = step.eval(lo);
    let (u1, l1) = step.eval(hi);
    let d = hi - lo;
    (
        u1.iter().zip(&u0).map(|(b, a)| (b - a) / d).collect(),
        (l1 - l0) / d,
    )
}

/// The earliest switch of an event function of `problem` on `step` within
/// [0, HORIZON step.length] (module docs, item 1).
pub fn locate<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
) -> Result<Option<Crossing>> {
    let g0 = problem.events(&step.u[0], step.lambda[0])?;
    if g0.is_empty() {
        return Ok(None);
    }
    let at = |problem: &mut P, a: f64| -> Result<Vec<f64>> {
        let (u, l) = state(step, a);
        problem.events(&u, l)
    };
    // Entering the band from outside it: a sign change, or |g| <= 1.
    let changed = |x: f64, y: f64| {
        x.is_finite() && y.is_finite() && ((x > 0.0) != (y > 0.0) || y.abs() <= 1.0)
    };
    let mut a0 = 0.0;
    let mut prev = g0.clone();
    let ends: Vec<f64> = (1..=SAMPLES)
        .map(|i| step.length * i as f64 / SAMPLES as f64)
        .chain([HORIZON * step.length])
        .collect();
    for a1 in ends {
        let next = at(problem, a1)?;
        if next.len() != prev.len() {
            return Ok(None);
        }
        // The earliest switch among those changing sign in [a0, a1].
        let mut best: Option<Crossing> = None;
        for k in (0..next.len()).filter(|&k| g0[k].abs() >= BAND && changed(prev[k], next[k])) {
            let (mut lo, mut hi) = (a0, a1);
            let sign = prev[k] > 0.0;
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                let g = at(problem, mid)?[k];
                if (g > 0.0) == sign && g.abs() > 1.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let a = 0.5 * (lo + hi);
            if best.is_none_or(|b| a < b.a) {
                best = Some(Crossing { event: k, a });
            }
        }
        if best.is_some() {
            return Ok(best);
        }
        a0 = a1;
        prev = next;
    }
    Ok(None)
}

/// The jump across `crossing` from the start of `step` (module docs, items
/// 2-4), or `None` when no prediction converged.
#[allow(clippy::too_many_arguments)]
pub fn jump<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
    crossing: Crossing,
    prev_length: Option<f64>,
    cfg: &ContinuationConfig,
    metric: &Metric,
    scale: f64,
    lu: &mut LinearSolver,
    stats: &mut Stats,
) -> Result<Option<PathStep>> {
    let forward = if cfg.lambda_end >= step.lambda[0] {
        1.0
    } else {
        -1.0
    };
    let a_b = crossing.a.min(step.length);
    let (u_b, l_b) = state(step, a_b);
    let (t_u, t_l) = derivative(step, a_b);
    let mut past = crossing.a.max(prev_length.unwrap_or(0.0));
    for _ in 0..JUMP_TRIES {
        let s = crossing.a + past - a_b;
        let mut p_u: Vec<f64> = u_b.iter().zip(&t_u).map(|(x, d)| x + s * d).collect();
        let mut p_l = l_b + s * t_l;
        // Land on lambda_end at fixed load rather than pass it.
        let at_end = (p_l - cfg.lambda_end) * forward > 0.0;
        if at_end {
            if (l_b - cfg.lambda_end) * forward >= 0.0 || t_l * forward <= 0.0 {
                return Ok(None);
            }
            let s = (cfg.lambda_end - l_b) / t_l;
            p_u = u_b.iter().zip(&t_u).map(|(x, d)| x + s * d).collect();
            p_l = cfg.lambda_end;
        }
        let settings = Settings {
            tol: cfg.residual_tol,
            max_iter: cfg.max_corrections,
            jacobian: Jacobian::Reuse {
                initial: None,
                contraction: 0.1,
                scale,
            },
            max_residual: f64::INFINITY,
            line_search: false,
            step: step.index,
        };
        let constraint = if at_end {
            Constraint::FixedLambda
        } else {
            Constraint::Arclength {
                t_u: &t_u,
                t_lambda: t_l,
                reference: Some((&p_u, p_l)),
            }
        };
        match correct::correct(
            problem,
            p_u.clone(),
            p_l,
            &constraint,
            &settings,
            metric,
            lu,
            stats,
        ) {
            Ok(end)
                if end.u.iter().all(|x| x.is_finite())
                    && end.lambda.is_finite()
                    && (end.lambda - step.lambda[0]) * forward > 0.0 =>
            {
                let mut c = chord(step, end.u, end.lambda, end.start_residual, metric);
                c.jump = Some(crossing);
                return Ok(Some(c));
            }
            Ok(_) => {}
            Err(e) if e.is_numerical() => {}
            Err(e) => return Err(e),
        }
        past *= 0.5;
    }
    Ok(None)
}

/// The step from the start of `step` to (u, lambda) as a straight chord in
/// its scaled arclength: U(a) = U_0 + a (u - U_0) / L, L the chord's scaled
/// length.
fn chord(
    step: &PathStep,
    u: Vec<f64>,
    lambda: f64,
    start_residual: f64,
    metric: &Metric,
) -> PathStep {
    let du: Vec<f64> = u.iter().zip(&step.u[0]).map(|(a, b)| a - b).collect();
    let dl = lambda - step.lambda[0];
    let len = (metric.dot_u(&du, &du) + dl * dl * metric.lambda_weight()).sqrt();
    PathStep {
        index: step.index,
        u: vec![step.u[0].clone(), du.iter().map(|d| d / len).collect()],
        lambda: vec![step.lambda[0], dl / len],
        length: len,
        a_poly: len,
        pade: None,
        geometric: None,
        singular_mode: vec![],
        end_residual: start_residual,
        u_end: u,
        lambda_end: lambda,
        negative_pivots: step.negative_pivots,
        jump: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// g(a) = 100 (1 - 2a) along a linear step of length 1 enters its band
    /// |g| <= 1 at a = 0.495, found inside the step; with the step 0.25 long
    /// it is found on the tangent beyond the step end, within HORIZON step
    /// lengths. g = 5 - 10a starts inside the band and is not an event.
    struct Line;
    impl ContinuationProblem for Line {
        fn ndof(&self) -> usize {
            1
        }
        fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
            Ok(vec![u[0] - lambda])
        }
        fn tangent(
            &mut self,
            _u: &[f64],
            _lambda: f64,
        ) -> Result<(crate::linalg::SparseMatrix, Vec<f64>)> {
            unreachable!()
        }
        fn series_rhs(&mut self, _p: usize, _u: &[Vec<f64>], _l: &[f64]) -> Result<Vec<f64>> {
            unreachable!()
        }
        fn events(&self, u: &[f64], _lambda: f64) -> Result<Vec<f64>> {
            Ok(vec![5.0 - 10.0 * u[0], 100.0 * (1.0 - 2.0 * u[0])])
        }
    }

    fn line(length: f64) -> PathStep {
        PathStep {
            index: 0,
            u: vec![vec![0.0], vec![1.0]],
            lambda: vec![0.0, 1.0],
            length,
            a_poly: length,
            pade: None,
            geometric: None,
            singular_mode: vec![],
            end_residual: 0.0,
            u_end: vec![length],
            lambda_end: length,
            negative_pivots: None,
            jump: None,
        }
    }

    #[test]
    fn the_earliest_entry_into_a_band_is_located_inside_and_beyond_the_step() {
        for length in [1.0, 0.25] {
            let c = locate(&mut Line, &line(length)).unwrap().unwrap();
            assert_eq!(c.event, 1);
            assert!((c.a - 0.495).abs() < 1e-12, "{length}: {c:?}");
        }
        // Beyond the horizon: no event.
        assert_eq!(locate(&mut Line, &line(0.1)).unwrap(), None);
    }
}

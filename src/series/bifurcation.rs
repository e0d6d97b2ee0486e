//! Critical points along a static path: detection between step ends and
//! location inside the step that contains them, from that step's series
//! (DESIGN §8).
//!
//! Detection. A simple critical point makes one eigenvalue of the tangent
//! Kt change sign, so the number of negative pivots of its symmetric
//! factorization (Sylvester's law of inertia) differs between the two ends
//! of the step that crosses it; the engine factorizes Kt at every step
//! start, so comparing consecutive steps costs nothing. A limit point is
//! told apart from a bifurcation by the path's own tangent: at a limit
//! point lambda turns back, dlambda/da = 0 (and lambda_1 changes sign
//! between the steps on either side); at a bifurcation dlambda/da stays of
//! the order of lambda_1. The Cochelin–Medale geometric-series test
//! ([`super::geometric`]) flags a step whose series is dominated by a
//! singular point at a ≈ alpha_1 ahead of it (the steps then shrink toward
//! it): it is reported as a `geometric` event with lambda(alpha_1) of the
//! series with its geometric part removed (Cochelin & Medale 2013, §3.2:
//! U_p − alpha_1^(N−p) U_N, the mode being U_N / |U_N|).
//!
//! Location (no extra stepping). On the step's series U(a), lambda(a) the
//! test function kappa(a), the eigenvalue of smallest modulus of
//! Kt(U(a), lambda(a)) (inverse iteration on its factorization,
//! [`crate::linalg::eigen::smallest_eigenvalue`]), changes sign at the
//! critical point. The inertia brackets the root: bisection on the count of
//! negative pivots until kappa has the expected signs at both ends of the
//! bracket with aligned eigenvectors (the crossing eigenvalue is then the
//! one nearest zero), then the Illinois variant of regula falsi on kappa
//! (superlinear; Dowell & Jarratt, BIT 11 (1971) 168–174) until the
//! bracket is below `tol` relative in lambda. Each evaluation is one
//! assembly and one factorization of the tangent at a series point. The
//! series itself is accurate to the step's eps there, far below the 1e-6
//! asked of the location. The mode is the eigenvector at the root.

use super::continuation::{ContinuationProblem, PathStep};
use super::taylor;
use crate::error::{Error, Result};
use crate::linalg::{Factorization, LinearSolver, SparseMatrix, dot, eigen};
use serde::Serialize;

/// What a critical point is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// lambda turns back (dlambda/da = 0).
    LimitPoint,
    /// The tangent is singular while lambda goes on.
    Bifurcation,
    /// A geometric series in the step's terms: a singular point ahead at
    /// a ≈ alpha_1, not (yet) crossed.
    Geometric,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::LimitPoint => "limit_point",
            Kind::Bifurcation => "bifurcation",
            Kind::Geometric => "geometric",
        }
    }
}

/// A critical point found on a step.
#[derive(Clone, Debug, Serialize)]
pub struct Event {
    pub kind: Kind,
    /// lambda at the point.
    pub lambda: f64,
    /// Index of the step (0-based) whose series holds the point.
    pub step: usize,
    /// Path parameter a of the point on that step's series.
    pub a: f64,
    /// Negative pivots of the tangent before and after the point (None for
    /// a non-symmetric tangent or a geometric event).
    pub negative_pivots: Option<(usize, usize)>,
    /// Width of the final bracket in lambda (0 for a limit point located by
    /// the root of dlambda/da, or a geometric event: an estimate only).
    pub bracket: f64,
    /// Eigenvalue of the tangent at the point (the test function's value).
    pub kappa: f64,
    /// Tangent factorizations spent locating it.
    pub factorizations: usize,
    /// The mode on the free unknowns, |mode| = 1.
    #[serde(skip)]
    pub mode: Vec<f64>,
}

/// Settings of the location.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Stop when the bracket in lambda is below tol × max(|lambda|, scale).
    pub tol: f64,
    /// The load scale (lambda_end of the run).
    pub lambda_scale: f64,
    /// Most tangent evaluations per event.
    pub max_evaluations: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tol: 1e-9,
            lambda_scale: 1.0,
            max_evaluations: 80,
        }
    }
}

/// The test function at a series point.
struct Sample {
    a: f64,
    lambda: f64,
    count: usize,
    kappa: f64,
    mode: Vec<f64>,
}

fn sample<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
    lu: &mut LinearSolver,
    a: f64,
    start: Option<&[f64]>,
) -> Result<Sample> {
    let (k, f, lambda) = factor_at(problem, step, lu, a)?;
    let fail = |detail: String| locating_error(step, lambda, detail);
    let count = f
        .inertia()
        .map(|i| i.0)
        .ok_or_else(|| fail("the tangent is not symmetric (no inertia)".into()))?;
    let (kappa, mode, _) =
        eigen::smallest_eigenvalue(&f, &|x| k.mul_vec(x), k.n, start, 1e-12, 200).map_err(fail)?;
    Ok(Sample {
        a,
        lambda,
        count,
        kappa,
        mode,
    })
}

/// The tangent at the step's series point a, factorized, and lambda there.
fn factor_at<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
    lu: &mut LinearSolver,
    a: f64,
) -> Result<(SparseMatrix, Factorization, f64)> {
    let (u, lambda) = step.eval(a);
    let (k, _) = problem.tangent(&u, lambda)?;
    let f = lu
        .factorize(&k)
        .map_err(|d| locating_error(step, lambda, d))?;
    Ok((k, f, lambda))
}

fn locating_error(step: &PathStep, lambda: f64, detail: String) -> Error {
    Error::SingularMatrix {
        step: step.index,
        param: "lambda",
        at: lambda,
        detail: format!("locating a critical point: {detail}"),
    }
}

/// dlambda/da of the step's polynomial series.
fn lambda_rate(step: &PathStep, a: f64) -> f64 {
    let d: Vec<f64> = (1..step.lambda.len())
        .map(|p| p as f64 * step.lambda[p])
        .collect();
    taylor::eval(&d, a)
}

/// Locates every critical point that the step crosses, given the negative
/// pivots at its start (`n0`) and at its end (`n1`, the next step's
/// start). Limit points are told apart from bifurcations by dlambda/da at
/// the root (module docs).
pub fn locate<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
    n0: usize,
    n1: usize,
    lu: &mut LinearSolver,
    settings: &Settings,
) -> Result<Vec<Event>> {
    let mut events = vec![];
    let mut lo = sample(problem, step, lu, 0.0, None)?;
    let mut evaluations = 1;
    // The series end: its count may differ from n1 only when the
    // correction crossed the point (then it is reported at the end).
    let mut end = sample(problem, step, lu, step.length, Some(&lo.mode))?;
    evaluations += 1;
    let rate_scale = (0..=16)
        .map(|i| lambda_rate(step, step.length * i as f64 / 16.0).abs())
        .fold(0.0f64, f64::max);
    while lo.count != end.count && events.len() < 8 {
        let up = end.count > lo.count;
        // The crossing eigenvalue is positive before and negative after
        // (up), or the reverse.
        let sign_ok = |s: &Sample, before: bool| (s.kappa > 0.0) == (up == before);
        let target = lo.count;
        let mut hi = Sample {
            a: end.a,
            lambda: end.lambda,
            count: end.count,
            kappa: end.kappa,
            mode: end.mode.clone(),
        };
        let mut used = 0;
        let mut root = None;
        let mut illinois_side = 0i8;
        let (mut k_lo, mut k_hi) = (lo.kappa, hi.kappa);
        let tol = settings.tol * lo.lambda.abs().max(settings.lambda_scale);
        while (hi.lambda - lo.lambda).abs() > tol && used < settings.max_evaluations {
            // Several crossings in the bracket (a step over several
            // critical points): bisection on the count alone until one is
            // left. The eigenvalue nearest zero may then belong to a later
            // point, whose sign says nothing of the first (review 4: a
            // plate whose first step crossed three points reported the
            // second, at lambda 1.1837, and missed the first at 1.0987).
            let isolated = lo.count.abs_diff(hi.count) == 1;
            let aligned = dot(&lo.mode, &hi.mode).abs() > 0.9;
            let secant = isolated && aligned && sign_ok(&lo, true) && sign_ok(&hi, false);
            let a = if secant {
                let a = (lo.a * k_hi - hi.a * k_lo) / (k_hi - k_lo);
                // Keep strictly inside the bracket.
                let w = hi.a - lo.a;
                a.clamp(lo.a + 1e-3 * w, hi.a - 1e-3 * w)
            } else {
                0.5 * (lo.a + hi.a)
            };
            let start = if secant { Some(&hi.mode[..]) } else { None };
            let s = sample(problem, step, lu, a, start)?;
            used += 1;
            // Within round-off of the root, the eigenvalue's sign and the
            // inertia disagree: the point is found.
            if secant
                && (s.count == target) != sign_ok(&s, true)
                && dot(&s.mode, &hi.mode).abs() > 0.9
            {
                root = Some(s);
                break;
            }
            if s.count == target {
                k_lo = s.kappa;
                if illinois_side == -1 {
                    k_hi *= 0.5;
                }
                illinois_side = -1;
                lo = s;
            } else {
                k_hi = s.kappa;
                if illinois_side == 1 {
                    k_lo *= 0.5;
                }
                illinois_side = 1;
                hi = s;
            }
        }
        evaluations += used;
        // The bracket the event reports: the inertia changes inside it.
        let mut bracket = (hi.lambda - lo.lambda).abs();
        if let Some(r) = &root {
            let (width, probes) = close_bracket(problem, step, lu, r, &lo, &hi, target)?;
            bracket = width;
            evaluations += probes;
        }
        let secant = lo.count.abs_diff(hi.count) == 1 && sign_ok(&lo, true) && sign_ok(&hi, false);
        let a = if let Some(r) = &root {
            r.a
        } else if secant {
            (lo.a * hi.kappa - hi.a * lo.kappa) / (hi.kappa - lo.kappa)
        } else {
            0.5 * (lo.a + hi.a)
        };
        let (_, lambda) = step.eval(a);
        let near = match &root {
            Some(r) => r,
            None if lo.kappa.abs() < hi.kappa.abs() => &lo,
            None => &hi,
        };
        let kind = if lambda_rate(step, a).abs() < 1e-2 * rate_scale {
            Kind::LimitPoint
        } else {
            Kind::Bifurcation
        };
        events.push(Event {
            kind,
            lambda,
            step: step.index,
            a,
            negative_pivots: Some((lo.count, hi.count)),
            bracket,
            kappa: near.kappa,
            factorizations: evaluations,
            mode: near.mode.clone(),
        });
        evaluations = 0;
        // Further crossings in the same step: from the bracket's upper end.
        lo = hi;
        if lo.count == end.count {
            break;
        }
        end = sample(problem, step, lu, step.length, Some(&lo.mode))?;
    }
    if events.is_empty() && n0 != n1 {
        // The count changed between the series end and the corrected end:
        // the point is at the step end (not on the series).
        events.push(Event {
            kind: Kind::Bifurcation,
            lambda: step.lambda_end,
            step: step.index,
            a: step.length,
            negative_pivots: Some((n0, n1)),
            bracket: (step.lambda_end - end.lambda).abs(),
            kappa: end.kappa,
            factorizations: evaluations,
            mode: end.mode,
        });
    }
    Ok(events)
}

/// Most probes that close the bracket around a root found by the sign of
/// kappa (each at four times the distance of the last).
const CLOSING_PROBES: usize = 4;

/// A root `r` found where kappa's sign and the inertia disagree is within
/// round-off of the crossing, but the bracket [lo, hi] around it may still
/// be wide (review 4: 5e-4 in lambda for a point located to 5e-11). The
/// crossing of the count lies on the side of `r` whose count differs from
/// `r`'s; probes there at a few times kappa's distance to zero by the
/// secant slope, |kappa_r| / |dkappa/da|, close a bracket [r, probe] of that
/// width. Returns its width in lambda (that of the side left open when no
/// probe closes it) and the probes spent.
fn close_bracket<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
    lu: &mut LinearSolver,
    r: &Sample,
    lo: &Sample,
    hi: &Sample,
    target: usize,
) -> Result<(f64, usize)> {
    let far = if r.count == target { hi } else { lo };
    let slope = ((hi.kappa - lo.kappa) / (hi.a - lo.a)).abs();
    let room = far.a - r.a;
    let floor = 64.0 * f64::EPSILON * r.a.abs().max(step.length);
    let mut distance = (4.0 * r.kappa.abs() / slope).max(floor);
    let mut probes = 0;
    while probes < CLOSING_PROBES && distance < 0.5 * room.abs() {
        let a = r.a + distance.copysign(room);
        let (_, f, lambda) = factor_at(problem, step, lu, a)?;
        probes += 1;
        if f.inertia().map(|i| i.0) != Some(r.count) {
            return Ok(((lambda - r.lambda).abs(), probes));
        }
        distance *= 4.0;
    }
    Ok(((far.lambda - r.lambda).abs(), probes))
}

/// A critical point located without inertia (non-symmetric tangent), in a
/// step whose series passed the geometric-series test: the real eigenvalue
/// of Kt nearest zero ([`eigen::nearest_real_eigenvalue`], started from
/// the geometric mode U_N) must change sign between a = 0 and the step's
/// length; then the Illinois iteration on it as in [`locate`] (no inertia
/// bracket: the sign of the eigenvalue is the bracket). None when it does
/// not change sign on the step.
pub fn locate_unsymmetric<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    step: &PathStep,
    lu: &mut LinearSolver,
    settings: &Settings,
) -> Result<Option<Event>> {
    let n = step.u.len() - 1;
    let start = step.u[n].clone();
    let mut eval = |a: f64, start: &[f64]| -> Result<(f64, f64, Vec<f64>)> {
        let (k, f, lambda) = factor_at(problem, step, lu, a)?;
        let fail = |detail: String| locating_error(step, lambda, detail);
        let (kappa, mode, _) =
            eigen::nearest_real_eigenvalue(&f, k.n, Some(start), 1e-12, 400).map_err(fail)?;
        Ok((lambda, kappa, mode))
    };
    let (mut a_lo, mut a_hi) = (0.0, step.length);
    let (mut l_lo, mut k_lo, m_lo) = eval(a_lo, &start)?;
    let (mut l_hi, mut k_hi, mut mode) = eval(a_hi, &m_lo)?;
    if k_lo.signum() == k_hi.signum() {
        return Ok(None);
    }
    let (mut f_lo, mut f_hi) = (k_lo, k_hi);
    let mut side = 0i8;
    let mut used = 2;
    let mut a = 0.5 * (a_lo + a_hi);
    let tol = settings.tol * l_lo.abs().max(settings.lambda_scale);
    while (l_hi - l_lo).abs() > tol && used < settings.max_evaluations {
        let w = a_hi - a_lo;
        a = ((a_lo * f_hi - a_hi * f_lo) / (f_hi - f_lo)).clamp(a_lo + 1e-3 * w, a_hi - 1e-3 * w);
        let (l, k, m) = eval(a, &mode)?;
        used += 1;
        mode = m;
        if k == 0.0 {
            break;
        }
        if k.signum() == k_lo.signum() {
            (a_lo, l_lo, k_lo, f_lo) = (a, l, k, k);
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            (a_hi, l_hi, k_hi, f_hi) = (a, l, k, k);
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
    }
    let (_, lambda) = step.eval(a);
    let rate_scale = (0..=16)
        .map(|i| lambda_rate(step, step.length * i as f64 / 16.0).abs())
        .fold(0.0f64, f64::max);
    let kind = if lambda_rate(step, a).abs() < 1e-2 * rate_scale {
        Kind::LimitPoint
    } else {
        Kind::Bifurcation
    };
    Ok(Some(Event {
        kind,
        lambda,
        step: step.index,
        a,
        negative_pivots: None,
        bracket: (l_hi - l_lo).abs(),
        kappa: if k_lo.abs() < k_hi.abs() { k_lo } else { k_hi },
        factorizations: used,
        mode,
    }))
}

/// A limit point without inertia (non-symmetric tangent): lambda_1 changed
/// sign between this step and the next; the root of dlambda/da on the
/// step's series (bisection on 64 samples), or the step end.
pub fn limit_point(step: &PathStep) -> Event {
    let k = 64;
    let mut a_root = step.length;
    let mut prev = lambda_rate(step, 0.0);
    for i in 1..=k {
        let a = step.length * i as f64 / k as f64;
        let r = lambda_rate(step, a);
        if r.signum() != prev.signum() {
            let (mut lo, mut hi) = (step.length * (i - 1) as f64 / k as f64, a);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if lambda_rate(step, mid).signum() == prev.signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            a_root = 0.5 * (lo + hi);
            break;
        }
        prev = r;
    }
    let (_, lambda) = step.eval(a_root);
    let u1 = &step.u[1];
    let s = crate::linalg::norm(u1).max(f64::MIN_POSITIVE);
    Event {
        kind: Kind::LimitPoint,
        lambda,
        step: step.index,
        a: a_root,
        negative_pivots: None,
        bracket: 0.0,
        kappa: f64::NAN,
        factorizations: 0,
        // At a limit point the null vector is the path's tangent dU/da.
        mode: u1.iter().map(|v| v / s).collect(),
    }
}

/// The geometric event of a step whose terms passed the Cochelin–Medale
/// test (module docs): lambda at a = alpha_1 of the series with its
/// geometric part removed, mode U_N / |U_N|.
pub fn geometric(step: &PathStep, g: &super::geometric::GeometricSeries) -> Event {
    Event {
        kind: Kind::Geometric,
        lambda: g.lambda,
        step: step.index,
        a: g.distance,
        negative_pivots: None,
        bracket: 0.0,
        kappa: f64::NAN,
        factorizations: 0,
        mode: step.singular_mode.clone(),
    }
}

//! The one Newton corrector of the engine, and the scaled metric every length
//! of the engine is measured in.
//!
//! # Scaled variables (DESIGN §1, last paragraph)
//!
//! Step lengths act on a scaled arclength so that the same problem written
//! in other units takes the same steps. With the characteristic magnitude
//! s_i of each unknown ([`ContinuationProblem::unknown_scale`]) and the load
//! range Lambda (`ContinuationConfig::lambda_scale`), the engine measures
//!   ũ_i = u_i / s_i,   λ̃ = lambda / Lambda,
//! so that every inner product of the engine is the weighted one
//!   <(U, lambda), (V, mu)>~ = sum_i U_i V_i / s_i^2 + lambda mu / Lambda^2.
//! [`Metric`] holds 1/s_i and 1/Lambda. With every scale 1 it reduces to the
//! plain Euclidean products, bit for bit.
//!
//! # The corrector
//!
//! Newton's method on R(U, lambda) = 0 and one of the constraints
//!   fixed load:  lambda = lambda_start                        (dlambda = 0),
//!   arclength:   <U - U_ref, t_U>~ + (lambda - lambda_ref) t_lambda / Lambda^2 = 0,
//! the hyperplane through a reference point (the predictor of the Newton
//! baseline, or the start point itself for the ANM step end) orthogonal to the
//! direction (t_U, t_lambda) (the step's (U_1, lambda_1) for the ANM).
//! Each iteration solves, with the factorization of Kt in use,
//!   Kt U_r = -R,  Kt U_t = -R_lambda (arclength only),
//!   dlambda = -(<U_r, t_U>~ + c) / (<U_t, t_U>~ + t_lambda / Lambda^2),
//!   dU = U_r + dlambda U_t,
//! where c is the current offset from the hyperplane (bordering by
//! elimination, as the series itself: DESIGN §2 "Arclength without a bordered
//! factorization"). Two ways to get Kt ([`Jacobian`]):
//! - `Fresh` (full Newton, the Newton-Raphson baseline): the tangent is
//!   assembled at every iterate before its residual (a problem may refresh
//!   state in `tangent`, e.g. its active contact set, that the residual relies
//!   on), and the residual is measured against |R_lambda| of that tangent;
//! - `Reuse` (modified Newton, the ANM step end and the output grid points):
//!   the residual comes first (a point already on the path costs one residual
//!   evaluation); the given factorization (the step's) serves while every
//!   iteration reduces the residual by at least 1/`contraction`, else the
//!   tangent is refactorized at the new iterate (`contraction = 0` refactorizes
//!   after every iteration: full Newton, residual first).

use super::continuation::{ContinuationProblem, factorize};
use super::stats::{Stats, charge};
use crate::error::{Error, Result};
use crate::linalg::{Factorization, LinearSolver, dot, norm};
use std::borrow::Cow;
use std::time::Instant;

/// The scaled inner product of the engine (module docs): 1/s_i and 1/Lambda.
#[derive(Clone, Debug)]
pub struct Metric {
    /// 1/s_i; `None` when every s_i = 1 (no product is formed then, so the
    /// engine is bit for bit the unscaled one).
    inv_u: Option<Vec<f64>>,
    /// 1/Lambda.
    inv_l: f64,
    /// Lambda.
    lambda_scale: f64,
}

impl Metric {
    /// The metric of unknown scales `s` and load scale `lambda_scale`; every
    /// scale must be finite and positive.
    pub fn new(s: &[f64], lambda_scale: f64) -> Result<Self> {
        let bad = |key: &str, problem: String| Error::Invalid {
            file: Default::default(),
            key: key.into(),
            problem,
        };
        if !(lambda_scale.is_finite() && lambda_scale > 0.0) {
            return Err(bad(
                "lambda_scale",
                format!("must be finite and positive, got {lambda_scale:e}"),
            ));
        }
        if let Some((i, x)) = s
            .iter()
            .enumerate()
            .find(|(_, x)| !(x.is_finite() && **x > 0.0))
        {
            return Err(bad(
                "unknown_scale",
                format!("scale of unknown {i} must be finite and positive, got {x:e}"),
            ));
        }
        let inv_u = (!s.iter().all(|&x| x == 1.0)).then(|| s.iter().map(|x| 1.0 / x).collect());
        Ok(Self {
            inv_u,
            inv_l: 1.0 / lambda_scale,
            lambda_scale,
        })
    }

    /// The metric of a problem: its [`ContinuationProblem::unknown_scale`]
    /// (one per unknown) and `lambda_scale`.
    pub fn for_problem<P: ContinuationProblem + ?Sized>(
        problem: &P,
        lambda_scale: f64,
    ) -> Result<Self> {
        let s = problem.unknown_scale();
        if s.len() != problem.ndof() {
            return Err(Error::Invalid {
                file: Default::default(),
                key: "unknown_scale".into(),
                problem: format!("{} scales for {} unknowns", s.len(), problem.ndof()),
            });
        }
        Self::new(&s, lambda_scale)
    }

    /// Unit scales (the plain Euclidean metric).
    pub fn unit() -> Self {
        Self {
            inv_u: None,
            inv_l: 1.0,
            lambda_scale: 1.0,
        }
    }

    /// ũ = u / s.
    pub fn u<'a>(&self, x: &'a [f64]) -> Cow<'a, [f64]> {
        match &self.inv_u {
            None => Cow::Borrowed(x),
            Some(w) => Cow::Owned(x.iter().zip(w).map(|(a, w)| a * w).collect()),
        }
    }

    /// Appends ũ = u / s to `out` (the values of [`Metric::u`]).
    pub fn extend_scaled(&self, x: &[f64], out: &mut Vec<f64>) {
        match &self.inv_u {
            None => out.extend_from_slice(x),
            Some(w) => out.extend(x.iter().zip(w).map(|(a, w)| a * w)),
        }
    }

    /// λ̃ = lambda / Lambda.
    pub fn l(&self, x: f64) -> f64 {
        x * self.inv_l
    }

    /// Lambda.
    pub fn lambda_scale(&self) -> f64 {
        self.lambda_scale
    }

    /// Whether every scale is 1 (the plain Euclidean metric).
    pub fn is_unit(&self) -> bool {
        self.inv_u.is_none() && self.inv_l == 1.0
    }

    /// <a, b>~ over the unknowns: sum a_i b_i / s_i^2.
    pub fn dot_u(&self, a: &[f64], b: &[f64]) -> f64 {
        match &self.inv_u {
            None => dot(a, b),
            Some(w) => a
                .iter()
                .zip(b)
                .zip(w)
                .map(|((x, y), w)| (x * w) * (y * w))
                .sum(),
        }
    }

    /// Norm of a residual (or of dR/dlambda): sqrt(sum (R_i s_i)^2). R_i is
    /// conjugate to u_i (R_i u_i is a work), so R_i s_i has one unit for
    /// every unknown (a force on a displacement, a moment on a director) and
    /// the relative residual |R| / |R_lambda| does not depend on units.
    pub fn residual_norm(&self, r: &[f64]) -> f64 {
        match &self.inv_u {
            None => norm(r),
            Some(w) => r
                .iter()
                .zip(w)
                .map(|(x, w)| (x / w) * (x / w))
                .sum::<f64>()
                .sqrt(),
        }
    }

    /// The weight of the load parameter in the inner product, 1/Lambda^2.
    pub fn lambda_weight(&self) -> f64 {
        self.inv_l * self.inv_l
    }
}

/// The equation closing R(U, lambda) = 0 (module docs).
#[derive(Clone, Copy, Debug)]
pub enum Constraint<'a> {
    /// lambda stays at its start value.
    FixedLambda,
    /// <U - U_ref, t_u>~ + (lambda - lambda_ref) t_lambda / Lambda^2 = 0, with
    /// the reference the start point when `reference` is `None` (then every
    /// correction is orthogonal to the direction).
    Arclength {
        t_u: &'a [f64],
        t_lambda: f64,
        reference: Option<(&'a [f64], f64)>,
    },
}

/// Where the corrector's tangent comes from (module docs).
#[derive(Clone, Copy)]
pub enum Jacobian<'f> {
    /// Full Newton, tangent assembled before the residual at every iterate;
    /// |R| measured against |R_lambda| of that tangent; a non-finite residual
    /// is a [`Error::NonFinite`].
    Fresh,
    /// Residual first; `initial` is a factorization of Kt and (for the
    /// arclength constraint) U_t = -Kt^-1 R_lambda to start with (else the
    /// tangent at the start point, assembled after its residual). The tangent
    /// is refactorized at an iterate whose residual exceeds `contraction`
    /// times the previous one. |R| is measured against `scale`; a non-finite
    /// residual is a [`Error::NoConvergence`].
    Reuse {
        initial: Option<(&'f Factorization, &'f [f64])>,
        contraction: f64,
        scale: f64,
    },
}

/// Settings of one correction.
#[derive(Clone, Copy)]
pub struct Settings<'f> {
    /// Converged when the relative residual |R| / scale <= tol.
    pub tol: f64,
    /// Iterations allowed (0: check only).
    pub max_iter: usize,
    pub jacobian: Jacobian<'f>,
    /// A relative residual above this is not corrected: the point is too far
    /// off the path ([`Error::NoConvergence`] with the iterations done).
    pub max_residual: f64,
    /// Backtracking on the residual after each full-Newton update (Newton
    /// baseline, `solver.newton_line_search`): the update is halved, up to
    /// 5 times, until |R| falls by at least 1e-4 of its share (Armijo on
    /// |R|; Dennis & Schnabel, Numerical Methods for Unconstrained
    /// Optimization and Nonlinear Equations, 1983, §6.3). Only with
    /// [`Jacobian::Fresh`].
    pub line_search: bool,
    /// Step index, for errors.
    pub step: usize,
}

/// A corrected point.
#[derive(Clone, Debug)]
pub struct Corrected {
    pub u: Vec<f64>,
    pub lambda: f64,
    pub iterations: usize,
    /// Relative residual at the start point.
    pub start_residual: f64,
}

/// Newton corrections of (u, lambda) onto R = 0 under `constraint` (module
/// docs). Counts residuals, solves, factorizations and iterations
/// (`stats.corrections`) in `stats`.
#[allow(clippy::too_many_arguments)]
pub fn correct<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    u: Vec<f64>,
    lambda: f64,
    constraint: &Constraint,
    settings: &Settings,
    metric: &Metric,
    lu: &mut LinearSolver,
    stats: &mut Stats,
) -> Result<Corrected> {
    let mut start = f64::NAN;
    correct_noting_start(
        problem, u, lambda, constraint, settings, metric, lu, stats, &mut start,
    )
}

/// [`correct`], also when it fails: `start_residual` receives the relative
/// residual at the start point once it is evaluated (it stays as it was when
/// the residual itself is refused, e.g. a contact node missed). A step's
/// end residual is reported even when its correction diverges.
#[allow(clippy::too_many_arguments)]
pub fn correct_noting_start<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    u: Vec<f64>,
    lambda: f64,
    constraint: &Constraint,
    settings: &Settings,
    metric: &Metric,
    lu: &mut LinearSolver,
    stats: &mut Stats,
    start_residual: &mut f64,
) -> Result<Corrected> {
    let mut u = u;
    let mut l = lambda;
    let step = settings.step;
    let arclength = matches!(constraint, Constraint::Arclength { .. });
    let fresh = matches!(settings.jacobian, Jacobian::Fresh);
    let (mut borrowed, contraction, fixed_scale) = match settings.jacobian {
        Jacobian::Fresh => (None, 0.0, f64::NAN),
        Jacobian::Reuse {
            initial,
            contraction,
            scale,
        } => (initial, contraction, scale),
    };
    // A factorization made here, with its U_t (empty for a fixed load).
    let mut own: Option<(Factorization, Vec<f64>)> = None;
    let tangent_solve = |f: &Factorization, rl: &[f64], stats: &mut Stats| -> Vec<f64> {
        if !arclength {
            return vec![];
        }
        let t = Instant::now();
        let ut = f.solve(&rl.iter().map(|x| -x).collect::<Vec<_>>());
        stats.solves += 1;
        charge(&mut stats.solve_s, t);
        ut
    };
    let mut it = 0;
    let mut prev_res = f64::NAN;
    loop {
        // Fresh: the tangent at the iterate, before its residual.
        let assembled = if fresh {
            let t = Instant::now();
            let kr = problem.tangent(&u, l)?;
            charge(&mut stats.assembly_s, t);
            Some(kr)
        } else {
            None
        };
        let t = Instant::now();
        let r = problem.residual(&u, l)?;
        stats.residual_evaluations += 1;
        charge(&mut stats.assembly_s, t);
        let scale = match &assembled {
            Some((_, rl)) => force_scale(&*problem, metric, rl),
            None => fixed_scale,
        };
        let res = metric.residual_norm(&r) / scale;
        if it == 0 {
            *start_residual = res;
        }
        // Reuse: refactorize after an iteration that contracted too little.
        if !fresh && it > 0 && res > contraction * prev_res && res > settings.tol {
            let t = Instant::now();
            let (k, rl) = problem.tangent(&u, l)?;
            charge(&mut stats.assembly_s, t);
            let f = factorize(lu, &k, stats, step, l)?;
            let ut = tangent_solve(&f, &rl, stats);
            own = Some((f, ut));
            borrowed = None;
        }
        if fresh && !res.is_finite() {
            return Err(Error::NonFinite {
                step,
                param: "lambda",
                at: l,
                what: "residual".into(),
            });
        }
        if res <= settings.tol {
            return Ok(Corrected {
                u,
                lambda: l,
                iterations: it,
                start_residual: *start_residual,
            });
        }
        if it >= settings.max_iter || !res.is_finite() || res > settings.max_residual {
            return Err(Error::NoConvergence {
                step,
                param: "lambda",
                at: l,
                iterations: it,
                residual: res,
                tolerance: settings.tol,
            });
        }
        if let Some((k, rl)) = assembled {
            let f = factorize(lu, &k, stats, step, l)?;
            let ut = tangent_solve(&f, &rl, stats);
            own = Some((f, ut));
        } else if own.is_none() && borrowed.is_none() {
            let t = Instant::now();
            let (k, rl) = problem.tangent(&u, l)?;
            charge(&mut stats.assembly_s, t);
            let f = factorize(lu, &k, stats, step, l)?;
            let ut = tangent_solve(&f, &rl, stats);
            own = Some((f, ut));
        }
        let (f, ut): (&Factorization, &[f64]) = match (&borrowed, &own) {
            (Some((f, ut)), _) => (*f, *ut),
            (None, Some((f, ut))) => (f, ut.as_slice()),
            (None, None) => unreachable!("a factorization was made above"),
        };
        let t = Instant::now();
        let ur = f.solve(&r.iter().map(|x| -x).collect::<Vec<_>>());
        stats.solves += 1;
        charge(&mut stats.solve_s, t);
        let before = (settings.line_search && fresh).then(|| (u.clone(), l));
        let (du, dl) = match *constraint {
            Constraint::FixedLambda => (ur, 0.0),
            Constraint::Arclength {
                t_u,
                t_lambda,
                reference,
            } => {
                let den = metric.dot_u(ut, t_u) + t_lambda * metric.lambda_weight();
                let dl = match reference {
                    None => -metric.dot_u(&ur, t_u) / den,
                    Some((u_ref, l_ref)) => {
                        // Offset of the iterate from the hyperplane.
                        let d: Vec<f64> = u.iter().zip(u_ref).map(|(a, b)| a - b).collect();
                        let offset =
                            metric.dot_u(&d, t_u) + (l - l_ref) * t_lambda * metric.lambda_weight();
                        -(metric.dot_u(&ur, t_u) + offset) / den
                    }
                };
                let du = ur.iter().zip(ut).map(|(b, t)| b + dl * t).collect();
                (du, dl)
            }
        };
        // The residual's round-off floor: it no longer falls, and the update
        // that would lower it is below what the state is held to. Iterating
        // on would only add noise (a cantilever under a 1e-3 N tip load:
        // |R| 1.1–1.3e-8 N from iteration 1 on, updates ≤ 5 ε |x|).
        let dl_below = dl.abs() <= ROUND_OFF * l.abs().max(metric.lambda_scale());
        // Or it stalls no higher than the floor the run has already
        // accepted (review 15: on the penalty law an update across a kink
        // is no round-off update, and a cantilever stopped at 1.6e-5 after
        // accepting 3.2e-5 at its floor).
        // Not above FLOOR_REUSE: a large relative floor comes from tiny
        // loads (review 17: 0.53 while a punch approached the shell under
        // eq. (3)'s pull alone), and at full load it would pass a real
        // failure for round-off.
        let at_floor = res <= stats.round_off_residual.min(FLOOR_REUSE);
        if it > 0
            && res > STALL * prev_res
            && (at_floor || (dl_below && below_round_off(problem, &u, l, &du)))
        {
            stats.round_off_stops += 1;
            if res > stats.round_off_residual {
                stats.round_off_residual = res;
                stats.round_off_lambda = l;
            }
            return Ok(Corrected {
                u,
                lambda: l,
                iterations: it,
                start_residual: *start_residual,
            });
        }
        for (x, d) in u.iter_mut().zip(&du) {
            *x += d;
        }
        l += dl;
        if let Some((u0, l0)) = before {
            line_search(problem, &mut u, &mut l, &u0, l0, res, scale, metric, stats);
        }
        it += 1;
        stats.corrections += 1;
        prev_res = res;
    }
}

/// The largest accepted floor a later stall may reuse (relative residual;
/// the cases that need the reuse stalled at 5e-9 to 3.2e-5).
const FLOOR_REUSE: f64 = 1e-3;

/// A correction whose residual is above `STALL` times the previous one has
/// stopped converging (Newton contracts far faster where it converges).
const STALL: f64 = 0.5;

/// An update below this fraction of what a value is held to cannot change
/// it (16 ε; the cantilever of the comment above: 0.5–5 ε).
const ROUND_OFF: f64 = 16.0 * f64::EPSILON;

/// Whether every entry of the update is at most 16 ε m_i, with m_i the
/// magnitude the state behind unknown i is held to
/// ([`ContinuationProblem::resolution`]; false where the problem gives none).
/// Rounding the positions alone moves the state by ε m_i.
fn below_round_off<P: ContinuationProblem + ?Sized>(
    problem: &P,
    u: &[f64],
    lambda: f64,
    du: &[f64],
) -> bool {
    problem
        .resolution(u, lambda)
        .is_some_and(|m| du.iter().zip(&m).all(|(d, m)| d.abs() <= ROUND_OFF * m))
}

/// Backtracking along the Newton update from (u0, l0) to (u, l) (at full
/// length on entry): halves it, up to 5 times, until the relative residual
/// is below (1 − 1e-4 s) `res`, s the fraction kept (Settings::line_search).
/// On the penalty law the full update crosses kinks (a node predicted open
/// penetrates by K = 1e9 N/m): plate-cylinder 0.1 m, arclength ≤ 0.1,
/// tol 1e-4: 4,556 → 2,928 factorizations, 621 → 423 increments. A trial
/// point the residual refuses (a left-out contact candidate come within
/// reach: the next tangent updates the active set) keeps the full update.
#[allow(clippy::too_many_arguments)]
fn line_search<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    u: &mut [f64],
    l: &mut f64,
    u0: &[f64],
    l0: f64,
    res: f64,
    scale: f64,
    metric: &Metric,
    stats: &mut Stats,
) {
    let du: Vec<f64> = u.iter().zip(u0).map(|(a, b)| a - b).collect();
    let dl = *l - l0;
    let mut s = 1.0;
    for _ in 0..5 {
        let t = Instant::now();
        let r = problem.residual(u, *l);
        stats.residual_evaluations += 1;
        charge(&mut stats.assembly_s, t);
        let Ok(r) = r else {
            for ((x, a), d) in u.iter_mut().zip(u0).zip(&du) {
                *x = a + d;
            }
            *l = l0 + dl;
            return;
        };
        let trial = metric.residual_norm(&r) / scale;
        if trial.is_finite() && trial < (1.0 - 1e-4 * s) * res {
            return;
        }
        s *= 0.5;
        for ((x, a), d) in u.iter_mut().zip(u0).zip(&du) {
            *x = a + s * d;
        }
        *l = l0 + s * dl;
    }
}

/// Newton correction of an output point at fixed load: R(U, lambda) = 0 for
/// U, lambda held, from `u`. Residual first (a point already within `tol`
/// costs one residual evaluation), then full Newton (a fresh tangent and
/// factorization per iteration, assembled after the residual at the iterate).
/// The residual is measured as |R| / `scale` in the norm of `metric`
/// ([`Metric::residual_norm`]; `scale` e.g. |F| or |R_lambda| in that norm).
/// Returns the corrected U and the iterations used (0: already on the path).
#[allow(clippy::too_many_arguments)]
pub fn correct_at_lambda<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    u: Vec<f64>,
    lambda: f64,
    tol: f64,
    scale: f64,
    metric: &Metric,
    max_iter: usize,
    lu: &mut LinearSolver,
    stats: &mut Stats,
    step: usize,
) -> Result<(Vec<f64>, usize)> {
    let settings = Settings {
        tol,
        max_iter,
        jacobian: Jacobian::Reuse {
            initial: None,
            contraction: 0.0,
            scale,
        },
        max_residual: f64::INFINITY,
        line_search: false,
        step,
    };
    let c = correct(
        problem,
        u,
        lambda,
        &Constraint::FixedLambda,
        &settings,
        metric,
        lu,
        stats,
    )?;
    Ok((c.u, c.iterations))
}

/// The scale of the relative residual test, |dR/dlambda| in the unit-free
/// norm; where that is exactly zero, the problem's drive floor
/// ([`ContinuationProblem::drive_floor`]) instead (review 15: a plate
/// pushed by a moving plane under the penalty law divided its residual by
/// the smallest positive number, 1.4e301, and stopped before the touch).
pub fn force_scale<P: ContinuationProblem + ?Sized>(
    problem: &P,
    metric: &Metric,
    rl: &[f64],
) -> f64 {
    let scale = metric.residual_norm(rl);
    let scale = if scale == 0.0 {
        problem
            .drive_floor()
            .map_or(0.0, |f| metric.residual_norm(&f))
    } else {
        scale
    };
    scale.max(f64::MIN_POSITIVE)
}

//! Caller-driven ANM path following: [`Path::step`] computes one accepted
//! step at a time; the caller decides what to do with it (outputs, grid
//! points, checkpoints) and whether to go on.
//!
//! One step from (U0, lambda0) (DESIGN §2; Cochelin, Damil, Potier-Ferry,
//! Rev. Eur. Eléments Finis 3 (1994) 281–297), in the scaled variables
//! ũ_i = u_i / s_i, λ̃ = lambda / Lambda of [`Metric`] (s_i from
//! [`ContinuationProblem::unknown_scale`], Lambda = `cfg.lambda_scale`):
//!
//! ```text
//! 1. Kt = dR/dU and R_lambda at (U0, lambda0), factorized once;
//!    U_t = -Kt^-1 R_lambda (= dU/dlambda on the path).
//! 2. Order 1 (O1): U_1 = lambda_1 U_t with |Ũ_1|^2 + λ̃_1^2 = 1:
//!    λ̃_1 = ±1 / sqrt(1 + Lambda^2 <U_t, U_t>~),  lambda_1 = Lambda λ̃_1;
//!    the sign makes <Ũ_1, Ũ_1'> + λ̃_1 λ̃_1' > 0 with the previous step's
//!    direction (U_1', lambda_1'), or lambda_1 point toward lambda_end on
//!    the first step.
//! 3. Order p = 2..N (Op): Kt U_p + R_lambda lambda_p + rhs_p = 0 and
//!    <Ũ_p, Ũ_1> + λ̃_p λ̃_1 = 0:
//!    U_b = -Kt^-1 rhs_p,
//!    lambda_p = -<U_b, U_1>~ / (<U_t, U_1>~ + lambda_1 / Lambda^2),
//!    U_p = lambda_p U_t + U_b.
//!    The path parameter is the scaled pseudo-arclength
//!    a = <U - U0, U_1>~ + (lambda - lambda0) lambda_1 / Lambda^2,
//!    and the terms stay in the problem's units:
//!    U(a) = U0 + sum a^p U_p,  lambda(a) = lambda0 + sum a^p lambda_p.
//! 4. Step length (L), on the stacked scaled terms T̃_p = (Ũ_p, λ̃_p):
//!    a_max = min((eps |T̃_1| / |T̃_N|)^(1/(N-1)), 1e15^(1/N) |T̃_1| / |T̃_1|_∞);
//!    with Padé, the range where |P_N - P_{N-1}| <= eps |P_N| (pade::range
//!    on T̃) below 0.95 of the first pole, up to 10 a_max. The
//!    Cochelin-Medale geometric-series test reads T̃ too; min_step bounds a.
//! 5. Step end: residual check |R| / |R_lambda| <= residual_tol, else the
//!    arclength-constrained correction <dŨ, Ũ_1> + dλ̃ λ̃_1 = 0
//!    (super::correct), else the step halved.
//! ```
//!
//! With every scale 1 this is exactly the unscaled method.
//!
//! Arc coordinates ([`ContinuationProblem::arc_coordinates`]): a problem
//! may add coordinates y(U, lambda), with y_p = y*_p + J U_p +
//! y_lambda lambda_p at every order, to every inner product above:
//! y_t = J U_t + y_lambda (= dy/dlambda on the path) joins |Ũ_t|^2 in O1,
//! <y_p, y_1> joins the orthogonality of Op (lambda_p = −(<U_b, U_1>~ +
//! <y_b, y_1>) / (<U_t, U_1>~ + lambda_1 / Lambda^2 + <y_t, y_1>), y_b =
//! J U_b + y*_p), and y_p joins the terms T̃_p of L. The path parameter is
//! then a = <U − U0, U_1>~ + (lambda − lambda0) lambda_1 / Lambda^2 +
//! <y − y0, y_1>; the step-end correction keeps its constraint in U and
//! lambda (any plane transverse to the path serves).

use super::continuation::{ContinuationConfig, ContinuationProblem, PathStep, factorize_solve};
use super::correct::{self, Constraint, Jacobian, Metric, Settings};
use super::events;
use super::geometric;
use super::kinks;
use super::pade;
use super::stats::{Stats, charge};
use super::stop::Stop;
use crate::error::{Error, Result};
use crate::linalg::{Factorization, LinearSolver, dot, norm};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// The state after an accepted step: enough to resume the path exactly
/// ([`Path::resume`]). Floating-point values are serialized as their bit
/// patterns (u64), so that they round-trip exactly through any serde format.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Index of the next step (= accepted steps so far).
    pub index: usize,
    #[serde(with = "bits::vec")]
    pub u: Vec<f64>,
    #[serde(with = "bits::scalar")]
    pub lambda: f64,
    /// (U_1, lambda_1) of the last step, which orients the next one.
    #[serde(with = "bits::dir")]
    pub prev_dir: Option<(Vec<f64>, f64)>,
    /// Length of the last step (the jump length past an event, see
    /// [`super::events`]).
    #[serde(default, with = "bits::opt")]
    pub prev_length: Option<f64>,
    pub stats: Stats,
}

/// Caller-driven stepper of the static ANM path (module docs).
pub struct Path<'p, P: ContinuationProblem> {
    problem: &'p mut P,
    cfg: ContinuationConfig,
    metric: Metric,
    u: Vec<f64>,
    lambda: f64,
    prev_dir: Option<(Vec<f64>, f64)>,
    prev_length: Option<f64>,
    index: usize,
    forward: f64,
    lu: LinearSolver,
    stats: Stats,
    stopped: Option<Stop>,
}

impl<'p, P: ContinuationProblem> Path<'p, P> {
    /// A path from (u0, lambda0) toward `cfg.lambda_end`. Invalid scales
    /// (non-positive or non-finite) make the first [`Path::step`] fail.
    pub fn new(problem: &'p mut P, u0: Vec<f64>, lambda0: f64, cfg: ContinuationConfig) -> Self {
        Self::build(
            problem,
            Checkpoint {
                index: 0,
                u: u0,
                lambda: lambda0,
                prev_dir: None,
                prev_length: None,
                stats: Stats::default(),
            },
            cfg,
        )
    }

    /// Resumes exactly where `cp` was taken: the later steps are those of an
    /// uninterrupted run, bit for bit, as far as the problem (and the sparse
    /// pattern it hands the factorization) is deterministic. The step
    /// counters continue from the checkpoint's; `cfg` should be the run's
    /// (a different `lambda_end` or `max_steps` is allowed).
    pub fn resume(problem: &'p mut P, cp: Checkpoint, cfg: ContinuationConfig) -> Self {
        Self::build(problem, cp, cfg)
    }

    fn build(problem: &'p mut P, cp: Checkpoint, cfg: ContinuationConfig) -> Self {
        let forward = if cfg.lambda_end >= cp.lambda {
            1.0
        } else {
            -1.0
        };
        let (metric, stopped) =
            match Metric::for_problem(&*problem, cfg.lambda_scale).and_then(|m| {
                if cp.u.len() == problem.ndof() {
                    Ok(m)
                } else {
                    Err(Error::Invalid {
                        file: Default::default(),
                        key: "u0".into(),
                        problem: format!("{} values for {} unknowns", cp.u.len(), problem.ndof()),
                    })
                }
            }) {
                Ok(m) => (m, None),
                Err(e) => (Metric::unit(), Some(Stop::Failed(e))),
            };
        let lu = LinearSolver::new(cfg.linear);
        Self {
            problem,
            cfg,
            metric,
            u: cp.u,
            lambda: cp.lambda,
            prev_dir: cp.prev_dir,
            prev_length: cp.prev_length,
            index: cp.index,
            forward,
            lu,
            stats: cp.stats,
            stopped,
        }
    }

    /// One accepted step, or why the path ended (`End` when the step before
    /// reached `lambda_end`, `MaxSteps` after `cfg.max_steps` steps in all,
    /// `Failed` on a numerical error). After a stop every further call
    /// returns the same stop (a failure's error is reproduced, not re-run).
    pub fn step(&mut self) -> std::result::Result<PathStep, Stop> {
        if let Some(s) = &self.stopped {
            return Err(s.clone());
        }
        let cfg = &self.cfg;
        let stop = if self.index > 0
            && (self.lambda - cfg.lambda_end) * self.forward
                >= -1e-14 * cfg.lambda_end.abs().max(1.0)
        {
            Some(Stop::End {
                lambda: self.lambda,
            })
        } else if self.index >= cfg.max_steps {
            Some(Stop::MaxSteps {
                steps: self.index,
                lambda: self.lambda,
            })
        } else {
            None
        };
        if let Some(s) = stop {
            self.stopped = Some(s.clone());
            return Err(s);
        }
        let start = Instant::now();
        let result = series_step(
            &mut *self.problem,
            &self.u,
            self.lambda,
            self.index,
            &self.cfg,
            &self.metric,
            &self.prev_dir,
            self.prev_length,
            self.forward,
            &mut self.lu,
            &mut self.stats,
        );
        charge(&mut self.stats.step_s, start);
        match result {
            Ok(step) => {
                self.stats.steps += 1;
                self.index += 1;
                self.u.clone_from(&step.u_end);
                self.lambda = step.lambda_end;
                self.prev_dir = Some((step.u[1].clone(), step.lambda[1]));
                self.prev_length = Some(step.length);
                Ok(step)
            }
            Err(e) => {
                let s = Stop::Failed(e);
                self.stopped = Some(s.clone());
                Err(s)
            }
        }
    }

    /// The state after the last accepted step.
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            index: self.index,
            u: self.u.clone(),
            lambda: self.lambda,
            prev_dir: self.prev_dir.clone(),
            prev_length: self.prev_length,
            stats: self.stats.clone(),
        }
    }

    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Gives the problem back (e.g. to start another path on it).
    pub fn into_problem(self) -> &'p mut P {
        self.problem
    }

    /// The problem (e.g. for output grid corrections between steps).
    pub fn problem(&mut self) -> &mut P {
        self.problem
    }

    /// Current (U, lambda): the end of the last accepted step.
    pub fn state(&self) -> (&[f64], f64) {
        (&self.u, self.lambda)
    }

    /// The scaled metric of the path.
    pub fn metric(&self) -> &Metric {
        &self.metric
    }

    /// Whether `lambda` (the end of the last step) has reached `lambda_end`.
    pub fn at_end(&self) -> bool {
        self.index > 0
            && (self.lambda - self.cfg.lambda_end) * self.forward
                >= -1e-14 * self.cfg.lambda_end.abs().max(1.0)
    }

    pub fn config(&self) -> &ContinuationConfig {
        &self.cfg
    }
}

/// Orders after which a piecewise-analytic problem looks for a kink within
/// EARLY_KINK_REACH times the ratio-rule length a_p of the orders so far
/// (super::kinks, "Few orders"). a_p is about eps^(1/(p-1)) times the
/// series' radius: order 3 reaches far past the mirrored nodes' kinks (a
/// ~ 1e-9). Measured on the penalty plate-cylinder (0.05 / 0.025 m,
/// solves of the run): all orders 777 / 2,261; after 3: 565 / 1,633;
/// 3, 6: 539 / 1,244; 3, 5, 8: 494 / 1,166; 3, 6, 10: 485 / 1,075.
const EARLY_KINK_ORDERS: [usize; 3] = [3, 6, 10];
/// At a_p itself the truncation error is eps: the residual test failed at
/// 34 step ends instead of 23 (0.025 m), so the kink must lie within a
/// quarter of it (order p: eps / 4^(p-1)), and a_p is taken at the
/// smaller of eps and the residual test's tolerance (at eps = 1e-4, N =
/// 20, with eps alone: 237 factorizations instead of 164 without early
/// kinks; with the smaller one: 168, and 1,099 solves instead of 2,979).
const EARLY_KINK_REACH: f64 = 0.25;

/// Largest share of the load in a geometric part (scaled |lambda_N| over
/// |T_N|) for which the part is taken as a bifurcated branch and removed
/// from the step ([`series_step`]).
const OFF_BRANCH_LOAD_SHARE: f64 = 1e-3;

/// The scaled terms T̃_p = (Ũ_p, λ̃_p, y_p) of orders 0..=p, each written
/// once into its own buffer, the orders on every thread.
fn stacked(metric: &Metric, us: &[Vec<f64>], ls: &[f64], ys: &[Vec<f64>]) -> Vec<Vec<f64>> {
    us.par_iter()
        .zip(ls)
        .zip(ys)
        .map(|((u, &l), y)| {
            let mut t = Vec::with_capacity(u.len() + 1 + y.len());
            metric.extend_scaled(u, &mut t);
            t.push(metric.l(l));
            t.extend_from_slice(y);
            t
        })
        .collect()
}

/// Ratio rule (eq. L) on the scaled terms of orders 0..=N:
/// a = (eps |T̃_1| / |T̃_N|)^(1/(N-1)), at most the cap
/// 1e15^(1/N) |T̃_1| / |T̃_1|_∞. Returns (a, cap).
///
/// The cap (for terms that vanish, e.g. on a linear problem) bounds the
/// first-order change of the largest scaled unknown, a |T̃_1|_∞, not the
/// arclength itself: the 2-norm of T̃_1 grows like the square root of the
/// number of unknowns that move, so a cap on a alone shortened the steps
/// of a refined mesh (strip-wrinkling on 993,243 unknowns: 10 of its 30
/// steps at a = 1e15^(1/15) = 10).
fn ratio_length(terms: &[Vec<f64>], eps: f64) -> (f64, f64) {
    let n = terms.len() - 1;
    let (n1, nn) = (norm(&terms[1]), norm(&terms[n]));
    let largest = terms[1].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let spread = if largest > 0.0 { n1 / largest } else { 1.0 };
    let cap = 1e15f64.powf(1.0 / n as f64) * spread;
    let a = if nn > 0.0 {
        (eps * n1 / nn).powf(1.0 / (n as f64 - 1.0)).min(cap)
    } else {
        cap
    };
    (a, cap)
}

/// x scaled by s.
fn scaled(x: &[f64], s: f64) -> Vec<f64> {
    x.iter().map(|v| s * v).collect()
}

/// One ANM step from (u0, lambda0) (module docs, items 1-5).
#[allow(clippy::too_many_arguments)]
pub(crate) fn series_step<P: ContinuationProblem + ?Sized>(
    problem: &mut P,
    u0: &[f64],
    lambda0: f64,
    index: usize,
    cfg: &ContinuationConfig,
    metric: &Metric,
    prev_dir: &Option<(Vec<f64>, f64)>,
    prev_length: Option<f64>,
    forward: f64,
    lu: &mut LinearSolver,
    stats: &mut Stats,
) -> Result<PathStep> {
    let n_ord = cfg.order;
    problem.reserve_orders(n_ord + 1);
    let t = Instant::now();
    let (kt, r_lambda) = problem.tangent(u0, lambda0)?;
    charge(&mut stats.assembly_s, t);
    // Order 1 (eq. O1): λ̃_1 = ±1/sqrt(1 + Lambda^2 |U_t|~^2); U_1 = lambda_1 U_t.
    // U_t = −Kt⁻¹ R_lambda is the solve that tests the factorization.
    let neg: Vec<f64> = r_lambda.iter().map(|x| -x).collect();
    let (fact, ut) = factorize_solve(lu, &kt, &neg, stats, index, lambda0)?;
    drop(neg);
    let finite = |x: Vec<f64>, what: &str| -> Result<Vec<f64>> {
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
    let solve = |b: &[f64], stats: &mut Stats, what: &str| -> Result<Vec<f64>> {
        let t = Instant::now();
        let neg: Vec<f64> = b.iter().map(|x| -x).collect();
        let x = Factorization::solve(&fact, &neg);
        stats.solves += 1;
        charge(&mut stats.solve_s, t);
        finite(x, what)
    };
    let ut = finite(ut, "order-1")?;
    // The problem's arc coordinates (none by default): y_t = dy/dlambda
    // along U_t; they join |Ũ_t|^2 in the normalization and every inner
    // product below.
    let arc = problem.arc_coordinates();
    let yt = arc.as_ref().map_or(vec![], |c| c.apply(&ut, 1.0));
    let big_l = metric.lambda_scale();
    let mut l1 = 1.0 / (1.0 + (metric.dot_u(&ut, &ut) + dot(&yt, &yt)) * (big_l * big_l)).sqrt();
    // Sign of <Ũ_1, Ũ_1'> + λ̃_1 λ̃_1' = (λ̃_1 / Lambda)(Lambda^2 <U_t, U_1'>~ + lambda_1').
    let orient = match prev_dir {
        Some((pu, pl)) => l1 * (metric.dot_u(&ut, pu) * (big_l * big_l) + pl),
        None => l1 * forward,
    };
    if orient < 0.0 {
        l1 = -l1;
    }
    let lambda1 = big_l * l1;
    let mut us = vec![
        u0.to_vec(),
        ut.iter().map(|x| lambda1 * x).collect::<Vec<_>>(),
    ];
    let mut ls = vec![lambda0, lambda1];
    let mut ys = vec![vec![0.0; yt.len()], scaled(&yt, lambda1)];
    let mut early_kink = None;
    // <U_t, U_1>~ + lambda_1 / Lambda^2 + <y_t, y_1> (eq. Op).
    let denom = metric.dot_u(&ut, &us[1]) + lambda1 * metric.lambda_weight() + dot(&yt, &ys[1]);
    for p in 2..=n_ord {
        let t = Instant::now();
        let rhs = problem.series_rhs(p, &us, &ls)?;
        // y_p = J U_b + y*_p + lambda_p y_t.
        let mut yb = match &arc {
            Some(_) => problem.arc_coordinates_rhs(p),
            None => vec![],
        };
        stats.series_terms += 1;
        charge(&mut stats.series_s, t);
        // The next order's inner terms, where the problem has some, on
        // another thread during this solve; the time the solve waits for
        // them is the series'.
        let ub = match (p < n_ord).then(|| problem.rhs_prepass(p + 1)).flatten() {
            None => solve(&rhs, stats, "order-p")?,
            Some(job) => {
                let t = Instant::now();
                let solve_before = stats.solve_s;
                let done = AtomicBool::new(false);
                let ub = rayon::in_place_scope(|s| {
                    let done = &done;
                    s.spawn(move |_| job(done));
                    let ub = solve(&rhs, stats, "order-p");
                    done.store(true, Ordering::Relaxed);
                    ub
                });
                stats.series_s += t.elapsed().as_secs_f64() - (stats.solve_s - solve_before);
                ub?
            }
        };
        if let Some(c) = &arc {
            for (y, j) in yb.iter_mut().zip(c.apply(&ub, 0.0)) {
                *y += j;
            }
        }
        let lp = -(metric.dot_u(&ub, &us[1]) + dot(&yb, &ys[1])) / denom;
        us.push(ub.iter().zip(&ut).map(|(b, t)| b + lp * t).collect());
        ls.push(lp);
        ys.push(yb.iter().zip(&yt).map(|(b, t)| b + lp * t).collect());
        // A kink closer than the ratio-rule length of the orders so far:
        // the higher orders would not be used (super::kinks, "Few orders").
        if problem.kinks() && p < n_ord && EARLY_KINK_ORDERS.contains(&p) {
            let tol = cfg.eps.min(cfg.residual_tol);
            let (a_p, _) = ratio_length(&stacked(metric, &us, &ls, &ys), tol);
            let reach = EARLY_KINK_REACH * a_p;
            if let Some(a) = kinks::within_orders(problem, &us, &ls, reach)? {
                early_kink = Some(a);
                break;
            }
        }
    }
    // The orders computed: all, or fewer before a near kink.
    let n_ord = us.len() - 1;
    // Step length (eq. L): ratio rule on the scaled terms T̃_p = (Ũ_p, λ̃_p, y_p).
    let terms = stacked(metric, &us, &ls, &ys);
    let n1 = norm(&terms[1]);
    let nn = norm(&terms[n_ord]);
    if !(n1.is_finite() && nn.is_finite()) {
        return Err(Error::NonFinite {
            step: index,
            param: "lambda",
            at: lambda0,
            what: format!("series terms (|U_1| = {n1:e}, |U_{n_ord}| = {nn:e}, scaled)"),
        });
    }
    // Truncated before a kink, the step ends there: no tail to test.
    let mut geometric = if early_kink.is_some() {
        None
    } else {
        geometric::detect(&terms)
    };
    // A geometric series in the last terms is a singular point ahead at
    // a = alpha_1. Where it moves the load by (almost) nothing, it is the
    // null direction of a nearly singular tangent at fixed load, seeded by
    // round-off and amplified order by order: a bifurcated branch, not the
    // one the path is on. The step then follows the series with it removed
    // (Cochelin & Medale 2013, §3.2: T_p − alpha_1^(N−p) T_N, p < N),
    // whose radius reaches past the point: it stays on its branch where
    // steps shrinking toward the point let the amplified part take the
    // path onto the other one (review 14: a pinned arch went round the
    // whole asymmetric loop, labelled "primary"). A geometric part that
    // moves the load is the path's own singularity (a contact law's switch:
    // load share 0.99 of the part on the spring of tests/contact; 1.5e-10
    // to 2.2e-6 on the arch's bifurcations) and is kept.
    let mut singular_mode = vec![];
    let terms = match geometric.as_mut() {
        Some(g) if metric.l(ls[n_ord]).abs() <= OFF_BRANCH_LOAD_SHARE * norm(&terms[n_ord]) => {
            let un = us.pop().expect("order N");
            let ln = ls.pop().expect("order N");
            let yn = ys.pop().expect("order N");
            for p in 1..n_ord {
                let w = g.distance.powi((n_ord - p) as i32);
                us[p].iter_mut().zip(&un).for_each(|(x, v)| *x -= w * v);
                ls[p] -= w * ln;
                ys[p].iter_mut().zip(&yn).for_each(|(x, v)| *x -= w * v);
            }
            g.lambda = super::taylor::eval(&ls, g.distance);
            let s = norm(&un).max(f64::MIN_POSITIVE);
            singular_mode = un.iter().map(|v| v / s).collect();
            stacked(metric, &us, &ls, &ys)
        }
        _ => terms,
    };
    let n_ord = us.len() - 1;
    let (a_poly, cap) = ratio_length(&terms, cfg.eps);
    let mut step = PathStep {
        index,
        u: us,
        lambda: ls,
        length: a_poly,
        a_poly,
        pade: None,
        geometric,
        singular_mode,
        end_residual: 0.0,
        u_end: vec![],
        lambda_end: 0.0,
        negative_pivots: fact.inertia().map(|i| i.0),
        jump: None,
    };
    // Padé on the scaled terms: its denominators are those of the scaled
    // series, and the approximant is linear in the terms, so that
    // `PathStep::eval` applies it to the terms in the problem's units.
    if cfg.pade
        && early_kink.is_none()
        && let Some((a, pn)) = pade::range(&terms, n_ord, cfg.eps, a_poly, cap.min(10.0 * a_poly))
        && a > a_poly
    {
        step.pade = Some(pn);
        step.length = a;
    }
    drop(terms);
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
    // A piecewise-analytic problem: end just past the first kink (the
    // series are not valid beyond it).
    // (Found already among fewer orders: the first kink, within a quarter
    // of a_p, the length before any cut.)
    let kink = match early_kink {
        Some(a) => (a <= step.length).then_some(a),
        None if problem.kinks() => kinks::first_kink(problem, &step)?,
        None => None,
    };
    if let Some(a) = kink {
        step.length = a;
        stats.kink_cuts += 1;
    }
    let scale = super::correct::force_scale(&*problem, metric, &r_lambda);
    // An event within reach: cross it by a corrected jump (super::events).
    if cfg.events
        && let Some(crossing) = events::locate(problem, &step)?
        && let Some(j) = events::jump(
            problem,
            &step,
            crossing,
            prev_length,
            cfg,
            metric,
            scale,
            lu,
            stats,
        )?
    {
        return Ok(j);
    }
    // Step end: accept when the residual is small; correct when it is
    // moderately large; otherwise (or when the correction fails) the step
    // length overestimated the series' validity (e.g. a contact node closing
    // within the step): halve it. Halving costs residual evaluations only;
    // correcting from far off the path can converge onto another branch.
    let snap = 1e-9 * cfg.lambda_scale;
    let mut first = true;
    loop {
        let (u_end, mut l_end) = step.eval(step.length);
        // A step that ends on lambda_end (its length was cut to reach it)
        // is corrected at that load: the arclength correction could move
        // its end past lambda_end (1.4e-8 measured on plate-cylinder-coarse,
        // N = 10, eps 1e-4), and the run would end off its last grid value.
        let at_end = (l_end - cfg.lambda_end).abs() < snap;
        if at_end {
            l_end = cfg.lambda_end;
        }
        // Arclength-constrained correction <dŨ, Ũ_1> + dλ̃ λ̃_1 = 0: modified
        // Newton with the step's factorization while it contracts by 10x per
        // iteration, else refactorized at the iterate. A start residual above
        // CORRECTABLE is not corrected.
        let settings = Settings {
            tol: cfg.residual_tol,
            max_iter: if cfg.correct { cfg.max_corrections } else { 0 },
            jacobian: Jacobian::Reuse {
                initial: Some((&fact, &ut)),
                contraction: 0.1,
                scale,
            },
            max_residual: CORRECTABLE,
            line_search: false,
            step: index,
        };
        let constraint = if at_end {
            Constraint::FixedLambda
        } else {
            Constraint::Arclength {
                t_u: &step.u[1],
                t_lambda: step.lambda[1],
                reference: None,
            }
        };
        let mut start_residual = f64::NAN;
        let attempt = correct::correct_noting_start(
            problem,
            u_end,
            l_end,
            &constraint,
            &settings,
            metric,
            lu,
            stats,
            &mut start_residual,
        );
        if first {
            // NaN where the end's residual was refused (a contact node
            // missed): steps.csv leaves the field empty.
            step.end_residual = start_residual;
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

/// Relative residual |R| / |R_lambda| above which a step end is not corrected
/// but the step shortened: a point this far off the path is outside the
/// series' validity, and Newton from it may land on another branch.
const CORRECTABLE: f64 = 1.0;

/// serde helpers: f64 values as their IEEE-754 bit patterns (exact round trip).
mod bits {
    pub mod scalar {
        use serde::{Deserialize, Deserializer, Serializer};
        pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
            s.serialize_u64(x.to_bits())
        }
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
            Ok(f64::from_bits(u64::deserialize(d)?))
        }
    }
    pub mod vec {
        use serde::{Deserialize, Deserializer, Serialize, Serializer};
        pub fn serialize<S: Serializer>(x: &[f64], s: S) -> Result<S::Ok, S::Error> {
            x.iter()
                .map(|v| v.to_bits())
                .collect::<Vec<u64>>()
                .serialize(s)
        }
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
            Ok(Vec::<u64>::deserialize(d)?
                .into_iter()
                .map(f64::from_bits)
                .collect())
        }
    }
    pub mod opt {
        use serde::{Deserialize, Deserializer, Serialize, Serializer};
        pub fn serialize<S: Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
            x.map(|v| v.to_bits()).serialize(s)
        }
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
            Ok(Option::<u64>::deserialize(d)?.map(f64::from_bits))
        }
    }
    pub mod dir {
        use serde::{Deserialize, Deserializer, Serialize, Serializer};
        #[allow(clippy::type_complexity)]
        pub fn serialize<S: Serializer>(
            x: &Option<(Vec<f64>, f64)>,
            s: S,
        ) -> Result<S::Ok, S::Error> {
            x.as_ref()
                .map(|(u, l)| {
                    (
                        u.iter().map(|v| v.to_bits()).collect::<Vec<u64>>(),
                        l.to_bits(),
                    )
                })
                .serialize(s)
        }
        #[allow(clippy::type_complexity)]
        pub fn deserialize<'de, D: Deserializer<'de>>(
            d: D,
        ) -> Result<Option<(Vec<f64>, f64)>, D::Error> {
            Ok(Option::<(Vec<u64>, u64)>::deserialize(d)?.map(|(u, l)| {
                (
                    u.into_iter().map(f64::from_bits).collect(),
                    f64::from_bits(l),
                )
            }))
        }
    }
}

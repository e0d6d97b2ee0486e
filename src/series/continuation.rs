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
//! Every norm and inner product above is the scaled one of
//! [`super::correct::Metric`] (unknowns over [`ContinuationProblem::unknown_scale`],
//! lambda over [`ContinuationConfig::lambda_scale`]); [`super::path`] has the
//! step in detail, [`super::correct`] the step-end correction.

use super::geometric::GeometricSeries;
use super::pade;
use super::path::Path;
use super::stats::Stats;
use super::stop::Stop;
use crate::error::{Error, Result};
use crate::linalg::{Choice, Factorization, LinearSolver, SparseMatrix};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Work toward the next series order, run during a solve
/// ([`ContinuationProblem::rhs_prepass`]); its argument is set once the
/// solve is done.
pub type Prepass<'a> = Box<dyn FnOnce(&AtomicBool) + Send + 'a>;

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
    /// Work toward `series_rhs(p, ..)` that reads only orders up to p − 2
    /// (default: none), to run on another thread while the engine solves
    /// for order p − 1: the engine starts it after `series_rhs(p − 1, ..)`
    /// and waits for it before `series_rhs(p, ..)`, and the problem is not
    /// touched meanwhile. A job that was not run, or was run for another
    /// order, must leave `series_rhs` correct. The engine sets `done` when
    /// its solve is over: the job may stop there and leave the rest to
    /// `series_rhs` (which runs on every thread).
    fn rhs_prepass(&mut self, _p: usize) -> Option<Prepass<'_>> {
        None
    }
    /// The magnitude m_i that the state behind unknown i is held to in
    /// floating point (e.g. the distance of a node from the origin for a
    /// translation, 1 for a director increment), or None (the default): a
    /// Newton update with |du_i| <= 16 ε m_i for every i cannot change the
    /// state, and the corrector stops at that round-off floor when the
    /// residual no longer falls ([`super::correct`]).
    fn resolution(&self, _u: &[f64], _lambda: f64) -> Option<Vec<f64>> {
        None
    }
    /// Characteristic magnitude s_i of each unknown (default: all 1.0): e.g.
    /// a length of the model for displacements, 1 for rotations or director
    /// increments. The engine measures step lengths, series norms, Padé
    /// ranges and the orthogonality conditions in u_i / s_i
    /// ([`super::correct::Metric`]), so that the same problem written in
    /// other units takes the same steps. Every s_i must be finite and > 0.
    fn unknown_scale(&self) -> Vec<f64> {
        vec![1.0; self.ndof()]
    }
    /// Event functions g_k(U, lambda) (default: none): the problem's
    /// behaviour switches at g_k = 0 within a band |g_k| of order 1 (e.g. a
    /// regularized contact law closing), which the engine crosses by a
    /// corrected jump instead of short steps ([`super::events`]). The same
    /// number of values, in the same order, at every state of a run.
    fn events(&self, _u: &[f64], _lambda: f64) -> Result<Vec<f64>> {
        Ok(vec![])
    }
    /// Whether the problem is only piecewise analytic, its pieces meeting
    /// where an event function changes sign (default: no): the engine then
    /// ends each step just past the first event function that leaves its
    /// band |g| <= 1 on the other side of its start ([`super::kinks`]).
    fn kinks(&self) -> bool {
        false
    }
    /// A force per unit lambda that drives the path where dR/dlambda is
    /// exactly zero (default: none): the residual test's scale there
    /// ([`super::correct::force_scale`]). A shell pushed only by a moving
    /// obstacle under the penalty law has no dR/dlambda before it touches.
    fn drive_floor(&self) -> Option<Vec<f64>> {
        None
    }
    /// The unknowns that [`Self::events`] reads (default: all). The kink
    /// search evaluates only these on the step's series, dozens of times
    /// per step: events must not read any other entry of `u`.
    fn event_unknowns(&self) -> Option<Vec<usize>> {
        None
    }
    /// The number of series orders (N + 1) the steps will compute, told
    /// before each step's tangent: a problem may size its series buffers
    /// once instead of growing them order by order (default: ignored).
    fn reserve_orders(&mut self, _orders: usize) {}
    /// Extra coordinates y(U, lambda) of the path parameter (default:
    /// none), linearized at the state of the last [`Self::tangent`] call.
    /// The step then measures its pseudo-arclength in (Ũ, λ̃, y) ([`super::path`]):
    /// a coordinate that changes fast where U and lambda hardly move (the
    /// logarithm of a contact reaction through the switch of its law)
    /// spreads that stretch of the path over an O(1) range of a.
    fn arc_coordinates(&mut self) -> Option<ArcCoordinates> {
        None
    }
    /// Coefficient p >= 2 of y(U(a), lambda(a)) with U_p = 0 and
    /// lambda_p = 0, called after [`Self::series_rhs`] of the same order
    /// (only when [`Self::arc_coordinates`] gave some).
    fn arc_coordinates_rhs(&mut self, _p: usize) -> Vec<f64> {
        vec![]
    }
}

/// The linear part of the problem's arc coordinates y at the step start:
/// y_p = J U_p + y_lambda lambda_p + y*_p at every order p >= 1.
#[derive(Clone, Debug, Default)]
pub struct ArcCoordinates {
    /// The rows of J = dy/dU, as (unknown, value) pairs.
    pub rows: Vec<Vec<(usize, f64)>>,
    /// dy/dlambda at fixed U.
    pub lambda: Vec<f64>,
}

impl ArcCoordinates {
    /// J u + y_lambda l.
    pub fn apply(&self, u: &[f64], l: f64) -> Vec<f64> {
        self.rows
            .iter()
            .zip(&self.lambda)
            .map(|(row, yl)| row.iter().fold(yl * l, |s, &(j, v)| s + v * u[j]))
            .collect()
    }
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
    /// Smallest admissible step length (scaled arclength) before the run
    /// stops as collapsed.
    pub min_step: f64,
    /// Characteristic range Lambda of the load parameter: the engine measures
    /// lambda / Lambda (with the unknowns over their `unknown_scale`). Set it
    /// to |lambda_end - lambda0| for steps independent of how lambda is
    /// normalized; default 1.
    pub lambda_scale: f64,
    /// Linear-solver backend: chosen per tangent (default) or forced.
    pub linear: Choice,
    /// Cross the problem's events ([`ContinuationProblem::events`]) by
    /// corrected jumps ([`super::events`]); off (default): by ordinary
    /// steps. Off by default: on plate-cylinder the jumps' Newton
    /// corrections converge too slowly across the contact law's corner
    /// (README, "plate-cylinder: ANM against Newton-Raphson").
    pub events: bool,
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
            lambda_scale: 1.0,
            linear: Choice::Auto,
            events: false,
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
    /// Step length a actually taken (scaled pseudo-arclength, see
    /// [`super::path`]).
    pub length: f64,
    /// Validity range of the polynomial series, a_max.
    pub a_poly: f64,
    /// Evaluate with Padé instead of the polynomial.
    pub pade: Option<pade::Pade>,
    /// Geometric series found in the last terms (Cochelin-Medale test);
    /// `u` and `lambda` then hold the series with it removed (one order
    /// less) and `singular_mode` its direction U_N / |U_N|.
    pub geometric: Option<GeometricSeries>,
    pub singular_mode: Vec<f64>,
    /// Relative residual at the step end, before any correction.
    pub end_residual: f64,
    /// End point after correction.
    pub u_end: Vec<f64>,
    pub lambda_end: f64,
    /// Negative pivots of the step-start tangent (its number of negative
    /// eigenvalues) when it was factored symmetrically.
    pub negative_pivots: Option<usize>,
    /// The event crossed by this step, when it is a jump
    /// ([`super::events`]): the step is then the chord to the corrected end.
    pub jump: Option<super::events::Crossing>,
}

impl PathStep {
    /// (U(a), lambda(a)) from the step's representation (polynomial or Padé).
    pub fn eval(&self, a: f64) -> (Vec<f64>, f64) {
        match &self.pade {
            Some(p) => {
                // The Padé weights apply to U and lambda apart (no stacked
                // copy of the terms: 128 MB per call at 1e6 unknowns).
                let inc = p.eval(&self.u, a);
                let u = self.u[0].iter().zip(&inc).map(|(x, d)| x + d).collect();
                (u, self.lambda_at(a))
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

    /// A step given by its series alone (polynomial, no end point yet):
    /// orders 0..N of U and lambda, valid over (0, length].
    pub fn from_series(u: Vec<Vec<f64>>, lambda: Vec<f64>, length: f64) -> Self {
        PathStep {
            index: 0,
            u,
            lambda,
            length,
            a_poly: length,
            pade: None,
            geometric: None,
            singular_mode: vec![],
            end_residual: 0.0,
            u_end: vec![],
            lambda_end: 0.0,
            negative_pivots: None,
            jump: None,
        }
    }

    /// [`PathStep::eval`] at the unknowns `idx` only, written into `u`
    /// (its other entries untouched; the same values, bit for bit);
    /// returns lambda(a).
    pub fn eval_at(&self, a: f64, idx: &[usize], u: &mut [f64]) -> f64 {
        match &self.pade {
            Some(p) => {
                let w = p.weights(a);
                for &i in idx {
                    let mut inc = 0.0;
                    for (f, t) in w.iter().zip(&self.u[1..]) {
                        inc += f * t[i];
                    }
                    u[i] = self.u[0][i] + inc;
                }
                self.lambda_at(a)
            }
            None => {
                for &i in idx {
                    u[i] = self.u.iter().rev().fold(0.0, |acc, t| acc * a + t[i]);
                }
                super::taylor::eval(&self.lambda, a)
            }
        }
    }

    /// lambda(a) alone, from the step's representation (polynomial or
    /// Padé): O(N), whatever the number of unknowns.
    pub fn lambda_at(&self, a: f64) -> f64 {
        match &self.pade {
            Some(p) => {
                let inc = p
                    .weights(a)
                    .iter()
                    .zip(&self.lambda[1..])
                    .fold(0.0, |s, (f, l)| s + f * l);
                self.lambda[0] + inc
            }
            None => super::taylor::eval(&self.lambda, a),
        }
    }

    /// Path parameter a at which lambda(a) = target, if it lies in [0, length]
    /// (Newton on the series, started by bisection-safe bracketing).
    pub fn a_at_lambda(&self, target: f64) -> Option<f64> {
        // lambda alone: bisection evaluates it 100 times.
        let f = |a: f64| self.lambda_at(a) - target;
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

    /// Whether lambda(a) of the step's representation (the polynomial, or
    /// its Padé approximant when the step uses one: the λ(a) that the
    /// output grid reads) is monotone over [0, length] (sampled at 32
    /// points): false where the step turns back through a limit point of
    /// lambda. (Reading the polynomial on a Padé step, whose length can
    /// exceed the polynomial's range, saw a turn that was not there, and an
    /// output value at the step's uncorrected end was reported twice.)
    pub fn lambda_is_monotone(&self) -> bool {
        let k = 32;
        let l: Vec<f64> = (0..=k)
            .map(|i| self.lambda_at(self.length * i as f64 / k as f64))
            .collect();
        l.windows(2).all(|w| w[1] >= w[0]) || l.windows(2).all(|w| w[1] <= w[0])
    }

    /// Every a in (0, length] where lambda(a) = target, in increasing order:
    /// the states at a lambda on a step that turns back through a limit
    /// point (32 samples, bisection on each sign change).
    pub fn a_at_lambda_all(&self, target: f64) -> Vec<f64> {
        let f = |a: f64| self.lambda_at(a) - target;
        let k = 32;
        let mut out = vec![];
        let mut a0 = 0.0;
        let mut f0 = f(0.0);
        for i in 1..=k {
            let a1 = self.length * i as f64 / k as f64;
            let f1 = f(a1);
            if f1 == 0.0 {
                out.push(a1);
            } else if f0 != 0.0 && f0.signum() != f1.signum() {
                let (mut lo, mut hi) = (a0, a1);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if f(mid).signum() == f0.signum() {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                out.push(0.5 * (lo + hi));
            }
            a0 = a1;
            f0 = f1;
        }
        out
    }
}

/// Result of a continuation run.
#[derive(Debug)]
pub struct PathResult {
    pub stats: Stats,
    /// Why the run stopped ([`Stop::reason`] is the string form: "end",
    /// "max_steps", or an error kind).
    pub stop: Stop,
    /// End of the last accepted step.
    pub u_end: Vec<f64>,
    pub lambda_end: f64,
}

impl PathResult {
    /// The error that stopped the run, if any.
    pub fn error(&self) -> Option<&Error> {
        self.stop.error()
    }
}

/// Follows the path from (u0, lambda0) toward `cfg.lambda_end`. `on_step` is
/// called with every accepted step (outputs, progress); returning an error
/// from it stops the run (`Stop::Failed` with that error). A thin loop over
/// [`Path`]: callers that need to stop, checkpoint or resume drive a `Path`
/// themselves.
pub fn run<P: ContinuationProblem>(
    problem: &mut P,
    u0: Vec<f64>,
    lambda0: f64,
    cfg: &ContinuationConfig,
    mut on_step: impl FnMut(&PathStep, &Stats) -> Result<()>,
) -> PathResult {
    let mut path = Path::new(problem, u0, lambda0, cfg.clone());
    let stop = loop {
        match path.step() {
            Ok(step) => {
                if let Err(e) = on_step(&step, path.stats()) {
                    break Stop::Failed(e);
                }
            }
            Err(stop) => break stop,
        }
    };
    let (u, lambda) = path.state();
    PathResult {
        stats: path.stats().clone(),
        stop,
        u_end: u.to_vec(),
        lambda_end: lambda,
    }
}

/// Factorizes a tangent, counting and timing it; a failure becomes a
/// singular-matrix error at (step, lambda).
pub(crate) fn factorize(
    lu: &mut LinearSolver,
    k: &SparseMatrix,
    stats: &mut Stats,
    step: usize,
    lambda: f64,
) -> Result<Factorization> {
    factorize_with(lu, k, None, stats, step, lambda).map(|(f, _)| f)
}

/// [`factorize`] and the solve of K x = b, which tests the factorization
/// ([`LinearSolver::factorize_solve`]); the solve is counted and timed as a
/// solve.
pub(crate) fn factorize_solve(
    lu: &mut LinearSolver,
    k: &SparseMatrix,
    b: &[f64],
    stats: &mut Stats,
    step: usize,
    lambda: f64,
) -> Result<(Factorization, Vec<f64>)> {
    let (f, x) = factorize_with(lu, k, Some(b), stats, step, lambda)?;
    Ok((f, x.expect("solved with b")))
}

fn factorize_with(
    lu: &mut LinearSolver,
    k: &SparseMatrix,
    b: Option<&[f64]>,
    stats: &mut Stats,
    step: usize,
    lambda: f64,
) -> Result<(Factorization, Option<Vec<f64>>)> {
    let t = Instant::now();
    let before = lu.stats().fallbacks;
    let singular = |detail| Error::SingularMatrix {
        step,
        param: "lambda",
        at: lambda,
        detail,
    };
    let (f, x) = match b {
        Some(b) => lu.factorize_solve(k, b).map(|(f, x)| (f, Some(x))),
        None => lu.factorize(k).map(|f| (f, None)),
    }
    .map_err(singular)?;
    stats
        .linear
        .record(&f, lu.stats().fallbacks - before, lu.stats());
    stats.factorizations += 1;
    let mut total = t.elapsed().as_secs_f64();
    if x.is_some() {
        stats.solves += 1;
        stats.solve_s += f.caller_solve_seconds();
        total -= f.caller_solve_seconds();
    }
    stats.factorization_s += total;
    Ok((f, x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step whose lambda(a) = a - a^2 turns back at a = 0.5 (a limit
    /// point): lambda = 0.21 is met twice, at a = 0.3 and 0.7.
    #[test]
    fn every_crossing_of_a_lambda_is_found_on_a_step_that_turns_back() {
        let step = PathStep {
            index: 0,
            u: vec![vec![0.0], vec![1.0], vec![0.0]],
            lambda: vec![0.0, 1.0, -1.0],
            length: 1.0,
            a_poly: 1.0,
            pade: None,
            geometric: None,
            singular_mode: vec![],
            end_residual: 0.0,
            u_end: vec![1.0],
            lambda_end: 0.0,
            negative_pivots: None,
            jump: None,
        };
        assert!(!step.lambda_is_monotone());
        let a = step.a_at_lambda_all(0.21);
        assert_eq!(a.len(), 2, "{a:?}");
        assert!(
            (a[0] - 0.3).abs() < 1e-12 && (a[1] - 0.7).abs() < 1e-12,
            "{a:?}"
        );
        assert!(step.a_at_lambda_all(0.3).is_empty());
        let mono = PathStep {
            lambda: vec![0.0, 1.0, 0.0],
            ..step.clone()
        };
        assert!(mono.lambda_is_monotone());
        assert_eq!(mono.a_at_lambda_all(0.25).len(), 1);
    }

    /// `eval_at` gives `eval`'s values bit for bit at the unknowns asked,
    /// polynomial and Padé, and leaves the others alone.
    #[test]
    fn eval_at_some_unknowns_matches_eval() {
        // u_i(a) = sum_p c_i^p a^p with c_i = 0.3 (i + 1) / (i + 2): radius
        // (i + 2) / (0.3 (i + 1)), a geometric series Padé represents.
        let n_ord = 8;
        let u: Vec<Vec<f64>> = (0..=n_ord)
            .map(|p| {
                (0..5)
                    .map(|i| (0.3 * (i + 1) as f64 / (i + 2) as f64).powi(p as i32))
                    .collect()
            })
            .collect();
        let lambda: Vec<f64> = (0..=n_ord).map(|p| 0.5f64.powi(p as i32)).collect();
        let mut terms = u.clone();
        for (t, l) in terms.iter_mut().zip(&lambda) {
            t.push(*l);
        }
        let pade = pade::range(&terms, n_ord, 1e-12, 0.1, 1.0).map(|p| p.1);
        assert!(pade.is_some());
        for pade in [None, pade] {
            let step = PathStep {
                pade,
                ..PathStep::from_series(u.clone(), lambda.clone(), 1.0)
            };
            for a in [0.0, 0.37, 1.0] {
                let (full, l) = step.eval(a);
                let mut some = vec![-7.0; 5];
                let l_at = step.eval_at(a, &[1, 3], &mut some);
                assert_eq!(l_at.to_bits(), l.to_bits());
                for i in 0..5 {
                    let want = if i == 1 || i == 3 { full[i] } else { -7.0 };
                    assert_eq!(some[i].to_bits(), want.to_bits(), "a = {a}, u_{i}");
                }
            }
        }
    }
}

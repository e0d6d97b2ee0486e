//! Taylor series in time for semi-explicit index-1 DAEs (DESIGN §2; paper
//! §3.2, eqs. 8–9).
//!
//! F(u, v, z, t) = 0 with v = du/dt: u are the differential unknowns, z the
//! algebraic ones, and dF/d(v, z) must be invertible (index 1). With a = t - t0,
//! u = sum u_p a^p, v = sum v_p a^p, z = sum z_p a^p and eq. (9)
//! v_p = (p + 1) u_{p+1}, order p proceeds as:
//!   u_p = v_{p-1} / p (known),   J (v_p, z_p) = -F_p|_{v_p = z_p = 0},
//! with J = dF/d(v, z) factorized once at the step start. The right-hand side is
//! propagated incrementally on a [`Tape`]; because F_p is affine in (v_p, z_p)
//! with matrix J, the solve is exact, and the defect F_p after it is checked.

use super::stats::{Stats, charge};
use super::tape::{Tangents, Tape, TapeBuilder, Var};
use super::taylor;
use crate::error::{Error, Result};
use crate::linalg::{DenseLu, norm};
use std::time::Instant;

mod implicit;

/// A semi-explicit index-1 DAE written once with tape arithmetic.
pub trait DaeProblem {
    /// Number of differential unknowns u (each with its velocity v).
    fn n_diff(&self) -> usize;
    /// Number of algebraic unknowns z.
    fn n_alg(&self) -> usize;
    /// Records the n_diff + n_alg residuals F(u, v, z, t).
    fn record<'a>(
        &self,
        b: &'a TapeBuilder,
        u: &[Var<'a>],
        v: &[Var<'a>],
        z: &[Var<'a>],
        t: Var<'a>,
    ) -> Vec<Var<'a>>;
    /// Names of u, v and z for outputs and diagnostics.
    fn names(&self) -> Vec<String>;
}

/// How the order 0 of the first step is obtained.
#[derive(Clone, Debug)]
pub enum Initialization {
    /// Damped Newton on F(u0, v, z, t0) = 0 for (v, z) from a guess.
    Newton { v: Vec<f64>, z: Vec<f64> },
    /// Exact initial values given by the user; only checked.
    Exact { v: Vec<f64>, z: Vec<f64> },
}

#[derive(Clone, Debug)]
pub struct DaeConfig {
    pub order: usize,
    pub eps: f64,
    pub t0: f64,
    pub t_end: f64,
    pub max_steps: usize,
    /// Absolute tolerance of the Newton initialization and corrections,
    /// relative to the residual scale.
    pub newton_tol: f64,
    /// Correct (v, z) by Newton at the step end when |F| exceeds `residual_tol`.
    pub correct: bool,
    pub residual_tol: f64,
    /// A step shorter than this means the solution ceased to be smooth: the
    /// run stops with reason "singularity".
    pub min_step: f64,
    /// Stop at the first singular point the series reveals (geometric-series
    /// test); otherwise record it as an event and go on with the step.
    pub stop_at_singularity: bool,
    /// Explicit series, its Padé approximants, implicit (backward) series,
    /// or chosen per step.
    pub stepping: Stepping,
    /// Times (increasing) where the caller evaluates the solution: inside
    /// an implicit step they are solved for by a shorter implicit step from
    /// the same start ([`TimeStep::points`]).
    pub output_times: Vec<f64>,
    /// Speed (largest |v| of a step end) beyond which the path has left the
    /// quasi-static regime: the regularized dynamics jumping across the
    /// end of the quasi-static solution (a breakdown). The run stops before
    /// the step that reaches it. `f64::INFINITY`: no limit.
    pub speed_limit: f64,
}

/// How a time step uses the series ([`implicit`] argues the choice).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stepping {
    /// The series at the step start, evaluated forward (eqs. 8–9): its
    /// length is bounded by the fastest time constant.
    Explicit,
    /// The series at the step start, continued by its common-denominator
    /// Padé approximants of orders N and N-1 while they agree to eps
    /// (`pade.rs`).
    Pade,
    /// The series at the step end, evaluated backward to the step start
    /// (implicit Taylor step): stable on fast decaying modes.
    Implicit,
    /// Explicit where the series at the step start is not limited by a
    /// fast mode or where it is as cheap, implicit otherwise; decided per step.
    Auto,
}

impl Stepping {
    pub fn name(self) -> &'static str {
        match self {
            Stepping::Explicit => "explicit",
            Stepping::Pade => "pade",
            Stepping::Implicit => "implicit",
            Stepping::Auto => "auto",
        }
    }
}

/// One accepted time step.
#[derive(Clone, Debug)]
pub struct TimeStep {
    pub index: usize,
    pub t0: f64,
    pub length: f64,
    /// Expansion point of `series`: t0 for an explicit step, t0 + length
    /// for an implicit one (the series at the step end, evaluated backward).
    pub origin: f64,
    /// Whether the step is implicit ([`implicit`]).
    pub implicit: bool,
    /// Dense output of an implicit step: per unknown, a polynomial in
    /// s = (t - t0)/length (two-point Hermite, [`implicit`]).
    pub dense: Option<Vec<Vec<f64>>>,
    /// Inside an implicit step, at the output times: (t, y, dy/dt) from an
    /// implicit step t0 -> t (exact to the step's tolerance, unlike `dense`).
    pub points: Vec<(f64, Vec<f64>, Vec<f64>)>,
    /// The Padé approximants that replace the polynomial (Stepping::Pade).
    pub pade: Option<Vec<super::time_pade::ScalarPade>>,
    /// Series of the inputs u (n_diff), v (n_diff), z (n_alg), in that order,
    /// in powers of t - origin.
    pub series: Vec<Vec<f64>>,
    /// |F| at the step end before correction.
    pub end_residual: f64,
    /// Distance to a singularity when the last terms form a geometric
    /// series (Cochelin-Medale test on (u, v, z)).
    pub geometric: Option<f64>,
}

impl TimeStep {
    /// (u, v, z) at time t in [t0, t0 + length].
    pub fn eval(&self, t: f64) -> Vec<f64> {
        if let Some(p) = &self.pade {
            return p.iter().map(|p| p.eval(t - self.origin)).collect();
        }
        if let Some(p) = self.point(t) {
            return p.1.clone();
        }
        if let Some(d) = &self.dense {
            // The end point itself exactly: the next step starts there.
            if t >= self.t0 + self.length {
                return self.series.iter().map(|c| c[0]).collect();
            }
            let s = (t - self.t0) / self.length;
            return d.iter().map(|c| taylor::eval(c, s)).collect();
        }
        self.series
            .iter()
            .map(|c| taylor::eval(c, t - self.origin))
            .collect()
    }

    /// The point of [`TimeStep::points`] at time t, if any.
    fn point(&self, t: f64) -> Option<&(f64, Vec<f64>, Vec<f64>)> {
        self.points
            .iter()
            .find(|p| (p.0 - t).abs() <= 1e-13 * t.abs().max(1.0))
    }

    /// dy/dt of every series at time t in [t0, t0 + length].
    pub fn eval_derivative(&self, t: f64) -> Vec<f64> {
        if let Some(p) = self.point(t) {
            return p.2.clone();
        }
        if let Some(d) = &self.dense {
            let s = (t - self.t0) / self.length;
            return d
                .iter()
                .map(|c| taylor::eval_derivative(c, s) / self.length)
                .collect();
        }
        if self.pade.is_some() {
            // Central difference of the approximant (outputs only).
            let d = 1e-6 * self.length;
            let (a, b) = (self.eval(t + d), self.eval(t - d));
            return a.iter().zip(b).map(|(x, y)| (x - y) / (2.0 * d)).collect();
        }
        self.series
            .iter()
            .map(|c| taylor::eval_derivative(c, t - self.origin))
            .collect()
    }
}

/// How a DAE run ended.
#[derive(Debug)]
pub struct DaeResult {
    pub stats: Stats,
    /// "end", "singularity", "max_steps" or an error kind.
    pub stop: String,
    /// Time of the stop: for a singularity, the start of the step whose
    /// series revealed it (the last regular point).
    pub t: f64,
    /// Located singular point: t0 + alpha_1 from the geometric-series test.
    pub t_singular: Option<f64>,
    /// Where the path, followed on from a singular point without output to
    /// see whether it gets past ([`singular_ahead`]), took a step shorter
    /// than `min_step` (a fast transient the explicit steps cannot resolve
    /// at that order, or the singular point itself).
    pub collapse_ahead: Option<f64>,
    /// Every step whose series was geometric: (t0, located singular point).
    pub events: Vec<(f64, f64)>,
    /// A step (or a step followed on by [`singular_ahead`]) whose end moved
    /// faster than `DaeConfig::speed_limit`: (its end time, its speed).
    pub jump: Option<(f64, f64)>,
    pub error: Option<Error>,
    /// Initial (v, z) actually used and |F| there.
    pub initial_residual: f64,
    pub implicit: ImplicitCounts,
}

/// What the implicit steps cost ([`implicit`]).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ImplicitCounts {
    /// Accepted implicit steps (of `Stats::steps`).
    pub steps: usize,
    /// Implicit tries rejected (error test or no convergence).
    pub rejected: usize,
    /// Quasi-Newton iterations of implicit tries, each a consistent
    /// initialization and a series at the try's end point.
    pub iterations: usize,
    /// Output times solved inside implicit steps (a step retried to end
    /// before an output time it missed counts the ones it had solved), and
    /// how many of them were taken from the step's Hermite interpolant (the
    /// others solved by (I2)).
    pub output_times: usize,
    pub hermite_outputs: usize,
}

/// The tape of a problem: inputs u, v, z, t in that order.
pub fn record_tape<P: DaeProblem + ?Sized>(problem: &P, order: usize) -> Tape {
    let b = TapeBuilder::new();
    let (nd, na) = (problem.n_diff(), problem.n_alg());
    let u = b.inputs(nd);
    let v = b.inputs(nd);
    let z = b.inputs(na);
    let t = b.input();
    let f = problem.record(&b, &u, &v, &z, t);
    assert_eq!(
        f.len(),
        nd + na,
        "a DAE needs as many equations as v and z unknowns"
    );
    b.finish(&f, order)
}

struct Engine<'p, P: DaeProblem + ?Sized> {
    problem: &'p P,
    tape: Tape,
    nd: usize,
    na: usize,
    stats: Stats,
    /// d node / d(v, z) at the step's order-0 point (see `Tape::add_to_order`).
    tangents: Tangents,
    /// Tape input indices of (v, z): the Jacobian's columns.
    vz_cols: Vec<usize>,
    /// LU of dF/d(v, z) at the step start.
    lu: DenseLu,
    /// Right-hand side, then solution, of the order-p solve (reused).
    rhs: Vec<f64>,
    /// The order-0 inputs (u, v, z, t) the tape was last propagated at.
    loaded: Vec<f64>,
    /// The last four terms of (u, v, z), for the geometric-series test (reused).
    tail: Vec<Vec<f64>>,
    /// Tape input indices of u, and d node / du at the step's order-0
    /// point, for A = dv/du (reused).
    u_cols: Vec<usize>,
    u_tangents: Tangents,
    /// Newton's residual, correction and base point (reused: allocated once
    /// per run instead of per iterate).
    f: Vec<f64>,
    dx: Vec<f64>,
    base: Vec<f64>,
}

impl<P: DaeProblem + ?Sized> Engine<'_, P> {
    fn n(&self) -> usize {
        self.nd + self.na
    }

    /// Sets the order-0 inputs and propagates. A step's end-residual check
    /// has already propagated the next step's start: that repeat is skipped.
    fn load0(&mut self, u: &[f64], vz: &[f64], t: f64) {
        let x = || u.iter().chain(vz).chain([&t]);
        if self.loaded.len() == self.n() + self.nd + 1
            && x()
                .zip(&self.loaded)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        {
            return;
        }
        self.loaded.clear();
        self.loaded.extend(x());
        for (i, &xi) in x().enumerate() {
            self.tape.set_input(i, 0, xi);
        }
        self.tape.propagate(0);
    }

    /// |coefficient p of F|.
    fn output_norm(&self, p: usize) -> f64 {
        // Summed as `linalg::norm` sums.
        (0..self.n())
            .map(|j| self.tape.output(j, p))
            .map(|x| x * x)
            .sum::<f64>()
            .sqrt()
    }

    /// Sets the order-0 inputs and propagates; returns F.
    fn eval0(&mut self, u: &[f64], vz: &[f64], t: f64) -> Vec<f64> {
        self.load0(u, vz, t);
        (0..self.n()).map(|j| self.tape.output(j, 0)).collect()
    }

    /// Sets the order-0 inputs and propagates; F into `self.f`, returns |F|.
    fn residual0(&mut self, u: &[f64], vz: &[f64], t: f64) -> f64 {
        self.load0(u, vz, t);
        self.f.clear();
        self.f
            .extend((0..self.nd + self.na).map(|j| self.tape.output(j, 0)));
        norm(&self.f)
    }

    /// | |J| ε |(v, z)| |: the residual that rounding (v, z) to floating
    /// point leaves, with J = dF/d(v, z) as last factorized (its tangents).
    fn rounding_floor(&self, vz: &[f64]) -> f64 {
        let n = self.n();
        let floor: Vec<f64> = (0..n)
            .map(|r| {
                (0..n)
                    .map(|c| {
                        self.tape.jacobian_entry(&self.tangents, r, c).abs()
                            * f64::EPSILON
                            * vz[c].abs()
                    })
                    .sum()
            })
            .collect();
        norm(&floor)
    }

    /// J = dF/d(v, z) at the current order-0 point, LU-factorized into
    /// `self.lu` (dense: the systems have a handful of unknowns). `lists`:
    /// also the tangents' lists that the series' orders need
    /// ([`Tape::add_to_order`]); a Newton iterate needs J alone. Returns
    /// the clock's reading at the end, for the caller's next phase (a clock
    /// read costs as much as a 4x4 solve).
    fn factorize(&mut self, step: usize, t: f64, lists: bool) -> Result<Instant> {
        let start = Instant::now();
        if lists {
            self.tape.update_tangents(&self.vz_cols, &mut self.tangents);
        } else {
            self.tape
                .update_dense_tangents(&self.vz_cols, &mut self.tangents);
        }
        let assembled = Instant::now();
        self.stats.assembly_s += (assembled - start).as_secs_f64();
        let n = self.n();
        let (tape, tangents) = (&self.tape, &self.tangents);
        self.lu
            .factorize(n, |r, c| tape.jacobian_entry(tangents, r, c));
        self.stats.factorizations += 1;
        let factorized = Instant::now();
        self.stats.factorization_s += (factorized - assembled).as_secs_f64();
        // Reciprocal condition estimate from the LU pivots, to name the trouble.
        let (mut dmin, mut dmax, mut worst) = (f64::INFINITY, 0.0f64, 0);
        for i in 0..n {
            let d = self.lu.pivot(i);
            if d < dmin {
                (dmin, worst) = (d, i);
            }
            dmax = dmax.max(d);
        }
        if !(dmin > 1e-14 * dmax) {
            return Err(Error::SingularMatrix {
                step,
                param: "t",
                at: t,
                detail: format!(
                    "dF/d(v,z) has pivot ratio {:.2e} at unknown `{}`",
                    dmin / dmax,
                    self.problem.names()[self.nd + worst]
                ),
            });
        }
        Ok(factorized)
    }

    /// `self.dx` = -J^-1 `self.f`, timed from `start`.
    fn solve_newton(&mut self, start: Instant) {
        self.dx.clear();
        self.dx.extend(self.f.iter().map(|x| -x));
        if !self.lu.solve_in_place(&mut self.dx) {
            self.dx.fill(f64::NAN);
        }
        self.stats.solves += 1;
        charge(&mut self.stats.solve_s, start);
    }

    /// `rhs` <- -J^-1 (coefficient p of F), in place; untimed (the order loop
    /// is timed as a whole: a clock read costs about as much as this solve).
    fn solve_order(&mut self, p: usize) {
        for j in 0..self.n() {
            self.rhs[j] = -self.tape.output(j, p);
        }
        if !self.lu.solve_in_place(&mut self.rhs) {
            self.rhs.fill(f64::NAN);
        }
        self.stats.solves += 1;
    }

    /// Damped Newton on F(u, ., t) = 0 for (v, z), from `vz`.
    fn newton(&mut self, u: &[f64], vz: &mut [f64], t: f64, tol: f64, step: usize) -> Result<f64> {
        let mut res = self.residual0(u, vz, t);
        self.stats.residual_evaluations += 1;
        let non_finite = || Error::NonFinite {
            step,
            param: "t",
            at: t,
            what: "the residual of the consistent (v, z) (Newton)".into(),
        };
        if !res.is_finite() {
            return Err(non_finite());
        }
        let mut it = 0;
        while res > tol {
            if it >= 100 {
                return Err(Error::NoConvergence {
                    step,
                    param: "t",
                    at: t,
                    iterations: it,
                    residual: res,
                    tolerance: tol,
                });
            }
            let factorized = self.factorize(step, t, false)?;
            self.solve_newton(factorized);
            // Converged to roundoff: the Newton step no longer changes the
            // unknowns (a steep law can keep |F| above an absolute tolerance),
            // and |F| is within 1e3 tol or below the floor that the
            // rounding of (v, z) alone leaves, | |J| ε |(v, z)| |: no (v, z)
            // in floating point does better (friction-roller, ω = 1e-6: |F|
            // stalled at 1.09e-11 with a floor of 4.2e-11, 1e3 tol = 1e-11).
            if norm(&self.dx) <= 1e-14 * (norm(vz) + f64::MIN_POSITIVE)
                && res <= (1e3 * tol).max(self.rounding_floor(vz))
            {
                break;
            }
            // Backtracking on |F|: the friction law is nearly flat away from
            // zero slip, so full Newton steps overshoot.
            let mut damping = 1.0;
            self.base.clear();
            self.base.extend_from_slice(vz);
            loop {
                for ((x, b), d) in vz.iter_mut().zip(&self.base).zip(&self.dx) {
                    *x = b + damping * d;
                }
                let r = self.residual0(u, vz, t);
                self.stats.residual_evaluations += 1;
                if r.is_finite() && (r < res || damping < 1e-10) {
                    res = r;
                    break;
                }
                // Non-finite however short the step (u itself overflows
                // the law, e.g. u0 = 1e308): stop, do not halve forever.
                if damping < 1e-10 {
                    return Err(non_finite());
                }
                damping *= 0.5;
            }
            it += 1;
        }
        Ok(res)
    }
}

impl<'p, P: DaeProblem + ?Sized> Engine<'p, P> {
    /// An engine for series up to `order`, nothing loaded yet.
    fn new(problem: &'p P, order: usize) -> Self {
        let (nd, na) = (problem.n_diff(), problem.n_alg());
        Engine {
            problem,
            tape: record_tape(problem, order),
            nd,
            na,
            stats: Stats::default(),
            tangents: Tangents::default(),
            vz_cols: (nd..nd + nd + na).collect(),
            lu: DenseLu::default(),
            rhs: vec![0.0; nd + na],
            loaded: Vec::new(),
            tail: vec![vec![0.0; 2 * nd + na]; 4],
            u_cols: (0..nd).collect(),
            u_tangents: Tangents::default(),
            f: Vec::new(),
            dx: Vec::new(),
            base: Vec::new(),
        }
    }
}

/// (v, z) consistent with u0 at t0 (F(u0, v, z, t0) = 0 within `tol`): the
/// damped Newton that starts a run from [`Initialization::Newton`], alone,
/// from the guess `vz` (v then z), which it overwrites; |F| at the end.
/// `model::friction_run` continues it in omega where it fails.
pub fn consistent<P: DaeProblem + ?Sized>(
    problem: &P,
    u0: &[f64],
    vz: &mut [f64],
    t0: f64,
    tol: f64,
) -> Result<f64> {
    Engine::new(problem, 1).newton(u0, vz, t0, tol, 0)
}

/// Integrates from u0 at cfg.t0 to cfg.t_end. `on_step` receives every
/// accepted step (for outputs; it keeps it if it wants, without a copy) and
/// may stop the run with an error.
pub fn run<P: DaeProblem + ?Sized>(
    problem: &P,
    u0: &[f64],
    init: &Initialization,
    cfg: &DaeConfig,
    on_step: impl FnMut(TimeStep, &Stats) -> Result<()>,
) -> DaeResult {
    let mut chooser = implicit::Chooser::default();
    let mut r = run_with(problem, u0, init, cfg, on_step, &mut chooser);
    r.implicit = ImplicitCounts {
        steps: chooser.accepted,
        rejected: chooser.rejected,
        iterations: chooser.iterations + chooser.output_iterations,
        output_times: chooser.output_points,
        hermite_outputs: chooser.hermite_points,
    };
    r
}

fn run_with<P: DaeProblem + ?Sized>(
    problem: &P,
    u0: &[f64],
    init: &Initialization,
    cfg: &DaeConfig,
    mut on_step: impl FnMut(TimeStep, &Stats) -> Result<()>,
    chooser: &mut implicit::Chooser,
) -> DaeResult {
    let nd = problem.n_diff();
    let mut eng = Engine::new(problem, cfg.order);
    let finish = |stats: Stats, stop: &str, t: f64, error: Option<Error>, r0: f64| DaeResult {
        stats,
        stop: error
            .as_ref()
            .map(|e| e.kind().to_string())
            .unwrap_or_else(|| stop.to_string()),
        t,
        t_singular: None,
        collapse_ahead: None,
        events: Vec::new(),
        jump: None,
        error,
        initial_residual: r0,
        implicit: ImplicitCounts::default(),
    };
    let mut u = u0.to_vec();
    let mut t = cfg.t0;
    let (mut vz, newton_init) = match init {
        Initialization::Newton { v, z } => ([v.clone(), z.clone()].concat(), true),
        Initialization::Exact { v, z } => ([v.clone(), z.clone()].concat(), false),
    };
    let r0 = if newton_init {
        match eng.newton(&u, &mut vz, t, cfg.newton_tol, 0) {
            Ok(r) => r,
            Err(e) => return finish(eng.stats, "", t, Some(e), f64::NAN),
        }
    } else {
        norm(&eng.eval0(&u, &vz, t))
    };
    let mut events = Vec::new();
    let finish_with_events = |mut r: DaeResult, events: Vec<(f64, f64)>| {
        r.events = events;
        r
    };
    // Singular points estimated before this time were found to be regular.
    let mut regular_until = f64::NEG_INFINITY;
    for index in 0..cfg.max_steps {
        if t >= cfg.t_end {
            return finish_with_events(finish(eng.stats, "end", t, None, r0), events);
        }
        match implicit::step(&mut eng, chooser, &u, &vz, t, index, cfg) {
            Ok(step)
                if let Some(ahead) = step
                    .geometric
                    .filter(|&d| cfg.stop_at_singularity && t + d > regular_until)
                    .map(|d| singular_ahead(&mut eng, chooser, &step, d, index, cfg))
                    && !matches!(ahead, Ahead::Regular | Ahead::Stalled) =>
            {
                // The last terms form a geometric series: a singular point
                // lies at t0 + alpha_1, within reach of this step, and the
                // path does not get past it. Stop at the last regular point
                // and report where the singularity is.
                let t_star = t + step.geometric.unwrap_or(0.0);
                events.push((t, t_star));
                let mut r = finish(eng.stats, "singularity", t, None, r0);
                r.t_singular = Some(t_star);
                match ahead {
                    Ahead::Collapsed(at) => r.collapse_ahead = Some(at),
                    Ahead::Jumped(at, speed) => r.jump = Some((at, speed)),
                    _ => {}
                }
                return finish_with_events(r, events);
            }
            Ok(mut step) => {
                if let Some(d) = step.geometric {
                    if cfg.stop_at_singularity {
                        // The path got past it (singular_ahead): a pair of
                        // complex singular points near the real axis, or a
                        // fast jump the steps resolve, not an end of the
                        // path. Not tested again up to there.
                        if t + d > regular_until {
                            regular_until = t + PAST * d;
                            eng.stats.singularities_passed += 1;
                        }
                    } else {
                        events.push((t, t + d));
                    }
                }
                let t_start = t;
                let Some(end) = step_end(&step, nd, cfg.t_end, &mut u, &mut vz) else {
                    let e = Error::NonFinite {
                        step: index,
                        param: "t",
                        at: t,
                        what: "series evaluation".into(),
                    };
                    return finish(eng.stats, "", t, Some(e), r0);
                };
                // A step that ends far faster than the scene's speeds
                // crossed the end of the quasi-static solution in a fast
                // jump (review 12: friction-roller at order 5 went on to
                // 15,965 m/s and ended "end" on the roller's underside):
                // stop before it, as at a singular point.
                let speed = max_speed(&vz[..nd]);
                if speed > cfg.speed_limit {
                    let mut r = finish(eng.stats, "singularity", t_start, None, r0);
                    r.jump = Some((end, speed));
                    return finish_with_events(r, events);
                }
                eng.stats.steps += 1;
                t = end;
                let end_residual = step.end_residual;
                if cfg.correct && end_residual > cfg.residual_tol {
                    correct_outputs(&mut eng, &mut step, cfg, index);
                }
                if let Err(e) = on_step(step, &eng.stats) {
                    return finish(eng.stats, "", t, Some(e), r0);
                }
                if cfg.correct && end_residual > cfg.residual_tol {
                    if let Err(e) = eng.newton(&u, &mut vz, t, cfg.newton_tol, index) {
                        return finish(eng.stats, "", t, Some(e), r0);
                    }
                    eng.stats.corrections += 1;
                }
            }
            // At the first step no shrinking steps point at a singular
            // point: the scene's fastest time scale lies below min_step
            // (e.g. its default 1e-13 t_end with an absurd t_end).
            Err(e @ Error::StepCollapse { .. }) if eng.stats.steps == 0 => {
                return finish(eng.stats, "", t, Some(e), r0);
            }
            Err(Error::StepCollapse { .. }) => {
                return finish(eng.stats, "singularity", t, None, r0);
            }
            Err(e) => return finish(eng.stats, "", t, Some(e), r0),
        }
    }
    finish(eng.stats, "max_steps", t, None, r0)
}

/// Steps (no output) that [`singular_ahead`] takes at most.
const LOOKAHEAD_STEPS: usize = 40;
/// [`singular_ahead`]: the path closes in on the singular point once it is
/// this fraction of the first estimate's distance from it (a path that went
/// past a complex pair came within 1.0% of it first).
const CLOSE_IN: f64 = 1e-3;
/// [`singular_ahead`]: a path that gets to t0 + PAST d, past the estimate by
/// twice the tolerance of the estimates, went past a regular point.
const PAST: f64 = 1.2;

/// Whether the singular point that the geometric tail of `step`'s series
/// puts at t0 + d is one. The test of Cochelin and Medale reads the last
/// four terms, and a pair of complex singular points at angle θ from the
/// real axis passes it whenever N θ is small: their terms, ρ^-n cos(n θ),
/// look geometric over four orders (friction-plane, zeta = omega = 1e-2 N,
/// order 15, eps 1e-8: terms 12–15 geometric to 4e-6, a breakdown reported
/// at t = 0.0005 s on a path that is smooth up to its end at 3 s). So the
/// path is followed on from the step's end, without output, on a copy of
/// the step choice: a path that gets to t0 + `PAST` d (or to the end) at
/// the scene's speeds went past a regular point; one whose steps close in
/// on it (within `CLOSE_IN` d), fail, or cross it in a fast jump
/// (`DaeConfig::speed_limit`) meets a singular one; one that stays short of
/// it for `LOOKAHEAD_STEPS` steps, its steps no longer closing in, has
/// stalled at a sharp but regular bend, and the run goes on there.
/// Its work counts in the run's factorizations and solves.
///
/// Seeing the same point again does not confirm it (as it did before,
/// after 3 steps): a complex pair is a fixed point too. Coulomb friction
/// (q = 0) at omega = 1e-2 showed the same point 3 times in a row at each
/// stick–slip switch and stopped friction-1d at t = 0.198 s, exit 0, a
/// motion that goes on to its plateau (review 12); followed on, its path
/// got past in 16 steps. A real fold is closed in on (friction-roller,
/// paper values: within CLOSE_IN d in 13 steps) or crossed in a jump
/// (omega = 1e-4: up to 1e2–1e4 times the scene's speeds).
fn singular_ahead<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    chooser: &implicit::Chooser,
    step: &TimeStep,
    d: f64,
    index: usize,
    cfg: &DaeConfig,
) -> Ahead {
    let mut ch = chooser.clone();
    let (t_star, past) = (step.t0 + d, (step.t0 + PAST * d).min(cfg.t_end));
    let (mut u, mut vz) = (Vec::new(), Vec::new());
    let Some(mut t) = step_end(step, eng.nd, cfg.t_end, &mut u, &mut vz) else {
        return Ahead::Singular;
    };
    let mut end_residual = step.end_residual;
    for k in 1..=LOOKAHEAD_STEPS {
        if cfg.correct
            && end_residual > cfg.residual_tol
            && eng
                .newton(&u, &mut vz, t, cfg.newton_tol, index + k)
                .is_err()
        {
            return Ahead::Singular;
        }
        if t >= past {
            return Ahead::Regular;
        }
        if (0.0..=CLOSE_IN * d).contains(&(t_star - t)) {
            return Ahead::Singular;
        }
        let next = match implicit::step(eng, &mut ch, &u, &vz, t, index + k, cfg) {
            Ok(next) => next,
            Err(Error::StepCollapse { at, .. }) => return Ahead::Collapsed(at),
            // Series terms beyond a double's range: a fast time constant
            // at a stalled step, not a sign of the point (review 12:
            // Coulomb friction at omega = 1e-6, whose run, going on, meets
            // the same overflow and names the order to lower).
            Err(Error::NonFinite { .. }) => return Ahead::Stalled,
            Err(_) => return Ahead::Singular,
        };
        let Some(end) = step_end(&next, eng.nd, cfg.t_end, &mut u, &mut vz) else {
            return Ahead::Singular;
        };
        let speed = max_speed(&vz[..eng.nd]);
        if speed > cfg.speed_limit {
            return Ahead::Jumped(end, speed);
        }
        t = end;
        end_residual = next.end_residual;
    }
    Ahead::Stalled
}

/// The largest |v| of a state's velocities.
fn max_speed(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m: f64, x| m.max(x.abs()))
}

/// The output times inside a step whose end needed a correction: the
/// series' (v, z) there are as far off as at its end (review 8:
/// friction-1d at omega = 1e-6, a first step with end residual 1.3e-2 wrote
/// R_T 8.5 % off k u at t = 0.13 s, the friction force amplifying the
/// velocity's error by f R_N / (omega Vc)). At each, (v, z) are solved
/// consistent with the series' u by Newton, as the step end is, and dy/dt
/// read from their order-1 series ([`TimeStep::points`]), at the times whose
/// own residual misses `residual_tol`. A time where Newton fails keeps the
/// series' values. Leaves the tape loaded elsewhere: the caller corrects
/// the step end after.
fn correct_outputs<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    step: &mut TimeStep,
    cfg: &DaeConfig,
    index: usize,
) {
    let nd = eng.nd;
    let (t0, t1) = (step.t0, step.t0 + step.length);
    let slack = 1e-12 * cfg.t_end;
    for &t in &cfg.output_times {
        if t <= t0 + slack || t > t1 + slack || step.point(t).is_some() {
            continue;
        }
        let y = step.eval(t);
        // Only where the row itself misses the test the step end missed
        // (one evaluation; most rows of such a step pass it).
        eng.stats.residual_evaluations += 1;
        if norm(&eng.eval0(&y[..nd], &y[nd..], t)) <= cfg.residual_tol {
            continue;
        }
        if let Some(point) = consistent_point(eng, &y[..nd], &y[nd..], t, index, cfg) {
            step.points.push(point);
        }
    }
}

/// The point at time t with positions `u`: (v, z) solved consistent with
/// them by Newton from `vz`, and dy/dt read from their order-1 series, as
/// (t, y, dy/dt); None where Newton fails or a value is not finite.
fn consistent_point<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    u: &[f64],
    vz: &[f64],
    t: f64,
    index: usize,
    cfg: &DaeConfig,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let mut vz = vz.to_vec();
    eng.newton(u, &mut vz, t, cfg.newton_tol, index).ok()?;
    solve_series(eng, u, &vz, t, index, 1).ok()?;
    let count = eng.nd + eng.n();
    let y: Vec<f64> = (0..count).map(|i| eng.tape.input_series(i)[0]).collect();
    let dy: Vec<f64> = (0..count).map(|i| eng.tape.input_series(i)[1]).collect();
    (y.iter().chain(&dy).all(|x| x.is_finite())).then_some((t, y, dy))
}

/// Moves (u, vz) (nd differential unknowns, the others) to the end of
/// `step` and returns its time (at most t_end); None where the series are
/// not finite there.
fn step_end(
    step: &TimeStep,
    nd: usize,
    t_end: f64,
    u: &mut Vec<f64>,
    vz: &mut Vec<f64>,
) -> Option<f64> {
    let y = step.eval(step.t0 + step.length);
    if y.iter().any(|x| !x.is_finite()) {
        return None;
    }
    u.clear();
    u.extend_from_slice(&y[..nd]);
    vz.clear();
    vz.extend_from_slice(&y[nd..]);
    Some((step.t0 + step.length).min(t_end))
}

/// What [`singular_ahead`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ahead {
    /// The path got past the point.
    Regular,
    /// It did not.
    Singular,
    /// A step fell below `min_step` at this time before it got past.
    Collapsed(f64),
    /// A step ending at this time crossed it at this speed, above
    /// `DaeConfig::speed_limit`: a fast jump of the regularized dynamics.
    Jumped(f64, f64),
    /// `LOOKAHEAD_STEPS` steps neither got past nor closed in: a bend too
    /// sharp for the look-ahead's budget, not an end of the path; the run
    /// goes on (and stops on a collapse or a jump if it is one).
    Stalled,
}

/// The Taylor series (u, v, z) of the solution through (u0, vz0) at t0, each
/// of `cfg.order` + 1 terms (eqs. 8–9): J factorized at (u0, vz0, t0), one
/// solve per order. Leaves the tape loaded at t0 (order 0) with J in `eng.lu`.
fn series_at<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    u0: &[f64],
    vz0: &[f64],
    t0: f64,
    index: usize,
    n_ord: usize,
) -> Result<Vec<Vec<f64>>> {
    solve_series(eng, u0, vz0, t0, index, n_ord)?;
    let mut out = Vec::new();
    copy_series(eng, &mut out);
    Ok(out)
}

/// [`series_at`] left on the tape (its inputs' series), not copied out.
fn solve_series<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    u0: &[f64],
    vz0: &[f64],
    t0: f64,
    index: usize,
    n_ord: usize,
) -> Result<()> {
    let (nd, n) = (eng.nd, eng.n());
    eng.load0(u0, vz0, t0);
    let start = eng.factorize(index, t0, true)?;
    for p in 1..=n_ord {
        for i in 0..nd {
            let vprev = eng.tape.input_series(nd + i)[p - 1];
            eng.tape.set_input(i, p, vprev / p as f64);
        }
        for i in 0..n {
            eng.tape.set_input(nd + i, p, 0.0);
        }
        eng.tape
            .set_input(nd + n, p, if p == 1 { 1.0 } else { 0.0 });
        eng.tape.propagate(p);
        eng.stats.series_terms += 1;
        eng.solve_order(p);
        // Store the solved coefficients in every node: an exact linear
        // update instead of a second propagation of order p.
        eng.tape.add_to_order(p, &eng.tangents, &eng.rhs);
        // The defect's square: finite exactly when |F_p| is (no root needed).
        let defect2: f64 = (0..n).map(|j| eng.tape.output(j, p)).map(|x| x * x).sum();
        if !defect2.is_finite() || eng.rhs.iter().any(|v| !v.is_finite()) {
            charge(&mut eng.stats.series_s, start);
            return Err(Error::NonFinite {
                step: index,
                param: "t",
                at: t0,
                what: overflow_diagnosis(eng, p),
            });
        }
    }
    charge(&mut eng.stats.series_s, start);
    Ok(())
}

/// What a non-finite series term of order p means. The terms of a series
/// whose radius in time is r grow like r^-p: where a fast time constant
/// makes r small (zeta = 1e-6 N, omega = 1e-4: the terms pass 1e170 at
/// order 26 at t = 0, and their squares overflow) they leave the range of a
/// double before the last order, and only a lower order runs.
fn overflow_diagnosis<P: DaeProblem + ?Sized>(eng: &Engine<P>, p: usize) -> String {
    let what = format!("series term of order {p}");
    if p < 3 {
        return what;
    }
    let last = (0..eng.nd + eng.n())
        .map(|i| eng.tape.input_series(i)[p - 1].abs())
        .fold(0.0, f64::max);
    // Products of two such terms (squares in the laws) overflow once the
    // terms pass the square root of the largest double.
    if !(last.is_finite() && last > 1e100) {
        return what;
    }
    format!(
        "{what}: the terms outgrow the range of a double (order {}: {last:.1e}; they grow like r^-p with r = {:.1e} s, the series' reach in time, set by a fast time constant); set solver.order below {p}",
        p - 1,
        last.powf(-1.0 / (p - 1) as f64)
    )
}

/// The inputs' series (u, v, z) on the tape into `out`, reusing its vectors
/// (an implicit try's iterates: one series each).
fn copy_series<P: DaeProblem + ?Sized>(eng: &Engine<P>, out: &mut Vec<Vec<f64>>) {
    let count = eng.nd + eng.n();
    out.truncate(count);
    for (i, c) in out.iter_mut().enumerate() {
        c.clear();
        c.extend_from_slice(eng.tape.input_series(i));
    }
    for i in out.len()..count {
        out.push(eng.tape.input_series(i).to_vec());
    }
}

/// Ratio rule a = (eps |y_1| / |y_N|)^(1/(N-1)) on y = (u, v, z), capped at
/// (1e15)^(1/N) (DESIGN §2).
fn ratio_length(series: &[Vec<f64>], eps: f64, n_ord: usize) -> f64 {
    let term_norm = |p: usize| {
        let s = series.iter().map(|c| c[p] * c[p]).sum::<f64>();
        if s.is_finite() {
            return s.sqrt();
        }
        // Terms past 1e154 (a fast time constant, a high order): their
        // squares overflow, which made the length 0 and the step a collapse;
        // linalg::norm scales them (off the hot path: only then).
        crate::linalg::norm(&series.iter().map(|c| c[p]).collect::<Vec<_>>())
    };
    let (n1, nn) = (term_norm(1), term_norm(n_ord));
    let cap = 1e15f64.powf(1.0 / n_ord as f64);
    if nn > 0.0 && n1 > 0.0 {
        (eps * n1 / nn).powf(1.0 / (n_ord as f64 - 1.0)).min(cap)
    } else {
        cap
    }
}

/// Distance to a singular point when the last terms of the series form a
/// geometric series (Cochelin–Medale test on (u, v, z)).
fn geometric_distance<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    series: &[Vec<f64>],
    n_ord: usize,
) -> Option<f64> {
    if n_ord < 3 {
        return None;
    }
    for (term, p) in eng.tail.iter_mut().zip(n_ord - 3..) {
        for (x, c) in term.iter_mut().zip(series) {
            *x = c[p];
        }
    }
    super::geometric::detect_tail(n_ord, &eng.tail).map(|g| g.distance)
}

/// The explicit step: the series at t0 (computed, or `known` from the
/// previous implicit step's end), its ratio-rule length, the geometric-series
/// test and the end residual.
fn explicit_step<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    u0: &[f64],
    vz0: &[f64],
    t0: f64,
    index: usize,
    cfg: &DaeConfig,
    known: Option<Vec<Vec<f64>>>,
) -> Result<TimeStep> {
    let nd = eng.nd;
    let n_ord = cfg.order;
    let series = match known {
        Some(s) => {
            // The tape may hold an implicit try's end point: reload t0.
            eng.load0(u0, vz0, t0);
            s
        }
        None => series_at(eng, u0, vz0, t0, index, n_ord)?,
    };
    let scale = 1.0 + eng.output_norm(0);
    let a_max = ratio_length(&series, cfg.eps, n_ord);
    if a_max < cfg.min_step {
        return Err(Error::StepCollapse {
            step: index,
            param: "t",
            at: t0,
            length: a_max,
        });
    }
    let geometric = geometric_distance(eng, &series, n_ord);
    let mut step = TimeStep {
        index,
        t0,
        length: a_max.min(cfg.t_end - t0),
        origin: t0,
        implicit: false,
        pade: None,
        dense: None,
        points: Vec::new(),
        series,
        end_residual: 0.0,
        geometric,
    };
    if cfg.stepping == Stepping::Pade && geometric.is_none() {
        let cap = (1e3 * a_max).min(cfg.t_end - t0);
        if a_max < cap
            && let Some((a, p)) = super::time_pade::range(&step.series, n_ord, cfg.eps, a_max, cap)
        {
            step.pade = Some(p);
            step.length = a;
        }
    }
    let length = step.length;
    let y = step.eval(t0 + length);
    eng.load0(&y[..nd], &y[nd..], t0 + length);
    eng.stats.residual_evaluations += 1;
    step.end_residual = eng.output_norm(0) / scale;
    Ok(step)
}

//! The path in time of the shell with friction (DESIGN §2, §7), by one of
//! two steps, each from one factorization ([`TimeConfig::stepping`]):
//!
//! - the Taylor series of [`super::friction_dae`], with the consistency
//!   (Newton) correction at a step start only where the equilibrium residual
//!   test fails. Step length: the ratio rule a = (eps |U_1| / |U_N|)^(1/(N−1))
//!   on the displacements over the model's length scale, never across a
//!   kink of the ramps or t_end (output times are summed from the series).
//!   Stops: a geometric series (Cochelin–Medale test,
//!   [`crate::series::geometric`]) whose singular point lies within the step
//!   (the quasi-static solution ceases to exist there: the time and the node
//!   of the largest last term are reported);
//! - the implicit RODAS4 step of [`super::implicit_step`], settled onto the
//!   equilibrium at its start, error-controlled, ending on output times and
//!   kinks ([`run_implicit`]); `auto` takes the series instead wherever its
//!   step reaches as far. Where three RODAS4 trials in a row fail from one
//!   start, the step is taken fully implicit, by backward Euler solved by
//!   Newton ([`super::implicit_step::newton_trial`]), and so are the
//!   [`NEWTON_STEPS`] steps after it.
//!
//! Both stop with a diagnosis (time, node) when the step collapses below
//! `min_step` or the step budget is spent.

use super::friction_dae::{FrictionDae, StepSeries, TimeState};
use crate::contact::Motion;
use crate::error::{Error, Result};
use crate::fe::dof::index as dof;
use crate::linalg::norm;
use crate::series::ContinuationProblem;
pub use crate::series::dae::Stepping;
use crate::series::geometric;
use crate::series::taylor;
use nalgebra::Vector3;

/// Numerical settings of a run in time.
#[derive(Clone, Debug)]
pub struct TimeConfig {
    pub order: usize,
    pub eps: f64,
    pub t_end: f64,
    pub max_steps: usize,
    /// Relative equilibrium residual above which a step start is corrected.
    pub residual_tol: f64,
    pub max_corrections: usize,
    /// Smallest step (s) before the run stops as collapsed.
    pub min_step: f64,
    /// Output times (increasing, within (0, t_end]).
    pub outputs: Vec<f64>,
    /// How a step uses the series (`solver.time_step`): `Explicit`, the
    /// series; `Implicit`, RODAS4 steps ([`super::implicit_step`]); `Auto`,
    /// implicit steps, with the series taken wherever its step reaches at
    /// least as far as the implicit one (tried every step while it wins,
    /// then every 2, 4 … 16 steps). `Pade` is not used here (the scene
    /// refuses it).
    pub stepping: Stepping,
}

/// The friction state of one node at an output time.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct NodeFriction {
    /// Index into the model's contact pairs.
    pub pair: usize,
    pub node: usize,
    pub obstacle: usize,
    pub gap: f64,
    /// Normal reaction R_N (eq. 3).
    pub rn: f64,
    pub normal: Vector3<f64>,
    /// Friction force R_T on the node.
    pub force: Vector3<f64>,
    /// Slip velocity v_s.
    pub slip: Vector3<f64>,
}

/// The solution at an output time.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TimeSample {
    pub t: f64,
    /// Load factor λ(t).
    pub lambda: f64,
    /// Full dof vector.
    pub full: Vec<f64>,
    pub friction: Vec<NodeFriction>,
    /// The DAE's state there (a run restarts from it: [`run_from`]).
    pub state: TimeState,
}

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeStop {
    End,
    /// The series became geometric: a singular point at time t, the node
    /// (its tag) whose unknowns carry the largest last term.
    Singularity {
        t: f64,
        node: usize,
    },
    /// Ctrl-C or SIGTERM (run::interrupt): stopped at the step end at t,
    /// every output time before it written.
    Interrupted {
        t: f64,
    },
    /// Numerical trouble after the start ([`run_keeping`] only): the
    /// error's kind and diagnosis, the last step end t; the samples are
    /// those computed before it.
    Failed {
        t: f64,
        kind: &'static str,
        /// The node the diagnosis names, if any (its tag,
        /// `ShellModel::node_tag`).
        node: Option<usize>,
        message: String,
    },
}

/// Counters of a run.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct TimeStats {
    pub steps: usize,
    /// Implicit steps whose error test failed (retried shorter).
    pub rejected: usize,
    /// Steps taken by the implicit step (the rest by the series).
    pub implicit: usize,
    /// Of those, the backward Euler steps solved by Newton
    /// ([`super::implicit_step::newton_trial`]).
    pub newton: usize,
    pub factorizations: usize,
    pub corrections: usize,
    pub max_residual: f64,
    /// Triangular solves and residual evaluations (0 in a checkpoint
    /// written before they were counted).
    #[serde(default)]
    pub solves: usize,
    #[serde(default)]
    pub residual_evaluations: usize,
}

impl TimeStats {
    /// The counters of a run followed by `later` (a resumed run).
    pub fn merged(&self, later: &TimeStats) -> TimeStats {
        TimeStats {
            steps: self.steps + later.steps,
            rejected: self.rejected + later.rejected,
            implicit: self.implicit + later.implicit,
            newton: self.newton + later.newton,
            factorizations: self.factorizations + later.factorizations,
            corrections: self.corrections + later.corrections,
            max_residual: self.max_residual.max(later.max_residual),
            solves: self.solves + later.solves,
            residual_evaluations: self.residual_evaluations + later.residual_evaluations,
        }
    }
}

pub struct TimeRun {
    pub samples: Vec<TimeSample>,
    pub stop: TimeStop,
    pub stats: TimeStats,
    /// Contact nodes left without friction (a fixed translation).
    pub skipped: Vec<usize>,
}

/// Integrates from the consistent state at t = 0 (U = 0, at rest) to t_end;
/// `progress(t, steps)` after every step.
pub fn run(
    dae: &mut FrictionDae,
    cfg: &TimeConfig,
    progress: &mut dyn FnMut(f64, usize),
) -> Result<TimeRun> {
    let start = at_rest(dae);
    run_from(dae, cfg, progress, start)
}

/// Integrates from the state `s` (made consistent first) to t_end; the
/// first sample is at s.t, then every output time after it. Any failure
/// is an error.
pub fn run_from(
    dae: &mut FrictionDae,
    cfg: &TimeConfig,
    progress: &mut dyn FnMut(f64, usize),
    s: TimeState,
) -> Result<TimeRun> {
    let mut samples = vec![];
    let mut stats = TimeStats::default();
    let stop = integrate(dae, cfg, progress, s, &mut samples, &mut stats)?;
    Ok(finish(dae, samples, stop, stats))
}

/// The state at rest at t = 0 (U = 0), where [`run`] starts.
pub fn at_rest(dae: &FrictionDae) -> TimeState {
    TimeState {
        t: 0.0,
        u: vec![0.0; dae.model.ndof()],
        w: vec![[0.0; 2]; dae.model.pairs.len()],
    }
}

/// The run's step 0 alone: the state at rest brought to equilibrium and
/// the first series at it (what `anm check` tries, so that a scene that
/// cannot start fails there rather than at run time).
pub fn check_start(dae: &mut FrictionDae, cfg: &TimeConfig) -> Result<()> {
    let s = start_state(dae, cfg)?;
    dae.series(&s).map(|_| ())
}

/// The state at rest brought to equilibrium at t = 0 (w = 0): where every
/// run starts, the ANM's and IDA's (`anm reference ida`).
pub fn start_state(dae: &mut FrictionDae, cfg: &TimeConfig) -> Result<TimeState> {
    let mut s = at_rest(dae);
    consistent(dae, &mut s, cfg, &mut TimeStats::default())?;
    Ok(s)
}

/// [`run_from`], keeping what was computed when numerical trouble (no
/// convergence, a collapsed step, the step budget, a singular matrix, a
/// non-finite value) stops the run after its start: the stop is then
/// [`TimeStop::Failed`] with the diagnosis, and the samples are those
/// before it. A failure at the start, or any other error, is an error.
pub fn run_keeping(
    dae: &mut FrictionDae,
    cfg: &TimeConfig,
    progress: &mut dyn FnMut(f64, usize),
    start: TimeState,
) -> Result<TimeRun> {
    let mut samples = vec![];
    let mut stats = TimeStats::default();
    let stop = match integrate(dae, cfg, progress, start, &mut samples, &mut stats) {
        Ok(stop) => stop,
        Err(e) if stops_a_run(&e) && !samples.is_empty() => TimeStop::Failed {
            t: e.at()
                .unwrap_or_else(|| samples.last().map_or(0.0, |s| s.t)),
            kind: e.kind(),
            node: e.node(),
            message: e.to_string(),
        },
        Err(e) => return Err(e),
    };
    Ok(finish(dae, samples, stop, stats))
}

/// Numerical trouble, as opposed to bad input or a failed write.
fn stops_a_run(e: &Error) -> bool {
    e.is_numerical() || matches!(e, Error::TimeSteps { .. } | Error::StepCollapse { .. })
}

/// The integration behind [`run_from`] and [`run_keeping`]: samples and
/// counters go to `samples` and `stats` as they are made.
fn integrate(
    dae: &mut FrictionDae,
    cfg: &TimeConfig,
    progress: &mut dyn FnMut(f64, usize),
    mut s: TimeState,
    samples: &mut Vec<TimeSample>,
    stats: &mut TimeStats,
) -> Result<TimeStop> {
    let kinks: Vec<f64> = {
        let mut k: Vec<f64> = dae.laws.kinks();
        k.retain(|&t| t > s.t);
        k.sort_by(f64::total_cmp);
        k
    };
    let mut next_out = first_output(cfg, s.t);
    consistent(dae, &mut s, cfg, stats)?;
    samples.push(sample(dae, &s, s.t)?);
    if cfg.stepping != Stepping::Explicit {
        return run_implicit(dae, cfg, progress, s, samples, stats, &kinks);
    }
    let mut stop = TimeStop::End;
    while s.t < cfg.t_end * (1.0 - 1e-14) {
        if stats.steps > 0 {
            consistent(dae, &mut s, cfg, stats)?;
        }
        let series = dae.series(&s)?;
        let n_ord = cfg.order;
        if stats.steps >= cfg.max_steps {
            return Err(Error::TimeSteps {
                param: "t",
                at: s.t,
                what: format!(
                    "step budget solver.max_steps = {} spent before t_end = {:.6e} s; node {} carries the largest last series term: the budget may be too small for the run (raise solver.max_steps), the quasi-static solution may cease to exist there (e.g. a pull above what friction can hold), or the regularized law makes the problem stiff (full slip at small omega: docs/shell-friction.md)",
                    cfg.max_steps,
                    cfg.t_end,
                    largest_node(dae, &series.u[n_ord])
                ),
                node: Some(largest_node(dae, &series.u[n_ord])),
            });
        }
        let horizon = next_kink(&kinks, s.t, cfg.t_end);
        let (mut a, found) = series_length(dae, &series, cfg);
        if let Some(t) = found {
            stop = TimeStop::Singularity {
                t: s.t + t,
                node: largest_node(dae, &series.u[n_ord]),
            };
        }
        a = a.min(horizon - s.t);
        if a < cfg.min_step && s.t + a < horizon * (1.0 - 1e-14) {
            return Err(Error::TimeSteps {
                param: "t",
                at: s.t,
                what: format!(
                    "step length collapsed to {a:.3e} s after {} steps; node {} carries the largest last series term",
                    stats.steps,
                    largest_node(dae, &series.u[n_ord])
                ),
                node: Some(largest_node(dae, &series.u[n_ord])),
            });
        }
        s = series_step(dae, cfg, &series, &s, a, horizon, &mut next_out, samples)?;
        stats.steps += 1;
        progress(s.t, stats.steps);
        if !matches!(stop, TimeStop::End) {
            break;
        }
        if crate::run::interrupt::requested() {
            stop = TimeStop::Interrupted { t: s.t };
            break;
        }
    }
    Ok(stop)
}

/// The series step of length a from s: the output times it covers are
/// summed from the series into `samples`; the end lands on `horizon` when
/// within round-off of it.
#[allow(clippy::too_many_arguments)]
fn series_step(
    dae: &FrictionDae,
    cfg: &TimeConfig,
    series: &StepSeries,
    s: &TimeState,
    a: f64,
    horizon: f64,
    next_out: &mut usize,
    samples: &mut Vec<TimeSample>,
) -> Result<TimeState> {
    let t1 = s.t + a;
    while *next_out < cfg.outputs.len() && cfg.outputs[*next_out] <= t1 * (1.0 + 1e-14) {
        let to = cfg.outputs[*next_out];
        let st = evaluate(dae, series, s, to - s.t);
        samples.push(sample(dae, &st, to)?);
        *next_out += 1;
    }
    let mut end = evaluate(dae, series, s, a);
    if (horizon - t1).abs() <= 1e-12 * horizon.max(1.0) {
        end.t = horizon;
    }
    Ok(end)
}

/// The run's result with the DAE's counters.
fn finish(
    dae: &FrictionDae,
    samples: Vec<TimeSample>,
    stop: TimeStop,
    mut stats: TimeStats,
) -> TimeRun {
    stats.factorizations = dae.factorizations;
    stats.solves = dae.solves.get();
    stats.residual_evaluations = dae.residual_evaluations;
    TimeRun {
        samples,
        stop,
        stats,
        skipped: dae.skipped.clone(),
    }
}

/// Index of the first output time after t (a run that starts at t).
fn first_output(cfg: &TimeConfig, t: f64) -> usize {
    cfg.outputs.iter().take_while(|&&o| o <= t).count()
}

/// The first kink of the ramps after t, or t_end.
fn next_kink(kinks: &[f64], t: f64, t_end: f64) -> f64 {
    kinks
        .iter()
        .copied()
        .find(|&k| k > t * (1.0 + 1e-14))
        .unwrap_or(t_end)
        .min(t_end)
}

/// The explicit step's length from the series: the ratio rule on the
/// displacements over the length scale, shortened to a singular point of
/// a geometric series (returned as its distance).
fn series_length(dae: &FrictionDae, series: &StepSeries, cfg: &TimeConfig) -> (f64, Option<f64>) {
    let n_ord = cfg.order;
    let scale = dae.model.length_scale;
    let scaled = |k: usize| norm(&series.u[k]) / scale;
    let (n1, nn) = (scaled(1), scaled(n_ord));
    let a = if nn > 0.0 && n1 > 0.0 {
        (cfg.eps * n1 / nn).powf(1.0 / (n_ord as f64 - 1.0))
    } else if nn > 0.0 {
        (cfg.eps / nn).powf(1.0 / n_ord as f64)
    } else {
        f64::INFINITY
    };
    match geometric::detect(&series.u) {
        Some(g) if g.distance <= a => (g.distance, Some(g.distance)),
        _ => (a, None),
    }
}

/// Linearizes at the step start and corrects it (damped Newton at fixed
/// tangential positions, a new factorization per iteration) until the
/// relative equilibrium residual is within the tolerance.
fn consistent(
    dae: &mut FrictionDae,
    s: &mut TimeState,
    cfg: &TimeConfig,
    stats: &mut TimeStats,
) -> Result<()> {
    for it in 0..=cfg.max_corrections {
        dae.linearize(s)?;
        let r = dae.residual(s)?;
        let rel = norm(&r) / dae.force_scale().max(f64::MIN_POSITIVE);
        if !rel.is_finite() {
            return Err(Error::NonFinite {
                step: stats.steps,
                param: "t",
                at: s.t,
                what: "equilibrium residual of the shell with friction".into(),
            });
        }
        if rel <= cfg.residual_tol {
            stats.max_residual = stats.max_residual.max(rel);
            return Ok(());
        }
        if it == cfg.max_corrections {
            return Err(Error::NoConvergence {
                step: stats.steps,
                param: "t",
                at: s.t,
                iterations: it,
                residual: rel,
                tolerance: cfg.residual_tol,
            });
        }
        // Damped: the regularized laws are sigmoids of the slip and the
        // gap, on which full Newton steps from a predictor overshoot.
        let d = dae.newton_direction(s, &r)?;
        let r0 = norm(&r);
        let mut alpha = 1.0;
        let mut next = dae.moved(s, &d, alpha);
        for _ in 0..10 {
            match dae.residual(&next) {
                Ok(rt) if norm(&rt) < r0 => break,
                _ => {
                    alpha *= 0.5;
                    next = dae.moved(s, &d, alpha);
                }
            }
        }
        *s = next;
        stats.corrections += 1;
    }
    unreachable!("the loop returns")
}

/// The series summed at a (U, w); the time advanced.
fn evaluate(dae: &FrictionDae, series: &StepSeries, s: &TimeState, a: f64) -> TimeState {
    let sum = |terms: &[Vec<f64>], i: usize| {
        let c: Vec<f64> = terms.iter().map(|t| t[i]).collect();
        taylor::eval(&c, a)
    };
    let u = (0..s.u.len()).map(|i| sum(&series.u, i)).collect();
    let flat: Vec<f64> = (0..series.w[0].len()).map(|i| sum(&series.w, i)).collect();
    let mut w = s.w.clone();
    dae.scatter_w(&flat, &mut w);
    TimeState { t: s.t + a, u, w }
}

/// The tag (`ShellModel::node_tag`) of the node whose free dofs carry the
/// largest entry of a term.
fn largest_node(dae: &FrictionDae, term: &[f64]) -> usize {
    let (k, _) =
        term.iter().enumerate().fold(
            (0, 0.0),
            |b, (i, v)| if v.abs() > b.1 { (i, v.abs()) } else { b },
        );
    node_of_dof(dae, k)
}

/// Implicit steps ([`super::implicit_step`]) from the consistent state s
/// to t_end, ending at every output time and kink of the ramps. Per step:
/// the linearization at its start, the factorization of M/(h γ) − J, the
/// start settled onto the equilibrium with it ([`implicit_step::settle`]),
/// the stages. A trial is accepted where the error estimate of U passes
/// and the equilibrium residual at its end is within `residual_tol`;
/// h ← h · clamp(0.9 err^(−1/p), 0.2, 5), p the estimate's order (4 for
/// RODAS4, 2 for the backward Euler step that takes over after three
/// failed trials).
fn run_implicit(
    dae: &mut FrictionDae,
    cfg: &TimeConfig,
    progress: &mut dyn FnMut(f64, usize),
    mut s: TimeState,
    samples: &mut Vec<TimeSample>,
    stats: &mut TimeStats,
    kinks: &[f64],
) -> Result<TimeStop> {
    use super::implicit_step::{self, Trial};
    use crate::series::rodas::{ERROR_ORDER, RODAS4};
    let mut next_out = first_output(cfg, s.t);
    let mut h = (cfg.t_end - s.t) * 1e-4;
    // Error test: |error of the translations| ≤ max(eps × the largest
    // translation so far, 1e-13 solver.length_scale), the second term a
    // few hundred round-offs of the node coordinates, which the residual's
    // gaps and frames see.
    let mut scale = 0.0f64;
    let atol = 1e-13 * dae.model.length_scale;
    let mut last_dof = 0;
    let settle_tol = cfg.residual_tol * 1e-3;
    let mut stop = TimeStop::End;
    // Auto: steps until the series is tried again, and the current period.
    let mut probe_wait = 0usize;
    let mut probe_every = 1usize;
    // Steps left that take the backward Euler step directly.
    let mut newton_left = 0usize;
    // The last step's start and length (the backward Euler error estimate).
    let mut prev: Option<(Vec<f64>, f64)> = None;
    let per_node = crate::fe::dof::PER_NODE;
    let mut translation = vec![false; s.u.len()];
    for (full, free) in dae.model.free.iter().enumerate() {
        if let Some(k) = free {
            translation[*k] = full % per_node < 3;
        }
    }
    let size_of = |u: &[f64]| {
        u.iter()
            .zip(&translation)
            .filter(|(_, t)| **t)
            .fold(0.0f64, |m, (v, _)| m.max(v.abs()))
    };
    loop {
        let at_output =
            next_out < cfg.outputs.len() && s.t >= cfg.outputs[next_out] * (1.0 - 1e-14);
        let done = s.t >= cfg.t_end * (1.0 - 1e-14);
        // At a step end, its output written: Ctrl-C or SIGTERM stop here.
        if !done && !at_output && crate::run::interrupt::requested() {
            stop = TimeStop::Interrupted { t: s.t };
            break;
        }
        if !done && stats.steps >= cfg.max_steps {
            return Err(Error::TimeSteps {
                param: "t",
                at: s.t,
                what: format!(
                    "step budget solver.max_steps = {} spent before t_end = {:.6e} s ({} implicit steps rejected); node {} carries the largest error estimate: the budget may be too small for the run (raise solver.max_steps), or the quasi-static solution may cease to exist there (e.g. a pull above what friction can hold)",
                    cfg.max_steps,
                    cfg.t_end,
                    stats.rejected,
                    node_of_dof(dae, last_dof)
                ),
                node: Some(node_of_dof(dae, last_dof)),
            });
        }
        let target = kinks
            .iter()
            .copied()
            .chain(cfg.outputs.get(next_out + usize::from(at_output)).copied())
            .filter(|&k| k > s.t * (1.0 + 1e-14))
            .fold(cfg.t_end, f64::min);
        // At t_end no step is left: the settle below relaxes with the last
        // step's length, not with 0 (M/(0 γ) − J moved the velocities of
        // the final state by up to 2.7 % of the roller speed; review 8).
        let mut length = if done { h } else { h.min(target - s.t) };
        // A step cut short to land on an output time or a kink says
        // nothing against the longer one: the next step starts from it.
        let clipped = length < h;
        dae.prepare(&s)?;
        dae.factor_implicit(length * RODAS4.gamma, s.t)?;
        let rel = implicit_step::settle(dae, &mut s, settle_tol, None)?;
        stats.max_residual = stats.max_residual.max(rel);
        if at_output {
            s.t = cfg.outputs[next_out];
            samples.push(sample(dae, &s, s.t)?);
            next_out += 1;
        }
        if done {
            break;
        }
        if cfg.stepping == Stepping::Auto && probe_wait == 0 {
            // The series from the settled start: its length against the
            // implicit step's.
            let probe = dae.linearize(&s).and_then(|_| dae.series(&s));
            if let Ok(series) = probe {
                let horizon = next_kink(kinks, s.t, cfg.t_end);
                let (a_exp, found) = series_length(dae, &series, cfg);
                let a = a_exp.min(horizon - s.t);
                if a >= length && a >= cfg.min_step {
                    let t0 = s.t;
                    let u0 = s.u.clone();
                    s = series_step(dae, cfg, &series, &s, a, horizon, &mut next_out, samples)?;
                    // The backward Euler error estimate extrapolates through
                    // the last step, this one (review 19: through the last
                    // implicit step, 2.3e-14 s long, before a series step
                    // of 2.5e-7 s, its slope was bogus and the steps
                    // collapsed to 4e-17 s on a sliding plate at ω = 0.03).
                    prev = Some((u0, s.t - t0));
                    scale = scale.max(size_of(&s.u));
                    h = h.max(a);
                    probe_every = 1;
                    stats.steps += 1;
                    progress(s.t, stats.steps);
                    if let Some(d) = found {
                        stop = TimeStop::Singularity {
                            t: t0 + d,
                            node: largest_node(dae, &series.u[cfg.order]),
                        };
                        break;
                    }
                    continue;
                }
                probe_every = (probe_every * 2).min(16);
            } else {
                probe_every = 16;
            }
            probe_wait = probe_every;
            // The series' factorization replaced the step's.
            dae.factor_implicit(length * RODAS4.gamma, s.t)?;
        } else {
            probe_wait = probe_wait.saturating_sub(1);
        }
        let mut rejections = 0;
        let accepted: Trial = loop {
            // Backward Euler solved by Newton where the Rosenbrock stages keep
            // failing from this start, and for a few steps after.
            let newton = newton_left > 0 || rejections >= 3;
            let attempt = if newton {
                implicit_step::newton_trial(
                    dae,
                    &s,
                    length,
                    prev.as_ref().map(|(u, h)| (u.as_slice(), *h)),
                    cfg.residual_tol * 1e-2,
                    atol,
                )
            } else {
                implicit_step::trial(dae, &s, length).map(Some)
            };
            // The error relative to what the test allows.
            let attempt = attempt.map(|t| {
                t.map(|mut t| {
                    let size = size_of(&s.u).max(size_of(&t.end.u)).max(scale);
                    t.error /= (cfg.eps * size).max(atol);
                    t
                })
            });
            // The end must also lie near the equilibrium (the algebraic
            // part), which the error test on U does not see: in saturated
            // slip the stages' w swing far from the linearization.
            let end_residual = match &attempt {
                Ok(Some(t)) if t.error.is_finite() && t.error <= 1.0 => {
                    norm(&dae.residual(&t.end)?) / dae.force_scale().max(f64::MIN_POSITIVE)
                }
                _ => f64::NAN,
            };
            let (factor, diagnosis) = match attempt {
                Ok(Some(t)) if end_residual <= cfg.residual_tol => break t,
                Ok(Some(t)) if t.error.is_finite() && t.error <= 1.0 => {
                    last_dof = t.worst_dof;
                    (
                        0.5,
                        format!(
                            "the equilibrium residual at the step end, {end_residual:.2e}, exceeds solver.residual_tol"
                        ),
                    )
                }
                Ok(Some(t)) if t.error.is_finite() => {
                    last_dof = t.worst_dof;
                    (
                        (0.9 * t.error.powf(-1.0 / t.error_order)).max(0.2),
                        "the error estimate exceeds eps".to_string(),
                    )
                }
                Ok(Some(_)) => (0.25, "the error estimate is not finite".to_string()),
                Ok(None) => (
                    0.25,
                    "the Newton iteration of the backward Euler step did not converge".to_string(),
                ),
                // A stage past the law's range (e.g. an unbounded slip
                // speed): the stage's own error names the entry, not t.
                Err(Error::NonFinite { what, .. }) => {
                    (0.25, format!("a trial stage gave a non-finite {what}"))
                }
                Err(e) => (0.25, e.to_string()),
            };
            stats.rejected += 1;
            rejections += 1;
            length *= factor;
            if rejections == 3 {
                // Trials keep failing from this start: settle it again with
                // Newton proper (measured: ζ = 1e-4 N on the conveying strip
                // collapsed at t = 2e-8 s with the start 20× off the
                // settle's target).
                let rel =
                    implicit_step::settle(dae, &mut s, settle_tol, Some(length * RODAS4.gamma))?;
                stats.max_residual = stats.max_residual.max(rel);
            }
            if length < cfg.min_step {
                // Whether the start itself is off the solution set: a
                // friction node loaded beyond its cap (README, "Stiffness
                // in time", item 4: the conveying strip at small zeta and
                // omega).
                // (A residual that fails here leaves the collapse's own
                // diagnosis, not its error.)
                let worst = dae.residual(&s).ok().and_then(|r| dae.worst_cap_ratio(&r));
                let infeasible = match worst {
                    Some((node, q)) if q > 1.0 => format!(
                        "; at the step start node {} carries a residual force {q:.2} times its friction cap f |R_N|_reg, which no slip velocity balances (a larger friction.zeta or friction.omega may run)",
                        dae.model.node_tag(node)
                    ),
                    _ => String::new(),
                };
                // Where the loads have barely started, no pull is to blame
                // (review 13: a slack strip, T = 0, and a 1e6 N tension
                // at t = 1.7e-9 s, with 0.009 N applied, were both told of
                // a pull above what friction can hold).
                // The motion ramp counts only where an obstacle moves
                // (review 18: a plate driven by a prescribed edge value,
                // its load ramp at 9e-7, was told of a pull because the
                // motion factor of its fixed plane was 1).
                let moving = dae
                    .laws
                    .motions
                    .iter()
                    .any(|m| !matches!(m, crate::contact::Motion::Fixed));
                let load = dae.laws.load.value(s.t);
                let motion = if moving {
                    dae.laws.motion.value(s.t)
                } else {
                    0.0
                };
                let unloaded = dae.model.dead.iter().all(|&f| f == 0.0)
                    && dae.model.prescribed.iter().all(|&x| x == 0.0)
                    && dae
                        .laws
                        .extra_loads
                        .iter()
                        .all(|(_, f)| f.iter().all(|&x| x == 0.0));
                // No friction node pressed: the only capacity is the
                // floor f zeta (review 18: a plate 5 cm above its plane,
                // pulled, was told of a pull above what friction holds).
                let pressed = sample(dae, &s, s.t)
                    .ok()
                    .map(|smp| smp.friction.iter().map(|f| f.rn).fold(0.0, f64::max));
                let zeta = dae.laws.law.zeta.unwrap_or(0.0);
                let cause = if unloaded {
                    "the scene applies no load, so the strip is slack: nothing presses it onto the obstacles, and a moving one drags it only through the regularized friction's floor f zeta; give the strip its tension".to_string()
                } else if load < 1e-3 && motion < 1e-3 {
                    format!(
                        "the loads and motions are at {load:.1e} and {motion:.1e} of their full values here, so the trouble is in the regularized friction's first instants, not a pull: a larger friction.zeta or friction.omega, or a slower ramp relative to the loads' size, may run"
                    )
                } else if let Some(rn) = pressed.filter(|&rn| rn <= zeta) {
                    format!(
                        "no friction node is pressed onto an obstacle (largest R_N = {rn:.3e}, at most friction.zeta = {zeta:e}): friction holds only through its floor f zeta per node, which the loads here exceed; check the gaps and that the loads press the shell onto the obstacles"
                    )
                } else {
                    "the quasi-static solution may cease to exist here (e.g. a pull above what friction can hold)".to_string()
                };
                return Err(Error::TimeSteps {
                    param: "t",
                    at: s.t,
                    what: format!(
                        "implicit step length collapsed to {length:.3e} s after {} steps: {diagnosis}; node {} carries the largest error estimate: {cause}{infeasible}",
                        stats.steps,
                        node_of_dof(dae, last_dof)
                    ),
                    node: Some(node_of_dof(dae, last_dof)),
                });
            }
            if !newton && rejections < 3 {
                dae.factor_implicit(length * RODAS4.gamma, s.t)?;
            }
        };
        newton_left = if newton_left > 0 {
            newton_left - 1
        } else if accepted.error_order < ERROR_ORDER {
            NEWTON_STEPS
        } else {
            0
        };
        last_dof = accepted.worst_dof;
        let grow = if accepted.error > 0.0 {
            (0.9 * accepted.error.powf(-1.0 / accepted.error_order)).clamp(0.2, 5.0)
        } else {
            5.0
        };
        h = if clipped && (accepted.end.t - target).abs() <= 1e-12 * target.abs().max(1.0) {
            h.max(length * grow)
        } else {
            length * grow
        };
        prev = Some((std::mem::take(&mut s.u), accepted.end.t - s.t));
        s = accepted.end;
        if (s.t - target).abs() <= 1e-12 * target.abs().max(1.0) {
            s.t = target;
        }
        scale = scale.max(size_of(&s.u));
        stats.steps += 1;
        stats.implicit += 1;
        stats.newton += usize::from(accepted.error_order < ERROR_ORDER);
        progress(s.t, stats.steps);
    }
    Ok(stop)
}

/// Steps taken by backward Euler after one that needed it
/// (the Rosenbrock stages are tried again after).
pub const NEWTON_STEPS: usize = 4;

/// The tag (`ShellModel::node_tag`) of the node of a free dof.
fn node_of_dof(dae: &FrictionDae, k: usize) -> usize {
    let node = dae
        .model
        .free
        .iter()
        .position(|f| *f == Some(k))
        .map_or(0, |full| full / crate::fe::dof::PER_NODE);
    dae.model.node_tag(node)
}

/// The solution at time t: the full vector, and per friction node R_N,
/// R_T and v_s evaluated from the laws directly (eq. 3 and
/// contact::friction::FrictionLaw::nodal, with the tangential velocity
/// t_1 w_1 + t_2 w_2 of the state).
pub fn sample(dae: &FrictionDae, s: &TimeState, t: f64) -> Result<TimeSample> {
    let lambda = dae.laws.load.value(t);
    let full = dae.model.expand(&s.u, lambda);
    let m = dae.laws.motion.value(t);
    let mut friction = vec![];
    for (ip, node) in dae.step_pairs() {
        let pair = &dae.model.pairs[ip];
        let ob = &dae.model.obstacles[pair.obstacle];
        let x = dae.model.x0[node] + v3(&full, node);
        let g = ob.gap(&x).ok_or_else(|| Error::NonFinite {
            step: 0,
            param: "t",
            at: t,
            what: format!(
                "contact gap of node {} (on the obstacle axis)",
                dae.model.node_tag(node)
            ),
        })?;
        let (t1, t2) = match ob {
            crate::contact::Obstacle::Plane { normal, .. } => {
                let t1 = super::friction_pair::plane_t1(normal);
                (t1, normal.cross(&t1))
            }
            crate::contact::Obstacle::Cylinder { axis, .. } => (*axis, g.n.cross(axis)),
        };
        let xdot = t1 * s.w[ip][0] + t2 * s.w[ip][1];
        let rn = pair.law.force(g.h);
        let motion = scaled(&dae.laws.motions[pair.obstacle], m);
        let nf = dae
            .laws
            .law
            .nodal(ob, &motion, &x, &xdot, rn)
            .expect("the gap is defined");
        friction.push(NodeFriction {
            pair: ip,
            node,
            obstacle: pair.obstacle,
            gap: g.h,
            rn,
            normal: g.n,
            force: nf.force,
            slip: nf.slip,
        });
    }
    Ok(TimeSample {
        t,
        lambda,
        full,
        friction,
        state: TimeState { t, ..s.clone() },
    })
}

fn v3(full: &[f64], node: usize) -> Vector3<f64> {
    Vector3::new(full[dof(node, 0)], full[dof(node, 1)], full[dof(node, 2)])
}

/// A motion with its velocity scaled by the ramp factor m.
fn scaled(motion: &Motion, m: f64) -> Motion {
    match motion {
        Motion::Fixed => Motion::Fixed,
        Motion::Translate { velocity } => Motion::Translate {
            velocity: velocity * m,
        },
        Motion::Rotate { omega } => Motion::Rotate { omega: omega * m },
    }
}

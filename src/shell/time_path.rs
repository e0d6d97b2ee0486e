//! The path in time of the shell with friction: Taylor steps of
//! [`super::friction_dae`], each from one factorization, with the
//! consistency (Newton) correction at a step start only where the
//! equilibrium residual test fails (DESIGN §2, §7).
//!
//! Step length: the ratio rule a = (eps |U_1| / |U_N|)^(1/(N−1)) on the
//! displacements over the model's length scale, never across a kink of the
//! ramps, an output time or t_end. Stops: t_end; a geometric series
//! (Cochelin–Medale test, [`crate::series::geometric`]) whose singular point
//! lies within the step (the quasi-static solution ceases to exist there:
//! the time and the node of the largest last term are reported); a step
//! shorter than `min_step` (collapse, with the same diagnosis).

use super::friction_dae::{FrictionDae, StepSeries, TimeState};
use crate::contact::Motion;
use crate::error::{Error, Result};
use crate::fe::dof::index as dof;
use crate::linalg::norm;
use crate::series::ContinuationProblem;
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
}

/// The friction state of one node at an output time.
#[derive(Clone, Debug)]
pub struct NodeFriction {
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
#[derive(Clone, Debug)]
pub struct TimeSample {
    pub t: f64,
    /// Load factor λ(t).
    pub lambda: f64,
    /// Full dof vector.
    pub full: Vec<f64>,
    pub friction: Vec<NodeFriction>,
}

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeStop {
    End,
    /// The series became geometric: a singular point at time t, the node
    /// whose unknowns carry the largest last term.
    Singularity {
        t: f64,
        node: usize,
    },
}

/// Counters of a run.
#[derive(Clone, Debug, Default)]
pub struct TimeStats {
    pub steps: usize,
    pub factorizations: usize,
    pub corrections: usize,
    pub max_residual: f64,
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
    let n_pairs = dae.model.pairs.len();
    let mut s = TimeState {
        t: 0.0,
        u: vec![0.0; dae.model.ndof()],
        w: vec![[0.0; 2]; n_pairs],
    };
    let mut stats = TimeStats::default();
    let kinks: Vec<f64> = {
        let mut k: Vec<f64> = dae.laws.load.kinks();
        k.extend(dae.laws.motion.kinks());
        k.retain(|&t| t > 0.0);
        k.sort_by(f64::total_cmp);
        k
    };
    let scale = dae.model.length_scale;
    let mut samples = vec![];
    let mut next_out = 0;
    consistent(dae, &mut s, cfg, &mut stats)?;
    samples.push(sample(dae, &s, None, 0.0)?);
    let mut stop = TimeStop::End;
    while s.t < cfg.t_end * (1.0 - 1e-14) {
        if stats.steps > 0 {
            consistent(dae, &mut s, cfg, &mut stats)?;
        }
        let series = dae.series(&s)?;
        let n_ord = cfg.order;
        if stats.steps >= cfg.max_steps {
            return Err(Error::TimeSteps {
                param: "t",
                at: s.t,
                what: format!(
                    "step budget solver.max_steps = {} spent before t_end = {:.6e} s; node {} carries the largest last series term: the quasi-static solution may cease to exist there (e.g. a pull above what friction can hold), or the regularized law makes the problem stiff (full slip at small omega: docs/shell-friction.md)",
                    cfg.max_steps,
                    cfg.t_end,
                    largest_node(dae, &series.u[n_ord]) + 1
                ),
            });
        }
        let scaled = |k: usize| norm(&series.u[k]) / scale;
        let (n1, nn) = (scaled(1), scaled(n_ord));
        let horizon = kinks
            .iter()
            .copied()
            .find(|&k| k > s.t * (1.0 + 1e-14))
            .unwrap_or(cfg.t_end)
            .min(cfg.t_end);
        let mut a = if nn > 0.0 && n1 > 0.0 {
            (cfg.eps * n1 / nn).powf(1.0 / (n_ord as f64 - 1.0))
        } else if nn > 0.0 {
            (cfg.eps / nn).powf(1.0 / n_ord as f64)
        } else {
            f64::INFINITY
        };
        let geo = geometric::detect(&series.u);
        if let Some(g) = geo
            && g.distance <= a
        {
            stop = TimeStop::Singularity {
                t: s.t + g.distance,
                node: largest_node(dae, &series.u[n_ord]),
            };
            a = g.distance;
        }
        a = a.min(horizon - s.t);
        if a < cfg.min_step && s.t + a < horizon * (1.0 - 1e-14) {
            return Err(Error::TimeSteps {
                param: "t",
                at: s.t,
                what: format!(
                    "step length collapsed to {a:.3e} s after {} steps; node {} carries the largest last series term",
                    stats.steps,
                    largest_node(dae, &series.u[n_ord]) + 1
                ),
            });
        }
        let t1 = s.t + a;
        while next_out < cfg.outputs.len() && cfg.outputs[next_out] <= t1 * (1.0 + 1e-14) {
            let to = cfg.outputs[next_out];
            let st = evaluate(dae, &series, &s, to - s.t);
            samples.push(sample(dae, &st, Some((&series, to - s.t)), to)?);
            next_out += 1;
        }
        s = evaluate(dae, &series, &s, a);
        if (horizon - t1).abs() <= 1e-12 * horizon.max(1.0) {
            s.t = horizon;
        }
        stats.steps += 1;
        progress(s.t, stats.steps);
        if !matches!(stop, TimeStop::End) {
            break;
        }
    }
    stats.factorizations = dae.factorizations;
    Ok(TimeRun {
        samples,
        stop,
        stats,
        skipped: dae.skipped.clone(),
    })
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

/// The node (0-based) whose free dofs carry the largest entry of a term.
fn largest_node(dae: &FrictionDae, term: &[f64]) -> usize {
    let (k, _) =
        term.iter().enumerate().fold(
            (0, 0.0),
            |b, (i, v)| if v.abs() > b.1 { (i, v.abs()) } else { b },
        );
    dae.model
        .free
        .iter()
        .position(|f| *f == Some(k))
        .map_or(0, |full| full / crate::fe::dof::PER_NODE)
}

/// The solution at time t: the full vector, and per friction node R_N,
/// R_T and v_s evaluated from the laws directly (eq. 3 and
/// contact::friction::FrictionLaw::nodal with ẋ from the series).
fn sample(
    dae: &FrictionDae,
    s: &TimeState,
    series: Option<(&StepSeries, f64)>,
    t: f64,
) -> Result<TimeSample> {
    let lambda = dae.laws.load.value(t);
    let full = dae.model.expand(&s.u, lambda);
    let m = dae.laws.motion.value(t);
    // ẋ = Σ k U_k a^(k−1) (prescribed dofs: λ'(t) × their value).
    let velocity = match series {
        Some((ser, a)) => {
            let n = s.u.len();
            let mut v = vec![0.0; n];
            for (k, uk) in ser.u.iter().enumerate().skip(1) {
                let f = k as f64 * a.powi(k as i32 - 1);
                for i in 0..n {
                    v[i] += f * uk[i];
                }
            }
            dae.model.expand(&v, dae.laws.load.rate(t))
        }
        None => vec![0.0; full.len()],
    };
    let mut friction = vec![];
    for (ip, node) in dae.step_pairs() {
        let pair = &dae.model.pairs[ip];
        let ob = &dae.model.obstacles[pair.obstacle];
        let x = dae.model.x0[node] + v3(&full, node);
        let xdot = v3(&velocity, node);
        let g = ob.gap(&x).ok_or_else(|| Error::NonFinite {
            step: 0,
            param: "t",
            at: t,
            what: format!("contact gap of node {} (on the obstacle axis)", node + 1),
        })?;
        let rn = pair.law.force(g.h);
        let motion = scaled(&dae.laws.motions[pair.obstacle], m);
        let nf = dae
            .laws
            .law
            .nodal(ob, &motion, &x, &xdot, rn)
            .expect("the gap is defined");
        friction.push(NodeFriction {
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

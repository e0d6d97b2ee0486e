//! Scenes of the paper's friction cases (§3.2, §3.3, §3.4; DESIGN §4).
//!
//! ```toml
//! [scene]     kind = "friction-plane"      # friction-1d | friction-plane | friction-roller
//! [spring]    k = 1.0                      # N/m
//! [friction]  f = 0.2, q = 0.05, Vc = 1.0, omega = 0.1, zeta = 0.1   # zeta: plane/roller
//! [contact]   K = 1e6, eta = 1e-3, delta = 1.0                       # plane/roller
//! [obstacle]  V = 1.0                      # plane speed (1d, plane); roller: r, Omega
//! [load]      F = 1.0                      # N/s (plane, roller); friction-1d: RN (N)
//! [initial]   mode = "newton", u0 = 0.0, v0 = 1.0
//! [solver]    order = 20, eps = 1e-10, t_end = 3.0, on_singularity = "stop"  # or "continue"
//!             time_step = "auto"           # or "explicit", "implicit", "pade" (series::dae::implicit)
//! [output]    dt = 0.01
//! ```

use super::{Checker, Kind, parse};
use crate::contact::{FrictionLaw, NormalLaw};
use crate::error::Result;
use crate::series::dae::Stepping;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Accepted `solver.order` of a friction scene (and of `anm time`/`bench`
/// methods `anm:ORDER:EPS`).
pub const ORDERS: std::ops::RangeInclusive<usize> = 2..=200;
/// Default `solver.min_step`, relative to `solver.t_end`.
pub const DEFAULT_MIN_STEP: f64 = 1e-13;
/// Accepted `solver.eps` of a friction scene (and of those methods).
pub const EPS: std::ops::RangeInclusive<f64> = 1e-16..=1.0;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    scene: RawScene,
    spring: RawSpring,
    friction: RawFriction,
    contact: Option<RawContact>,
    obstacle: RawObstacle,
    load: RawLoad,
    #[serde(default)]
    initial: RawInitial,
    solver: RawSolver,
    output: RawOutput,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    // Read by `scene::kind` before this schema is chosen.
    #[allow(dead_code)]
    kind: String,
    title: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpring {
    k: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawFriction {
    f: f64,
    q: f64,
    Vc: f64,
    omega: f64,
    zeta: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawContact {
    K: f64,
    eta: f64,
    delta: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawObstacle {
    V: Option<f64>,
    r: Option<f64>,
    Omega: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawLoad {
    F: Option<f64>,
    RN: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInitial {
    mode: Option<String>,
    u0: Option<f64>,
    v0: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    method: Option<String>,
    order: i64,
    eps: f64,
    t_end: f64,
    max_steps: Option<i64>,
    min_step: Option<f64>,
    newton_tol: Option<f64>,
    residual_tol: Option<f64>,
    correct: Option<bool>,
    on_singularity: Option<String>,
    time_step: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    dt: f64,
    plot: Option<bool>,
}

/// How order 0 of the first step is found (§3.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InitMode {
    /// Newton on the order-0 equations, started from `v0` (default: at rest).
    Newton,
    /// The exact initial velocity `v0` is given; only checked.
    Exact,
}

/// The geometry and motion of the rigid obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Obstacle {
    /// A plane translating along x at speed V (m/s).
    Plane { v: f64 },
    /// A cylinder of radius r centred at (0, -(delta + r)), spinning at Omega
    /// (rad/s, counterclockwise about +z).
    Roller { r: f64, omega: f64 },
}

/// A validated friction scene.
#[derive(Clone, Debug)]
pub struct FrictionScene {
    pub file: PathBuf,
    pub kind: Kind,
    pub title: String,
    /// Spring stiffness k (N/m).
    pub k: f64,
    pub friction: FrictionLaw,
    /// Contact law (plane, roller); friction-1d has a known normal force.
    pub contact: Option<NormalLaw>,
    pub obstacle: Obstacle,
    /// Load rate F (N/s) of the force F t toward the obstacle (plane, roller).
    pub load_rate: f64,
    /// Known normal force R_N (N), friction-1d.
    pub normal_force: f64,
    pub init: InitMode,
    /// Initial displacement along x (friction-1d; 0 for the others).
    pub u0: f64,
    /// Initial velocity along x: exact value, or Newton's starting guess.
    pub v0: Option<f64>,
    pub order: usize,
    pub eps: f64,
    pub t_end: f64,
    pub max_steps: usize,
    pub min_step: f64,
    pub newton_tol: f64,
    pub residual_tol: f64,
    pub correct: bool,
    /// Stop at the first singular point the series reveals ("stop"), or
    /// record it and go on ("continue").
    pub stop_at_singularity: bool,
    /// Explicit, implicit or per-step choice of the time step
    /// ([`crate::series::dae::Stepping`]).
    pub stepping: Stepping,
    pub dt: f64,
    pub plot: bool,
}

impl FrictionScene {
    /// The speed of the scene's quasi-static motions: the largest of Vc,
    /// the plane's speed, the roller's surface speed and the load rate over
    /// the spring's stiffness (m/s). A mass moving far faster is jumping
    /// ([`crate::model::friction_run::JUMP`]).
    pub fn speed_scale(&self) -> f64 {
        let obstacle = match self.obstacle {
            Obstacle::Plane { v } => v.abs(),
            Obstacle::Roller { r, omega } => (r * omega).abs(),
        };
        self.friction
            .vc
            .max(obstacle)
            .max(self.load_rate.abs() / self.k)
    }

    /// The uniform output grid 0, dt, 2 dt, ..., t_end.
    /// 0, dt, 2 dt, … and t_end itself where dt does not divide it (as the
    /// shell runs in time; review 8: dt = 0.7 wrote rows at 0 and 0.7 only).
    pub fn output_times(&self) -> Vec<f64> {
        let n = (self.t_end / self.dt * (1.0 + 1e-12)).floor() as usize;
        let mut times: Vec<f64> = (0..=n)
            .map(|i| (i as f64 * self.dt).min(self.t_end))
            .collect();
        if times
            .last()
            .is_some_and(|&t| t < self.t_end * (1.0 - 1e-12))
        {
            times.push(self.t_end);
        }
        times
    }
}

/// Reads and validates a friction scene.
pub fn load(path: &Path, text: &str, kind: Kind) -> Result<FrictionScene> {
    let raw: Raw = parse(path, text)?;
    let c = Checker { file: path };
    let k = c.positive("spring.k", raw.spring.k)?;
    let fr = &raw.friction;
    let f = c.positive("friction.f", fr.f)?;
    let q = c.within("friction.q", fr.q, 0.0, 1.0)?;
    let vc = c.positive("friction.Vc", fr.Vc)?;
    let omega = c.positive("friction.omega", fr.omega)?;
    c.slip_speeds(vc, omega, q)?;
    let zeta = match kind {
        Kind::Friction1d => {
            c.unused("friction.zeta", &fr.zeta, kind)?;
            None
        }
        _ => Some(c.positive("friction.zeta", c.required("friction.zeta", fr.zeta, kind)?)?),
    };
    let contact = match (kind, &raw.contact) {
        (Kind::Friction1d, Some(_)) => {
            return Err(c.fail(
                "contact",
                "not used by a `friction-1d` scene (the normal force is known: [load] RN)",
            ));
        }
        (Kind::Friction1d, None) => None,
        (_, None) => {
            return Err(c.fail(
                "contact",
                format!(
                    "missing: a `{}` scene needs [contact] K, eta, delta",
                    kind.name()
                ),
            ));
        }
        (_, Some(ct)) => {
            let law = NormalLaw {
                k: c.positive("contact.K", ct.K)?,
                eta: c.positive("contact.eta", ct.eta)?,
                delta: c.positive("contact.delta", ct.delta)?,
            };
            if law.eta >= law.k * law.delta {
                return Err(c.fail(
                    "contact.eta",
                    format!(
                        "must be below K*delta = {:e} for eq. (3) to have a real root at every gap",
                        law.k * law.delta
                    ),
                ));
            }
            Some(law)
        }
    };
    let ob = &raw.obstacle;
    let obstacle = match kind {
        Kind::FrictionRoller => {
            c.unused("obstacle.V", &ob.V, kind)?;
            Obstacle::Roller {
                r: c.positive("obstacle.r", c.required("obstacle.r", ob.r, kind)?)?,
                omega: c.finite(
                    "obstacle.Omega",
                    c.required("obstacle.Omega", ob.Omega, kind)?,
                )?,
            }
        }
        _ => {
            c.unused("obstacle.r", &ob.r, kind)?;
            c.unused("obstacle.Omega", &ob.Omega, kind)?;
            Obstacle::Plane {
                v: c.finite("obstacle.V", c.required("obstacle.V", ob.V, kind)?)?,
            }
        }
    };
    let (load_rate, normal_force) = match kind {
        Kind::Friction1d => {
            c.unused("load.F", &raw.load.F, kind)?;
            (
                0.0,
                c.positive("load.RN", c.required("load.RN", raw.load.RN, kind)?)?,
            )
        }
        _ => {
            c.unused("load.RN", &raw.load.RN, kind)?;
            (
                c.non_negative("load.F", c.required("load.F", raw.load.F, kind)?)?,
                0.0,
            )
        }
    };
    let init = match raw.initial.mode.as_deref() {
        None | Some("newton") => InitMode::Newton,
        Some("exact") => InitMode::Exact,
        Some(other) => {
            return Err(c.fail(
                "initial.mode",
                format!("expected \"newton\" or \"exact\", got \"{other}\""),
            ));
        }
    };
    let v0 = raw
        .initial
        .v0
        .map(|v| c.finite("initial.v0", v))
        .transpose()?;
    if init == InitMode::Exact && v0.is_none() {
        return Err(c.fail(
            "initial.v0",
            "missing: mode = \"exact\" needs the exact initial velocity v0",
        ));
    }
    let u0 = match kind {
        Kind::Friction1d => c.finite("initial.u0", raw.initial.u0.unwrap_or(0.0))?,
        _ => {
            c.unused("initial.u0", &raw.initial.u0, kind)?;
            0.0
        }
    };
    let s = &raw.solver;
    if let Some(m) = s.method.as_deref()
        && m != "anm"
    {
        return Err(c.fail(
            "solver.method",
            format!("friction scenes support \"anm\" only, got \"{m}\""),
        ));
    }
    if s.order < *ORDERS.start() as i64 {
        return Err(c.fail(
            "solver.order",
            format!("must be >= {}, got {}", ORDERS.start(), s.order),
        ));
    }
    if s.order > *ORDERS.end() as i64 {
        return Err(c.fail(
            "solver.order",
            format!("must be <= {}, got {}", ORDERS.end(), s.order),
        ));
    }
    let eps = c.within("solver.eps", s.eps, *EPS.start(), *EPS.end())?;
    let t_end = c.positive("solver.t_end", s.t_end)?;
    let max_steps = match s.max_steps {
        Some(m) if m < 1 => {
            return Err(c.fail("solver.max_steps", format!("must be >= 1, got {m}")));
        }
        Some(m) => m as usize,
        None => 100_000,
    };
    // Default: a few hundred round-offs of t_end (IDA's floor is the
    // round-off of t). At 1e-9 t_end the explicit steps of legitimate fast
    // transients (zeta = 1e-6 N, order 10: 2.5e-9 s at t_end = 3 s) were
    // called a collapse; README "False singular points".
    let min_step = c.positive(
        "solver.min_step",
        s.min_step.unwrap_or(DEFAULT_MIN_STEP * t_end),
    )?;
    if min_step >= t_end {
        return Err(c.fail(
            "solver.min_step",
            format!("must be below solver.t_end = {t_end:?}, got {min_step:?}"),
        ));
    }
    let newton_tol = c.positive("solver.newton_tol", s.newton_tol.unwrap_or(1e-14))?;
    let residual_tol = c.positive("solver.residual_tol", s.residual_tol.unwrap_or(1e-8))?;
    let stop_at_singularity = match s.on_singularity.as_deref() {
        None | Some("stop") => true,
        Some("continue") => false,
        Some(other) => {
            return Err(c.fail(
                "solver.on_singularity",
                format!("expected \"stop\" or \"continue\", got \"{other}\""),
            ));
        }
    };
    let stepping = match s.time_step.as_deref() {
        None | Some("auto") => Stepping::Auto,
        Some("explicit") => Stepping::Explicit,
        Some("implicit") => Stepping::Implicit,
        Some("pade") => Stepping::Pade,
        Some(other) => {
            return Err(c.fail(
                "solver.time_step",
                format!(
                    "expected \"auto\", \"explicit\", \"pade\" or \"implicit\", got \"{other}\""
                ),
            ));
        }
    };
    let dt = c.positive("output.dt", raw.output.dt)?;
    if dt > t_end {
        return Err(c.fail(
            "output.dt",
            format!("must not exceed solver.t_end = {t_end:?}, got {dt:?}"),
        ));
    }
    // Rows at 0, dt, … and t_end.
    let rows = (t_end / dt).ceil() + 1.0;
    if rows > 1e6 {
        return Err(c.fail(
            "output.dt",
            format!("gives {rows:.0} history rows up to solver.t_end (at most 1e6)"),
        ));
    }
    Ok(FrictionScene {
        file: path.to_path_buf(),
        kind,
        title: raw.scene.title.unwrap_or_else(|| kind.name().to_string()),
        k,
        friction: FrictionLaw {
            f,
            q,
            vc,
            omega,
            zeta,
        },
        contact,
        obstacle,
        load_rate,
        normal_force,
        init,
        u0,
        v0,
        order: s.order as usize,
        eps,
        t_end,
        max_steps,
        min_step,
        newton_tol,
        residual_tol,
        correct: s.correct.unwrap_or(true),
        stop_at_singularity,
        stepping,
        dt,
        plot: raw.output.plot.unwrap_or(true),
    })
}

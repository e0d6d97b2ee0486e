//! `anm buckle SCENE [--lambda L | --time T]`: linearized buckling about a state of
//! the path, as Abaqus *BUCKLE (Abaqus Theory Guide, "Eigenvalue buckling
//! prediction"): the lowest eigenpairs of
//!
//!   (K_0 + mu K_sigma) phi = 0,                                  (B1)
//!
//! K_0 the tangent at the base state (U_0, lambda_0) (the path followed by
//! the ANM up to lambda_0 = L, or the initial state) and K_sigma the
//! derivative of the tangent along the path per unit lambda:
//!
//!   K_sigma = d/dlambda Kt(U_0 + (lambda − lambda_0) U_t, lambda),
//!   U_t = −K_0⁻¹ R_lambda,                                       (B2)
//!
//! the initial-stress (and load) stiffness of the scene's load pattern,
//! plus the initial-displacement terms of the linear prebuckling increment
//! U_t (of the order of its strains). The critical load is
//! lambda_cr = lambda_0 + mu. (B2) is taken by the central difference
//! (Kt(+h) − Kt(−h)) / 2h, h = 0.1 × |lambda_end|: exact for the shell's
//! tangent, which is quadratic in the state (St Venant–Kirchhoff with
//! quadratic strains), up to round-off of 1e-16 |K| / h. Contact enters
//! K_0 only: K_sigma leaves out the contact part of the tangent, which is
//! held at the base state as Abaqus holds the contact state in *BUCKLE
//! (the law of eq. 3 is not quadratic, and its stiffness changes by
//! orders of magnitude across its switch). The eigenpairs
//! come from [`crate::linalg::eigen::pencil`] (subspace iteration on our
//! LDLᵀ factorization of K_0, which must be positive definite: a base
//! state past a critical point is refused with its negative pivot count).
//!
//! A scene with [friction] is buckled about its state at a time t
//! (`--time`), reached by its run in time, with K_0 the tied tangent of
//! [`crate::shell::stability`] (eq. S1: sticking nodes held in their
//! obstacle's tangent plane, the Coulomb limit) and lambda_0 = λ(t), the
//! load ramp's value; mu then scales the ramped loads.
//!
//! Outputs: the eigenvalue table on stdout; with `-o DIR`, buckle.csv,
//! buckle.json and one `buckle_mode_K.vtu` per mode (the mode on the
//! reference surface, [`crate::output::mode`]).

use crate::error::{Error, Result};
use crate::linalg::{LinearSolver, SparseMatrix, eigen};
use crate::output::mode;
use crate::run::build::build_model;
use crate::run::shell_time;
use crate::scene::shell::ShellScene;
use crate::series::path::Path as AnmPath;
use crate::series::stop::Stop;
use crate::series::{ContinuationProblem, continuation::factorize};
use crate::shell::model::ShellModel;
use crate::shell::stability::{self, Tie};
use crate::shell::time_path::TimeStop;
use serde::Serialize;
use std::path::Path;

/// One buckling mode.
#[derive(Clone, Debug, Serialize)]
pub struct Mode {
    /// 1-based, in increasing |mu|.
    pub index: usize,
    /// Eigenvalue of (B1): load factor on top of the base state.
    pub mu: f64,
    /// lambda_0 + mu.
    pub lambda_critical: f64,
    /// |K_0 phi + mu K_sigma phi| / |K_0 phi|.
    pub residual: f64,
    pub half_waves: Option<f64>,
    pub wavelength: Option<f64>,
    pub wave_direction: Option<String>,
    /// Wrinkles of a flat sheet's mode ([`mode::wrinkles`]).
    pub wrinkles: Option<mode::Wrinkles>,
    pub vtk: Option<String>,
    /// On the free unknowns, |phi| = 1.
    #[serde(skip)]
    pub vector: Vec<f64>,
}

/// Result of `anm buckle` (buckle.json).
#[derive(Clone, Debug, Serialize)]
pub struct BuckleReport {
    pub scene: String,
    pub dofs: usize,
    /// lambda_0 of the base state.
    pub lambda_base: f64,
    /// The time of the base state (friction scenes).
    pub time_base: Option<f64>,
    /// Friction nodes tied (sticking) and left free (slipping) there.
    pub sticking: usize,
    pub slipping: usize,
    /// ANM steps to reach it.
    pub path_steps: usize,
    pub modes: Vec<Mode>,
    pub iterations: usize,
    pub solves: usize,
    pub subspace: usize,
    pub wall_s: f64,
    /// Why the linearization may not predict the critical point here.
    pub warnings: Vec<String>,
}

/// The state to buckle about.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Base {
    /// The ANM path of a scene without friction at this lambda.
    Lambda(f64),
    /// A friction scene's run in time at this time (s).
    Time(f64),
}

/// The base state: the model there, its unknowns, lambda, the sticking
/// contact nodes to tie (node, unit normal, stiffness) and the steps taken.
struct BaseState {
    model: ShellModel,
    u0: Vec<f64>,
    lambda: f64,
    ties: Vec<Tie>,
    slipping: usize,
    steps: usize,
}

/// The ANM path of a scene without friction up to `lambda_base`.
fn lambda_base_state(scene: &ShellScene, lambda_base: f64) -> Result<BaseState> {
    let mut model = build_model(scene)?;
    let mut cfg = scene.solver.clone();
    cfg.lambda_scale = cfg.lambda_end.abs();
    let mut u0 = vec![0.0; model.ndof()];
    let mut steps = 0;
    if lambda_base != 0.0 {
        cfg.lambda_end = lambda_base;
        let mut path = AnmPath::new(&mut model, u0.clone(), 0.0, cfg);
        loop {
            match path.step() {
                Ok(_) => steps += 1,
                Err(Stop::End { .. }) => break,
                Err(Stop::Failed(e)) => return Err(e),
                Err(other) => {
                    return Err(Error::Invalid {
                        file: scene.file.clone(),
                        key: "--lambda".into(),
                        problem: format!("the path did not reach lambda = {lambda_base}: {other}"),
                    });
                }
            }
        }
        u0 = path.state().0.to_vec();
    }
    Ok(BaseState {
        model,
        u0,
        lambda: lambda_base,
        ties: vec![],
        slipping: 0,
        steps,
    })
}

/// A friction scene's run in time up to `t`: the state there, its load
/// factor, and its sticking nodes tied ([`stability`], eq. S1: K_0 is the
/// tied tangent).
fn time_base_state(scene: &ShellScene, t: f64) -> Result<BaseState> {
    let mut sc = scene.clone();
    let fr = sc.friction.as_mut().expect("a friction scene");
    fr.t_end = t;
    fr.output_step = t;
    let (run, dae) = shell_time::solve(&sc)?;
    let last = match (&run.stop, run.samples.last()) {
        (TimeStop::End, Some(last)) if (last.t - t).abs() <= 1e-9 * t => last.clone(),
        (stop, _) => {
            return Err(Error::Invalid {
                file: scene.file.clone(),
                key: "--time".into(),
                problem: format!("the run in time did not reach t = {t}: {stop:?}"),
            });
        }
    };
    let (ties, slipping) = stability::stick_ties(&dae.model, &last.friction, &dae.laws.law);
    let model = dae.model;
    Ok(BaseState {
        u0: model.reduce(&last.full),
        model,
        lambda: last.lambda,
        ties,
        slipping,
        steps: run.stats.steps,
    })
}

/// Linearized buckling of `scene` about the state `base` (module docs):
/// `count` modes; files into `out_dir` when given.
pub fn buckle(
    scene: &ShellScene,
    base: Base,
    count: usize,
    out_dir: Option<&Path>,
) -> Result<BuckleReport> {
    let start = std::time::Instant::now();
    let bad_modes = |problem: String| Error::Invalid {
        file: scene.file.clone(),
        key: "--modes".into(),
        problem,
    };
    if count == 0 {
        return Err(bad_modes("must be at least 1".into()));
    }
    let state = match (base, scene.friction.is_some()) {
        (Base::Lambda(l), false) => {
            if !l.is_finite() {
                return Err(Error::Invalid {
                    file: scene.file.clone(),
                    key: "--lambda".into(),
                    problem: format!("must be finite, got {l}"),
                });
            }
            lambda_base_state(scene, l)?
        }
        (Base::Time(t), true) => {
            let t_end = scene.friction.as_ref().map_or(f64::INFINITY, |f| f.t_end);
            if !(t > 0.0 && t <= t_end) {
                return Err(Error::Invalid {
                    file: scene.file.clone(),
                    key: "--time".into(),
                    problem: format!(
                        "must be a time of the scene's run, in (0, friction.t_end = {t_end}] s, got {t}"
                    ),
                });
            }
            // Review 25: a load with its own ramp is not in the load
            // pattern (the loads friction.load_ramp scales): subspace
            // iteration then found no mode and blamed tension.
            if let Some((k, _)) = scene.friction.as_ref().and_then(|f| f.load_ramps.first()) {
                return Err(Error::Invalid {
                    file: scene.file.clone(),
                    key: format!("load[{k}].ramp"),
                    problem: "`anm buckle --time` takes the loads that friction.load_ramp scales as its load pattern, and this load has its own ramp: give it friction.load_ramp's (remove load.ramp) to buckle the state along it; the run's own stability monitor (friction.stability) covers every load".into(),
                });
            }
            time_base_state(scene, t)?
        }
        (Base::Lambda(_), true) => {
            return Err(Error::Invalid {
                file: scene.file.clone(),
                key: "--lambda".into(),
                problem: "a scene with [friction] reaches its states in time: give --time".into(),
            });
        }
        (Base::Time(_), false) => {
            return Err(Error::Invalid {
                file: scene.file.clone(),
                key: "--time".into(),
                problem: "only a scene with [friction] runs in time: give --lambda".into(),
            });
        }
    };
    let BaseState {
        mut model,
        u0,
        lambda: lambda_base,
        ties,
        slipping,
        steps: path_steps,
    } = state;
    let n = model.ndof();
    if count > n {
        return Err(bad_modes(format!(
            "{count} modes asked of a model with {n} unknowns"
        )));
    }
    let cfg = scene.solver.clone();
    let scale = cfg.lambda_end.abs();
    let mut lu = LinearSolver::new(cfg.linear);
    let mut stats = crate::series::Stats::default();
    let (k0, r_lambda) = stability::tied_tangent(&mut model, &u0, lambda_base, &ties)?;
    let f0 = factorize(&mut lu, &k0, &mut stats, path_steps, lambda_base)?;
    if let Some((neg, _, _)) = f0.inertia()
        && neg > 0
    {
        return Err(Error::SingularMatrix {
            step: path_steps,
            param: "lambda",
            at: lambda_base,
            detail: format!(
                "the base state has {neg} negative pivot(s): it is past a critical point; \
                 linearized buckling needs a stable base state (choose {})",
                match base {
                    Base::Time(_) => "an earlier --time",
                    Base::Lambda(_) => "a smaller --lambda",
                }
            ),
        });
    }
    // Review 25: with ties, the static tangent may already have lost its
    // stability (the regularized law's onset, which the run's monitor
    // reports) while the tied one has not: a column pushed on a wall was
    // critical at 1.0 P_c in the run and buckled at 8.25 P_c here, with
    // no word.
    let mut static_warning = None;
    if !ties.is_empty() {
        let (ks, _) = stability::tied_tangent(&mut model, &u0, lambda_base, &[])?;
        let mut lu_static = LinearSolver::new(cfg.linear);
        if let Ok(fs) = lu_static.factorize(&ks)
            && let Some((neg, _, _)) = fs.inertia()
            && neg > 0
        {
            static_warning = Some(format!(
                "the static tangent of this base state (no sticking node tied) has {neg} negative pivot(s): under the regularized friction law the state is already past a critical point, which the run's friction.stability monitor locates; lambda_critical here is the onset under Coulomb friction (the {} sticking nodes tied)",
                ties.len()
            ));
        }
    }
    let ut: Vec<f64> = f0.solve(&r_lambda.iter().map(|x| -x).collect::<Vec<_>>());
    // (B2) by central differences along the prebuckling tangent.
    let h = 0.1 * scale;
    let at = |s: f64| -> Vec<f64> { u0.iter().zip(&ut).map(|(u, t)| u + s * t).collect() };
    // Contact stays as at the base state (its pairs and the law's
    // stiffness are in K_0, not in K_sigma): eq. (3)'s stiffness changes
    // by orders of magnitude across the law's switch, and its derivative
    // is no initial-stress stiffness (Abaqus *BUCKLE likewise holds the
    // contact state of the base state).
    let (kp, _) = model.tangent(&at(h), lambda_base + h)?;
    let kcp = model.contact_tangent(&at(h), lambda_base + h)?;
    let (km, _) = model.tangent(&at(-h), lambda_base - h)?;
    let kcm = model.contact_tangent(&at(-h), lambda_base - h)?;
    let mut ks = SparseMatrix::new(n);
    for (matrix, sign) in [(&kp, 1.0), (&kcp, -1.0), (&km, -1.0), (&kcm, 1.0)] {
        for (i, j, v) in matrix.entries() {
            ks.add(i, j, sign * v / (2.0 * h));
        }
    }
    let settings = eigen::Settings {
        count,
        ..Default::default()
    };
    let (pairs, work) = eigen::pencil(&f0, &|x| k0.mul_vec(x), &|x| ks.mul_vec(x), n, &settings)
        .map_err(|detail| Error::Study {
            study: "buckle",
            case: match base {
                Base::Time(t) => format!("base state at t = {t} (lambda = {lambda_base})"),
                Base::Lambda(_) => format!("base state at lambda = {lambda_base}"),
            },
            problem: format!("no buckling mode found: {detail}"),
        })?;
    let mut modes = vec![];
    for (i, p) in pairs.into_iter().enumerate() {
        let full = model.expand(&p.vector, 0.0);
        let wave = mode::wavelength(&model.x0, &model.a30, &model.quads(), &full);
        let vtk = match out_dir {
            Some(d) => {
                crate::output::create_dir(d)?;
                let name = format!("buckle_mode_{}.vtu", i + 1);
                mode::write(&d.join(&name), &model.x0, &scene.mesh.quads, &full)?;
                Some(name)
            }
            None => None,
        };
        modes.push(Mode {
            index: i + 1,
            mu: p.mu,
            lambda_critical: lambda_base + p.mu,
            residual: p.residual,
            half_waves: wave.map(|w| w.half_waves),
            wavelength: wave.map(|w| w.wavelength),
            wave_direction: wave.map(|w| w.direction.to_string()),
            wrinkles: mode::wrinkles(&model.x0, &full),
            vtk,
            vector: p.vector,
        });
    }
    let mut report = BuckleReport {
        scene: scene.file.display().to_string(),
        dofs: n,
        lambda_base,
        time_base: match base {
            Base::Time(t) => Some(t),
            Base::Lambda(_) => None,
        },
        sticking: ties.len(),
        slipping,
        path_steps,
        modes,
        iterations: work.iterations,
        solves: work.solves,
        subspace: work.subspace,
        wall_s: start.elapsed().as_secs_f64(),
        warnings: vec![],
    };
    report.warnings = opposite_pairs(&report.modes);
    report
        .warnings
        .extend(reversed_loads(&report.modes, report.lambda_base));
    report.warnings.extend(static_warning);
    if let Some(d) = out_dir {
        crate::output::write_json(&d.join("buckle.json"), &report)?;
        let rows: Vec<Vec<f64>> = report
            .modes
            .iter()
            .map(|m| {
                vec![
                    m.index as f64,
                    m.mu,
                    m.lambda_critical,
                    m.residual,
                    m.half_waves.unwrap_or(0.0),
                    m.wavelength.unwrap_or(0.0),
                ]
            })
            .collect();
        crate::output::write_csv_ids(
            &d.join("buckle.csv"),
            &[
                "mode",
                "mu",
                "lambda_critical",
                "residual",
                "half_waves",
                "wavelength",
            ],
            1,
            &rows,
        )?;
    }
    Ok(report)
}

/// Modes whose mu come in opposite pairs (|mu_i + mu_j| below 5 % of
/// |mu_i|): K_sigma is indefinite on a soft direction of K_0 (a slack
/// region, e.g. a strip's edge near a contact), where the linear
/// extrapolation of the tangent from the base state says nothing of the
/// path (the path's own detection, `anm run`, does).
fn opposite_pairs(modes: &[Mode]) -> Vec<String> {
    let mut w = vec![];
    for (i, a) in modes.iter().enumerate() {
        for b in &modes[i + 1..] {
            if a.mu * b.mu < 0.0 && (a.mu + b.mu).abs() < 0.05 * a.mu.abs() {
                w.push(format!(
                    "modes {} and {} have opposite mu ({:.3e}, {:.3e}): K_sigma is indefinite on a soft direction of K_0; the linearized critical load is not predictive there (locate the point on the path with `anm run`)",
                    a.index, b.index, a.mu, b.mu
                ));
            }
        }
    }
    w
}

/// A warning for modes with mu < 0 (review 14: a lambda_critical of 0.2246
/// below a base state of 0.9 that the path passed stable): their critical
/// load needs the load reversed from the base state. With it, that a
/// linearized analysis does not see limit points.
fn reversed_loads(modes: &[Mode], base: f64) -> Vec<String> {
    let negative: Vec<String> = modes
        .iter()
        .filter(|m| m.mu < 0.0)
        .map(|m| m.index.to_string())
        .collect();
    if negative.is_empty() {
        return vec![];
    }
    vec![format!(
        "mode(s) {} have mu < 0: their lambda_critical lies below the base state lambda = {base}, reached by unloading from it, not by loading on; and a linearized buckling analysis predicts bifurcations only, not limit points (locate those on the path with `anm run`)",
        negative.join(", ")
    )]
}

/// The eigenvalue table printed by `anm buckle`.
pub fn table(r: &BuckleReport) -> String {
    let about = match r.time_base {
        Some(t) => format!(
            "t = {t} (lambda = {}; {} sticking friction nodes tied, {} slipping)",
            r.lambda_base, r.sticking, r.slipping
        ),
        None => format!("lambda = {}", r.lambda_base),
    };
    let mut s = format!(
        "{}: linearized buckling about {about} ({} dofs, {} path steps; {} iterations, {} vectors, {} solves, {:.3} s)\n",
        r.scene, r.dofs, r.path_steps, r.iterations, r.subspace, r.solves, r.wall_s
    );
    s.push_str("| mode | mu | lambda_critical | residual | half-waves | wavelength | uz crests across y | at (x, y) | x where abs(uz) > max/2 |\n|---|---|---|---|---|---|---|---|---|\n");
    for m in &r.modes {
        s.push_str(&format!(
            "| {} | {:.9e} | {:.9e} | {:.1e} | {} {} | {} | {} |\n",
            m.index,
            m.mu,
            m.lambda_critical,
            m.residual,
            m.half_waves.map_or("-".into(), |h| format!("{h:.3}")),
            m.wave_direction.clone().unwrap_or_default(),
            m.wavelength.map_or("-".into(), |w| format!("{w:.6}")),
            m.wrinkles.map_or("- | - | -".into(), |w| format!(
                "{} | ({:.4}, {:.4}) | {:.4}–{:.4}",
                w.count, w.at[0], w.at[1], w.extent_x[0], w.extent_x[1]
            )),
        ));
    }
    for w in &r.warnings {
        s.push_str(&format!("warning: {w}\n"));
    }
    s
}

//! `anm buckle SCENE [--lambda L]`: linearized buckling about a state of
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
//! (Kt(+h) − Kt(−h)) / 2h, h = 1e-3 × |lambda_end|: exact for the shell's
//! tangent, which is quadratic in the state (St Venant–Kirchhoff with
//! quadratic strains), up to round-off of 1e-16 |K| / h. The eigenpairs
//! come from [`crate::linalg::eigen::pencil`] (subspace iteration on our
//! LDLᵀ factorization of K_0, which must be positive definite: a base
//! state past a critical point is refused with its negative pivot count).
//!
//! Outputs: the eigenvalue table on stdout; with `-o DIR`, buckle.csv,
//! buckle.json and one `buckle_mode_K.vtu` per mode (the mode on the
//! reference surface, [`crate::output::mode`]).

use crate::error::{Error, Result};
use crate::linalg::{LinearSolver, SparseMatrix, eigen};
use crate::output::mode;
use crate::run::build::build_model;
use crate::scene::shell::ShellScene;
use crate::series::path::Path as AnmPath;
use crate::series::stop::Stop;
use crate::series::{ContinuationProblem, continuation::factorize};
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
    /// ANM steps to reach it.
    pub path_steps: usize,
    pub modes: Vec<Mode>,
    pub iterations: usize,
    pub solves: usize,
    pub subspace: usize,
    pub wall_s: f64,
}

/// Linearized buckling of `scene` about the state at `lambda_base`
/// (module docs): `count` modes; files into `out_dir` when given.
pub fn buckle(
    scene: &ShellScene,
    lambda_base: f64,
    count: usize,
    out_dir: Option<&Path>,
) -> Result<BuckleReport> {
    let start = std::time::Instant::now();
    let mut model = build_model(scene)?;
    model.length_scale = scene.length_scale;
    let n = model.ndof();
    let mut cfg = scene.solver.clone();
    let scale = cfg.lambda_end.abs();
    cfg.lambda_scale = scale;
    let mut u0 = vec![0.0; n];
    let mut path_steps = 0;
    if lambda_base != 0.0 {
        cfg.lambda_end = lambda_base;
        let mut path = AnmPath::new(&mut model, u0.clone(), 0.0, cfg.clone());
        loop {
            match path.step() {
                Ok(_) => path_steps += 1,
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
    let mut lu = LinearSolver::new(cfg.linear);
    let mut stats = crate::series::Stats::default();
    let (k0, r_lambda) = model.tangent(&u0, lambda_base)?;
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
                 linearized buckling needs a stable base state (choose a smaller --lambda)"
            ),
        });
    }
    let ut: Vec<f64> = f0.solve(&r_lambda.iter().map(|x| -x).collect::<Vec<_>>());
    // (B2) by central differences along the prebuckling tangent.
    let h = 0.1 * scale;
    let at = |s: f64| -> Vec<f64> { u0.iter().zip(&ut).map(|(u, t)| u + s * t).collect() };
    let (kp, _) = model.tangent(&at(h), lambda_base + h)?;
    let (km, _) = model.tangent(&at(-h), lambda_base - h)?;
    let mut ks = SparseMatrix::new(n);
    for (i, j, v) in kp.entries() {
        ks.add(i, j, v / (2.0 * h));
    }
    for (i, j, v) in km.entries() {
        ks.add(i, j, -v / (2.0 * h));
    }
    let settings = eigen::Settings {
        count,
        ..Default::default()
    };
    let (pairs, work) = eigen::pencil(&f0, &|x| k0.mul_vec(x), &|x| ks.mul_vec(x), n, &settings)
        .map_err(|detail| Error::SingularMatrix {
            step: path_steps,
            param: "lambda",
            at: lambda_base,
            detail: format!("buckling eigenproblem: {detail}"),
        })?;
    let mut modes = vec![];
    for (i, p) in pairs.into_iter().enumerate() {
        let full = model.expand(&p.vector, 0.0);
        let wave = mode::wavelength(&model.x0, &full);
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
    let report = BuckleReport {
        scene: scene.file.display().to_string(),
        dofs: n,
        lambda_base,
        path_steps,
        modes,
        iterations: work.iterations,
        solves: work.solves,
        subspace: work.subspace,
        wall_s: start.elapsed().as_secs_f64(),
    };
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
        crate::output::write_csv(
            &d.join("buckle.csv"),
            &[
                "mode",
                "mu",
                "lambda_critical",
                "residual",
                "half_waves",
                "wavelength",
            ],
            &rows,
        )?;
    }
    Ok(report)
}

/// The eigenvalue table printed by `anm buckle`.
pub fn table(r: &BuckleReport) -> String {
    let mut s = format!(
        "{}: linearized buckling about lambda = {} ({} dofs, {} path steps; {} iterations, {} vectors, {} solves, {:.3} s)\n",
        r.scene, r.lambda_base, r.dofs, r.path_steps, r.iterations, r.subspace, r.solves, r.wall_s
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
    s
}

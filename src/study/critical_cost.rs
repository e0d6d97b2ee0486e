//! Cost of locating a critical point (issue 14, item 7): the ANM, which
//! finds it between two step ends and locates it on the series of the step
//! that holds it ([`crate::series::bifurcation`]), against the way of
//! incremental Newton codes (Abaqus, "Unstable collapse and postbuckling
//! analysis"; Crisfield vol. 2 §21): load increments of fixed size, each
//! converged by full Newton at fixed lambda, the stability indicator (the
//! negative pivots of the tangent's LDLᵀ) checked at every converged
//! point, and, once it changes, bisection in lambda (a Newton solve and a
//! factorization per halving) until the bracket is below `tol` relative.
//!
//! Both use the scene's model, residual, tangent and linear solver, so the
//! factorization counts compare the methods. Symmetric tangents only (the
//! indicator needs the inertia); a non-symmetric tangent is an error.

use crate::error::{Error, Result};
use crate::linalg::LinearSolver;
use crate::run::build::build_model;
use crate::run::run_loaded;
use crate::scene::shell::ShellScene;
use crate::series::continuation::factorize;
use crate::series::correct::{Metric, correct_at_lambda};
use crate::series::{ContinuationProblem, Stats};
use serde::Serialize;
use std::time::Instant;

/// How many times faster per unit load than the increment before a
/// load-controlled increment must move the displacements to be taken as a
/// snap past a limit point (here and in a Newton run's notes). Measured:
/// the snaps 5.1 (clamped arch, increments 0.1) and 25 times faster
/// (pinned arch, 0.03); approaching the limit, 2.6 times at most.
pub const SNAP: f64 = 4.0;

/// One method's location of the first critical point.
#[derive(Clone, Debug, Serialize)]
pub struct Location {
    pub method: String,
    pub lambda: f64,
    /// Width of the final bracket in lambda (0 where the method gives none).
    pub bracket: f64,
    /// Every factorization made up to the location (steps, corrections,
    /// indicator and location).
    pub factorizations: usize,
    pub wall_s: f64,
}

/// The ANM run of the scene: its first `bifurcation` or `limit_point`
/// event, with the factorizations of the steps before it and of its
/// location.
pub fn anm(scene: &ShellScene) -> Result<Location> {
    let start = Instant::now();
    let mut sc = scene.clone();
    sc.output.plot = false;
    let r = run_loaded(&sc, None, false)?;
    let e = r
        .events
        .iter()
        .find(|e| e.kind == "bifurcation" || e.kind == "limit_point")
        .ok_or_else(|| no_critical_point(scene, "the ANM path"))?;
    Ok(Location {
        method: "ANM (location on the step's series)".into(),
        lambda: e.lambda,
        bracket: e.bracket,
        // One factorization per step up to the one that holds the point
        // (plus the corrections made on the way, counted by the run only
        // as a total), then the location's own.
        factorizations: e.step + e.factorizations,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Most Newton load increments [`newton_bisection`] takes up to lambda_end.
const MAX_INCREMENTS: f64 = 1e6;

/// Newton increments of `increment` in lambda and bisection on the
/// negative-pivot count (module docs) to `tol` relative.
pub fn newton_bisection(scene: &ShellScene, increment: f64, tol: f64) -> Result<Location> {
    let start = Instant::now();
    let cfg = &scene.solver;
    // At most a million increments up to lambda_end (as the output grids):
    // --locate 1e-300 took increments forever (b + 1e-300 == b).
    let increments = cfg.lambda_end.abs() / increment;
    if !(increments <= MAX_INCREMENTS) {
        return Err(Error::Invalid {
            file: scene.file.clone(),
            key: "--locate".into(),
            problem: format!(
                "increments of {increment:e} up to lambda_end = {} are {increments:.3e} \
                 (at most {MAX_INCREMENTS:e})",
                cfg.lambda_end
            ),
        });
    }
    let mut model = build_model(scene)?;
    let metric = Metric::for_problem(&model, cfg.lambda_end.abs())?;
    let mut lu = LinearSolver::new(cfg.linear);
    let mut stats = Stats::default();
    let n = model.ndof();
    let not_symmetric = |l: f64| Error::Invalid {
        file: scene.file.clone(),
        key: "solver".into(),
        problem: format!(
            "the tangent at lambda = {l} is not symmetric: no negative-pivot count to bisect on"
        ),
    };
    let (k0, r_lambda) = model.tangent(&vec![0.0; n], 0.0)?;
    let scale = metric.residual_norm(&r_lambda).max(f64::MIN_POSITIVE);
    let count0 = factorize(&mut lu, &k0, &mut stats, 0, 0.0)?
        .inertia()
        .map(|i| i.0)
        .ok_or_else(|| not_symmetric(0.0))?;
    // The negative pivots of the tangent at (u, l).
    let indicator =
        |model: &mut _, lu: &mut _, u: &[f64], l: f64, stats: &mut Stats| -> Result<usize> {
            let (k, _) = ContinuationProblem::tangent(model, u, l)?;
            let f = factorize(lu, &k, stats, 0, l)?;
            f.inertia().map(|i| i.0).ok_or_else(|| not_symmetric(l))
        };
    let newton_tol = cfg.residual_tol;
    // Newton and the indicator share one solver (one symbolic analysis).
    let solve =
        |model: &mut _, lu: &mut _, u: &[f64], l: f64, stats: &mut Stats| -> Result<Vec<f64>> {
            correct_at_lambda(
                model,
                u.to_vec(),
                l,
                newton_tol,
                scale,
                &metric,
                cfg.max_corrections.max(25),
                lu,
                stats,
                0,
            )
            .map(|(u, _)| u)
        };
    // Increments until the indicator changes. Load control cannot pass a
    // limit point: an increment that does not converge, or that converges
    // with its displacements moving SNAP times faster than the increment
    // before (onto the far side of a snap), has one between its ends,
    // where the count of negative pivots need not differ (review 14: "no
    // critical point" on an arch with a limit point at 0.9986).
    let passed = |a: f64, b: f64, what: String| {
        Error::study(
            "locate",
            scene.file.display().to_string(),
            format!(
                "the load-controlled Newton increment from lambda = {a:.6} to {b:.6} {what}: a limit point lies between them, which load control cannot pass (the ANM locates it; a smaller --locate increment brackets it closer but never crosses it)"
            ),
        )
    };
    let (mut a, mut ua) = (0.0, vec![0.0; n]);
    let mut b = increment;
    let mut last_rate: Option<f64> = None;
    loop {
        if b > cfg.lambda_end.abs() * (1.0 + 1e-12) {
            return Err(no_critical_point(scene, "the Newton increments"));
        }
        let ub = match solve(&mut model, &mut lu, &ua, b, &mut stats) {
            Ok(u) => u,
            Err(e) if e.is_numerical() => {
                return Err(passed(a, b, format!("did not converge ({e})")));
            }
            Err(e) => return Err(e),
        };
        let du: Vec<f64> = ub.iter().zip(&ua).map(|(x, y)| x - y).collect();
        let rate = metric.dot_u(&du, &du).sqrt() / (b - a);
        if let Some(r) = last_rate
            && rate > SNAP * r
        {
            return Err(passed(
                a,
                b,
                format!(
                    "moved the displacements {:.0} times faster than the one before",
                    rate / r
                ),
            ));
        }
        last_rate = Some(rate);
        if indicator(&mut model, &mut lu, &ub, b, &mut stats)? != count0 {
            break;
        }
        (a, ua) = (b, ub);
        b += increment;
    }
    while b - a > tol * b.abs() {
        let m = 0.5 * (a + b);
        let um = solve(&mut model, &mut lu, &ua, m, &mut stats)?;
        if indicator(&mut model, &mut lu, &um, m, &mut stats)? == count0 {
            (a, ua) = (m, um);
        } else {
            b = m;
        }
    }
    Ok(Location {
        method: format!("Newton, increments {increment}, bisection on the negative pivots"),
        lambda: 0.5 * (a + b),
        bracket: b - a,
        factorizations: stats.factorizations,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

fn no_critical_point(scene: &ShellScene, by: &str) -> Error {
    Error::Invalid {
        file: scene.file.clone(),
        key: "solver.lambda_end".into(),
        problem: format!("{by} found no critical point up to lambda_end"),
    }
}

/// The markdown table of locations of one scene.
pub fn table(scene: &str, rows: &[Location]) -> String {
    let mut s = format!(
        "\n### {scene}\n\n| method | located lambda | bracket | factorizations | wall (s) |\n|---|---|---|---|---|\n"
    );
    for r in rows {
        s += &format!(
            "| {} | {:.9} | {:.1e} | {} | {:.3} |\n",
            r.method, r.lambda, r.bracket, r.factorizations, r.wall_s
        );
    }
    s
}

//! What one ANM step on the plate-cylinder shell costs, part by part
//! (assembly, factorization, solves, series terms), against the issue's
//! target: step <= 1.5 x (one factorization + N solves).
//!
//! Ignored (a measurement, not a check; about a minute):
//! `cargo test --release --test shell step_cost -- --ignored --nocapture`.
//! The path is followed to lambda = 0.3 (contact active), then the step from
//! there is repeated and each part timed; the minimum over the repetitions is
//! printed, the least disturbed by other work on a shared machine. "parts"
//! sums the parts of one step (tangent, factorization, N solves, N − 1
//! terms, one residual); "step" times whole steps, which a loaded machine
//! rarely leaves undisturbed for their whole length (parts is the figure).

use anm::linalg::{Factorization, LinearSolver, dot};
use anm::run::build::build_model;
use anm::scene::shell::load;
use anm::series::ContinuationProblem;
use anm::series::continuation::run;
use anm::shell::ShellModel;
use std::time::Instant;

/// The scene with mesh `mesh`, loaded from a temporary file that is gone
/// once it returns (a loaded scene runs without its file).
fn scene_with_mesh(mesh: &str) -> anm::scene::shell::ShellScene {
    let text = std::fs::read_to_string("scenes/plate-cylinder.toml")
        .unwrap()
        .replace(
            "../meshes/plate-cylinder.msh",
            &format!("{}/meshes/{mesh}", env!("CARGO_MANIFEST_DIR")),
        );
    let path = crate::scratch::ScratchFile::with_text("step-cost", "scene.toml", &text);
    load(&path).unwrap()
}

/// Minimum wall time of `reps` calls of `f`: the repetition least
/// disturbed by other work on a shared machine.
fn min_time(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The series of one step as the engine computes it: order 1 from the
/// tangent, then per order p the right-hand side, a solve and lambda_p.
fn series(
    m: &mut ShellModel,
    f: &Factorization,
    rl: &[f64],
    u0: &[f64],
    l0: f64,
    order: usize,
) -> (Vec<Vec<f64>>, Vec<f64>) {
    let neg = |b: &[f64]| b.iter().map(|x| -x).collect::<Vec<_>>();
    let ut = f.solve(&neg(rl));
    let l1 = 1.0 / (1.0 + dot(&ut, &ut)).sqrt();
    let mut us = vec![u0.to_vec(), ut.iter().map(|x| l1 * x).collect()];
    let mut ls = vec![l0, l1];
    let denom = dot(&ut, &us[1]) + l1;
    for p in 2..=order {
        let ub = f.solve(&neg(&m.series_rhs(p, &us, &ls).unwrap()));
        let lp = -dot(&ub, &us[1]) / denom;
        us.push(ub.iter().zip(&ut).map(|(b, t)| b + lp * t).collect());
        ls.push(lp);
    }
    (us, ls)
}

/// One step: tangent, factorization, series, residual at the step end.
fn step(m: &mut ShellModel, lu: &mut LinearSolver, u0: &[f64], l0: f64, order: usize) {
    let (k, rl) = m.tangent(u0, l0).unwrap();
    let f = lu.factorize(&k).unwrap();
    let (us, ls) = series(m, &f, &rl, u0, l0, order);
    let a = 1e-3;
    let u: Vec<f64> = (0..u0.len())
        .map(|i| us.iter().rev().fold(0.0, |acc, t| acc * a + t[i]))
        .collect();
    let l = ls.iter().rev().fold(0.0, |acc, t| acc * a + t);
    m.residual(&u, l).unwrap();
}

#[test]
#[ignore]
fn plate_cylinder_step_cost() {
    println!(
        "{:>6} {:>5} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "mesh",
        "dofs",
        "trip",
        "tangent",
        "factor",
        "solve",
        "term",
        "residual",
        "parts",
        "step",
        "ratio"
    );
    for (label, mesh) in [
        ("20x2", "plate-cylinder-20x2.msh"),
        ("40x4", "plate-cylinder.msh"),
    ] {
        let scene = scene_with_mesh(mesh);
        let mut m = build_model(&scene).unwrap();
        let mut cfg = scene.solver.clone();
        cfg.lambda_end = 0.3;
        let n = m.ndof();
        let res = run(&mut m, vec![0.0; n], 0.0, &cfg, |_, _| Ok(()));
        assert!(res.error().is_none(), "{:?}", res.error());
        assert!(!m.active_pairs().is_empty(), "contact must be active");
        let order = cfg.order;
        let (u0, l0) = (res.u_end, res.lambda_end);
        let mut lu = LinearSolver::default();
        let (k, rl) = m.tangent(&u0, l0).unwrap();
        let f = lu.factorize(&k).unwrap();
        let (us, ls) = series(&mut m, &f, &rl, &u0, l0, order);
        let reps = 51;
        let tangent = min_time(reps, || drop(m.tangent(&u0, l0).unwrap()));
        let factor = min_time(reps, || drop(lu.factorize(&k).unwrap()));
        let solve = min_time(reps, || {
            for u in &us[1..] {
                drop(f.solve(u));
            }
        }) / order as f64;
        // Each term timed alone (minimum per order), after a tangent that
        // restarts the series at order 0.
        let mut term_min = vec![f64::INFINITY; order + 1];
        for _ in 0..reps {
            m.tangent(&u0, l0).unwrap();
            for p in 2..=order {
                let t = Instant::now();
                drop(m.series_rhs(p, &us[..p], &ls[..p]).unwrap());
                term_min[p] = term_min[p].min(t.elapsed().as_secs_f64());
            }
        }
        let term = term_min[2..].iter().sum::<f64>() / (order - 1) as f64;
        let residual = min_time(reps, || drop(m.residual(&u0, l0).unwrap()));
        let whole = min_time(reps, || step(&mut m, &mut lu, &u0, l0, order));
        let parts = tangent + factor + order as f64 * solve + (order - 1) as f64 * term + residual;
        let ms = |s: f64| s * 1e3;
        let ratio = parts / (factor + order as f64 * solve);
        println!(
            "{label:>6} {n:>5} {:>6} {:>9.3} {:>9.3} {:>9.4} {:>9.4} {:>9.3} {:>9.3} {:>9.3} {ratio:>9.2}",
            k.stored(),
            ms(tangent),
            ms(factor),
            ms(solve),
            ms(term),
            ms(residual),
            ms(parts),
            ms(whole),
        );
    }
    println!(
        "(ms, minimum over 51 repetitions at the state lambda = 0.3; trip: triplets of the tangent; ratio = parts / (factorization + N solves), N = 15)"
    );
}

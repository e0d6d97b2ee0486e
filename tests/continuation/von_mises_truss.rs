//! Shallow two-bar (von Mises) truss snap-through: closed form, e.g. Crisfield,
//! *Non-linear Finite Element Analysis of Solids and Structures*, vol. 1
//! (1991), §1.2 and §9.
//!
//! Goal: the arclength ANM follows the equilibrium path through both limit
//! points, with error <= 1e-8 against the closed form and one factorization
//! per step; Padé approximants extend the steps (30-dof test below).
//!
//! ```text
//!              P = lambda P_ref
//!                  |  w
//!                  v
//!                 /\          H = 0.1, half-span L = 1
//!               /    \        EA = 1, bars of length L0 = sqrt(L^2 + H^2)
//!            ///      ///
//! ```
//! Green-Lagrange bar strain E = (w^2 - 2 H w) / (2 L0^2), axial force EA E;
//! vertical equilibrium: P(w) = EA (w^2 - 2 H w)(w - H) / L0^3.
//! Limit points at w = H (1 -+ 1/sqrt(3)), lambda = ±2 H^3 EA / (3 sqrt(3) L0^3 P_ref).

use anm::series::TapeProblem;
use anm::series::continuation::{ContinuationConfig, run};

const H: f64 = 0.1;
const EA: f64 = 1.0;
const P_REF: f64 = 1e-4;

fn l0() -> f64 {
    (1.0 + H * H).sqrt()
}

fn lambda_exact(w: f64) -> f64 {
    EA * (w * w - 2.0 * H * w) * (w - H) / l0().powi(3) / P_REF
}

fn truss(order: usize) -> TapeProblem {
    TapeProblem::new(1, order, |_b, u, lambda| {
        let w = u[0];
        let c = EA / l0().powi(3);
        vec![c * (w * w - 2.0 * H * w) * (w - H) - P_REF * lambda]
    })
}

/// Runs to lambda_end past the second limit point; returns (max error, steps,
/// factorizations, max w reached) with points checked inside every step.
fn follow(pade: bool) -> (f64, usize, usize, f64) {
    follow_eps(pade, 1e-12)
}

fn follow_eps(pade: bool, eps: f64) -> (f64, usize, usize, f64) {
    let lmax = 2.0 * H.powi(3) * EA / (3.0 * 3f64.sqrt() * l0().powi(3)) / P_REF;
    let cfg = ContinuationConfig {
        order: 20,
        eps,
        lambda_end: 2.0 * lmax,
        pade,
        residual_tol: 1e-9,
        ..Default::default()
    };
    let mut problem = truss(cfg.order);
    let mut worst: f64 = 0.0;
    let mut w_max: f64 = 0.0;
    let result = run(&mut problem, vec![0.0], 0.0, &cfg, |step, _| {
        for k in 0..=8 {
            let a = step.length * k as f64 / 8.0;
            let (u, l) = step.eval(a);
            worst = worst.max((l - lambda_exact(u[0])).abs() / lmax);
            w_max = w_max.max(u[0]);
        }
        Ok(())
    });
    assert_eq!(result.stop, "end", "{:?}", result.error());
    (
        worst,
        result.stats.steps,
        result.stats.factorizations,
        w_max,
    )
}

#[test]
fn follows_the_snap_through_path_within_1e_8() {
    println!("max |lambda - lambda(w)| / lambda_max   steps  factorizations");
    {
        let (err, steps, facts, w_max) = follow(false);
        println!("{err:<40.2e} {steps:<6} {facts}");
        // Past both limit points (w = 0.042 and 0.158) and beyond the flat state w = 2H.
        assert!(w_max > 2.0 * H, "path stopped at w = {w_max}");
        assert!(err <= 1e-8, "error {err:e}");
        assert_eq!(facts, steps, "one factorization per step");
    }
}

#[test]
fn error_shrinks_with_eps() {
    // Truncation control: the error follows the tolerance (about 100 eps here).
    println!("eps      max error   steps");
    let mut last = f64::INFINITY;
    for eps in [1e-6, 1e-8, 1e-10, 1e-12] {
        let (err, steps, _, _) = follow_eps(false, eps);
        println!("{eps:<8.0e} {err:<11.2e} {steps}");
        assert!(err < last && err < 1e3 * eps, "eps {eps:e}: error {err:e}");
        last = err;
    }
}

/// 30 independent softening springs sharing one load parameter:
/// R_i = k_i w_i - alpha_i w_i^2 - lambda P_i, so on the path every dof obeys
/// lambda = (k_i w_i - alpha_i w_i^2) / P_i, with a limit point at
/// lambda_i = k_i^2 / (4 alpha_i P_i). Enough independent series terms for
/// the common-denominator Padé approximants (the 1-dof truss has not).
#[test]
fn pade_covers_more_path_in_the_same_steps_on_a_30_dof_problem() {
    let n = 30;
    let k: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * i as f64).collect();
    let alpha: Vec<f64> = (0..n).map(|i| 0.5 + 0.05 * (i as f64).sin()).collect();
    let p: Vec<f64> = (0..n).map(|i| 1.0 + 0.02 * i as f64).collect();
    let lam = |i: usize, w: f64| (k[i] * w - alpha[i] * w * w) / p[i];
    let lmin = (0..n)
        .map(|i| k[i] * k[i] / (4.0 * alpha[i] * p[i]))
        .fold(f64::INFINITY, f64::min);
    // Both runs take the same number of steps toward a target they never
    // reach (the path turns back at the first limit point); Padé must cover
    // more of the path (sum of step lengths a) at the same accuracy.
    println!("method      max error   steps  arclength covered");
    let mut covered = vec![];
    for pade in [false, true] {
        let cfg = ContinuationConfig {
            order: 20,
            eps: 1e-12,
            lambda_end: 2.0 * lmin,
            pade,
            residual_tol: 1e-10,
            max_steps: 15,
            ..Default::default()
        };
        let (kc, ac, pc) = (k.clone(), alpha.clone(), p.clone());
        let mut problem = TapeProblem::new(n, cfg.order, move |_b, u, lambda| {
            (0..n)
                .map(|i| kc[i] * u[i] - ac[i] * u[i] * u[i] - pc[i] * lambda)
                .collect()
        });
        let mut worst: f64 = 0.0;
        let mut passed_limit = false;
        let mut length = 0.0;
        let result = run(&mut problem, vec![0.0; n], 0.0, &cfg, |step, _| {
            for s in 0..=8 {
                let (u, l) = step.eval(step.length * s as f64 / 8.0);
                for (i, w) in u.iter().enumerate() {
                    worst = worst.max((l - lam(i, *w)).abs() / lmin);
                }
            }
            passed_limit |= step.lambda[1] < 0.0;
            length += step.length;
            Ok(())
        });
        assert_eq!(result.stop, "max_steps", "{:?}", result.error());
        println!(
            "{:<11} {worst:<11.2e} {:<6} {length:.4}",
            if pade { "ANM+Pade" } else { "ANM" },
            result.stats.steps
        );
        assert!(
            passed_limit,
            "the path must turn back at the first limit point"
        );
        assert!(worst <= 1e-8, "error {worst:e}");
        covered.push(length);
    }
    assert!(
        covered[1] > covered[0],
        "Padé covers {} vs polynomial {}",
        covered[1],
        covered[0]
    );
}

#[test]
fn newton_baseline_follows_the_same_path() {
    // Arclength Newton (the baseline of the benchmarks) through both limit
    // points, landing exactly on requested load levels. Load control cannot
    // follow the unstable part: past lambda_max it snaps through to the far
    // stable branch, w > H (1 + 1/sqrt 3).
    use anm::series::newton::{Control, NewtonConfig, run as newton};
    let lmax = 2.0 * H.powi(3) * EA / (3.0 * 3f64.sqrt() * l0().powi(3)) / P_REF;
    let targets = [0.5 * lmax, 1.5 * lmax];
    let cfg = NewtonConfig {
        control: Control::Arclength,
        initial_step: 0.1,
        tol: 1e-12,
        lambda_end: 2.0 * lmax,
        ..Default::default()
    };
    let mut problem = truss(2);
    let mut worst: f64 = 0.0;
    let mut hits = vec![];
    let mut w_max: f64 = 0.0;
    let r = newton(&mut problem, vec![0.0], 0.0, &cfg, &targets, |u, l, _| {
        worst = worst.max((l - lambda_exact(u[0])).abs() / lmax);
        w_max = w_max.max(u[0]);
        if targets
            .iter()
            .chain([&(2.0 * lmax)])
            .any(|t| (t - l).abs() < 1e-12)
        {
            hits.push(l);
        }
        Ok(())
    });
    println!(
        "Newton arclength: stop {}, {} steps, {} factorizations, error {worst:.1e}, targets hit {hits:?}",
        r.stop.reason(),
        r.stats.steps,
        r.stats.factorizations
    );
    assert_eq!(r.stop, "end", "{:?}", r.error());
    assert!(w_max > 2.0 * H);
    assert!(worst <= 1e-10, "error {worst:e}");
    assert!(hits.len() >= 3, "targets hit: {hits:?}");

    let load = NewtonConfig {
        control: Control::Load,
        ..cfg
    };
    let mut problem = truss(2);
    let mut snapped = None;
    let r = newton(&mut problem, vec![0.0], 0.0, &load, &[], |u, l, _| {
        if l > lmax && snapped.is_none() {
            snapped = Some((l, u[0]));
        }
        Ok(())
    });
    println!(
        "Newton load control: stop {}; first point past lambda_max: {snapped:?}",
        r.stop.reason()
    );
    let (_, w) = snapped.expect("a converged point past lambda_max");
    assert!(
        w > H * (1.0 + 1.0 / 3f64.sqrt()),
        "w = {w}: not on the far branch"
    );
    assert!((w * w - 2.0 * H * w) * (w - H) > 0.0);
}

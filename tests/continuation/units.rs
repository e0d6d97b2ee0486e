//! Step control independent of units (DESIGN §1, last paragraph), and exact
//! resume of the caller-driven stepper from a serialized checkpoint.
//!
//! Problem: the shallow von Mises truss of `continuation_von_mises_truss.rs`,
//! R(w, lambda) = EA (w^2 - 2 H w)(w - H) / L0^3 - P_ref lambda, written once
//! with lengths in m and once in mm. EA and P_ref are forces (N) in both, so
//! the residual is the same force and the physics is identical; w differs by
//! the factor 1000. With unknown_scale = H (the rise, in each unit system) and
//! lambda_scale = |lambda_end - lambda0| the engine sees the same scaled
//! problem and must take the same steps.

use anm::linalg::SparseMatrix;
use anm::series::continuation::{ContinuationConfig, ContinuationProblem, run};
use anm::series::{Checkpoint, Path, PathStep, Stop, TapeProblem};

const EA: f64 = 1.0;
const P_REF: f64 = 1e-4;

/// The truss with lengths multiplied by `unit` (1 for m, 1000 for mm), and
/// `scaled` choosing unknown_scale = H (else the default 1).
struct Truss {
    tape: TapeProblem,
    h: f64,
    scaled: bool,
}

impl Truss {
    fn new(unit: f64, order: usize, scaled: bool) -> Self {
        let h = 0.1 * unit;
        let l0 = (unit * unit + h * h).sqrt();
        let tape = TapeProblem::new(1, order, move |_b, u, lambda| {
            let w = u[0];
            let c = EA / (l0 * l0 * l0);
            vec![c * (w * w - 2.0 * h * w) * (w - h) - P_REF * lambda]
        });
        Self { tape, h, scaled }
    }
}

impl ContinuationProblem for Truss {
    fn ndof(&self) -> usize {
        1
    }
    fn residual(&mut self, u: &[f64], lambda: f64) -> anm::Result<Vec<f64>> {
        self.tape.residual(u, lambda)
    }
    fn tangent(&mut self, u: &[f64], lambda: f64) -> anm::Result<(SparseMatrix, Vec<f64>)> {
        self.tape.tangent(u, lambda)
    }
    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], lambda: &[f64]) -> anm::Result<Vec<f64>> {
        self.tape.series_rhs(p, u, lambda)
    }
    fn unknown_scale(&self) -> Vec<f64> {
        vec![if self.scaled { self.h } else { 1.0 }]
    }
}

/// lambda at the first limit point (the same in both unit systems).
fn lambda_max() -> f64 {
    let l0 = (1.0f64 + 0.01).sqrt();
    2.0 * 0.1f64.powi(3) * EA / (3.0 * 3f64.sqrt() * l0.powi(3)) / P_REF
}

fn config(scaled: bool) -> ContinuationConfig {
    let lambda_end = 2.0 * lambda_max();
    ContinuationConfig {
        order: 20,
        eps: 1e-10,
        lambda_end,
        residual_tol: 1e-9,
        lambda_scale: if scaled { lambda_end } else { 1.0 },
        ..Default::default()
    }
}

/// lambda on the path at w (m), closed form.
fn lambda_exact(w: f64) -> f64 {
    let (h, l0) = (0.1, (1.0f64 + 0.01).sqrt());
    EA * (w * w - 2.0 * h * w) * (w - h) / l0.powi(3) / P_REF
}

/// Step ends (w in m, lambda), the step count and the largest error
/// |lambda - lambda(w)| / lambda_max inside the steps of a run to 2 lambda_max.
fn follow(unit: f64, scaled: bool) -> (Vec<(f64, f64)>, usize, Stop, f64) {
    let cfg = config(scaled);
    let mut problem = Truss::new(unit, cfg.order, scaled);
    let mut ends = vec![];
    let mut worst: f64 = 0.0;
    let result = run(&mut problem, vec![0.0], 0.0, &cfg, |s, _| {
        for k in 0..=8 {
            let (u, l) = s.eval(s.length * k as f64 / 8.0);
            worst = worst.max((l - lambda_exact(u[0] / unit)).abs() / lambda_max());
        }
        ends.push((s.u_end[0] / unit, s.lambda_end));
        Ok(())
    });
    (ends, result.stats.steps, result.stop, worst)
}

#[test]
fn same_steps_in_m_and_mm_with_scaling() {
    let lmax = lambda_max();
    let (m, steps_m, stop_m, err_m) = follow(1.0, true);
    let (mm, steps_mm, stop_mm, err_mm) = follow(1000.0, true);
    let (_, raw_m, raw_stop_m, raw_err_m) = follow(1.0, false);
    let (_, raw_mm, raw_stop_mm, raw_err_mm) = follow(1000.0, false);
    println!("units  scaled: steps  error     unscaled: steps  error     stop");
    println!(
        "m      {steps_m:<14} {err_m:<9.2e} {raw_m:<16} {raw_err_m:<9.2e} {}",
        raw_stop_m.reason()
    );
    println!(
        "mm     {steps_mm:<14} {err_mm:<9.2e} {raw_mm:<16} {raw_err_mm:<9.2e} {}",
        raw_stop_mm.reason()
    );
    // Accuracy of the scaled runs (eps = 1e-10; about 100 eps, as unscaled).
    assert!(err_m.max(err_mm) <= 1e-7, "error {:e}", err_m.max(err_mm));
    assert!(stop_m.is_end(), "{stop_m}");
    assert!(stop_mm.is_end(), "{stop_mm}");
    assert_eq!(steps_m, steps_mm, "scaled runs take different steps");
    // The same points, converted back to m: to 1e-8 of the path's scales.
    let mut worst: f64 = 0.0;
    for ((wm, lm), (wmm, lmm)) in m.iter().zip(&mm) {
        worst = worst
            .max((wm - wmm).abs() / 0.1)
            .max((lm - lmm).abs() / lmax);
    }
    println!("largest difference of the step ends (|dw| / H, |dlambda| / lambda_max): {worst:.2e}");
    assert!(worst <= 1e-8, "step ends differ by {worst:e}");
    // Both pass the second limit point and the flat state w = 2H.
    assert!(m.iter().any(|(w, _)| *w > 0.2), "path stopped early");
}

/// Steps of an uninterrupted Path run: (index, length, U_end, lambda_end, terms).
fn steps_of(path: &mut Path<'_, Truss>, until: Option<usize>) -> (Vec<PathStep>, Stop) {
    let mut out = vec![];
    loop {
        if until.is_some_and(|k| out.len() >= k) {
            return (
                out,
                Stop::Interrupted {
                    lambda: path.state().1,
                },
            );
        }
        match path.step() {
            Ok(s) => out.push(s),
            Err(stop) => return (out, stop),
        }
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

#[test]
fn resume_from_a_serialized_checkpoint_repeats_the_run() {
    let cfg = config(true);
    let k = 3;
    // Uninterrupted.
    let mut p1 = Truss::new(1000.0, cfg.order, true);
    let mut path = Path::new(&mut p1, vec![0.0], 0.0, cfg.clone());
    let (all, stop) = steps_of(&mut path, None);
    assert!(stop.is_end(), "{stop}");
    assert!(
        all.len() > k + 2,
        "too few steps ({}) for the test",
        all.len()
    );
    // Every call after the stop repeats it.
    let again = path.step().expect_err("the path has ended");
    assert_eq!(again.reason(), "end");
    let (u_final, l_final) = (path.state().0.to_vec(), path.state().1);
    let final_stats = path.stats().clone();

    // Interrupted after k steps, checkpoint through JSON, resumed on a new problem.
    let mut p2 = Truss::new(1000.0, cfg.order, true);
    let mut path = Path::new(&mut p2, vec![0.0], 0.0, cfg.clone());
    let (first, interrupted) = steps_of(&mut path, Some(k));
    assert_eq!(interrupted.reason(), "interrupted");
    assert_eq!(first.len(), k);
    let cp = path.checkpoint();
    let json = serde_json::to_string(&cp).unwrap();
    let back: Checkpoint = serde_json::from_str(&json).unwrap();
    assert_eq!(back.index, k);
    assert_eq!(back.u[0].to_bits(), cp.u[0].to_bits());
    assert_eq!(back.lambda.to_bits(), cp.lambda.to_bits());
    let (du, dl) = back.prev_dir.clone().unwrap();
    let (cu, cl) = cp.prev_dir.clone().unwrap();
    assert_eq!(du[0].to_bits(), cu[0].to_bits());
    assert_eq!(dl.to_bits(), cl.to_bits());
    drop(path);
    let mut p3 = Truss::new(1000.0, cfg.order, true);
    let mut path = Path::resume(&mut p3, back, cfg.clone());
    let (rest, stop) = steps_of(&mut path, None);
    assert!(stop.is_end(), "{stop}");
    assert_eq!(k + rest.len(), all.len(), "resumed run takes other steps");
    let mut worst: f64 = 0.0;
    for (a, b) in all[k..].iter().zip(&rest) {
        assert_eq!(a.index, b.index);
        worst = worst
            .max(rel(a.length, b.length))
            .max(rel(a.u_end[0], b.u_end[0]))
            .max(rel(a.lambda_end, b.lambda_end));
        for (x, y) in a.u.iter().zip(&b.u) {
            worst = worst.max(rel(x[0], y[0]));
        }
        for (x, y) in a.lambda.iter().zip(&b.lambda) {
            worst = worst.max(rel(*x, *y));
        }
    }
    worst = worst
        .max(rel(u_final[0], path.state().0[0]))
        .max(rel(l_final, path.state().1));
    println!(
        "resume after {k} of {} steps: largest relative difference {worst:.1e}",
        all.len()
    );
    assert!(worst <= 1e-12, "resumed run differs by {worst:e}");
    assert_eq!(path.stats().steps, final_stats.steps);
    assert_eq!(path.stats().factorizations, final_stats.factorizations);
}

#[test]
fn checkpoint_round_trips_bit_exactly_through_json() {
    let awkward = [
        0.1 + 0.2,
        std::f64::consts::PI,
        -0.0,
        1e-310, // subnormal
        f64::MAX,
        -f64::MIN_POSITIVE,
        1.0 / 3.0,
        f64::NAN,
        f64::INFINITY,
    ];
    let stats = anm::series::Stats {
        steps: 7,
        solve_s: 0.1 + 0.7,
        ..Default::default()
    };
    let cp = Checkpoint {
        index: 7,
        u: awkward.to_vec(),
        lambda: 0.1 + 0.2,
        prev_dir: Some((awkward.iter().rev().copied().collect(), -1.0 / 7.0)),
        prev_length: Some(0.1 + 0.2),
        stats,
    };
    let json = serde_json::to_string(&cp).unwrap();
    let back: Checkpoint = serde_json::from_str(&json).unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&back.u), bits(&cp.u));
    assert_eq!(back.lambda.to_bits(), cp.lambda.to_bits());
    let (bu, bl) = back.prev_dir.unwrap();
    let (cu, cl) = cp.prev_dir.unwrap();
    assert_eq!(bits(&bu), bits(&cu));
    assert_eq!(bl.to_bits(), cl.to_bits());
    assert_eq!(back.index, 7);
    assert_eq!(back.stats.steps, 7);
    // Timings are plain JSON numbers (serde_json's parser may be 1 ulp off).
    assert!((back.stats.solve_s - cp.stats.solve_s).abs() <= 1e-15);
}

#[test]
fn invalid_scales_stop_the_path() {
    let mut cfg = config(true);
    cfg.lambda_scale = 0.0;
    let mut p = Truss::new(1.0, cfg.order, true);
    let mut path = Path::new(&mut p, vec![0.0], 0.0, cfg);
    let stop = path.step().expect_err("lambda_scale = 0 is invalid");
    assert_eq!(stop.reason(), "invalid_input");
    assert_eq!(
        path.step().expect_err("stays stopped").reason(),
        "invalid_input"
    );
}

#[test]
fn newton_arclength_takes_the_same_steps_in_m_and_mm_with_scaling() {
    use anm::series::newton::{Control, NewtonConfig, run as newton};
    let lambda_end = 2.0 * lambda_max();
    let follow = |unit: f64, scaled: bool| {
        let cfg = NewtonConfig {
            control: Control::Arclength,
            initial_step: 0.05,
            max_step: 0.2,
            tol: 1e-12,
            lambda_end,
            lambda_scale: if scaled { lambda_end } else { 1.0 },
            ..Default::default()
        };
        let mut p = Truss::new(unit, 2, scaled);
        let mut points = vec![];
        let r = newton(&mut p, vec![0.0], 0.0, &cfg, &[], |u, l, _| {
            points.push((u[0] / unit, l));
            Ok(())
        });
        assert!(r.stop.is_end(), "{}", r.stop);
        (points, r.stats.steps, r.stats.factorizations)
    };
    let (m, steps_m, facts_m) = follow(1.0, true);
    let (mm, steps_mm, facts_mm) = follow(1000.0, true);
    let (_, raw_m, _) = follow(1.0, false);
    let (_, raw_mm, _) = follow(1000.0, false);
    println!(
        "Newton arclength steps (factorizations): scaled m {steps_m} ({facts_m}), mm {steps_mm} ({facts_mm}); unscaled m {raw_m}, mm {raw_mm}"
    );
    assert_eq!((steps_m, facts_m), (steps_mm, facts_mm));
    let worst = m
        .iter()
        .zip(&mm)
        .map(|((a, b), (c, d))| ((a - c).abs() / 0.1).max((b - d).abs() / lambda_max()))
        .fold(0.0f64, f64::max);
    assert!(worst <= 1e-8, "points differ by {worst:e}");
}

#[test]
fn correct_at_lambda_returns_to_the_path_at_fixed_load() {
    use anm::linalg::LinearSolver;
    use anm::series::{Stats, correct_at_lambda};
    // On the first stable branch, w = 0.02 m; lambda from the closed form.
    let w = 0.02;
    let lambda = lambda_exact(w);
    let mut p = Truss::new(1.0, 2, true);
    let (mut lu, mut stats) = (LinearSolver::default(), Stats::default());
    let (u, it) = correct_at_lambda(
        &mut p,
        vec![1.05 * w],
        lambda,
        1e-12,
        P_REF,
        &anm::series::correct::Metric::unit(),
        20,
        &mut lu,
        &mut stats,
        0,
    )
    .unwrap();
    println!(
        "fixed-load correction: {it} iterations, {} factorizations, w error {:.1e}",
        stats.factorizations,
        (u[0] - w).abs() / w
    );
    assert!(it > 0 && stats.factorizations == it, "full Newton");
    assert!((u[0] - w).abs() <= 1e-9 * w);
    // A point on the path costs one residual and no iteration.
    let (u2, it2) = correct_at_lambda(
        &mut p,
        u.clone(),
        lambda,
        1e-12,
        P_REF,
        &anm::series::correct::Metric::unit(),
        20,
        &mut lu,
        &mut stats,
        0,
    )
    .unwrap();
    assert_eq!((it2, u2[0].to_bits()), (0, u[0].to_bits()));
    // Too few iterations: no convergence, with the values.
    let e = correct_at_lambda(
        &mut p,
        vec![1.5 * w],
        lambda,
        1e-14,
        P_REF,
        &anm::series::correct::Metric::unit(),
        1,
        &mut lu,
        &mut stats,
        3,
    )
    .unwrap_err();
    assert_eq!(e.kind(), "no_convergence", "{e}");
}

//! A contact event crossed by the engine (src/series/events.rs): one unknown
//! u, a spring k_s pushed by lambda F toward a rigid wall at gap delta, with
//! the regularized law of paper eq. (3) (K = 1e9 N/m, eta = 1e-6 N, the
//! plate-cylinder values):
//!
//! ```text
//!   k_s u + R(h) = lambda F,  h = delta - u,  R (R/K + h) = eta (delta - h)
//!
//!   F --> [k_s]~~~~o u      | wall at u = delta
//! ```
//!
//! Reference: the scalar equilibrium solved by bisection at each lambda
//! (R(h) in closed form, NormalLaw::force). Goal: with events on, the
//! contact (at lambda ≈ k_s delta / F = 0.1) is crossed by one jump instead
//! of the steps that shrink toward it and grow back, at the same accuracy.

use anm::contact::log_reaction::LogReaction;
use anm::contact::normal::NormalLaw;
use anm::error::Result;
use anm::linalg::{Choice, LinearSolver, SparseMatrix};
use anm::series::continuation::{ArcCoordinates, ContinuationConfig, ContinuationProblem, run};
use anm::series::{Metric, Stats, correct_at_lambda};

const KS: f64 = 1e3;
const F: f64 = 1.0;

struct Spring {
    law: NormalLaw,
    /// Weight c of the arc coordinate c ln(R + eta) (0: none).
    arc: f64,
    /// u at the last tangent (the step start).
    u0: f64,
    /// R_0..R_p of the last right-hand side (R_p with h_p = 0).
    r: Vec<f64>,
}

impl Spring {
    /// R_0..R_p of R(h(a)) with h_p replaced by `hp`.
    fn force_series(&self, u: &[Vec<f64>], p: usize, hp: f64) -> Vec<f64> {
        let mut h: Vec<f64> = u.iter().map(|x| -x[0]).collect();
        h[0] += self.law.delta;
        h.truncate(p);
        h.push(hp);
        let mut r = vec![self.law.force(h[0])];
        for m in 1..=p {
            r.push(0.0);
            r[m] = self.law.force_coeff(&r, &h, m);
        }
        r
    }
}

impl ContinuationProblem for Spring {
    fn ndof(&self) -> usize {
        1
    }
    fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
        Ok(vec![
            KS * u[0] + self.law.force(self.law.delta - u[0]) - lambda * F,
        ])
    }
    fn tangent(&mut self, u: &[f64], _lambda: f64) -> Result<(SparseMatrix, Vec<f64>)> {
        self.u0 = u[0];
        let k = KS - self.law.stiffness(self.law.delta - u[0]);
        Ok((SparseMatrix::from_dense(&[vec![k]]), vec![-F]))
    }
    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], _lambda: &[f64]) -> Result<Vec<f64>> {
        self.r = self.force_series(u, p, 0.0);
        Ok(vec![self.r[p]])
    }
    /// y = c ln(R + eta): dy/du = −dy/dh (h = delta − u).
    fn arc_coordinates(&mut self) -> Option<ArcCoordinates> {
        (self.arc > 0.0).then(|| {
            let h0 = self.law.delta - self.u0;
            let y = LogReaction::start(self.arc, &self.law, h0, self.law.force(h0), 1);
            ArcCoordinates {
                rows: vec![vec![(0, -y.dy_dh)]],
                lambda: vec![0.0],
            }
        })
    }
    fn arc_coordinates_rhs(&mut self, p: usize) -> Vec<f64> {
        let h0 = self.law.delta - self.u0;
        let mut y = LogReaction::start(self.arc, &self.law, h0, self.r[0], p + 1);
        for m in 1..p {
            y.complete(&self.r[..=m]);
        }
        vec![y.starred(self.r[p], &self.r, p)]
    }
    fn unknown_scale(&self) -> Vec<f64> {
        vec![self.law.delta]
    }
    fn events(&self, u: &[f64], _lambda: f64) -> Result<Vec<f64>> {
        // The penalty law's width is the smallest positive f64: its band
        // |g| <= 1 (series::kinks) is the exact kink.
        Ok(vec![(self.law.delta - u[0]) / self.law.switch_width()])
    }
    fn kinks(&self) -> bool {
        self.law.is_piecewise()
    }
}

/// The equilibrium u at lambda by bisection (the residual is increasing in u).
fn reference(law: &NormalLaw, lambda: f64) -> f64 {
    let r = |u: f64| KS * u + law.force(law.delta - u) - lambda * F;
    let (mut lo, mut hi) = (-1.0, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if r(mid) > 0.0 { hi = mid } else { lo = mid }
    }
    0.5 * (lo + hi)
}

/// Steps taken, jumps, and the largest error of u over the lambda grid
/// 0.05, 0.1, ..., 1: points on the series of ordinary steps, and on a
/// jump's chord corrected by Newton at their lambda (as the shell driver
/// does for its output grid).
fn solve(events: bool, arc: f64) -> (usize, usize, f64) {
    solve_law(1e-6, events, arc)
}

/// [`solve`] with the law's eta (0: the penalty law R = max(0, -K h)).
fn solve_law(eta: f64, events: bool, arc: f64) -> (usize, usize, f64) {
    let law = NormalLaw {
        k: 1e9,
        eta,
        delta: 1e-4,
    };
    let spring = || Spring {
        law,
        arc,
        u0: 0.0,
        r: vec![],
    };
    let mut problem = spring();
    let cfg = ContinuationConfig {
        order: 15,
        eps: 1e-8,
        pade: true,
        residual_tol: 1e-10,
        events,
        ..Default::default()
    };
    let grid: Vec<f64> = (1..=20).map(|i| 0.05 * i as f64).collect();
    let mut jumps = 0;
    let mut err: f64 = 0.0;
    let mut grid_problem = spring();
    let metric = Metric::for_problem(&grid_problem, 1.0).unwrap();
    let mut lu = LinearSolver::new(Choice::Auto);
    let mut stats = Stats::default();
    let res = run(&mut problem, vec![0.0], 0.0, &cfg, |step, _| {
        jumps += step.jump.is_some() as usize;
        for &g in &grid {
            if let Some(a) = step.a_at_lambda(g) {
                let mut u = step.eval(a).0;
                if step.jump.is_some() {
                    u = correct_at_lambda(
                        &mut grid_problem,
                        u,
                        g,
                        cfg.residual_tol,
                        metric.residual_norm(&[F]),
                        &metric,
                        // At lambda = 0.1, on the switch itself, Newton from
                        // the chord halves its distance per iteration until
                        // within the band w ≈ 3e-10 m (measured: 10 leave a
                        // residual of 3e-9).
                        40,
                        &mut lu,
                        &mut stats,
                        step.index,
                    )?
                    .0;
                }
                err = err.max((u[0] - reference(&law, g)).abs() / law.delta);
            }
        }
        if step.lambda_end > 0.0 {
            let u = step.u_end[0];
            err = err.max((u - reference(&law, step.lambda_end)).abs() / law.delta);
        }
        Ok(())
    });
    assert!(res.stop.is_end(), "{:?}", res.stop);
    (res.stats.steps, jumps, err)
}

#[test]
fn one_contact_event_is_crossed_by_a_jump_at_the_same_accuracy() {
    let (off_steps, off_jumps, off_err) = solve(false, 0.0);
    let (on_steps, on_jumps, on_err) = solve(true, 0.0);
    println!("events off: {off_steps} steps, error {off_err:.2e}");
    println!("events on: {on_steps} steps ({on_jumps} jumps), error {on_err:.2e}");
    assert_eq!(off_jumps, 0);
    assert!(on_jumps >= 1, "the event was not crossed by a jump");
    assert!(on_steps < off_steps, "{on_steps} vs {off_steps} steps");
    // Both within the accuracy of the series (eps = 1e-8) on u / delta.
    assert!(off_err <= 1e-6 && on_err <= 1e-6, "{off_err:e} {on_err:e}");
}

/// The same contact crossed by ordinary steps measured along the arc
/// coordinate y = ln(R + eta) as well (contact::log_reaction): the law's
/// switch becomes an O(1) stretch of the path parameter instead of a
/// near-singularity the steps shrink toward.
#[test]
fn the_reaction_logarithm_in_the_arclength_crosses_the_event_in_fewer_steps() {
    let (plain_steps, _, plain_err) = solve(false, 0.0);
    let (log_steps, _, log_err) = solve(false, 1.0);
    println!("plain arclength: {plain_steps} steps, error {plain_err:.2e}");
    println!("with ln(R + eta): {log_steps} steps, error {log_err:.2e}");
    assert!(
        2 * log_steps <= plain_steps,
        "{log_steps} vs {plain_steps} steps"
    );
    assert!(log_err <= 1e-6, "{log_err:e}");
}

/// The penalty law (eta = 0): linear on each side of contact, so the series
/// of each piece terminate and the engine ends a step at the kink
/// (src/series/kinks.rs): one step to the contact at lambda = k_s delta / F
/// = 0.1, one to lambda = 1. Against the closed form u = lambda F / k_s
/// before contact and (lambda F + K delta) / (k_s + K) after it.
#[test]
fn the_penalty_law_takes_one_step_per_piece() {
    let (steps, jumps, err) = solve_law(0.0, false, 0.0);
    println!("penalty law: {steps} steps, error {err:.2e}");
    assert_eq!(jumps, 0);
    assert_eq!(steps, 2, "one step per piece of the law");
    assert!(err <= 1e-12, "{err:e}");
    let law = NormalLaw {
        k: 1e9,
        eta: 0.0,
        delta: 1e-4,
    };
    for lambda in [0.05, 0.1, 0.3, 1.0] {
        let closed = if lambda * F / KS <= law.delta {
            lambda * F / KS
        } else {
            (lambda * F + law.k * law.delta) / (KS + law.k)
        };
        assert!(
            (reference(&law, lambda) - closed).abs() <= 1e-15,
            "lambda = {lambda}"
        );
    }
}

/// Two springs like the one above side by side, their walls 1e-9 apart in
/// gap: they touch at lambda = 0.1 and 0.1 (1 + 1e-9), as nodes mirrored
/// across a symmetric shell do (~4e-11 apart, by round-off).
struct TwoSprings {
    laws: [NormalLaw; 2],
}

impl ContinuationProblem for TwoSprings {
    fn ndof(&self) -> usize {
        2
    }
    fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
        Ok((0..2)
            .map(|i| KS * u[i] + self.laws[i].force(self.laws[i].delta - u[i]) - lambda * F)
            .collect())
    }
    fn tangent(&mut self, u: &[f64], _lambda: f64) -> Result<(SparseMatrix, Vec<f64>)> {
        let k = |i: usize| KS - self.laws[i].stiffness(self.laws[i].delta - u[i]);
        Ok((
            SparseMatrix::from_dense(&[vec![k(0), 0.0], vec![0.0, k(1)]]),
            vec![-F, -F],
        ))
    }
    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], _lambda: &[f64]) -> Result<Vec<f64>> {
        Ok((0..2)
            .map(|i| {
                let law = &self.laws[i];
                // h_0..h_{p-1}, and h_p = 0 (its part is in the tangent).
                let mut h: Vec<f64> = u[..p].iter().map(|x| -x[i]).collect();
                h[0] += law.delta;
                h.push(0.0);
                let mut r = vec![law.force(h[0])];
                for m in 1..=p {
                    r.push(0.0);
                    r[m] = law.force_coeff(&r, &h, m);
                }
                r[p]
            })
            .collect())
    }
    fn unknown_scale(&self) -> Vec<f64> {
        vec![self.laws[0].delta; 2]
    }
    fn events(&self, u: &[f64], _lambda: f64) -> Result<Vec<f64>> {
        Ok((0..2)
            .map(|i| (self.laws[i].delta - u[i]) / self.laws[i].switch_width())
            .collect())
    }
    fn kinks(&self) -> bool {
        true
    }
}

/// The penalty law on the two springs: one step per piece (3), and the
/// step from the first kink to the second, 1e-10 long in lambda, computes
/// orders 0..3 only (src/series/kinks.rs, "Few orders"): the kink lies
/// within a quarter of the ratio-rule length of 3 orders. Against the closed
/// form on every step end and on the lambda grid.
#[test]
fn a_kink_right_after_another_takes_a_step_of_few_orders() {
    let law = |delta: f64| NormalLaw {
        k: 1e9,
        eta: 0.0,
        delta,
    };
    let laws = [law(1e-4), law(1e-4 * (1.0 + 1e-9))];
    let closed = |i: usize, lambda: f64| {
        let l = &laws[i];
        if lambda * F / KS <= l.delta {
            lambda * F / KS
        } else {
            (lambda * F + l.k * l.delta) / (KS + l.k)
        }
    };
    let mut problem = TwoSprings { laws };
    let cfg = ContinuationConfig {
        order: 15,
        eps: 1e-8,
        pade: true,
        residual_tol: 1e-10,
        ..Default::default()
    };
    let grid: Vec<f64> = (1..=20).map(|i| 0.05 * i as f64).collect();
    let mut err: f64 = 0.0;
    let mut orders = vec![];
    let res = run(&mut problem, vec![0.0, 0.0], 0.0, &cfg, |step, _| {
        orders.push((step.lambda_end - step.lambda[0], step.u.len() - 1));
        let mut points: Vec<(Vec<f64>, f64)> = grid
            .iter()
            .filter_map(|&g| step.a_at_lambda(g).map(|a| step.eval(a)))
            .collect();
        points.push((step.u_end.clone(), step.lambda_end));
        for (u, lambda) in points {
            for (i, ui) in u.iter().enumerate() {
                err = err.max((ui - closed(i, lambda)).abs() / 1e-4);
            }
        }
        Ok(())
    });
    assert!(res.stop.is_end(), "{:?}", res.stop);
    println!("steps (lambda span, orders): {orders:?}; error {err:.2e}");
    assert_eq!(orders.len(), 3, "one step per piece: {orders:?}");
    let (span, order) = orders[1];
    assert!(span < 1e-9, "the second step spans {span:e}");
    assert!(order <= 3, "the 1e-10 step computed {order} orders");
    assert!(err <= 1e-12, "{err:e}");
}

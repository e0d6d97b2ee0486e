//! Derivative checks of the shell model (DESIGN §6): the tangent against
//! central finite differences of the residual, and the order-p right-hand
//! sides against the residual evaluated along the series of one ANM step.
//!
//! Problem: a curved cantilever panel (cylindrical, R = 2, 4 × 2 elements,
//! t = 0.02, E = 1e7, nu = 0.3) clamped at x = 0, with a dead end load, a
//! follower end couple and a rigid cylinder near the free end carrying the
//! contact law of eq. (3) (K = 1e4, eta = 1e-2, delta = initial gaps).

use crate::shell_common;

use anm::contact::Obstacle;
use anm::linalg::norm;
use anm::mesh::{Vec3, structured};
use anm::series::ContinuationProblem;
use anm::series::continuation::{ContinuationConfig, PathStep, run};
use anm::shell::{FollowerCouple, ShellModel};

fn problem() -> ShellModel {
    let mesh = structured::cylinder_panel(2.0, 0.0, 1.0, -0.1, 0.1, 4, 2);
    let mut m = shell_common::model(&mesh, 0.02, 1e7, 0.3);
    let mut fixed = vec![];
    shell_common::fix(&mut fixed, &mesh.groups["s0"], &[0, 1, 2, 3, 4, 5]);
    m.set_constraints(&fixed);
    for &n in &mesh.groups["s1"] {
        m.dead[6 * n + 2] = 0.5;
        m.dead[6 * n + 1] = 0.1;
        m.follower.push(FollowerCouple {
            node: n,
            moment: Vec3::new(0.0, -0.2, 0.05),
        });
    }
    // Cylinder above the free end, axis along y, 0.01 above the panel top.
    let top = mesh.nodes[mesh.groups["s1"][1]];
    let cyl = Obstacle::cylinder(top + Vec3::new(0.0, 0.0, 0.51), Vec3::y(), 0.5).unwrap();
    let cand: Vec<usize> = (0..mesh.nodes.len()).collect();
    m.set_contact(vec![cyl], &cand, 1e4, 1e-2, 0.2).unwrap();
    m
}

fn state(m: &ShellModel, scale: f64) -> Vec<f64> {
    (0..m.ndof())
        .map(|i| scale * ((i as f64 * 0.731).sin() + 0.3 * (i as f64 * 1.37).cos()))
        .collect()
}

#[test]
fn tangent_matches_finite_differences_of_the_residual() {
    let mut m = problem();
    let u = state(&m, 0.01);
    let lambda = 0.7;
    let (k, rl) = m.tangent(&u, lambda).unwrap();
    assert!(
        !m.active_pairs().is_empty(),
        "contact terms must be exercised"
    );
    let n = m.ndof();
    let mut kd = vec![vec![0.0; n]; n];
    for (r, c, v) in k.entries() {
        kd[r][c] += v;
    }
    let kmax = kd.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
    let h = 1e-6;
    let mut worst = 0.0f64;
    for j in 0..n {
        let mut up = u.clone();
        let mut um = u.clone();
        up[j] += h;
        um[j] -= h;
        let rp = m.residual(&up, lambda).unwrap();
        let rm = m.residual(&um, lambda).unwrap();
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            worst = worst.max((fd - kd[i][j]).abs() / kmax);
        }
    }
    let rp = m.residual(&u, lambda + h).unwrap();
    let rm = m.residual(&u, lambda - h).unwrap();
    let rl_fd: Vec<f64> = rp
        .iter()
        .zip(&rm)
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect();
    let dl: Vec<f64> = rl_fd.iter().zip(&rl).map(|(a, b)| a - b).collect();
    let lerr = norm(&dl) / norm(&rl);
    println!(
        "tangent vs FD: max |K - K_fd| / max|K| = {worst:.3e}; dR/dlambda rel. error {lerr:.3e}"
    );
    assert!(worst < 1e-7, "tangent mismatch {worst:.3e}");
    assert!(lerr < 1e-7, "dR/dlambda mismatch {lerr:.3e}");
}

#[test]
fn series_terms_match_the_residual_along_the_series() {
    let mut m = problem();
    let cfg = ContinuationConfig {
        order: 15,
        eps: 1e-9,
        max_steps: 2,
        lambda_end: 100.0,
        ..Default::default()
    };
    let mut steps: Vec<PathStep> = vec![];
    let n0 = m.ndof();
    let res = run(&mut m, vec![0.0; n0], 0.0, &cfg, |s, _| {
        steps.push(s.clone());
        Ok(())
    });
    assert!(res.error().is_none(), "{:?}", res.error());
    // Second step: starts from a deformed, stressed, contacting state.
    let s = &steps[1];
    let (_, rl) = m.tangent(&s.u[0], s.lambda[0]).unwrap();
    let scale = norm(&rl);
    // The step starts from a corrected point whose residual R0 is below the
    // engine's tolerance but not zero; the series cancels the coefficients
    // 1..N of R(U(a), lambda(a)), so R(U(a)) - R0 is the truncation error.
    let r0 = m.residual(&s.u[0], s.lambda[0]).unwrap();
    let a = 0.5 * s.a_poly;
    let mut table = vec![];
    for n in 1..=15 {
        let mut u = vec![0.0; m.ndof()];
        let mut l = 0.0;
        for p in (0..=n).rev() {
            for (ui, c) in u.iter_mut().zip(&s.u[p]) {
                *ui = *ui * a + c;
            }
            l = l * a + s.lambda[p];
        }
        let r: Vec<f64> = m
            .residual(&u, l)
            .unwrap()
            .iter()
            .zip(&r0)
            .map(|(a, b)| a - b)
            .collect();
        let r = norm(&r) / scale;
        let du = norm(&s.u[n]) * a.powi(n as i32);
        table.push((n, r, du));
    }
    println!("start residual |R0|/|R_l| = {:.3e}", norm(&r0) / scale);
    println!(
        "step 2, a = a_max/2 = {a:.4e}, lambda(a) - lambda0 = {:.4e}",
        s.eval(a).1 - s.lambda[0]
    );
    println!("{:>3} {:>12} {:>12}", "N", "|R-R0|/|R_l|", "|U_N| a^N");
    for (n, r, du) in &table {
        println!("{n:>3} {r:>12.3e} {du:>12.3e}");
    }
    let (r2, r15) = (table[1].1, table[14].1);
    assert!(r15 < 1e-9, "residual along the order-15 series {r15:.3e}");
    assert!(
        r2 > 1e4 * r15,
        "the check must discriminate: order 2 gives {r2:.3e}"
    );
    // The truncation error falls with the order until the round-off floor.
    for w in table.windows(2).take(9) {
        assert!(
            w[1].1 <= 2.0 * w[0].1,
            "order {}: residual grew: {:?}",
            w[1].0,
            w
        );
    }
}

/// The tangent is assembled by column blocks, one per thread: every entry
/// must be the same sum, bit for bit, on 1, 2 and 3 threads (the clamped
/// columns go to dR/dlambda, the follower couples and contacts after).
#[test]
fn tangent_is_the_same_on_any_number_of_threads() {
    let tangent_on = |threads: usize| {
        let mut m = problem();
        let n = m.ndof();
        let u: Vec<f64> = (0..n).map(|i| 1e-3 * (0.37 * i as f64).sin()).collect();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (k, rl) = pool.install(|| m.tangent(&u, 0.3)).unwrap();
        let mut entries: Vec<_> = k.entries().map(|(i, j, v)| (i, j, v.to_bits())).collect();
        entries.sort_unstable();
        (entries, rl)
    };
    let one = tangent_on(1);
    assert!(one.0.len() > 1000, "{} entries", one.0.len());
    assert!(one.1.iter().any(|v| *v != 0.0));
    for threads in [2, 3] {
        let many = tangent_on(threads);
        assert!(many.0 == one.0, "{threads} threads: tangent entries differ");
        assert!(many.1 == one.1, "{threads} threads: dR/dlambda differs");
    }
}

//! Contact with a rigid plane against the closed form of a propped
//! cantilever (Euler–Bernoulli, small deflection: tip stiffness 3 EI / L³).
//!
//! Goal: the regularized contact law (eq. 3) with delta = initial gap, the
//! plane obstacle and the ANM continuation give the support reaction
//! R = P − 3 EI g / L³ once the tip has closed the gap g (the law's
//! penetration, about R / K, changes R by 3 EI (R/K) / L³ ≈ 1e-10 N; the
//! geometric nonlinearity, of relative size (g/L)² = 1e-4, is the largest
//! modelling difference). g/L = 1e-2 rather than smaller: the engine's
//! arclength norm is not scaled, so displacements much smaller than lambda
//! get a loose relative step control (a first try with g = 1e-4 failed the
//! end-of-step residual check at the contact corner).
//!
//! ```text
//!   clamp |=========== L = 1, b = 0.1, t = 0.01 ==========| tip, P = 1 N down
//!                                                   g = 1e-2 ___ plane z = -g
//!   E = 2e9, nu = 0, 40 x 1 elements, K = 1e9 N/m, eta = 1e-6 N per node
//! ```

use crate::shell_common;

use anm::contact::Obstacle;
use anm::mesh::{Vec3, structured};
use anm::series::continuation::{ContinuationConfig, run};

#[test]
fn tip_reaction_on_a_plane_matches_the_propped_cantilever() {
    let (l, b, t, e, g, p) = (1.0, 0.1, 0.01, 2e9, 1e-2, 1.0);
    let mesh = structured::rectangle(0.0, l, -b / 2.0, b / 2.0, 40, 1);
    let mut m = shell_common::model(&mesh, t, e, 0.0);
    let mut fixed = vec![];
    shell_common::fix(&mut fixed, &mesh.groups["s0"], &[0, 1, 2, 3, 4, 5]);
    m.set_constraints(&fixed);
    let tip = mesh.groups["s1"].clone();
    for &n in &tip {
        m.dead[6 * n + 2] = -p / tip.len() as f64;
    }
    let plane = Obstacle::plane(Vec3::new(0.0, 0.0, -g), Vec3::z()).unwrap();
    m.set_contact(vec![plane], &tip, 1e9, 1e-6, 1.0).unwrap();
    let cfg = ContinuationConfig {
        order: 15,
        eps: 1e-8,
        lambda_end: 1.0,
        ..Default::default()
    };
    let n0 = anm::series::ContinuationProblem::ndof(&m);
    let res = run(&mut m, vec![0.0; n0], 0.0, &cfg, |_, _| Ok(()));
    assert!(
        res.error().is_none() && res.stop == "end",
        "{:?}",
        res.error()
    );
    let full = m.expand(&res.u_end, res.lambda_end);
    let forces = m.contact_forces(&full, res.lambda_end).unwrap();
    let r: f64 = forces.iter().map(|c| c.r).sum();
    let ei = e * b * t.powi(3) / 12.0;
    let want = p - 3.0 * ei * g / l.powi(3);
    let wz: f64 = tip.iter().map(|&n| full[6 * n + 2]).sum::<f64>() / tip.len() as f64;
    println!(
        "propped cantilever: R = {r:.6} N (closed form {want:.6}), tip w = {wz:.6e} (gap {g:e}), {} steps",
        res.stats.steps
    );
    assert!(
        (r - want).abs() <= 1e-3 * want,
        "R = {r}, closed form {want}"
    );
    assert!((wz + g).abs() <= 1e-3 * g, "tip deflection {wz} vs -g");
}

/// A node that reaches its obstacle within one step while outside the search
/// distance (so without contact terms in that step) is caught by the step-end
/// check: the step is shortened, the node joins the active set at the next
/// step start, and the run ends with the closed-form reaction.
#[test]
fn contact_outside_the_search_distance_shortens_the_step() {
    let (l, b, t, e, g, p) = (1.0, 0.1, 0.01, 2e9, 1e-2, 1.0);
    let mesh = structured::rectangle(0.0, l, -b / 2.0, b / 2.0, 40, 1);
    let mut m = shell_common::model(&mesh, t, e, 0.0);
    let mut fixed = vec![];
    shell_common::fix(&mut fixed, &mesh.groups["s0"], &[0, 1, 2, 3, 4, 5]);
    m.set_constraints(&fixed);
    let tip = mesh.groups["s1"].clone();
    for &n in &tip {
        m.dead[6 * n + 2] = -p / tip.len() as f64;
    }
    let plane = Obstacle::plane(Vec3::new(0.0, 0.0, -g), Vec3::z()).unwrap();
    // Search distance below the initial gap: the tip starts inactive.
    m.set_contact(vec![plane], &tip, 1e9, 1e-6, 5e-3).unwrap();
    let cfg = ContinuationConfig {
        order: 15,
        eps: 1e-8,
        lambda_end: 1.0,
        ..Default::default()
    };
    let n0 = anm::series::ContinuationProblem::ndof(&m);
    let res = run(&mut m, vec![0.0; n0], 0.0, &cfg, |_, _| Ok(()));
    assert!(
        res.error().is_none() && res.stop == "end",
        "{:?}",
        res.error()
    );
    let full = m.expand(&res.u_end, res.lambda_end);
    let forces = m.contact_forces(&full, res.lambda_end).unwrap();
    let r: f64 = forces.iter().map(|c| c.r).sum();
    let want = p - 3.0 * (e * b * t.powi(3) / 12.0) * g / l.powi(3);
    println!(
        "search distance 5e-3 < gap 1e-2: R = {r:.6} N (closed form {want:.6}), {} steps, {} step cuts",
        res.stats.steps, res.stats.step_cuts
    );
    assert!(res.stats.step_cuts >= 1, "no step was shortened");
    assert!(
        (r - want).abs() <= 1e-3 * want,
        "R = {r}, closed form {want}"
    );
}

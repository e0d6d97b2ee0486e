//! Large-rotation cantilever strips against closed forms, solved by the ANM
//! continuation engine (order 15).
//!
//! 1. Cantilever rolled into a full circle by an end moment (nu = 0):
//!    curvature M/EI, tip rotation theta = M L / EI, tip position
//!    (R sin theta, R (1 - cos theta)), R = EI / M; M_max = 2 pi EI / L.
//!    The moment is a follower couple on the director unknowns (the director
//!    force m × a3, see shell::model), so the closed form holds for any
//!    rotation; a dead couple would not close the circle.
//! 2. Cantilever under a dead end shear P against the exact elastica (Mattiasson,
//!    IJNME 17 (1981) 145–153, table 1): k = P L² / EI = 1, 2, 4 gives
//!    (u/L, w/L) = (0.05643, 0.30172), (0.16064, 0.49346), (0.32894, 0.66996),
//!    u the horizontal shortening, w the deflection.
//!
//! ```text
//!   clamp |=================== L = 10, b = 1, t = 0.1 ===========| <- M or P
//!         E = 1e7, nu = 0, EI = E b t^3 / 12, 40 x 1 elements
//! ```

use crate::shell_common;

use anm::mesh::{Vec3, structured};
use anm::series::continuation::{ContinuationConfig, PathStep, run};
use anm::shell::{FollowerCouple, ShellModel};

const L: f64 = 10.0;
const T: f64 = 0.1;
const E: f64 = 1e7;
const NX: usize = 80;

fn ei() -> f64 {
    E * 1.0 * T.powi(3) / 12.0
}

fn strip() -> (ShellModel, Vec<usize>) {
    let mesh = structured::rectangle(0.0, L, -0.5, 0.5, NX, 1);
    let mut m = shell_common::model(&mesh, T, E, 0.0);
    let mut fixed = vec![];
    shell_common::fix(&mut fixed, &mesh.groups["s0"], &[0, 1, 2, 3, 4, 5]);
    // Planar motion (v_y = w_y = 0): the closed forms are planar and, with
    // nu = 0, the constraint does not change the planar solution. Without
    // it, the fixed-axis end moment (m × a3 has moment m, fixed in space)
    // meets an out-of-plane bifurcation near M/Mmax = 0.79 (b = 1; 0.15 for
    // a square section): the ANM steps collapse there, as they should.
    shell_common::fix(&mut fixed, &mesh.groups["all"], &[1, 4]);
    m.set_constraints(&fixed);
    (m, mesh.groups["s1"].clone())
}

/// Runs to lambda = 1 and returns the mean tip displacement at each target.
fn tip_path(m: &mut ShellModel, tip: &[usize], targets: &[f64]) -> (Vec<Vec3>, usize) {
    let cfg = ContinuationConfig {
        order: 20,
        eps: 1e-8,
        lambda_end: 1.0,
        ..Default::default()
    };
    let mut steps: Vec<PathStep> = vec![];
    let n0 = anm::series::ContinuationProblem::ndof(m);
    let res = run(m, vec![0.0; n0], 0.0, &cfg, |s, _| {
        steps.push(s.clone());
        Ok(())
    });
    assert!(
        res.error().is_none() && res.stop == "end",
        "{:?}",
        res.error()
    );
    let mut out = vec![];
    for &lt in targets {
        let (u, lambda) = steps
            .iter()
            .find_map(|s| {
                if (s.lambda_end - lt).abs() < 1e-12 {
                    Some((s.u_end.clone(), s.lambda_end))
                } else {
                    s.a_at_lambda(lt).map(|a| s.eval(a))
                }
            })
            .expect("target lambda on the path");
        let full = m.expand(&u, lambda);
        let mut d = Vec3::zeros();
        for &n in tip {
            d += Vec3::new(full[6 * n], full[6 * n + 1], full[6 * n + 2]) / tip.len() as f64;
        }
        out.push(d);
    }
    (out, res.stats.steps)
}

#[test]
fn end_moment_rolls_the_strip_into_a_circle() {
    let (mut m, tip) = strip();
    let mmax = 2.0 * std::f64::consts::PI * ei() / L;
    for &n in &tip {
        m.follower.push(FollowerCouple {
            node: n,
            moment: Vec3::new(0.0, -mmax / tip.len() as f64, 0.0),
        });
    }
    let targets = [0.25, 0.5, 0.75, 1.0];
    let (d, steps) = tip_path(&mut m, &tip, &targets);
    println!("rolled cantilever, {NX} elements, {steps} ANM steps");
    println!(
        "{:>6} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "M/Mmax", "x_tip", "x_exact", "z_tip", "z_exact", "err/L"
    );
    let mut worst = 0.0f64;
    for (lt, di) in targets.iter().zip(&d) {
        let theta = lt * 2.0 * std::f64::consts::PI;
        let r = L / theta;
        let (xe, ze) = (r * theta.sin(), r * (1.0 - theta.cos()));
        let (x, z) = (L + di[0], di[2]);
        let err = ((x - xe).powi(2) + (z - ze).powi(2)).sqrt() / L;
        worst = worst.max(err);
        println!("{lt:>6.2} {x:>10.5} {xe:>10.5} {z:>10.5} {ze:>10.5} {err:>9.2e}");
    }
    assert!(worst <= 0.005, "tip position error {worst:.3e} L > 0.5%");
}

#[test]
fn end_shear_matches_the_exact_elastica() {
    let (mut m, tip) = strip();
    let pmax = 4.0 * ei() / (L * L);
    for &n in &tip {
        m.dead[6 * n + 2] = pmax / tip.len() as f64;
    }
    let targets = [0.25, 0.5, 1.0];
    let exact = [(0.05643, 0.30172), (0.16064, 0.49346), (0.32894, 0.66996)];
    let (d, steps) = tip_path(&mut m, &tip, &targets);
    println!("elastica, {NX} elements, {steps} ANM steps");
    println!(
        "{:>4} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "k", "u/L", "exact", "err", "w/L", "exact", "err"
    );
    for ((lt, di), (ue, we)) in targets.iter().zip(&d).zip(exact) {
        let (u, w) = (-di[0] / L, di[2] / L);
        let (eu, ew) = ((u - ue) / ue, (w - we) / we);
        println!(
            "{:>4.0} {u:>9.5} {ue:>9.5} {eu:>9.2e} {w:>9.5} {we:>9.5} {ew:>9.2e}",
            lt * 4.0
        );
        assert!(
            eu.abs() <= 0.01 && ew.abs() <= 0.01,
            "k = {}: u/L {u}, w/L {w}",
            lt * 4.0
        );
    }
}

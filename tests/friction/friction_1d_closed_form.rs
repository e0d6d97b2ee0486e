//! Béchet, Boudaoud, Lejeune, Potier-Ferry, CFM 2009, §3.2, eq. (7), fig. 5.
//!
//! Goal: the ANM Taylor series in time reproduces the closed forms of the
//! spring on a moving plane, without the 2.3% plateau error the paper reports
//! for its Newton initialization.
//!
//! ```text
//!      k        u ->
//!   |/\/\/\/[m]            R_N = 1 N known
//!   ===========> V = 1 m/s (plane)
//! ```
//! k = 1 N/m, f = 0.2, q = 0.05, Vc = 1 m/s, u(0) = 0, t in [0, 1].
//! Plateau (v = 0): k u = f R_N |V|_reg^(q-1) V / Vc^q = 0.2 (1 + omega^2)^((q-1)/2).
//! Exact omega = 0 curve: du/dt = V - Vc (k u / (f R_N))^(1/q).

use crate::common;
use anm::model::friction_run::run;
use common::{assert_close, column, friction_scene};

fn plateau(omega: f64, q: f64) -> f64 {
    0.2 * (1.0 + omega * omega).powf(0.5 * (q - 1.0))
}

#[test]
fn plateau_with_newton_initialization() {
    let scene = friction_scene("friction-1d.toml", &[]);
    let r = run(&scene, None, false).unwrap();
    assert_eq!(r.stop.reason, "end");
    let u = column(&r, "u");
    println!(
        "Newton init: u(1) = {:.15}, closed form {:.15}, |F(0)| = {:.1e}",
        u[u.len() - 1],
        plateau(0.1, 0.05),
        r.initial_residual
    );
    assert_close(
        "u(1), Newton initialization",
        *u.last().unwrap(),
        plateau(0.1, 0.05),
        1e-6,
        0.0,
    );
    assert!(
        r.initial_residual < 1e-12,
        "initial residual {}",
        r.initial_residual
    );
}

#[test]
fn plateau_with_exact_initial_value() {
    let scene = friction_scene(
        "friction-1d.toml",
        &[("initial.mode", "\"exact\""), ("initial.v0", "1.0")],
    );
    let r = run(&scene, None, false).unwrap();
    assert_eq!(r.stop.reason, "end");
    let u = column(&r, "u");
    println!(
        "exact init: u(1) = {:.15}, closed form {:.15}",
        u[u.len() - 1],
        plateau(0.1, 0.05)
    );
    assert_close(
        "u(1), exact initialization",
        *u.last().unwrap(),
        plateau(0.1, 0.05),
        1e-6,
        0.0,
    );
}

#[test]
fn plateau_for_other_exponents_and_regularizations() {
    // Relaxation time toward the plateau is about f R_N q / k: all well below 1 s here.
    for (q, omega) in [(0.0, 0.1), (0.1, 0.05), (0.2, 0.3)] {
        let scene = friction_scene(
            "friction-1d.toml",
            &[
                ("friction.q", &q.to_string()),
                ("friction.omega", &omega.to_string()),
            ],
        );
        let r = run(&scene, None, false).unwrap();
        let u = column(&r, "u");
        assert_close(
            &format!("u(1), q = {q}, omega = {omega}"),
            *u.last().unwrap(),
            plateau(omega, q),
            1e-6,
            0.0,
        );
    }
}

#[test]
fn coulomb_friction_gets_past_its_stick_slip_switch() {
    // q = 0 (Coulomb, documented as valid): at each stick-slip switch the
    // series see a pair of complex singular points close to the real axis,
    // the same point step after step. Review 12: with the default
    // on_singularity = "stop", the run stopped there at t = 0.198 s with
    // exit 0 and "a singular point ends the smooth quasi-static solution",
    // at omega = 1e-2 … 1e-6; the plateau after the switch was never
    // computed. Followed on, the path gets past (README "False singular
    // points"); at omega = 1e-6 the bend's time scale needs series terms
    // beyond a double's range: a diagnosed stop (exit 2), not a breakdown.
    for omega in [1e-2, 1e-3, 1e-4] {
        let w = omega.to_string();
        let scene = friction_scene(
            "friction-1d.toml",
            &[("friction.q", "0.0"), ("friction.omega", &w)],
        );
        let r = run(&scene, None, false).unwrap();
        assert_eq!(r.stop.reason, "end", "omega = {w}: {:?}", r.stop);
        let u = column(&r, "u");
        println!(
            "q = 0, omega = {w}: u(1) = {:.12} against {:.12}, {} steps",
            u[u.len() - 1],
            plateau(omega, 0.0),
            r.stats.steps
        );
        assert_close(
            &format!("u(1), q = 0, omega = {w}"),
            *u.last().unwrap(),
            plateau(omega, 0.0),
            1e-7,
            0.0,
        );
    }
    let scene = friction_scene(
        "friction-1d.toml",
        &[("friction.q", "0.0"), ("friction.omega", "1e-6")],
    );
    let r = run(&scene, None, false).unwrap();
    assert_eq!(r.stop.reason, "non_finite", "{:?}", r.stop);
}

#[test]
fn viscous_law_matches_the_exponential_solution() {
    // q = 1: R_T = -f R_N (v - V) / Vc whatever omega, so k u = f R_N (V - v)/Vc
    // and u(t) = (f R_N V / k) (1 - exp(-k Vc t / (f R_N))) = 0.2 (1 - e^(-5 t)).
    let scene = friction_scene(
        "friction-1d.toml",
        &[("friction.q", "1.0"), ("friction.omega", "0.2")],
    );
    let r = run(&scene, None, false).unwrap();
    for (t, u) in column(&r, "t").iter().zip(column(&r, "u")) {
        let want = 0.2 * (1.0 - (-5.0 * t).exp());
        assert_close(&format!("u({t:.2})"), u, want, 1e-9, 1e-3);
    }
}

/// u(t) of du/dt = 1 - (5 u)^20 (omega = 0) by classical RK4 with step h, on the grid.
fn exact_curve(grid: &[f64], h: f64) -> Vec<f64> {
    let f = |u: f64| 1.0 - (5.0 * u).powi(20);
    let mut out = Vec::with_capacity(grid.len());
    let (mut t, mut u) = (0.0, 0.0);
    for &tg in grid {
        while t < tg - 1e-15 {
            let dt = h.min(tg - t);
            let k1 = f(u);
            let k2 = f(u + 0.5 * dt * k1);
            let k3 = f(u + 0.5 * dt * k2);
            let k4 = f(u + dt * k3);
            u += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            t += dt;
        }
        out.push(u);
    }
    out
}

#[test]
fn error_against_the_unregularized_curve_shrinks_with_omega() {
    let base = friction_scene("friction-1d.toml", &[]);
    let grid = base.output_times();
    let exact = exact_curve(&grid, 1e-5);
    // The reference itself: halving the RK4 step changes it by far less than the errors measured.
    let check = exact_curve(&grid, 2e-5);
    let ref_err = exact
        .iter()
        .zip(&check)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(ref_err < 1e-10, "RK4 reference not converged: {ref_err:e}");
    println!("omega   max|u - u_exact| over [0, 1]   steps");
    let mut errors = vec![];
    for omega in [0.1, 0.03, 0.01] {
        let scene = friction_scene(
            "friction-1d.toml",
            &[("friction.omega", &omega.to_string())],
        );
        let r = run(&scene, None, false).unwrap();
        assert_eq!(r.stop.reason, "end", "omega = {omega}: {:?}", r.stop);
        let u = column(&r, "u");
        let err = u
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!("{omega:<7} {err:<30.3e} {}", r.stats.steps);
        errors.push(err);
    }
    assert!(
        errors[1] < errors[0] && errors[2] < errors[1],
        "errors do not shrink: {errors:?}"
    );
}

/// A start whose displacement overflows the law (u0 = 1e308) stops with a
/// diagnosis at t = 0: the initialization's backtracking used to halve its
/// step forever on a residual that is non-finite however short the step.
#[test]
fn overflowing_start_stops_with_a_diagnosis() {
    let scene = friction_scene("friction-1d.toml", &[("initial.u0", "1e308")]);
    let r = run(&scene, None, false).unwrap();
    println!("{:?}", r.stop);
    assert_eq!(r.stop.reason, "non_finite");
    assert!(
        r.stop
            .message
            .as_deref()
            .is_some_and(|m| m.contains("t = 0")),
        "{:?}",
        r.stop
    );
    assert!(r.history.iter().flatten().all(|x| x.is_finite()));
}

/// Review 8: at omega = 1e-6 the first step's end residual was 1.3e-2
/// (residual_tol 1e-8): its end was corrected, but the output rows inside
/// it kept the series' velocity, and the friction force R_T(v) amplifies
/// the velocity's error by f R_N / (omega Vc): rt was 8.5 % off k u at
/// t = 0.13 s (eps 1e-6). Those rows are now corrected as the step end is:
/// k u + R_T = 0 holds on every row (eq. 7).
#[test]
fn every_row_holds_the_equilibrium_at_small_omega() {
    for eps in ["1e-6", "1e-10"] {
        let scene = friction_scene(
            "friction-1d.toml",
            &[("friction.omega", "1e-6"), ("solver.eps", eps)],
        );
        let r = run(&scene, None, false).unwrap();
        assert_eq!(r.stop.reason, "end");
        let (u, rt) = (column(&r, "u"), column(&r, "rt"));
        let worst = u
            .iter()
            .zip(&rt)
            .map(|(u, rt)| (u - rt).abs())
            .fold(0.0, f64::max);
        println!("omega = 1e-6, eps {eps}: max |k u − rt| over the rows {worst:.2e}");
        assert!(worst < 1e-7, "eps {eps}: {worst:e}");
    }
}

/// Review 8: an output step that does not divide t_end left the end state
/// out of history.csv (dt = 0.7: rows at 0 and 0.7 only); the shell runs
/// in time add the row at t_end, and so do these now.
#[test]
fn the_last_row_is_at_t_end() {
    let scene = friction_scene("friction-1d.toml", &[("output.dt", "0.7")]);
    let r = run(&scene, None, false).unwrap();
    let t = column(&r, "t");
    assert_eq!(t, [0.0, 0.7, 1.0]);
    assert_close(
        "u(1)",
        *column(&r, "u").last().unwrap(),
        plateau(0.1, 0.05),
        1e-6,
        0.0,
    );
}

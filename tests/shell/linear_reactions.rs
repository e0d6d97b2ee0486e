//! Support reactions of a linear analysis (`solver.method = "linear"`)
//! balance the loads of the linear model. They were read from the shell's
//! nonlinear residual at the linear solution, which is off equilibrium:
//! 1.0031 N of reaction under a 1 N tip load (the cantilever below, tip
//! rotation 0.03 rad), 32.3 N under 100 N.

use crate::scratch::ScratchFile;
use anm::run::run_loaded;

/// The shared cantilever (shell_common::cantilever_scene) in metres, solved
/// by the linear method.
fn cantilever(q: f64, lambda_end: f64, lambda_step: f64) -> String {
    crate::shell_common::cantilever_scene(1.0, q, "linear", lambda_end, lambda_step)
}

#[test]
fn linear_reactions_balance_the_load_on_every_row() {
    // Tip loads 1 N and 100 N (rotations 0.03 and 3 rad in the linear
    // model): the reaction is the load, whatever the linear displacement.
    for q in [-10.0, -1000.0] {
        let file = ScratchFile::with_text("linear-reactions", "c.toml", &cantilever(q, 1.0, 0.25));
        let scene = anm::scene::shell::load(&file).expect("scene");
        let r = run_loaded(&scene, None, false).expect("linear run");
        assert_eq!(r.stop.reason, "end");
        let load = -0.1 * q;
        // Euler-Bernoulli tip deflection F L^3 / 3EI, I = b t^3 / 12.
        let tip = load / (3.0 * 2e9 * 0.1 * 1e-6 / 12.0);
        let (rz, rx, uz) = (r.end["Rz"], r.end["Rx"], r.end["uz_tip"]);
        println!(
            "q = {q}: Rz = {rz:.15e} (load {load}), Rx = {rx:.3e}, uz_tip = {uz:.6e} (beam {tip:.6e})"
        );
        assert!((rz - load).abs() <= 1e-9 * load, "Rz = {rz} against {load}");
        assert!(rx.abs() <= 1e-9 * load, "Rx = {rx}");
        assert!(
            (-uz - tip).abs() <= 1e-3 * tip,
            "uz_tip = {uz} against {tip}"
        );
    }
}

#[test]
fn linear_reactions_at_a_lambda_end_off_the_grid() {
    // lambda_end = 0.9 with a grid of 0.25: the last row (0.9) is recorded
    // with the linear model's reactions too.
    let file = ScratchFile::with_text(
        "linear-reactions",
        "c.toml",
        &cantilever(-1000.0, 0.9, 0.25),
    );
    let scene = anm::scene::shell::load(&file).expect("scene");
    let r = run_loaded(&scene, None, false).expect("linear run");
    let rz = r.end["Rz"];
    assert!((rz - 90.0).abs() <= 1e-9 * 90.0, "Rz = {rz} against 90");
}

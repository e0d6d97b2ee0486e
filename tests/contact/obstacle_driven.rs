//! A path driven only by a moving obstacle (review 15): three-point
//! bending of a simply supported strip by a rigid cylinder that starts
//! 1e-4 m above it and moves down by 2e-3 lambda
//! (tests/data/three-point-bending.toml). Euler–Bernoulli: P = 48 EI w /
//! L³ = 800 w N with w = 2e-3 lambda − 1e-4 after the touch at lambda =
//! 0.05.
//! - Under the penalty law (eta = 0) dR/dlambda is zero until the touch:
//!   the residual test divided by the smallest positive number (residual
//!   1.4e301), the steps halved toward the touch and the run stopped
//!   there. Its scale is now the force the motion exerts once the
//!   candidates touch (K × velocity).
//! - With eta > 0 the regularization's pull is compared with the contact
//!   reactions where there is no load: the note said "3.69e300 times the
//!   applied loads' 0" against 1.5 N of contact force.

use anm::run::run_loaded;
use anm::scene::shell::load;

fn scene(eta: &str) -> anm::scene::shell::ShellScene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/three-point-bending.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("eta = 0.0", &format!("eta = {eta}"));
    assert!(text.contains(&format!("eta = {eta}")));
    let f = crate::scratch::ScratchFile::with_text("obstacle-driven", "scene.toml", &text);
    load(&f).unwrap()
}

#[test]
fn a_moving_obstacle_alone_drives_the_penalty_law_and_the_notes_read_the_contact() {
    for eta in ["0.0", "1e-9"] {
        let r = run_loaded(&scene(eta), None, false).unwrap();
        assert_eq!(r.stop.reason, "end", "eta = {eta}: {:?}", r.stop);
        let (p, w) = (r.end["P"], r.end["w_mid"]);
        let closed = 800.0 * (2e-3 - 1e-4);
        println!(
            "eta = {eta}: {} steps, P(1) = {p:.6} N (closed form {closed:.6}), w = {w:.6e}, notes {:?}",
            r.steps, r.notes
        );
        assert!((p - closed).abs() <= 1e-3 * closed, "{p} vs {closed}");
        assert!(
            !r.notes.iter().any(|n| n.contains("contact.eta")),
            "{:?}",
            r.notes
        );
    }
}

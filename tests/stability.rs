//! Stability stress, fast subset (the full matrix: `anm stress`).
//!
//! Goal: on the three friction scenes, with each of eta, K, omega, zeta, q and
//! the order pushed toward its extremes, every run either meets its accuracy
//! check (the output solves the physical equations, `anm::study::check`) or
//! stops with a diagnosis; zero NaN or inf in any output, zero panics.

mod common;
use anm::study::stress::{Verdict, markdown, stress};
use common::friction_scene;

#[test]
fn every_run_meets_its_check_or_stops_with_a_diagnosis() {
    let scenes = [
        "friction-1d.toml",
        "friction-plane.toml",
        "friction-roller.toml",
    ]
    .map(|s| friction_scene(s, &[]));
    let axes = vec![
        ("eta", vec![1e-8, 1.0]),
        ("K", vec![1e3, 1e12]),
        ("omega", vec![1e-4, 1.0]),
        ("zeta", vec![1e-6, 1.0]),
        ("q", vec![0.01, 1.0]),
        ("order", vec![5.0, 40.0]),
    ];
    let cases = stress(&scenes, &axes, 5000);
    println!("{}", markdown(&cases));
    let failed: Vec<_> = cases
        .iter()
        .filter(|c| c.verdict == Verdict::Failed)
        .collect();
    assert!(failed.is_empty(), "failed runs: {failed:#?}");
    // Diagnosed stops must say what happened.
    for c in cases.iter().filter(|c| c.verdict == Verdict::Diagnosed) {
        assert!(!c.message.is_empty(), "{c:?}");
    }
    assert!(cases.iter().filter(|c| c.verdict == Verdict::Met).count() >= cases.len() / 2);
}

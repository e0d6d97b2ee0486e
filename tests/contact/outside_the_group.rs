//! Nodes outside `contact.group` do not feel the obstacles: a run whose
//! other nodes go through an obstacle says so in its notes (review 10: a
//! strip pulled 1.23 m through rollers it did not touch, exit 0, no word).
//!
//! The cantilever of scenes/verification/moving-plane.toml, its tip the
//! only contact node, held at the fixed plane 5e-3 m below by a uniform
//! traction q b = 20 N/m: a propped cantilever with the support settled by
//! δ, whose span sags below the support (beam theory, ν = 0):
//! w(x) = q x² (3L² − 5Lx + 2x²) / (48 EI) + δ (3x²/L² − x³/L³) / 2, the
//! largest w − δ = 3.769e-3 m at x = 0.657 m. The note names the deepest
//! node's depth, which must be that.

use anm::run::run_loaded;
use anm::scene::shell::load;

#[test]
fn nodes_outside_the_contact_group_inside_an_obstacle_are_named() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/verification/moving-plane.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let edited = text
        .replace(
            "motion = { type = \"translate\", velocity = [0.0, 0.0, -5e-3] }\n",
            "",
        )
        .replacen(
            "group = \"s1\"\nforce = [0.0, 0.0, -0.5]",
            "surface = \"all\"\ntraction = [0.0, 0.0, -200.0]",
            1,
        );
    assert_eq!(edited.matches("traction").count(), 1);
    assert!(!edited.contains("translate"));
    let file = crate::scratch::ScratchFile::with_text("outside-group", "sag.toml", &edited);
    let r = run_loaded(&load(&file).unwrap(), None, false).unwrap();
    let note = r
        .notes
        .iter()
        .find(|n| n.contains("outside contact.group"))
        .unwrap_or_else(|| panic!("no note: {:?}", r.notes));
    println!("{note}");
    let depth: f64 = note
        .split(" at ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    let (l, ei, q, delta) = (1.0, 2e9 * 0.1 * 0.01f64.powi(3) / 12.0, 20.0, 5e-3);
    let beam = (0..=100_000)
        .map(|i| {
            let x = i as f64 * l / 100_000.0;
            q * x * x * (3.0 * l * l - 5.0 * l * x + 2.0 * x * x) / (48.0 * ei)
                + delta * (3.0 * x * x / (l * l) - x.powi(3) / l.powi(3)) / 2.0
                - delta
        })
        .fold(f64::MIN, f64::max);
    println!("deepest node {depth:.4e} m inside the plane; beam theory {beam:.4e}");
    assert!((depth - beam).abs() <= 0.02 * beam, "{depth} vs {beam}");
    // The shipped scene, whose span stays above the plane, has no such note.
    let shipped = run_loaded(
        &load(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenes/verification/moving-plane.toml"),
        )
        .unwrap(),
        None,
        false,
    )
    .unwrap();
    assert!(
        !shipped
            .notes
            .iter()
            .any(|n| n.contains("outside contact.group")),
        "{:?}",
        shipped.notes
    );
}

//! Contact regularizations that carry the answer are named in the run's
//! notes (review 12: eta = 1e3 N on plate-cylinder-coarse gave a 67 N
//! reaction for a 30 N load with exit 0 and no word; a soft K let the strip
//! sink into the cylinder without a word), and eta >= K delta is refused
//! by name as in the point-mass scenes.

use anm::run::run_loaded;
use anm::scene::shell::load;

fn coarse(edits: &[(&str, &str)]) -> crate::scratch::ScratchFile {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/plate-cylinder-coarse.toml");
    let mut text = std::fs::read_to_string(&path).unwrap().replace(
        "../meshes/",
        &format!("{}/meshes/", env!("CARGO_MANIFEST_DIR")),
    );
    for (old, new) in edits {
        assert!(text.contains(old), "`{old}` is not in the scene");
        text = text.replacen(old, new, 1);
    }
    crate::scratch::ScratchFile::with_text("regularization-notes", "scene.toml", &text)
}

/// The run of plate-cylinder-coarse with `edits`, and its note that names
/// `key`.
fn noted(edits: &[(&str, &str)], key: &str) -> (anm::run::RunReport, String) {
    let r = run_loaded(&load(&coarse(edits)).unwrap(), None, false).unwrap();
    let note = r
        .notes
        .iter()
        .find(|n| n.contains(key))
        .unwrap_or_else(|| panic!("no {key} note: {:?}", r.notes))
        .clone();
    println!("{note}");
    (r, note)
}

#[test]
fn regularizations_that_carry_the_answer_are_noted() {
    // The canonical values carry neither note.
    let r = run_loaded(&load(&coarse(&[])).unwrap(), None, false).unwrap();
    assert!(
        !r.notes.iter().any(|n| n.contains("contact.")),
        "{:?}",
        r.notes
    );
    // 63 candidates (one obstacle: 63 pairs) x 1e3 N of possible pull
    // against 3 x 10 N of load.
    let (_, note) = noted(&[("eta = 1e-6", "eta = 1e3")], "contact.eta");
    assert!(
        note.contains("63 pairs (63 candidate nodes)") && note.contains("6.300e4"),
        "{note}"
    );
    // K = 10 N/m: the end's reactions (~1 N per node) sink nodes by ~0.1 m.
    let (r, note) = noted(&[("k = 1e9", "k = 10.0")], "contact.k");
    let depth: f64 = note
        .split(" ends ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no depth in `{note}`"));
    // Above the 1% of the 2 m strip that triggers the note, below the tip's
    // whole deflection.
    assert!(depth > 0.02 && depth < r.end["uz_A"], "{depth}");
}

#[test]
fn an_eta_beyond_k_delta_is_refused_by_name() {
    let e = load(&coarse(&[("eta = 1e-6", "eta = 1e12")]))
        .and_then(|s| anm::run::build::build_model(&s).map(|_| ()))
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(
        e.contains("contact.eta") && e.contains("below K delta") && e.contains("node 16"),
        "{e}"
    );
}

/// A free plate held only by penalty-law candidates (eta = 0: no force
/// before they touch) under a pressure (tests/data/free-plate-on-plane.toml,
/// review 15): the first step falls through the 1e-3 m gap at lambda =
/// 4e-13 and the plate rocks as its nodes touch, which the run reported as
/// two bifurcations with wavelengths of 4e10 m. The end state is right
/// (the plane carries p A = 100 N), and a note now says that the shell was
/// not held at the start.
#[test]
fn a_shell_not_held_before_contact_is_noted() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/free-plate-on-plane.toml");
    let r = run_loaded(&load(&path).unwrap(), None, false).unwrap();
    assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
    println!("{:?}", r.notes);
    assert!((r.end["R"] - 100.0).abs() <= 1e-3 * 100.0, "{}", r.end["R"]);
    assert!(
        r.notes.iter().any(|n| n.contains("it is not held")),
        "{:?}",
        r.notes
    );
}

/// Review 27: a symmetric nip whose rolls close on a strip that cannot
/// give way holds K × depth (300 N at K = 1e8 N/m, 30,000 N at 1e10): the
/// note blamed a soft K and gave the depth's share of a zero displacement
/// as a 306-digit percentage. It now says the placement overlaps a shell
/// that cannot move and that K sets the force.
#[test]
fn a_nip_closed_on_a_shell_that_cannot_move_is_named() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/symmetric-nip.toml");
    let sc = load(&path).expect("scene");
    let r = run_loaded(&sc, None, false).expect("run");
    println!("{:?}", r.notes);
    let note = r
        .notes
        .iter()
        .find(|n| n.contains("cannot give way"))
        .expect("the overlap note");
    assert!(note.contains("contact.k = 1e8"), "{note}");
    assert!(note.len() < 600, "{note}");
}

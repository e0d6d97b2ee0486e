//! Step control that does not depend on units (the README's rule: the
//! ANM measures displacements against `solver.length_scale`, by default the
//! mesh size, and lambda against its range). The same scenes written in
//! m, N, Pa and in mm, N, MPa take the same steps and give the same answers
//! (1e-8 relative to each column's largest value, converted back to m).

use anm::run::{RunReport, run_loaded};

fn run(text: &str, name: &str) -> RunReport {
    let p = crate::scratch::ScratchFile::with_text("units", name, text);
    let s = anm::scene::shell::load(&p).unwrap();
    let r = run_loaded(&s, None, false).unwrap();
    assert_eq!(r.stop.reason, "end", "{name}: {:?}", r.stop);
    r
}

fn edit(text: &str, edits: &[(&str, &str)]) -> String {
    let mut t = text.to_string();
    for (a, b) in edits {
        assert!(t.contains(a), "`{a}` not in the scene");
        t = t.replace(a, b);
    }
    t
}

/// Compares the m run with the mm run; `length` lists the columns that are
/// lengths (divided by 1000 in the mm run).
fn compare(m: &RunReport, mm: &RunReport, length: &[&str]) {
    println!(
        "steps: m {} mm {}; factorizations: m {} mm {}",
        m.steps, mm.steps, m.factorizations, mm.factorizations
    );
    let ratio = mm.steps as f64 / m.steps as f64;
    assert!(
        (ratio - 1.0).abs() <= 0.05,
        "steps {} vs {}",
        m.steps,
        mm.steps
    );
    assert_eq!(m.history.len(), mm.history.len());
    for (k, c) in m.columns.iter().enumerate() {
        let f = if length.contains(&c.as_str()) {
            1e-3
        } else {
            1.0
        };
        let scale = m
            .history
            .iter()
            .map(|r| r[k].abs())
            .fold(0.0, f64::max)
            .max(1e-300);
        let worst = m
            .history
            .iter()
            .zip(&mm.history)
            .map(|(a, b)| (a[k] - f * b[k]).abs() / scale)
            .fold(0.0, f64::max);
        println!("{c}: max relative difference {worst:.2e}");
        assert!(worst <= 1e-8, "{c}: {worst:e}");
    }
}

#[test]
fn cantilever_elastica_in_m_and_mm() {
    let m = std::fs::read_to_string("scenes/verification/cantilever-shear.toml").unwrap();
    let mm = edit(
        &m,
        &[
            ("x = [0.0, 10.0]", "x = [0.0, 10000.0]"),
            ("y = [-0.5, 0.5]", "y = [-500.0, 500.0]"),
            ("young = 1e7", "young = 10.0"),
            ("thickness = 0.1", "thickness = 100.0"),
        ],
    );
    compare(
        &run(&m, "shear-m.toml"),
        &run(&mm, "shear-mm.toml"),
        &["ux_tip", "uz_tip"],
    );
}

#[test]
fn propped_cantilever_on_a_plane_in_m_and_mm() {
    let m = std::fs::read_to_string("scenes/verification/propped-cantilever.toml").unwrap();
    let mm = edit(
        &m,
        &[
            ("x = [0.0, 1.0]", "x = [0.0, 1000.0]"),
            ("y = [-0.05, 0.05]", "y = [-50.0, 50.0]"),
            ("young = 2e9", "young = 2e3"),
            ("thickness = 0.01", "thickness = 10.0"),
            ("point = [0.0, 0.0, -0.01]", "point = [0.0, 0.0, -10.0]"),
            ("k = 1e9", "k = 1e6"),
            ("search_distance = 1.0", "search_distance = 1000.0"),
        ],
    );
    compare(
        &run(&m, "propped-m.toml"),
        &run(&mm, "propped-mm.toml"),
        &["uz_tip"],
    );
}

//! A sticking node keeps the friction the load history put on it (review
//! 10): on a three-roller line whose first roller is an idler (no motion:
//! its surface at the strip's speed, 0), the nodes on it stick while
//! carrying friction, so the tension it passes on depends on the ramp and
//! on omega, not on Coulomb's law alone. friction.csv only said `stick`;
//! the run now says it in its notes, and the nodes it counts are those
//! friction.csv marks `stick` with a friction force above 1 % of f R_N.

use anm::run::shell_time;
use anm::scene::shell::load;

#[test]
fn nodes_that_stick_with_friction_are_named_in_the_notes() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/three-roller-line.toml");
    let scene = load(&path).unwrap();
    let dir = crate::scratch::scratch("idler");
    let r = shell_time::run(&scene, Some(dir.path())).unwrap();
    assert_eq!(r.stop.reason, "end");
    let note = r
        .notes
        .iter()
        .find(|n| n.contains("stick at"))
        .unwrap_or_else(|| panic!("no note: {:?}", r.notes));
    println!("{note}");
    let counted: usize = note.split_whitespace().next().unwrap().parse().unwrap();
    // The same count from friction.csv: state `stick`, |R_T| > 0.01 f R_N.
    let mut csv = csv::Reader::from_path(dir.path().join("friction.csv")).unwrap();
    let head: Vec<String> = csv.headers().unwrap().iter().map(String::from).collect();
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let (rn, fx, fy, fz, state) = (
        col("rn"),
        col("ft_x"),
        col("ft_y"),
        col("ft_z"),
        col("state"),
    );
    let law_f = scene.friction.as_ref().unwrap().law.f;
    let mut from_csv = 0;
    for rec in csv.records() {
        let rec = rec.unwrap();
        let v = |k: usize| rec[k].parse::<f64>().unwrap();
        let force = (v(fx).powi(2) + v(fy).powi(2) + v(fz).powi(2)).sqrt();
        if &rec[state] == "stick" && force > 0.01 * law_f * v(rn).abs() {
            from_csv += 1;
        }
    }
    assert_eq!(counted, from_csv, "{note}");
    assert!(counted > 0);
}

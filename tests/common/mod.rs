//! Shared helpers of the verification tests.
#![allow(dead_code)]

/// Asserts |got - want| <= tol * max(|want|, floor); fails on NaN and prints both values.
#[track_caller]
pub fn assert_close(what: &str, got: f64, want: f64, tol: f64, floor: f64) {
    assert!(
        got.is_finite(),
        "{what}: got non-finite {got} (want {want})"
    );
    let err = (got - want).abs() / want.abs().max(floor);
    assert!(
        err <= tol,
        "{what}: got {got:.12e}, want {want:.12e}, relative error {err:.3e} > {tol:.1e}"
    );
}

/// Reads a friction scene from scenes/ and applies TOML edits (`table.key = value` lines).
pub fn friction_scene(name: &str, edits: &[(&str, &str)]) -> anm::scene::friction::FrictionScene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    let mut value: toml::Table = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    for (key, v) in edits {
        let (table, k) = key.split_once('.').unwrap();
        let parsed: toml::Table = toml::from_str(&format!("x = {v}")).unwrap();
        let t = value
            .entry(table)
            .or_insert(toml::Value::Table(Default::default()));
        t.as_table_mut()
            .unwrap()
            .insert(k.to_string(), parsed["x"].clone());
    }
    let text = toml::to_string(&value).unwrap();
    let kind = anm::scene::kind(&path, &text).unwrap();
    anm::scene::friction::load(&path, &text, kind).unwrap()
}

/// Column `name` of a run's history.
pub fn column(run: &anm::model::friction_run::FrictionRun, name: &str) -> Vec<f64> {
    let j = run
        .columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    run.history.iter().map(|r| r[j]).collect()
}

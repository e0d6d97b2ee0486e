//! docs/scenes.md documents every key the scene parsers accept.
//!
//! The keys are read from the parsers themselves: an unknown key injected
//! into each table makes serde list the fields that table accepts
//! (`deny_unknown_fields`), and each `table.key` must appear in the docs.

use anm::scene::Kind;
use std::path::Path;

/// The fields serde expects in the table where `zzz_unknown` was injected.
fn accepted(parse: impl Fn(&Path, &str) -> String, text: &str, table: &str) -> Vec<String> {
    let injected = if table.is_empty() {
        format!("zzz_unknown = 1\n{text}")
    } else if table == "obstacle.motion" {
        text.replacen("motion = { type", "motion = { zzz_unknown = 1, type", 1)
    } else {
        let header = if text.contains(&format!("[[{table}]]")) {
            format!("[[{table}]]")
        } else {
            format!("[{table}]")
        };
        assert!(text.contains(&header), "fixture lacks {header}");
        text.replacen(&header, &format!("{header}\nzzz_unknown = 1"), 1)
    };
    assert_ne!(injected, text, "nothing injected for {table}");
    let path = crate::scratch::ScratchFile::with_text("scene-docs", "scene.toml", &injected);
    let message = parse(&path, &injected);
    let expected = message
        .split("expected")
        .nth(1)
        .unwrap_or_else(|| panic!("{table}: no field list in `{message}`"));
    let names: Vec<String> = expected
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect();
    assert!(!names.is_empty(), "{table}: `{message}`");
    names
}

fn check(parse: impl Fn(&Path, &str) -> String + Copy, text: &str, docs: &str) -> usize {
    let mut count = 0;
    let tables = accepted(parse, text, "");
    let mut nested: Vec<String> = tables.clone();
    if text.contains("motion = {") {
        nested.push("obstacle.motion".into());
    }
    let mut missing = vec![];
    for table in nested {
        for key in accepted(parse, text, &table) {
            let name = format!("`{table}.{key}`");
            count += 1;
            if !docs.contains(&name) {
                missing.push(name);
            }
        }
    }
    assert!(
        missing.is_empty(),
        "docs/scenes.md lacks {} keys: {}",
        missing.len(),
        missing.join(", ")
    );
    count
}

#[test]
fn every_shell_and_friction_key_is_documented() {
    let docs = std::fs::read_to_string("docs/scenes.md").expect("docs/scenes.md");
    let mut shell = std::fs::read_to_string("tests/data/shell-every-table.toml").unwrap();
    // The friction table from its own fixture (a scene in time, which the
    // fuzz test does not run).
    let friction = std::fs::read_to_string("tests/data/shell-friction.toml").unwrap();
    let table = &friction[friction.find("\n[friction]").expect("[friction]")..];
    shell.push_str(&table[..table.find("\n[[probe]]").unwrap_or(table.len())]);
    let n_shell = check(
        |p, _| {
            format!(
                "{}",
                anm::scene::shell::load(p).expect_err("injected key must fail")
            )
        },
        &shell,
        &docs,
    );
    let friction = std::fs::read_to_string("scenes/friction-roller.toml").unwrap();
    let n_friction = check(
        |p, t| {
            format!(
                "{}",
                anm::scene::friction::load(p, t, Kind::FrictionRoller)
                    .expect_err("injected key must fail")
            )
        },
        &friction,
        &docs,
    );
    println!("documented: {n_shell} shell keys, {n_friction} friction keys");
    assert!(n_shell > 60 && n_friction > 30);
}

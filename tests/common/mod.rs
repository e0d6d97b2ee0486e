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

/// Rows of two runs on the same output grid with t <= t_max, matched by
/// time (asserted: at least one, and equal times).
pub fn rows_up_to<'a>(
    a: &'a [Vec<f64>],
    b: &'a [Vec<f64>],
    t_max: f64,
) -> Vec<(&'a Vec<f64>, &'a Vec<f64>)> {
    let rows: Vec<_> = a.iter().zip(b).filter(|(ra, _)| ra[0] <= t_max).collect();
    assert!(!rows.is_empty(), "no rows to compare");
    for (ra, rb) in &rows {
        assert!(
            (ra[0] - rb[0]).abs() <= 1e-9,
            "grids differ: {} vs {}",
            ra[0],
            rb[0]
        );
    }
    rows
}

/// Per column j >= 1 (or only those named): max_i |a_ij - b_ij| / max_i
/// |b_ij| over `rows` (from [`rows_up_to`]).
pub fn column_errors(
    cols: &[String],
    rows: &[(&Vec<f64>, &Vec<f64>)],
    only: &[&str],
) -> Vec<(String, f64)> {
    (1..cols.len())
        .filter(|&j| only.is_empty() || only.contains(&cols[j].as_str()))
        .map(|j| {
            let scale = rows.iter().map(|(_, rb)| rb[j].abs()).fold(0.0, f64::max);
            let diff = rows
                .iter()
                .map(|(ra, rb)| (ra[j] - rb[j]).abs())
                .fold(0.0, f64::max);
            (
                cols[j].clone(),
                if scale > 0.0 { diff / scale } else { diff },
            )
        })
        .collect()
}

/// Prints the per-column errors of [`column_errors`] under `title`.
pub fn print_table(title: &str, errs: &[(String, f64)]) {
    println!("{title}");
    println!("  {:<8} {:>12}", "column", "max rel err");
    for (name, e) in errs {
        println!("  {name:<8} {e:>12.3e}");
    }
}

/// The (timestep, part) entries of DIR/shell.pvd, asserted distinct (review
/// 7: shell_final.vtu and the last step's snapshot were both listed at the
/// same time) and naming files that exist; returns their number.
pub fn unique_pvd_entries(dir: &std::path::Path) -> usize {
    let pvd = std::fs::read_to_string(dir.join("shell.pvd")).expect("shell.pvd");
    let attr = |line: &str, key: &str| -> String {
        let at = line.find(&format!("{key}=\"")).expect(key) + key.len() + 2;
        line[at..].split('"').next().unwrap().to_string()
    };
    let mut seen = std::collections::BTreeSet::new();
    for line in pvd.lines().filter(|l| l.contains("<DataSet")) {
        let key = (attr(line, "timestep"), attr(line, "part"));
        assert!(
            seen.insert(key.clone()),
            "{key:?} listed twice in shell.pvd"
        );
        assert!(dir.join(attr(line, "file")).is_file(), "{line}");
    }
    seen.len()
}

/// `anm run --quiet SCENE -o OUT` (the binary of the test target).
pub fn anm_run(scene: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["run", "--quiet"])
        .arg(scene)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

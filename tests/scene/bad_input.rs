//! Bad scene input: each case must give a clear error naming the file and the
//! key, a non-zero exit code, no panic, and no output files.

use crate::scratch::{ScratchFile, scratch};
use std::path::Path;
use std::process::Command;

fn scene_with(edit: impl Fn(&str) -> String, name: &str) -> ScratchFile {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/friction-plane.toml"),
    )
    .unwrap();
    ScratchFile::with_text("bad", &format!("{name}.toml"), &edit(&base))
}

/// `anm run SCENE -o OUT --quiet`, its output.
fn run_to(scene: &Path, out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_anm"))
        .arg("run")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap()
}

/// Runs `anm run SCENE -o OUT` and returns (exit code, stderr, out dir exists).
fn run(scene: &Path) -> (i32, String, bool) {
    let out = scene.with_extension("out");
    let o = run_to(scene, &out);
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
        out.exists(),
    )
}

#[track_caller]
fn expect_error(scene: &Path, needles: &[&str]) {
    let (code, err, out_exists) = run(scene);
    println!("{}: exit {code}: {err}", scene.display());
    assert_ne!(code, 0, "must fail");
    assert!(!err.contains("panicked"), "panic: {err}");
    assert!(
        err.contains(&scene.display().to_string()),
        "error does not name the file: {err}"
    );
    for n in needles {
        assert!(err.contains(n), "error does not mention `{n}`: {err}");
    }
    assert!(!out_exists, "no output may be written for a rejected scene");
}

#[test]
fn unknown_key() {
    let p = scene_with(
        |s| s.replace("k = 1.0 ", "k = 1.0\nstiffness = 2.0 "),
        "unknown",
    );
    expect_error(&p, &["spring.stiffness", "unknown field"]);
}

#[test]
fn wrong_type() {
    let p = scene_with(|s| s.replace("f = 0.2", "f = \"high\""), "type");
    expect_error(&p, &["friction.f", "invalid type"]);
}

#[test]
fn missing_file() {
    let p = ScratchFile::new("missing", "anm-no-such-scene.toml");
    let (code, err, _) = run(&p);
    assert_ne!(code, 0);
    assert!(
        err.contains("anm-no-such-scene.toml") && err.contains("cannot read"),
        "{err}"
    );
}

#[test]
fn negative_stiffness() {
    let p = scene_with(|s| s.replace("k = 1.0 ", "k = -1.0 "), "negk");
    expect_error(&p, &["spring.k", "must be > 0", "-1"]);
}

#[test]
fn negative_friction_coefficient() {
    let p = scene_with(|s| s.replace("f = 0.2", "f = -0.2"), "negf");
    expect_error(&p, &["friction.f", "must be > 0"]);
}

/// Speeds whose square leaves the range of a double made the law's
/// derivatives 0 · ∞ (a NaN backward error at step 0).
#[test]
fn slip_speed_out_of_double_range() {
    for (name, vc) in [("vcbig", "1e300"), ("vcsmall", "1e-300")] {
        let p = scene_with(|s| s.replace("Vc = 1.0 ", &format!("Vc = {vc} ")), name);
        expect_error(&p, &["friction.Vc", "out of the range of a double"]);
    }
    // Review 12: omega = 1e-300 was blamed on friction.Vc.
    let p = scene_with(
        |s| s.replace("omega = 0.1\n", "omega = 1e-300\n"),
        "omegasmall",
    );
    expect_error(&p, &["friction.omega", "out of the range of a double"]);
}

#[test]
fn exponent_outside_unit_interval() {
    for (name, q) in [("qneg", "-0.1"), ("qbig", "1.5")] {
        let p = scene_with(|s| s.replace("q = 0.05", &format!("q = {q}")), name);
        expect_error(&p, &["friction.q", "[0, 1]"]);
    }
}

#[test]
fn order_below_two() {
    let p = scene_with(|s| s.replace("order = 20", "order = 1"), "order");
    expect_error(&p, &["solver.order", ">= 2"]);
}

#[test]
fn end_time_not_positive() {
    for (name, t) in [("tzero", "0.0"), ("tneg", "-3.0")] {
        let p = scene_with(|s| s.replace("t_end = 3.0", &format!("t_end = {t}")), name);
        expect_error(&p, &["solver.t_end", "must be > 0"]);
    }
}

/// A step floor at or above the end time (review 3, D7: min_step = 10 s
/// with t_end = 3 s stopped at t = 0 "at a singularity").
#[test]
fn min_step_not_below_end_time() {
    let p = scene_with(
        |s| s.replace("t_end = 3.0", "t_end = 3.0\nmin_step = 10.0"),
        "minstep",
    );
    expect_error(&p, &["solver.min_step", "below solver.t_end"]);
}

/// Review 3: t_end = 1e300 s makes the default step floor (1e-13 t_end)
/// 1e287 s; the first step, which reaches 1e-1 s or so, stopped the run "at
/// a singular point" at t = 0 with exit 0. A floor above the very first
/// step is a step collapse naming the key, exit 2.
#[test]
fn a_first_step_below_the_floor_is_no_singularity() {
    let p = scene_with(
        |s| {
            s.replace("t_end = 3.0", "t_end = 1e300")
                .replace("dt = 0.01", "dt = 1e298")
        },
        "huge-end",
    );
    let out = p.with_extension("out");
    let o = run_to(&p, &out);
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains("stop = step_collapse"), "{text}");
    assert!(
        text.contains("below solver.min_step = 1.000e287 s"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn unknown_kind_and_missing_section() {
    let p = scene_with(
        |s| s.replace("kind = \"friction-plane\"", "kind = \"friction-cube\""),
        "kind",
    );
    expect_error(&p, &["scene.kind", "friction-cube"]);
    let p = scene_with(|s| s.replace("[contact]", "[contact_law]"), "section");
    expect_error(&p, &["contact_law"]);
}

#[test]
fn key_of_another_kind() {
    let p = scene_with(
        |s| s.replace("V = 1.0 ", "V = 1.0\nOmega = 2.0 "),
        "otherkind",
    );
    expect_error(
        &p,
        &["obstacle.Omega", "not used by a `friction-plane` scene"],
    );
}

#[test]
fn valid_scenes_pass_check() {
    for s in ["friction-1d", "friction-plane", "friction-roller"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{s}.toml"));
        let o = Command::new(env!("CARGO_BIN_EXE_anm"))
            .arg("check")
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{s}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// `anm factor`: a missing or malformed matrix file and a bad option stop
/// with the file or the option named, no panic.
#[test]
fn factor_rejects_bad_matrices_and_options() {
    let tmp = scratch("factor-bad-input");
    let dir = tmp.path();
    let bad = dir.join("bad.mtx");
    std::fs::write(
        &bad,
        "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n",
    )
    .unwrap();
    let good = dir.join("good.mtx");
    std::fs::write(
        &good,
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2.0\n2 1 -1.0\n2 2 2.0\n",
    )
    .unwrap();
    let missing = dir.join("missing.mtx");
    let cases: [(&Path, &[&str], &[&str]); 4] = [
        (&missing, &[], &["missing.mtx"]),
        (&bad, &[], &["bad.mtx", "1 entries, the size line says 2"]),
        (&good, &["--backend", "pardiso"], &["--backend", "pardiso"]),
        (&good, &["--threads", "0"], &["--threads"]),
    ];
    for (file, args, needles) in cases {
        let o = Command::new(env!("CARGO_BIN_EXE_anm"))
            .arg("factor")
            .arg(file)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_ne!(o.status.code(), Some(0), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        for n in needles {
            assert!(err.contains(n), "`{n}` not in: {err}");
        }
    }
    // The good one factors: LDLᵀ of [[2, −1], [−1, 2]], no negative pivot.
    let o = Command::new(env!("CARGO_BIN_EXE_anm"))
        .arg("factor")
        .arg(&good)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["backend"], "ldlt");
    assert_eq!(v["negative_pivots"], 0);
    assert!(v["backward_error"].as_f64().unwrap() <= 1e-15);
}

/// `anm time --method anm:ORDER:EPS` within a friction scene's bounds of
/// solver.order and solver.eps: order 0 panicked (a series index past its
/// end), eps 0 or NaN ran as if meaningful.
#[test]
fn time_rejects_anm_methods_outside_the_scene_bounds() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/friction-1d.toml");
    for (method, needle) in [
        ("anm:0:1e-9", "the order must lie in [2, 200], got 0"),
        ("anm:201:1e-9", "the order must lie in [2, 200], got 201"),
        ("anm:15:0", "eps must lie in [1e-16, 1]"),
        ("anm:15:nan", "eps must lie in [1e-16, 1]"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_anm"))
            .args(["time", "--repeat", "1", "--method", method])
            .arg(&scene)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_ne!(o.status.code(), Some(0), "{method}: {err}");
        assert!(!err.contains("panicked"), "{method}: {err}");
        assert!(
            err.contains(method) && err.contains(needle),
            "{method}: {err}"
        );
    }
}

/// `-o` naming a file (or a path under one): an error that says so, the
/// file untouched ("cannot read: Not a directory" before).
#[test]
fn output_folder_that_is_a_file() {
    let p = scene_with(|s| s.to_string(), "outfile");
    let file = p.with_extension("txt");
    std::fs::write(&file, "keep").unwrap();
    for out in [file.clone(), file.join("sub")] {
        let o = run_to(&p, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        println!("{err}");
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("is a file, not a folder"), "{err}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
}

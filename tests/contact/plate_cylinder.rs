//! plate-cylinder (paper §2.2, DESIGN §4) through the scene driver.
//!
//! Goal: the scene runs to lambda = 1 and writes its outputs (CI: the 0.1 m
//! mesh); the mesh convergence study (ignored: about 20 minutes on 2 shared
//! cores; run with `--ignored --nocapture`) prints uz_A at lambda = 0.05,
//! 0.1, 0.2, 0.5, 1 for the 0.1, 0.05 and 0.025 m meshes (gmsh, 20x2, 40x4,
//! 80x8 elements) and checks the 0.05 m mesh within 1% of the 0.025 m one.
//!
//! Measured (issue 3): uz_A
//! ```text
//! mesh        0.05      0.1       0.2       0.5       1       steps  facts  wall_s
//! 20x2     0.350013  0.494712  0.613096  0.687468  0.705805    257    334     7.4
//! 40x4     0.353928  0.507355  0.617562  0.687011  0.704971    474    559    71.7
//! 80x8     0.355331  0.508088  0.616118  0.686946  0.704847    706    801   469.7
//! ```
//! (order 15, eps 1e-8, no Padé, 2 shared cores.) The 0.05 m mesh is within
//! 0.4% of the 0.025 m one at every lambda (0.02% at lambda = 1).

use anm::run::{run_loaded, run_scene};
use anm::scene::shell::load;
use std::path::Path;

fn scene_with_mesh(mesh: &str, out: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string("scenes/plate-cylinder.toml").unwrap();
    let text = text.replace(
        "../meshes/plate-cylinder.msh",
        &format!("{}/meshes/{mesh}", env!("CARGO_MANIFEST_DIR")),
    );
    std::fs::create_dir_all(out).unwrap();
    let p = out.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
#[ignore]
fn plate_cylinder_mesh_convergence() {
    let lams = [0.05, 0.1, 0.2, 0.5, 1.0];
    let mut rows = vec![];
    for mesh in [
        "plate-cylinder-20x2.msh",
        "plate-cylinder-40x4.msh",
        "plate-cylinder-80x8.msh",
    ] {
        let tmp = crate::scratch::scratch(&format!("pc-{mesh}"));
        let dir = tmp.path();
        let p = scene_with_mesh(mesh, dir);
        let r = run_scene(&p, dir, false).unwrap();
        println!(
            "{mesh}: stop {:?}, steps {}, factorizations {}, wall {:.1} s",
            r.stop, r.steps, r.factorizations, r.wall_s
        );
        rows.push((
            mesh,
            lams.map(|l| r.value_at("uz_A", l).unwrap_or(f64::NAN)),
            r.steps,
            r.factorizations,
            r.wall_s,
        ));
    }
    println!(
        "{:<26} {:>10} {:>10} {:>10} {:>10} {:>10} {:>6} {:>6} {:>8}",
        "mesh", "0.05", "0.1", "0.2", "0.5", "1", "steps", "facts", "wall_s"
    );
    for (m, v, s, f, w) in &rows {
        println!(
            "{m:<26} {:>10.6} {:>10.6} {:>10.6} {:>10.6} {:>10.6} {s:>6} {f:>6} {w:>8.1}",
            v[0], v[1], v[2], v[3], v[4]
        );
    }
    // Target (issue 3, item 7): the 0.05 m mesh within 1% of the finest.
    let (mid, fine) = (rows[1].1, rows[2].1);
    for (k, l) in lams.iter().enumerate() {
        let err = (mid[k] - fine[k]).abs() / fine[k].abs();
        assert!(
            err <= 0.01,
            "lambda {l}: 0.05 m mesh {} vs 0.025 m {} ({err:.2e})",
            mid[k],
            fine[k]
        );
    }
}

#[test]
fn gmsh_mesh_has_the_groups_rows_and_orientation() {
    let m = anm::mesh::gmsh::read(Path::new("meshes/plate-cylinder.msh")).unwrap();
    assert_eq!((m.nodes.len(), m.quads.len()), (41 * 5, 40 * 4));
    let clamp = &m.groups["clamp"];
    assert_eq!(clamp.len(), 5);
    assert!(clamp.iter().all(|&n| m.nodes[n][0] == 0.0));
    let a = &m.groups["load_A"];
    assert_eq!(a.len(), 1);
    assert!((m.nodes[a[0]] - anm::mesh::Vec3::new(2.0, 0.0, 0.0)).norm() < 1e-12);
    for x in [1.0, 1.1, 1.2] {
        let row = m.nodes.iter().filter(|p| (p[0] - x).abs() < 1e-9).count();
        assert_eq!(row, 5, "node row at x = {x}");
    }
    let d = m.directors().unwrap();
    // Consistent orientation: every director is the same unit normal (±z).
    assert!(
        d.iter()
            .all(|v| (v - d[0]).norm() < 1e-12 && (v[2].abs() - 1.0).abs() < 1e-12)
    );
}

/// CI run: the coarse (0.1 m) mesh to lambda = 1 through the scene driver.
#[test]
fn plate_cylinder_scene_runs_and_writes_outputs() {
    let tmp = crate::scratch::scratch("pc-ci");
    let dir = tmp.path().join("out");
    let p = scene_with_mesh("plate-cylinder-20x2.msh", &dir);
    let r = run_scene(&p, &dir, false).unwrap();
    println!("{}", serde_json::to_string_pretty(&r).unwrap());
    assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
    for f in [
        "history.csv",
        "summary.json",
        "plot.svg",
        "shell.pvd",
        "steps.csv",
        "obstacle_0.vtu",
        "shell_0000.vtu",
        "shell_final.vtu",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    // The uniform grid 0, 0.01, ..., 1 is complete and uz_A grows with lambda.
    assert_eq!(r.history.len(), 101);
    for (k, w) in r.history.windows(2).enumerate() {
        assert!((w[1][0] - 0.01 * (k + 1) as f64).abs() < 1e-12);
        assert!(
            w[1][1] > w[0][1],
            "uz_A not increasing at lambda {}",
            w[1][0]
        );
    }
    assert_eq!(r.columns[1], "uz_A");
    assert!((r.history[100][1] - r.end["uz_A"]).abs() < 1e-15);
    let _ = (run_loaded, load);
}

/// The backends give the same answer: the coarse plate-cylinder with the
/// automatic choice (symmetric tangents: LDLᵀ, checked to be the one used)
/// and with the LU forced. Measured: uz_A(1) = 0.7058050842717 and
/// 0.7058050844455 (2.5e-10 apart, below the series tolerance eps = 1e-8),
/// both backward errors 2.9e-16. The step counts are not equal (161 and
/// 147): the flat strip's tangent has a condition number near 1e10, so two
/// backward-stable factorizations give high-order terms that differ in
/// their last digits, and the Padé and step-length tests read those digits.
/// The bound below (25%) only guards against a backend that derails.
#[test]
fn ldlt_and_lu_follow_the_same_path() {
    use anm::linalg::{Backend, Choice};
    let tmp = crate::scratch::scratch("pc-backends");
    let dir = tmp.path();
    let p = scene_with_mesh("plate-cylinder-20x2.msh", dir);
    let mut scene = load(&p).unwrap();
    scene.output.plot = false;
    scene.output.vtk_every = 0;
    let auto = run_loaded(&scene, None, false).unwrap();
    scene.solver.linear = Choice::Only(Backend::Lu);
    let lu = run_loaded(&scene, None, false).unwrap();
    for r in [&auto, &lu] {
        assert_eq!(r.stop.reason, "end");
    }
    let linear = &auto.stats.linear;
    assert!(
        linear.ldlt > 0 && linear.lu == 0 && linear.fallbacks == 0,
        "{linear:?}"
    );
    assert_eq!(auto.stats.linear.negative_pivots, Some(0));
    assert!(lu.stats.linear.lu > 0 && lu.stats.linear.ldlt == 0);
    let (a, b) = (auto.end["uz_A"], lu.end["uz_A"]);
    println!(
        "steps {} / {}, uz_A {a:.13} / {b:.13}, max backward error {:.1e} / {:.1e}",
        auto.steps, lu.steps, linear.max_backward_error, lu.stats.linear.max_backward_error
    );
    assert!((a - b).abs() <= 1e-9 * b.abs());
    assert!(auto.steps.abs_diff(lu.steps) * 4 <= lu.steps);
}

/// The penalty law (contact.eta = 0, R = max(0, -K h)): every step ends at
/// the first node touching or lifting off (src/series/kinks.rs). On the
/// 0.1 m mesh it must follow eq. (3) at eta = 1e-10 N (the limit it is,
/// computed through the regularized switch with the contact arclength) and
/// Newton-Raphson on the same law (small arclength increments, |R|/|F| <=
/// 1e-7) over the lambda grid, in at most a quarter of the steps of the
/// former. Measured (the scene's N = 15 with Padé): 18 steps (13 ending at
/// a kink) against 168 (Newton: 1,403); uz_A, rn_total within 5.9e-7,
/// 3.4e-7 of eta = 1e-10 and 5.9e-7, 2.4e-7 of Newton.
#[test]
fn the_penalty_law_follows_the_small_eta_limit_in_a_quarter_of_the_steps() {
    let tmp = crate::scratch::scratch("pc-penalty");
    let dir = tmp.path();
    let p = scene_with_mesh("plate-cylinder-20x2.msh", dir);
    let text = std::fs::read_to_string(&p).unwrap();
    let with = |name: &str, edits: &[(&str, &str)]| {
        let mut t = text.clone();
        for (old, new) in edits {
            assert!(t.contains(old), "{old}");
            t = t.replacen(old, new, 1);
        }
        let q = dir.join(name);
        std::fs::write(&q, t).unwrap();
        let mut s = load(&q).unwrap();
        s.output.plot = false;
        s.output.vtk_every = 0;
        let r = run_loaded(&s, None, false).unwrap();
        assert_eq!(r.stop.reason, "end", "{name}: {:?}", r.stop);
        r
    };
    let penalty = with("penalty.toml", &[("eta = 1e-6", "eta = 0.0")]);
    let small_eta = with("small-eta.toml", &[("eta = 1e-6", "eta = 1e-10")]);
    let newton = with(
        "newton.toml",
        &[
            ("eta = 1e-6", "eta = 0.0"),
            (
                "order = 15\neps = 1e-8",
                "method = \"newton\"\nnewton_step = 0.001\nnewton_max_step = 0.005\nnewton_tol = 1e-7",
            ),
            ("pade = true\n", ""),
            ("correct = true\nmax_corrections = 10\n", ""),
            ("residual_tol = 1e-6", "residual_tol = 1e-7"),
        ],
    );
    // The same Newton with a line search on |R| (solver.newton_line_search):
    // the full update crosses kinks; backtracking takes fewer
    // factorizations to the same curves (measured: 1,403 → 1,333
    // increments, 3,823 → 3,300 factorizations here).
    let searched = with(
        "newton-line-search.toml",
        &[
            ("eta = 1e-6", "eta = 0.0"),
            (
                "order = 15\neps = 1e-8",
                "method = \"newton\"\nnewton_step = 0.001\nnewton_max_step = 0.005\nnewton_tol = 1e-7\nnewton_line_search = true",
            ),
            ("pade = true\n", ""),
            ("correct = true\nmax_corrections = 10\n", ""),
            ("residual_tol = 1e-6", "residual_tol = 1e-7"),
        ],
    );
    let deviation = |a: &anm::run::RunReport, b: &anm::run::RunReport, name: &str| {
        let k = a.columns.iter().position(|c| c == name).unwrap();
        assert_eq!(a.history.len(), b.history.len());
        let big = b.history.iter().map(|r| r[k].abs()).fold(0.0, f64::max);
        a.history
            .iter()
            .zip(&b.history)
            .map(|(x, y)| (x[k] - y[k]).abs())
            .fold(0.0, f64::max)
            / big
    };
    let kinks = penalty.stats.kink_cuts;
    println!(
        "penalty: {} steps ({kinks} ending at a kink); eta = 1e-10: {} steps; Newton: {} steps",
        penalty.steps, small_eta.steps, newton.steps
    );
    for name in ["uz_A", "rn_total"] {
        let (e, n) = (
            deviation(&penalty, &small_eta, name),
            deviation(&penalty, &newton, name),
        );
        let ls = deviation(&penalty, &searched, name);
        println!(
            "{name}: {e:.2e} from eta = 1e-10, {n:.2e} from Newton, {ls:.2e} from Newton with line search"
        );
        assert!(
            e <= 1e-6 && n <= 1e-6 && ls <= 1e-6,
            "{name}: {e:e} {n:e} {ls:e}"
        );
    }
    println!(
        "Newton: {} increments, {} factorizations; with line search: {}, {}",
        newton.steps, newton.stats.factorizations, searched.steps, searched.stats.factorizations
    );
    assert!(
        searched.stats.factorizations < newton.stats.factorizations,
        "line search: {} factorizations against {}",
        searched.stats.factorizations,
        newton.stats.factorizations
    );
    assert!(kinks > 0, "no step ended at a kink");
    assert!(
        4 * penalty.steps <= small_eta.steps,
        "{} vs {}",
        penalty.steps,
        small_eta.steps
    );
}

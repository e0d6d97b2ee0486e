//! Critical points and buckling (issue 14, DESIGN §8) against closed forms:
//! the Euler column (cantilever strip, P_cr = pi² E I / (4 L²)) by
//! `anm buckle` and located on the ANM path, its post-buckled branch
//! against the elastica, and the simply supported square plate under
//! uniaxial compression (sigma_cr = 4 pi² E t² / (12 (1 − nu²) b²)). The
//! scenes put P_cr (resp. sigma_cr t) at lambda = 1.

use anm::run::run_loaded;
use anm::scene::shell::{ShellScene, load};
use anm::study::buckle::{Base, buckle};
use std::f64::consts::PI;

fn scene(name: &str) -> ShellScene {
    let path = format!(
        "{}/scenes/verification/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    load(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Complete elliptic integral of the first kind K(k) = pi / (2 AGM(1,
/// sqrt(1 − k²))) (Abramowitz & Stegun 17.6; DLMF 19.8.5).
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    while (a - b).abs() > 1e-15 * a {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

/// Elastica of the clamped–free column: P / P_cr = (2 K(sin(alpha/2)) / pi)².
fn elastica(alpha: f64) -> f64 {
    (2.0 * elliptic_k((0.5 * alpha).sin()) / PI).powi(2)
}

#[test]
fn elliptic_integral_by_the_agm_matches_tabulated_values() {
    // A&S Table 17.1: K(sin 30°) = 1.685750355, K(sin 60°) = 2.156515647.
    assert!((elliptic_k(0.5) - 1.685_750_355).abs() < 1e-9);
    assert!((elliptic_k(60f64.to_radians().sin()) - 2.156_515_647).abs() < 1e-9);
    assert!((elastica(1e-6) - 1.0).abs() < 1e-10);
}

#[test]
fn euler_column_buckle_and_path_bifurcation_match_the_closed_form() {
    let sc = scene("euler-column");
    let b = buckle(&sc, Base::Lambda(0.0), 2, None).expect("buckle");
    print!("{}", anm::study::buckle::table(&b));
    let mu = b.modes[0].mu;
    println!("| case | lambda_cr | closed form | relative error |\n|---|---|---|---|");
    println!("| anm buckle (20 x 1) | {mu:.9} | 1 | {:.2e} |", mu - 1.0);
    assert!((mu - 1.0).abs() <= 5e-3, "buckle: {mu}");
    // The second mode: (3 pi / 2L)² → 9 P_cr.
    assert!(
        (b.modes[1].mu / 9.0 - 1.0).abs() <= 2e-2,
        "{}",
        b.modes[1].mu
    );
    // Mode shape 1 − cos(pi x / 2L): a quarter wave, wavelength 4L = 40.
    let w = b.modes[0].wavelength.expect("wavelength");
    assert!((w / 40.0 - 1.0).abs() < 0.05, "wavelength {w}");

    // The perfect column's path crosses the bifurcation in one step.
    let r = run_loaded(&sc, None, false).expect("run");
    assert_eq!(r.stop.reason, "end");
    let bif: Vec<_> = r
        .events
        .iter()
        .filter(|e| e.kind == "bifurcation")
        .collect();
    assert_eq!(bif.len(), 1, "{:?}", r.events);
    let e = bif[0];
    println!(
        "| located on the path | {:.9} | 1 | {:.2e} | ({} factorizations, step {}, pivots {:?})",
        e.lambda,
        e.lambda - 1.0,
        e.factorizations,
        e.step,
        e.negative_pivots
    );
    assert!((e.lambda - 1.0).abs() <= 5e-3, "{}", e.lambda);
    assert_eq!(e.negative_pivots, Some((0, 1)));
    assert!((e.wavelength.unwrap() / 40.0 - 1.0).abs() < 0.05);
    // The path ends past P_cr: its end's tangent has one negative
    // eigenvalue, which summary.json's stats.linear reports (review 14:
    // it reported the last step's start, 0).
    assert_eq!(r.stats.linear.negative_pivots, Some(1));

    // Location accuracy, independently of the locator: linearized buckling
    // (subspace iteration on the pencil) about the path state just before
    // the located point, lambda_b = 0.999 lambda*, predicts
    // lambda_b + mu_1; its linearization error is O((lambda* − lambda_b)²)
    // times the prebuckling nonlinearity (strains ~ 2e-5), far below 1e-6.
    let lb = 0.999 * e.lambda;
    let near = buckle(&sc, Base::Lambda(lb), 1, None).expect("buckle near");
    let predicted = lb + near.modes[0].mu;
    let rel = (predicted - e.lambda).abs() / e.lambda;
    println!(
        "location: path {:.12}, buckle about {lb:.9}: {predicted:.12}, relative difference {rel:.2e} (target 1e-6)",
        e.lambda
    );
    assert!(rel <= 1e-6, "{rel:e}");
}

/// Worst relative difference of P/P_cr from the elastica over the history
/// rows with alpha >= 10° (below, an imperfection governs), and the largest
/// alpha; prints the table.
fn elastica_error(r: &anm::run::RunReport) -> (f64, f64) {
    let col = |n: &str| r.columns.iter().position(|c| c == n).unwrap();
    let (wx, wz) = (col("wx_tip"), col("wz_tip"));
    println!("| P/P_cr | alpha (deg) | elastica | relative error |\n|---|---|---|---|");
    let mut worst: f64 = 0.0;
    let mut alpha_max: f64 = 0.0;
    for row in &r.history {
        let alpha = row[wx].abs().atan2(1.0 + row[wz]);
        if alpha < 10f64.to_radians() {
            continue;
        }
        let want = elastica(alpha);
        let err = row[0] / want - 1.0;
        println!(
            "| {:.3} | {:.2} | {want:.6} | {err:+.2e} |",
            row[0],
            alpha.to_degrees()
        );
        worst = worst.max(err.abs());
        alpha_max = alpha_max.max(alpha);
    }
    println!(
        "worst {worst:.2e} up to alpha = {:.1}°",
        alpha_max.to_degrees()
    );
    (worst, alpha_max.to_degrees())
}

#[test]
fn post_buckled_column_follows_the_elastica_to_120_degrees() {
    // With a lateral imperfection (1e-3 P): the path itself goes round the
    // bifurcation.
    let r = run_loaded(&scene("euler-column-postbuckling"), None, false).expect("run");
    assert_eq!(r.stop.reason, "end");
    let (worst, alpha_max) = elastica_error(&r);
    assert!(alpha_max >= 120.0, "{alpha_max}");
    assert!(worst <= 5e-3, "{worst:e}");
}

#[test]
fn perfect_column_switches_to_the_bifurcated_branch_in_either_direction() {
    let mut sc = scene("euler-column-secondary");
    let r = run_loaded(&sc, None, false).expect("run");
    assert_eq!(r.stop.reason, "end");
    let at = r.switched_at.expect("switched");
    println!("left the primary path at lambda = {at:.9}");
    assert!((at - 1.0).abs() <= 5e-3, "{at}");
    // The post-buckled branch is stable: no further event.
    assert_eq!(r.events.len(), 1, "{:?}", r.events);
    let (worst, alpha_max) = elastica_error(&r);
    assert!(alpha_max >= 120.0, "{alpha_max}");
    assert!(worst <= 5e-3, "{worst:e}");
    // The other direction: the mirror image (uz of the tip reversed), same
    // load-rotation curve.
    sc.branch = anm::scene::shell::Branch::Secondary { direction: -1.0 };
    let m = run_loaded(&sc, None, false).expect("run, direction -1");
    assert_eq!(m.stop.reason, "end");
    let (uz, uz_m) = (r.end["uz_tip"], m.end["uz_tip"]);
    println!("tip uz at lambda = 1.9: direction +1 {uz:.6}, direction -1 {uz_m:.6}");
    assert!(uz.signum() != uz_m.signum() && ((uz + uz_m) / uz).abs() < 1e-6);
    let (worst_m, _) = elastica_error(&m);
    assert!(worst_m <= 5e-3, "{worst_m:e}");
}

#[test]
fn simply_supported_plate_buckles_at_the_closed_form_stress() {
    let sc = scene("plate-buckling");
    let b = buckle(&sc, Base::Lambda(0.0), 2, None).expect("buckle");
    print!("{}", anm::study::buckle::table(&b));
    let mu = b.modes[0].mu;
    println!(
        "plate 16 x 16: sigma_cr / closed form = {mu:.6} (error {:.2e}, tolerance 1e-2)",
        mu - 1.0
    );
    assert!((mu - 1.0).abs() <= 1e-2, "{mu}");
    // One half-wave each way: wavelength 2a.
    let h = b.modes[0].half_waves.unwrap();
    assert!((h - 1.0).abs() < 0.05, "half-waves {h}");
    // The second mode, two half-waves along x: k = (2 + 1/2)² = 6.25.
    assert!(
        (b.modes[1].mu / (6.25 / 4.0) - 1.0).abs() <= 3e-2,
        "{}",
        b.modes[1].mu
    );
}

#[test]
fn arch_limit_points_are_told_apart_and_located_where_lambda_turns() {
    // The shallow clamped arch passes a limit point, turns back and snaps
    // (two limit points). Located by the tangent's eigenvalue crossing
    // zero, each must sit where the same series has dlambda/da = 0 (the
    // other characterization of a limit point; bisection on the series'
    // polynomial, no tangent involved).
    use anm::series::bifurcation::{self, Kind};
    let sc = scene("clamped-arch-snap");
    let r = run_loaded(&sc, None, false).expect("run");
    let kinds: Vec<&str> = r.events.iter().map(|e| e.kind.as_str()).collect();
    assert_eq!(kinds, ["limit_point", "limit_point"], "{:?}", r.events);
    let mut model = anm::run::build::build_model(&sc).expect("model");
    model.length_scale = sc.length_scale;
    let mut cfg = sc.solver.clone();
    cfg.lambda_scale = cfg.lambda_end.abs();
    let settings = bifurcation::Settings {
        lambda_scale: cfg.lambda_scale,
        ..Default::default()
    };
    let n = anm::series::ContinuationProblem::ndof(&model);
    let mut steps = vec![];
    {
        let mut path = anm::series::Path::new(&mut model, vec![0.0; n], 0.0, cfg.clone());
        while let Ok(s) = path.step() {
            steps.push(s);
        }
    }
    let mut lu = anm::linalg::LinearSolver::default();
    println!(
        "| step | lambda located (eigenvalue) | lambda at dlambda/da = 0 | relative difference | a difference / step length |\n|---|---|---|---|---|"
    );
    let mut found = 0;
    for w in steps.windows(2) {
        let (n0, n1) = (w[0].negative_pivots.unwrap(), w[1].negative_pivots.unwrap());
        if n0 == n1 {
            continue;
        }
        let located = bifurcation::locate(&mut model, &w[0], n0, n1, &mut lu, &settings).unwrap();
        assert_eq!(located.len(), 1);
        assert_eq!(located[0].kind, Kind::LimitPoint);
        let turn = bifurcation::limit_point(&w[0]);
        let rel = (located[0].lambda - turn.lambda).abs() / turn.lambda.abs();
        // lambda is stationary there: the path parameter is the sharper test.
        let da = (located[0].a - turn.a).abs() / w[0].length;
        println!(
            "| {} | {:.15} | {:.15} | {rel:.1e} | {da:.1e} |",
            w[0].index + 1,
            located[0].lambda,
            turn.lambda
        );
        assert!(rel <= 1e-6, "{rel:e}");
        assert!(da <= 1e-4, "{da:e}");
        found += 1;
    }
    assert_eq!(found, 2);
}

#[test]
fn cantilever_under_end_moment_bifurcates_out_of_plane_and_follows_the_branch() {
    // Issue 14, 5d. No closed form for this point: its two independent
    // estimates must agree, the Cochelin–Medale geometric series (the
    // step's series with its geometric part removed, at a = alpha_1) and
    // the root of the tangent's real eigenvalue nearest zero on the series.
    let mut sc = scene("cantilever-moment-bifurcation");
    let r = run_loaded(&sc, None, false).expect("run");
    assert_eq!(r.stop.reason, "end");
    let find = |k: &str| r.events.iter().find(|e| e.kind == k).cloned();
    let g = find("geometric").expect("geometric event");
    let b = find("bifurcation").expect("located bifurcation");
    let rel = (g.lambda - b.lambda).abs() / b.lambda;
    println!(
        "out-of-plane bifurcation: located lambda = M / M_max = {:.12} (bracket {:.1e}, {} factorizations), geometric-series estimate {:.12}, relative difference {rel:.1e}",
        b.lambda, b.bracket, b.factorizations, g.lambda
    );
    assert!((0.78..0.80).contains(&b.lambda), "{}", b.lambda);
    assert!(rel <= 1e-6, "{rel:e}");
    assert_eq!(r.switched_at, Some(b.lambda));
    // Reported branch by branch: the switching point is on the primary.
    assert_eq!(b.branch, "primary");
    for e in &r.events {
        let expected = if e.step <= b.step {
            "primary"
        } else {
            "secondary"
        };
        assert_eq!(e.branch, expected, "{e:?}");
    }
    // The followed branch is out of plane; the tip of the planar (primary)
    // solution would have uy = 0 and be back at the clamp (ux = -L).
    let uy = r.end["uy_tip"];
    println!(
        "secondary branch at lambda = 1: tip uy = {uy:.6}, ux = {:.6}, uz = {:.6}",
        r.end["ux_tip"], r.end["uz_tip"]
    );
    assert!(uy.abs() > 0.1, "{uy}");
    sc.branch = anm::scene::shell::Branch::Primary;
    let p = run_loaded(&sc, None, false).expect("primary run");
    println!(
        "primary path at lambda = 1: tip uy = {:.2e}, ux = {:.6} (closed circle: ux = -10)",
        p.end["uy_tip"], p.end["ux_tip"]
    );
    assert!(p.end["uy_tip"].abs() < 1e-6);
    assert!((p.end["ux_tip"] + 10.0).abs() < 0.05);
}

#[test]
fn bad_branch_keys_and_an_unstable_buckling_state_are_clear_errors() {
    let base = std::fs::read_to_string(format!(
        "{}/scenes/verification/euler-column.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let tmp = crate::scratch::scratch("bifurcation-bad-input");
    let dir = tmp.path();
    let cases = [
        ("branch = \"tertiary\"", "solver.branch"),
        ("branch_direction = -1.0", "solver.branch_direction"),
        (
            "branch = \"secondary\"\nbranch_direction = 2.0",
            "solver.branch_direction",
        ),
        (
            "branch = \"secondary\"\nmethod = \"newton\"",
            "solver.branch",
        ),
    ];
    for (k, (extra, key)) in cases.iter().enumerate() {
        let text = base.replace("lambda_end = 2.0", &format!("lambda_end = 2.0\n{extra}"));
        let text = if extra.contains("newton") {
            text.replace("order = 20\neps = 1e-8\n", "")
        } else {
            text
        };
        let p = dir.join(format!("case{k}.toml"));
        std::fs::write(&p, text).unwrap();
        let e = load(&p)
            .err()
            .unwrap_or_else(|| panic!("{extra}: accepted"));
        let msg = e.to_string();
        println!("{extra:?}: {msg}");
        assert!(msg.contains(key) && msg.contains("case"), "{msg}");
    }
    // Past the bifurcation the base state is unstable: refused, with why.
    let e = buckle(&scene("euler-column"), Base::Lambda(1.5), 1, None)
        .expect_err("unstable base state");
    let msg = e.to_string();
    println!("{msg}");
    assert!(msg.contains("negative pivot"), "{msg}");
    // A friction scene's states are in time, the others' in lambda.
    let e = buckle(&scene("euler-column-in-time"), Base::Lambda(0.5), 1, None)
        .expect_err("lambda on a friction scene");
    assert!(e.to_string().contains("--time"), "{e}");
    let e = buckle(&scene("euler-column"), Base::Time(0.5), 1, None)
        .expect_err("time on a scene without friction");
    assert!(e.to_string().contains("--lambda"), "{e}");
    let e = buckle(&scene("euler-column-in-time"), Base::Time(-1.0), 1, None)
        .expect_err("negative time");
    assert!(e.to_string().contains("--time"), "{e}");
}

/// The cost comparison of issue 14 item 7 (`anm buckle --locate`): Newton
/// load increments with bisection on the negative pivots, an independent
/// locator, finds the Euler column's bifurcation where the ANM locates it
/// on its series (measured: 1.000967026 and 1.000967174, 1.5e-7 apart, the
/// bisection's bracket 7.6e-7; 56 and 11 factorizations).
#[test]
fn newton_bisection_and_the_anm_locate_the_same_euler_load() {
    use anm::study::critical_cost;
    let sc = scene("euler-column");
    let a = critical_cost::anm(&sc).expect("ANM");
    let n = critical_cost::newton_bisection(&sc, 0.1, 1e-6).expect("Newton");
    print!(
        "{}",
        critical_cost::table("euler-column", &[a.clone(), n.clone()])
    );
    assert!(n.bracket <= 1e-6 * n.lambda);
    assert!(
        (a.lambda - n.lambda).abs() <= 1e-6 * a.lambda,
        "{} vs {}",
        a.lambda,
        n.lambda
    );
    assert!((n.lambda - 1.0).abs() <= 5e-3);
}

/// Items 1 and 2 on a path in time (shell::stability): the Euler column of
/// euler-column.toml loaded in time by a [friction] scene whose contact
/// group is the clamped end (no contact force on the free unknowns). The
/// tied tangent is then the static tangent; the critical point, found
/// between two outputs 0.05 s apart and located by restarts from the
/// earlier one, must be the closed form (+9.7e-4 on 20 elements) and the
/// ANM path's location on the same mesh to 1e-6; `anm buckle --time`
/// about t = 0.5 must agree with it.
#[test]
fn stability_monitor_in_time_locates_the_euler_load() {
    let sc = scene("euler-column-in-time");
    let r = anm::run::shell_time::run(&sc, None).expect("run in time");
    assert_eq!(r.events.len(), 1, "one critical point: {:?}", r.events);
    let e = &r.events[0];
    // The load is 1.2 P_cr at lambda = 1.
    let p = 1.2 * e.lambda;
    let path = run_loaded(&scene("euler-column"), None, false).expect("lambda path");
    let on_path = path
        .events
        .iter()
        .find(|e| e.kind == "bifurcation")
        .expect("located on the path")
        .lambda;
    let b = buckle(&sc, Base::Time(0.5), 1, None).expect("buckle about t = 0.5");
    let pb = 1.2 * b.modes[0].lambda_critical;
    println!("| estimate | P / P_cr | vs closed form |\n|---|---|---|");
    println!(
        "| monitor in time, located ({} restarts, bracket {:.1e} s) | {p:.9} | {:.2e} |",
        e.restarts,
        e.bracket[1] - e.bracket[0],
        p - 1.0
    );
    println!(
        "| ANM path (euler-column.toml) | {on_path:.9} | {:.2e} |",
        on_path - 1.0
    );
    println!("| anm buckle --time 0.5 | {pb:.9} | {:.2e} |", pb - 1.0);
    assert_eq!(e.negative_pivots, [0, 1]);
    assert_eq!(e.detected_by, "negative pivots");
    assert!(e.bracket[0] <= e.t && e.t <= e.bracket[1]);
    assert!(e.bracket[1] - e.bracket[0] <= 1e-7 * e.t, "{:?}", e.bracket);
    assert!((p - 1.0).abs() < 5e-3, "P / P_cr = {p}");
    assert!(
        (p / on_path - 1.0).abs() < 1e-6,
        "{p} vs the path's {on_path}"
    );
    assert!((pb - p).abs() < 1e-5, "buckle {pb} vs monitor {p}");
    // The cantilever's quarter wave.
    let hw = e.half_waves.expect("a wavelength");
    assert!((hw - 0.5).abs() < 0.05, "half-waves {hw}");
    assert_eq!((b.sticking, b.slipping), (0, 0));
}

/// A plate a/b = 1.5 under the same compression: k(m) = (m b/a + a/(m b))²
/// puts its points at lambda = k/4 = 1.0851 (m = 2), 1.1736 (m = 1),
/// 1.5625 (m = 3), and the path's one first step (to lambda 2) crosses all
/// three. Review 4: the location took the eigenvalue nearest zero with
/// three crossings in the bracket and reported only the second point
/// (1.1837, its bracket the whole step); `branch = "secondary"` then left
/// at it. Each point must be located, in order, with its half-waves.
#[test]
fn a_step_over_three_critical_points_locates_each() {
    let path = format!(
        "{}/scenes/verification/plate-buckling.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("x = [0.0, 1.0]", "x = [0.0, 1.5]")
        .replace("divisions = [16, 16]", "divisions = [18, 12]")
        .replace("point = [0.5, 0.5, 0.0]", "point = [0.75, 0.5, 0.0]");
    let file = crate::scratch::ScratchFile::with_text("three-points", "p.toml", &text);
    let sc = load(&file).unwrap();
    let r = run_loaded(&sc, None, false).unwrap();
    let found: Vec<(f64, f64, (usize, usize))> = r
        .events
        .iter()
        .map(|e| {
            (
                e.lambda,
                e.half_waves.unwrap_or(0.0),
                e.negative_pivots.unwrap(),
            )
        })
        .collect();
    println!("{found:?}");
    let k = |m: f64| (m / 1.5 + 1.5 / m).powi(2) / 4.0;
    let want = [(k(2.0), 2.0), (k(1.0), 1.0), (k(3.0), 3.0)];
    assert_eq!(found.len(), 3, "{found:?}");
    for (i, ((l, waves, pivots), (l_cf, m))) in found.iter().zip(want).enumerate() {
        // The 18 x 12 mesh's own error: 1.3 %, 1.0 %, 3.3 %.
        assert!(
            (l - l_cf).abs() <= 0.04 * l_cf,
            "point {i}: {l} against {l_cf}"
        );
        assert!(
            (waves - m).abs() < 0.1,
            "point {i}: {waves} half-waves against {m}"
        );
        assert_eq!(*pivots, (i, i + 1));
    }
    // The secondary branch leaves at the first.
    let mut sec = sc.clone();
    sec.branch = anm::scene::shell::Branch::Secondary { direction: 1.0 };
    sec.solver.lambda_end = 1.3;
    let r = run_loaded(&sec, None, false).unwrap();
    let at = r.switched_at.expect("a switch");
    assert!((at - found[0].0).abs() < 1e-9, "switched at {at}");
    assert!(
        r.events.iter().all(|e| e.lambda <= at + 1e-9),
        "{:?}",
        r.events
    );
}

/// The Newton baseline does not locate critical points, but its steps'
/// inertia brackets them, and the run says so (review 4: steps.csv showed
/// one negative pivot past P_cr and the run was silent). The Euler
/// column's point, lambda = 1 by the closed form, lies in the bracket.
#[test]
fn newton_runs_name_the_critical_points_their_steps_bracket() {
    let path = format!(
        "{}/scenes/verification/euler-column.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).unwrap().replace(
        "order = 20\neps = 1e-8\nlambda_end = 2.0",
        "method = \"newton\"\nlambda_end = 1.5",
    );
    let file = crate::scratch::ScratchFile::with_text("newton-bracket", "c.toml", &text);
    let r = run_loaded(&load(&file).unwrap(), None, false).unwrap();
    assert!(r.events.is_empty());
    println!("{:?}", r.notes);
    assert_eq!(r.notes.len(), 1, "{:?}", r.notes);
    let note = &r.notes[0];
    assert!(note.contains("negative pivots 0 -> 1"), "{note}");
    let words: Vec<&str> = note
        .split("increment ends at lambda = ")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .collect();
    let numbers: Vec<f64> = [words[0], words[2].trim_end_matches(':')]
        .iter()
        .map(|w| w.parse().unwrap())
        .collect();
    assert!(numbers[0] <= 1.0 && 1.0 <= numbers[1] * 1.01, "{numbers:?}");
}

/// A pinned-pinned column (P_cr = pi² EI / L² per unit lambda; the 40
/// elements' error 7.8e-4). Its point is found where kappa's sign and the
/// inertia disagree, within round-off of the crossing, while the bracket
/// left by the iteration was still 5e-4 wide in lambda (review 4): the
/// event's `bracket` must be one the inertia changes in, as tight as the
/// location (1e-9 relative asked of it).
#[test]
fn an_event_s_bracket_is_as_tight_as_its_location() {
    let text = r#"
[scene]
kind = "shell"
units = "m"

[mesh]
type = "rectangle"
x = [0.0, 5.0]
y = [-0.5, 0.5]
divisions = [40, 1]

[material]
young = 2e8
poisson = 0.0

[shell]
thickness = 0.05

[[fix]]
group = "s0"
dofs = ["ux", "uz"]

[[fix]]
group = "s1"
dofs = ["uz"]

[[fix]]
group = "all"
dofs = ["uy", "wy"]

[[load]]
group = "s1"
force = [-411.2335167120566, 0.0, 0.0]

[solver]
lambda_end = 1.5

[output]
lambda_step = 0.1
vtk_every = 0
"#;
    let file = crate::scratch::ScratchFile::with_text("pinned-bracket", "c.toml", text);
    let sc = load(&file).unwrap();
    let r = run_loaded(&sc, None, false).unwrap();
    assert_eq!(r.events.len(), 1, "{:?}", r.events);
    let e = &r.events[0];
    println!(
        "lambda {:.12}, bracket {:.1e}, kappa {:?}, {} factorizations",
        e.lambda, e.bracket, e.kappa, e.factorizations
    );
    assert!((e.lambda - 1.0).abs() < 1e-3, "{}", e.lambda);
    assert!(
        e.bracket > 0.0 && e.bracket <= 1e-9 * e.lambda,
        "{}",
        e.bracket
    );
}

/// Review 5: Newton runs over the clamped arch's snap-through. Under load
/// control the increment over the limit point jumped to the far branch
/// (27 times the displacement rate of the increment before) with no word;
/// under arclength control the path turned back while history.csv kept
/// each lambda once. Both are now noted.
#[test]
fn newton_runs_note_a_jump_and_a_turning_back() {
    let path = format!(
        "{}/scenes/verification/clamped-arch-snap.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let base = std::fs::read_to_string(path)
        .unwrap()
        .replace("order = 20\neps = 1e-8", "method = \"newton\"")
        .replace("snapshots = [0.45]", "");
    for (control, needle) in [
        (
            "\nnewton_control = \"load\"",
            "a jump, as past a limit point",
        ),
        ("", "the path turns back at lambda"),
    ] {
        let text = base.replace(
            "method = \"newton\"",
            &format!("method = \"newton\"{control}"),
        );
        let file = crate::scratch::ScratchFile::with_text("newton-snap", "a.toml", &text);
        let r = run_loaded(&load(&file).unwrap(), None, false).unwrap();
        println!("{:?}", r.notes);
        assert_eq!(r.stop.reason, "end");
        assert!(r.notes.iter().any(|n| n.contains(needle)), "{:?}", r.notes);
    }
}

/// The LU gives no inertia (review 9): on the Euler column (bifurcation at
/// λ = 1.000967 with LDLᵀ, closed form 1) `linear_solver = "lu"` sees no
/// event, and the run now says why in its notes; a secondary branch and the
/// stability monitor in time, which need the inertia, refuse it up front.
#[test]
fn the_lu_backend_names_the_critical_points_it_cannot_see() {
    let root = format!("{}/scenes/verification", env!("CARGO_MANIFEST_DIR"));
    let with_lu = |name: &str| {
        let text = std::fs::read_to_string(format!("{root}/{name}.toml")).unwrap();
        assert!(text.contains("[solver]"));
        let file = crate::scratch::ScratchFile::with_text(
            "lu-inertia",
            &format!("{name}.toml"),
            &text
                .replace("../../meshes/", &format!("{root}/../../meshes/"))
                .replacen("[solver]", "[solver]\nlinear_solver = \"lu\"", 1),
        );
        (load(&file), file)
    };
    let (sc, _file) = with_lu("euler-column");
    let r = run_loaded(&sc.unwrap(), None, false).unwrap();
    let ldlt = run_loaded(&scene("euler-column"), None, false).unwrap();
    assert_eq!(ldlt.events.len(), 1, "{:?}", ldlt.events);
    assert!(r.events.is_empty(), "{:?}", r.events);
    assert!(r.stats.linear.symmetric_without_inertia >= 1);
    assert!(
        r.notes.iter().any(|n| n.contains("no inertia")),
        "{:?}",
        r.notes
    );
    for (name, key) in [
        ("euler-column-secondary", "solver.branch"),
        ("euler-column-in-time", "friction.stability"),
    ] {
        let (sc, _file) = with_lu(name);
        let e = sc.expect_err(name).to_string();
        assert!(e.contains(key) && e.contains("inertia"), "{name}: {e}");
    }
}

/// The primary path of a pinned shallow arch (tests/data/pinned-arch.toml,
/// review 14) stays symmetric through both its bifurcations. Near the
/// second one, at lambda = −0.382, the steps used to shrink toward the
/// point until the antisymmetric part of the series, seeded by round-off,
/// took the path onto the asymmetric branch: it went round that loop back
/// to the unloaded state and on to lambda = −2540 (max_steps; on 800
/// elements round the loop and on to the end, with 5 rows at lambda = 0.5
/// instead of 3). The step now follows its series with the geometric part
/// removed where that part does not move the load (Cochelin & Medale
/// 2013). Shallow-arch theory: bifurcations at 1 and −0.3820, limit points
/// at 1.2062 and −0.5882 (20 elements: within 1.5 %).
#[test]
fn an_arch_s_primary_path_stays_symmetric_through_its_bifurcations() {
    let path = format!("{}/tests/data/pinned-arch.toml", env!("CARGO_MANIFEST_DIR"));
    let r = run_loaded(&load(std::path::Path::new(&path)).unwrap(), None, false).unwrap();
    assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
    let col = |name: &str| r.columns.iter().position(|h| h == name).unwrap();
    let (q1, q3) = (col("uz_q1"), col("uz_q3"));
    let scale = r
        .history
        .iter()
        .map(|row| row[q1].abs())
        .fold(0.0, f64::max);
    let asym = r
        .history
        .iter()
        .map(|row| (row[q1] - row[q3]).abs())
        .fold(0.0, f64::max);
    let at_half = r
        .history
        .iter()
        .filter(|row| (row[0] - 0.5).abs() < 1e-9)
        .count();
    println!(
        "largest |uz_q1 − uz_q3| = {asym:.2e} of {scale:.3e}; rows at lambda = 0.5: {at_half}"
    );
    assert!(asym <= 1e-6 * scale, "{asym:e}");
    assert_eq!(at_half, 3);
    let located = |kind: &str| -> Vec<f64> {
        r.events
            .iter()
            .filter(|e| e.kind == kind)
            .map(|e| e.lambda)
            .collect()
    };
    let (bif, lim) = (located("bifurcation"), located("limit_point"));
    println!("bifurcations {bif:?}, limit points {lim:?}");
    let near = |got: &[f64], want: f64| got.iter().any(|l| (l - want).abs() <= 0.015 * want.abs());
    assert_eq!(bif.len(), 2, "{bif:?}");
    assert!(near(&bif, 1.0) && near(&bif, -0.3820), "{bif:?}");
    assert_eq!(lim.len(), 2, "{lim:?}");
    assert!(near(&lim, 1.2062) && near(&lim, -0.5882), "{lim:?}");
}

/// `anm buckle --locate` on a limit point (review 14): load-controlled
/// Newton cannot pass it, and says so with the increment that brackets it
/// (exit 2), beside the ANM's location. It used to fail with a bare "no
/// convergence" or to report "no critical point up to lambda_end" (an
/// increment that jumped onto the snapped branch), hiding the ANM's row.
#[test]
fn locate_says_that_load_control_cannot_pass_a_limit_point() {
    let scene = format!(
        "{}/scenes/verification/clamped-arch-snap.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_anm"))
        .args(["buckle", &scene, "--locate", "0.1"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let anm_row = text
        .lines()
        .find(|l| l.starts_with("| ANM"))
        .expect("the ANM's row");
    let located: f64 = anm_row.split('|').nth(2).unwrap().trim().parse().unwrap();
    // The arch's limit point (arch_limit_points_are_told_apart_...).
    assert!((located - 0.5016).abs() < 1e-3, "{located}");
    assert!(text.contains("a limit point lies between them"), "{text}");
    assert!(text.contains("lambda = 0.500000 to 0.600000"), "{text}");
}

/// `anm buckle` about a loaded state warns of modes with mu < 0 (review
/// 14: a "lambda_critical" of 0.2246 below a base state of 0.9 that the
/// path passed stable, without a word): the clamped arch about lambda =
/// 0.45 has one among its first four.
#[test]
fn buckle_warns_of_negative_mu() {
    let sc = scene("clamped-arch-snap");
    let b = buckle(&sc, Base::Lambda(0.45), 4, None).expect("buckle");
    print!("{}", anm::study::buckle::table(&b));
    let negative: Vec<usize> = b
        .modes
        .iter()
        .filter(|m| m.mu < 0.0)
        .map(|m| m.index)
        .collect();
    assert!(
        !negative.is_empty(),
        "no mu < 0 here any more: {:?}",
        b.modes
    );
    assert!(
        b.warnings
            .iter()
            .any(|w| w.contains("mu < 0") && w.contains(&negative[0].to_string())),
        "{:?}",
        b.warnings
    );
}

/// Review 25: a compression that rises past the critical load and falls
/// back between two outputs (1.05 N_cr at t = 0.5 s, outputs at 0.4 and
/// 0.6 s both at 0.84 N_cr, the same inertia) gave no event. The state at
/// the ramps' kink between them is now checked, and the crossing located:
/// P(t) = 1.05 N_cr t / 0.5 must lie within the element's error above
/// Kirchhoff's N_cr (plate-buckling.toml's mesh is 16 × 16 and +0.3 %;
/// this 12 × 12 one, under 2 %).
#[test]
fn a_critical_load_passed_between_two_outputs_is_found_at_the_kink() {
    let path = format!(
        "{}/tests/data/plate-compressed-up-and-down.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let sc = anm::scene::shell::load(std::path::Path::new(&path)).expect("scene");
    let r = anm::run::shell_time::run(&sc, None).expect("run in time");
    assert_eq!(r.events.len(), 1, "one critical point: {:?}", r.events);
    let e = &r.events[0];
    let p = 1.05 * e.t / 0.5;
    println!(
        "{}: t = {:.9} s, P = {p:.6} N_cr, bracket {:?}, {} restarts",
        e.detected_by, e.t, e.bracket, e.restarts
    );
    assert_eq!(e.detected_by, "negative pivots at a load kink");
    assert_eq!(e.negative_pivots, [0, 1]);
    assert!(
        (e.outputs[0] - 0.4).abs() < 1e-12 && (e.outputs[1] - 0.6).abs() < 1e-12,
        "{:?}",
        e.outputs
    );
    assert!(e.bracket[1] - e.bracket[0] <= 1e-7 * e.t, "{:?}", e.bracket);
    assert!(p > 1.0 && p < 1.02, "P / N_cr = {p}");
    // `anm buckle --time` cannot buckle along loads with their own ramps
    // (not in its load pattern): refused, naming the key (review 25: no
    // mode found, the load called tension).
    let err = buckle(&sc, Base::Time(0.5), 1, None).expect_err("refused");
    assert!(err.to_string().contains("load[0].ramp"), "{err}");
    // Its unpressed nodes hold f zeta at most: the sticking note's share
    // of the capacity was 6.2e306 (f R_N = 0 in the denominator).
    for n in r
        .notes
        .iter()
        .filter(|n| n.contains("of the law's capacity"))
    {
        let share: f64 = n
            .split(" of the law's capacity")
            .next()
            .and_then(|x| x.split_whitespace().last())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("a share in: {n}"));
        println!("sticking note: share {share}");
        assert!(share <= 1.0 + 1e-9, "{n}");
    }
}

/// Review 25: a column pushed on a frictional wall is critical at P_c
/// under the regularized law (the static tangent: the tip slides across
/// the wall) and at 8.18 P_c under Coulomb friction (the tied tangent:
/// clamped–pinned, Timoshenko & Gere). `anm buckle --time 0.5` (5 P_c)
/// buckles the tied tangent (lambda_cr ≈ 0.825, 8.25 P_c) and now warns
/// that the static one has a negative pivot already.
#[test]
fn buckle_in_time_warns_when_the_static_tangent_is_past_critical() {
    let sc = load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/column-pushed-on-a-wall.toml"
    )))
    .expect("scene");
    let b = buckle(&sc, Base::Time(0.5), 1, None).expect("buckle about t = 0.5");
    let p = 10.0 * b.modes[0].lambda_critical;
    println!(
        "tied onset {p:.4} P_c (clamped-pinned 8.1830); warnings {:?}",
        b.warnings
    );
    assert!((p / 8.1830 - 1.0).abs() < 0.02, "{p}");
    assert!(
        b.warnings
            .iter()
            .any(|w| w.starts_with("the static tangent of this base state")),
        "{:?}",
        b.warnings
    );
    // At t = 0.05 (0.5 P_c) the static tangent is still stable: no word.
    let early = buckle(&sc, Base::Time(0.05), 1, None).expect("buckle about t = 0.05");
    assert!(
        early
            .warnings
            .iter()
            .all(|w| !w.starts_with("the static tangent")),
        "{:?}",
        early.warnings
    );
}

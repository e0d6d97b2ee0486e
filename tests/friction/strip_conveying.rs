//! Issue 10 item 4: scenes/strip-conveying.toml (a strip over three
//! rollers, the middle one 0.5% fast) on a coarser mesh, at steady state,
//! against closed forms:
//! - roller 2 slips on its whole arc and drags the strip forward, so the
//!   tension falls across it as T_in exp(−f g φ) (Euler–Eytelwein, g the
//!   regularization's factor V / |V|_reg, φ the angle from its entry): the
//!   exit reaction is T_in exp(−f g θ_2);
//! - rollers 1 and 3 turn with the strip: at rest the regularized law
//!   carries no friction, so their two sides carry the same tension and
//!   their nodes stick.

use anm::run::along_strip::AlongRow;
use anm::run::{along_strip, shell_time};
use anm::scene::shell::load;
use anm::shell::friction_dae::FrictionDae;
use anm::shell::time_path::{TimeSample, TimeStop};
use std::f64::consts::FRAC_PI_2;

/// The conveying scene with 0.1 m elements on the spans, 0.03 m on the arcs
/// and 2 across the width.
fn coarse_conveying() -> anm::scene::shell::ShellScene {
    let text = std::fs::read_to_string("scenes/strip-conveying.toml").expect("scene");
    let text = text
        .replace("element_length = 0.05", "element_length = 0.1")
        .replace("arc_element_length = 0.01", "arc_element_length = 0.03")
        .replace("divisions_across = 8", "divisions_across = 2");
    // One directory per call: the tests run in parallel, and one writing
    // the file while another loads it would hand the other a partial scene.
    let path =
        crate::scratch::ScratchFile::with_text("conveying", "strip-conveying-coarse.toml", &text);
    load(&path).expect("scene loads")
}

/// The cross-section rows along the strip at the run's last sample (slip
/// counted above `threshold`) and the rows of roller 2's entry and exit.
fn roller_two_rows(
    sc: &anm::scene::shell::ShellScene,
    dae: &FrictionDae,
    end: &TimeSample,
    threshold: f64,
) -> (Vec<AlongRow>, usize, usize) {
    let grid = sc.mesh.grid.expect("a built-in mesh");
    let rows = along_strip::rows(
        &dae.model,
        &grid,
        &sc.mesh.quads,
        sc.thickness,
        &end.full,
        &end.friction,
        threshold,
    );
    let row_of = |group: &str| grid.row_of(&sc.mesh.groups[group]).expect("a row");
    (rows, row_of("r2_in"), row_of("r2_out"))
}

/// The slip speeds of the friction nodes on roller `name`'s arc.
fn arc_slips(sc: &anm::scene::shell::ShellScene, end: &TimeSample, name: &str) -> Vec<f64> {
    let nodes = &sc.mesh.groups[&format!("{name}_arc")];
    end.friction
        .iter()
        .filter(|f| nodes.binary_search(&f.node).is_ok())
        .map(|f| f.slip.norm())
        .collect()
}

#[test]
fn conveying_strip_reaches_the_euler_eytelwein_steady_state() {
    let sc = coarse_conveying();
    let law = sc.friction.as_ref().expect("friction").law;
    let (t_in, v) = (5000.0, 0.01);
    let g = v / (v * v + (law.omega * law.vc).powi(2)).sqrt();
    let report = shell_time::run(&sc, None).expect("runs to t_end");
    assert_eq!(report.stop, "end");
    let col = |name: &str| report.header.iter().position(|h| h == name).expect(name);
    let last = report.history.last().expect("rows");
    let before = &report.history[report.history.len() - 6];
    let exit = last[col("exit_reaction_y")];
    let closed = t_in * (-law.f * g * FRAC_PI_2).exp();
    let rel = exit / closed - 1.0;
    let drift = (exit - before[col("exit_reaction_y")]).abs() / exit;
    println!(
        "steps {} ({} factorizations); exit tension {exit:.3} N vs T_in exp(−f g θ2) = {closed:.3} N ({rel:.1e}); change over the last 0.1 s {drift:.1e}",
        report.steps, report.factorizations
    );
    assert!(rel.abs() < 1e-2, "exit {exit} vs {closed}");
    // The section force across the held edge is its support reaction (the
    // element forces there against the residual at the fixed dofs).
    let section = last[col("T_exit")];
    println!("tension across the exit edge {section:.6} N, its reaction {exit:.6} N");
    assert!((section - exit).abs() < 1e-6 * exit, "{section} vs {exit}");
    assert!(drift < 1e-4, "not steady: {drift}");
    for r in ["r1", "r3"] {
        let (a, b) = (
            last[col(&format!("T_{r}_in"))],
            last[col(&format!("T_{r}_out"))],
        );
        println!("{r}: in {a:.3} N, out {b:.3} N ({:.1e})", (a - b) / a);
        assert!((a - b).abs() < 1e-3 * a, "{r}: {a} vs {b}");
    }
    // Roller 2's free spans (`side` probes at its tangent rows): the entry
    // span carries T_in, the exit span T_in exp(−f g θ2); the cuts that
    // average the span with the first arc element read between the two.
    let (span_in, span_out) = (last[col("T_r2_in_span")], last[col("T_r2_out_span")]);
    let (mean_in, mean_out) = (last[col("T_r2_in")], last[col("T_r2_out")]);
    let ratio = span_out / span_in;
    let closed_ratio = (-law.f * g * FRAC_PI_2).exp();
    println!(
        "roller 2 spans: in {span_in:.4} N ({:.1e} from T_in), out {span_out:.4} N; ratio {ratio:.6} vs exp(−f g θ2) = {closed_ratio:.6} ({:.1e}); two-sided cuts: in {mean_in:.4} N, out {mean_out:.4} N, ratio {:.6} ({:.1e})",
        span_in / t_in - 1.0,
        ratio / closed_ratio - 1.0,
        mean_out / mean_in,
        mean_out / mean_in / closed_ratio - 1.0
    );
    assert!((span_in / t_in - 1.0).abs() < 1e-3, "{span_in}");
    assert!((ratio / closed_ratio - 1.0).abs() < 2e-3, "{ratio}");

    // The tension along roller 2's arc and the slip map.
    let (run, dae) = shell_time::solve(&sc).expect("runs");
    let end = run.samples.last().expect("samples");
    let threshold = 10.0 * law.omega * law.vc;
    let (rows, j_in, j_out) = roller_two_rows(&sc, &dae, end, threshold);
    let radius = 0.30000001;
    let mut worst = 0.0f64;
    for j in j_in + 1..j_out {
        let phi = (rows[j].s - rows[j_in].s) / radius;
        let closed = t_in * (-law.f * g * phi).exp();
        worst = worst.max((rows[j].tension / closed - 1.0).abs());
    }
    println!("tension on roller 2's arc against T_in exp(−f g φ): largest deviation {worst:.1e}");
    assert!(worst < 2e-3, "{worst}");
    let on = |name: &str| arc_slips(&sc, end, name);
    let r2 = on("r2");
    let slowest = r2.iter().copied().fold(f64::INFINITY, f64::min);
    println!(
        "roller 2: {} nodes, slowest slip {slowest:.6} m/s (surface 0.01 m/s relative)",
        r2.len()
    );
    assert!(!r2.is_empty() && slowest > 0.99 * v, "{slowest}");
    for r in ["r1", "r3"] {
        let fastest = on(r).iter().copied().fold(0.0, f64::max);
        println!("{r}: fastest slip {fastest:.2e} m/s (stick below {threshold:.0e})");
        assert!(fastest < threshold, "{r}: {fastest}");
    }
}

/// Issue 13 item 4 on the conveying strip: ζ = 1e-4 N (a hundredth of the
/// scene's) runs to t_end within 3× the steps of the scene's ζ, and the
/// exit tension does not move (the audit's "answers stop moving").
#[test]
fn conveying_strip_runs_at_a_small_zeta() {
    let base = coarse_conveying();
    let mut small = coarse_conveying();
    small.friction.as_mut().expect("friction").law.zeta = Some(1e-4);
    let a = shell_time::run(&base, None).expect("runs at the scene's zeta");
    let b = shell_time::run(&small, None).expect("runs at zeta = 1e-4 N");
    let exit = |r: &shell_time::TimeReport| r.end["T_exit"];
    let moved = (exit(&b) - exit(&a)).abs() / exit(&a);
    println!(
        "zeta 1e-2 N: {} steps, {} factorizations; zeta 1e-4 N: {} steps, {} factorizations; exit tension moves by {moved:.1e}",
        a.steps, a.factorizations, b.steps, b.factorizations
    );
    assert!(b.steps <= 3 * a.steps, "{} vs {}", b.steps, a.steps);
    assert!(moved < 1e-6, "{moved}");
}

/// The coarse conveying scene at (ζ, ω).
fn coarse_conveying_at(zeta: f64, omega: f64) -> anm::scene::shell::ShellScene {
    let mut sc = coarse_conveying();
    let law = &mut sc.friction.as_mut().expect("friction").law;
    (law.zeta, law.omega) = (Some(zeta), omega);
    sc
}

/// Runs the scene to t_end within 3× the steps at ζ = ω = 0.1 (issue 13
/// item 4's measure), and checks roller 2, in full slip, against
/// Euler–Eytelwein from its own entry span (the friction the load ramp
/// locks into rollers 1 and 3 creeps away slowly at small ω, so that entry
/// tension is not the line's 5,000 N): span to span within 1e-3, along
/// the arc within 2e-3, every node slipping at the roller's 0.01 m/s.
fn runs_with_roller_two_in_full_slip(sc: &anm::scene::shell::ShellScene) {
    let a = shell_time::run(&coarse_conveying_at(0.1, 0.1), None).expect("runs at 0.1");
    let (run, dae) = shell_time::solve(sc).expect("runs to t_end");
    let b = &run.stats;
    let law = sc.friction.as_ref().expect("friction").law;
    println!(
        "zeta = omega = 0.1: {} steps, {} factorizations; zeta = {:e} N, omega = {:e}: {} steps ({} by backward Euler, {} rejected), {} factorizations",
        a.steps,
        a.factorizations,
        law.zeta.unwrap_or(0.0),
        law.omega,
        b.steps,
        b.newton,
        b.rejected,
        b.factorizations
    );
    assert!(matches!(run.stop, TimeStop::End), "{:?}", run.stop);
    assert!(b.steps <= 3 * a.steps, "{} vs {}", b.steps, a.steps);

    let v = 0.01;
    let g = v / (v * v + (law.omega * law.vc).powi(2)).sqrt();
    let end = run.samples.last().expect("samples");
    let (rows, j_in, j_out) = roller_two_rows(sc, &dae, end, 10.0 * law.omega * law.vc);
    let radius = 0.30000001;
    // Across the roller, span to span: T_out = T_in exp(−f g θ_2), θ_2 = π/2.
    let (span_in, span_out) = (rows[j_in - 1].tension, rows[j_out + 1].tension);
    let across = span_out / (span_in * (-law.f * g * FRAC_PI_2).exp()) - 1.0;
    // Along the arc, from its first row (the entry row j_in, at the tangent
    // point, carries part of the first node's friction).
    let (t_first, phi_first) = (rows[j_in + 1].tension, rows[j_in + 1].s / radius);
    let mut worst = 0.0f64;
    for row in &rows[j_in + 2..j_out] {
        let closed = t_first * (-law.f * g * (row.s / radius - phi_first)).exp();
        worst = worst.max((row.tension / closed - 1.0).abs());
    }
    println!(
        "roller 2: spans {span_in:.3} N in, {span_out:.3} N out, against T_in exp(−f g θ2): {across:.1e}; along the arc from its first row: largest deviation {worst:.1e}; exit tension {:.3} N",
        rows[rows.len() - 1].tension
    );
    assert!(across.abs() < 1e-3, "{across}");
    assert!(worst < 2e-3, "{worst}");
    let slowest = arc_slips(sc, end, "r2")
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    println!("roller 2: slowest slip {slowest:.6} m/s");
    assert!(slowest > 0.99 * v, "{slowest}");
}

/// Issue 13 item 4 on the conveying strip: ζ = 1e-4 N and ω = 1e-4
/// together. The Rosenbrock stages alone collapsed at t = 3.1e-8 s (a
/// friction node loaded 6.3 times beyond its cap); backward Euler solved by
/// Newton takes the steps where they fail.
#[test]
fn conveying_strip_runs_at_small_zeta_and_omega() {
    runs_with_roller_two_in_full_slip(&coarse_conveying_at(1e-4, 1e-4));
}

/// ω = 1e-5 (ω Vc = 1e-7 m/s): backward Euler's Newton reaches it only with
/// each node's slip taken through the law's inverse (without, its line
/// search stalled at α ≈ 1e-6, t = 6.1e-6 s).
#[test]
fn conveying_strip_runs_at_omega_1e_5() {
    runs_with_roller_two_in_full_slip(&coarse_conveying_at(1e-2, 1e-5));
}

/// Loads full at t = 0 on a shell that starts at rest: when the state at
/// rest cannot be brought to equilibrium under them, the error names
/// `friction.load_ramp` (it was a bare "step 0, t = 0: no convergence"),
/// from a run and from `anm check`.
#[test]
fn loads_full_at_rest_name_the_load_ramp() {
    let text = std::fs::read_to_string("scenes/strip-conveying.toml")
        .expect("scene")
        .replace("element_length = 0.05", "element_length = 0.1")
        .replace("arc_element_length = 0.01", "arc_element_length = 0.03")
        .replace("divisions_across = 8", "divisions_across = 2")
        .replace("load_ramp = [0.0, 0.2]\n", "");
    let path = crate::scratch::ScratchFile::with_text("conveying", "at-rest.toml", &text);
    let sc = load(&path).expect("scene loads");
    let e = match shell_time::solve(&sc) {
        Ok(_) => panic!("expected the start at rest to fail"),
        Err(e) => e,
    };
    let msg = e.to_string();
    println!("{msg}");
    assert_eq!(e.kind(), "invalid_input", "{msg}");
    for part in [
        "at-rest.toml",
        "friction.load_ramp",
        "load_ramp = [0, 0.15]",
    ] {
        assert!(msg.contains(part), "`{msg}` lacks `{part}`");
    }
    // `anm check` tries step 0 and gives the same diagnosis.
    let checked = shell_time::check_start(&sc).expect_err("step 0 fails in the check too");
    assert_eq!(checked.to_string(), msg);
}

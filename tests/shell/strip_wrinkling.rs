//! Wrinkling of a strip under tension over a crowned roll (issue 14, item
//! 6b): scenes/strip-wrinkling.toml on a coarser mesh (20 elements across,
//! 0.1 m along the spans, 0.05 m on the arc), frictionless.
//!
//! Checked: the prebuckling state against the closed form of a
//! frictionless wrap (the tension is the same on both sides of the roll
//! and equals the applied line tension: capstan with f = 0), the critical
//! point located on the path (negative pivots 0 -> 1, a bifurcation, in
//! the span before the roll), and its location against linearized
//! buckling (`anm buckle`) about the path's state just before it.

use crate::scratch::ScratchFile;
use anm::run::shell::run_loaded;
use anm::scene::shell::load;
use anm::study::buckle::{Base, buckle};

/// The coarse scene, loaded from a temporary file that is gone once it
/// returns (a loaded scene runs without its file).
fn coarse(lambda_end: f64) -> anm::scene::shell::ShellScene {
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/scenes/strip-wrinkling.toml")).unwrap();
    let text = text
        .replace("divisions_across = 40", "divisions_across = 20")
        .replace("element_length = 0.05", "element_length = 0.1")
        .replace("arc_element_length = 0.025", "arc_element_length = 0.05")
        .replace("lambda_end = 1.5", &format!("lambda_end = {lambda_end}"));
    let p = ScratchFile::with_text(
        "strip-wrinkling",
        &format!("coarse-{lambda_end}.toml"),
        &text,
    );
    load(&p).expect("scene")
}

#[test]
fn strip_over_a_crowned_roll_wrinkles_in_the_span_before_it() {
    let sc = coarse(1.5);
    let r = run_loaded(&sc, None, false).expect("run");
    assert_eq!(r.stop.reason, "end");
    // Frictionless wrap: T_in = T_out = 200 N/m x 1 m x lambda.
    let applied = 200.0 * 1.5;
    let (t_in, t_out) = (r.end["T_in"], r.end["T_out"]);
    println!("lambda = 1.5: T_in = {t_in:.4} N, T_out = {t_out:.4} N, applied {applied} N");
    assert!((t_in / applied - 1.0).abs() < 2e-3, "T_in {t_in}");
    assert!((t_out / applied - 1.0).abs() < 2e-3, "T_out {t_out}");
    assert!((t_in - t_out).abs() < 1e-3 * applied);

    for e in &r.events {
        println!("  event: {} at {:.9} (step {})", e.kind, e.lambda, e.step);
    }
    // The onset: located on a step's series where the path crosses it
    // (negative pivots 0 -> 1), or, where the path leaves along the
    // stable bifurcated branch without crossing, the geometric test's
    // estimate, which successive steps must repeat.
    let located = r.events.iter().find(|e| e.kind != "geometric");
    let geometric: Vec<f64> = r
        .events
        .iter()
        .filter(|e| e.kind == "geometric")
        .map(|e| e.lambda)
        .collect();
    let onset = match located {
        Some(e) => {
            println!(
                "located: {} at lambda = {:.9} MPa (step {}, pivots {:?}, bracket {:.1e}, {} factorizations), {:?} half-waves along {:?}",
                e.kind,
                e.lambda,
                e.step,
                e.negative_pivots,
                e.bracket,
                e.factorizations,
                e.half_waves,
                e.wave_direction
            );
            assert_eq!(e.kind, "bifurcation");
            assert_eq!(e.negative_pivots, Some((0, 1)));
            assert!(e.bracket <= 1e-6 * e.lambda, "{}", e.bracket);
            // The wrinkles' pitch across the width (x; the path runs in
            // y, z): review 13 found 6.81 "half-waves" along the 3.63 m
            // path, the length of the mode's lobe, where the mode has ~3
            // across (its own Rayleigh quotient across x: 3.05).
            assert_eq!(e.wave_direction.as_deref(), Some("x"));
            let waves = e.half_waves.expect("a wavelength");
            assert!((2.5..3.5).contains(&waves), "{waves} half-waves");
            e.lambda
        }
        None => {
            assert!(geometric.len() >= 3, "{:?}", r.events);
            geometric[0]
        }
    };
    for g in &geometric {
        assert!((g / onset - 1.0).abs() < 1e-6, "geometric {g} vs {onset}");
    }
    // Measured 1.1728 on this mesh (1.0757 on the scene's).
    assert!(onset > 0.9 && onset < 1.4, "{onset}");

    // Linearized buckling about the path's states just before the point:
    // its lowest positive mu predicts the onset, the closer the better
    // (the prebuckling state is nonlinear through the contact, so the
    // prediction is not exact at any finite distance).
    let mut errors = vec![];
    for gap in [1e-3, 1e-4] {
        let lb = (1.0 - gap) * onset;
        let b = buckle(&coarse(1.5), Base::Lambda(lb), 4, None).expect("buckle");
        let m = b
            .modes
            .iter()
            .filter(|m| m.mu > 0.0)
            .min_by(|a, c| a.mu.total_cmp(&c.mu))
            .expect("a positive mu");
        let rel = (m.lambda_critical - onset).abs() / onset;
        println!(
            "buckle about {lb:.7}: mode {} lambda_cr = {:.9} ({rel:.2e} from the onset; mu off by {:.1} %); warnings {:?}",
            m.index,
            m.lambda_critical,
            100.0 * rel * onset / (onset - lb),
            b.warnings
        );
        for m in &b.modes {
            println!(
                "  mode {}: mu = {:.6e}, wrinkles {:?}",
                m.index, m.mu, m.wrinkles
            );
        }
        errors.push(rel);
    }
    assert!(errors[0] < 2e-4, "{errors:?}");
    assert!(errors[1] < errors[0] / 5.0, "{errors:?}");
}

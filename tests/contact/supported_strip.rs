//! A simply supported strip under a uniform load over a rigid plane
//! (tests/data/supported-strip-on-plane.toml, review 15) against
//! Euler–Bernoulli: for lambda > 5 the strip lies flat on [a, L − a],
//! a = (24 EI g / q)^(1/4), the plane carries q (L − a) and the supports
//! q a in all. The support reaction of the equilibrium check
//! (`shell_check`, the audit's "support" column) counts the load that acts
//! on the supported nodes: with the internal forces alone there it missed
//! that share, q dx / 2 per node, and showed an imbalance of 1.2e-2.

use anm::run::run_loaded;
use anm::study::shell_check::{check, with_grid_snapshots};

#[test]
fn the_supports_carry_their_share_of_a_load_over_a_supported_edge() {
    let path = format!(
        "{}/tests/data/supported-strip-on-plane.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = anm::scene::shell::load(std::path::Path::new(&path)).expect("scene");
    let scene = with_grid_snapshots(&scene);
    let r = run_loaded(&scene, None, false).expect("runs");
    assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
    let (l, b, t, e, g): (f64, f64, f64, f64, f64) = (1.0, 0.1, 0.01, 2e9, 1e-3);
    let ei = e * b * t * t * t / 12.0;
    let q = 20.0 * 384.0 * ei * g / (5.0 * l * l * l * l);
    let a = (24.0 * ei * g / q).powf(0.25);
    let c = check(&scene, &r).expect("check");
    let support = c.clamp_force.expect("at lambda_end")[2];
    let contact = c.contact_force.expect("at lambda_end")[2];
    let balance = c.balance.expect("at lambda_end");
    println!(
        "q = {q} N/m, a = {a:.6} m: contact {contact:.6} N (closed form {:.6}), supports {support:.6} N ({:.6}), |P + C + S| / |P| = {balance:.1e}",
        q * (l - a),
        q * a
    );
    assert!(
        (support - q * a).abs() <= 1e-3 * q * a,
        "{support} vs {}",
        q * a
    );
    assert!(
        (contact - q * (l - a)).abs() <= 1e-3 * q * l,
        "{contact} vs {}",
        q * (l - a)
    );
    assert!(balance <= 1e-8, "{balance:e}");
}

/// A penalty soft enough to change the answer is noted even where the
/// nodes sink by less than 1 % of the model (review 15: K = 10 N/m sank a
/// cantilever's tip 6.2 times its gap, 86 % of its deflection, contact
/// force −23 %, with no word): the note now also reads the depth against
/// the largest displacement. K = 100 N/m here: ~2e-3 m, 0.2 % of the strip.
#[test]
fn a_penalty_that_carries_the_deflection_is_noted() {
    let path = format!(
        "{}/tests/data/supported-strip-on-plane.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("k = 1e9", "k = 100.0");
    assert!(text.contains("k = 100.0"));
    let f = crate::scratch::ScratchFile::with_text("soft-penalty", "scene.toml", &text);
    let r = run_loaded(&anm::scene::shell::load(&f).unwrap(), None, false).expect("runs");
    println!("{:?}", r.notes);
    let note = r
        .notes
        .iter()
        .find(|n| n.contains("contact.k"))
        .expect("a contact.k note");
    assert!(note.contains("of its largest displacement"), "{note}");
    // The scene's own K carries no such note.
    let stiff = run_loaded(
        &anm::scene::shell::load(std::path::Path::new(&path)).unwrap(),
        None,
        false,
    )
    .expect("runs");
    assert!(
        !stiff.notes.iter().any(|n| n.contains("contact.k")),
        "{:?}",
        stiff.notes
    );
}

/// A cantilever under a uniform load settling flat onto a plane under the
/// penalty law (tests/data/cantilever-on-plane-penalty.toml, review 15).
/// Its step ends sit at the residual's round-off floor (3.2e-5 against
/// residual_tol 1e-6). Where the flat zone starts to spread (lambda = 9)
/// the correction crossed a kink and stalled at 1.6e-5, not a round-off
/// update, and the run stopped there; a stall no higher than the floor the
/// run has already accepted is now accepted too. Euler–Bernoulli at
/// lambda = 50: R = q (L − 2a/3), a = (72 EI g / q)^(1/4).
#[test]
fn a_cantilever_settles_flat_on_a_plane_under_the_penalty_law() {
    let path = format!(
        "{}/tests/data/cantilever-on-plane-penalty.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let r = run_loaded(
        &anm::scene::shell::load(std::path::Path::new(&path)).unwrap(),
        None,
        false,
    )
    .expect("runs");
    assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
    let (l, b, t, e, g): (f64, f64, f64, f64, f64) = (1.0, 0.1, 0.01, 2e9, 1e-3);
    let ei = e * b * t * t * t / 12.0;
    let q = 50.0 * 8.0 * ei * g / l.powi(4);
    let a = (72.0 * ei * g / q).powf(0.25);
    let closed = q * (l - 2.0 * a / 3.0);
    let got = r.end["R"];
    println!(
        "{} steps: R(50) = {got:.6} N, Euler–Bernoulli {closed:.6} N ({:.1e}); round-off stops {}, largest {:.2e}",
        r.steps,
        (got - closed) / closed,
        r.stats.round_off_stops,
        r.stats.round_off_residual
    );
    assert!((got - closed).abs() <= 1e-4 * closed, "{got} vs {closed}");
}

/// Review 19: a cantilever's tip pushed onto a plane under the penalty law
/// (contact.eta = 0) with K = 1e9 N/mm took 20,000 steps of 1e-14 at the
/// first touch (λ = 0.4375 = k_b g / P, 75 s) and ended on max_steps with
/// no hint. It now stops within CRAWL_STEPS with a diagnosis that names
/// the penalty law and contact.k, and eta = 1e-6 runs the same scene to
/// the end with the contact force of rigid contact, P − k_b g = 16.875 N.
#[test]
fn a_path_that_stalls_at_a_stiff_penalty_kink_stops_and_names_the_key() {
    let path = format!(
        "{}/tests/data/cantilever-tip-stiff-penalty.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut sc = anm::scene::shell::load(std::path::Path::new(&path)).unwrap();
    let r = run_loaded(&sc, None, false).expect("runs");
    let message = r.stop.message.clone().unwrap_or_default();
    println!("{} steps: {} — {message}", r.steps, r.stop.reason);
    assert_eq!(r.stop.reason, "stalled", "{:?}", r.stop);
    assert!(r.steps < 100, "{}", r.steps);
    assert!((r.stop.lambda.unwrap() - 0.4375).abs() < 1e-3);
    assert!(
        message.contains("contact.eta = 0") && message.contains("contact.k"),
        "{message}"
    );
    sc.contact.as_mut().unwrap().eta = 1e-6;
    let r = run_loaded(&sc, None, false).expect("runs");
    assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
    let (p, kb, g) = (30.0, 2.625, 5.0);
    let rn = r.end["rn_total"];
    println!(
        "eta = 1e-6: {} steps, contact {rn:.6} N against {}",
        r.steps,
        p - kb * g
    );
    assert!((rn - (p - kb * g)).abs() <= 1e-2 * (p - kb * g), "{rn}");
}

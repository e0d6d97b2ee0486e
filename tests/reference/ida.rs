//! Source: SUNDIALS IDA (variable-order BDF, through sundials-sys), solving
//! the paper's regularized friction DAEs (Béchet et al., CFM 2009, §3.2–3.4;
//! DESIGN §4, §5) as written independently in `anm::reference` (plain f64,
//! analytic Jacobians, global Cartesian coordinates), and closed forms.
//!
//! Goals:
//! (a) IDA against closed forms we did not write: friction-plane with q = 0
//!     and small regularizations, u_x = (f/k) F (t - 1) after contact (1%);
//!     friction-1d plateau u = f R_N / k (1 + omega^2)^((q-1)/2) (1e-8); the
//!     roller's Cartesian index-1 form against the plane in the large-radius
//!     limit.
//! (b) The ANM (`anm::model::friction_run::run`) against IDA at rtol 1e-10 on
//!     the three scenes in scenes/: max |y_anm - y_ida| / max |y_ida| per
//!     column <= 1e-6 (friction-roller: up to 0.05 s before the ANM's stop).
//! (c) friction-roller: the ANM's stop time lies within the window where
//!     IDA's |slip speed| rises from Vc to 10 Vc.
//! (d) Issue 16 (IDA at its best; diffsol as a second solver), on the grid
//!     zeta in {1e-1, 1e-2, 1e-4, 1e-6} N x omega in {1e-1, 1e-4, 1e-6} of
//!     friction-plane and friction-roller (friction-1d: omega only, its R_N
//!     is given): IDA with the set-up of `anm reference ida` and diffsol BDF
//!     both reach t_end at rtol = atol = 1e-8 in at most 1,500 steps; IDA
//!     and diffsol BDF agree to 1e-7 on the displacements at rtol 1e-10
//!     (roller: up to 0.05 s before IDA's |v_s| reaches Vc); the roller's
//!     surge window of IDA still brackets the ANM's stop at every cell's
//!     default. The errors at rtol 1e-8 against IDA at rtol 1e-12 are printed
//!     (README "Fair baselines").
#![cfg(feature = "reference")]

use anm::model::friction_run::{FrictionRun, run as anm_run};
use anm::reference::diffsol::DiffsolSettings;
use anm::reference::ida_run::solve_model;
use anm::reference::settings::DiffsolMethod;
use anm::reference::{IdaRun, IdaSettings, solve};
use anm::scene::{self, friction::FrictionScene};
use anm::series::dae::Stepping;
use std::path::Path;

const RTOL: f64 = 1e-10;

fn settings(rtol: f64) -> IdaSettings {
    IdaSettings::new(rtol).expect("valid tolerances")
}

fn load(name: &str) -> FrictionScene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"));
    let text = scene::read(&path).expect("scene readable");
    let kind = scene::kind(&path, &text).expect("scene kind");
    scene::friction::load(&path, &text, kind).expect("valid scene")
}

fn ida(scene: &FrictionScene) -> IdaRun {
    let run = solve(scene, &settings(RTOL)).unwrap_or_else(|e| panic!("IDA failed: {e}"));
    for row in &run.history {
        assert!(
            row.iter().all(|v| v.is_finite()),
            "non-finite IDA row {row:?}"
        );
    }
    println!(
        "IDA {} on {}: stop {} at t = {:.9} s; {} steps, {} res, {} jac, {} setups, {:.3} s, max constraint drift {:.2e}",
        run.version,
        run.kind,
        run.stop.reason,
        run.stop.t,
        run.counters.steps,
        run.counters.residual_evaluations,
        run.counters.jacobian_evaluations,
        run.counters.factorizations,
        run.wall_s,
        run.max_constraint_drift
    );
    run
}

fn col(run_cols: &[String], name: &str) -> usize {
    run_cols
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

/// (a) friction-plane, q = 0, omega = zeta = 1e-3, eta = 1e-8, K = 1e8:
/// u_x = (f/k) F (t - 1) within 1% for t in [1.2, 3].
///
/// IDA tolerances here: rtol 1e-6, atol 1e-8. With these regularizations the
/// DAE is extremely ill-conditioned: before contact the slip velocity obeys
/// dv_x/du_x = -k / (f zeta g'(-V)) = -5e9 after the stick-slip transition
/// (t ~ 2e-4 s), and the contact transition at t = 1 s is ~1e-8 s wide. At
/// rtol 1e-10 or 1e-7 IDA's step collapses (t ~ 2e-4 s, t ~ 1 s); at looser
/// tolerances it steps over the contact and its Newton iteration lands on the
/// quadratic contact law's other root (R_N ~ -1e-8, the mass passing through
/// the plane, u_y -> -3). rtol 1e-6 / atol 1e-8 resolves both (about 2.5e5
/// steps with the friction law as written); the branch is checked below.
///
/// Here the algebraic unknowns stay in the error test (atol 1e-8, IDASVtolerances),
/// unlike the default set-up: with them suppressed only u_x is tested, and
/// nothing in the test sees the 1e-8 s wide contact transition (u_y and R_N
/// are algebraic on the plane), so IDA steps over it in 63 steps and lands on
/// the other root (R_N = 1.3e-8 N, u_y = -1.2 m at t = 1.2 s).
#[test]
fn ida_plane_coulomb_closed_form() {
    let mut sc = load("friction-plane");
    sc.friction.q = 0.0;
    sc.friction.omega = 1e-3;
    sc.friction.zeta = Some(1e-3);
    let c = sc.contact.as_mut().expect("contact");
    c.eta = 1e-8;
    c.k = 1e8;
    let mut set = settings(1e-6);
    set.tol.atol = 1e-8;
    set.algebraic = anm::reference::settings::AlgebraicControl::Atol(1e-8);
    let run = solve(&sc, &set).unwrap_or_else(|e| panic!("IDA failed: {e}"));
    println!(
        "IDA on plane q=0: stop {} at t = {:.9}; {} steps, {} res, {} jac, {:.3} s",
        run.stop.reason,
        run.stop.t,
        run.counters.steps,
        run.counters.residual_evaluations,
        run.counters.jacobian_evaluations,
        run.wall_s
    );
    assert_eq!(run.stop.reason, "end", "{:?}", run.stop);
    let (ux, uy, rn) = (
        col(&run.columns, "ux"),
        col(&run.columns, "uy"),
        col(&run.columns, "rn"),
    );
    let (f, k, ff) = (sc.friction.f, sc.k, sc.load_rate);
    let mut worst: (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    for row in run.history.iter().filter(|r| r[0] >= 1.2 - 1e-12) {
        assert!(row.iter().all(|v| v.is_finite()), "{row:?}");
        assert!(
            row[uy] > -1.0 - 1e-6 && row[rn] > 0.0,
            "t = {}: u_y = {}, R_N = {}: not on the contact branch",
            row[0],
            row[uy],
            row[rn]
        );
        let exact = f / k * ff * (row[0] - 1.0);
        let rel = (row[ux] - exact).abs() / exact.abs();
        if rel > worst.0 {
            worst = (rel, row[0], row[ux], exact);
        }
    }
    println!(
        "plane q=0: worst relative error of u_x on [1.2, 3]: {:.3e} at t = {} (IDA {:.9e}, closed form {:.9e})",
        worst.0, worst.1, worst.2, worst.3
    );
    assert!(worst.0 <= 1e-2, "u_x off the closed form by {worst:?}");
}

/// (a) friction-1d plateau: u = f R_N / k |V|_reg^(q-1) V / Vc^q with v = 0,
/// = 0.2 (1 + omega^2)^((q-1)/2) for the scene's values, to 1e-8 relative.
#[test]
fn ida_1d_plateau() {
    let sc = load("friction-1d");
    let run = ida(&sc);
    assert_eq!(run.stop.reason, "end", "{:?}", run.stop);
    let fr = &sc.friction;
    assert_eq!((sc.k, fr.f, sc.normal_force, fr.vc), (1.0, 0.2, 1.0, 1.0));
    let plateau = 0.2 * (1.0 + fr.omega * fr.omega).powf((fr.q - 1.0) / 2.0);
    let last = run.history.last().expect("rows");
    let rel = (last[1] - plateau).abs() / plateau;
    println!(
        "1d plateau at t = {}: IDA u = {:.15e}, closed form {:.15e}, relative {:.3e}",
        last[0], last[1], plateau, rel
    );
    assert!(rel <= 1e-8, "plateau off by {rel:e}");
}

/// (a) The roller's Cartesian index-1 form in the plane limit: radius r,
/// Omega r = -V (the top moves at +V), against the plane formulation. The
/// difference is the geometry's O(u/r) effect (normal tilt u_x/r): it must be
/// small at r = 1e3 and shrink like 1/r from r = 1e2. (Radii above ~1e4 put
/// the gap h = |x - C| - r at round-off noise the rtol 1e-10 error test sees.)
#[test]
fn ida_roller_plane_limit() {
    let plane = load("friction-plane");
    let flat = ida(&plane);
    let v = match plane.obstacle {
        anm::scene::friction::Obstacle::Plane { v } => v,
        _ => unreachable!(),
    };
    let mut errs = Vec::new();
    for r in [1e2, 1e3] {
        let mut sc = load("friction-roller");
        sc.obstacle = anm::scene::friction::Obstacle::Roller { r, omega: -v / r };
        sc.friction = plane.friction;
        sc.contact = plane.contact;
        sc.load_rate = plane.load_rate;
        sc.k = plane.k;
        sc.t_end = plane.t_end;
        sc.dt = plane.dt;
        let model = anm::reference::run::model(&sc).expect("model");
        let roller = solve_model(&sc, model.as_ref(), &settings(RTOL)).expect("IDA roller");
        println!(
            "roller r = {r:e}: stop {} at t = {}, {} steps, max constraint drift {:.2e}",
            roller.stop.reason, roller.stop.t, roller.counters.steps, roller.max_constraint_drift
        );
        assert_eq!(roller.stop.reason, "end", "{:?}", roller.stop);
        let e = column_errors(&flat.columns, &roller.history, &flat.history, f64::INFINITY);
        crate::common::print_table(&format!("roller (r = {r:e}) vs plane, IDA"), &e);
        errs.push(e);
    }
    for ((name, e2), (_, e3)) in errs[0].iter().zip(&errs[1]) {
        println!("  {name}: ratio err(r=1e2)/err(r=1e3) = {:.2}", e2 / e3);
        assert!(*e3 <= 5e-3, "{name}: {e3:e} at r = 1e3");
        assert!(
            e2 / e3 >= 5.0,
            "{name}: no 1/r convergence: {e2:e} -> {e3:e}"
        );
    }
}

/// [`column_errors`](crate::common::column_errors) of every column over
/// the rows with t <= t_max, all values finite (asserted).
fn column_errors(
    cols: &[String],
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    t_max: f64,
) -> Vec<(String, f64)> {
    let rows = crate::common::rows_up_to(a, b, t_max);
    for (ra, rb) in &rows {
        assert!(ra.iter().chain(rb.iter()).all(|v| v.is_finite()));
    }
    crate::common::column_errors(cols, &rows, &[])
}

fn anm(scene: &FrictionScene) -> FrictionRun {
    let run = anm_run(scene, None, false).unwrap_or_else(|e| panic!("ANM failed: {e}"));
    println!(
        "ANM on {}: stop {} at t = {:.9} s; t* estimate {:?}; {} steps, {:.3} s",
        run.kind,
        run.stop.reason,
        run.stop.t.unwrap_or(f64::NAN),
        run.t_singular_estimate,
        run.stats.steps,
        run.wall_s
    );
    run
}

fn anm_vs_ida(name: &str, before_stop: f64) {
    let sc = load(name);
    let a = anm(&sc);
    let b = ida(&sc);
    assert_eq!(a.columns, b.columns);
    let t_max = match a.stop.reason.as_str() {
        "end" => f64::INFINITY,
        _ => a.stop.t.expect("stop time") - before_stop,
    };
    let errs = column_errors(&a.columns, &a.history, &b.history, t_max);
    crate::common::print_table(
        &format!("{name}: ANM vs IDA (rtol {RTOL:e}), t <= {t_max}"),
        &errs,
    );
    let bad: Vec<_> = errs
        .iter()
        .filter(|(_, e)| e.is_nan() || *e > 1e-6)
        .collect();
    assert!(bad.is_empty(), "{name}: columns above 1e-6: {bad:?}");
}

/// (b) friction-1d: ANM vs IDA.
#[test]
fn anm_vs_ida_friction_1d() {
    anm_vs_ida("friction-1d", 0.0);
}

/// (b) friction-plane: ANM vs IDA.
#[test]
fn anm_vs_ida_friction_plane() {
    anm_vs_ida("friction-plane", 0.0);
}

/// (b) friction-roller: ANM vs IDA up to 0.05 s before the ANM's stop.
#[test]
fn anm_vs_ida_friction_roller() {
    anm_vs_ida("friction-roller", 0.05);
}

/// (c) friction-roller near the breakdown: IDA's step sizes and slip speeds
/// beside the ANM's stop time and located singular time. With the paper's
/// explicit series the ANM's stop must lie in [t(|v_s| = Vc),
/// t(|v_s| = 10 Vc)] of IDA's dense output. Where the geometric test fires
/// depends on the step sequence (explicit steps ~0.35 (t* - t) long near t*),
/// so for the default stepping (`auto`, other steps) the check is on what
/// the series locates, t*, which does not: the fold of the quasi-static
/// solution must come after IDA's slip has passed 10 Vc and no later than
/// the peak of IDA's slip (the regularized dynamics leaves the fold there).
#[test]
fn roller_breakdown_window() {
    let sc = load("friction-roller");
    let mut explicit = sc.clone();
    explicit.stepping = Stepping::Explicit;
    let a = anm(&explicit);
    let b = ida(&sc);
    let t_stop = a.stop.t.expect("ANM stop time");
    println!("ANM: stop reason {}, {:?}", a.stop.reason, a.stop.message);
    println!("IDA crossings of |v_s|: {:?}", b.crossings);
    let window = b.surge_window();
    println!(
        "IDA window [t(Vc), t(10 Vc)] = {window:?}; ANM stop t = {t_stop:.9}, t* = {:?}",
        a.t_singular_estimate
    );
    if let Some(s) = b.min_step_after(2.0) {
        println!(
            "IDA smallest step after t = 2: h = {:.3e} s at t = {:.9} s (slip {:.3e})",
            s.h, s.t, s.slip
        );
    }
    println!("IDA steps near the ANM stop (t, h, slip, order):");
    let near: Vec<_> = b
        .steps
        .iter()
        .filter(|s| (s.t - t_stop).abs() <= 0.02)
        .collect();
    let stride = (near.len() / 40).max(1);
    for s in near.iter().step_by(stride) {
        println!("  {:.9} {:.3e} {:+.6e} {}", s.t, s.h, s.slip, s.order);
    }
    println!(
        "IDA stop: {} at t = {:.9} ({:?})",
        b.stop.reason, b.stop.t, b.stop.message
    );
    assert_eq!(a.stop.reason, "singularity", "{:?}", a.stop);
    let (t1, t10) = window.expect("IDA's |slip| reaches 10 Vc");
    assert!(
        t1 <= t_stop && t_stop <= t10,
        "ANM stop {t_stop} outside IDA's window [{t1}, {t10}]"
    );
    let peak = b.slip_peak().expect("IDA steps");
    let d = anm(&sc);
    let t_star = d.t_singular_estimate.expect("ANM t* estimate");
    println!(
        "default stepping ({}): stop at {:.9}, t* = {t_star:.9}; IDA t(10 Vc) = {t10:.9}, \
         peak |v_s| = {:.3e} at {:.9}",
        sc.stepping.name(),
        d.stop.t.unwrap_or(f64::NAN),
        peak.slip.abs(),
        peak.t
    );
    assert_eq!(d.stop.reason, "singularity", "{:?}", d.stop);
    assert!(
        t10 <= t_star && t_star <= peak.t,
        "ANM t* {t_star} outside [IDA t(10 Vc) {t10}, IDA peak {}]",
        peak.t
    );
}

/// The cells of issue 16: (scene, zeta, omega); friction-1d has no zeta.
fn grid() -> Vec<(&'static str, Option<f64>, f64)> {
    let mut cells = vec![];
    for omega in [1e-1, 1e-4, 1e-6] {
        cells.push(("friction-1d", None, omega));
    }
    for name in ["friction-plane", "friction-roller"] {
        for zeta in [1e-1, 1e-2, 1e-4, 1e-6] {
            for omega in [1e-1, 1e-4, 1e-6] {
                cells.push((name, Some(zeta), omega));
            }
        }
    }
    cells
}

fn cell(name: &str, zeta: Option<f64>, omega: f64) -> FrictionScene {
    let mut sc = load(name);
    sc.friction.omega = omega;
    if zeta.is_some() {
        sc.friction.zeta = zeta;
    }
    sc
}

/// The displacement columns compared in the grid.
fn positions(name: &str) -> &'static [&'static str] {
    match name {
        "friction-1d" => &["u"],
        "friction-plane" => &["ux"],
        _ => &["ux", "uy"],
    }
}

/// Max relative error of the named columns of `a` against `b` on t <= t_max
/// (infinite when `a` stopped before t_max).
fn position_error(name: &str, a: &IdaRun, b: &IdaRun, t_max: f64) -> f64 {
    let want = b.history.iter().filter(|r| r[0] <= t_max).count();
    if a.history.iter().filter(|r| r[0] <= t_max).count() < want {
        return f64::INFINITY;
    }
    column_errors(&a.columns, &a.history, &b.history, t_max)
        .into_iter()
        .filter(|(c, _)| positions(name).contains(&c.as_str()))
        .map(|(_, e)| e)
        .fold(0.0, f64::max)
}

/// The comparison window: the whole run, or for the roller up to 0.05 s
/// before the reference's |v_s| first reaches Vc (the quasi-static regime;
/// the ANM stops in the surge that follows).
fn window(name: &str, reference: &IdaRun) -> f64 {
    match (name, reference.surge_window()) {
        ("friction-roller", Some((t1, _))) => t1 - 0.05,
        _ => f64::INFINITY,
    }
}

/// (d) Every cell: IDA and diffsol BDF end within 1,500 steps at rtol 1e-8;
/// they agree to 1e-7 at rtol 1e-10. The errors at rtol 1e-8 against IDA at
/// rtol 1e-12 are printed, not asserted (README: where 1e-7 is reached).
#[test]
fn baselines_on_the_regularization_grid() {
    println!(
        "| scene | zeta | omega | IDA steps | IDA etf | IDA err | diffsol BDF steps | BDF err | IDA vs BDF (1e-8) | IDA vs BDF (1e-10) |"
    );
    let mut failures = vec![];
    for (name, zeta, omega) in grid() {
        let sc = cell(name, zeta, omega);
        let ida8 = solve(&sc, &settings(1e-8)).expect("IDA");
        let ida10 = solve(&sc, &settings(1e-10)).expect("IDA");
        let ida12 = solve(&sc, &settings(1e-12)).expect("IDA");
        let bdf = |rtol| {
            let s = DiffsolSettings::new(DiffsolMethod::Bdf, rtol).expect("settings");
            anm::reference::diffsol::solve(&sc, &s).expect("diffsol")
        };
        let (bdf8, bdf10) = (bdf(1e-8), bdf(1e-10));
        let t_max = window(name, &ida12);
        let e = |a: &IdaRun, b: &IdaRun| position_error(name, a, b, t_max);
        let agree10 = e(&bdf10, &ida10);
        println!(
            "| {name} | {} | {omega:e} | {} | {} | {:.1e} | {} | {:.1e} | {:.1e} | {:.1e} |",
            zeta.map_or("–".into(), |z| format!("{z:e}")),
            ida8.counters.steps,
            ida8.counters.error_test_failures,
            e(&ida8, &ida12),
            bdf8.counters.steps,
            e(&bdf8, &ida12),
            e(&bdf8, &ida8),
            agree10,
        );
        for (who, run) in [("IDA", &ida8), ("diffsol BDF", &bdf8)] {
            if run.stop.reason != "end" || run.counters.steps > 1500 {
                failures.push(format!(
                    "{name} zeta {zeta:?} omega {omega:e}: {who} {} after {} steps",
                    run.stop.reason, run.counters.steps
                ));
            }
        }
        if agree10.is_nan() || agree10 > 1e-7 {
            failures.push(format!(
                "{name} zeta {zeta:?} omega {omega:e}: IDA and diffsol (rtol 1e-10) differ by {agree10:e}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// (d) The tuned set-up against IDA's library defaults on the paper's
/// equations (every unknown in the error test with atol = rtol, the friction
/// law as written), friction-plane at zeta = 1e-2 N, rtol 1e-8: the default
/// set-up pins IDA at order 1 (issue 16: 44,437 steps, 43,753 error-test
/// failures); the velocity v_y dominates the local error estimate.
#[test]
fn library_defaults_stall_and_the_tuned_setup_does_not() {
    let sc = cell("friction-plane", Some(1e-2), 1e-1);
    let plain = solve(&sc, &IdaSettings::library_default(1e-8, 1e-8).unwrap()).expect("IDA");
    let tuned = solve(&sc, &settings(1e-8)).expect("IDA");
    let dominant = |r: &IdaRun| {
        r.unknowns
            .iter()
            .zip(&r.dominant_error)
            .max_by_key(|(_, n)| **n)
            .map(|(u, n)| format!("{u} ({n} steps)"))
    };
    for (what, r) in [("library defaults", &plain), ("tuned", &tuned)] {
        println!(
            "{what}: {} steps, {} at order 1, {} error-test failures; largest local error: {:?}",
            r.counters.steps,
            r.order_one_steps(),
            r.counters.error_test_failures,
            dominant(r)
        );
    }
    assert!(plain.counters.steps > 10 * tuned.counters.steps);
    assert!(plain.order_one_steps() * 2 > plain.counters.steps as usize);
    assert!(tuned.counters.steps <= 1500);
}

/// Review 6: IDA with the algebraic unknowns out of its error test (the
/// default, `suppress`) ended friction-plane at q = 0, K = 1e8 N/m, eta =
/// 1e-8 N at u_y = -3 m, 2 m through the plane, with R_N = -1.5e-8 N (the
/// other root of eq. 3), exit 0. The run now stops there, and with the
/// algebraic unknowns in the test it reaches the end on the contact, where
/// the ANM ends too (u_x within 1e-6).
#[test]
fn ida_off_the_contact_law_s_root_is_stopped() {
    let mut sc = load("friction-plane");
    sc.friction.q = 0.0;
    let law = sc.contact.as_mut().expect("contact");
    law.k = 1e8;
    law.eta = 1e-8;
    let run = solve(&sc, &settings(1e-8)).expect("IDA runs");
    println!("suppress: {:?}", run.stop);
    assert_eq!(run.stop.reason, "off_branch");
    assert!(
        run.stop
            .message
            .as_deref()
            .unwrap_or("")
            .contains("--atol-algebraic")
    );
    let mut kept = settings(1e-8);
    kept.algebraic = anm::reference::settings::AlgebraicControl::Atol(1e-8);
    let run = solve(&sc, &kept).expect("IDA runs");
    assert_eq!(run.stop.reason, "end", "{:?}", run.stop);
    let ux = col(&run.columns, "ux");
    let uy = col(&run.columns, "uy");
    let last = run.history.last().expect("rows");
    let a = anm(&sc);
    let a_last = a.history.last().expect("ANM rows");
    println!(
        "IDA u = ({}, {}), ANM u = ({}, {})",
        last[ux], last[uy], a_last[1], a_last[2]
    );
    assert!((last[uy] + 1.0).abs() < 1e-6, "u_y = {}", last[uy]);
    assert!((last[ux] - a_last[1]).abs() < 1e-6 * a_last[1].abs(), "u_x");
}

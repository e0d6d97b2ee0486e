//! Support reactions of a linear analysis (`solver.method = "linear"`)
//! balance the loads of the linear model. They were read from the shell's
//! nonlinear residual at the linear solution, which is off equilibrium:
//! 1.0031 N of reaction under a 1 N tip load (the cantilever below, tip
//! rotation 0.03 rad), 32.3 N under 100 N.

use crate::scratch::ScratchFile;
use anm::run::run_loaded;

/// The shared cantilever (shell_common::cantilever_scene) in metres, solved
/// by the linear method.
fn cantilever(q: f64, lambda_end: f64, lambda_step: f64) -> String {
    crate::shell_common::cantilever_scene(1.0, q, "linear", lambda_end, lambda_step)
}

#[test]
fn linear_reactions_balance_the_load_on_every_row() {
    // Tip loads 1 N and 100 N (rotations 0.03 and 3 rad in the linear
    // model): the reaction is the load, whatever the linear displacement.
    for q in [-10.0, -1000.0] {
        let file = ScratchFile::with_text("linear-reactions", "c.toml", &cantilever(q, 1.0, 0.25));
        let scene = anm::scene::shell::load(&file).expect("scene");
        let r = run_loaded(&scene, None, false).expect("linear run");
        assert_eq!(r.stop.reason, "end");
        let load = -0.1 * q;
        // Euler-Bernoulli tip deflection F L^3 / 3EI, I = b t^3 / 12.
        let tip = load / (3.0 * 2e9 * 0.1 * 1e-6 / 12.0);
        let (rz, rx, uz) = (r.end["Rz"], r.end["Rx"], r.end["uz_tip"]);
        println!(
            "q = {q}: Rz = {rz:.15e} (load {load}), Rx = {rx:.3e}, uz_tip = {uz:.6e} (beam {tip:.6e})"
        );
        assert!((rz - load).abs() <= 1e-9 * load, "Rz = {rz} against {load}");
        assert!(rx.abs() <= 1e-9 * load, "Rx = {rx}");
        assert!(
            (-uz - tip).abs() <= 1e-3 * tip,
            "uz_tip = {uz} against {tip}"
        );
    }
}

#[test]
fn linear_reactions_at_a_lambda_end_off_the_grid() {
    // lambda_end = 0.9 with a grid of 0.25: the last row (0.9) is recorded
    // with the linear model's reactions too.
    let file = ScratchFile::with_text(
        "linear-reactions",
        "c.toml",
        &cantilever(-1000.0, 0.9, 0.25),
    );
    let scene = anm::scene::shell::load(&file).expect("scene");
    let r = run_loaded(&scene, None, false).expect("linear run");
    let rz = r.end["Rz"];
    assert!((rz - 90.0).abs() <= 1e-9 * 90.0, "Rz = {rz} against 90");
}

/// The tension probe of a linear analysis is the linear model's too
/// (review 4): a 2 m wide membrane pulled across its edge at q N/m carries
/// T = 2 q on every row (the support reaction), and the free edge of the
/// same plate pulled along x carries none. Read from the nonlinear element
/// forces at the linear solution they were 200.345 N for 200 N (+18 % at
/// q = 10 kN/m) and 0.075 N on the free edge.
#[test]
fn linear_tension_is_the_linear_model_s() {
    for (q, pull) in [(100.0, [0.0, 1.0]), (1e4, [0.0, 1.0]), (100.0, [1.0, 0.0])] {
        let text = format!(
            r#"[scene]
kind = "shell"

[mesh]
type = "rectangle"
x = [0.0, 2.0]
y = [0.0, 1.0]
divisions = [8, 4]

[material]
young = 1e7
poisson = 0.3

[shell]
thickness = 0.01

[[fix]]
group = "{held}"
dofs = ["{held_dof}", "uz"]

[[fix]]
group = "all"
dofs = ["uz"]

[[fix]]
point = [0.0, 0.0, 0.0]
dofs = ["ux", "uy"]

[[load]]
edge = "{pulled}"
line_force = [{fx}, {fy}, 0.0]

[[probe]]
name = "T"
quantity = "tension"
group = "t1"

[[probe]]
name = "R"
quantity = "reaction_{held_axis}"
group = "{held}"

[solver]
method = "linear"
lambda_end = 1.0

[output]
lambda_step = 0.5
vtk_every = 0
plot = false
"#,
            held = if pull[1] == 1.0 { "t0" } else { "s0" },
            held_dof = if pull[1] == 1.0 { "uy" } else { "ux" },
            held_axis = if pull[1] == 1.0 { "y" } else { "x" },
            pulled = if pull[1] == 1.0 { "t1" } else { "s1" },
            fx = q * pull[0],
            fy = q * pull[1],
        );
        let file = ScratchFile::with_text("linear-tension", "m.toml", &text);
        let scene = anm::scene::shell::load(&file).expect("scene");
        let r = run_loaded(&scene, None, false).expect("linear run");
        let t = r.end["T"];
        let want = 2.0 * q * pull[1];
        println!(
            "q = {q}, pull {pull:?}: T = {t:.12e} against {want}, R = {}",
            r.end["R"]
        );
        assert!((t - want).abs() <= 1e-8 * q, "T = {t} against {want}");
        // Half-way, half the tension (the linear model).
        let half = r.history[1][r.columns.iter().position(|c| c == "T").unwrap()];
        assert!((half - want / 2.0).abs() <= 1e-8 * q, "T(0.5) = {half}");
    }
}

/// A negative lambda_end (review 4): history.csv listed each step's grid
/// values backwards (0, -3, -2, -1, -10, -9, ...). The rows must run from 0
/// down to lambda_end in order, each grid value once, and mirror the run
/// to +lambda_end (the cantilever's tip load reversed).
#[test]
fn a_negative_lambda_end_writes_its_rows_in_path_order() {
    let run = |end: f64| {
        let text = crate::shell_common::cantilever_scene(1.0, -10.0, "anm", end, 0.5);
        let file = ScratchFile::with_text("negative-lambda", "c.toml", &text);
        run_loaded(&anm::scene::shell::load(&file).unwrap(), None, false).unwrap()
    };
    let (down, up) = (run(-3.0), run(3.0));
    let lambdas: Vec<f64> = down.history.iter().map(|r| r[0]).collect();
    let want: Vec<f64> = (0..=6).map(|k| -0.5 * k as f64).collect();
    assert_eq!(lambdas.len(), want.len(), "{lambdas:?}");
    for (l, w) in lambdas.iter().zip(&want) {
        assert!((l - w).abs() < 1e-12, "{lambdas:?}");
    }
    let uz = down.columns.iter().position(|c| c == "uz_tip").unwrap();
    for (d, u) in down.history.iter().zip(&up.history) {
        assert!(
            (d[uz] + u[uz]).abs() <= 1e-6 * u[uz].abs().max(1e-9),
            "{} vs {}",
            d[uz],
            u[uz]
        );
    }
}

/// Review 5: reactions at a deflection far beyond the linear range summed
/// to 9.16 times the load on a thin plate (1.4e4 plate lengths), the
/// nonlinear terms' round-off in the cubic through λ_end / 3 steps. Here a
/// tip load of 1e7 N on the cantilever: 2e5 m of tip deflection in the
/// linear model. The linear model's reactions are the load, whatever its
/// amplitude.
#[test]
fn linear_reactions_balance_the_load_at_any_amplitude() {
    let q = -1e8;
    let file = ScratchFile::with_text("linear-reactions", "c.toml", &cantilever(q, 1.0, 1.0));
    let scene = anm::scene::shell::load(&file).expect("scene");
    let r = run_loaded(&scene, None, false).expect("linear run");
    let load = -0.1 * q;
    let (rz, uz) = (r.end["Rz"], r.end["uz_tip"]);
    println!("q = {q}: Rz = {rz:.15e} (load {load}), uz_tip = {uz:.6e}");
    assert!((rz - load).abs() <= 1e-9 * load, "Rz = {rz} against {load}");
}

/// Review 5: a clamped plate at thickness 1e-6, 1e-7, 1e-8 of its size
/// deflected 2.3e-4, 1.9e-2 and 28% off the plate's closed form, exit 0:
/// the membrane stiffness, (L/t)² times the bending's, buries the bending
/// in round-off. The linear run estimates that error by one step of
/// iterative refinement and stops where it exceeds solver.residual_tol.
#[test]
fn a_thin_shell_beyond_round_off_is_refused_by_the_linear_method() {
    let thick = cantilever(-10.0, 1.0, 1.0);
    assert!(thick.contains("thickness = 0.01"), "{thick}");
    // The same cantilever, t / L = 1e-7, with the load scaled by t³.
    let thin = thick
        .replace("thickness = 0.01", "thickness = 1e-7")
        .replace("-10", "-1e-14");
    let file = ScratchFile::with_text("linear-thin", "c.toml", &thin);
    let scene = anm::scene::shell::load(&file).expect("scene");
    let e = run_loaded(&scene, None, false).expect_err("refused");
    let text = e.to_string();
    println!("{text}");
    for needle in [
        "ill-conditioned to round-off",
        "iterative refinement",
        "solver.residual_tol",
        "thickness / model size = 1.0e-7",
    ] {
        assert!(text.contains(needle), "`{needle}` not in: {text}");
    }
}

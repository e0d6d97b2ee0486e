//! Issue 10 item 3c: SUNDIALS IDA integrates the same shell-friction
//! residual as the ANM ([`anm::reference::shell_ida`]) on a coarse
//! strip-on-roller scene (the capstan of scenes/strip-capstan.toml with a
//! 90° wrap and 8 elements); the ANM's implicit steps agree with IDA at
//! rtol 1e-10 to 1e-6 relative on the translations at every output time.
#![cfg(feature = "reference")]

use anm::reference::shell_ida::{ShellIda, trajectory_difference};
use anm::run::shell_time;
use anm::scene::shell::load;

fn coarse_capstan() -> anm::scene::shell::ShellScene {
    let text = std::fs::read_to_string("scenes/strip-capstan.toml").expect("scene");
    let text = text
        .replace("angle = [0.0, 180.0]", "angle = [0.0, 90.0]")
        .replace("divisions = [1, 64]", "divisions = [1, 8]")
        .replace(
            "line_force = [0.0, -400.0, 0.0]",
            "line_force = [0.0, 0.0, -400.0]",
        );
    let dir = std::env::temp_dir().join(format!("anm-shell-ida-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("coarse-capstan.toml");
    std::fs::write(&path, text).expect("write scene");
    load(&path).expect("scene loads")
}

#[test]
fn anm_implicit_steps_agree_with_ida_on_the_shell_residual() {
    let mut sc = coarse_capstan();
    sc.solver.eps = 1e-10;
    let cfg = shell_time::config(&sc);
    let (run, _) = shell_time::solve(&sc).expect("ANM runs");
    let anm: Vec<(f64, Vec<f64>)> = run.samples.iter().map(|s| (s.t, s.full.clone())).collect();
    let ida = ShellIda::new(shell_time::problem(&sc).expect("problem")).expect("IDA set-up");
    let mut kinks: Vec<f64> = {
        let fr = sc.friction.as_ref().expect("friction");
        let mut k = fr.load.kinks();
        k.extend(fr.motion.kinks());
        k
    };
    kinks.retain(|&k| k > 0.0);
    let reference = ida
        .solve(&cfg.outputs, &kinks, 1e-10, 1_000_000)
        .expect("IDA runs");
    // The ANM's samples start at t = 0; IDA's at the first output.
    let diff = trajectory_difference(&anm[1..], &reference.samples);
    println!(
        "coarse capstan: ANM {} steps, {} factorizations; IDA rtol 1e-10: {} steps, {} residuals, {} Jacobians, {} error-test and {} convergence failures, {:.2} s; max |u_anm - u_ida| / max |u_ida| = {diff:.2e}",
        run.stats.steps,
        run.stats.factorizations,
        reference.steps,
        reference.residual_evals,
        reference.jacobian_evals,
        reference.error_test_fails,
        reference.nonlinear_conv_fails,
        reference.wall_s
    );
    assert!(diff <= 1e-6, "{diff}");
}

//! Profiling loop of the stiffness grid's ANM runs alone (no IDA):
//! `cargo run --release --example friction_loop -- REPEAT [EPS]` runs
//! friction-plane and friction-roller at zeta in {1e-2, 1e-4, 1e-6} N and
//! omega in {1e-2, 1e-4} (`solver.time_step = "auto"`), REPEAT times each,
//! and prints per cell the steps, the minimum wall and microseconds per step.
use anm::scene;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let repeat: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20);
    let eps: Option<f64> = args.get(2).and_then(|s| s.parse().ok());
    let mut total = 0.0;
    for case in ["friction-plane", "friction-roller"] {
        let path = std::path::PathBuf::from(format!("scenes/{case}.toml"));
        let text = scene::read(&path).unwrap();
        let kind = scene::kind(&path, &text).unwrap();
        let base = scene::friction::load(&path, &text, kind).unwrap();
        for zeta in [1e-2, 1e-4, 1e-6] {
            for omega in [1e-2, 1e-4] {
                let mut s = base.clone();
                s.stepping = anm::series::dae::Stepping::Auto;
                s.friction.zeta = Some(zeta);
                s.friction.omega = omega;
                if let Some(e) = eps {
                    s.eps = e;
                }
                let mut best = f64::INFINITY;
                let mut steps = 0;
                for _ in 0..repeat {
                    let r = anm::model::friction_run::run(&s, None, false).unwrap();
                    best = best.min(r.wall_s);
                    steps = r.stats.steps;
                }
                total += best;
                println!(
                    "{case} zeta={zeta:.0e} omega={omega:.0e}: {steps} steps, {:.3} ms, {:.2} us/step",
                    1e3 * best,
                    1e6 * best / steps as f64
                );
            }
        }
    }
    println!("sum of minima: {:.3} ms", 1e3 * total);
}

//! `cargo bench`: the friction work-precision tables of `anm bench` (ANM
//! orders x tolerances; IDA with `--features reference`; diffsol BDF and
//! ESDIRK34), friction-plane and friction-roller at zeta = 1e-1 and 1e-4 N,
//! the fastest setting of each method at errors 1e-6 and 1e-8 with the
//! ANM / best-baseline ratio, then the interleaved head-to-heads. Prints
//! tables; asserts nothing.

use anm::study::bench::{self, fastest_markdown, friction_methods, markdown, work_precision};
use anm::study::target;
use std::path::Path;

fn main() {
    let with_ida = cfg!(feature = "reference");
    let targets = [1e-6, 1e-8];
    let mut heads = vec![];
    for case in ["friction-1d", "friction-plane", "friction-roller"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{case}.toml"));
        let text = anm::scene::read(&path).expect("scene");
        let kind = anm::scene::kind(&path, &text).expect("kind");
        let scene = anm::scene::friction::load(&path, &text, kind).expect("valid scene");
        let variants: Vec<(String, _)> = if scene.contact.is_some() {
            [1e-1, 1e-4]
                .iter()
                .map(|&z| {
                    let mut s = scene.clone();
                    s.friction.zeta = Some(z);
                    (format!("{case} zeta={z:.0e}"), s)
                })
                .collect()
        } else {
            vec![(case.to_string(), scene)]
        };
        for (name, scene) in variants {
            let reference = bench::reference(&scene, with_ida).expect("reference run");
            println!(
                "\n## {name} (ANM(30, 1e-14) vs reference: {:.2e})\n",
                reference.anm_floor
            );
            let methods = friction_methods(with_ida);
            let rows = work_precision(
                &name,
                &scene,
                &methods,
                &reference.solution,
                reference.t_max,
                5,
            );
            print!("{}", markdown(&rows, &reference.name));
            print!("\n{}", fastest_markdown(&rows, &targets));
            for t in targets {
                heads.push(
                    target::head_to_head(
                        &name,
                        &scene,
                        &rows,
                        &methods,
                        reference.target(t),
                        100,
                        None,
                    )
                    .expect("head-to-head runs"),
                );
            }
        }
    }
    println!("\n## Head-to-head at the error targets\n");
    print!("{}", target::markdown(&heads));
}

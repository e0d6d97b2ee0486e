//! `cargo bench`: the friction work-precision tables of `anm bench` (ANM
//! orders x tolerances, and IDA with `--features reference`), then the
//! head-to-head at error 1e-8. Prints tables; asserts nothing.

use anm::study::bench::{self, friction_methods, markdown, work_precision};
use anm::study::target;
use std::path::Path;

fn main() {
    let with_ida = cfg!(feature = "reference");
    let mut heads = vec![];
    for case in ["friction-1d", "friction-plane", "friction-roller"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{case}.toml"));
        let text = anm::scene::read(&path).expect("scene");
        let kind = anm::scene::kind(&path, &text).expect("kind");
        let scene = anm::scene::friction::load(&path, &text, kind).expect("valid scene");
        let reference = bench::reference(&scene, with_ida).expect("reference run");
        println!(
            "\n## {case} (ANM(30, 1e-14) vs reference: {:.2e})\n",
            reference.anm_floor
        );
        let methods = friction_methods(with_ida);
        let rows = work_precision(
            case,
            &scene,
            &methods,
            &reference.solution,
            reference.t_max,
            5,
        );
        print!("{}", markdown(&rows, &reference.name));
        heads.push(
            target::head_to_head(
                case,
                &scene,
                &rows,
                &methods,
                reference.target(1e-8),
                100,
                None,
            )
            .expect("head-to-head runs"),
        );
    }
    println!("\n## Head-to-head at the error target\n");
    print!("{}", target::markdown(&heads));
}

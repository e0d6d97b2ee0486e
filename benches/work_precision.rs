//! `cargo bench`: the friction work-precision tables of `anm bench` (ANM
//! orders x tolerances, and IDA with `--features reference`). Prints tables;
//! asserts nothing.

use anm::study::bench::{self, friction_methods, markdown, work_precision};
use std::path::Path;

fn main() {
    let with_ida = cfg!(feature = "reference");
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
        let rows = work_precision(
            case,
            &scene,
            &friction_methods(with_ida),
            &reference.solution,
            reference.t_max,
            5,
        );
        print!("{}", markdown(&rows, &reference.name));
    }
}

//! `cargo bench`: the friction work-precision tables of `anm bench` (ANM
//! orders x tolerances, and IDA with `--features reference`). Prints tables;
//! asserts nothing.

use anm::study::bench::{Method, error, friction_methods, markdown, solve, work_precision};
use std::path::Path;

fn main() {
    let with_ida = cfg!(feature = "reference");
    for case in ["friction-1d", "friction-plane", "friction-roller"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{case}.toml"));
        let text = anm::scene::read(&path).expect("scene");
        let kind = anm::scene::kind(&path, &text).expect("kind");
        let scene = anm::scene::friction::load(&path, &text, kind).expect("valid scene");
        let ref_method = if with_ida {
            Method::Ida { rtol: 1e-12 }
        } else {
            Method::Anm {
                order: 30,
                eps: 1e-14,
            }
        };
        let reference = solve(&scene, &ref_method).expect("reference run");
        let anm_ref = solve(
            &scene,
            &Method::Anm {
                order: 30,
                eps: 1e-14,
            },
        )
        .expect("ANM reference");
        let t_max = if anm_ref.stop == "singularity" {
            anm_ref.t_stop - 0.05
        } else {
            scene.t_end
        };
        println!(
            "\n## {case} (ANM(30, 1e-14) vs reference: {:.2e})\n",
            error(&anm_ref, &reference, t_max)
        );
        let rows = work_precision(
            case,
            &scene,
            &friction_methods(with_ida),
            &reference,
            t_max,
            5,
        );
        print!(
            "{}",
            markdown(
                &rows,
                &format!("{} {}", ref_method.label(), ref_method.setting())
            )
        );
    }
}

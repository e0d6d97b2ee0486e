//! Simply supported square plate under uniaxial compression (issue 14,
//! req. 5c): `anm buckle` on scenes/verification/plate-buckling.toml
//! against the linear buckling load of the same plate as a thin 3D solid,
//! computed by dolfinx 0.5.2 + SLEPc (reference/dolfinx/plate_buckling.py,
//! stored in reference/data/plate-buckling/buckling.json: Q2 hexahedra
//! graded towards the edges, uz = 0 on the lateral faces with the edge
//! free to rotate and twist (the soft simple support that the shell's free
//! director gives), the edge load as a uniform traction over the
//! thickness; mesh convergence in those files and in reference/README.md).
//! The hard-support solid (no edge twist) is printed for comparison. CI
//! only reads the stored files.

use crate::shell_common;
use anm::scene::shell::{Load, load};
use anm::study::buckle::{Base, buckle};
use std::f64::consts::PI;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn plate_buckling_stress_matches_the_dolfinx_slepc_solid() {
    let reference = shell_common::stored_json("reference/data/plate-buckling/buckling.json");
    let sigma_ref = reference["reference"]["sigma_cr_Pa"]
        .as_f64()
        .expect("reference.sigma_cr_Pa");

    let sc = load(&root().join("scenes/verification/plate-buckling.toml")).expect("scene");
    // The stored data must be of this scene: same E, nu, t and load.
    let data = &reference["data"];
    let same = |key: &str, ours: f64| shell_common::assert_stored(data, key, ours);
    same("young", sc.material.young);
    same("poisson", sc.material.poisson);
    same("thickness", sc.thickness);
    let n_line = sc
        .loads
        .iter()
        .find_map(|l| match l {
            Load::Line { force, .. } => Some(force.norm()),
            _ => None,
        })
        .expect("the scene's edge line force");
    same("line_force_per_lambda", n_line);

    let (e, nu, t) = (sc.material.young, sc.material.poisson, sc.thickness);
    // Kirchhoff, k = 4 (Timoshenko & Gere 1961, §9.2); the square's side b
    // from the stored data (the scene's mesh is [0, 1]²).
    let side = data["b"].as_f64().expect("data.b");
    let sigma_closed = 4.0 * PI * PI * e / (12.0 * (1.0 - nu * nu)) * (t / side).powi(2);

    println!("| model | mesh | dofs | sigma_cr [Pa] | / closed form | / dolfinx reference |");
    println!("|---|---|---|---|---|---|");
    for file in ["buckling", "buckling_hard"] {
        let text = std::fs::read_to_string(
            root().join(format!("reference/data/plate-buckling/{file}.json")),
        )
        .expect("stored dolfinx data");
        let runs: serde_json::Value = serde_json::from_str(&text).expect("json");
        for r in runs["runs"].as_array().expect("runs") {
            let s = r["modes"][0]["sigma_cr_Pa"].as_f64().unwrap();
            println!(
                "| dolfinx 3D Q2, {} support | {} x {} x {}, grade {} | {} | {s:.4} | {:.6} | {:.6} |",
                r["supports"].as_str().unwrap_or("?"),
                r["n"],
                r["n"],
                r["nz"],
                r["grade"],
                r["dofs"],
                s / sigma_closed,
                s / sigma_ref
            );
        }
    }
    println!(
        "| Kirchhoff closed form | | | {sigma_closed:.4} | 1 | {:.6} |",
        sigma_closed / sigma_ref
    );

    // The shell: the scene's 16 x 16 mesh and the same plate on 32 x 32 and
    // 64 x 64 (the scene text with its divisions replaced: the edge layer
    // of the soft support needs the finer meshes, see docs/bifurcation.md).
    let source = std::fs::read_to_string(&sc.file).expect("scene text");
    assert!(
        source.contains("divisions = [16, 16]"),
        "scene mesh changed"
    );
    let mut errors = Vec::new();
    for n in [16, 32, 64] {
        let file = crate::scratch::ScratchFile::with_text(
            "plate-buckling",
            &format!("{n}.toml"),
            &source.replace("divisions = [16, 16]", &format!("divisions = [{n}, {n}]")),
        );
        let scn = load(&file).expect("refined scene");
        let b = buckle(&scn, Base::Lambda(0.0), 1, None).expect("buckle");
        let sigma_ours = b.modes[0].mu * n_line / t;
        println!(
            "| anm buckle (shell, director free) | {n} x {n} | {} | {sigma_ours:.4} | {:.6} | {:.6} |",
            b.dofs,
            sigma_ours / sigma_closed,
            sigma_ours / sigma_ref
        );
        errors.push((n, sigma_ours / sigma_ref - 1.0));
    }
    for (n, err) in &errors {
        println!(
            "anm {n} x {n} vs dolfinx reference: relative error {err:+.2e} (tolerance 1e-2 from 32 x 32)"
        );
    }
    // Tolerance 1e-2 (req. 5c) on the meshes that resolve the plate to
    // that accuracy; the 16 x 16 mesh is printed only (+1.3 %).
    for (n, err) in errors.iter().filter(|(n, _)| *n >= 32) {
        assert!(err.abs() <= 1e-2, "{n} x {n}: {err:e}");
    }
    // Both models converge downwards to the soft-support value: the finer
    // shell mesh must be closer.
    assert!(errors[2].1.abs() < errors[1].1.abs() && errors[1].1.abs() < errors[0].1.abs());
}

//! A built-in cylinder over a full turn closes its seam (the last node row
//! is the first): a tube with free ends under internal pressure p takes
//! the hoop strain p R / (E t), so its radius grows by w = p R² / (E t)
//! all around. Left open, the seam's two rows were unjoined and the same
//! tube deflected 80 m for w = 1e-3 m.

use crate::scratch::ScratchFile;
use anm::run::run_loaded;

/// The tube R = 1 m, L = 1 m, t = 0.01 m, E = 1e7 Pa, ν = 0.3, p = 100 Pa
/// (w = 1e-3 m), `around` elements around, linear analysis; symmetric
/// about x = 0, three points hold the rigid motions in the plane.
fn tube(around: usize, angle: &str) -> String {
    format!(
        r#"
[scene]
kind = "shell"

[mesh]
type = "cylinder"
x = [0.0, 1.0]
radius = 1.0
angle = {angle}
divisions = [2, {around}]

[material]
young = 1e7
poisson = 0.3

[shell]
thickness = 0.01

[[fix]]
group = "s0"
symmetry = "x"

[[fix]]
point = [0.0, 0.0, 1.0]
dofs = ["uy"]

[[fix]]
point = [0.0, 0.0, -1.0]
dofs = ["uy"]

[[fix]]
point = [0.0, 1.0, 0.0]
dofs = ["uz"]

[[load]]
surface = "all"
pressure = 100.0

[[probe]]
name = "top"
quantity = "uz"
point = [1.0, 0.0, 1.0]

[[probe]]
name = "side"
quantity = "uy"
point = [1.0, 1.0, 0.0]

[[probe]]
name = "bottom"
quantity = "uz"
point = [1.0, 0.0, -1.0]

[solver]
method = "linear"
lambda_end = 1.0

[output]
lambda_step = 1.0
vtk_every = 0
plot = false
"#
    )
}

fn radial(around: usize, angle: &str) -> [f64; 3] {
    let f = ScratchFile::with_text("closed-tube", "tube.toml", &tube(around, angle));
    let scene = anm::scene::shell::load(&f).expect("scene");
    let r = run_loaded(&scene, None, false).expect("run");
    [r.end["top"], r.end["side"], -r.end["bottom"]]
}

#[test]
fn a_full_turn_closes_the_seam_and_a_tube_inflates_uniformly() {
    let w = 100.0 * 1.0 / (1e7 * 0.01);
    let mut errors = vec![];
    for around in [32, 64] {
        let r = radial(around, "[0.0, 360.0]");
        let err = (r[0] - w).abs() / w;
        println!(
            "{around} around: top {:.6e}, side {:.6e}, bottom {:.6e} (p R²/Et {w:.1e}, error {err:.2e})",
            r[0], r[1], r[2]
        );
        // The same radial displacement all around (the seam at the top).
        for v in r {
            assert!((v - r[0]).abs() <= 1e-9 * w, "{r:?}");
        }
        errors.push(err);
    }
    // Faceting error O(h²): within 0.5% at 64 around, a quarter at 32.
    assert!(errors[1] <= 5e-3, "{errors:?}");
    let order = (errors[0] / errors[1]).log2();
    assert!((order - 2.0).abs() < 0.2, "convergence order {order}");
    // The turn the other way round: the normal points inward (docs/scenes.md:
    // outward for an increasing angle), and so does the pressure's push.
    let r = radial(64, "[360.0, 0.0]");
    for v in r {
        assert!((v + w).abs() <= 5e-3 * w, "{r:?}");
    }
}

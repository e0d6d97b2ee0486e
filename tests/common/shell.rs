//! Helpers shared by the shell verification tests (included with
//! `#[path = "common/shell.rs"] mod shell_common;`).
#![allow(dead_code)]

use anm::linalg::LinearSolver;
use anm::mesh::{Mesh, Vec3};
use anm::series::ContinuationProblem;
use anm::shell::kinematics::shape;
use anm::shell::{Material, ShellModel};

/// Builds the model of a mesh with its reference directors.
pub fn model(mesh: &Mesh, thickness: f64, young: f64, poisson: f64) -> ShellModel {
    let dirs = mesh.directors().expect("valid mesh");
    ShellModel::new(
        mesh.nodes.clone(),
        dirs,
        &mesh.quads,
        thickness,
        Material { young, poisson },
    )
    .expect("valid elements")
}

/// Consistent nodal forces of a uniform load per unit area `q` (2×2 Gauss on
/// the bilinear reference geometry), added to the dead load pattern.
pub fn add_area_load(m: &mut ShellModel, mesh: &Mesh, q: Vec3) {
    let g = 1.0 / 3f64.sqrt();
    for quad in &mesh.quads {
        for (xi, eta) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
            let (n, nx, ny) = shape(xi, eta);
            let mut a1 = Vec3::zeros();
            let mut a2 = Vec3::zeros();
            for i in 0..4 {
                a1 += nx[i] * mesh.nodes[quad[i]];
                a2 += ny[i] * mesh.nodes[quad[i]];
            }
            let da = a1.cross(&a2).norm();
            for i in 0..4 {
                for k in 0..3 {
                    m.dead[6 * quad[i] + k] += n[i] * da * q[k];
                }
            }
        }
    }
}

/// Linear solution (one solve with the tangent at U = 0) for lambda = 1:
/// K U = -dR/dlambda. Returns the full 6-per-node vector.
pub fn linear(m: &mut ShellModel) -> Vec<f64> {
    let u0 = vec![0.0; m.ndof()];
    let (k, rl) = m.tangent(&u0, 0.0).expect("tangent");
    let f = LinearSolver::default()
        .factorize(&k)
        .expect("factorization");
    let neg: Vec<f64> = rl.iter().map(|x| -x).collect();
    let u = f.solve(&neg);
    assert!(
        u.iter().all(|x| x.is_finite()),
        "non-finite linear solution"
    );
    m.expand(&u, 1.0)
}

/// Fixes the given components (0..3 v, 3..6 w) at every node of `nodes`.
pub fn fix(list: &mut Vec<(usize, usize)>, nodes: &[usize], comps: &[usize]) {
    for &n in nodes {
        for &c in comps {
            list.push((n, c));
        }
    }
}

#[track_caller]
pub fn assert_rel(got: f64, want: f64, tol: f64, what: &str) {
    let err = (got - want).abs() / want.abs();
    assert!(
        got.is_finite() && err <= tol,
        "{what}: got {got:.6e}, want {want:.6e}, relative error {err:.3e} > {tol:.1e}"
    );
}

/// A stored reference file (path from the crate root), parsed.
pub fn stored_json(rel: &str) -> serde_json::Value {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{rel}: {e}"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Stored reference data must be of the scene under test: `data[key]`
/// equals `ours` to 1e-12 relative.
pub fn assert_stored(data: &serde_json::Value, key: &str, ours: f64) {
    let theirs = data[key].as_f64().unwrap_or(f64::NAN);
    assert!(
        (theirs - ours).abs() <= 1e-12 * ours.abs(),
        "{key}: dolfinx {theirs}, scene {ours}"
    );
}

/// The clamped cantilever 1 × 0.1 × 0.01 m, E = 2e9 Pa, ν = 0, 20 × 2
/// elements, under a tip line load of `q` N/m on the edge s1 (total 0.1 q
/// N), written in metres (`unit` = 1) or in millimetres and MPa (`unit` =
/// 1e3, the load in N/mm), solved by `method` to `lambda_end` with outputs
/// every `lambda_step`; probes Rz, Rx (clamp reactions) and uz_tip.
pub fn cantilever_scene(
    unit: f64,
    q: f64,
    method: &str,
    lambda_end: f64,
    lambda_step: f64,
) -> String {
    let young = 2e9 / (unit * unit);
    let q = q / unit;
    let (l, b, t) = (unit, 0.05 * unit, 0.01 * unit);
    format!(
        r#"
[scene]
kind = "shell"

[mesh]
type = "rectangle"
x = [0.0, {l}]
y = [-{b}, {b}]
divisions = [20, 2]

[material]
young = {young}
poisson = 0.0

[shell]
thickness = {t}

[[fix]]
group = "s0"
clamp = true

[[load]]
edge = "s1"
line_force = [0.0, 0.0, {q}]

[[probe]]
name = "Rz"
quantity = "reaction_z"
group = "s0"

[[probe]]
name = "Rx"
quantity = "reaction_x"
group = "s0"

[[probe]]
name = "uz_tip"
quantity = "uz"
group = "s1"

[solver]
method = "{method}"
lambda_end = {lambda_end}

[output]
lambda_step = {lambda_step}
vtk_every = 0
plot = false
"#
    )
}

//! Patch tests on the distorted 5-element patch of MacNeal and Harder,
//! Finite Elem. Anal. Des. 1 (1985) 3–20, fig. 2: rectangle 0.24 × 0.12,
//! interior nodes (0.04, 0.02), (0.18, 0.03), (0.16, 0.08), (0.08, 0.08);
//! t = 0.001, E = 1e6, nu = 0.25.
//!
//! Goal: constant membrane and constant bending states prescribed on the
//! boundary nodes are reproduced exactly at the interior nodes (1e-8
//! relative), linear analysis.
//!
//! ```text
//!  (0,.12)+----------------------+(.24,.12)
//!         |  \ 8___________7 /   |
//!         |   |            |     |
//!         |   5‾‾‾‾‾‾‾‾‾‾‾‾‾6    |
//!  (0,0)  +----------------------+(.24,0)
//! ```
//! Membrane: v = 1e-3 (x + y/2, y + x/2, 0); plane stress through the
//! thickness stretch: director increment w = (0, 0, -nu/(1-nu) (e_xx + e_yy)).
//! Bending: v_z = 1e-3 (x² + xy + y²)/2, director w = (-v_z,x, -v_z,y, 0).

use crate::shell_common;

use anm::mesh::{Mesh, Vec3};
use std::collections::BTreeMap;

fn patch() -> Mesh {
    let nodes = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.24, 0.0, 0.0),
        Vec3::new(0.24, 0.12, 0.0),
        Vec3::new(0.0, 0.12, 0.0),
        Vec3::new(0.04, 0.02, 0.0),
        Vec3::new(0.18, 0.03, 0.0),
        Vec3::new(0.16, 0.08, 0.0),
        Vec3::new(0.08, 0.08, 0.0),
    ];
    let quads = vec![
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7],
        [4, 5, 6, 7],
    ];
    let mut groups = BTreeMap::new();
    groups.insert("boundary".to_string(), vec![0, 1, 2, 3]);
    Mesh {
        file: "<MacNeal-Harder patch>".into(),
        node_tags: (1..=nodes.len()).collect(),
        nodes,
        quad_lines: vec![0; 5],
        quad_tags: (1..=5).collect(),
        quads,
        exact_normals: None,
        groups,
        edge_groups: BTreeMap::new(),
        surface_groups: BTreeMap::new(),
        grid: None,
        notes: vec![],
        digest: None,
    }
}

/// Solves with the boundary dofs prescribed to `exact` (by moving them to
/// the right-hand side) and returns the worst relative nodal error.
fn run(exact: impl Fn(&Vec3) -> [f64; 6], free_boundary: &[usize]) -> f64 {
    let mesh = patch();
    let mut m = shell_common::model(&mesh, 0.001, 1e6, 0.25);
    let ex: Vec<[f64; 6]> = mesh.nodes.iter().map(&exact).collect();
    // Prescribed values: impose through the dead load f = -K_fp u_p, i.e.
    // assemble the full tangent with everything free, then reduce.
    let mut fixed = vec![];
    for n in 0..4 {
        for k in 0..6 {
            if !free_boundary.contains(&k) {
                fixed.push((n, k));
            }
        }
    }
    m.set_constraints(&[]);
    let nfull = 6 * mesh.nodes.len();
    let (k, _) = anm::series::ContinuationProblem::tangent(&mut m, &vec![0.0; nfull], 0.0).unwrap();
    let mut kd = vec![vec![0.0; nfull]; nfull];
    for (r, c, v) in k.entries() {
        kd[r][c] += v;
    }
    let is_fixed = |i: usize| fixed.contains(&(i / 6, i % 6));
    let free: Vec<usize> = (0..nfull).filter(|&i| !is_fixed(i)).collect();
    let up: Vec<f64> = (0..nfull)
        .map(|i| if is_fixed(i) { ex[i / 6][i % 6] } else { 0.0 })
        .collect();
    let rows: Vec<Vec<f64>> = free
        .iter()
        .map(|&i| free.iter().map(|&j| kd[i][j]).collect())
        .collect();
    let rhs: Vec<f64> = free
        .iter()
        .map(|&i| -(0..nfull).map(|j| kd[i][j] * up[j]).sum::<f64>())
        .collect();
    let a = anm::linalg::SparseMatrix::from_dense(&rows);
    let f = anm::linalg::LinearSolver::default().factorize(&a).unwrap();
    let x = f.solve(&rhs);
    let mut u = up.clone();
    for (xi, &i) in x.iter().zip(&free) {
        u[i] = *xi;
    }
    let scale = ex.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
    let mut worst = 0.0f64;
    for n in 0..mesh.nodes.len() {
        for k in 0..6 {
            worst = worst.max((u[6 * n + k] - ex[n][k]).abs() / scale);
        }
    }
    worst
}

#[test]
fn membrane_patch_test_on_distorted_mesh() {
    let nu: f64 = 0.25;
    let e33 = -nu / (1.0 - nu) * 2e-3;
    let err = run(
        |x| {
            [
                1e-3 * (x[0] + x[1] / 2.0),
                1e-3 * (x[1] + x[0] / 2.0),
                0.0,
                0.0,
                0.0,
                e33,
            ]
        },
        &[5],
    );
    println!("membrane patch test: max relative nodal error {err:.3e}");
    assert!(err < 1e-8, "membrane patch test error {err:.3e}");
}

#[test]
fn bending_patch_test_on_distorted_mesh() {
    let err = run(
        |x| {
            let (a, b) = (x[0], x[1]);
            [
                0.0,
                0.0,
                1e-3 * (a * a + a * b + b * b) / 2.0,
                -1e-3 * (a + b / 2.0),
                -1e-3 * (b + a / 2.0),
                0.0,
            ]
        },
        &[5],
    );
    println!("bending patch test: max relative nodal error {err:.3e}");
    assert!(err < 1e-8, "bending patch test error {err:.3e}");
}

//! Linear shell benchmarks of the obstacle course (MacNeal, Harder, Finite
//! Elem. Anal. Des. 1 (1985) 3–20; Belytschko et al., CMAME 51 (1985)).
//!
//! Goal: the 4-node ANS + EAS element converges to the published reference
//! values: Scordelis–Lo roof 0.3024, pinched cylinder with rigid diaphragms
//! 1.8248e-5, pinched hemisphere with an 18° hole 0.0924 (linear = one solve
//! with the tangent at U = 0). Each test prints its convergence table and
//! asserts 2% on the finest ("moderate") mesh it runs.
//!
//! ```text
//!  Scordelis-Lo (quarter)      pinched cylinder (octant)    hemisphere (quarter)
//!   diaphragm x = 25            diaphragm x = 300             F = 1 at (R,0,0) +x
//!   R = 25, phi = 40 deg        R = 300, t = 3                F = 1 at (0,R,0) -y
//!   t = 0.25, q = 90 (-z)       E = 3e6, nu = 0.3, P/4        R = 10, t = 0.04
//!   E = 4.32e8, nu = 0          at (0,0,R) toward the axis    E = 6.825e7, nu = 0.3
//! ```

use crate::shell_common;

use anm::mesh::{Vec3, structured};
use shell_common::*;

fn scordelis_lo(n: usize) -> f64 {
    let mesh = structured::cylinder_panel(25.0, 0.0, 25.0, 0.0, 40f64.to_radians(), n, n);
    let mut m = model(&mesh, 0.25, 4.32e8, 0.0);
    add_area_load(&mut m, &mesh, Vec3::new(0.0, 0.0, -90.0));
    let mut fixed = vec![];
    fix(&mut fixed, &mesh.groups["s1"], &[1, 2]); // diaphragm
    fix(&mut fixed, &mesh.groups["s0"], &[0, 3]); // symmetry x = 0
    fix(&mut fixed, &mesh.groups["t0"], &[1, 4]); // symmetry y = 0 (crown)
    m.set_constraints(&fixed);
    let u = linear(&mut m);
    let a = n * (n + 1); // (i = 0, j = n): midspan of the free edge
    -u[6 * a + 2]
}

#[test]
fn scordelis_lo_roof_converges_to_0_3024() {
    println!("Scordelis-Lo roof, vertical displacement at the free-edge midspan (ref 0.3024)");
    println!("{:>6} {:>12} {:>10}", "mesh", "w", "w/ref");
    let mut last = 0.0;
    for n in [4, 8, 16, 32] {
        last = scordelis_lo(n);
        println!("{:>3}x{:<2} {:>12.6} {:>10.4}", n, n, last, last / 0.3024);
    }
    assert_rel(last, 0.3024, 0.02, "Scordelis-Lo 32x32");
}

fn pinched_cylinder(n: usize) -> f64 {
    let mesh = structured::cylinder_panel(300.0, 0.0, 300.0, 0.0, 90f64.to_radians(), n, n);
    let mut m = model(&mesh, 3.0, 3e6, 0.3);
    let load = 0; // (i = 0, j = 0): x = 0, phi = 0, at (0, 0, R)
    m.dead[6 * load + 2] = -0.25;
    let mut fixed = vec![];
    fix(&mut fixed, &mesh.groups["s1"], &[1, 2]); // rigid diaphragm
    fix(&mut fixed, &mesh.groups["s0"], &[0, 3]); // symmetry x = 0
    fix(&mut fixed, &mesh.groups["t0"], &[1, 4]); // symmetry y = 0
    fix(&mut fixed, &mesh.groups["t1"], &[2, 5]); // symmetry z = 0
    m.set_constraints(&fixed);
    let u = linear(&mut m);
    -u[6 * load + 2]
}

#[test]
fn pinched_cylinder_converges_to_1_8248e_5() {
    println!("Pinched cylinder with rigid diaphragms, displacement under the load (ref 1.8248e-5)");
    println!("{:>6} {:>12} {:>10}", "mesh", "w", "w/ref");
    let mut last = 0.0;
    for n in [4, 8, 16, 32] {
        last = pinched_cylinder(n);
        println!(
            "{:>3}x{:<2} {:>12.5e} {:>10.4}",
            n,
            n,
            last,
            last / 1.8248e-5
        );
    }
    assert_rel(last, 1.8248e-5, 0.02, "pinched cylinder 32x32");
}

fn hemisphere(n: usize) -> f64 {
    let mesh = structured::hemisphere_quarter(10.0, 18f64.to_radians(), n);
    let mut m = model(&mesh, 0.04, 6.825e7, 0.3);
    let a = 0; // (lon 0, equator) = (R, 0, 0)
    let b = n; // (lon 90, equator) = (0, R, 0)
    m.dead[6 * a] = 1.0;
    m.dead[6 * b + 1] = -1.0;
    let mut fixed = vec![];
    fix(&mut fixed, &mesh.groups["s0"], &[1, 4]); // symmetry y = 0
    fix(&mut fixed, &mesh.groups["s1"], &[0, 3]); // symmetry x = 0
    fixed.push((mesh.groups["t1"][0], 2)); // z translation
    m.set_constraints(&fixed);
    let u = linear(&mut m);
    u[6 * a]
}

#[test]
fn pinched_hemisphere_converges_to_0_0924() {
    println!("Pinched hemisphere (18 deg hole), displacement under the load (ref 0.0924)");
    println!("{:>6} {:>12} {:>10}", "mesh", "u", "u/ref");
    let mut last = 0.0;
    for n in [4, 8, 16, 32] {
        last = hemisphere(n);
        println!("{:>3}x{:<2} {:>12.6} {:>10.4}", n, n, last, last / 0.0924);
    }
    assert_rel(last, 0.0924, 0.02, "hemisphere 32x32");
}

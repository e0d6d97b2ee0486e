//! Surface loads on 4-node bilinear quadrilaterals, integrated with 2 × 2
//! Gauss points in natural coordinates ξ, η ∈ [−1, 1] (conventions in
//! [`crate::fe`]).
//!
//! - Dead traction t (force per unit reference area, a fixed vector):
//!   f_a = ∫ N_a t dA0, dA0 = |X,ξ × X,η| dξ dη.
//! - Dead pressure p along the reference normal:
//!   f_a = ∫ N_a p (X,ξ × X,η) dξ dη.
//! - Follower pressure p along the current normal:
//!   f_a(x) = ∫ N_a p (x,ξ × x,η) dξ dη, x = X + v the current positions.
//!
//! **Sign convention**: a positive p pushes along +n = x,ξ × x,η / |x,ξ × x,η|,
//! the element's orientation normal (for the built-in meshes, the normal
//! documented with each mesher, e.g. outward on a sphere patch). A pressure
//! acting on the side that n points to, pushing the surface inward, is
//! therefore a negative p.
//!
//! The pressure integrands are polynomials of degree ≤ 2 in ξ and in η, so
//! 2 × 2 Gauss points integrate them exactly: the follower forces of a closed
//! surface sum to zero to rounding. The follower force is quadratic in x:
//! f(x) = B(x, x) with the symmetric bilinear form [`follower_bilinear`];
//! along an ANM series x(a) = Σ a^r x_r its coefficient of order q is
//! Σ_{r=0}^{q} B(x_r, x_{q−r}). Its derivative [`follower_stiffness`] (the load
//! stiffness) is not symmetric in general.

use super::{Vec3, gauss_2x2, shape, tangents};

/// Nodal forces of the dead traction `t` (force per unit reference area) on
/// the element with reference positions `x0`.
pub fn dead_traction_forces(t: Vec3, x0: &[Vec3; 4]) -> [Vec3; 4] {
    let mut f = [Vec3::zeros(); 4];
    for [xi, eta] in gauss_2x2() {
        let (n, dxi, deta) = shape(xi, eta);
        let (a, b) = tangents(x0, &dxi, &deta);
        let da = a.cross(&b).norm();
        for k in 0..4 {
            f[k] += t * (n[k] * da);
        }
    }
    f
}

/// Nodal forces of the dead pressure `p` along the reference normal
/// X,ξ × X,η (positive along it) on the element with reference positions
/// `x0`.
pub fn dead_pressure_forces(p: f64, x0: &[Vec3; 4]) -> [Vec3; 4] {
    follower_forces(p, x0)
}

/// Nodal forces of the follower pressure `p` along the current normal
/// x,ξ × x,η (positive along it) at current positions `x`.
pub fn follower_forces(p: f64, x: &[Vec3; 4]) -> [Vec3; 4] {
    follower_bilinear(p, x, x)
}

/// The symmetric bilinear form of the follower pressure:
/// B(x, y)_a = ½ ∫ N_a p (x,ξ × y,η + y,ξ × x,η) dξ dη, so that
/// B(x, x) = [`follower_forces`]`(p, x)`.
pub fn follower_bilinear(p: f64, x: &[Vec3; 4], y: &[Vec3; 4]) -> [Vec3; 4] {
    let mut f = [Vec3::zeros(); 4];
    for [xi, eta] in gauss_2x2() {
        let (n, dxi, deta) = shape(xi, eta);
        let (xa, xb) = tangents(x, &dxi, &deta);
        let (ya, yb) = tangents(y, &dxi, &deta);
        let g = (xa.cross(&yb) + ya.cross(&xb)) * (0.5 * p);
        for k in 0..4 {
            f[k] += g * n[k];
        }
    }
    f
}

/// The load stiffness of the follower pressure at current positions `x`:
/// entry (3a + i, 3b + j) is ∂f_{a,i} / ∂x_{b,j}. Not symmetric in general.
pub fn follower_stiffness(p: f64, x: &[Vec3; 4]) -> [[f64; 12]; 12] {
    // d(x,ξ × x,η) = N_b,ξ δ × x,η + x,ξ × N_b,η δ
    //             = (N_b,η [x,ξ]× − N_b,ξ [x,η]×) δ.
    let mut k = [[0.0; 12]; 12];
    for [xi, eta] in gauss_2x2() {
        let (n, dxi, deta) = shape(xi, eta);
        let (xa, xb) = tangents(x, &dxi, &deta);
        let (sa, sb) = (xa.cross_matrix(), xb.cross_matrix());
        for b in 0..4 {
            let m = (sa * deta[b] - sb * dxi[b]) * p;
            for a in 0..4 {
                for i in 0..3 {
                    for j in 0..3 {
                        k[3 * a + i][3 * b + j] += n[a] * m[(i, j)];
                    }
                }
            }
        }
    }
    k
}

/// Nodal follower-pressure forces on the elements `elems` of `quads` at the
/// current nodal positions `x` (one vector per node of `x`).
pub fn assemble_follower(p: f64, quads: &[[usize; 4]], elems: &[usize], x: &[Vec3]) -> Vec<Vec3> {
    let mut f = vec![Vec3::zeros(); x.len()];
    for &e in elems {
        let q = quads[e];
        let fe = follower_forces(p, &std::array::from_fn(|i| x[q[i]]));
        for (k, &node) in q.iter().enumerate() {
            f[node] += fe[k];
        }
    }
    f
}

/// Nodal dead-traction forces on the elements `elems` of `quads` with
/// reference positions `x0` (one vector per node of `x0`).
pub fn assemble_dead_traction(
    t: Vec3,
    quads: &[[usize; 4]],
    elems: &[usize],
    x0: &[Vec3],
) -> Vec<Vec3> {
    let mut f = vec![Vec3::zeros(); x0.len()];
    for &e in elems {
        let q = quads[e];
        let fe = dead_traction_forces(t, &std::array::from_fn(|i| x0[q[i]]));
        for (k, &node) in q.iter().enumerate() {
            f[node] += fe[k];
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured;
    use nalgebra::{DMatrix, DVector};
    use std::f64::consts::PI;
    use std::path::Path;

    /// Deterministic pseudo-random numbers in [−1, 1) (xorshift).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
        /// A warped, stretched quadrilateral near the unit square.
        fn quad(&mut self) -> [Vec3; 4] {
            let c = [[0.0, 0.0], [1.3, 0.0], [1.1, 0.9], [-0.1, 1.2]];
            std::array::from_fn(|i| Vec3::new(c[i][0], c[i][1], 0.0) + self.vec() * 0.2)
        }
    }

    fn max_diff(a: &[Vec3; 4], b: &[Vec3; 4]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, f64::max)
    }

    #[test]
    fn flat_unit_square_unit_pressure() {
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        for f in [follower_forces(1.0, &x), dead_pressure_forces(1.0, &x)] {
            for fa in f {
                assert!((fa - Vec3::new(0.0, 0.0, 0.25)).norm() < 1e-15);
            }
        }
        let t = Vec3::new(0.5, -2.0, 1.0);
        for fa in dead_traction_forces(t, &x) {
            assert!((fa - t * 0.25).norm() < 1e-15);
        }
        // Reversed orientation: the normal, hence the force, flips.
        let r = [x[0], x[3], x[2], x[1]];
        for fa in follower_forces(1.0, &r) {
            assert!((fa + Vec3::new(0.0, 0.0, 0.25)).norm() < 1e-15);
        }
    }

    #[test]
    fn dead_traction_total_is_t_times_area() {
        // A plane parallelogram (constant Jacobian): area exact.
        let x = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(2.5, 1.5, 1.0),
            Vec3::new(0.5, 1.5, 1.0),
        ];
        let t = Vec3::new(1.0, 2.0, 3.0);
        let total: Vec3 = dead_traction_forces(t, &x).iter().sum();
        assert!((total - t * 3.0).norm() < 1e-14);
    }

    #[test]
    fn bilinear_form_is_symmetric_and_gives_the_forces() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..5 {
            let (x, y) = (rng.quad(), rng.quad());
            let p = 1.0 + rng.next();
            let f = follower_forces(p, &x);
            assert!(max_diff(&follower_bilinear(p, &x, &x), &f) < 1e-15);
            assert!(max_diff(&follower_bilinear(p, &x, &y), &follower_bilinear(p, &y, &x)) < 1e-15);
            // Bilinear: B(x + 2y, y) = B(x, y) + 2 B(y, y).
            let x2y: [Vec3; 4] = std::array::from_fn(|i| x[i] + 2.0 * y[i]);
            let lhs = follower_bilinear(p, &x2y, &y);
            let bxy = follower_bilinear(p, &x, &y);
            let byy = follower_bilinear(p, &y, &y);
            let rhs: [Vec3; 4] = std::array::from_fn(|i| bxy[i] + 2.0 * byy[i]);
            assert!(max_diff(&lhs, &rhs) < 1e-14);
        }
    }

    #[test]
    fn stiffness_matches_central_differences() {
        let mut rng = Rng(12345);
        for _ in 0..5 {
            let x = rng.quad();
            let p = 2.0 + rng.next();
            let k = follower_stiffness(p, &x);
            let h = 1e-6;
            let scale = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            let mut nonsym = 0.0f64;
            for b in 0..4 {
                for j in 0..3 {
                    let (mut xp, mut xm) = (x, x);
                    xp[b][j] += h;
                    xm[b][j] -= h;
                    let (fp, fm) = (follower_forces(p, &xp), follower_forces(p, &xm));
                    for a in 0..4 {
                        for i in 0..3 {
                            let fd = (fp[a][i] - fm[a][i]) / (2.0 * h);
                            let kk = k[3 * a + i][3 * b + j];
                            assert!(
                                (fd - kk).abs() <= 1e-7 * scale,
                                "K[{a}{i}][{b}{j}] = {kk}, fd {fd}"
                            );
                            nonsym = nonsym.max((kk - k[3 * b + j][3 * a + i]).abs());
                        }
                    }
                }
            }
            assert!(
                nonsym > 1e-3 * scale,
                "expected a non-symmetric load stiffness"
            );
        }
    }

    #[test]
    fn series_coefficients_are_convolutions_of_the_bilinear_form() {
        // x(a) = x0 + a x1 + a² x2; f(x(a)) is a polynomial of degree 4 in a.
        let mut rng = Rng(777);
        let x0 = rng.quad();
        let x1: [Vec3; 4] = std::array::from_fn(|_| rng.vec());
        let x2: [Vec3; 4] = std::array::from_fn(|_| rng.vec());
        let xs = [x0, x1, x2];
        let p = 1.7;
        // Fit the exact polynomial through 5 values of a.
        let a_vals = [-1.0, -0.5, 0.0, 0.5, 1.0];
        let v = DMatrix::from_fn(5, 5, |r, c| f64::powi(a_vals[r], c as i32));
        let lu = v.lu();
        let samples: Vec<[Vec3; 4]> = a_vals
            .iter()
            .map(|&a| {
                let x: [Vec3; 4] = std::array::from_fn(|i| x0[i] + a * x1[i] + a * a * x2[i]);
                follower_forces(p, &x)
            })
            .collect();
        let mut coef = [[Vec3::zeros(); 4]; 5];
        for node in 0..4 {
            for comp in 0..3 {
                let rhs = DVector::from_fn(5, |r, _| samples[r][node][comp]);
                let c = lu.solve(&rhs).unwrap();
                for q in 0..5 {
                    coef[q][node][comp] = c[q];
                }
            }
        }
        for (q, cq) in coef.iter().enumerate() {
            let mut conv = [Vec3::zeros(); 4];
            for r in 0..=q {
                if r > 2 || q - r > 2 {
                    continue;
                }
                let b = follower_bilinear(p, &xs[r], &xs[q - r]);
                for i in 0..4 {
                    conv[i] += b[i];
                }
            }
            assert!(max_diff(cq, &conv) < 1e-12, "order {q}");
        }
    }

    #[test]
    fn closed_surfaces_have_zero_total_follower_force() {
        // Full cylinder (seam nodes duplicated): lateral surface closed
        // around the axis.
        let (r, len, p) = (0.7, 2.0, 3.0);
        let m = structured::cylinder_panel(r, 0.0, len, 0.0, 2.0 * PI, 4, 24);
        let elems = m.surface("all", Path::new("s.toml"), "k").unwrap();
        let f = assemble_follower(p, &m.quads, elems, &m.nodes);
        let total: Vec3 = f.iter().sum();
        let area = 2.0 * PI * r * len;
        assert!(total.norm() / (p * area) < 1e-12, "{total}");
        // Each node of an interior ring (seam nodes merged) carries the
        // pressure on a quarter of its two facets: p (len / 4) r sin Δφ
        // radially (chord 2r sin(Δφ/2), facet angle Δφ).
        let dphi = 2.0 * PI / 24.0;
        let ring: f64 =
            (1..24).map(|j| f[j * 5 + 2].norm()).sum::<f64>() + (f[2] + f[24 * 5 + 2]).norm();
        let expected = 24.0 * p * (len / 4.0) * r * dphi.sin();
        assert!((ring / expected - 1.0).abs() < 1e-13, "{ring} {expected}");
        // Warped cube: 6 non-planar faces, outward, on 8 perturbed corners.
        let mut rng = Rng(4242);
        let c: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)
                    + rng.vec() * 0.2
            })
            .collect();
        let faces = vec![
            [0, 2, 3, 1], // z = 0, normal −z
            [4, 5, 7, 6], // z = 1, +z
            [0, 1, 5, 4], // y = 0, −y
            [2, 6, 7, 3], // y = 1, +y
            [0, 4, 6, 2], // x = 0, −x
            [1, 3, 7, 5], // x = 1, +x
        ];
        let f = assemble_follower(p, &faces, &[0, 1, 2, 3, 4, 5], &c);
        let total: Vec3 = f.iter().sum();
        assert!(total.norm() / p < 1e-13, "{total}");
        // Outward: the force on the top face points up.
        let top: Vec3 = follower_forces(p, &std::array::from_fn(|i| c[faces[1][i]]))
            .iter()
            .sum();
        assert!(top.z > 0.5 * p);
    }

    #[test]
    fn assembled_dead_traction_on_a_sphere_patch() {
        // Total = t × area, area of the faceted patch → exact area.
        let r = 1.5;
        let m = structured::sphere_patch(r, 0.0, 1.0, 0.0, 0.8, 16, 16);
        let t = Vec3::new(0.0, 0.0, -2.0);
        let f = assemble_dead_traction(t, &m.quads, &m.surface_groups["all"], &m.nodes);
        let total: Vec3 = f.iter().sum();
        let area = r * r * 1.0 * 0.8f64.sin();
        assert!(
            (total.z / (t.z * area) - 1.0).abs() < 5e-3,
            "{}",
            total.z / (t.z * area)
        );
        assert!(total.x == 0.0 && total.y == 0.0);
    }
}

//! Finite-element pieces with no shell knowledge: bilinear quadrilateral
//! shape functions and Gauss points, surface loads on 4-node quadrilaterals
//! ([`surface_load`]: dead traction, dead and follower pressure) and line
//! loads on 2-node edges ([`edge_load`]), and the degrees of freedom of
//! the shell nodes ([`dof`]), the tangent's sparsity pattern
//! ([`pattern`]).
//!
//! Element conventions are those of [`crate::mesh`]: nodes 1..4
//! counterclockwise at natural coordinates (ξ, η) = (−1, −1), (1, −1),
//! (1, 1), (−1, 1); the element's orientation normal is x,ξ × x,η.

pub mod dof;
pub mod edge_load;
pub mod pattern;
pub mod prefetch;
pub mod surface_load;

pub use crate::mesh::Vec3;

/// Natural coordinates of the four nodes.
pub const CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// The 2 × 2 Gauss points (ξ, η); every weight is 1.
pub fn gauss_2x2() -> [[f64; 2]; 4] {
    let g = 1.0 / 3f64.sqrt();
    [[-g, -g], [g, -g], [g, g], [-g, g]]
}

/// Bilinear shape functions N_a and their derivatives ∂N_a/∂ξ, ∂N_a/∂η at
/// (ξ, η).
pub fn shape(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let n =
        std::array::from_fn(|a| 0.25 * (1.0 + CORNERS[a][0] * xi) * (1.0 + CORNERS[a][1] * eta));
    let dxi = std::array::from_fn(|a| 0.25 * CORNERS[a][0] * (1.0 + CORNERS[a][1] * eta));
    let deta = std::array::from_fn(|a| 0.25 * (1.0 + CORNERS[a][0] * xi) * CORNERS[a][1]);
    (n, dxi, deta)
}

/// Covariant base vectors x,ξ and x,η of the bilinear map through `x` at
/// natural coordinates with shape derivatives `dxi`, `deta`.
pub fn tangents(x: &[Vec3; 4], dxi: &[f64; 4], deta: &[f64; 4]) -> (Vec3, Vec3) {
    let mut a = Vec3::zeros();
    let mut b = Vec3::zeros();
    for k in 0..4 {
        a += dxi[k] * x[k];
        b += deta[k] * x[k];
    }
    (a, b)
}

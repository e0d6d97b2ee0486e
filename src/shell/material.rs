//! 3D St Venant–Kirchhoff law in curvilinear coordinates, no plane-stress
//! condensation (DESIGN §3):
//!
//!   S^ij = C^ijkl E_kl,  C^ijkl = λ G^ij G^kl + μ (G^ik G^jl + G^il G^jk),
//!
//! λ = E ν / ((1 + ν)(1 − 2ν)), μ = E / (2 (1 + ν)), G^ij the contravariant
//! metric of the mid-surface basis (A1, A2, A3). With the six tensor
//! components e = (E11, E22, E12, E13, E23, E33), the energy density is
//! W = ½ eᵀ D e with D_ab = m_a m_b C^ab, m = (1, 1, 2, 2, 2, 1) counting the
//! symmetric pairs; s = D e is the stress conjugate to e.
//!
//! Through the thickness, e(θ3) = e⁰ + θ3 e¹ and D is taken constant (the
//! metric of the mid-surface; the shifter terms of order t/R are dropped), so
//! the integral over θ3 ∈ [−t/2, t/2] is exact:
//! ∫ W dθ3 = ½ (t e⁰ᵀ D e⁰ + t³/12 e¹ᵀ D e¹), the same as 2-point Gauss.

use nalgebra::{Matrix3, SMatrix};

use super::kinematics::{NSTRAIN, Vec3};

pub type DMatrix = SMatrix<f64, NSTRAIN, NSTRAIN>;

const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (0, 1), (0, 2), (1, 2), (2, 2)];
const MULT: [f64; 6] = [1.0, 1.0, 2.0, 2.0, 2.0, 1.0];

/// Isotropic elastic constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub young: f64,
    pub poisson: f64,
}

impl Material {
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }

    /// The 6×6 matrix D in the natural basis with covariant base vectors g.
    /// Returns None if the basis is degenerate.
    pub fn d_natural(&self, g: &[Vec3; 3]) -> Option<SMatrix<f64, 6, 6>> {
        let gm = Matrix3::from_fn(|i, j| g[i].dot(&g[j]));
        let gi = gm.try_inverse()?;
        let (lam, mu) = self.lame();
        let c = |i: usize, j: usize, k: usize, l: usize| {
            lam * gi[(i, j)] * gi[(k, l)] + mu * (gi[(i, k)] * gi[(j, l)] + gi[(i, l)] * gi[(j, k)])
        };
        Some(SMatrix::<f64, 6, 6>::from_fn(|a, b| {
            let (i, j) = PAIRS[a];
            let (k, l) = PAIRS[b];
            MULT[a] * MULT[b] * c(i, j, k, l)
        }))
    }

    /// Thickness-integrated 12×12 matrix blockdiag(t D, t³/12 D) acting on
    /// (e⁰, e¹).
    pub fn d_shell(&self, g: &[Vec3; 3], t: f64) -> Option<DMatrix> {
        let d = self.d_natural(g)?;
        let mut out = DMatrix::zeros();
        out.fixed_view_mut::<6, 6>(0, 0).copy_from(&(d * t));
        out.fixed_view_mut::<6, 6>(6, 6)
            .copy_from(&(d * (t * t * t / 12.0)));
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cartesian_basis_gives_the_isotropic_hooke_matrix() {
        let m = Material {
            young: 210.0,
            poisson: 0.3,
        };
        let d = m.d_natural(&[Vec3::x(), Vec3::y(), Vec3::z()]).unwrap();
        let (lam, mu) = m.lame();
        // Uniaxial stress check: E11 = 1, E22 = E33 = -nu gives S11 = E.
        let e = nalgebra::SVector::<f64, 6>::from([1.0, -0.3, 0.0, 0.0, 0.0, -0.3]);
        let s = d * e;
        assert!((s[0] - 210.0).abs() < 1e-12 && s[1].abs() < 1e-12 && s[5].abs() < 1e-12);
        assert!((d[(2, 2)] - 4.0 * mu).abs() < 1e-12 && (d[(0, 1)] - lam).abs() < 1e-12);
    }
}

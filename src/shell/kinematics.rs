//! Director-difference kinematics of the 3D shell (DESIGN §3; Büchter, Ramm,
//! Roehl, IJNME 37 (1994) 2551–2568, eqs. 7–12).
//!
//! A material point is x = x̄(ξ, η) + θ3 a3(ξ, η), with the mid-surface
//! position x̄ = X + v and the director a3 = A3 + w interpolated from the
//! nodes (6 unknowns per node: v, w; no rotations). θ3 ∈ [-t/2, t/2] is the
//! physical thickness coordinate and A3 the unit reference normal. The
//! covariant base vectors are g_α = a_α + θ3 a3,α and g_3 = a3, and the
//! Green–Lagrange strains E_ij = ½ (g_i·g_j − G_i·G_j), with the θ3² terms
//! dropped, are E = E⁰ + θ3 E¹:
//!
//! ```text
//! E⁰_αβ = ½ (a_α·a_β − A_α·A_β)          E¹_αβ = ½ (a_α·a3,β + a_β·a3,α − ref)
//! E⁰_α3 = ½ (a_α·a3 − A_α·A3)            E¹_α3 = ½ (a3,α·a3 − A3,α·A3)
//! E⁰_33 = ½ (a3·a3 − A3·A3)              E¹_33 = 0 (enhanced by EAS)
//! ```
//!
//! Every component is a sum of terms c (x_k · x_l) of the five point vectors
//! x = (a1, a2, a3, a3,1, a3,2), each linear in the element unknowns, so the
//! strain is exactly quadratic in (v, w): its first derivative B is linear and
//! its second derivative constant. This is what makes the ANM right-hand side
//! a plain convolution (Zahrouni, Cochelin, Potier-Ferry, CMAME 175 (1999)).
//!
//! Nodal Gram form (the element series and tangent, super::series): with
//! the element's nodal vectors as the columns of Y ([`NodalVectors`]), each
//! point vector is x_k = Y w_k, so E_c = Σ coef w_kᵀ (YᵀY − ref) w_l is
//! linear in the 7×7 Gram matrix YᵀY ([`Point::gram_strain`]).

// Node/dof/component loops read better with explicit indices.
#![allow(clippy::needless_range_loop)]

use nalgebra::{SMatrix, SVector, Vector3};

/// Number of strain components: (E⁰, E¹) × (11, 22, 12, 13, 23, 33), tensor
/// (not engineering) components in the natural covariant basis.
pub const NSTRAIN: usize = 12;
/// Element unknowns: 4 nodes × (v, w).
pub const NDOF_EL: usize = 24;

pub type Vec3 = Vector3<f64>;
/// The five point vectors a1, a2, a3, a3,1, a3,2.
pub type PointVectors = [Vec3; 5];
pub type Strain = [f64; NSTRAIN];
pub type BMatrix = SMatrix<f64, NSTRAIN, NDOF_EL>;
/// Columns of the element's nodal-vector matrix Y: the position differences
/// x_I − x_0 (I = 1, 2, 3), then the directors d_0..d_3. The strain sees the
/// positions only through a1 and a2, derivatives whose nodal weights sum to
/// zero, so the differences carry all of it (7 columns instead of 8: a
/// translation changes nothing).
pub const NCOL: usize = 7;
/// Unknowns of Y (3 per column), column-major.
pub const NDOF_Y: usize = 3 * NCOL;
pub type NodalVectors = SMatrix<f64, 3, NCOL>;
/// A symmetric matrix over the columns of Y: a nodal Gram matrix YᵀY or a
/// geometric stiffness (the Y block is this ⊗ I3).
pub type Sym = SMatrix<f64, NCOL, NCOL>;
pub type YMatrix = SMatrix<f64, NDOF_Y, NDOF_Y>;

/// Entries of a symmetric NCOL × NCOL matrix: its upper triangle, row by row.
pub const NSYM: usize = NCOL * (NCOL + 1) / 2;
pub type PackedSym = SVector<f64, NSYM>;
pub const SYM_PAIRS: [(usize, usize); NSYM] = {
    let mut pairs = [(0, 0); NSYM];
    let (mut a, mut k) = (0, 0);
    while a < NCOL {
        let mut b = a;
        while b < NCOL {
            pairs[k] = (a, b);
            k += 1;
            b += 1;
        }
        a += 1;
    }
    pairs
};
/// `SYM_INDEX[a][b]`: position of the pair (a, b) or (b, a) in SYM_PAIRS.
pub const SYM_INDEX: [[usize; NCOL]; NCOL] = {
    let mut index = [[0; NCOL]; NCOL];
    let mut k = 0;
    while k < NSYM {
        let (a, b) = SYM_PAIRS[k];
        index[a][b] = k;
        index[b][a] = k;
        k += 1;
    }
    index
};

pub fn pack(m: &Sym) -> PackedSym {
    PackedSym::from_fn(|k, _| m[SYM_PAIRS[k]])
}

pub fn unpack(v: &PackedSym) -> Sym {
    let mut m = Sym::zeros();
    for (k, &(a, b)) in SYM_PAIRS.iter().enumerate() {
        m[(a, b)] = v[k];
        m[(b, a)] = v[k];
    }
    m
}

/// Y from the nodal positions (or their coefficients) and directors.
pub fn nodal_vectors(x: &[Vec3; 4], d: &[Vec3; 4]) -> NodalVectors {
    NodalVectors::from_fn(|dim, col| {
        if col < 3 {
            x[col + 1][dim] - x[0][dim]
        } else {
            d[col - 3][dim]
        }
    })
}

/// Element unknown a (6 per node: v, w) as Y unknowns, δY = S δq:
/// (first, count, sign), the Y unknowns first + 3 m for m < count. v_0
/// enters the three differences with −1, v_I (I ≥ 1) its difference, w_I
/// its director column.
const Y_DOFS: [(usize, usize, f64); NDOF_EL] = {
    let mut t = [(0, 0, 0.0); NDOF_EL];
    let mut a = 0;
    while a < NDOF_EL {
        let (node, k) = (a / 6, a % 6);
        let dim = k % 3;
        t[a] = if k >= 3 {
            (3 * (3 + node) + dim, 1, 1.0)
        } else if node == 0 {
            (dim, 3, -1.0)
        } else {
            (3 * (node - 1) + dim, 1, 1.0)
        };
        a += 1;
    }
    t
};

/// Element force from the force on Y: f_q = Sᵀ f_Y.
pub fn element_force(fy: &NodalVectors) -> [f64; NDOF_EL] {
    let fy = fy.as_slice();
    std::array::from_fn(|a| {
        let (first, count, sign) = Y_DOFS[a];
        sign * (0..count).map(|m| fy[first + 3 * m]).sum::<f64>()
    })
}

/// Element matrix from a matrix on Y: K_q = Sᵀ K_Y S. S copies every
/// element unknown to one Y unknown except v_0, which enters the three
/// differences with −1: its rows and columns are minus the sums of three.
pub fn element_matrix(ky: &YMatrix) -> SMatrix<f64, NDOF_EL, NDOF_EL> {
    let y = ky.as_slice();
    // Entry a of S^T v for a vector v on Y.
    let gather = |v: &[f64], a: usize| {
        let (first, count, _) = Y_DOFS[a];
        if count == 1 {
            v[first]
        } else {
            -(v[first] + v[first + 3] + v[first + 6])
        }
    };
    // Columns of K_Y S: column b of K_Y S is K_Y (S e_b).
    let mut ks = [[0.0; NDOF_Y]; NDOF_EL];
    for (b, kb) in ks.iter_mut().enumerate() {
        let (first, count, _) = Y_DOFS[b];
        let column = |m: usize| &y[(first + 3 * m) * NDOF_Y..][..NDOF_Y];
        if count == 1 {
            kb.copy_from_slice(column(0));
        } else {
            let (c0, c1, c2) = (column(0), column(1), column(2));
            for r in 0..NDOF_Y {
                kb[r] = -(c0[r] + c1[r] + c2[r]);
            }
        }
    }
    let mut k = SMatrix::<f64, NDOF_EL, NDOF_EL>::zeros();
    for (b, kb) in ks.iter().enumerate() {
        for a in 0..NDOF_EL {
            k[(a, b)] = gather(kb, a);
        }
    }
    k
}

/// Which nodal field each point vector interpolates: 0 = mid-surface
/// position (v slot), 1 = director (w slot).
const SLOT: [usize; 5] = [0, 0, 1, 1, 1];
/// The columns of Y a slot's vectors draw on (their nonzero weights).
const COLS: [(usize, usize); 2] = [(0, 3), (3, NCOL)];

/// Strain component c = sum over terms coef (x_k · x_l) − reference.
const TERMS: [&[(usize, usize, f64)]; NSTRAIN] = [
    &[(0, 0, 0.5)],
    &[(1, 1, 0.5)],
    &[(0, 1, 0.5)],
    &[(0, 2, 0.5)],
    &[(1, 2, 0.5)],
    &[(2, 2, 0.5)],
    &[(0, 3, 1.0)],
    &[(1, 4, 1.0)],
    &[(0, 4, 0.5), (1, 3, 0.5)],
    &[(3, 2, 0.5)],
    &[(4, 2, 0.5)],
    &[],
];

/// Bilinear shape functions of the 4-node quadrilateral, nodes at
/// (−1,−1), (1,−1), (1,1), (−1,1).
pub fn shape(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    const S: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut n = [0.0; 4];
    let mut nx = [0.0; 4];
    let mut ny = [0.0; 4];
    for (i, &(a, b)) in S.iter().enumerate() {
        n[i] = 0.25 * (1.0 + a * xi) * (1.0 + b * eta);
        nx[i] = 0.25 * a * (1.0 + b * eta);
        ny[i] = 0.25 * b * (1.0 + a * xi);
    }
    (n, nx, ny)
}

/// Interpolation weights of the five point vectors at one point (ξ, η).
#[derive(Clone, Debug)]
pub struct Point {
    /// `phi[k][I]`: weight of node I in vector k.
    pub phi: [[f64; 4]; 5],
    /// `w[k][c]`: weight of column c of Y in vector k (the position weights
    /// of nodes 1..3 on the differences, since those of a1, a2 sum to 0).
    w: [[f64; NCOL]; 5],
}

impl Point {
    pub fn new(xi: f64, eta: f64) -> Self {
        let (n, nx, ny) = shape(xi, eta);
        let phi = [nx, ny, n, nx, ny];
        let w = std::array::from_fn(|k| {
            std::array::from_fn(|c| match (SLOT[k], c) {
                (0, c) if c < 3 => phi[k][c + 1],
                (1, c) if c >= 3 => phi[k][c - 3],
                _ => 0.0,
            })
        });
        Self { phi, w }
    }

    /// The point vectors from nodal positions `x` and directors `d` (full
    /// values or series coefficients: the map is linear).
    pub fn vectors(&self, x: &[Vec3; 4], d: &[Vec3; 4]) -> PointVectors {
        let mut out = [Vec3::zeros(); 5];
        for (k, o) in out.iter_mut().enumerate() {
            let field = if SLOT[k] == 0 { x } else { d };
            for i in 0..4 {
                *o += self.phi[k][i] * field[i];
            }
        }
        out
    }

    /// Point vectors from an element unknown vector (v, w per node).
    pub fn vectors_of(&self, q: &[f64; NDOF_EL]) -> PointVectors {
        let mut x = [Vec3::zeros(); 4];
        let mut d = [Vec3::zeros(); 4];
        for i in 0..4 {
            x[i] = Vec3::new(q[6 * i], q[6 * i + 1], q[6 * i + 2]);
            d[i] = Vec3::new(q[6 * i + 3], q[6 * i + 4], q[6 * i + 5]);
        }
        self.vectors(&x, &d)
    }

    /// B = dE/dq at the state with point vectors `x`.
    pub fn bmatrix(&self, x: &PointVectors) -> BMatrix {
        let mut b = BMatrix::zeros();
        for (c, terms) in TERMS.iter().enumerate() {
            for &(k, l, coef) in terms.iter() {
                for i in 0..4 {
                    for dim in 0..3 {
                        b[(c, 6 * i + 3 * SLOT[k] + dim)] += coef * self.phi[k][i] * x[l][dim];
                        b[(c, 6 * i + 3 * SLOT[l] + dim)] += coef * self.phi[l][i] * x[k][dim];
                    }
                }
            }
        }
        b
    }

    /// B(x)^T sigma without forming B.
    pub fn bt_sigma(&self, x: &PointVectors, sigma: &Strain, out: &mut [f64; NDOF_EL]) {
        for (c, terms) in TERMS.iter().enumerate() {
            let s = sigma[c];
            if s == 0.0 {
                continue;
            }
            for &(k, l, coef) in terms.iter() {
                for i in 0..4 {
                    let (fk, fl) = (coef * s * self.phi[k][i], coef * s * self.phi[l][i]);
                    for dim in 0..3 {
                        out[6 * i + 3 * SLOT[k] + dim] += fk * x[l][dim];
                        out[6 * i + 3 * SLOT[l] + dim] += fl * x[k][dim];
                    }
                }
            }
        }
    }

    /// Strain of a nodal Gram matrix M (linear in M): E_c = Σ coef w_kᵀ M w_l,
    /// w_k the weights of point vector k over the columns of Y, so that
    /// M = YᵀY − Y_refᵀY_ref gives [`strain`] and the series coefficient
    /// M_p = Σ_r Y_rᵀY_(p−r) gives the order-p strain.
    pub fn gram_strain(&self, m: &Sym) -> Strain {
        let mut e = [0.0; NSTRAIN];
        for (c, terms) in TERMS.iter().enumerate() {
            for &(k, l, coef) in terms.iter() {
                let mut s = 0.0;
                for i in COLS[SLOT[k]].0..COLS[SLOT[k]].1 {
                    for j in COLS[SLOT[l]].0..COLS[SLOT[l]].1 {
                        s += self.w[k][i] * self.w[l][j] * m[(i, j)];
                    }
                }
                e[c] += coef * s;
            }
        }
        e
    }

    /// Adds the geometric stiffness Σ_c σ_c d²E_c/dY² over the columns of Y
    /// (the Y block is this ⊗ I3). Since E is quadratic in Y, the force on
    /// Y is B(x)ᵀσ = Y Kg(σ), and on the element unknowns
    /// [`element_force`] of it.
    pub fn geometric(&self, sigma: &Strain, kg: &mut Sym) {
        for (c, terms) in TERMS.iter().enumerate() {
            let s = sigma[c];
            if s == 0.0 {
                continue;
            }
            for &(k, l, coef) in terms.iter() {
                for i in COLS[SLOT[k]].0..COLS[SLOT[k]].1 {
                    for j in COLS[SLOT[l]].0..COLS[SLOT[l]].1 {
                        let v = coef * s * self.w[k][i] * self.w[l][j];
                        kg[(i, j)] += v;
                        kg[(j, i)] += v;
                    }
                }
            }
        }
    }
}

/// Strain of the current point vectors `x` relative to the reference `x0`.
pub fn strain(x: &PointVectors, x0: &PointVectors) -> Strain {
    let mut e = [0.0; NSTRAIN];
    for (c, terms) in TERMS.iter().enumerate() {
        for &(k, l, coef) in terms.iter() {
            e[c] += coef * (x[k].dot(&x[l]) - x0[k].dot(&x0[l]));
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(seed: f64) -> [f64; NDOF_EL] {
        let mut q = [0.0; NDOF_EL];
        for (i, v) in q.iter_mut().enumerate() {
            *v = (seed * (i as f64 + 1.0) * 0.37).sin();
        }
        q
    }

    #[test]
    fn bmatrix_and_geometric_stiffness_match_finite_differences() {
        let pt = Point::new(0.3, -0.6);
        let q0 = state(1.0);
        let zero = pt.vectors_of(&[0.0; NDOF_EL]);
        let b = pt.bmatrix(&pt.vectors_of(&q0));
        let sigma: Strain = std::array::from_fn(|c| 0.1 * c as f64 - 0.4);
        let mut kg = Sym::zeros();
        pt.geometric(&sigma, &mut kg);
        let kq = element_matrix(&YMatrix::from_fn(|i, j| {
            if i % 3 == j % 3 {
                kg[(i / 3, j / 3)]
            } else {
                0.0
            }
        }));
        let h = 1e-6;
        for j in 0..NDOF_EL {
            let mut qp = q0;
            let mut qm = q0;
            qp[j] += h;
            qm[j] -= h;
            let ep = strain(&pt.vectors_of(&qp), &zero);
            let em = strain(&pt.vectors_of(&qm), &zero);
            for c in 0..NSTRAIN {
                let fd = (ep[c] - em[c]) / (2.0 * h);
                assert!(
                    (fd - b[(c, j)]).abs() < 1e-8,
                    "B[{c},{j}]: {} vs {fd}",
                    b[(c, j)]
                );
            }
            // d(B^T sigma)/dq_j = Kg column j.
            let mut fp = [0.0; NDOF_EL];
            let mut fm = [0.0; NDOF_EL];
            pt.bt_sigma(&pt.vectors_of(&qp), &sigma, &mut fp);
            pt.bt_sigma(&pt.vectors_of(&qm), &sigma, &mut fm);
            for i in 0..NDOF_EL {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                let an = kq[(i, j)];
                assert!((fd - an).abs() < 1e-8, "Kg[{i},{j}]: {an} vs {fd}");
            }
        }
    }

    #[test]
    fn gram_forms_match_the_pointwise_strain_and_force() {
        let pt = Point::new(-0.4, 0.7);
        let (q0, q) = (state(1.0), state(2.0));
        let nodal = |q: &[f64; NDOF_EL]| {
            let v = |i: usize| Vec3::new(q[i], q[i + 1], q[i + 2]);
            nodal_vectors(
                &std::array::from_fn(|n| v(6 * n)),
                &std::array::from_fn(|n| v(6 * n + 3)),
            )
        };
        let (y0, y) = (nodal(&q0), nodal(&q));
        let e = strain(&pt.vectors_of(&q), &pt.vectors_of(&q0));
        let eg = pt.gram_strain(&(y.tr_mul(&y) - y0.tr_mul(&y0)));
        for c in 0..NSTRAIN {
            assert!(
                (e[c] - eg[c]).abs() < 1e-14,
                "E[{c}]: {} vs {}",
                e[c],
                eg[c]
            );
        }
        let sigma: Strain = std::array::from_fn(|c| 0.3 * c as f64 - 1.1);
        let mut f = [0.0; NDOF_EL];
        pt.bt_sigma(&pt.vectors_of(&q), &sigma, &mut f);
        let mut kg = Sym::zeros();
        pt.geometric(&sigma, &mut kg);
        let fg = element_force(&(y * kg));
        for i in 0..NDOF_EL {
            assert!(
                (f[i] - fg[i]).abs() < 1e-13,
                "f[{i}]: {} vs {}",
                f[i],
                fg[i]
            );
        }
    }
}

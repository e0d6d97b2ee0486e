//! The element's linear map M ↦ Kg(σ(E(M))) on packed symmetric 7×7
//! matrices (a nodal Gram matrix to its geometric stiffness), stored as a
//! symmetric matrix: half the memory, and half of what the series reads
//! from memory per element and order.
//!
//! Why it is symmetric up to a diagonal scaling: with m the packed Gram
//! matrix (entries M_ab, a ≤ b), every strain component is E_c = Σ_k A_ck
//! m_k (kinematics::Point::gram_strain), the stresses are σ = D A m with D
//! symmetric (material, ANS as an interpolation and its transpose, EAS
//! condensation), and Kg_ab = Σ_c σ_c (∂E_c/∂M_ab + ∂E_c/∂M_ba), which in
//! packed form is S Aᵀ σ with S = 2 on the diagonal pairs (a = b) and 1
//! elsewhere. So K = S P with P = Aᵀ D A symmetric (measured on a distorted
//! element: K_ij / s_i − K_ji / s_j ≤ 2e-16 of max |K|).

use super::kinematics::{NSYM, PackedSym, SYM_PAIRS};
use nalgebra::SMatrix;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// Maps within this [`GeometricMap::distance`] of each other are one map.
/// Congruent elements (a structured strip: every element the same
/// rectangle) give maps that differ by the round-off of building them from
/// translated coordinates, 2e-13 on the 400×40 strip.
pub const SHARE_TOL: f64 = 1e-12;

/// Bucket key: the scaled entries ([`GeometricMap::scaled`]) rounded to
/// 2^-30 and hashed (FNV-1a), so that maps within [`SHARE_TOL`] nearly
/// always share a bucket (one straddling a rounding boundary only misses
/// the sharing; a collision only costs a comparison).
fn key(map: &GeometricMap) -> u64 {
    map.scaled()
        .map(|v| (v * f64::powi(2.0, 30)).round() as i64 as u64)
        .fold(0xcbf2_9ce4_8422_2325, |h, q| {
            (h ^ q).wrapping_mul(0x0000_0100_0000_01b3)
        })
}

/// One copy of equal maps: every map becomes the first earlier map within
/// [`SHARE_TOL`] of it, and only those first ones are allocated. The series
/// stream each element's map once per order; shared, the few distinct maps
/// stay in cache, and a million unknowns hold 0.5 GB less. Returns the maps
/// and the number of distinct ones.
pub fn share(maps: Vec<GeometricMap>) -> (Vec<Arc<GeometricMap>>, usize) {
    let keys: Vec<u64> = maps.par_iter().with_min_len(256).map(key).collect();
    let mut buckets: HashMap<u64, Vec<Arc<GeometricMap>>> = HashMap::new();
    let mut distinct = 0;
    let shared = maps
        .iter()
        .zip(keys)
        .map(|(map, key)| {
            let bucket = buckets.entry(key).or_default();
            match bucket.iter().find(|m| m.distance(map) <= SHARE_TOL) {
                Some(m) => Arc::clone(m),
                None => {
                    let m = Arc::new(map.clone());
                    bucket.push(Arc::clone(&m));
                    distinct += 1;
                    m
                }
            }
        })
        .collect();
    (shared, distinct)
}

/// Stored entries: the upper triangle of P.
const NPACKED: usize = NSYM * (NSYM + 1) / 2;

/// S, the packing weight of entry k: 2 for a diagonal pair (a, a).
pub(crate) const fn weight(k: usize) -> f64 {
    if SYM_PAIRS[k].0 == SYM_PAIRS[k].1 {
        2.0
    } else {
        1.0
    }
}

/// K = S P with P symmetric, P's upper triangle stored column by column
/// (column j: P_0j … P_jj, contiguous).
#[derive(Clone)]
pub struct GeometricMap {
    p: [f64; NPACKED],
}

impl GeometricMap {
    /// From the full map K, its columns the images of the unit packed
    /// matrices. P = S⁻¹ K is symmetrized (its two triangles agree to
    /// round-off, see the module note).
    pub fn from_full(k: &SMatrix<f64, NSYM, NSYM>) -> Self {
        let mut p = [0.0; NPACKED];
        let mut n = 0;
        for j in 0..NSYM {
            for i in 0..=j {
                p[n] = 0.5 * (k[(i, j)] / weight(i) + k[(j, i)] / weight(j));
                n += 1;
            }
        }
        Self { p }
    }

    /// K a and K b with one pass over the stored entries (the series needs
    /// two images per order: the completed order and the next right-hand
    /// side). Column j of the triangle adds a_j P_{0..j, j} to rows 0..j
    /// (above the diagonal) and its dot product with a_{0..j} to row j
    /// (below it, by symmetry).
    pub fn apply_pair(&self, a: &PackedSym, b: &PackedSym) -> (PackedSym, PackedSym) {
        // a and b side by side: every stored entry multiplies a pair.
        let ab: [[f64; 2]; NSYM] = std::array::from_fn(|j| [a[j], b[j]]);
        let mut k = [[0.0; 2]; NSYM];
        for j in 0..NSYM {
            let off = j * (j + 1) / 2;
            let col = &self.p[off..off + j + 1];
            let abj = ab[j];
            let mut below = [0.0; 2];
            for i in 0..j {
                let c = col[i];
                k[i][0] += c * abj[0];
                k[i][1] += c * abj[1];
                below[0] += c * ab[i][0];
                below[1] += c * ab[i][1];
            }
            k[j][0] += below[0] + col[j] * abj[0];
            k[j][1] += below[1] + col[j] * abj[1];
        }
        (
            PackedSym::from_fn(|i, _| weight(i) * k[i][0]),
            PackedSym::from_fn(|i, _| weight(i) * k[i][1]),
        )
    }

    /// P_ij / sqrt(P_ii P_jj) over the stored entries: P = Aᵀ D A is
    /// positive semidefinite, so these are at most 1 in magnitude, and the
    /// bending entries (t³/12) are measured against bending, not membrane.
    fn scaled(&self) -> impl Iterator<Item = f64> + '_ {
        self.p.iter().zip(self.scales()).map(|(v, s)| v / s)
    }

    /// sqrt(P_ii P_jj) of each stored entry P_ij (at least the smallest
    /// positive number).
    fn scales(&self) -> impl Iterator<Item = f64> + '_ {
        let diag = |j: usize| self.p[j * (j + 1) / 2 + j].abs();
        (0..NSYM)
            .flat_map(|j| (0..=j).map(move |i| (i, j)))
            .map(move |(i, j)| (diag(i) * diag(j)).sqrt().max(f64::MIN_POSITIVE))
    }

    /// Largest |P_ij − Q_ij| / sqrt(P_ii P_jj).
    pub fn distance(&self, other: &Self) -> f64 {
        self.p
            .iter()
            .zip(&other.p)
            .zip(self.scales())
            .map(|((p, q), s)| (p - q).abs() / s)
            .fold(0.0, f64::max)
    }

    /// Prefetches the stored entries (fe::prefetch).
    pub fn prefetch(&self) {
        crate::fe::prefetch::prefetch(&self.p);
    }

    /// K m.
    pub fn apply(&self, m: &PackedSym) -> PackedSym {
        self.apply_pair(m, &PackedSym::zeros()).0
    }

    /// The full map K (the tangent reads its columns).
    pub fn full(&self) -> SMatrix<f64, NSYM, NSYM> {
        let mut k = SMatrix::<f64, NSYM, NSYM>::zeros();
        let mut n = 0;
        for j in 0..NSYM {
            for i in 0..=j {
                k[(i, j)] = weight(i) * self.p[n];
                k[(j, i)] = weight(j) * self.p[n];
                n += 1;
            }
        }
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map K = S P from a random-looking symmetric P: stored and applied,
    /// it gives the products of the full matrix.
    #[test]
    fn packed_map_applies_as_the_full_matrix() {
        let p = SMatrix::<f64, NSYM, NSYM>::from_fn(|i, j| {
            let (a, b) = (i.min(j) as f64, i.max(j) as f64);
            (0.37 * a + 1.1 * b).sin() + if i == j { 3.0 } else { 0.0 }
        });
        let k = SMatrix::<f64, NSYM, NSYM>::from_fn(|i, j| weight(i) * p[(i, j)]);
        let map = GeometricMap::from_full(&k);
        assert_eq!(map.full(), k);
        let a = PackedSym::from_fn(|i, _| (0.3 * i as f64).cos());
        let b = PackedSym::from_fn(|i, _| (0.7 * i as f64 + 0.2).sin());
        let (ka, kb) = map.apply_pair(&a, &b);
        let scale = (k * a).norm();
        assert!((ka - k * a).norm() <= 1e-14 * scale);
        assert!((kb - k * b).norm() <= 1e-14 * (k * b).norm());
        assert!((map.apply(&a) - k * a).norm() <= 1e-14 * scale);
    }

    /// Elements of a structured strip (the same rectangle translated) share
    /// one map; a distorted element, a thicker one, or one of another
    /// material keeps its own. The shared map is within SHARE_TOL of each
    /// element's own.
    #[test]
    fn congruent_elements_share_one_map_and_others_keep_theirs() {
        use crate::shell::kinematics::Vec3;
        use crate::shell::{Material, ShellElement};
        let steel = Material {
            young: 2e11,
            poisson: 0.3,
        };
        let soft = Material {
            young: 7e10,
            poisson: 0.33,
        };
        let d = [Vec3::new(0.0, 0.0, 1.0); 4];
        let quad = |x0: f64, y0: f64, skew: f64, t: f64, m: &Material| {
            let x = [
                Vec3::new(x0, y0, 0.0),
                Vec3::new(x0 + 0.005, y0, 0.0),
                Vec3::new(x0 + 0.005 + skew, y0 + 0.005, 0.0),
                Vec3::new(x0, y0 + 0.005, 0.0),
            ];
            ShellElement::new(0, [0, 1, 2, 3], &x, &d, t, m).expect("element")
        };
        let mut elements = vec![];
        for i in 0..40 {
            for j in 0..4 {
                elements.push(quad(
                    0.005 * i as f64 + 0.3,
                    0.005 * j as f64 - 0.01,
                    0.0,
                    8e-4,
                    &steel,
                ));
            }
        }
        let own: Vec<_> = elements.iter().map(|e| Arc::clone(e.map())).collect();
        elements.push(quad(0.1, 0.0, 1e-4, 8e-4, &steel));
        elements.push(quad(0.1, 0.0, 0.0, 9e-4, &steel));
        elements.push(quad(0.1, 0.0, 0.0, 8e-4, &soft));
        let (maps, distinct) = share(elements.iter().map(|e| (**e.map()).clone()).collect());
        assert_eq!(distinct, 4);
        for (m, o) in maps.iter().zip(&own) {
            assert!(Arc::ptr_eq(m, &maps[0]));
            assert!(m.distance(o) <= SHARE_TOL);
        }
        for m in &maps[160..] {
            assert!(!Arc::ptr_eq(m, &maps[0]));
            assert!(m.distance(&maps[0]) > 1e3 * SHARE_TOL);
        }
    }
}

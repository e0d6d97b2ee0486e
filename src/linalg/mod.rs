//! Factorize once, solve many: the linear algebra an ANM step needs.
//!
//! Sparse tangents are assembled into a [`SparseMatrix`] (values in the
//! assembler's fixed [`Structure`], or free triplets for small problems) and
//! factored by a [`LinearSolver`]: faer's supernodal LDLᵀ / LBLᵀ for
//! symmetric tangents (with their inertia), faer's sparse LU otherwise, each
//! factorization checked by its backward error (`solver.rs`). The pattern's
//! ordering and symbolic analysis are kept while the pattern stays the same.
//! Systems of a few unknowns (the friction DAEs) use the dense [`DenseLu`].

mod dense_lu;
pub mod eigen;
mod lu;
pub mod matrix_market;
#[cfg(feature = "mumps")]
pub mod mpi;
#[cfg(feature = "mumps")]
pub mod mumps;
mod solver;
mod sparse_matrix;
mod split;
mod symmetric;

pub use dense_lu::DenseLu;
pub use solver::{
    BACKWARD_ERROR_LIMIT, Backend, Choice, Factorization, LinearSolver, SYMMETRY_TOLERANCE,
    SolverStats, is_symmetric,
};
pub use sparse_matrix::{ColumnBlock, SparseMatrix, Structure};

/// Euclidean inner product.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Euclidean norm. The plain sum of squares overflows once an entry passes
/// 1.3e154 (high-order series terms do: plate-cylinder at order 40 has
/// |U_39| ~ 1e148 with entries beyond that), and underflows below 1e-154;
/// there the vector is scaled by its largest entry first. Elsewhere the
/// result is the plain sqrt(a.a), bit for bit.
pub fn norm(a: &[f64]) -> f64 {
    let s = dot(a, a);
    if s.is_finite() && s >= f64::MIN_POSITIVE {
        return s.sqrt();
    }
    let m = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 || !m.is_finite() || s.is_nan() {
        return if s.is_nan() { f64::NAN } else { m };
    }
    m * a.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norm_neither_overflows_nor_underflows() {
        assert_eq!(norm(&[3.0, 4.0]), 5.0);
        assert_eq!(norm(&[]), 0.0);
        assert_eq!(norm(&[0.0, 0.0]), 0.0);
        let big = norm(&[3e200, 4e200]);
        assert!((big / 5e200 - 1.0).abs() < 1e-15, "{big}");
        let small = norm(&[3e-200, 4e-200]);
        assert!((small / 5e-200 - 1.0).abs() < 1e-15, "{small}");
        assert_eq!(norm(&[1.0, f64::INFINITY]), f64::INFINITY);
        assert!(norm(&[1.0, f64::NAN]).is_nan());
    }

    #[test]
    fn solves_small_system_and_reuses_symbolic() {
        let a = SparseMatrix::from_dense(&[
            vec![4.0, 1.0, 0.0],
            vec![1.0, 3.0, 1.0],
            vec![0.0, 1.0, 2.0],
        ]);
        let mut lu = LinearSolver::default();
        let f = lu.factorize(&a).unwrap();
        let x = f.solve(&[1.0, 2.0, 3.0]);
        let r = a.mul_vec(&x);
        for (ri, bi) in r.iter().zip([1.0, 2.0, 3.0]) {
            assert!((ri - bi).abs() < 1e-14);
        }
        let f2 = lu.factorize(&a).unwrap();
        assert_eq!(f2.solve(&[1.0, 2.0, 3.0]), x);
    }

    #[test]
    fn duplicates_are_summed_and_a_new_pattern_is_detected() {
        // 2 x 2 with the (0, 0) entry split in two triplets.
        let mut a = SparseMatrix::new(2);
        a.add(0, 0, 1.0);
        a.add(1, 1, 2.0);
        a.add(0, 0, 1.0);
        let mut lu = LinearSolver::default();
        assert_eq!(lu.factorize(&a).unwrap().solve(&[2.0, 2.0]), vec![1.0, 1.0]);
        // Same values, another order and an extra off-diagonal entry: a new
        // pattern.
        let mut b = SparseMatrix::new(2);
        b.add(1, 1, 2.0);
        b.add(0, 0, 2.0);
        b.add(1, 0, 1.0);
        let x = lu.factorize(&b).unwrap().solve(&[2.0, 3.0]);
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
        // Back to the first pattern: analysed again.
        let x = lu.factorize(&a).unwrap().solve(&[2.0, 2.0]);
        assert_eq!(x, vec![1.0, 1.0]);
        assert_eq!(lu.stats().analyses, 3);
    }
}

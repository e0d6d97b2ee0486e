//! Factorize once, solve many: the linear algebra an ANM step needs.
//!
//! Sparse matrices are assembled as triplets (duplicates summed) and factored
//! by faer's sparse LU. The symbolic analysis depends only on the pattern,
//! which is fixed for a mesh, so [`SparseLu`] keeps it and reuses it for every
//! later numeric factorization. Systems of a few unknowns use the dense
//! [`DenseLu`].

mod dense_lu;
pub use dense_lu::DenseLu;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};

/// A square sparse matrix under assembly.
#[derive(Clone, Debug, Default)]
pub struct SparseMatrix {
    pub n: usize,
    pub entries: Vec<Triplet<usize, usize, f64>>,
}

impl SparseMatrix {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            entries: Vec::new(),
        }
    }

    /// Adds `value` at (row, col); repeated entries are summed.
    pub fn add(&mut self, row: usize, col: usize, value: f64) {
        self.entries.push(Triplet::new(row, col, value));
    }

    /// A dense row-major matrix as sparse (small problems and tests).
    pub fn from_dense(rows: &[Vec<f64>]) -> Self {
        let mut m = Self::new(rows.len());
        for (i, row) in rows.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                if v != 0.0 || i == j {
                    m.add(i, j, v);
                }
            }
        }
        m
    }

    /// y = A x.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for t in &self.entries {
            y[t.row] += t.val * x[t.col];
        }
        y
    }

    fn to_csc(&self) -> Result<SparseColMat<usize, f64>, String> {
        SparseColMat::try_new_from_triplets(self.n, self.n, &self.entries)
            .map_err(|e| format!("{e:?}"))
    }
}

/// Sparse LU with the symbolic analysis kept across factorizations.
#[derive(Default)]
pub struct SparseLu {
    symbolic: Option<(usize, usize, SymbolicLu<usize>)>,
}

/// A numeric factorization, ready for any number of solves.
pub struct Factorization {
    lu: Lu<usize, f64>,
    n: usize,
}

impl SparseLu {
    pub fn new() -> Self {
        Self::default()
    }

    /// Factorizes `a`; reuses the symbolic analysis when the pattern size is
    /// unchanged (the pattern itself is fixed by the mesh). Returns a message
    /// describing the failure, for the caller to wrap with step and lambda.
    pub fn factorize(&mut self, a: &SparseMatrix) -> Result<Factorization, String> {
        let csc = a.to_csc()?;
        let key = (a.n, csc.compute_nnz());
        let symbolic = match &self.symbolic {
            Some((n, nnz, s)) if (*n, *nnz) == key => s.clone(),
            _ => {
                let s = SymbolicLu::try_new(csc.symbolic()).map_err(|e| format!("{e:?}"))?;
                self.symbolic = Some((key.0, key.1, s.clone()));
                s
            }
        };
        let lu = Lu::try_new_with_symbolic(symbolic, csc.as_ref()).map_err(|e| format!("{e:?}"))?;
        Ok(Factorization { lu, n: a.n })
    }
}

impl Factorization {
    /// Solves A x = b. Non-finite entries in x mean A is (numerically) singular.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut rhs = faer::Mat::<f64>::from_fn(self.n, 1, |i, _| b[i]);
        self.lu.solve_in_place(rhs.as_mut());
        (0..self.n).map(|i| rhs[(i, 0)]).collect()
    }
}

/// Euclidean inner product.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Euclidean norm.
pub fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_small_system_and_reuses_symbolic() {
        let a = SparseMatrix::from_dense(&[
            vec![4.0, 1.0, 0.0],
            vec![1.0, 3.0, 1.0],
            vec![0.0, 1.0, 2.0],
        ]);
        let mut lu = SparseLu::new();
        let f = lu.factorize(&a).unwrap();
        let x = f.solve(&[1.0, 2.0, 3.0]);
        let r = a.mul_vec(&x);
        for (ri, bi) in r.iter().zip([1.0, 2.0, 3.0]) {
            assert!((ri - bi).abs() < 1e-14);
        }
        let f2 = lu.factorize(&a).unwrap();
        assert_eq!(f2.solve(&[1.0, 2.0, 3.0]), x);
    }
}

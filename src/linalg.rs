//! Factorize once, solve many: the linear algebra an ANM step needs.
//!
//! Sparse matrices are assembled as triplets (duplicates summed) and factored
//! by faer's sparse LU. Assembly visits the same (row, col) sequence for a
//! given mesh and active contact set, so [`SparseLu`] keeps, for the last
//! sequence seen, the compressed-column pattern, the slot of every triplet in
//! it (a scatter map) and the symbolic analysis: a later factorization with
//! the same sequence only scatters the values (no sort) and runs the numeric
//! phase. A new sequence whose positions all lie in the kept pattern (a
//! contact pair adds entries inside its node's diagonal block, which the
//! elements already fill) only gets a new scatter map, by binary search in
//! the columns; the symbolic analysis is kept.
//!
//! Measured on the plate-cylinder tangent (360 dofs, 6-dof nodal blocks),
//! faer's automatic choice takes the simplicial (column-by-column) LU; the
//! supernodal LU works on dense nodal blocks and is several times faster, so
//! it is forced. Both run sequentially: the systems are far too small for
//! threads to pay, and the machine is shared. Systems of a few unknowns
//! (the friction DAEs) use the dense [`DenseLu`].

mod dense_lu;
pub use dense_lu::DenseLu;
#[cfg(feature = "mumps")]
pub mod mpi;
#[cfg(feature = "mumps")]
pub mod mumps;

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{
    LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, Triplet};
use faer::{Conj, MatMut, Par};

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

    /// True if `self` lists its triplets at the positions of `pattern`, in
    /// the same order.
    fn matches(&self, pattern: &Pattern) -> bool {
        self.n == pattern.n
            && self.entries.len() == pattern.coords.len()
            && self
                .entries
                .iter()
                .zip(&pattern.coords)
                .all(|(t, &(r, c))| t.row == r && t.col == c)
    }
}

/// Compressed-column pattern of a triplet sequence, with its symbolic LU.
struct Pattern {
    n: usize,
    /// (row, col) of every triplet, in assembly order.
    coords: Vec<(usize, usize)>,
    /// Value slot of every triplet in the compressed columns.
    scatter: Vec<usize>,
    csc: SymbolicSparseColMat<usize>,
    symbolic: Arc<SymbolicLu<usize>>,
}

impl Pattern {
    /// The slot of (row, col) in the compressed columns, if present.
    fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let start = self.csc.col_ptr()[col];
        let rows = &self.csc.row_idx()[start..self.csc.col_ptr()[col + 1]];
        rows.binary_search(&row).ok().map(|k| start + k)
    }

    /// The same pattern for another triplet sequence, if all its positions
    /// are in it: only the scatter map changes.
    fn remap(&mut self, a: &SparseMatrix) -> bool {
        if a.n != self.n {
            return false;
        }
        let scatter: Option<Vec<usize>> = a
            .entries
            .iter()
            .map(|t| {
                if t.row < a.n && t.col < a.n {
                    self.slot(t.row, t.col)
                } else {
                    None
                }
            })
            .collect();
        let Some(scatter) = scatter else {
            return false;
        };
        self.coords = a.entries.iter().map(|t| (t.row, t.col)).collect();
        self.scatter = scatter;
        true
    }

    /// Sorts the triplets by (col, row) once, merges duplicates and runs the
    /// symbolic analysis (fill-reducing ordering, supernodes).
    fn new(a: &SparseMatrix) -> Result<Self, String> {
        let n = a.n;
        if let Some(t) = a.entries.iter().find(|t| t.row >= n || t.col >= n) {
            return Err(format!(
                "entry ({}, {}) outside the {n} x {n} matrix",
                t.row, t.col
            ));
        }
        let coords: Vec<(usize, usize)> = a.entries.iter().map(|t| (t.row, t.col)).collect();
        let mut order: Vec<usize> = (0..coords.len()).collect();
        order.sort_unstable_by_key(|&k| (coords[k].1, coords[k].0));
        let mut scatter = vec![0; coords.len()];
        let mut col_ptr = vec![0; n + 1];
        let mut row_idx: Vec<usize> = Vec::new();
        let mut last = None;
        for &k in &order {
            let (r, c) = coords[k];
            if last != Some((r, c)) {
                row_idx.push(r);
                col_ptr[c + 1] += 1;
                last = Some((r, c));
            }
            scatter[k] = row_idx.len() - 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let csc = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(csc.as_ref(), params).map_err(|e| format!("{e:?}"))?;
        Ok(Self {
            n,
            coords,
            scatter,
            csc,
            symbolic: Arc::new(symbolic),
        })
    }
}

/// Sparse LU with the pattern and symbolic analysis kept across
/// factorizations.
#[derive(Default)]
pub struct SparseLu {
    pattern: Option<Pattern>,
    /// Scratch of the numeric factorization, kept between calls.
    scratch: Option<MemBuffer>,
}

/// A numeric factorization, ready for any number of solves.
pub struct Factorization {
    symbolic: Arc<SymbolicLu<usize>>,
    numeric: NumericLu<usize, f64>,
    n: usize,
}

impl SparseLu {
    pub fn new() -> Self {
        Self::default()
    }

    /// Factorizes `a`. The pattern (and symbolic analysis) of the previous
    /// call is reused when `a` lists its triplets at the same positions in
    /// the same order, or at positions all inside it (new scatter map);
    /// otherwise it is rebuilt. Returns a message describing
    /// the failure, for the caller to wrap with step and lambda.
    pub fn factorize(&mut self, a: &SparseMatrix) -> Result<Factorization, String> {
        let known = match &mut self.pattern {
            Some(p) => a.matches(p) || p.remap(a),
            None => false,
        };
        if !known {
            self.pattern = Some(Pattern::new(a)?);
            self.scratch = None;
        }
        let pattern = self.pattern.as_ref().expect("pattern set above");
        let mut values = vec![0.0; pattern.csc.row_idx().len()];
        for (t, &slot) in a.entries.iter().zip(&pattern.scatter) {
            values[slot] += t.val;
        }
        let symbolic = &pattern.symbolic;
        let scratch = self.scratch.get_or_insert_with(|| {
            MemBuffer::new(
                symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            )
        });
        let mut numeric = NumericLu::new();
        symbolic
            .factorize_numeric_lu(
                &mut numeric,
                SparseColMatRef::new(pattern.csc.as_ref(), &values),
                Par::Seq,
                MemStack::new(scratch),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        Ok(Factorization {
            symbolic: Arc::clone(symbolic),
            numeric,
            n: a.n,
        })
    }
}

impl Factorization {
    /// Solves A x = b. Non-finite entries in x mean A is (numerically) singular.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        let mut scratch = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x, self.n, 1),
            Par::Seq,
            MemStack::new(&mut scratch),
        );
        x
    }
}

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

    #[test]
    fn duplicates_are_summed_and_a_new_pattern_is_detected() {
        // 2 x 2 with the (0, 0) entry split in two triplets.
        let mut a = SparseMatrix::new(2);
        a.add(0, 0, 1.0);
        a.add(1, 1, 2.0);
        a.add(0, 0, 1.0);
        let mut lu = SparseLu::new();
        assert_eq!(lu.factorize(&a).unwrap().solve(&[2.0, 2.0]), vec![1.0, 1.0]);
        // Same values, another order and an extra off-diagonal entry: a new
        // pattern.
        let mut b = SparseMatrix::new(2);
        b.add(1, 1, 2.0);
        b.add(0, 0, 2.0);
        b.add(1, 0, 1.0);
        let x = lu.factorize(&b).unwrap().solve(&[2.0, 3.0]);
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
        // A sequence inside that pattern (the (1, 0) slot left zero): remapped.
        let x = lu.factorize(&a).unwrap().solve(&[2.0, 2.0]);
        assert_eq!(x, vec![1.0, 1.0]);
    }
}

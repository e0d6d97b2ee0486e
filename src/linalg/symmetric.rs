//! Symmetric factorizations of a symmetric tangent with faer's supernodal
//! Cholesky codes, after an AMD ordering: LDLᵀ without pivoting, and the
//! intranode LBLᵀ (Bunch–Kaufman pivoting inside each supernode, 1×1 and
//! 2×2 blocks) for indefinite matrices where LDLᵀ meets a tiny pivot.
//!
//! Only the lower triangle of the compressed columns is read. Both give the
//! inertia (Sylvester's law: the signs of the blocks of D are those of the
//! eigenvalues of A), which the engine reads as the number of negative
//! pivots.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::supernodal::{
    SupernodalIntranodeLbltRef, SupernodalLdltRef, SymbolicSupernodalCholesky,
};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, IntranodeLbltRef, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::sparse_matrix::Structure;

/// The symbolic analysis (AMD ordering, supernodes) of a symmetric pattern.
pub struct SymmetricSymbolic {
    symbolic: SymbolicCholesky<usize>,
}

impl SymmetricSymbolic {
    pub fn new(s: &Structure) -> Result<Self, String> {
        let a = SymbolicSparseColMatRef::new_checked(s.n(), s.n(), s.col_ptr(), None, s.row_idx());
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(a, Side::Lower, SymmetricOrdering::Amd, params)
            .map_err(|e| format!("symbolic analysis: {e:?}"))?;
        Ok(Self { symbolic })
    }

    /// Entries of the factor L.
    pub fn factor_entries(&self) -> usize {
        self.symbolic.len_val()
    }
}

/// Which symmetric factorization.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pivoting {
    /// LDLᵀ, no pivoting.
    None,
    /// Intranode Bunch–Kaufman LBLᵀ.
    BunchKaufman,
}

/// A numeric LDLᵀ or LBLᵀ factorization.
pub struct SymmetricFactor {
    pivoting: Pivoting,
    values: Vec<f64>,
    /// LBLᵀ only: the subdiagonal of B (non-zero at the first row of a 2×2
    /// block) and the pivoting permutation.
    subdiag: Vec<f64>,
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
}

fn matrix<'a>(s: &'a Structure, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
    SparseColMatRef::new(
        SymbolicSparseColMatRef::new_checked(s.n(), s.n(), s.col_ptr(), None, s.row_idx()),
        values,
    )
}

impl SymmetricFactor {
    /// Factorizes the lower triangle of (s, values).
    pub fn new(
        sym: &SymmetricSymbolic,
        s: &Structure,
        values: &[f64],
        pivoting: Pivoting,
        par: Par,
    ) -> Result<Self, String> {
        let n = s.n();
        let a = matrix(s, values);
        let mut l = vec![0.0; sym.symbolic.len_val()];
        match pivoting {
            Pivoting::None => {
                let req = sym
                    .symbolic
                    .factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
                let mut mem = MemBuffer::try_new(req).map_err(|_| "out of memory".to_string())?;
                sym.symbolic
                    .factorize_numeric_ldlt(
                        &mut l,
                        a,
                        Side::Lower,
                        Default::default(),
                        par,
                        MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .map_err(|e| format!("LDLᵀ: {e:?}"))?;
                Ok(Self {
                    pivoting,
                    values: l,
                    subdiag: vec![],
                    perm_fwd: vec![],
                    perm_inv: vec![],
                })
            }
            Pivoting::BunchKaufman => {
                let req = sym
                    .symbolic
                    .factorize_numeric_intranode_lblt_scratch::<f64>(par, Default::default());
                let mut mem = MemBuffer::try_new(req).map_err(|_| "out of memory".to_string())?;
                let mut subdiag = vec![0.0; n];
                let mut perm_fwd = vec![0; n];
                let mut perm_inv = vec![0; n];
                sym.symbolic.factorize_numeric_intranode_lblt(
                    &mut l,
                    &mut subdiag,
                    &mut perm_fwd,
                    &mut perm_inv,
                    a,
                    Side::Lower,
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                );
                Ok(Self {
                    pivoting,
                    values: l,
                    subdiag,
                    perm_fwd,
                    perm_inv,
                })
            }
        }
    }

    /// Solves A x = b in place.
    pub fn solve_in_place(&self, sym: &SymmetricSymbolic, x: &mut [f64], par: Par) {
        let n = x.len();
        let mut mem = MemBuffer::new(sym.symbolic.solve_in_place_scratch::<f64>(1, par));
        let stack = MemStack::new(&mut mem);
        let rhs = MatMut::from_column_major_slice_mut(x, n, 1);
        match self.pivoting {
            Pivoting::None => LdltRef::new(&sym.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                stack,
            ),
            Pivoting::BunchKaufman => IntranodeLbltRef::new(
                &sym.symbolic,
                &self.values,
                &self.subdiag,
                PermRef::new_checked(&self.perm_fwd, &self.perm_inv, n),
            )
            .solve_in_place_with_conj(Conj::No, rhs, par, stack),
        }
    }

    /// (negative, zero, positive) eigenvalue counts of A, from the blocks of
    /// D (a 2×2 block with a negative determinant holds one of each sign).
    pub fn inertia(&self, sym: &SymmetricSymbolic) -> (usize, usize, usize) {
        let mut d = Vec::with_capacity(sym.symbolic.nrows());
        let sn: &SymbolicSupernodalCholesky<usize> = match sym.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            // faer keeps a simplicial factor where AMD predicts no
            // elimination work (a diagonal pattern), whatever the threshold:
            // unpivoted, D first in each column of L.
            SymbolicCholeskyRaw::Simplicial(s) => {
                d.extend(s.col_ptr()[..s.nrows()].iter().map(|&k| self.values[k]));
                return Self::count(&d, &[]);
            }
        };
        for k in 0..sn.n_supernodes() {
            let block = match self.pivoting {
                Pivoting::None => SupernodalLdltRef::new(sn, &self.values).supernode(k).val(),
                Pivoting::BunchKaufman => SupernodalIntranodeLbltRef::new(
                    sn,
                    &self.values,
                    &self.subdiag,
                    PermRef::new_checked(&self.perm_fwd, &self.perm_inv, self.perm_fwd.len()),
                )
                .supernode(k)
                .val(),
            };
            d.extend((0..block.ncols()).map(|j| block[(j, j)]));
        }
        Self::count(&d, &self.subdiag)
    }

    /// Inertia of the block diagonal (d, subdiag).
    fn count(d: &[f64], subdiag: &[f64]) -> (usize, usize, usize) {
        let mut counts = (0, 0, 0);
        let mut count = |v: f64| match v.partial_cmp(&0.0) {
            Some(std::cmp::Ordering::Less) => counts.0 += 1,
            Some(std::cmp::Ordering::Greater) => counts.2 += 1,
            _ => counts.1 += 1,
        };
        let mut i = 0;
        while i < d.len() {
            let s = subdiag.get(i).copied().unwrap_or(0.0);
            if s != 0.0 && i + 1 < d.len() {
                let det = d[i] * d[i + 1] - s * s;
                if det < 0.0 {
                    count(-1.0);
                    count(1.0);
                } else {
                    // Both eigenvalues have the sign of the trace.
                    count(det.signum() * (d[i] + d[i + 1]));
                    count(det.signum() * (d[i] + d[i + 1]));
                }
                i += 2;
            } else {
                count(d[i]);
                i += 1;
            }
        }
        counts
    }
}

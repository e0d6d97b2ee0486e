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
use faer::sparse::linalg::cholesky::supernodal::{
    SupernodalIntranodeLbltRef, SupernodalLdltRef, SymbolicSupernodalCholesky,
};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, IntranodeLbltRef, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, amd};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::sparse_matrix::Structure;

/// The symbolic analysis of a symmetric pattern: the AMD ordering P, the
/// lower triangle of P A Pᵀ (the slots of A it gathers), and the supernodes
/// of that permuted matrix.
///
/// faer's factorization with an ordering permutes A into a new matrix at
/// every numeric factorization (a counting pass and a scatter over all the
/// entries) and checks the index arrays of A each time; here the permuted
/// pattern is built and checked once, and a factorization gathers the
/// values of its lower triangle through a slot map. The factor is the same,
/// bit for bit: the same ordering, the same supernodes, each entry of A
/// added once into the same zeroed block.
pub struct SymmetricSymbolic {
    /// Supernodes of the permuted matrix (identity ordering).
    symbolic: SymbolicCholesky<usize>,
    /// fwd[i]: the unknown of A at position i of the permuted matrix.
    fwd: Vec<usize>,
    /// Lower triangle of P A Pᵀ, rows sorted within each column.
    lower: SymbolicSparseColMat<usize>,
    /// For each slot of `lower`, the slot of A it takes its value from
    /// (32 bits: 0.1 GB less at a million unknowns).
    gather: Vec<u32>,
}

/// The values of the last symmetric factors dropped in this process, which
/// the next factorizations that fit in them reuse: a fresh factor's pages
/// are faulted in and zeroed by the kernel before faer zeroes them (measured
/// 7% of the factorization at 98,400 unknowns). Shared by all solvers, so
/// that a solver that keeps its analysis holds no factor while another
/// factorizes (the peak of the run stays one factor); two buffers, for the
/// two halves of a split factorization (`split.rs`).
static SPARE_FACTORS: Mutex<Vec<Vec<f64>>> = Mutex::new(Vec::new());

/// How many dropped factors are kept.
const SPARES: usize = 2;

/// A buffer of `len` values, the smallest spare that is large enough. Its
/// values are left as they are: faer's numeric factorizations zero the
/// factor themselves (a second memset of the whole factor otherwise).
fn factor_buffer(len: usize) -> Vec<f64> {
    let spare = SPARE_FACTORS.lock().ok().and_then(|mut spares| {
        let best = (0..spares.len())
            .filter(|&i| spares[i].capacity() >= len)
            .min_by_key(|&i| spares[i].capacity())?;
        Some(spares.swap_remove(best))
    });
    match spare {
        Some(mut v) => {
            v.truncate(len);
            v.resize(len, 0.0);
            v
        }
        None => vec![0.0; len],
    }
}

/// The values the spares may hold in all: about those of the last
/// factorization (one whole factor, or the two halves of a split one), so
/// that two whole factors are never kept.
static SPARE_BUDGET: AtomicUsize = AtomicUsize::new(usize::MAX);

/// Sets the spares' budget to the `values` of a factorization about to be
/// made (a quarter more is allowed: a reused buffer keeps its capacity).
pub fn set_spare_budget(values: usize) {
    SPARE_BUDGET.store(values.saturating_add(values / 4), Ordering::Relaxed);
}

/// Keeps `values` as a spare factor: the smallest spares go while there
/// are more than `SPARES` or they hold more than the budget.
fn keep_spare(values: Vec<f64>) {
    if let Ok(mut spares) = SPARE_FACTORS.lock() {
        spares.push(values);
        let budget = SPARE_BUDGET.load(Ordering::Relaxed);
        while spares.len() > SPARES || spares.iter().map(|v| v.capacity()).sum::<usize>() > budget {
            let smallest = (0..spares.len())
                .min_by_key(|&i| spares[i].capacity())
                .expect("not empty");
            spares.swap_remove(smallest);
        }
    }
}

impl SymmetricSymbolic {
    /// The analysis of the whole pattern, in faer's AMD ordering.
    pub fn new(s: &Structure) -> Result<Self, String> {
        let n = s.n();
        Self::fits_32_bits(s)?;
        let a = SymbolicSparseColMatRef::new_checked(n, n, s.col_ptr(), None, s.row_idx());
        Self::with_order(s, amd_order(a)?)
    }

    /// The map from the permuted slots to A's is 32-bit (half the memory).
    fn fits_32_bits(s: &Structure) -> Result<(), String> {
        if u32::try_from(s.nnz()).is_err() || u32::try_from(s.n()).is_err() {
            return Err(format!("{} entries: more than 32-bit slots", s.nnz()));
        }
        Ok(())
    }

    /// The analysis of the principal submatrix of A on the unknowns `fwd`,
    /// in that order (`fwd[i]`: the unknown of A at position i).
    pub fn with_order(s: &Structure, fwd: Vec<usize>) -> Result<Self, String> {
        Self::fits_32_bits(s)?;
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let n = fwd.len();
        let mut inv = vec![usize::MAX; s.n()];
        for (i, &k) in fwd.iter().enumerate() {
            inv[k] = i;
        }
        // The lower entries of A at (max, min) of their permuted positions,
        // gathered by columns; the full permuted pattern for the supernodes.
        let mut lower_count = vec![0usize; n + 1];
        let mut full_count = vec![0usize; n + 1];
        let moved = |k: usize, c: usize| {
            let r = s.row_idx()[k];
            (r >= c && inv[r] != usize::MAX && inv[c] != usize::MAX)
                .then(|| (inv[r].max(inv[c]), inv[r].min(inv[c])))
        };
        for c in 0..s.n() {
            for k in s.col_ptr()[c]..s.col_ptr()[c + 1] {
                if let Some((i, j)) = moved(k, c) {
                    lower_count[j + 1] += 1;
                    full_count[j + 1] += 1;
                    if i != j {
                        full_count[i + 1] += 1;
                    }
                }
            }
        }
        for j in 0..n {
            lower_count[j + 1] += lower_count[j];
            full_count[j + 1] += full_count[j];
        }
        let (lower_ptr, full_ptr) = (lower_count.clone(), full_count.clone());
        // (row << 32 | slot of A): one sort key per entry, 8 bytes.
        let mut lower_rows = vec![0u64; lower_ptr[n]];
        let mut full_rows = vec![0usize; full_ptr[n]];
        for c in 0..s.n() {
            for k in s.col_ptr()[c]..s.col_ptr()[c + 1] {
                if let Some((i, j)) = moved(k, c) {
                    lower_rows[lower_count[j]] = (i as u64) << 32 | k as u64;
                    lower_count[j] += 1;
                    full_rows[full_count[j]] = i;
                    full_count[j] += 1;
                    if i != j {
                        full_rows[full_count[i]] = j;
                        full_count[i] += 1;
                    }
                }
            }
        }
        drop((lower_count, full_count));
        for j in 0..n {
            lower_rows[lower_ptr[j]..lower_ptr[j + 1]].sort_unstable();
            full_rows[full_ptr[j]..full_ptr[j + 1]].sort_unstable();
        }
        let full = SymbolicSparseColMatRef::new_checked(n, n, &full_ptr, None, &full_rows);
        let symbolic =
            factorize_symbolic_cholesky(full, Side::Lower, SymmetricOrdering::Identity, params)
                .map_err(|e| format!("symbolic analysis: {e:?}"))?;
        drop((full_ptr, full_rows));
        // The rows in place of the keys (same size: no new buffer).
        let gather = lower_rows.iter().map(|&e| e as u32).collect();
        let row_idx = lower_rows.into_iter().map(|e| (e >> 32) as usize).collect();
        let lower = SymbolicSparseColMat::new_checked(n, n, lower_ptr, None, row_idx);
        Ok(Self {
            symbolic,
            fwd,
            lower,
            gather,
        })
    }

    /// Entries of the factor L.
    pub fn factor_entries(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Order of the matrix analysed.
    pub fn n(&self) -> usize {
        self.fwd.len()
    }

    /// The unknowns of A in the analysed order.
    pub fn order(&self) -> &[usize] {
        &self.fwd
    }

    /// The supernodes (`None` where faer kept a simplicial factor: a
    /// pattern without elimination work).
    pub fn supernodal(&self) -> Option<&SymbolicSupernodalCholesky<usize>> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => Some(s),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        }
    }
}

/// faer's AMD ordering of a symmetric pattern (both triangles stored).
pub fn amd_order(a: SymbolicSparseColMatRef<'_, usize>) -> Result<Vec<usize>, String> {
    let n = a.nrows();
    let mut fwd = vec![0usize; n];
    let mut inv = vec![0usize; n];
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
        n,
        a.compute_nnz(),
    ))
    .map_err(|_| "symbolic analysis: out of memory".to_string())?;
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        a,
        CholeskySymbolicParams::default().amd_params,
        MemStack::new(&mut mem),
    )
    .map_err(|e| format!("symbolic analysis: {e:?}"))?;
    Ok(fwd)
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

impl SymmetricFactor {
    /// Factorizes the lower triangle of `values`, on the pattern `sym` was
    /// analysed for.
    pub fn new(
        sym: &SymmetricSymbolic,
        values: &[f64],
        pivoting: Pivoting,
        par: Par,
    ) -> Result<Self, String> {
        let n = sym.fwd.len();
        let mut l = factor_buffer(sym.symbolic.len_val());
        let gathered: Vec<f64> = sym.gather.iter().map(|&k| values[k as usize]).collect();
        let a = SparseColMatRef::new(sym.lower.as_ref(), &gathered);
        let result = match pivoting {
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
                    .map(|_| (vec![], vec![], vec![]))
                    .map_err(|e| match e {
                        // faer counts in its fill-reducing order, from 0.
                        faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                            format!(
                                "LDLᵀ: a zero pivot at elimination step {} (of the fill-reducing order): singular, or indefinite beyond LDLᵀ without pivoting",
                                index + 1
                            )
                        }
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
                Ok((subdiag, perm_fwd, perm_inv))
            }
        };
        drop(gathered);
        let (subdiag, perm_fwd, perm_inv) = result?;
        Ok(Self {
            pivoting,
            values: l,
            subdiag,
            perm_fwd,
            perm_inv,
        })
    }

    /// The values of L (D on its diagonal for LDLᵀ), by supernodes.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Solves A x = b in place: P A Pᵀ (P x) = P b.
    pub fn solve_in_place(&self, sym: &SymmetricSymbolic, x: &mut [f64], par: Par) {
        let n = x.len();
        let mut y: Vec<f64> = sym.fwd.iter().map(|&i| x[i]).collect();
        let mut mem = MemBuffer::new(sym.symbolic.solve_in_place_scratch::<f64>(1, par));
        let stack = MemStack::new(&mut mem);
        let rhs = MatMut::from_column_major_slice_mut(&mut y, n, 1);
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
        for (&i, v) in sym.fwd.iter().zip(y) {
            x[i] = v;
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

impl Drop for SymmetricFactor {
    /// The factor's buffer becomes a spare.
    fn drop(&mut self) {
        keep_spare(std::mem::take(&mut self.values));
    }
}

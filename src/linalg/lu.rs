//! General (non-symmetric) tangents: faer's supernodal sparse LU with partial
//! pivoting, COLAMD column ordering.
//!
//! faer sizes the LU's factor from the Cholesky factor of AᵀA (an upper
//! bound for any row pivoting, George & Ng 1987). A symmetric ordering (AMD
//! on A, the LDLᵀ's) through faer's lower-level supernodal LU was tried on
//! the 98,400-unknown strip: its AᵀA-sized factor exceeded the machine's
//! 24 GiB and the process was killed, where COLAMD (which orders for AᵀA)
//! takes 3.5 GiB. So COLAMD stays; symmetric tangents go to LDLᵀ instead.
//!
//! Measured on the plate-cylinder tangent (360 dofs, 6-dof nodal blocks),
//! faer's automatic choice takes the simplicial (column-by-column) LU; the
//! supernodal LU works on dense nodal blocks and is several times faster, so
//! it is forced.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{
    LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

use super::sparse_matrix::Structure;

/// The symbolic analysis (column ordering, supernodes) of a pattern.
pub struct LuSymbolic {
    symbolic: SymbolicLu<usize>,
}

impl LuSymbolic {
    pub fn new(s: &Structure) -> Result<Self, String> {
        let a = SymbolicSparseColMatRef::new_checked(s.n(), s.n(), s.col_ptr(), None, s.row_idx());
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_lu(a, params).map_err(|e| format!("symbolic analysis: {e:?}"))?;
        Ok(Self { symbolic })
    }
}

/// A numeric LU factorization.
pub struct LuFactor {
    numeric: NumericLu<usize, f64>,
}

impl LuFactor {
    pub fn new(sym: &LuSymbolic, s: &Structure, values: &[f64], par: Par) -> Result<Self, String> {
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(s.n(), s.n(), s.col_ptr(), None, s.row_idx()),
            values,
        );
        let req = sym
            .symbolic
            .factorize_numeric_lu_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(req).map_err(|_| "out of memory".to_string())?;
        let mut numeric = NumericLu::new();
        sym.symbolic
            .factorize_numeric_lu(
                &mut numeric,
                a,
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| format!("LU: {e:?}"))?;
        Ok(Self { numeric })
    }

    /// Solves A x = b in place.
    pub fn solve_in_place(&self, sym: &LuSymbolic, x: &mut [f64], par: Par) {
        let n = x.len();
        let mut mem = MemBuffer::new(sym.symbolic.solve_in_place_scratch::<f64>(1, par));
        LuRef::new_unchecked(&sym.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            par,
            MemStack::new(&mut mem),
        );
    }
}

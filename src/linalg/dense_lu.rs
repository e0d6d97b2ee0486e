//! Dense LU with partial pivoting for systems of a handful of unknowns (the
//! DAE's dF/d(v, z), 1 to 6 unknowns), factorized once per time step and
//! solved once per series order.
//!
//! The arithmetic is nalgebra's `LU` (same pivot choice, multipliers scaled
//! by the reciprocal pivot, same update and substitution order), so results
//! are bitwise those of `DMatrix::lu`; what differs is the cost: storage is
//! reused across steps and a solve is a few loops over a flat array, where
//! the generic version spends hundreds of instructions on views and
//! iterators for a 4x4 system.

/// An LU factorization P A = L U, kept in place (column-major).
#[derive(Clone, Debug, Default)]
pub struct DenseLu {
    n: usize,
    /// L below the diagonal (unit diagonal implied), U on and above it;
    /// entry (r, c) at `c * n + r`.
    lu: Vec<f64>,
    /// Row transpositions (i, piv), applied in order.
    swaps: Vec<(usize, usize)>,
}

impl DenseLu {
    /// Factorizes the n x n matrix with entries `a(r, c)`, reusing storage.
    /// A column without a nonzero pivot candidate is left as is (its U
    /// diagonal is 0: see [`DenseLu::pivot`]).
    pub fn factorize(&mut self, n: usize, a: impl Fn(usize, usize) -> f64) {
        self.n = n;
        self.lu.clear();
        self.lu.extend((0..n * n).map(|k| a(k % n, k / n)));
        self.swaps.clear();
        let m = &mut self.lu;
        for i in 0..n {
            // First row of largest |entry| on or below the diagonal.
            let mut piv = i;
            for r in i + 1..n {
                if m[i * n + r].abs() > m[i * n + piv].abs() {
                    piv = r;
                }
            }
            let diag = m[i * n + piv];
            if diag == 0.0 {
                continue;
            }
            if piv != i {
                self.swaps.push((i, piv));
                for c in 0..n {
                    m.swap(c * n + i, c * n + piv);
                }
            }
            let inv = 1.0 / diag;
            for r in i + 1..n {
                m[i * n + r] *= inv;
            }
            for c in i + 1..n {
                let u = m[c * n + i];
                for r in i + 1..n {
                    m[c * n + r] += -u * m[i * n + r];
                }
            }
        }
    }

    /// |U_ii|, the i-th pivot's magnitude.
    pub fn pivot(&self, i: usize) -> f64 {
        self.lu[i * self.n + i].abs()
    }

    /// b <- A^-1 b; false (b partly overwritten) when a pivot is zero.
    pub fn solve_in_place(&self, b: &mut [f64]) -> bool {
        for &(i, piv) in &self.swaps {
            b.swap(i, piv);
        }
        // A constant size lets the compiler unroll the substitutions of the
        // tiny systems (a general loop costs ~400 instructions at n = 4).
        match self.n {
            1 => substitute(1, &self.lu, b),
            2 => substitute(2, &self.lu, b),
            3 => substitute(3, &self.lu, b),
            4 => substitute(4, &self.lu, b),
            5 => substitute(5, &self.lu, b),
            6 => substitute(6, &self.lu, b),
            n => substitute(n, &self.lu, b),
        }
    }
}

/// Forward (unit L) then backward (U) substitution, column by column.
#[inline(always)]
fn substitute(n: usize, lu: &[f64], b: &mut [f64]) -> bool {
    let (m, b) = (&lu[..n * n], &mut b[..n]);
    for i in 0..n {
        let coeff = b[i];
        for r in i + 1..n {
            b[r] += -coeff * m[i * n + r];
        }
    }
    for i in (0..n).rev() {
        let diag = m[i * n + i];
        if diag == 0.0 {
            return false;
        }
        let coeff = b[i] / diag;
        b[i] = coeff;
        for r in 0..i {
            b[r] += -coeff * m[i * n + r];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn bitwise_equal_to_nalgebra() {
        // Pivoting needed (small leading entries), 1x1 to 6x6.
        for n in 1..=6 {
            let a = |r: usize, c: usize| {
                ((r * 7 + c * 3) % 5) as f64 - 1.7 + if r == c { 0.01 } else { 0.3 * c as f64 }
            };
            let mut lu = DenseLu::default();
            lu.factorize(n, a);
            let reference = DMatrix::from_fn(n, n, a).lu();
            let b: Vec<f64> = (0..n).map(|i| 1.0 / (i as f64 + 1.3)).collect();
            let mut x = b.clone();
            assert!(lu.solve_in_place(&mut x));
            let want = reference.solve(&DVector::from_vec(b)).expect("regular");
            for i in 0..n {
                assert_eq!(x[i].to_bits(), want[i].to_bits(), "n = {n}, x[{i}]");
                assert_eq!(lu.pivot(i), reference.u()[(i, i)].abs());
            }
        }
    }

    #[test]
    fn singular_matrix_has_a_zero_pivot() {
        let mut lu = DenseLu::default();
        lu.factorize(2, |r, _| if r == 0 { 1.0 } else { 2.0 });
        assert_eq!(lu.pivot(1), 0.0);
        assert!(!lu.solve_in_place(&mut [1.0, 1.0]));
    }
}

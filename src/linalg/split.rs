//! LDLᵀ on two cores: one level of nested dissection (George, *Nested
//! dissection of a regular finite element mesh*, SIAM J. Numer. Anal. 10,
//! 1973). A separator S splits the unknowns into two parts with no entry
//! between them,
//!
//! ```text
//! A = [ A11   0    A1S ]      B_i = [ A_ii  A_iS ]
//!     [ 0     A22  A2S ]            [ A_Si  A_SS ]
//!     [ AS1   AS2  ASS ]
//! ```
//!
//! and the two halves B_1, B_2 (principal submatrices of A) are factored at
//! once, one per core, each in its own AMD order with S last. The trailing
//! block of B_i's factor is T_i = A_SS − A_Si A_ii⁻¹ A_iS = L_SS D_SS L_SSᵀ,
//! so the Schur complement of A on S is
//!
//! ```text
//! S = A_SS − Σ_i A_Si A_ii⁻¹ A_iS = T_1 + T_2 − A_SS,
//! ```
//!
//! dense (S is a row of nodes across a strip) and factored last. A solve
//! is a forward sweep over each part (y_i = L_ii⁻¹ b_i, which leaves
//! −LS_i y_i in the separator's rows), x_S = S⁻¹ (b_S − Σ_i LS_i y_i), and a
//! backward sweep over each part, x_i = L_iiᵀ⁻¹ (D_i⁻¹ y_i − LS_iᵀ x_S); the
//! parts run on both cores. The inertia adds up (Haynsworth):
//! In(A) = In(A_11) + In(A_22) + In(S).
//!
//! The separator is a level of a breadth-first search from a
//! pseudo-peripheral unknown (George & Liu, *Computer Solution of Large
//! Sparse Positive Definite Systems*, 1981, §4.4): unknowns of the levels
//! before it and after it share no entry.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{
    LdltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as triangular_matmul};
use faer::linalg::triangular_solve::{
    solve_unit_lower_triangular_in_place, solve_unit_upper_triangular_in_place,
};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::{Accum, Mat, MatMut, MatRef, Par};

use super::sparse_matrix::Structure;
use super::symmetric::{Pivoting, SymmetricFactor, SymmetricSymbolic, amd_order};

/// Largest separator: S is dense, and its factor costs |S|³/3.
const MAX_SEPARATOR: usize = 2000;

/// The analysis of a split: both halves, each with the separator last.
pub struct SplitSymbolic {
    halves: [SymmetricSymbolic; 2],
    /// The separator's unknowns of A, in the order of the halves' last block.
    sep: Vec<usize>,
    /// The lower triangle of A_SS: (row, column) in separator positions and
    /// the slot of A.
    sep_lower: Vec<(u32, u32, u32)>,
}

impl SplitSymbolic {
    /// The split of a pattern, or `None` where no balanced separator of at
    /// most [`MAX_SEPARATOR`] unknowns and an eighth of the pattern is found
    /// (a pattern in several pieces, a dense one).
    pub fn new(s: &Structure) -> Result<Option<Self>, String> {
        let Some((parts, sep)) = bisect(s) else {
            return Ok(None);
        };
        let mut position = vec![u32::MAX; s.n()];
        for (i, &k) in sep.iter().enumerate() {
            position[k] = i as u32;
        }
        let mut sep_lower = vec![];
        for (j, &c) in sep.iter().enumerate() {
            for k in s.col_ptr()[c]..s.col_ptr()[c + 1] {
                let i = position[s.row_idx()[k]];
                if i != u32::MAX && i as usize >= j {
                    sep_lower.push((i, j as u32, k as u32));
                }
            }
        }
        // Each part in the AMD order of its half, the separator made a
        // clique (so that AMD counts it in its neighbours' degrees and leaves
        // it to the end, as a constrained ordering would), then moved last.
        // Ordered without the separator, the part's unknowns next to it look
        // loosely connected, are eliminated early, and carry the separator's
        // rows into many columns.
        let half = |part: &Vec<usize>| -> Result<SymmetricSymbolic, String> {
            let both: Vec<usize> = part.iter().chain(&sep).copied().collect();
            let mut fwd: Vec<usize> = amd_order_of(s, &both, part.len())?
                .into_iter()
                .filter(|&i| i < part.len())
                .map(|i| part[i])
                .collect();
            fwd.extend_from_slice(&sep);
            SymmetricSymbolic::with_order(s, fwd)
        };
        let (h1, h2) = rayon::join(|| half(&parts[0]), || half(&parts[1]));
        let halves = [h1?, h2?];
        if halves.iter().any(|h| h.supernodal().is_none()) {
            return Ok(None);
        }
        Ok(Some(Self {
            halves,
            sep,
            sep_lower,
        }))
    }

    /// Entries of the factor: both parts, and S's lower triangle.
    pub fn factor_entries(&self) -> usize {
        let ns = self.sep.len();
        self.halves
            .iter()
            .map(|h| h.factor_entries())
            .sum::<usize>()
            - ns * (ns + 1)
            + ns * (ns + 1) / 2
    }

    /// Values stored by the two halves' factors.
    pub fn stored_values(&self) -> usize {
        self.halves.iter().map(|h| h.factor_entries()).sum()
    }

    /// Unknowns of the separator.
    pub fn separator(&self) -> usize {
        self.sep.len()
    }
}

/// A numeric split LDLᵀ.
pub struct SplitFactor {
    halves: [SymmetricFactor; 2],
    /// S factored in place: unit L below the diagonal, D on it.
    schur: Mat<f64>,
}

impl SplitFactor {
    /// Both halves at once, then S; `beside` runs with the smaller half
    /// (the solver's checks on the values, which would otherwise hold up
    /// one of the two threads).
    pub fn new<R: Send>(
        sym: &SplitSymbolic,
        values: &[f64],
        beside: impl FnOnce() -> R + Send,
    ) -> (Result<Self, String>, R) {
        let ns = sym.sep.len();
        let half = |h: &SymmetricSymbolic| -> Result<(SymmetricFactor, Mat<f64>), String> {
            let f = SymmetricFactor::new(h, values, Pivoting::None, Par::Seq)?;
            let t = trailing_schur(&f, h, ns);
            Ok((f, t))
        };
        let small = usize::from(sym.halves[1].factor_entries() < sym.halves[0].factor_entries());
        let ((r_small, side), r_big) = rayon::join(
            || (half(&sym.halves[small]), beside()),
            || half(&sym.halves[1 - small]),
        );
        let (r1, r2) = if small == 0 {
            (r_small, r_big)
        } else {
            (r_big, r_small)
        };
        (Self::with_schur(sym, values, r1, r2), side)
    }

    /// S from the halves' factors, and its factorization.
    fn with_schur(
        sym: &SplitSymbolic,
        values: &[f64],
        r1: Result<(SymmetricFactor, Mat<f64>), String>,
        r2: Result<(SymmetricFactor, Mat<f64>), String>,
    ) -> Result<Self, String> {
        let ns = sym.sep.len();
        let ((f1, t1), (f2, t2)) = (r1?, r2?);
        // S = T_1 + T_2 − A_SS, lower triangle.
        let mut schur = t1;
        for j in 0..ns {
            for i in j..ns {
                schur[(i, j)] += t2[(i, j)];
            }
        }
        for &(i, j, k) in &sym.sep_lower {
            schur[(i as usize, j as usize)] -= values[k as usize];
        }
        let mut mem = MemBuffer::try_new(cholesky_in_place_scratch::<f64>(
            ns,
            Par::Seq,
            Default::default(),
        ))
        .map_err(|_| "out of memory".to_string())?;
        cholesky_in_place(
            schur.as_mut(),
            LdltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| format!("LDLᵀ of the separator's Schur complement: {e:?}"))?;
        Ok(Self {
            halves: [f1, f2],
            schur,
        })
    }

    /// Solves A x = b in place.
    pub fn solve_in_place(&self, sym: &SplitSymbolic, x: &mut [f64]) {
        let ns = sym.sep.len();
        let forward = |i: usize| {
            let (h, f) = (&sym.halves[i], &self.halves[i]);
            let part = h.n() - ns;
            let mut y: Vec<f64> = h.order()[..part].iter().map(|&k| x[k]).collect();
            y.resize(h.n(), 0.0);
            sweep_forward(f, h, &mut y, part);
            y
        };
        let (mut y1, mut y2) = rayon::join(|| forward(0), || forward(1));
        let (p1, p2) = (y1.len() - ns, y2.len() - ns);
        let mut xs: Vec<f64> = (0..ns)
            .map(|j| x[sym.sep[j]] + y1[p1 + j] + y2[p2 + j])
            .collect();
        let l = self.schur.as_ref();
        {
            let mut v = MatMut::from_column_major_slice_mut(&mut xs, ns, 1);
            solve_unit_lower_triangular_in_place(l, v.as_mut(), Par::Seq);
            for j in 0..ns {
                v[(j, 0)] /= l[(j, j)];
            }
            solve_unit_upper_triangular_in_place(l.transpose(), v.as_mut(), Par::Seq);
        }
        let backward = |i: usize, y: &mut Vec<f64>| {
            let (h, f) = (&sym.halves[i], &self.halves[i]);
            let part = h.n() - ns;
            y[part..].copy_from_slice(&xs);
            sweep_backward(f, h, y, part);
        };
        rayon::join(|| backward(0, &mut y1), || backward(1, &mut y2));
        for (i, y) in [(0, y1), (1, y2)] {
            let h = &sym.halves[i];
            for (&k, v) in h.order()[..h.n() - ns].iter().zip(y) {
                x[k] = v;
            }
        }
        for (&k, v) in sym.sep.iter().zip(xs) {
            x[k] = v;
        }
    }

    /// (negative, zero, positive) eigenvalue counts of A: the parts' pivots
    /// and S's.
    pub fn inertia(&self, sym: &SplitSymbolic) -> (usize, usize, usize) {
        let ns = sym.sep.len();
        let mut d: Vec<f64> = (0..ns).map(|j| self.schur[(j, j)]).collect();
        for (h, f) in sym.halves.iter().zip(&self.halves) {
            let part = h.n() - ns;
            d.extend(pivots(f, h).into_iter().take(part));
        }
        let mut counts = (0, 0, 0);
        for v in d {
            match v.partial_cmp(&0.0) {
                Some(std::cmp::Ordering::Less) => counts.0 += 1,
                Some(std::cmp::Ordering::Greater) => counts.2 += 1,
                _ => counts.1 += 1,
            }
        }
        counts
    }
}

/// The supernodes of an LDLᵀ factor, and for each the columns it holds
/// before `part`: (first column, columns kept, its block).
fn part_supernodes<'a>(
    f: &'a SymmetricFactor,
    h: &'a SymmetricSymbolic,
    part: usize,
) -> impl DoubleEndedIterator<Item = (usize, usize, MatRef<'a, f64>, &'a [usize])> + 'a {
    let sn = h.supernodal().expect("a split's halves are supernodal");
    let l = SupernodalLdltRef::new(sn, f.values());
    let count = sn.supernode_begin().partition_point(|&b| b < part);
    (0..count).map(move |s| l.supernode(s)).map(move |node| {
        let val = node.val();
        let k = val.ncols().min(part - node.start());
        (node.start(), k, val, node.pattern())
    })
}

/// Row `r` (≥ k) of a supernode's block below its kept columns: the block's
/// own later columns, then its pattern.
fn below_row(start: usize, ncols: usize, pattern: &[usize], r: usize) -> usize {
    if r < ncols {
        start + r
    } else {
        pattern[r - ncols]
    }
}

/// y ← D⁻¹ L⁻¹ y on the part's columns; the rows after them receive the
/// forward updates (−LS y in the separator's rows).
fn sweep_forward(f: &SymmetricFactor, h: &SymmetricSymbolic, y: &mut [f64], part: usize) {
    let mut below_y = vec![];
    for (start, k, val, pattern) in part_supernodes(f, h, part) {
        let below = val.submatrix(k, 0, val.nrows() - k, k);
        below_y.clear();
        below_y.resize(below.nrows(), 0.0);
        {
            let mut top = MatMut::from_column_major_slice_mut(&mut y[start..start + k], k, 1);
            solve_unit_lower_triangular_in_place(val.submatrix(0, 0, k, k), top.as_mut(), Par::Seq);
            let out = MatMut::from_column_major_slice_mut(&mut below_y, below.nrows(), 1);
            matmul(out, Accum::Replace, below, top.as_ref(), 1.0, Par::Seq);
        }
        for (r, v) in below_y.iter().enumerate() {
            y[below_row(start, val.ncols(), pattern, r + k)] -= v;
        }
        for j in 0..k {
            y[start + j] /= val[(j, j)];
        }
    }
}

/// y ← L⁻ᵀ y on the part's columns, the later rows (the separator's x)
/// given.
fn sweep_backward(f: &SymmetricFactor, h: &SymmetricSymbolic, y: &mut [f64], part: usize) {
    let mut below_y = vec![];
    for (start, k, val, pattern) in part_supernodes(f, h, part).rev() {
        let below = val.submatrix(k, 0, val.nrows() - k, k);
        below_y.clear();
        below_y
            .extend((0..below.nrows()).map(|r| y[below_row(start, val.ncols(), pattern, r + k)]));
        let mut top = MatMut::from_column_major_slice_mut(&mut y[start..start + k], k, 1);
        let rhs = MatRef::from_column_major_slice(&below_y, below.nrows(), 1);
        matmul(
            top.as_mut(),
            Accum::Add,
            below.transpose(),
            rhs,
            -1.0,
            Par::Seq,
        );
        solve_unit_upper_triangular_in_place(val.submatrix(0, 0, k, k).transpose(), top, Par::Seq);
    }
}

/// The pivots of an LDLᵀ factor, in column order.
fn pivots(f: &SymmetricFactor, h: &SymmetricSymbolic) -> Vec<f64> {
    let sn = h.supernodal().expect("a split's halves are supernodal");
    let l = SupernodalLdltRef::new(sn, f.values());
    (0..sn.n_supernodes())
        .flat_map(|s| {
            let val = l.supernode(s).val();
            (0..val.ncols()).map(move |j| val[(j, j)])
        })
        .collect()
}

/// T = L_SS D_SS L_SSᵀ of the last `ns` columns of an LDLᵀ factor, lower
/// triangle (dense).
fn trailing_schur(f: &SymmetricFactor, h: &SymmetricSymbolic, ns: usize) -> Mat<f64> {
    let first = h.n() - ns;
    let sn = h.supernodal().expect("a split's halves are supernodal");
    let l = SupernodalLdltRef::new(sn, f.values());
    let mut lss = Mat::<f64>::zeros(ns, ns);
    let mut d = vec![0.0; ns];
    for s in 0..sn.n_supernodes() {
        let node = l.supernode(s);
        let (start, val, pattern) = (node.start(), node.val(), node.pattern());
        let end = start + val.ncols();
        for c in start.max(first)..end {
            let (jc, cc) = (c - start, c - first);
            d[cc] = val[(jc, jc)];
            lss[(cc, cc)] = 1.0;
            for r in jc + 1..val.nrows() {
                lss[(below_row(start, val.ncols(), pattern, r) - first, cc)] = val[(r, jc)];
            }
        }
    }
    let mut ld = lss.clone();
    for (j, dj) in d.iter().enumerate() {
        for i in j..ns {
            ld[(i, j)] *= dj;
        }
    }
    let mut t = Mat::<f64>::zeros(ns, ns);
    triangular_matmul(
        t.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        ld.as_ref(),
        BlockStructure::TriangularLower,
        lss.as_ref().transpose(),
        BlockStructure::TriangularUpper,
        1.0,
        Par::Seq,
    );
    t
}

/// AMD order of the principal submatrix of A on `part` (positions in it),
/// with its unknowns from `clique` on connected to each other.
fn amd_order_of(s: &Structure, part: &[usize], clique: usize) -> Result<Vec<usize>, String> {
    let mut local = vec![usize::MAX; s.n()];
    for (i, &k) in part.iter().enumerate() {
        local[k] = i;
    }
    let mut col_ptr = Vec::with_capacity(part.len() + 1);
    let mut row_idx = vec![];
    col_ptr.push(0);
    for (j, &c) in part.iter().enumerate() {
        let rows = &s.row_idx()[s.col_ptr()[c]..s.col_ptr()[c + 1]];
        row_idx.extend(rows.iter().map(|&r| local[r]).filter(|&r| r != usize::MAX));
        if j >= clique {
            row_idx.extend(clique..part.len());
        }
        col_ptr.push(row_idx.len());
    }
    let n = part.len();
    let a = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &col_ptr, None, &row_idx);
    amd_order(a)
}

/// Breadth-first levels from `root`: (level of each unknown, or u32::MAX
/// where not reached; the unknowns by level; the start of each level).
fn levels(s: &Structure, root: usize) -> (Vec<u32>, Vec<usize>, Vec<usize>) {
    let mut level = vec![u32::MAX; s.n()];
    let mut order = vec![root];
    let mut starts = vec![0];
    level[root] = 0;
    let mut head = 0;
    while head < order.len() {
        let end = order.len();
        starts.push(end);
        for q in head..end {
            let c = order[q];
            for &r in &s.row_idx()[s.col_ptr()[c]..s.col_ptr()[c + 1]] {
                if level[r] == u32::MAX {
                    level[r] = level[c] + 1;
                    order.push(r);
                }
            }
        }
        head = end;
    }
    starts.pop();
    starts.push(order.len());
    (level, order, starts)
}

/// The two parts and the separator (unknowns of A), or `None`.
fn bisect(s: &Structure) -> Option<([Vec<usize>; 2], Vec<usize>)> {
    let n = s.n();
    if n < 8 {
        return None;
    }
    let degree = |c: usize| s.col_ptr()[c + 1] - s.col_ptr()[c];
    // A pseudo-peripheral root: from the last level's least connected
    // unknown while the number of levels grows.
    let (mut level, mut order, mut starts) = levels(s, 0);
    for _ in 0..8 {
        let last = &order[starts[starts.len() - 2]..];
        let far = *last.iter().min_by_key(|&&c| degree(c))?;
        let next = levels(s, far);
        if next.2.len() <= starts.len() {
            break;
        }
        (level, order, starts) = next;
    }
    if order.len() < n {
        return None;
    }
    // Among the levels within 10% of the smallest one that leaves each part
    // at least 40% of the rest, the most balanced.
    let depth = starts.len() - 1;
    let size = |m: usize| starts[m + 1] - starts[m];
    let imbalance = |m: usize| starts[m].abs_diff(n - starts[m + 1]);
    let candidates: Vec<usize> = (1..depth.saturating_sub(1))
        .filter(|&m| 5 * imbalance(m) <= n - size(m))
        .collect();
    let smallest = candidates.iter().map(|&m| size(m)).min()?;
    let best = candidates
        .into_iter()
        .filter(|&m| 10 * size(m) <= 11 * smallest)
        .min_by_key(|&m| imbalance(m))?;
    let ns = size(best);
    if ns > MAX_SEPARATOR || 8 * ns > n {
        return None;
    }
    let (b, e) = (starts[best], starts[best + 1]);
    let sep = order[b..e].to_vec();
    let mut part1: Vec<usize> = order[..b].to_vec();
    let mut part2: Vec<usize> = order[e..].to_vec();
    part1.sort_unstable();
    part2.sort_unstable();
    debug_assert!(part1.iter().all(|&c| level[c] < best as u32));
    Some(([part1, part2], sep))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::SparseMatrix;

    /// A 2D grid matrix with 2 coupled unknowns per node, shifted (its
    /// eigenvalues lie in [0.86 + shift, 9.4 + shift]).
    fn grid(nx: usize, ny: usize, shift: f64) -> SparseMatrix {
        let id = |i: usize, j: usize, k: usize| 2 * (i * ny + j) + k;
        let mut a = SparseMatrix::new(2 * nx * ny);
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..2 {
                    a.add(id(i, j, k), id(i, j, k), 5.0 + shift + 0.1 * k as f64);
                    a.add(id(i, j, k), id(i, j, 1 - k), 0.3);
                    let mut link = |p: usize, q: usize| {
                        a.add(id(i, j, k), id(p, q, k), -1.0);
                        a.add(id(p, q, k), id(i, j, k), -1.0);
                    };
                    if i + 1 < nx {
                        link(i + 1, j);
                    }
                    if j + 1 < ny {
                        link(i, j + 1);
                    }
                }
            }
        }
        a
    }

    /// The split analysis and factor of `a`, and the largest residual of a
    /// split solve.
    fn split_solve(a: &SparseMatrix) -> (SplitSymbolic, SplitFactor, f64) {
        let (s, values) = a.compressed(None).unwrap();
        let sym = SplitSymbolic::new(&s).unwrap().expect("a grid splits");
        let f = SplitFactor::new(&sym, &values, || ()).0.unwrap();
        let b: Vec<f64> = (0..s.n()).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let mut x = b.clone();
        f.solve_in_place(&sym, &mut x);
        let r = a.mul_vec(&x);
        let err = r
            .iter()
            .zip(&b)
            .fold(0.0f64, |m, (r, b)| m.max((r - b).abs()));
        (sym, f, err)
    }

    /// The split solve solves A x = b to round-off (a strip-like grid, with
    /// the separator across it), and the separator is one column of nodes.
    #[test]
    fn the_split_solve_is_a_solve() {
        let a = grid(60, 7, 0.0);
        let (sym, _, err) = split_solve(&a);
        assert_eq!(sym.separator(), 2 * 7, "one column of the grid");
        assert!(err < 1e-13, "residual {err:e}");
    }

    /// The inertia of an indefinite matrix (shifted grid) equals the count
    /// of its negative eigenvalues, with the separator's pivots included.
    #[test]
    fn the_split_inertia_counts_negative_eigenvalues() {
        let a = grid(30, 3, -4.3);
        let (sym, f, err) = split_solve(&a);
        let dense = faer::Mat::from_fn(a.n, a.n, |i, j| {
            a.entries()
                .filter(|&(r, c, _)| r == i && c == j)
                .map(|e| e.2)
                .sum::<f64>()
        });
        let eig = dense.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        let negative = eig.iter().filter(|&&v| v < 0.0).count();
        assert!(negative > 0 && negative < a.n);
        assert_eq!(f.inertia(&sym).0, negative);
        assert!(err < 1e-10, "residual {err:e}");
    }

    /// A pattern in two pieces has no level separator: not split.
    #[test]
    fn two_pieces_are_not_split() {
        let mut a = SparseMatrix::new(40);
        for i in 0..40 {
            a.add(i, i, 2.0);
            if i % 20 != 19 {
                a.add(i, i + 1, -1.0);
                a.add(i + 1, i, -1.0);
            }
        }
        let (s, _) = a.compressed(None).unwrap();
        assert!(SplitSymbolic::new(&s).unwrap().is_none());
    }
}

//! Sparse matrices under assembly: either free triplets (small problems,
//! tests) or values in a fixed compressed-column [`Structure`] that the
//! assembler builds once from its connectivity (large shells: no triplet list,
//! no sort per factorization).

use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

/// A compressed-column pattern (rows sorted, no duplicates), shared between
/// the tangents that use it. Its `id` tells a solver that a pattern is the
/// one it analysed, without comparing the index arrays.
#[derive(Debug)]
pub struct Structure {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    id: u64,
    /// For every slot (i, j), the slot of (j, i); `None` when the pattern is
    /// not structurally symmetric. Computed on first use; 32-bit (half the
    /// memory: 0.2 GB at a million unknowns), so `None` also when the
    /// pattern has 2³² entries or more.
    transpose: OnceLock<Option<Vec<u32>>>,
}

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// Values per task of the passes over a matrix's values on the thread pool.
const PARALLEL_CHUNK: usize = 1 << 16;

impl Structure {
    /// The pattern of the positions `coords` in an n × n matrix (duplicates
    /// merged). Positions outside the matrix are an error.
    pub fn from_coords(
        n: usize,
        coords: impl IntoIterator<Item = (usize, usize)>,
    ) -> Result<Self, String> {
        let mut by_col: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (r, c) in coords {
            if r >= n || c >= n {
                return Err(format!("entry ({r}, {c}) outside the {n} x {n} matrix"));
            }
            by_col[c].push(r);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for rows in &mut by_col {
            rows.sort_unstable();
            rows.dedup();
            row_idx.extend_from_slice(rows);
            col_ptr.push(row_idx.len());
            *rows = Vec::new();
        }
        Ok(Self::from_parts(n, col_ptr, row_idx))
    }

    /// A pattern given in compressed columns; rows must be strictly
    /// increasing within each column.
    pub fn from_compressed(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> Result<Self, String> {
        let ok = col_ptr.len() == n + 1
            && col_ptr[0] == 0
            && col_ptr[n] == row_idx.len()
            && col_ptr.windows(2).all(|w| {
                w[0] <= w[1]
                    && row_idx[w[0]..w[1]].windows(2).all(|r| r[0] < r[1])
                    && row_idx[w[0]..w[1]].iter().all(|&r| r < n)
            });
        if !ok {
            return Err("compressed columns: pointers or sorted rows invalid".into());
        }
        Ok(Self::from_parts(n, col_ptr, row_idx))
    }

    fn from_parts(n: usize, mut col_ptr: Vec<usize>, mut row_idx: Vec<usize>) -> Self {
        // Built by pushes, the arrays may hold up to twice their length.
        col_ptr.shrink_to_fit();
        row_idx.shrink_to_fit();
        Self {
            n,
            col_ptr,
            row_idx,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            transpose: OnceLock::new(),
        }
    }

    pub fn n(&self) -> usize {
        self.n
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// A number unique to this pattern in the process.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The slot of (row, col), if the pattern holds it.
    pub fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let start = *self.col_ptr.get(col)?;
        let rows = &self.row_idx[start..self.col_ptr[col + 1]];
        rows.binary_search(&row).ok().map(|k| start + k)
    }

    /// The slot of the transposed position of every slot, if the pattern is
    /// structurally symmetric.
    pub fn transpose_slots(&self) -> Option<&[u32]> {
        self.transpose
            .get_or_init(|| {
                if u32::try_from(self.nnz()).is_err() {
                    return None;
                }
                let mut t = Vec::with_capacity(self.nnz());
                for c in 0..self.n {
                    for &r in &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]] {
                        t.push(self.slot(c, r)? as u32);
                    }
                }
                Some(t)
            })
            .as_deref()
    }

    /// This pattern with the positions `extra` added.
    fn union(&self, extra: &[(usize, usize)]) -> Result<Self, String> {
        let own = (0..self.n).flat_map(|c| {
            self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]]
                .iter()
                .map(move |&r| (r, c))
        });
        Self::from_coords(self.n, own.chain(extra.iter().copied()))
    }
}

/// A square sparse matrix under assembly. With a [`Structure`], `add` sums
/// into the slot of (row, col) (binary search in the column); positions
/// outside it, and every position without one, are kept as triplets.
/// Columns `cols` of a [`SparseMatrix`] on a pattern: their stored values,
/// the first of which is the pattern's slot `first_slot`.
pub struct ColumnBlock<'a> {
    pub cols: std::ops::Range<usize>,
    pub first_slot: usize,
    pub values: &'a mut [f64],
}

#[derive(Clone, Debug, Default)]
pub struct SparseMatrix {
    pub n: usize,
    structure: Option<Arc<Structure>>,
    values: Vec<f64>,
    extra: Vec<(usize, usize, f64)>,
}

impl SparseMatrix {
    /// An n × n matrix collecting triplets.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            ..Self::default()
        }
    }

    /// A zero matrix on `structure`.
    pub fn with_structure(structure: Arc<Structure>) -> Self {
        // Zeroed on every thread: on one, the writes and the page faults of
        // a fresh block (5 MB at 12,600 unknowns) were ~1 ms of every
        // tangent with the other thread idle.
        let mut values = Vec::with_capacity(structure.nnz());
        rayon::iter::repeat_n(0.0, structure.nnz())
            .with_min_len(PARALLEL_CHUNK)
            .collect_into_vec(&mut values);
        Self {
            n: structure.n,
            values,
            structure: Some(structure),
            extra: Vec::new(),
        }
    }

    /// Adds `value` at (row, col); repeated entries are summed.
    pub fn add(&mut self, row: usize, col: usize, value: f64) {
        if let Some(k) = self.structure.as_ref().and_then(|s| s.slot(row, col)) {
            self.values[k] += value;
        } else {
            self.extra.push((row, col, value));
        }
    }

    /// Adds `values[k]` at (`rows[k]`, `col`), rows increasing. One search
    /// finds the first row; the next ones are taken from the following slots
    /// when the pattern holds them there (a nodal block's rows are adjacent
    /// in a node-block pattern), and searched otherwise.
    pub fn add_sorted_rows(&mut self, rows: &[usize], col: usize, values: &[f64]) {
        let Some(s) = self.structure.as_deref() else {
            for (&r, &v) in rows.iter().zip(values) {
                self.extra.push((r, col, v));
            }
            return;
        };
        let end = s.col_ptr[col + 1];
        let mut next = None;
        for (&r, &v) in rows.iter().zip(values) {
            let k = match next {
                Some(k) if k < end && s.row_idx[k] == r => Some(k),
                _ => s.slot(r, col),
            };
            match k {
                Some(k) => {
                    self.values[k] += v;
                    next = Some(k + 1);
                }
                None => {
                    self.extra.push((r, col, v));
                    next = None;
                }
            }
        }
    }

    /// Adds `values` to the consecutive slots from `slot` of the pattern
    /// (positions precomputed by the assembler, fe::pattern::element_slots).
    /// Panics without a pattern or past its end: a wrong slot is a bug of
    /// the caller, not a position to keep aside.
    pub fn add_at_slots(&mut self, slot: usize, values: &[f64]) {
        assert!(self.structure.is_some(), "add_at_slots needs a pattern");
        for (v, &x) in self.values[slot..slot + values.len()]
            .iter_mut()
            .zip(values)
        {
            *v += x;
        }
    }

    /// The stored values split into `parts` blocks of whole columns with
    /// about equal numbers of entries, so that threads can add to disjoint
    /// columns at once; `None` without a pattern.
    pub fn column_blocks(&mut self, parts: usize) -> Option<Vec<ColumnBlock<'_>>> {
        let s = self.structure.as_deref()?;
        let nnz = s.nnz();
        let parts = parts.clamp(1, s.n.max(1));
        let mut blocks = Vec::with_capacity(parts);
        let mut rest = self.values.as_mut_slice();
        let mut first_col = 0;
        for part in 1..=parts {
            let last_col = if part == parts {
                s.n
            } else {
                // The first column boundary at or past part / parts of the entries.
                let target = nnz * part / parts;
                first_col + s.col_ptr[first_col..=s.n].partition_point(|&p| p < target)
            };
            let first_slot = s.col_ptr[first_col];
            let (values, tail) = rest.split_at_mut(s.col_ptr[last_col] - first_slot);
            rest = tail;
            blocks.push(ColumnBlock {
                cols: first_col..last_col,
                first_slot,
                values,
            });
            first_col = last_col;
        }
        Some(blocks)
    }

    /// The first entry that is not finite, if any (a scan of the stored
    /// values first: the entries' positions are looked up only then).
    pub fn first_non_finite(&self) -> Option<(usize, usize, f64)> {
        // By chunks, on every thread, each chunk tested whole (no early
        // exit inside it: the test vectorizes).
        let finite = self
            .values
            .par_chunks(PARALLEL_CHUNK)
            .all(|c| c.iter().fold(true, |all, v| all & v.is_finite()))
            && self.extra.iter().all(|t| t.2.is_finite());
        if finite {
            None
        } else {
            self.entries().find(|t| !t.2.is_finite())
        }
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

    /// Every stored entry as (row, col, value); a position may appear more
    /// than once (the values are then summed).
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let structured = self.structure.iter().flat_map(move |s| {
            (0..s.n).flat_map(move |c| {
                (s.col_ptr[c]..s.col_ptr[c + 1]).map(move |k| (s.row_idx[k], c, self.values[k]))
            })
        });
        structured.chain(self.extra.iter().copied())
    }

    /// Number of stored entries (slots and loose triplets).
    pub fn stored(&self) -> usize {
        self.values.len() + self.extra.len()
    }

    /// y = A x.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for (r, c, v) in self.entries() {
            y[r] += v * x[c];
        }
        y
    }

    /// The matrix in compressed columns: its structure (the assembler's, or
    /// one built from the triplets, `known` reused when it is the same
    /// pattern) and the summed values per slot.
    pub fn compressed(
        &self,
        known: Option<&Arc<Structure>>,
    ) -> Result<(Arc<Structure>, Cow<'_, [f64]>), String> {
        if let (true, Some(s)) = (self.extra.is_empty(), &self.structure) {
            // The assembler's own pattern: no copy of the values.
            return Ok((Arc::clone(s), Cow::Borrowed(&self.values)));
        }
        let extra: Vec<(usize, usize)> = self.extra.iter().map(|&(r, c, _)| (r, c)).collect();
        let built = match &self.structure {
            Some(s) => s.union(&extra)?,
            None => Structure::from_coords(self.n, extra)?,
        };
        let structure = match known {
            Some(k) if k.col_ptr == built.col_ptr && k.row_idx == built.row_idx => Arc::clone(k),
            _ => Arc::new(built),
        };
        let mut values = vec![0.0; structure.nnz()];
        for (r, c, v) in self.entries() {
            let k = structure.slot(r, c).expect("every entry is in the union");
            values[k] += v;
        }
        Ok((structure, Cow::Owned(values)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structured_and_loose_entries_sum_to_the_same_matrix() {
        let s =
            Arc::new(Structure::from_coords(3, [(0, 0), (1, 1), (2, 2), (1, 0), (0, 1)]).unwrap());
        let mut a = SparseMatrix::with_structure(Arc::clone(&s));
        a.add(0, 0, 1.0);
        a.add(0, 0, 2.0);
        a.add(2, 1, 5.0); // outside the structure
        a.add(1, 0, -1.0);
        let (c, v) = a.compressed(Some(&s)).unwrap();
        assert_ne!(c.id(), s.id(), "a new position makes a new pattern");
        assert_eq!(c.nnz(), 6);
        assert_eq!(v[c.slot(0, 0).unwrap()], 3.0);
        assert_eq!(v[c.slot(2, 1).unwrap()], 5.0);
        assert_eq!(a.mul_vec(&[1.0, 1.0, 1.0]), vec![3.0, -1.0, 5.0]);
        assert!(c.transpose_slots().is_none(), "(2, 1) has no (1, 2)");
        assert!(s.transpose_slots().is_some());
    }

    /// A pattern of several chunks of the parallel passes: the values
    /// start zeroed, and a non-finite value is found wherever it sits (past
    /// the first chunk, in the last one, among the loose triplets).
    #[test]
    fn non_finite_entries_are_found_in_any_chunk() {
        let n = 3 * PARALLEL_CHUNK + 5;
        let s = Arc::new(Structure::from_coords(n, (0..n).map(|i| (i, i))).unwrap());
        let clean = SparseMatrix::with_structure(Arc::clone(&s));
        assert!(clean.values.len() == n && clean.values.iter().all(|&v| v == 0.0));
        assert_eq!(clean.first_non_finite(), None);
        for (i, bad) in [
            (PARALLEL_CHUNK + 7, f64::NAN),
            (n - 1, f64::INFINITY),
            (0, f64::NEG_INFINITY),
        ] {
            let mut a = SparseMatrix::with_structure(Arc::clone(&s));
            a.add(i, i, bad);
            let (r, c, v) = a.first_non_finite().expect("found");
            assert_eq!((r, c), (i, i));
            assert!(!v.is_finite() && v.is_nan() == bad.is_nan());
        }
        let mut loose = SparseMatrix::with_structure(Arc::clone(&s));
        loose.add(0, 1, f64::NAN);
        assert_eq!(loose.first_non_finite().map(|t| (t.0, t.1)), Some((0, 1)));
    }

    #[test]
    fn triplets_with_the_known_pattern_reuse_it() {
        let mut a = SparseMatrix::new(2);
        a.add(1, 1, 2.0);
        a.add(0, 0, 1.0);
        let (s1, _) = a.compressed(None).unwrap();
        let mut b = SparseMatrix::new(2);
        b.add(0, 0, 4.0);
        b.add(1, 1, 1.0);
        let (s2, v) = b.compressed(Some(&s1)).unwrap();
        assert_eq!(s1.id(), s2.id());
        assert_eq!(*v, [4.0, 1.0]);
        assert!(Structure::from_coords(2, [(2, 0)]).is_err());
    }

    #[test]
    fn column_blocks_split_the_values_by_whole_columns() {
        // Column j holds rows 0..=j: 55 entries over 10 columns.
        let n = 10;
        let s = Arc::new(
            Structure::from_coords(n, (0..n).flat_map(|j| (0..=j).map(move |i| (i, j)))).unwrap(),
        );
        let mut a = SparseMatrix::with_structure(Arc::clone(&s));
        for parts in 1..=4 {
            let blocks = a.column_blocks(parts).unwrap();
            assert_eq!(blocks.len(), parts);
            let (mut col, mut slot) = (0, 0);
            for b in &blocks {
                assert_eq!((b.cols.start, b.first_slot), (col, slot));
                assert_eq!(
                    b.values.len(),
                    s.col_ptr()[b.cols.end] - s.col_ptr()[b.cols.start]
                );
                (col, slot) = (b.cols.end, slot + b.values.len());
            }
            assert_eq!((col, slot), (n, s.nnz()));
            // No block holds more than its share and one column (10 entries).
            assert!(blocks.iter().all(|b| b.values.len() <= 55 / parts + 10));
        }
        // Writing through the blocks writes the matrix.
        for b in a.column_blocks(3).unwrap() {
            for v in b.values.iter_mut() {
                *v = b.cols.start as f64;
            }
        }
        // Boundaries at 21 and 36 entries: columns 0..6, 6..8, 8..10.
        assert_eq!(a.values[s.slot(9, 9).unwrap()], 8.0);
        assert_eq!(a.values[s.slot(0, 6).unwrap()], 6.0);
        assert_eq!(a.values[0], 0.0);
        assert!(SparseMatrix::new(3).column_blocks(2).is_none());
    }
}

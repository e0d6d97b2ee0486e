//! MatrixMarket coordinate files (NIST, "The Matrix Market Exchange
//! Formats", 1996): how a tangent leaves `anm` for other sparse solvers
//! (reference/peers/) and comes back for `anm factor`.
//!
//! A symmetric matrix is written as `symmetric` with its lower triangle only,
//! as the format specifies; anything else as `general`. Indices are 1-based.

use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::Path;

use super::sparse_matrix::{SparseMatrix, Structure};

/// Writes the compressed-column matrix (s, values); `symmetric` writes the
/// lower triangle with the `symmetric` qualifier.
pub fn write(path: &Path, s: &Structure, values: &[f64], symmetric: bool) -> std::io::Result<()> {
    let mut w = BufWriter::new(std::fs::File::create(path)?);
    let kind = if symmetric { "symmetric" } else { "general" };
    writeln!(w, "%%MatrixMarket matrix coordinate real {kind}")?;
    writeln!(w, "% written by anm {}", env!("CARGO_PKG_VERSION"))?;
    let keep = |r: usize, c: usize| !symmetric || r >= c;
    let count = (0..s.n())
        .map(|c| {
            s.row_idx()[s.col_ptr()[c]..s.col_ptr()[c + 1]]
                .iter()
                .filter(|&&r| keep(r, c))
                .count()
        })
        .sum::<usize>();
    writeln!(w, "{} {} {count}", s.n(), s.n())?;
    for c in 0..s.n() {
        let slots = s.col_ptr()[c]..s.col_ptr()[c + 1];
        for (&r, v) in s.row_idx()[slots.clone()].iter().zip(&values[slots]) {
            if keep(r, c) {
                writeln!(w, "{} {} {v:.17e}", r + 1, c + 1)?;
            }
        }
    }
    w.flush()
}

/// Reads a real square coordinate matrix (general or symmetric).
pub fn read(path: &Path) -> Result<SparseMatrix, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut lines = BufReader::new(file).lines().enumerate();
    let bad = |line: usize, what: &str| format!("line {}: {what}", line + 1);
    let (_, header) = lines.next().ok_or("empty file")?;
    let header = header.map_err(|e| e.to_string())?.to_lowercase();
    let words: Vec<&str> = header.split_whitespace().collect();
    if words.len() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(bad(0, "not a MatrixMarket matrix header"));
    }
    if words[2] != "coordinate" || !matches!(words[3], "real" | "integer") {
        return Err(bad(0, "only real coordinate matrices are read"));
    }
    let symmetric = match words[4] {
        "general" => false,
        "symmetric" => true,
        other => return Err(bad(0, &format!("unsupported symmetry `{other}`"))),
    };
    let mut size = None;
    let mut m = SparseMatrix::new(0);
    let mut seen = 0usize;
    // Rows and columns holding an entry (a symmetric entry holds both of
    // its mirror's too).
    let (mut rows_seen, mut cols_seen): (Vec<bool>, Vec<bool>) = (vec![], vec![]);
    for (i, line) in lines {
        let line = line.map_err(|e| e.to_string())?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        let f: Vec<&str> = t.split_whitespace().collect();
        match size {
            None => {
                let v: Vec<usize> = f
                    .iter()
                    .map(|x| {
                        x.parse()
                            .map_err(|_| bad(i, "size line: expected 3 integers"))
                    })
                    .collect::<Result<_, _>>()?;
                if v.len() != 3 || v[0] != v[1] {
                    return Err(bad(
                        i,
                        "size line: expected `n n entries` of a square matrix",
                    ));
                }
                if v[0] == 0 {
                    return Err(bad(i, "size line: an empty matrix (n = 0)"));
                }
                // Each entry fills at most two rows (one, or its mirror of a
                // symmetric matrix): with fewer, a row is empty and the
                // matrix singular, whatever its values. Refused here, before
                // anything of size n (a size line of 1e9 with 4 entries ran
                // the analysis into memory exhaustion).
                if v[0] > 2 * v[2] {
                    return Err(bad(
                        i,
                        &format!(
                            "size line: {} entries cannot fill {} rows (structurally singular)",
                            v[2], v[0]
                        ),
                    ));
                }
                size = Some((v[0], v[2]));
                m = SparseMatrix::new(v[0]);
                rows_seen = vec![false; v[0]];
                cols_seen = vec![false; v[0]];
            }
            Some((n, _)) => {
                let entry = || -> Option<(usize, usize, f64)> {
                    if f.len() != 3 {
                        return None;
                    }
                    Some((f[0].parse().ok()?, f[1].parse().ok()?, f[2].parse().ok()?))
                };
                let (r, c, v) = entry().ok_or_else(|| bad(i, "expected `row col value`"))?;
                if r == 0 || c == 0 || r > n || c > n {
                    return Err(bad(i, &format!("index ({r}, {c}) outside 1..={n}")));
                }
                let v: f64 = v;
                if !v.is_finite() {
                    return Err(bad(
                        i,
                        &format!("entry ({r}, {c}) is {v}, not a finite number"),
                    ));
                }
                m.add(r - 1, c - 1, v);
                if symmetric && r != c {
                    m.add(c - 1, r - 1, v);
                    (rows_seen[c - 1], cols_seen[r - 1]) = (true, true);
                }
                (rows_seen[r - 1], cols_seen[c - 1]) = (true, true);
                seen += 1;
            }
        }
    }
    match size {
        Some((_, entries)) if entries == seen => {
            for (what, seen) in [("row", &rows_seen), ("column", &cols_seen)] {
                if let Some(k) = seen.iter().position(|&x| !x) {
                    return Err(format!(
                        "{what} {} holds no entry: the matrix is structurally singular",
                        k + 1
                    ));
                }
            }
            Ok(m)
        }
        Some((_, entries)) => Err(format!("{seen} entries, the size line says {entries}")),
        None => Err("no size line".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_and_general_matrices_round_trip() {
        let a = SparseMatrix::from_dense(&[
            vec![4.0, -1.0, 0.0],
            vec![-1.0, 4.0, 0.5],
            vec![0.0, 0.5, 3.0],
        ]);
        let (s, v) = a.compressed(None).unwrap();
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        for symmetric in [true, false] {
            let p = dir.join(format!("a-{symmetric}.mtx"));
            write(&p, &s, &v, symmetric).unwrap();
            let b = read(&p).unwrap();
            let (_, w) = b.compressed(Some(&s)).unwrap();
            assert_eq!(v, w);
        }
        std::fs::write(
            dir.join("bad.mtx"),
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1.0\n",
        )
        .unwrap();
        let e = read(&dir.join("bad.mtx")).unwrap_err();
        assert!(e.contains("line 3") && e.contains("outside"), "{e}");
        // A size line no entry count can fill (it ran the analysis of a
        // 1e9 × 1e9 matrix into memory exhaustion), an empty row, an
        // empty column.
        for (name, text, want) in [
            (
                "huge",
                "%%MatrixMarket matrix coordinate real symmetric\n1000000000 1000000000 1\n1 1 4.0\n",
                "line 2: size line: 1 entries cannot fill 1000000000 rows",
            ),
            (
                "empty",
                "%%MatrixMarket matrix coordinate real symmetric\n0 0 0\n",
                "line 2: size line: an empty matrix",
            ),
            (
                "nan",
                "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 NaN\n",
                "line 3: entry (1, 1) is NaN",
            ),
            (
                "row",
                "%%MatrixMarket matrix coordinate real symmetric\n3 3 2\n1 1 4.0\n3 3 1.0\n",
                "row 2 holds no entry",
            ),
            (
                "column",
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 4.0\n2 1 1.0\n",
                "column 2 holds no entry",
            ),
        ] {
            let p = dir.join(format!("{name}.mtx"));
            std::fs::write(&p, text).unwrap();
            let e = read(&p).unwrap_err();
            assert!(e.contains(want), "{name}: {e}");
        }
    }
}

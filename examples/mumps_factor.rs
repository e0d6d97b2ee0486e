//! Factorization time and memory: MUMPS (1 or P ranks) against faer's
//! SparseLu (what `anm` uses), on generated SPD matrices.
//!
//!     cargo run --release --features mumps --example mumps_factor -- shell 410 40
//!     mpirun -n 2 target/release/examples/mumps_factor shell 410 40
//!     cargo run --release --features mumps --example mumps_factor -- shell 410 40 --solver faer
//!
//! Matrices: `lap2d M` (5-point Laplacian, M² unknowns), `lap3d M`
//! (7-point, M³), `shell NX NY` (NX × NY nodes of a quadrilateral grid, 6
//! coupled dofs per node, 9-point nodal stencil: the pattern of a shell
//! tangent; 410 × 40 has the 98,400 unknowns of the issue-17 strip).
//! Options: `--solver mumps|faer`, `--sym 0|1|2` (MUMPS), `--ordering K`
//! (MUMPS ICNTL(7)), `--repeat R` (factorizations, best time reported).
//! Each run is one process so that its peak resident memory (VmHWM) is the
//! solver's.

#[cfg(not(feature = "mumps"))]
fn main() {
    eprintln!("build with --features mumps");
    std::process::exit(2);
}

#[cfg(feature = "mumps")]
fn main() {
    bench::main();
}

#[cfg(feature = "mumps")]
mod bench {
    use std::time::Instant;

    use anm::linalg::mumps::{self, Mumps};
    use anm::linalg::{LinearSolver, SparseMatrix, mpi};

    struct Coo {
        n: usize,
        rows: Vec<usize>,
        cols: Vec<usize>,
        vals: Vec<f64>,
    }

    impl Coo {
        fn add(&mut self, r: usize, c: usize, v: f64) {
            self.rows.push(r);
            self.cols.push(c);
            self.vals.push(v);
        }
        fn mul(&self, x: &[f64]) -> Vec<f64> {
            let mut y = vec![0.0; self.n];
            for k in 0..self.rows.len() {
                y[self.rows[k]] += self.vals[k] * x[self.cols[k]];
            }
            y
        }
    }

    fn generate(kind: &str, a: usize, b: usize) -> Coo {
        let mut m = Coo {
            n: 0,
            rows: Vec::new(),
            cols: Vec::new(),
            vals: Vec::new(),
        };
        match kind {
            "lap2d" => {
                m.n = a * a;
                for i in 0..a {
                    for j in 0..a {
                        let p = i * a + j;
                        m.add(p, p, 4.0);
                        for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                            let (ii, jj) = (i as i64 + di, j as i64 + dj);
                            if (0..a as i64).contains(&ii) && (0..a as i64).contains(&jj) {
                                m.add(p, ii as usize * a + jj as usize, -1.0);
                            }
                        }
                    }
                }
            }
            "lap3d" => {
                m.n = a * a * a;
                let idx = |i: usize, j: usize, k: usize| (i * a + j) * a + k;
                for i in 0..a {
                    for j in 0..a {
                        for k in 0..a {
                            let p = idx(i, j, k);
                            m.add(p, p, 6.0);
                            for d in [
                                (-1i64, 0i64, 0i64),
                                (1, 0, 0),
                                (0, -1, 0),
                                (0, 1, 0),
                                (0, 0, -1),
                                (0, 0, 1),
                            ] {
                                let (ii, jj, kk) = (i as i64 + d.0, j as i64 + d.1, k as i64 + d.2);
                                let r = 0..a as i64;
                                if r.contains(&ii) && r.contains(&jj) && r.contains(&kk) {
                                    m.add(p, idx(ii as usize, jj as usize, kk as usize), -1.0);
                                }
                            }
                        }
                    }
                }
            }
            "shell" => {
                // Kronecker product of the Q1 Laplacian stencil (+ mass) on
                // the node grid with a dense SPD 6 × 6 block: SPD, nodal
                // blocks dense like a shell tangent's.
                let dof = 6;
                m.n = a * b * dof;
                let s: Vec<Vec<f64>> = (0..dof)
                    .map(|r| {
                        (0..dof)
                            .map(|c| {
                                if r == c {
                                    2.0 + r as f64 * 0.5
                                } else {
                                    1.0 / (1.0 + (r + c) as f64)
                                }
                            })
                            .collect()
                    })
                    .collect();
                for i in 0..a {
                    for j in 0..b {
                        let p = i * b + j;
                        for di in -1i64..=1 {
                            for dj in -1i64..=1 {
                                let (ii, jj) = (i as i64 + di, j as i64 + dj);
                                if !(0..a as i64).contains(&ii) || !(0..b as i64).contains(&jj) {
                                    continue;
                                }
                                let q = ii as usize * b + jj as usize;
                                let w = if p == q { 8.0 / 3.0 + 0.01 } else { -1.0 / 3.0 };
                                for (r, row) in s.iter().enumerate() {
                                    for (c, &v) in row.iter().enumerate() {
                                        m.add(p * dof + r, q * dof + c, w * v);
                                    }
                                }
                            }
                        }
                    }
                }
            }
            _ => panic!("unknown matrix {kind}: lap2d M | lap3d M | shell NX NY"),
        }
        m
    }

    /// Peak resident memory of this process (VmHWM), MiB.
    fn peak_rss_mib() -> f64 {
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmHWM:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
            .map_or(f64::NAN, |kb| kb / 1024.0)
    }

    /// CPU time (user + system) of this process so far, s (/proc, 10 ms
    /// ticks): on a loaded machine the wall time overstates the work.
    fn cpu_s() -> f64 {
        let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
        let after = stat.rsplit_once(')').map_or("", |(_, r)| r);
        let f: Vec<f64> = after
            .split_whitespace()
            .filter_map(|v| v.parse().ok())
            .collect();
        // utime, stime: fields 14, 15 of stat; f[0] is field 4 (field 3, the
        // state, is not a number).
        if f.len() > 11 {
            (f[10] + f[11]) / 100.0
        } else {
            f64::NAN
        }
    }

    fn backward_error(a: &Coo, x: &[f64], b: &[f64]) -> f64 {
        let ax = a.mul(x);
        let r = ax
            .iter()
            .zip(b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        let mut rows = vec![0.0f64; a.n];
        for k in 0..a.rows.len() {
            rows[a.rows[k]] += a.vals[k].abs();
        }
        let an = rows.into_iter().fold(0.0, f64::max);
        let xn = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let bn = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        r / (an * xn + bn)
    }

    pub fn main() {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let mut pos = Vec::new();
        let (mut solver, mut sym, mut ordering, mut repeat) = ("mumps".to_string(), 1, None, 3);
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let mut val = || it.next().expect("option value").clone();
            match a.as_str() {
                "--solver" => solver = val(),
                "--sym" => sym = val().parse().unwrap(),
                "--ordering" => ordering = Some(val().parse::<i32>().unwrap()),
                "--repeat" => repeat = val().parse().unwrap(),
                _ => pos.push(a.clone()),
            }
        }
        let kind = pos.first().map_or("shell", |s| s.as_str());
        let a: usize = pos.get(1).map_or(410, |s| s.parse().unwrap());
        let b: usize = pos.get(2).map_or(40, |s| s.parse().unwrap());
        let t = Instant::now();
        let m = generate(kind, a, b);
        let gen_s = t.elapsed().as_secs_f64();
        let rhs: Vec<f64> = (0..m.n)
            .map(|i| ((i * 37 % 101) as f64 - 50.0) / 17.0)
            .collect();
        match solver.as_str() {
            "faer" => {
                let mut s = SparseMatrix::new(m.n);
                for k in 0..m.rows.len() {
                    s.add(m.rows[k], m.cols[k], m.vals[k]);
                }
                let mut lu = LinearSolver::default();
                let t = Instant::now();
                let f = lu.factorize(&s).unwrap();
                let first = t.elapsed().as_secs_f64();
                drop(f);
                let mut best = f64::INFINITY;
                let mut best_cpu = f64::INFINITY;
                let mut f = None;
                for _ in 0..repeat {
                    let (t, c) = (Instant::now(), cpu_s());
                    f = Some(lu.factorize(&s).unwrap());
                    best = best.min(t.elapsed().as_secs_f64());
                    best_cpu = best_cpu.min(cpu_s() - c);
                }
                let t = Instant::now();
                let x = f.unwrap().solve(&rhs);
                let solve = t.elapsed().as_secs_f64();
                println!(
                    "{kind} n={} entries={} faer: analysis+factorization {first:.3} s, \
                     factorization {best:.3} s (cpu {best_cpu:.2} s, best of {repeat}), solve {solve:.4} s, \
                     backward error {:.1e}, peak RSS {:.0} MiB (matrix generated in {gen_s:.2} s)",
                    m.n,
                    m.rows.len(),
                    backward_error(&m, &x, &rhs),
                    peak_rss_mib()
                );
            }
            "mumps" => {
                mumps::mpi_init();
                {
                    let mut mu = Mumps::new(sym).unwrap();
                    if let Some(o) = ordering {
                        mu.set_icntl(7, o);
                    }
                    let t = Instant::now();
                    mu.analyse(m.n, &m.rows, &m.cols).unwrap();
                    let analysis = t.elapsed().as_secs_f64();
                    let mut best = f64::INFINITY;
                    let mut best_cpu = f64::INFINITY;
                    for _ in 0..repeat {
                        let (t, c) = (Instant::now(), cpu_s());
                        mu.factorize(&m.vals).unwrap();
                        best = best.min(t.elapsed().as_secs_f64());
                        best_cpu = best_cpu.min(cpu_s() - c);
                    }
                    let mut x = rhs.clone();
                    let t = Instant::now();
                    mu.solve(&mut x).unwrap();
                    let solve = t.elapsed().as_secs_f64();
                    let (used, max, total) = mu.memory_mb();
                    let (alloc, _, alloc_total) = mu.memory_allocated_mb();
                    if mumps::is_root() {
                        println!(
                            "{kind} n={} entries={} MUMPS sym={sym} ranks={} ordering={}: analysis {analysis:.3} s, \
                             factorization {best:.3} s (root cpu {best_cpu:.2} s, best of {repeat}), solve {solve:.4} s, \
                             factor entries {:.3e}, backward error {:.1e}, memory used max/total {max}/{total} MB, \
                             allocated total {alloc_total} MB",
                            m.n,
                            m.rows.len(),
                            mu.ranks(),
                            mu.infog(7),
                            mu.factor_entries() as f64,
                            backward_error(&m, &x, &rhs),
                        );
                    }
                    // Every rank prints its own figures.
                    println!(
                        "  rank {}: MUMPS memory used {used} MB, allocated {alloc} MB, pivots {}, peak RSS {:.0} MiB",
                        mu.rank(),
                        mu.info(23),
                        peak_rss_mib()
                    );
                }
                if mpi::ranks() > 1 {
                    mumps::mpi_finalize();
                }
            }
            s => panic!("unknown solver {s}: mumps | faer"),
        }
    }
}

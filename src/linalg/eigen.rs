//! Lowest eigenpairs of sparse symmetric problems, on our own factorization.
//!
//! Two solvers:
//!
//! - [`pencil`]: the eigenvalues mu of smallest modulus of the symmetric
//!   pencil (A + mu B) phi = 0 with A positive definite (linearized
//!   buckling, Abaqus *BUCKLE: A = K_0, B = K_sigma), by subspace iteration
//!   with Rayleigh–Ritz projection (Bathe, *Finite Element Procedures*, 2nd
//!   ed. 2014, §11.6.3). A phi = −mu B phi is iterated as
//!   Y = A⁻¹ B X (the shift-invert operator: one factorization of A, many
//!   solves), so that the eigenvalues theta = −1/mu of largest modulus, i.e.
//!   the mu of smallest modulus, converge at the rate |theta_{q+1} / theta_i|
//!   with q = max(2k, k + 8) vectors for k wanted pairs. The q × q projected
//!   pencil (Yᵀ B Y) z = theta (Yᵀ A Y) z is reduced by the Cholesky factor
//!   of Yᵀ A Y to a standard symmetric problem (nalgebra).
//! - [`smallest_eigenvalue`]: the eigenvalue of smallest modulus of a
//!   symmetric (possibly indefinite) A, by inverse iteration with its
//!   Rayleigh quotient (Golub & Van Loan, *Matrix Computations*, 4th ed.,
//!   §8.2.2): the test function whose sign change locates a critical point
//!   on a path ([`crate::series::bifurcation`]).
//!
//! Why our own: the shift-invert step needs a sparse symmetric
//! factorization with inertia, which [`super::LinearSolver`] already is
//! (faer LDLᵀ / LBLᵀ, MUMPS). The Rust candidates seen (docs.rs, 2026):
//! `arpack` 0.0.x (early scaffolding around a system ARPACK-NG found by
//! pkg-config, libarpack2-dev, a Fortran library not on our build
//! machines; its first releases give one eigenpair only) and
//! `scirs2-sparse` (its own sparse formats and factorizations, a large
//! dependency tree, none of our LDLᵀ or MUMPS); nalgebra and faer are dense
//! only. Subspace iteration is a few dozen lines over our factorization and
//! converges in 5–10 iterations on the lowest buckling modes of our cases
//! (Euler column, plate: tests/shell/bifurcation.rs).

use super::{Factorization, dot, norm};
use nalgebra::DMatrix;

/// One eigenpair of (A + mu B) phi = 0.
#[derive(Clone, Debug)]
pub struct Eigenpair {
    pub mu: f64,
    /// Normalized to |phi| = 1 (Euclidean).
    pub vector: Vec<f64>,
    /// |A phi + mu B phi| / |A phi|.
    pub residual: f64,
}

/// Settings of [`pencil`].
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Wanted pairs k.
    pub count: usize,
    /// Convergence: every wanted residual |A phi + mu B phi| / |A phi| below
    /// this (the eigenvalue is then accurate to about its square).
    pub tol: f64,
    pub max_iter: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            count: 4,
            tol: 1e-6,
            max_iter: 300,
        }
    }
}

/// What [`pencil`] did.
#[derive(Clone, Debug, Default)]
pub struct Work {
    pub iterations: usize,
    pub solves: usize,
    pub subspace: usize,
}

/// Deterministic start vectors with entries in (−1, 1) (a linear
/// congruential generator: reproducible runs).
fn start_vectors(n: usize, q: usize) -> Vec<Vec<f64>> {
    let mut s: u64 = 0x2545_F491_4F6C_DD1D;
    (0..q)
        .map(|_| {
            (0..n)
                .map(|_| {
                    s = s
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
                })
                .collect()
        })
        .collect()
}

/// Modified Gram–Schmidt, twice; a column that vanishes is replaced by a
/// fresh start vector made orthogonal to the others.
fn orthonormalize(y: &mut [Vec<f64>]) {
    let n = y.first().map_or(0, Vec::len);
    let mut spare = start_vectors(n, y.len() + 3).into_iter().rev();
    for j in 0..y.len() {
        for _attempt in 0..3 {
            let before = norm(&y[j]);
            for _pass in 0..2 {
                for i in 0..j {
                    let c = dot(&y[i], &y[j]);
                    let (head, tail) = y.split_at_mut(j);
                    for (t, h) in tail[0].iter_mut().zip(&head[i]) {
                        *t -= c * h;
                    }
                }
            }
            let after = norm(&y[j]);
            if after > 1e-10 * before && after > 0.0 {
                y[j].iter_mut().for_each(|v| *v /= after);
                break;
            }
            y[j] = spare.next().unwrap_or_else(|| vec![1.0; n]);
        }
    }
}

/// The `settings.count` eigenpairs of (A + mu B) phi = 0 of smallest |mu|,
/// in increasing |mu| (module docs). `a` is the factorization of A (which
/// must be positive definite on the iterated subspace: an error says so
/// otherwise), `a_mul` and `b_mul` the products with A and B.
pub fn pencil(
    a: &Factorization,
    a_mul: &dyn Fn(&[f64]) -> Vec<f64>,
    b_mul: &dyn Fn(&[f64]) -> Vec<f64>,
    n: usize,
    settings: &Settings,
) -> Result<(Vec<Eigenpair>, Work), String> {
    let k = settings.count.min(n);
    if k == 0 {
        return Ok((vec![], Work::default()));
    }
    let q = (2 * k).max(k + 8).min(n);
    let mut work = Work {
        subspace: q,
        ..Default::default()
    };
    let mut x = start_vectors(n, q);
    let mut bx: Vec<Vec<f64>> = x.iter().map(|v| b_mul(v)).collect();
    let mut last: Vec<Eigenpair> = vec![];
    for it in 1..=settings.max_iter {
        work.iterations = it;
        // Y = A⁻¹ B X, orthonormalized (keeps the projected matrices well
        // conditioned; the span is unchanged).
        let mut y: Vec<Vec<f64>> = bx.iter().map(|b| a.solve(b)).collect();
        work.solves += q;
        if y.iter().flatten().any(|v| !v.is_finite()) {
            return Err("non-finite solve with A (singular?)".into());
        }
        orthonormalize(&mut y);
        let ay: Vec<Vec<f64>> = y.iter().map(|v| a_mul(v)).collect();
        let by: Vec<Vec<f64>> = y.iter().map(|v| b_mul(v)).collect();
        let ar = DMatrix::from_fn(q, q, |i, j| 0.5 * (dot(&y[i], &ay[j]) + dot(&y[j], &ay[i])));
        let br = DMatrix::from_fn(q, q, |i, j| 0.5 * (dot(&y[i], &by[j]) + dot(&y[j], &by[i])));
        let chol = ar.clone().cholesky().ok_or_else(|| {
            "A is not positive definite on the iterated subspace (an unstable base state?)"
                .to_string()
        })?;
        let l_inv = chol
            .l()
            .try_inverse()
            .ok_or_else(|| "singular Cholesky factor of the projected A".to_string())?;
        let c = &l_inv * &br * l_inv.transpose();
        let c = 0.5 * (&c + c.transpose());
        let eig = c.symmetric_eigen();
        let mut order: Vec<usize> = (0..q).collect();
        order.sort_by(|&i, &j| {
            eig.eigenvalues[j]
                .abs()
                .total_cmp(&eig.eigenvalues[i].abs())
        });
        // Ritz vectors z = L⁻ᵀ w (A-orthonormal), X = Y Z, and A X, B X.
        let z = l_inv.transpose() * &eig.eigenvectors;
        let combine = |basis: &[Vec<f64>], col: usize| -> Vec<f64> {
            let mut out = vec![0.0; n];
            for (r, b) in basis.iter().enumerate() {
                let w = z[(r, col)];
                out.iter_mut().zip(b).for_each(|(o, v)| *o += w * v);
            }
            out
        };
        let mut pairs = vec![];
        let mut converged = true;
        x = Vec::with_capacity(q);
        bx = Vec::with_capacity(q);
        for (rank, &col) in order.iter().enumerate() {
            let xv = combine(&y, col);
            let bv = combine(&by, col);
            if rank < k {
                let theta = eig.eigenvalues[col];
                let av = combine(&ay, col);
                let mu = if theta != 0.0 {
                    -1.0 / theta
                } else {
                    f64::INFINITY
                };
                let r: Vec<f64> = av.iter().zip(&bv).map(|(a, b)| a + mu * b).collect();
                let residual = norm(&r) / norm(&av).max(f64::MIN_POSITIVE);
                if !(residual <= settings.tol) {
                    converged = false;
                }
                let s = norm(&xv);
                pairs.push(Eigenpair {
                    mu,
                    vector: xv.iter().map(|v| v / s).collect(),
                    residual,
                });
            }
            x.push(xv);
            bx.push(bv);
        }
        if converged {
            return Ok((pairs, work));
        }
        last = pairs;
    }
    Err(unconverged(&last, settings.max_iter, q))
}

/// Why the subspace iteration stopped, with its last estimates: their mu
/// range, largest residual, and the sign that tells a load stiffening the
/// base state (every mu < 0: K_sigma positive on the subspace, e.g. a
/// membrane in pure tension, with no critical load in the load's direction).
fn unconverged(last: &[Eigenpair], iterations: usize, vectors: usize) -> String {
    let mut s = format!(
        "subspace iteration did not converge in {iterations} iterations ({vectors} vectors)"
    );
    if last.is_empty() {
        return s;
    }
    let lo = last.iter().map(|p| p.mu).fold(f64::INFINITY, f64::min);
    let hi = last.iter().map(|p| p.mu).fold(f64::NEG_INFINITY, f64::max);
    let worst = last.iter().map(|p| p.residual).fold(0.0, f64::max);
    s += &format!("; last estimates of mu in [{lo:.3e}, {hi:.3e}], residuals up to {worst:.1e}");
    if hi < 0.0 {
        s += "; every estimate is negative: the load stiffens this base state \
              (tension), so no critical load may lie in its direction";
    }
    s
}

/// y = A⁻¹ x of an inverse iteration; a non-finite solve is an error.
fn inverse_step(a: &Factorization, x: &[f64]) -> Result<Vec<f64>, String> {
    let y = a.solve(x);
    if y.iter().any(|v| !v.is_finite()) {
        return Err("non-finite solve in inverse iteration (singular matrix)".into());
    }
    Ok(y)
}

/// `start` (or a fixed vector when it is absent, empty or of the wrong
/// length), normalized.
fn unit_start(start: Option<&[f64]>, n: usize) -> Vec<f64> {
    let mut x = match start {
        Some(s) if s.len() == n && norm(s) > 0.0 => s.to_vec(),
        _ => start_vectors(n, 1).pop().unwrap_or_default(),
    };
    let s = norm(&x);
    x.iter_mut().for_each(|v| *v /= s);
    x
}

/// What [`smallest_eigenvalue`] did.
#[derive(Clone, Copy, Debug, Default)]
pub struct InverseWork {
    pub solves: usize,
    pub iterations: usize,
    /// Vectors iterated at the end (1, or [`CLUSTER_BLOCK`] after a switch).
    pub block: usize,
}

/// Block size of [`smallest_eigenvalue`] once single-vector inverse
/// iteration is seen to converge slowly (clustered eigenvalues nearest
/// zero): the rate becomes |kappa_1 / kappa_5| instead of |kappa_1 / kappa_2|.
pub const CLUSTER_BLOCK: usize = 4;

/// The eigenvalue of smallest modulus of the symmetric A (factorized as
/// `a`, products by `a_mul`) and its unit eigenvector, by inverse iteration
/// from `start` (or a fixed vector) with Rayleigh–Ritz on the iterated
/// block (Golub & Van Loan, *Matrix Computations*, 4th ed., §8.2.2 and
/// §8.2.4, "orthogonal iteration" on A⁻¹).
///
/// Stopping test on the Ritz pair (theta, x) of smallest |theta| with
/// residual r = A x − theta x: with one vector, the change of theta
/// between iterations below `tol` |theta|; with a block, the Rayleigh
/// quotient's error bound |r|² / gap below `tol` |theta| (gap: distance to
/// the next Ritz value; Parlett, *The Symmetric Eigenvalue Problem*,
/// Thm 11.7.1); or, in both, |r| below the absolute floor 100 eps |A| (|A|
/// estimated by |A s| / |s| for a fixed vector s): theta is then within
/// round-off of an eigenvalue (Bauer–Fike), and a relative test alone can
/// never pass for an eigenvalue at round-off level (kappa at a located
/// root).
///
/// One vector first; when the residual falls by less than a factor 2 per
/// iteration from the fourth on (close eigenvalues nearest zero), the
/// block grows to [`CLUSTER_BLOCK`] vectors (the current one and fixed
/// start vectors). At most `max_iter` iterations; returns the last Ritz
/// pair then.
pub fn smallest_eigenvalue(
    a: &Factorization,
    a_mul: &dyn Fn(&[f64]) -> Vec<f64>,
    n: usize,
    start: Option<&[f64]>,
    tol: f64,
    max_iter: usize,
) -> Result<(f64, Vec<f64>, InverseWork), String> {
    let probe = start_vectors(n, 1).pop().unwrap_or_default();
    let a_norm = norm(&a_mul(&probe)) / norm(&probe).max(f64::MIN_POSITIVE);
    let floor = 100.0 * f64::EPSILON * a_norm;
    let mut x = vec![unit_start(start, n)];
    let mut work = InverseWork::default();
    let mut last = (f64::NAN, x[0].clone());
    let mut previous_residual = f64::INFINITY;
    for it in 1..=max_iter {
        work.iterations = it;
        let mut y = x
            .iter()
            .map(|v| inverse_step(a, v))
            .collect::<Result<Vec<_>, _>>()?;
        work.solves += y.len();
        orthonormalize(&mut y);
        let ay: Vec<Vec<f64>> = y.iter().map(|v| a_mul(v)).collect();
        let p = y.len();
        let h = DMatrix::from_fn(p, p, |i, j| 0.5 * (dot(&y[i], &ay[j]) + dot(&y[j], &ay[i])));
        let eig = h.symmetric_eigen();
        let mut order: Vec<usize> = (0..p).collect();
        order.sort_by(|&i, &j| {
            eig.eigenvalues[i]
                .abs()
                .total_cmp(&eig.eigenvalues[j].abs())
        });
        let combine = |basis: &[Vec<f64>], col: usize| -> Vec<f64> {
            let mut out = vec![0.0; n];
            for (r, b) in basis.iter().enumerate() {
                let w = eig.eigenvectors[(r, col)];
                out.iter_mut().zip(b).for_each(|(o, v)| *o += w * v);
            }
            out
        };
        let theta = eig.eigenvalues[order[0]];
        let xv = combine(&y, order[0]);
        let av = combine(&ay, order[0]);
        let residual = norm(
            &av.iter()
                .zip(&xv)
                .map(|(a, x)| a - theta * x)
                .collect::<Vec<_>>(),
        );
        let gap = order[1..]
            .iter()
            .map(|&j| (eig.eigenvalues[j] - theta).abs())
            .fold(f64::INFINITY, f64::min);
        // One vector: the Rayleigh quotient's change (its error is of the
        // order of the change when converging linearly); a block: |r|² / gap.
        let bound = if p == 1 {
            (theta - last.0).abs()
        } else if gap > residual {
            residual * residual / gap
        } else {
            residual
        };
        // Ritz vectors as the next block (smallest |theta| first).
        x = order.iter().map(|&j| combine(&y, j)).collect();
        let s = norm(&x[0]);
        last = (theta, x[0].iter().map(|v| v / s).collect());
        if bound <= tol * theta.abs() || residual <= floor {
            work.block = p;
            return Ok((last.0, last.1, work));
        }
        if p == 1 && it >= 4 && residual > 0.5 * previous_residual && n > CLUSTER_BLOCK {
            x.extend(start_vectors(n, CLUSTER_BLOCK).into_iter().skip(1));
            x.truncate(CLUSTER_BLOCK);
        }
        previous_residual = residual;
    }
    work.block = x.len();
    Ok((last.0, last.1, work))
}

/// The real eigenvalue nearest zero of a general (non-symmetric) A and its
/// unit right eigenvector, by inverse iteration: y = A⁻¹ x, kappa =
/// 1 / (x · y) for |x| = 1 (exact once x is an eigenvector), until kappa
/// changes by less than `tol` relative. The eigenvector's sign follows
/// `start`. A complex pair nearest zero does not converge: an error.
pub fn nearest_real_eigenvalue(
    a: &Factorization,
    n: usize,
    start: Option<&[f64]>,
    tol: f64,
    max_iter: usize,
) -> Result<(f64, Vec<f64>, usize), String> {
    let mut x = unit_start(start, n);
    let reference = x.clone();
    let mut kappa = f64::NAN;
    for it in 1..=max_iter {
        let y = inverse_step(a, &x)?;
        let next = 1.0 / dot(&x, &y);
        let s = norm(&y) * dot(&y, &reference).signum();
        x = y.iter().map(|v| v / s).collect();
        if (next - kappa).abs() <= tol * next.abs() {
            return Ok((next, x, it));
        }
        kappa = next;
    }
    Err(format!(
        "inverse iteration did not converge in {max_iter} solves (complex eigenvalues nearest zero?)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{LinearSolver, SparseMatrix};

    /// tridiag(−1, 2, −1) of size m: eigenvalues 2 − 2 cos(j pi / (m + 1)).
    fn laplacian(m: usize, shift: f64) -> SparseMatrix {
        let mut a = SparseMatrix::new(m);
        for i in 0..m {
            a.add(i, i, 2.0 + shift);
            if i > 0 {
                a.add(i, i - 1, -1.0);
                a.add(i - 1, i, -1.0);
            }
        }
        a
    }

    #[test]
    fn pencil_gives_the_lowest_eigenvalues_of_a_discrete_laplacian() {
        // (A − mu I) phi = 0 with A the 1D Laplacian: mu_j = 2 − 2 cos(j pi / (m + 1)).
        let m = 200;
        let a = laplacian(m, 0.0);
        let f = LinearSolver::default().factorize(&a).unwrap();
        let s = Settings {
            count: 3,
            tol: 1e-9,
            max_iter: 500,
        };
        let (pairs, _) = pencil(
            &f,
            &|x| a.mul_vec(x),
            &|x| x.iter().map(|v| -v).collect(),
            m,
            &s,
        )
        .unwrap();
        for (j, p) in pairs.iter().enumerate() {
            let exact = 2.0 - 2.0 * ((j + 1) as f64 * std::f64::consts::PI / (m + 1) as f64).cos();
            assert!(
                (p.mu / exact - 1.0).abs() < 1e-10,
                "{j}: {} vs {exact}",
                p.mu
            );
        }
    }

    /// B = +I (a load that stiffens, as tension does): every mu is
    /// negative, and a run stopped before convergence says so with its
    /// estimates instead of calling the matrix singular.
    #[test]
    fn an_unconverged_pencil_reports_its_estimates_and_a_stiffening_load() {
        let m = 200;
        let a = laplacian(m, 0.0);
        let f = LinearSolver::default().factorize(&a).unwrap();
        let s = Settings {
            count: 3,
            tol: 1e-14,
            max_iter: 2,
        };
        let e = pencil(&f, &|x| a.mul_vec(x), &|x| x.to_vec(), m, &s).unwrap_err();
        assert!(e.contains("did not converge in 2 iterations"), "{e}");
        assert!(e.contains("last estimates of mu in [-"), "{e}");
        assert!(e.contains("every estimate is negative"), "{e}");
    }

    #[test]
    fn inverse_iteration_finds_the_eigenvalue_nearest_zero_of_an_indefinite_matrix() {
        let m = 50;
        // Shifted so that one eigenvalue sits just below zero.
        let e = |j: usize| 2.0 - 2.0 * (j as f64 * std::f64::consts::PI / (m + 1) as f64).cos();
        let shift = -0.5 * (e(3) + e(4)) + 1e-3;
        let a = laplacian(m, shift);
        let f = LinearSolver::default().factorize(&a).unwrap();
        let (k, _, _) = smallest_eigenvalue(&f, &|x| a.mul_vec(x), m, None, 1e-14, 500).unwrap();
        let exact = (1..=m)
            .map(|j| e(j) + shift)
            .min_by(|x, y| x.abs().total_cmp(&y.abs()))
            .unwrap();
        assert!((k / exact - 1.0).abs() < 1e-9, "{k} vs {exact}");
    }

    #[test]
    fn close_eigenvalues_nearest_zero_switch_to_a_block() {
        // Diagonal with 1e-3 and 1.001e-3 nearest zero: one vector
        // converges at the rate 0.999 per iteration; the block at 1e-3 / 0.5.
        let m = 60;
        let mut a = SparseMatrix::new(m);
        for i in 0..m {
            let d = match i {
                7 => 1.001e-3,
                23 => 1e-3,
                _ => 0.5 + i as f64 * 0.01,
            };
            a.add(i, i, d);
        }
        let f = LinearSolver::default().factorize(&a).unwrap();
        let (k, x, work) = smallest_eigenvalue(&f, &|x| a.mul_vec(x), m, None, 1e-12, 200).unwrap();
        assert_eq!(work.block, CLUSTER_BLOCK);
        assert!((k / 1e-3 - 1.0).abs() < 1e-10, "{k}");
        assert!(x[23].abs() > 1.0 - 1e-6, "{}", x[23]);
        assert!(work.iterations < 60, "{work:?}");
    }

    #[test]
    fn an_eigenvalue_at_round_off_stops_at_the_absolute_floor() {
        // The Laplacian shifted by its smallest eigenvalue: kappa ~ 1e-16,
        // which no relative test on the Rayleigh quotient can pass.
        let m = 50;
        let e1 = 2.0 - 2.0 * (std::f64::consts::PI / (m + 1) as f64).cos();
        let a = laplacian(m, -e1);
        let f = LinearSolver::default().factorize(&a).unwrap();
        let (k, _, work) = smallest_eigenvalue(&f, &|x| a.mul_vec(x), m, None, 1e-12, 200).unwrap();
        assert!(k.abs() < 1e-12, "{k}");
        assert!(work.iterations < 10, "{work:?}");
    }
}

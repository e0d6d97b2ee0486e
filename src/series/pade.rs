//! Padé approximants with a common denominator for vector series
//! (Najah, Cochelin, Damil, Potier-Ferry, Commun. Numer. Meth. Eng. 14 (1998);
//! Cochelin, Damil, Potier-Ferry 2007, §4.4).
//!
//! The terms W_1..W_{n-1} are orthonormalised (Gram-Schmidt) into w*_j with
//! W_k = sum_{j<=k} alpha_{kj} w*_j, and W_n is projected on them. The
//! denominator coefficients follow from
//!   d_1 = -alpha_{n,n-1}/alpha_{n-1,n-1},
//!   d_i = -(alpha_{n,n-i} + sum_{j=1}^{i-1} d_j alpha_{n-j,n-i}) / alpha_{n-i,n-i},
//! and the approximant is W(a) = sum_{k=1}^{n-1} a^k W_k D_{n-1-k}(a)/D_{n-1}(a),
//! with D_m(a) = 1 + sum_{i=1}^{m} d_i a^i.

use crate::linalg::{dot, norm};
use rayon::prelude::*;

/// Unknowns from which the terms are orthogonalized on the pool's threads.
const PARALLEL_LEN: usize = 4096;

/// Relative size below which an orthogonalized term counts as dependent on
/// the previous ones (its denominator coefficients would be noise).
const DEPENDENT: f64 = 1e-9;

/// a·b in 8 interleaved partial sums. The orthogonalization takes ~n²/2
/// dot products over all the unknowns, and one running sum waits for each
/// addition (latency-bound: 4.6 ms per step at 25,200 unknowns, N = 15);
/// 8 sums run at the speed of the loads. The rounding differs from
/// [`dot`]'s by the usual few ulps of the sum's magnitudes.
fn dot_interleaved(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = dot(ca.remainder(), cb.remainder());
    let mut s = [0.0; 8];
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            s[i] += x[i] * y[i];
        }
    }
    ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7])) + tail
}

/// |a| by [`dot_interleaved`]; by [`norm`] where the sum of squares leaves
/// the normal range (its scaled path).
fn norm_interleaved(a: &[f64]) -> f64 {
    let s = dot_interleaved(a, a);
    if s.is_finite() && s >= f64::MIN_POSITIVE {
        s.sqrt()
    } else {
        norm(a)
    }
}

/// Common-denominator Padé approximant built from `terms[1..=n]` (fewer when
/// the last terms are numerically dependent; see [`Pade::terms_used`]).
#[derive(Clone, Debug)]
pub struct Pade {
    /// d_1..d_{n-1}.
    d: Vec<f64>,
}

/// The modified Gram–Schmidt of W_1..W_n: W_k = Σ_{j≤min(k, n−1)} α_kj w*_j
/// (+ a remainder ⊥ w*_1..w*_{n−1} for k = n), stopped at the first W_k
/// (k ≤ n − 1) in the span of the previous ones.
struct Orthogonalized {
    /// α[k−1][j−1], k = 1..=n, j = 1..=min(k, n − 1).
    alpha: Vec<Vec<f64>>,
    /// The terms W_1..W_n used: n' ≤ n.
    n: usize,
}

impl Orthogonalized {
    /// Of W_1..W_n', n' ≤ n the longest prefix whose first n' − 1 terms are
    /// numerically independent; `None` when fewer than 3 terms remain.
    fn new(terms: &[Vec<f64>], n: usize) -> Option<Self> {
        if n < 3 {
            return None;
        }
        let m = n - 1;
        let mut alpha = vec![vec![0.0; m]; n];
        // Right-looking: once w*_k is formed, it is taken off every later
        // term at once. Each term meets w*_1, w*_2, … in order, each time
        // in its current state: the same operations as term by term, so
        // the same bits, but the later terms are independent of each other
        // (on 2 threads from PARALLEL_LEN unknowns: the orthogonalization
        // cost ~1.2 ms per step on one at 12,600 unknowns, N = 15).
        let mut w: Vec<Vec<f64>> = terms[1..=n].to_vec();
        for k in 1..=m {
            let nk = norm_interleaved(&w[k - 1]);
            if !(nk > DEPENDENT * norm_interleaved(&terms[k])) {
                // W_k is (numerically) in the span of W_1..W_{k-1}: build
                // the approximant from W_1..W_k instead, whose W_k is
                // then exactly represented by the basis.
                return if k >= 3 && k < n {
                    alpha.truncate(k);
                    for row in &mut alpha {
                        row.truncate(k - 1);
                    }
                    Some(Self { alpha, n: k })
                } else {
                    None
                };
            }
            alpha[k - 1][k - 1] = nk;
            let (done, later) = w.split_at_mut(k);
            let basis = &mut done[k - 1];
            for x in basis.iter_mut() {
                *x /= nk;
            }
            let basis = &*basis;
            // Modified Gram-Schmidt: a = <W_l, w*_k>, then W_l −= a w*_k.
            let take_off = |(wl, row): (&mut Vec<f64>, &mut Vec<f64>)| {
                let a = dot_interleaved(wl, basis);
                row[k - 1] = a;
                for (wi, bi) in wl.iter_mut().zip(basis) {
                    *wi -= a * bi;
                }
            };
            let rows = &mut alpha[k..];
            if basis.len() >= PARALLEL_LEN {
                later.par_iter_mut().zip(rows).for_each(take_off);
            } else {
                later.iter_mut().zip(rows).for_each(take_off);
            }
        }
        Some(Self { alpha, n })
    }

    /// The approximant of W_1..W_p (3 ≤ p ≤ n), whose coefficients are
    /// those of this orthogonalization's first p rows: the Gram–Schmidt of
    /// a prefix is the prefix of the Gram–Schmidt.
    fn pade(&self, p: usize) -> Option<Pade> {
        if p < 3 || p > self.n {
            return None;
        }
        let al = |k: usize, j: usize| self.alpha[k - 1][j - 1];
        let m = p - 1;
        let mut d = Vec::with_capacity(m);
        for i in 1..=m {
            let mut s = al(p, p - i);
            for j in 1..i {
                s += d[j - 1] * al(p - j, p - i);
            }
            d.push(-s / al(p - i, p - i));
        }
        d.iter().all(|x| x.is_finite()).then_some(Pade { d })
    }

    /// |Σ_k c_k W_k| for k ≤ n − 1, from the coordinates on the orthonormal
    /// w*_j: no pass over the vectors.
    fn norm_of(&self, c: &[f64]) -> f64 {
        (1..self.n)
            .map(|j| {
                let cj: f64 = (j..=c.len())
                    .map(|k| c[k - 1] * self.alpha[k - 1][j - 1])
                    .sum();
                cj * cj
            })
            .sum::<f64>()
            .sqrt()
    }
}

impl Pade {
    /// Uses the longest prefix W_1..W_n' (n' <= n) whose first n' - 1 terms are
    /// numerically independent; returns `None` when fewer than 3 terms remain
    /// (the polynomial should then be used).
    pub fn new(terms: &[Vec<f64>], n: usize) -> Option<Self> {
        let o = Orthogonalized::new(terms, n)?;
        o.pade(o.n)
    }

    /// Number n' of series terms the approximant is built from.
    pub fn terms_used(&self) -> usize {
        self.d.len() + 1
    }

    /// D_j(a) for j = 0..=n-1.
    fn denominators(&self, a: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.d.len() + 1);
        let mut acc = 1.0;
        let mut ai = 1.0;
        out.push(acc);
        for di in &self.d {
            ai *= a;
            acc += di * ai;
            out.push(acc);
        }
        out
    }

    /// The weights f_k(a) = a^k D_{m-k}(a) / D_m(a), k = 1..=m, of the
    /// increment W(a) - W_0 = sum_k f_k(a) W_k: the approximant is linear
    /// in the terms, so one component (lambda) costs m products.
    pub fn weights(&self, a: f64) -> Vec<f64> {
        let m = self.d.len();
        let dens = self.denominators(a);
        let mut ak = 1.0;
        (1..=m)
            .map(|k| {
                ak *= a;
                ak * dens[m - k] / dens[m]
            })
            .collect()
    }

    /// The increment W(a) - W_0.
    pub fn eval(&self, terms: &[Vec<f64>], a: f64) -> Vec<f64> {
        let mut out = vec![0.0; terms[1].len()];
        self.eval_into(terms, a, &mut out);
        out
    }

    /// [`Pade::eval`] into `out` (no allocation).
    pub fn eval_into(&self, terms: &[Vec<f64>], a: f64, out: &mut [f64]) {
        out.fill(0.0);
        for (f, t) in self.weights(a).iter().zip(&terms[1..]) {
            for (o, t) in out.iter_mut().zip(t) {
                *o += f * t;
            }
        }
    }

    /// Smallest positive real root of D_{n-1} below `limit`, if any.
    pub fn pole(&self, limit: f64) -> Option<f64> {
        let m = self.d.len();
        let f = |a: f64| self.denominators(a)[m];
        let samples = 400;
        let mut lo = 0.0;
        let mut flo: f64 = 1.0;
        for s in 1..=samples {
            let hi = limit * s as f64 / samples as f64;
            let fhi = f(hi);
            if fhi.signum() != flo.signum() {
                let (mut a, mut b) = (lo, hi);
                for _ in 0..60 {
                    let c = 0.5 * (a + b);
                    if f(c).signum() == flo.signum() {
                        a = c;
                    } else {
                        b = c;
                    }
                }
                return Some(a);
            }
            lo = hi;
            flo = fhi;
        }
        None
    }
}

/// Range of the Padé approximant: the largest a in [a_poly, a_cap] (below the
/// first pole) with |P_n(a) - P_{n-1}(a)| <= eps |P_n(a)|, found by bisection;
/// with P_n, which the step then uses. Returns `None` when Padé cannot be
/// built.
pub fn range(
    terms: &[Vec<f64>],
    n: usize,
    eps: f64,
    a_poly: f64,
    a_cap: f64,
) -> Option<(f64, Pade)> {
    let o = Orthogonalized::new(terms, n)?;
    let pn = o.pade(o.n)?;
    let pm = o.pade(o.n - 1)?;
    let mut hi = a_cap;
    for p in [&pn, &pm] {
        if let Some(pole) = p.pole(a_cap) {
            hi = hi.min(0.95 * pole);
        }
    }
    if hi <= a_poly {
        return Some((a_poly, pn));
    }
    // Both approximants are combinations of W_1..W_{n'−1} (the weights of
    // P_{n−1} stop one term earlier): their norms come from the
    // orthogonalization's coordinates, without a pass over the vectors.
    let ok = |a: f64| {
        let x = pn.weights(a);
        let mut diff = x.clone();
        for (d, g) in diff.iter_mut().zip(pm.weights(a)) {
            *d -= g;
        }
        o.norm_of(&diff) <= eps * o.norm_of(&x)
    };
    if !ok(a_poly) {
        return Some((a_poly, pn));
    }
    if ok(hi) {
        return Some((hi, pn));
    }
    let (mut lo, mut up) = (a_poly, hi);
    for _ in 0..40 {
        let mid = 0.5 * (lo + up);
        if ok(mid) {
            lo = mid;
        } else {
            up = mid;
        }
    }
    Some((lo, pn))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_a_rational_vector_function() {
        // W_i(a) = a^i / (1 - 2a), i = 1..11: W_k = sum_{i<=k} e_i 2^(k-i).
        // The common-denominator approximant is exact, and its pole is 0.5,
        // beyond the polynomial's radius of convergence.
        let n = 12;
        let dim = n - 1;
        let mut terms = vec![vec![0.0; dim]];
        for k in 1..=n {
            let t: Vec<f64> = (1..=dim)
                .map(|i| {
                    if i <= k {
                        2f64.powi((k - i) as i32)
                    } else {
                        0.0
                    }
                })
                .collect();
            terms.push(t);
        }
        let p = Pade::new(&terms, n).expect("pade");
        let a = 0.45;
        let got = p.eval(&terms, a);
        for i in 1..=dim {
            let want = a.powi(i as i32) / (1.0 - 2.0 * a);
            assert!(
                (got[i - 1] - want).abs() < 1e-10 * want.abs().max(1.0),
                "{i}: {} vs {want}",
                got[i - 1]
            );
        }
        let pole = p.pole(1.0).expect("pole");
        assert!((pole - 0.5).abs() < 1e-9, "pole {pole}");
    }

    /// Terms of a sum of 12 rational vector functions with poles at
    /// a = 0.6 … 2.8: independent terms.
    fn series_terms(n: usize, dim: usize) -> Vec<Vec<f64>> {
        (0..=n)
            .map(|k| {
                (0..dim)
                    .map(|i| {
                        (0..12)
                            .map(|s| {
                                let c = (0.7 * (s * i) as f64 + s as f64).cos();
                                c / (0.6 + 0.2 * s as f64).powi(k as i32)
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect()
    }

    /// The approximant of a prefix from the full orthogonalization is the
    /// one built from the prefix alone, bit for bit, and the norms from
    /// coordinates are those of the evaluated vectors.
    #[test]
    fn one_orthogonalization_gives_both_approximants_and_their_norms() {
        let (n, dim) = (10, 40);
        let terms = series_terms(n, dim);
        let o = Orthogonalized::new(&terms, n).expect("orthogonalized");
        assert_eq!(o.n, n);
        let alone = Pade::new(&terms, n - 1).expect("pade");
        let prefix = o.pade(n - 1).expect("prefix");
        assert_eq!(alone.d, prefix.d);
        let pn = o.pade(n).expect("pade");
        for a in [0.05, 0.2, 0.5] {
            let (x, y) = (pn.eval(&terms, a), prefix.eval(&terms, a));
            let diff: Vec<f64> = x.iter().zip(&y).map(|(x, y)| x - y).collect();
            let w = pn.weights(a);
            let mut dw = w.clone();
            for (d, g) in dw.iter_mut().zip(prefix.weights(a)) {
                *d -= g;
            }
            for (got, want) in [(o.norm_of(&w), norm(&x)), (o.norm_of(&dw), norm(&diff))] {
                assert!(
                    (got - want).abs() <= 1e-12 * norm(&x),
                    "a = {a}: {got:e} against {want:e}"
                );
            }
        }
    }

    /// The interleaved sums give the dot product and the norm to round-off,
    /// for lengths that are not multiples of 8, and the norm keeps its
    /// scaled path past the normal range of the sum of squares.
    #[test]
    fn interleaved_dot_and_norm_match_the_plain_ones() {
        for len in [0, 1, 7, 8, 9, 1001] {
            let a: Vec<f64> = (0..len).map(|i| (0.37 * i as f64).sin()).collect();
            let b: Vec<f64> = (0..len).map(|i| (0.11 * i as f64 + 1.0).cos()).collect();
            let scale = dot(
                &a.iter().map(|x| x.abs()).collect::<Vec<_>>(),
                &vec![1.0; len],
            );
            assert!((dot_interleaved(&a, &b) - dot(&a, &b)).abs() <= 1e-15 * scale.max(1.0));
            assert!((norm_interleaved(&a) - norm(&a)).abs() <= 1e-15 * norm(&a).max(1.0));
        }
        let big = vec![1e200, -3e200, 2e199];
        assert!(dot_interleaved(&big, &big).is_infinite());
        assert_eq!(norm_interleaved(&big), norm(&big));
        assert!(norm_interleaved(&big).is_finite());
    }
}

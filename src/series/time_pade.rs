//! Scalar Padé approximants of the series in time, one per unknown
//! (Baker & Graves-Morris, Padé Approximants, 2nd ed., §1.1): [L/M] with
//! L = M = N/2 from c_0..c_N, and its error estimate against [L-1/M] (built
//! from c_0..c_{N-1}). The common-denominator approximants of `pade.rs`
//! need as many independent terms as orders, i.e. at least N unknowns; a
//! DAE in time has a handful, hence one denominator per unknown here.
//!
//! Denominator b (b_0 = 1): sum_{j=0}^{M} b_j c_{k-j} = 0, k = L+1..L+M;
//! numerator a_k = sum_{j=0}^{min(k,M)} b_j c_{k-j}, k = 0..L.

use crate::linalg::DenseLu;

/// P(a) = num(a) / den(a) for one unknown.
#[derive(Clone, Debug)]
pub struct ScalarPade {
    num: Vec<f64>,
    den: Vec<f64>,
}

impl ScalarPade {
    /// [l/m] from c (needs c.len() > l + m); the polynomial when the
    /// Toeplitz system is singular.
    pub fn new(c: &[f64], l: usize, m: usize) -> Self {
        let poly = || Self {
            num: c[..=l + m].to_vec(),
            den: vec![1.0],
        };
        let at = |k: isize| if k < 0 { 0.0 } else { c[k as usize] };
        let mut lu = DenseLu::default();
        lu.factorize(m, |r, col| at((l + 1 + r) as isize - (col + 1) as isize));
        let mut b: Vec<f64> = (0..m).map(|r| -c[l + 1 + r]).collect();
        let max_pivot = (0..m).map(|i| lu.pivot(i)).fold(0.0, f64::max);
        let min_pivot = (0..m).map(|i| lu.pivot(i)).fold(f64::INFINITY, f64::min);
        if m == 0 || !(min_pivot > 1e-13 * max_pivot) || !lu.solve_in_place(&mut b) {
            return poly();
        }
        let mut den = vec![1.0];
        den.extend(b);
        if !den.iter().all(|x| x.is_finite()) {
            return poly();
        }
        let num = (0..=l)
            .map(|k| (0..=k.min(m)).map(|j| den[j] * c[k - j]).sum())
            .collect();
        Self { num, den }
    }

    pub fn eval(&self, a: f64) -> f64 {
        super::taylor::eval(&self.num, a) / super::taylor::eval(&self.den, a)
    }

    /// Whether the denominator keeps its sign on [0, a] (no pole there).
    fn pole_free(&self, a: f64) -> bool {
        (1..=64).all(|s| super::taylor::eval(&self.den, a * s as f64 / 64.0) > 0.0)
    }
}

/// Approximants [N/2 / N/2] of every series, and the largest a in
/// [a_poly, cap] with |P_N(a) - P_{N-1}(a)| <= eps |P_N(a) - y_0| (norms
/// over the unknowns) and no pole in [0, a] (bisection). None when the
/// approximants do not reach beyond a_poly.
pub fn range(
    series: &[Vec<f64>],
    n: usize,
    eps: f64,
    a_poly: f64,
    cap: f64,
) -> Option<(f64, Vec<ScalarPade>)> {
    let m = n / 2;
    let l = n - m;
    let pn: Vec<ScalarPade> = series.iter().map(|c| ScalarPade::new(c, l, m)).collect();
    let pm: Vec<ScalarPade> = series
        .iter()
        .map(|c| ScalarPade::new(c, l - 1, m))
        .collect();
    let ok = |a: f64| {
        let (mut diff, mut inc) = (0.0, 0.0);
        for ((p, q), c) in pn.iter().zip(&pm).zip(series) {
            if !p.pole_free(a) || !q.pole_free(a) {
                return false;
            }
            let (x, y) = (p.eval(a), q.eval(a));
            diff += (x - y) * (x - y);
            inc += (x - c[0]) * (x - c[0]);
        }
        diff.is_finite() && diff.sqrt() <= eps * inc.sqrt()
    };
    if !ok(a_poly) {
        return None;
    }
    let (mut lo, mut hi) = (a_poly, cap);
    if ok(hi) {
        return Some((hi, pn));
    }
    // Grow geometrically first: the admissible set need not be an interval.
    while lo * 2.0 < hi && ok(lo * 2.0) {
        lo *= 2.0;
    }
    hi = hi.min(lo * 2.0);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo > a_poly).then_some((lo, pn))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_a_rational_function_beyond_the_radius() {
        // 1 / (1 + 4a): radius 0.25; [1/1] is exact.
        let c: Vec<f64> = (0..=6).map(|p| (-4.0f64).powi(p)).collect();
        let p = ScalarPade::new(&c, 1, 1);
        for a in [0.1, 0.5, 2.0] {
            let want = 1.0 / (1.0 + 4.0 * a);
            assert!((p.eval(a) - want).abs() < 1e-10, "{a}: {}", p.eval(a));
        }
    }
}

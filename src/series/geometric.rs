//! Detection of a geometric power series (Cochelin & Medale, J. Comput. Phys.
//! 236 (2013) 594–607, §3): near a simple bifurcation or pole the last terms
//! satisfy U_{N-p} ≈ alpha_p U_N with alpha_p ≈ alpha_1^p, and the singular
//! point lies at a ≈ alpha_1.

use crate::linalg::{dot, norm};

/// Result of the test on the last terms of a vector series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometricSeries {
    /// Distance (in the path parameter) to the singular point, alpha_1.
    pub distance: f64,
    /// lambda there, on the series with the geometric part removed (set by
    /// the step, [`super::path`]; NaN from the test alone).
    pub lambda: f64,
}

/// Applies the test to `terms[1..=N]` (needs N >= 10). Thresholds are those of
/// the reference: sum_p (alpha_p^(1/p)/alpha_1 - 1)^2 <= 1e-5 and
/// sum_p |U_{N-p} - alpha_p U_N| / |U_{N-p}| <= 1e-4, p = 1..3.
pub fn detect(terms: &[Vec<f64>]) -> Option<GeometricSeries> {
    let n = terms.len().checked_sub(1)?;
    detect_tail(n, &terms[n.saturating_sub(3)..])
}

/// [`detect`] given only the last four terms U_{N-3}, ..., U_N of a series
/// of order N (the test reads no others).
pub fn detect_tail<T: AsRef<[f64]>>(n: usize, tail: &[T]) -> Option<GeometricSeries> {
    if n < 10 {
        return None;
    }
    let term = |p: usize| tail[3 - p].as_ref();
    let un = term(0);
    let un2 = dot(un, un);
    if !(un2 > 0.0) {
        return None;
    }
    let alpha = [1, 2, 3].map(|p| dot(term(p), un) / un2);
    if alpha[0] <= 0.0 {
        return None;
    }
    let mut ratio_dev = 0.0;
    let mut direction_dev = 0.0;
    for p in 1..=3 {
        let ap = alpha[p - 1];
        let root = ap.signum() * ap.abs().powf(1.0 / p as f64);
        ratio_dev += (root / alpha[0] - 1.0).powi(2);
        // |U_{N-p} - alpha_p U_N|, summed in the order of `norm`.
        let diff2: f64 = term(p)
            .iter()
            .zip(un)
            .map(|(a, b)| a - ap * b)
            .map(|d| d * d)
            .sum();
        let den = norm(term(p));
        if den == 0.0 {
            return None;
        }
        direction_dev += diff2.sqrt() / den;
    }
    (ratio_dev <= 1e-5 && direction_dev <= 1e-4).then_some(GeometricSeries {
        distance: alpha[0],
        lambda: f64::NAN,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_pure_geometric_series_and_rejects_polynomial_decay() {
        // U_p = v / 0.3^p has its pole at a = 0.3.
        let v = [1.0, -2.0, 0.5];
        let terms: Vec<Vec<f64>> = (0..=15)
            .map(|p| v.iter().map(|x| x / 0.3f64.powi(p)).collect())
            .collect();
        let g = detect(&terms).expect("geometric series");
        assert!((g.distance - 0.3).abs() < 1e-12);
        // Factorial decay (exp series) is not geometric.
        let mut f = 1.0;
        let terms: Vec<Vec<f64>> = (0..=15)
            .map(|p| {
                if p > 0 {
                    f *= p as f64;
                }
                v.iter().map(|x| x / f).collect()
            })
            .collect();
        assert!(detect(&terms).is_none());
    }
}

//! Regularized penalized unilateral contact, paper eq. (3):
//!
//!   R (R / K + h) = eta (delta - h),
//!
//! with R the normal reaction (positive when the obstacle pushes), h the gap,
//! delta the initial gap, K the penalty stiffness and eta the regularization.
//! R = 0 at h = delta; R ≈ -K h when penetrating; R h ≈ eta delta near contact;
//! R → -eta far away (h ≫ delta), the "pull" DESIGN §3 warns about.
//!
//! At eta = 0 the law is the penalty law R = max(0, −K h), the limit of
//! eq. (3) as eta → 0 (its switch width sqrt(eta delta / K) goes to 0): linear
//! on each side of contact, only continuous at h = 0 ([`NormalLaw::is_piecewise`];
//! the continuation engine ends its steps at these kinks, series::kinks). Each function below takes the piece from the sign of h
//! (h = 0: the open piece).

use crate::series::Var;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalLaw {
    /// Penalty stiffness K (N/m per node, or Pa/m in pressure form).
    pub k: f64,
    /// Regularization eta (N per node).
    pub eta: f64,
    /// Initial gap delta (m).
    pub delta: f64,
}

impl NormalLaw {
    /// The root R(h) of eq. (3) that is continuous through contact,
    /// R = (K/2)(-h + sqrt(h^2 + 4 eta (delta - h)/K)), written without
    /// cancellation on either side of h = 0.
    pub fn force(&self, h: f64) -> f64 {
        if self.is_piecewise() {
            return (-self.k * h).max(0.0);
        }
        let disc = h * h + 4.0 * self.eta * (self.delta - h) / self.k;
        let root = disc.max(0.0).sqrt();
        if h >= 0.0 {
            2.0 * self.eta * (self.delta - h) / (h + root)
        } else {
            0.5 * self.k * (root - h)
        }
    }

    /// eta = 0: the penalty law R = max(0, −K h), analytic on each side of
    /// h = 0 and only continuous across it.
    pub fn is_piecewise(&self) -> bool {
        self.eta == 0.0
    }

    /// Width w = sqrt(eta |delta| / K) of the switch of eq. (3) at h = 0: in
    /// g = h / w and r = R / (K w) (delta ≫ h) the law reads r (r + g) = 1,
    /// whose branch points g = ±2i bound the radius of convergence of any
    /// series through contact. Positive (the smallest normal f64 for a zero
    /// delta or eta).
    pub fn switch_width(&self) -> f64 {
        (self.eta * self.delta.abs() / self.k)
            .sqrt()
            .max(f64::MIN_POSITIVE)
    }

    /// dR/dh from differentiating eq. (3): (2R/K + h) dR = -(R + eta) dh.
    pub fn stiffness(&self, h: f64) -> f64 {
        if self.is_piecewise() {
            return if h < 0.0 { -self.k } else { 0.0 };
        }
        let r = self.force(h);
        -(r + self.eta) / (2.0 * r / self.k + h)
    }

    /// Residual of eq. (3), R (R/K + h) - eta (delta - h).
    pub fn residual(&self, r: f64, h: f64) -> f64 {
        r * (r / self.k + h) - self.eta * (self.delta - h)
    }

    /// Coefficient p >= 1 of R(a) given the series of h(a) and R_0..R_{p-1}:
    /// order p of eq. (3) reads
    ///   (2 R_0/K + h_0) R_p = -eta h_p - R_0 h_p - (1/K) sum_{k=1}^{p-1} R_k R_{p-k}
    ///                          - sum_{k=1}^{p-1} R_k h_{p-k}.
    /// O(p) per order (incremental propagation).
    pub fn force_coeff(&self, r: &[f64], h: &[f64], p: usize) -> f64 {
        if self.is_piecewise() {
            // The piece of the series' start: R_p = −K h_p in contact.
            return if h[0] < 0.0 { -self.k * h[p] } else { 0.0 };
        }
        let mut s = -(self.eta + r[0]) * h[p];
        for k in 1..p {
            s -= r[k] * r[p - k] / self.k + r[k] * h[p - k];
        }
        s / (2.0 * r[0] / self.k + h[0])
    }

    /// Records eq. (3) as a residual on a tape (algebraic unknown R).
    pub fn record<'a>(&self, r: Var<'a>, h: Var<'a>) -> Var<'a> {
        r * (r * (1.0 / self.k) + h) - self.eta * (self.delta - h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::series::taylor;

    fn law() -> NormalLaw {
        NormalLaw {
            k: 1e9,
            eta: 1e-6,
            delta: 1e-4,
        }
    }

    #[test]
    fn force_solves_the_law_on_both_sides_of_contact() {
        let l = law();
        for h in [-1e-6, -1e-9, 0.0, 1e-9, 1e-5, 1e-4, 1e-2, 10.0] {
            let r = l.force(h);
            // Relative to the size of the terms of eq. (3).
            let size = (r * r / l.k).abs() + (r * h).abs() + l.eta * (l.delta - h).abs();
            assert!(
                l.residual(r, h).abs() <= 1e-14 * size.max(1e-300),
                "h = {h}: R = {r}"
            );
        }
        assert_eq!(l.force(l.delta), 0.0);
        assert!(
            (l.force(-1e-6) - 1e3).abs() / 1e3 < 1e-3,
            "penalty branch R = -K h"
        );
        assert!(
            (l.force(1e6) + l.eta).abs() < 1e-9 * l.eta + 1e-16,
            "far pull tends to -eta"
        );
    }

    /// eta = 0: R = max(0, -K h), its slope and its series on each piece,
    /// and eq. (3) at a small eta tends to it (the limit the penalty law is).
    #[test]
    fn eta_zero_is_the_penalty_law_on_each_side_of_contact() {
        let pen = NormalLaw { eta: 0.0, ..law() };
        assert!(pen.is_piecewise() && !law().is_piecewise());
        for h in [-1e-3, -1e-9, 0.0, 1e-9, 1e-3] {
            let want = if h < 0.0 { -1e9 * h } else { 0.0 };
            assert_eq!(pen.force(h), want, "h = {h}");
            assert_eq!(pen.stiffness(h), if h < 0.0 { -1e9 } else { 0.0 });
            // eq. (3) at eta = 1e-18 N is within about eta (delta + |h|) / |h|
            // of it (R (R/K + h) = eta (delta - h) to first order in eta).
            let tiny = NormalLaw {
                eta: 1e-18,
                ..law()
            };
            if h != 0.0 {
                let bound = 2.0 * tiny.eta * (tiny.delta + h.abs()) / h.abs() + 1e-12 * want;
                assert!((tiny.force(h) - want).abs() <= bound, "h = {h}");
            }
        }
        // Series along h(a) = h0 + h1 a: R_p = -K h_p in contact, 0 outside.
        for (h0, k) in [(-2e-5, -1e9), (3e-5, 0.0)] {
            let h = [h0, 1e-5, 0.0];
            let r = [pen.force(h0), 0.0];
            assert_eq!(pen.force_coeff(&r, &h, 1), k * 1e-5);
            assert_eq!(pen.force_coeff(&r, &h, 2), 0.0);
        }
    }

    /// r = R / (K w) against the closed form of r (r + g) = 1 in g = h / w
    /// (the switch band of the law): r(0) = 1 up to the eta h term.
    #[test]
    fn the_switch_width_makes_the_law_dimensionless() {
        let l = law();
        let w = l.switch_width();
        assert!((w - 1e-19f64.sqrt()).abs() < 1e-24);
        for g in [-10.0, -1.0, 0.0, 1.0, 10.0] {
            let r = l.force(g * w) / (l.k * w);
            let want = 0.5 * (-g + (g * g + 4.0).sqrt());
            assert!((r - want).abs() < 1e-4 * want, "g = {g}: {r} vs {want}");
        }
    }

    #[test]
    fn stiffness_matches_finite_differences() {
        let l = law();
        for h in [-1e-7f64, 1e-8, 5e-5, 3e-3] {
            let dh = 1e-6 * h.abs();
            let fd = (l.force(h + dh) - l.force(h - dh)) / (2.0 * dh);
            let an = l.stiffness(h);
            assert!((an - fd).abs() <= 1e-6 * an.abs(), "h = {h}: {an} vs {fd}");
        }
    }

    #[test]
    fn series_coefficients_match_direct_evaluation_along_a_path() {
        // h(a) = h0 + h1 a + h2 a^2: the series of R(h(a)) summed at a must
        // equal the law solved directly at h(a).
        let l = law();
        let n = 20;
        let h: Vec<f64> = [2e-5, -3e-5, 1e-5]
            .iter()
            .copied()
            .chain(std::iter::repeat(0.0))
            .take(n + 1)
            .collect();
        let mut r = vec![l.force(h[0])];
        for p in 1..=n {
            r.push(0.0);
            r[p] = l.force_coeff(&r, &h, p);
        }
        for a in [0.05, 0.1, 0.2] {
            let want = l.force(taylor::eval(&h, a));
            let got = taylor::eval(&r, a);
            assert!(
                (got - want).abs() <= 1e-10 * want.abs(),
                "a = {a}: {got} vs {want}"
            );
        }
    }
}

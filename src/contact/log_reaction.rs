//! The logarithm of a contact reaction as a coordinate of the ANM path.
//!
//! Eq. (3), R (R/K + h) = eta (delta - h), reads with rho = R + eta
//!
//!   R^2 / K + h rho = eta delta,   i.e.   h = (eta delta - (rho - eta)^2 / K) / rho:
//!
//! the gap is a rational function of rho, whose only pole is rho = 0
//! (h → ∞), and with rho = e^s an entire function of s. Across the law's
//! switch (a gap band of width sqrt(eta delta / K), 3e-10 m on
//! plate-cylinder) the displacements and the load hardly move while rho
//! grows by decades: in the pseudo-arclength of U and lambda the switch is
//! a near-singularity that every series meets (branch points of R(h) at
//! h ≈ ±2i sqrt(eta delta / K)), and the steps shrink geometrically toward
//! it and grow back after it. Measured along y = c ln rho as well
//! (ContinuationProblem::arc_coordinates), the switch spans an O(c) range
//! of the path parameter, on which U, lambda and rho are exponentials of
//! the parameter rather than square roots near a branch point.
//!
//! Along a step, with rho_0 = R_0 + eta > 0 and rho_k = R_k (k >= 1),
//! rho y' = c rho' gives, order by order,
//!
//!   m rho_0 y_m = c m R_m - sum_{k=1}^{m-1} k y_k R_{m-k},
//!
//! and dy/dh = c R'(h) / rho_0 = -c / (2 R_0 / K + h_0) (eq. 3 differentiated).

use super::normal::NormalLaw;

/// The series of y = c ln(R + eta) of one contact pair along a step
/// (`Default`: the coordinate off, no order yet; [`LogReaction::restart`]
/// starts it).
#[derive(Clone, Debug, Default)]
pub struct LogReaction {
    /// c; 0 where rho_0 <= 0 (a law with delta <= 0 away from contact),
    /// which makes the coordinate constant.
    c: f64,
    /// 1 / rho_0 (0 with the coordinate off).
    inv_rho0: f64,
    /// dy/dh at the step start.
    pub dy_dh: f64,
    /// y_0 = 0 (the coordinate's origin is irrelevant), y_1, …, completed.
    y: Vec<f64>,
}

impl LogReaction {
    /// Order 0 at gap h0 with reaction r0 = law.force(h0), weight c >= 0.
    pub fn start(c: f64, law: &NormalLaw, h0: f64, r0: f64, orders: usize) -> Self {
        let mut series = Self::default();
        series.restart(c, law, h0, r0, orders);
        series
    }

    /// [`LogReaction::start`] in the buffer of an earlier series.
    pub fn restart(&mut self, c: f64, law: &NormalLaw, h0: f64, r0: f64, orders: usize) {
        let rho0 = r0 + law.eta;
        let root = 2.0 * r0 / law.k + h0;
        let on = c > 0.0 && rho0 > 0.0 && root > 0.0 && rho0.is_finite() && root.is_finite();
        self.y.clear();
        self.y.reserve(orders);
        self.y.push(0.0);
        (self.c, self.inv_rho0, self.dy_dh) = if on {
            (c, 1.0 / rho0, -c / root)
        } else {
            (0.0, 0.0, 0.0)
        };
    }

    /// Prefetches the coefficients (fe::prefetch).
    pub fn prefetch(&self) {
        crate::fe::prefetch::prefetch_growing(&self.y);
    }

    /// y_m from r = R_0..R_m, m = the next order (pushed).
    pub fn complete(&mut self, r: &[f64]) {
        let m = self.y.len();
        let y = self.coefficient(r[m], r, m);
        self.y.push(y);
    }

    /// y*_p: order p with R_p = r_star (the reaction's order p with
    /// U_p = 0 and lambda_p = 0), given R_0..R_{p-1} and y_0..y_{p-1}.
    pub fn starred(&self, r_star: f64, r: &[f64], p: usize) -> f64 {
        self.coefficient(r_star, r, p)
    }

    /// (c R_m − (1/m) Σ_{k=1}^{m−1} k y_k R_{m−k}) / rho_0.
    fn coefficient(&self, rm: f64, r: &[f64], m: usize) -> f64 {
        // Off: every y_k is 0 (the sum below would give 0 too).
        if self.c == 0.0 {
            return 0.0;
        }
        let mut s = 0.0;
        for k in 1..m {
            s += k as f64 * self.y[k] * r[m - k];
        }
        self.c * self.inv_rho0 * rm - self.inv_rho0 * s / m as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::series::taylor;

    /// Along h(a) = h0 + h1 a + h2 a^2 through the law's switch, the series
    /// of y summed at a equals c ln(R(h(a)) + eta) with R solved directly.
    #[test]
    fn series_match_the_logarithm_of_the_reaction_along_a_path() {
        let law = NormalLaw {
            k: 1e9,
            eta: 1e-6,
            delta: 1e-4,
        };
        let c = 2.0;
        let w = law.switch_width();
        // From 3 switch widths open to 3 widths closed over a = 0..1.
        let h = [3.0 * w, -5.0 * w, -w];
        let n = 30;
        let hs: Vec<f64> = h
            .iter()
            .copied()
            .chain(std::iter::repeat(0.0))
            .take(n + 1)
            .collect();
        let mut r = vec![law.force(hs[0])];
        let mut lr = LogReaction::start(c, &law, hs[0], r[0], n + 1);
        for m in 1..=n {
            r.push(0.0);
            r[m] = law.force_coeff(&r, &hs, m);
            lr.complete(&r);
        }
        let y0 = c * (r[0] + law.eta).ln();
        // The branch points of R(h(a)) lie at |a| ≈ 0.72 (h = ±2i w).
        for a in [0.1, 0.2, 0.3] {
            let want = c * (law.force(taylor::eval(&hs, a)) + law.eta).ln() - y0;
            let got = taylor::eval(&lr.y, a);
            assert!(
                (got - want).abs() < 1e-9 * want.abs().max(1.0),
                "a = {a}: {got} vs {want}"
            );
        }
        // The linear part: y_1 = dy/dh h_1.
        assert!((lr.y[1] - lr.dy_dh * hs[1]).abs() < 1e-12 * lr.y[1].abs());
        // The starred order with R_p's h_p part removed: y_p − dy/dh h_p.
        let mut h_star = hs.clone();
        h_star[2] = 0.0;
        let r2_star = law.force_coeff(&r, &h_star, 2);
        let y2_star = lr.starred(r2_star, &r, 2);
        assert!((lr.y[2] - (y2_star + lr.dy_dh * hs[2])).abs() < 1e-12 * lr.y[2].abs());
    }
}

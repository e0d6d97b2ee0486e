//! friction-plane (paper §3.3, eqs. 10a-d with 11) for IDA: a mass on springs
//! k at delta above a plane moving at V along x, pushed toward it by F t.
//!
//! y = (u_x, u_y, v_x, v_y, R_N, R_T); only u_x is differential:
//!   F1 = u_x' - v_x
//!   F2 = -k u_x + R_T                                  (10a)
//!   F3 = -k u_y + R_N - F t                            (10b)
//!   F4 = G(R_N, h) = R_N (R_N/K + h) - eta (delta - h), h = delta + u_y   (10c)
//!   F5 = (k G_R + G_h) v_y + G_R F                     (d/dt of 10b, 10c)
//!   F6 = P(R_T, |R_N|_reg, v_x - V)                      (10d with 11)
//! where P = R_T Vc^q |w|_reg^(1-q) + f N w is the friction law R_T +
//! f N g(w) = 0 in the product form of [`Friction::product_row`] (not
//! steep in v_x).
//! with G_R = 2 R_N/K + h, G_h = R_N + eta.
//!
//! Why u_y is algebraic: the normal equations (10b, 10c) fix u_y and R_N at
//! every t, so keeping u_y differential (u_y' = v_y) would leave two algebraic
//! equations acting on the one algebraic unknown R_N: index 2. With u_y
//! algebraic, the algebraic block d(F2..F6)/d(u_y, v_x, v_y, R_N, R_T) is
//! nonsingular (det of the normal block -(k G_R + G_h) != 0, the friction row
//! has dP/dv_x >= q f |R_N|_reg > 0): index 1. v_y is not u_y's BDF derivative but the
//! exact time derivative of the normal equations: R_N' = k v_y + F and
//! G_R R_N' + G_h v_y = 0 give F5, an algebraic equation solved to IDA's
//! tolerance like the others.

use super::dae::{Dae, Dense, FrictionDae};
use super::laws::{Contact, Friction};

pub struct FrictionPlane {
    pub k: f64,
    pub law: Friction,
    pub contact: Contact,
    pub v_plane: f64,
    pub load_rate: f64,
}

impl Dae for FrictionPlane {
    fn dim(&self) -> usize {
        6
    }
    fn differential(&self) -> Vec<bool> {
        vec![true, false, false, false, false, false]
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let [ux, uy, vx, vy, rn, rt] = [y[0], y[1], y[2], y[3], y[4], y[5]];
        let (k, f) = (self.k, self.load_rate);
        let c = &self.contact;
        let h = c.delta + uy;
        let (gr, gh) = (c.d_force(rn, h), c.d_gap(rn));
        let (nreg, _) = self.law.normal(rn);
        r[0] = yp[0] - vx;
        r[1] = -k * ux + rt;
        r[2] = -k * uy + rn - f * t;
        r[3] = c.residual(rn, h);
        r[4] = (k * gr + gh) * vy + gr * f;
        r[5] = self.law.row(rt, nreg, vx - self.v_plane).0;
    }
    fn jacobian(&self, _t: f64, cj: f64, y: &[f64], _yp: &[f64], j: &mut Dense) {
        let [_, uy, vx, vy, rn, rt] = [y[0], y[1], y[2], y[3], y[4], y[5]];
        let (k, f) = (self.k, self.load_rate);
        let c = &self.contact;
        let h = c.delta + uy;
        let (gr, gh) = (c.d_force(rn, h), c.d_gap(rn));
        let (nreg, dnreg) = self.law.normal(rn);
        let (_, d_rt, d_n, d_w) = self.law.row(rt, nreg, vx - self.v_plane);
        // F1
        j.add(0, 0, cj);
        j.add(0, 2, -1.0);
        // F2
        j.add(1, 0, -k);
        j.add(1, 5, 1.0);
        // F3
        j.add(2, 1, -k);
        j.add(2, 4, 1.0);
        // F4: dG/dh dh/du_y, dG/dR
        j.add(3, 1, gh);
        j.add(3, 4, gr);
        // F5: dG_R/du_y = 1, dG_R/dR = 2/K, dG_h/dR = 1
        j.add(4, 1, k * vy + f);
        j.add(4, 3, k * gr + gh);
        j.add(4, 4, (2.0 * k / c.k + 1.0) * vy + 2.0 * f / c.k);
        // F6
        j.add(5, 2, d_w);
        j.add(5, 4, d_n * dnreg);
        j.add(5, 5, d_rt);
    }
}

impl FrictionDae for FrictionPlane {
    fn columns(&self) -> &'static [&'static str] {
        &["t", "ux", "uy", "vx", "vy", "rn", "rt"]
    }
    fn unknowns(&self) -> &'static [&'static str] {
        &["ux", "uy", "vx", "vy", "rn", "rt"]
    }
    fn initial_guess(&self) -> (Vec<f64>, Vec<f64>) {
        // At rest on the moving plane's speed; R_N = R_T = 0.
        (
            vec![0.0, 0.0, self.v_plane, 0.0, 0.0, 0.0],
            vec![self.v_plane, 0.0, 0.0, 0.0, 0.0, 0.0],
        )
    }
    fn row(&self, t: f64, y: &[f64]) -> Vec<f64> {
        vec![t, y[0], y[1], y[2], y[3], y[4], y[5]]
    }
    fn contact_branch(&self, _t: f64, y: &[f64]) -> Option<f64> {
        Some(self.contact.d_force(y[4], self.contact.delta + y[1]))
    }
    fn slip(&self, _t: f64, y: &[f64]) -> f64 {
        y[2] - self.v_plane
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::dae::jacobian_error;

    #[test]
    fn analytic_jacobian_matches_finite_differences() {
        let m = FrictionPlane {
            k: 1.3,
            law: Friction {
                f: 0.2,
                q: 0.05,
                vc: 1.0,
                omega: 0.1,
                zeta: 0.1,
                form: super::super::laws::RowForm::Product,
            },
            contact: Contact {
                k: 1e3,
                eta: 1e-3,
                delta: 1.0,
            },
            v_plane: 1.0,
            load_rate: 0.7,
        };
        let y = [0.1, -0.9, 0.3, -0.2, 0.4, 0.05];
        let yp = [0.3, 0.1, 0.2, -0.1, 0.5, 0.0];
        let e = jacobian_error(&m, 1.2, 37.0, &y, &yp);
        assert!(e < 1e-6, "Jacobian error {e:e}");
    }
}

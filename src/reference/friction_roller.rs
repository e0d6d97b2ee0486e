//! friction-roller (paper §3.4) for IDA, in global Cartesian coordinates.
//!
//! The mass is at x = u (it starts at the origin); the roller, of radius r,
//! has its centre at C = (0, -(delta + r)) and spins at Omega
//! (counterclockwise). With d = x - C, rho = |d|:
//!   h = rho - r,  n = d / rho,  t = (n_y, -n_x)  (n turned by -90 degrees),
//!   v_s = v.t + Omega r,  load L = (0, -F t).
//! Equations of the quasi-static problem:
//!   equilibrium  -k u + R_N n + R_T t + L = 0        (2 Cartesian components)
//!   contact      G(R_N, h) = R_N (R_N/K + h) - eta (delta - h) = 0
//!   friction     R_T + f |R_N|_reg g(v_s) = 0, written in the product form
//!                P(R_T, |R_N|_reg, v_s) = 0 of [`Friction::product_row`]
//!                (not steep in v_s)
//!
//! ## Index-1 form
//! Unknowns y = (u_x, u_y, v_x, v_y, R_N, R_T), u differential (u' = v), the
//! rest algebraic. Written as they stand, the equations are index 2: the two
//! equilibrium components and the contact law act on u and (R_N, R_T) only,
//! three equations for the two algebraic unknowns R_N, R_T, so one
//! combination (normal equilibrium + contact) is a position-level constraint
//! Phi(u, t) = 0 that no algebraic unknown can satisfy, and nothing fixes the
//! normal velocity v.n. We keep both equilibrium components (they determine
//! R_N, R_T from u, through the orthonormal matrix [n t]) and the friction
//! law (it determines v.t), and replace the contact law by its time
//! derivative along the solution, stabilized (Baumgarte):
//!   dG/dt + alpha G = 0,  dG/dt = G_R R_N' + G_h v.n,
//! G_R = 2 R_N/K + h, G_h = R_N + eta. On the equilibrium manifold
//! R_N = (k u - L).n and R_T = (k u - L).t; with dn/dt = (v.t / rho) t this
//! gives R_N' = k v.n + R_T v.t / rho + F n_y. The row in v of this equation
//! is (k G_R + G_h) n + G_R R_T / rho t and that of the friction law is
//! f |R_N|_reg g'(v_s) t, so in the (n, t) basis the velocity block is upper
//! triangular with diagonal (k G_R + G_h, dP/dv_s) != 0: the algebraic
//! block is nonsingular, index 1. Consistent initial values satisfy G = 0
//! (at t = 0: u = 0, h = delta, R_N = 0), and G = 0 for all t is then the
//! exact solution of dG/dt + alpha G = 0; alpha only damps the drift that
//! integration errors would leave (G decays like exp(-alpha t)). The largest
//! |G| seen is reported as the constraint drift.
//!
//! Checked on the plane limit: with r large and Omega r = -V, the roller
//! solution matches the plane's (tests/reference/ida.rs).

use super::dae::{Dae, Dense, FrictionDae};
use super::laws::{Contact, Friction};

/// Default Baumgarte rate alpha (1/s) of the differentiated contact law.
pub const BAUMGARTE_ALPHA: f64 = 100.0;

pub struct FrictionRoller {
    pub k: f64,
    pub law: Friction,
    pub contact: Contact,
    pub radius: f64,
    pub spin: f64,
    pub load_rate: f64,
    pub alpha: f64,
}

/// Geometry at a position u.
struct Frame {
    rho: f64,
    h: f64,
    n: [f64; 2],
    t: [f64; 2],
}

impl FrictionRoller {
    fn frame(&self, ux: f64, uy: f64) -> Frame {
        let d = [ux, uy + self.contact.delta + self.radius];
        let rho = d[0].hypot(d[1]);
        let n = [d[0] / rho, d[1] / rho];
        Frame {
            rho,
            h: rho - self.radius,
            n,
            t: [n[1], -n[0]],
        }
    }
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

impl Dae for FrictionRoller {
    fn dim(&self) -> usize {
        6
    }
    fn differential(&self) -> Vec<bool> {
        vec![true, true, false, false, false, false]
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let [ux, uy, vx, vy, rn, rt] = [y[0], y[1], y[2], y[3], y[4], y[5]];
        let (k, f) = (self.k, self.load_rate);
        let c = &self.contact;
        let fr = self.frame(ux, uy);
        let v = [vx, vy];
        let (vn, vt) = (dot(v, fr.n), dot(v, fr.t));
        let (gr, gh) = (c.d_force(rn, fr.h), c.d_gap(rn));
        let rn_rate = k * vn + rt * vt / fr.rho + f * fr.n[1];
        let (nreg, _) = self.law.normal(rn);
        r[0] = yp[0] - vx;
        r[1] = yp[1] - vy;
        r[2] = -k * ux + rn * fr.n[0] + rt * fr.t[0];
        r[3] = -k * uy + rn * fr.n[1] + rt * fr.t[1] - f * t;
        r[4] = gr * rn_rate + gh * vn + self.alpha * c.residual(rn, fr.h);
        r[5] = self.law.row(rt, nreg, vt + self.spin * self.radius).0;
    }
    // Index loops mirror the component formulas (rows x, y; columns u_x, u_y).
    #[allow(clippy::needless_range_loop)]
    fn jacobian(&self, _t: f64, cj: f64, y: &[f64], _yp: &[f64], j: &mut Dense) {
        let [ux, uy, vx, vy, rn, rt] = [y[0], y[1], y[2], y[3], y[4], y[5]];
        let (k, f) = (self.k, self.load_rate);
        let c = &self.contact;
        let Frame { rho, h, n, t } = self.frame(ux, uy);
        let v = [vx, vy];
        let (vn, vt) = (dot(v, n), dot(v, t));
        let (gr, gh) = (c.d_force(rn, h), c.d_gap(rn));
        let a = k * vn + rt * vt / rho + f * n[1];
        let (nreg, dnreg) = self.law.normal(rn);
        let (_, d_rt, d_n, d_w) = self.law.row(rt, nreg, vt + self.spin * self.radius);
        // dn/du = t t^T / rho, dt/du = -n t^T / rho, drho/du = n,
        // d(v.n)/du = v.t t / rho, d(v.t)/du = -v.n t / rho.
        j.add(0, 0, cj);
        j.add(0, 2, -1.0);
        j.add(1, 1, cj);
        j.add(1, 3, -1.0);
        // Equilibrium, components x (row 2) and y (row 3).
        for (row, i) in [(2, 0), (3, 1)] {
            let s = (rn * t[i] - rt * n[i]) / rho;
            for col in 0..2 {
                j.add(row, col, s * t[col]);
            }
            j.add(row, row - 2, -k);
            j.add(row, 4, n[i]);
            j.add(row, 5, t[i]);
        }
        // Differentiated contact law: r4 = G_R a + G_h v.n + alpha G.
        let da_dt = (k * vt + f * t[1] - rt * vn / rho) / rho;
        let da_dn = -rt * vt / (rho * rho);
        for col in 0..2 {
            let da_du = da_dt * t[col] + da_dn * n[col];
            let dvn_du = vt * t[col] / rho;
            j.add(
                4,
                col,
                a * n[col] + gr * da_du + gh * dvn_du + self.alpha * gh * n[col],
            );
            j.add(
                4,
                2 + col,
                gr * (k * n[col] + rt * t[col] / rho) + gh * n[col],
            );
        }
        j.add(4, 4, 2.0 / c.k * a + vn + self.alpha * gr);
        j.add(4, 5, gr * vt / rho);
        // Friction law (product form), w = v.t + Omega r.
        for col in 0..2 {
            j.add(5, col, -d_w * vn * t[col] / rho);
            j.add(5, 2 + col, d_w * t[col]);
        }
        j.add(5, 4, d_n * dnreg);
        j.add(5, 5, d_rt);
    }
}

impl FrictionDae for FrictionRoller {
    fn columns(&self) -> &'static [&'static str] {
        &["t", "ux", "uy", "vx", "vy", "rn", "rt"]
    }
    fn unknowns(&self) -> &'static [&'static str] {
        &["ux", "uy", "vx", "vy", "rn", "rt"]
    }
    fn initial_guess(&self) -> (Vec<f64>, Vec<f64>) {
        // At the top, t = e_x: moving with the roller's surface, v = (-Omega r, 0).
        let vx = -self.spin * self.radius;
        (
            vec![0.0, 0.0, vx, 0.0, 0.0, 0.0],
            vec![vx, 0.0, 0.0, 0.0, 0.0, 0.0],
        )
    }
    fn row(&self, t: f64, y: &[f64]) -> Vec<f64> {
        vec![t, y[0], y[1], y[2], y[3], y[4], y[5]]
    }
    fn slip(&self, _t: f64, y: &[f64]) -> f64 {
        let fr = self.frame(y[0], y[1]);
        dot([y[2], y[3]], fr.t) + self.spin * self.radius
    }
    fn contact_branch(&self, _t: f64, y: &[f64]) -> Option<f64> {
        let fr = self.frame(y[0], y[1]);
        Some(self.contact.d_force(y[4], fr.h))
    }
    fn constraint_drift(&self, _t: f64, y: &[f64]) -> f64 {
        let fr = self.frame(y[0], y[1]);
        self.contact.residual(y[4], fr.h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::dae::jacobian_error;

    #[test]
    fn analytic_jacobian_matches_finite_differences() {
        let m = FrictionRoller {
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
            radius: 1.0,
            spin: 1.0,
            load_rate: 0.7,
            alpha: 3.0,
        };
        let y = [-0.3, -0.9, 0.3, -0.2, 0.4, 0.05];
        let yp = [0.3, 0.1, 0.2, -0.1, 0.5, 0.0];
        let e = jacobian_error(&m, 1.2, 37.0, &y, &yp);
        assert!(e < 1e-6, "Jacobian error {e:e}");
    }
}

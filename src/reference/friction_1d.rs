//! friction-1d (paper §3.2, eq. 7) for IDA: a spring k on a plane moving at V
//! with a known normal force R_N.
//!
//! y = (u, v), u differential, v algebraic:
//!   F1 = u' - v
//!   F2 = P(k u, R_N, v - V) = k u Vc^q |v - V|_reg^(1-q) + f R_N (v - V)
//! the friction law k u + f R_N g(v - V) = 0, g(w) = |w|_reg^(q-1) w / Vc^q, in the product form of [`Friction::product_row`] (not
//! steep in v). Index 1: dF2/dv >= q f R_N > 0 on the solution.
//! Columns t, u, v, rt with rt = -f R_N g(v - V) (= k u on the solution).

use super::dae::{Dae, Dense, FrictionDae};
use super::laws::Friction;

pub struct Friction1d {
    pub k: f64,
    pub law: Friction,
    pub v_plane: f64,
    pub rn: f64,
    pub u0: f64,
}

impl Dae for Friction1d {
    fn dim(&self) -> usize {
        2
    }
    fn differential(&self) -> Vec<bool> {
        vec![true, false]
    }
    fn residual(&self, _t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let (u, v) = (y[0], y[1]);
        r[0] = yp[0] - v;
        r[1] = self.law.row(self.k * u, self.rn, v - self.v_plane).0;
    }
    fn jacobian(&self, _t: f64, cj: f64, y: &[f64], _yp: &[f64], j: &mut Dense) {
        let (_, d_rt, _, d_w) = self.law.row(self.k * y[0], self.rn, y[1] - self.v_plane);
        j.add(0, 0, cj);
        j.add(0, 1, -1.0);
        j.add(1, 0, self.k * d_rt);
        j.add(1, 1, d_w);
    }
}

impl FrictionDae for Friction1d {
    fn columns(&self) -> &'static [&'static str] {
        &["t", "u", "v", "rt"]
    }
    fn unknowns(&self) -> &'static [&'static str] {
        &["u", "v"]
    }
    fn initial_guess(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![self.u0, self.v_plane], vec![self.v_plane, 0.0])
    }
    fn row(&self, t: f64, y: &[f64]) -> Vec<f64> {
        let (g, _) = self.law.shape(y[1] - self.v_plane);
        vec![t, y[0], y[1], -self.law.f * self.rn * g]
    }
    fn slip(&self, _t: f64, y: &[f64]) -> f64 {
        y[1] - self.v_plane
    }
}

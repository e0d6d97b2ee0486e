//! Regularized power friction law, paper eqs. (5), (6), (11):
//!
//!   R_T = -f |R_N|_reg |v_s|_reg^(q-1) / Vc^q  v_s,
//!   |v|_reg = sqrt(v.v + omega^2 Vc^2),   |R_N|_reg = sqrt(R_N^2 + zeta^2).
//!
//! q = 0 is regularized Coulomb; q = 1 is viscous. With zeta = None the normal
//! force enters as R_N itself (eq. 5, used in §3.2 where R_N is known).

use crate::series::Var;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionLaw {
    /// Friction coefficient f.
    pub f: f64,
    /// Exponent q in [0, 1].
    pub q: f64,
    /// Characteristic velocity Vc (m/s).
    pub vc: f64,
    /// Velocity regularization omega (dimensionless).
    pub omega: f64,
    /// Normal-force regularization zeta (N); `None`: eq. (5) with R_N as is.
    pub zeta: Option<f64>,
}

impl FrictionLaw {
    /// |R_N|_reg of eq. (11), or R_N for eq. (5).
    pub fn normal_magnitude(&self, rn: f64) -> f64 {
        match self.zeta {
            Some(z) => (rn * rn + z * z).sqrt(),
            None => rn,
        }
    }

    /// |v_s|_reg of eq. (6), scalar slip.
    pub fn slip_magnitude(&self, vs: f64) -> f64 {
        (vs * vs + (self.omega * self.vc).powi(2)).sqrt()
    }

    /// R_T for a scalar slip velocity v_s.
    pub fn force(&self, rn: f64, vs: f64) -> f64 {
        -self.f * self.normal_magnitude(rn) * self.slip_magnitude(vs).powf(self.q - 1.0)
            / self.vc.powf(self.q)
            * vs
    }

    /// dR_T/dv_s = -f |R_N|_reg / Vc^q |v|_reg^(q-3) (q v_s^2 + omega^2 Vc^2).
    pub fn d_force_d_slip(&self, rn: f64, vs: f64) -> f64 {
        let w2 = (self.omega * self.vc).powi(2);
        let m = self.slip_magnitude(vs);
        -self.f * self.normal_magnitude(rn) / self.vc.powf(self.q)
            * m.powf(self.q - 3.0)
            * (self.q * vs * vs + w2)
    }

    /// dR_T/dR_N = R_T / |R_N|_reg * d|R_N|_reg/dR_N.
    pub fn d_force_d_normal(&self, rn: f64, vs: f64) -> f64 {
        let dn = match self.zeta {
            Some(_) => rn / self.normal_magnitude(rn),
            None => 1.0,
        };
        -self.f * dn * self.slip_magnitude(vs).powf(self.q - 1.0) / self.vc.powf(self.q) * vs
    }

    /// Records R_T(R_N, v_s) on a tape.
    pub fn record<'a>(&self, rn: Var<'a>, vs: Var<'a>) -> Var<'a> {
        let normal = match self.zeta {
            Some(z) => (rn * rn + z * z).sqrt(),
            None => rn,
        };
        let slip2 = vs * vs + (self.omega * self.vc).powi(2);
        // |v|_reg^(q-1) = (v^2 + omega^2 Vc^2)^((q-1)/2): one power, no sqrt.
        -self.f / self.vc.powf(self.q) * normal * slip2.powf(0.5 * (self.q - 1.0)) * vs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::series::{TapeBuilder, taylor};

    fn laws() -> Vec<FrictionLaw> {
        let mut v = vec![];
        for q in [0.0, 0.05, 0.5, 1.0] {
            for zeta in [None, Some(0.1)] {
                v.push(FrictionLaw {
                    f: 0.2,
                    q,
                    vc: 1.3,
                    omega: 0.1,
                    zeta,
                });
            }
        }
        v
    }

    #[test]
    fn coulomb_and_viscous_limits() {
        // q = 0, omega -> 0: |R_T| = f R_N; q = 1: R_T = -f R_N v / Vc exactly.
        let c = FrictionLaw {
            f: 0.2,
            q: 0.0,
            vc: 1.0,
            omega: 1e-9,
            zeta: None,
        };
        assert!((c.force(2.0, -0.5) - 0.4).abs() < 1e-12);
        let v = FrictionLaw {
            f: 0.2,
            q: 1.0,
            vc: 2.0,
            omega: 0.3,
            zeta: None,
        };
        assert!((v.force(2.0, -0.5) - 0.2 * 2.0 * 0.5 / 2.0).abs() < 1e-15);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for law in laws() {
            for (rn, vs) in [(0.7, -0.3), (0.0, 0.02), (1.5, 2.0), (-0.2, 0.0)] {
                let h = 1e-6;
                let fd_v = (law.force(rn, vs + h) - law.force(rn, vs - h)) / (2.0 * h);
                let fd_n = (law.force(rn + h, vs) - law.force(rn - h, vs)) / (2.0 * h);
                let (dv, dn) = (law.d_force_d_slip(rn, vs), law.d_force_d_normal(rn, vs));
                assert!(
                    (dv - fd_v).abs() <= 1e-7 * (1.0 + dv.abs()),
                    "{law:?} dv {dv} vs {fd_v}"
                );
                assert!(
                    (dn - fd_n).abs() <= 1e-7 * (1.0 + dn.abs()),
                    "{law:?} dn {dn} vs {fd_n}"
                );
            }
        }
    }

    #[test]
    fn series_terms_match_direct_evaluation_and_jacobian() {
        // Along R_N = 0.4 + 0.3 a, v_s = -0.2 + 0.5 a - 0.1 a^2, the series of the
        // recorded law summed at a equals the direct law; the tape Jacobian
        // equals the analytic derivatives.
        let n = 30;
        for law in laws() {
            let b = TapeBuilder::new();
            let rn = b.input();
            let vs = b.input();
            let rt = law.record(rn, vs);
            let mut tape = b.finish(&[rt], n);
            let rn_s = [0.4, 0.3];
            let vs_s = [-0.2, 0.5, -0.1];
            for p in 0..=n {
                tape.set_input(0, p, *rn_s.get(p).unwrap_or(&0.0));
                tape.set_input(1, p, *vs_s.get(p).unwrap_or(&0.0));
                tape.propagate(p);
            }
            for a in [0.05, 0.15] {
                let want = law.force(taylor::eval(&rn_s, a), taylor::eval(&vs_s, a));
                let got = taylor::eval(tape.output_series(0), a);
                assert!(
                    (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "{law:?} a = {a}: {got} vs {want}"
                );
            }
            let jac = tape.jacobian(&[0, 1]);
            let (dn, dv) = (
                law.d_force_d_normal(0.4, -0.2),
                law.d_force_d_slip(0.4, -0.2),
            );
            assert!((jac[0][0] - dn).abs() <= 1e-13 * (1.0 + dn.abs()));
            assert!((jac[0][1] - dv).abs() <= 1e-13 * (1.0 + dv.abs()));
        }
    }
}

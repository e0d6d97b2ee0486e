//! The regularized contact and friction laws in plain f64, with their
//! derivatives, written from the paper's equations (§2.1 eq. 3, §3.1 eqs. 5,
//! 6, 11) for the IDA reference. Only the parameter values are taken from the
//! scene's [`crate::contact::FrictionLaw`] and [`crate::contact::NormalLaw`];
//! none of their functions is called, so an error there shows against IDA.

use crate::contact::{FrictionLaw, NormalLaw};

/// Power friction law R_T = -f |R_N|_reg g(v_s) with
/// g(w) = |w|_reg^(q-1) w / Vc^q, |w|_reg = sqrt(w^2 + omega^2 Vc^2),
/// |R_N|_reg = sqrt(R_N^2 + zeta^2) (zeta = 0: |R_N| is R_N as given).
#[derive(Clone, Copy, Debug)]
pub struct Friction {
    pub f: f64,
    pub q: f64,
    pub vc: f64,
    pub omega: f64,
    pub zeta: f64,
}

impl Friction {
    pub fn from_law(law: &FrictionLaw) -> Self {
        Self {
            f: law.f,
            q: law.q,
            vc: law.vc,
            omega: law.omega,
            zeta: law.zeta.unwrap_or(0.0),
        }
    }

    /// g(w) and dg/dw:
    /// g'(w) = (w^2 + omega^2 Vc^2)^((q-3)/2) (q w^2 + omega^2 Vc^2) / Vc^q.
    pub fn shape(&self, w: f64) -> (f64, f64) {
        let reg2 = self.omega * self.omega * self.vc * self.vc;
        let s2 = w * w + reg2;
        let vcq = self.vc.powf(self.q);
        let g = s2.powf(0.5 * (self.q - 1.0)) * w / vcq;
        let dg = s2.powf(0.5 * (self.q - 3.0)) * (self.q * w * w + reg2) / vcq;
        (g, dg)
    }

    /// |R_N|_reg and its derivative in R_N.
    pub fn normal(&self, rn: f64) -> (f64, f64) {
        let m = (rn * rn + self.zeta * self.zeta).sqrt();
        (m, rn / m)
    }
}

/// Regularized unilateral contact, eq. (3): G(R, h) = R (R/K + h) - eta (delta - h) = 0.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    pub k: f64,
    pub eta: f64,
    pub delta: f64,
}

impl Contact {
    pub fn from_law(law: &NormalLaw) -> Self {
        Self {
            k: law.k,
            eta: law.eta,
            delta: law.delta,
        }
    }

    /// G(R, h).
    pub fn residual(&self, r: f64, h: f64) -> f64 {
        r * (r / self.k + h) - self.eta * (self.delta - h)
    }

    /// dG/dR = 2 R / K + h.
    pub fn d_force(&self, r: f64, h: f64) -> f64 {
        2.0 * r / self.k + h
    }

    /// dG/dh = R + eta.
    pub fn d_gap(&self, r: f64) -> f64 {
        r + self.eta
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        let fr = Friction {
            f: 0.2,
            q: 0.05,
            vc: 1.3,
            omega: 0.1,
            zeta: 0.1,
        };
        for w in [-3.0, -0.2, 0.0, 0.05, 2.0] {
            let e = 1e-6;
            let fd = (fr.shape(w + e).0 - fr.shape(w - e).0) / (2.0 * e);
            let an = fr.shape(w).1;
            assert!(
                (fd - an).abs() <= 1e-6 * an.abs().max(1.0),
                "{w}: {fd} {an}"
            );
        }
        for rn in [-1.0, 0.0, 0.3] {
            let e = 1e-7;
            let fd = (fr.normal(rn + e).0 - fr.normal(rn - e).0) / (2.0 * e);
            assert!((fd - fr.normal(rn).1).abs() < 1e-6);
        }
    }
}

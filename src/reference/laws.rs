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
    /// How the DAEs write the law (see [`RowForm`]).
    pub form: RowForm,
}

/// How the reference DAEs write the friction law R_T + f N g(w) = 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RowForm {
    /// R_T Vc^q |w|_reg^(1-q) + f N w = 0 ([`Friction::product_row`]): not
    /// steep in w (the default).
    #[default]
    Product,
    /// R_T + f N g(w) = 0 as the paper writes it (eqs. 5, 6, 11).
    Direct,
}

impl std::str::FromStr for RowForm {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "product" => Ok(Self::Product),
            "direct" => Ok(Self::Direct),
            _ => Err(format!(
                "unknown friction row `{s}`: expected `product` or `direct`"
            )),
        }
    }
}

impl RowForm {
    pub fn name(&self) -> &'static str {
        match self {
            Self::Product => "product",
            Self::Direct => "direct",
        }
    }
}

impl Friction {
    pub fn from_law(law: &FrictionLaw) -> Self {
        Self {
            f: law.f,
            q: law.q,
            vc: law.vc,
            omega: law.omega,
            zeta: law.zeta.unwrap_or(0.0),
            form: RowForm::Product,
        }
    }

    /// The friction row in the chosen [`RowForm`]: (value, d/dR_T, d/dN,
    /// d/dw) at (R_T, N, w).
    pub fn row(&self, rt: f64, n: f64, w: f64) -> (f64, f64, f64, f64) {
        match self.form {
            RowForm::Product => self.product_row(rt, n, w),
            RowForm::Direct => {
                let (g, dg) = self.shape(w);
                (rt + self.f * n * g, 1.0, self.f * g, self.f * n * dg)
            }
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

    /// The friction law as the reference DAEs write it, in product form:
    /// P(R_T, N, w) = R_T Vc^q |w|_reg^(1-q) + f N w = 0, i.e. R_T + f N g(w)
    /// = 0 multiplied by Vc^q |w|_reg^(1-q) > 0 (same solutions, same index).
    /// Returns (P, dP/dR_T, dP/dN, dP/dw).
    ///
    /// Why: R_T + f N g(w) is steep in w where |w| < omega Vc (g' ~
    /// omega^(q-1)) and flat beyond (g' ~ q |w|^(q-1)), so a Newton step on it
    /// from a predictor overshoots by orders of magnitude, and with omega =
    /// 1e-6 IDA's corrector fails repeatedly (IDA_CONV_FAIL on the roller at
    /// t = 0.011 s and 2.17 s). In product form P is nearly linear in w
    /// (|w|^0.95 for q = 0.05) and, on the solution, dP/dw = f N (1 - (1-q)
    /// w^2 / |w|_reg^2) >= q f N > 0: Newton converges in one or two
    /// iterations at every omega.
    pub fn product_row(&self, rt: f64, n: f64, w: f64) -> (f64, f64, f64, f64) {
        let s2 = w * w + self.omega * self.omega * self.vc * self.vc;
        let vcq = self.vc.powf(self.q);
        let m = vcq * s2.powf(0.5 * (1.0 - self.q));
        let dm = vcq * (1.0 - self.q) * s2.powf(-0.5 * (1.0 + self.q)) * w;
        (rt * m + self.f * n * w, m, self.f * w, rt * dm + self.f * n)
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
            form: RowForm::Product,
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
        for (rt, n, w) in [(0.3, 0.7, -2.0), (-0.01, 1e-3, 0.05), (0.1, 0.2, 0.0)] {
            let p = fr.product_row(rt, n, w);
            let e = 1e-6;
            let fd = [
                (fr.product_row(rt + e, n, w).0 - fr.product_row(rt - e, n, w).0) / (2.0 * e),
                (fr.product_row(rt, n + e, w).0 - fr.product_row(rt, n - e, w).0) / (2.0 * e),
                (fr.product_row(rt, n, w + e).0 - fr.product_row(rt, n, w - e).0) / (2.0 * e),
            ];
            for (an, fd) in [p.1, p.2, p.3].into_iter().zip(fd) {
                assert!((an - fd).abs() <= 1e-6 * fd.abs().max(1.0), "{an} {fd}");
            }
            // Same root as R_T + f N g(w).
            let rt0 = -fr.f * n * fr.shape(w).0;
            assert!(fr.product_row(rt0, n, w).0.abs() <= 1e-14);
        }
        for rn in [-1.0, 0.0, 0.3] {
            let e = 1e-7;
            let fd = (fr.normal(rn + e).0 - fr.normal(rn - e).0) / (2.0 * e);
            assert!((fd - fr.normal(rn).1).abs() < 1e-6);
        }
    }
}

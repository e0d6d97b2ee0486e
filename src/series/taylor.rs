//! Truncated power-series arithmetic with incremental coefficient propagation.
//!
//! Every function here returns the coefficient `w_p` of a result series `w`
//! from the coefficients `0..=p` of its inputs and `0..p` of `w` itself, so an
//! order-p update costs O(p) per operation (Cochelin, Damil, Potier-Ferry 2007,
//! ch. 3; Griewank & Walther, *Evaluating Derivatives*, 2nd ed., table 10.1).
//! Nothing is re-evaluated: lower coefficients are read, never recomputed.

/// `w = a * b`: w_p = sum_{k=0}^{p} a_k b_{p-k}.
pub fn mul_coeff(a: &[f64], b: &[f64], p: usize) -> f64 {
    // Zipped slices instead of indices: no bounds check per term.
    a[..=p]
        .iter()
        .zip(b[..=p].iter().rev())
        .map(|(x, y)| x * y)
        .sum()
}

/// `w = a / b`: w_p = (a_p - sum_{k=1}^{p} b_k w_{p-k}) / b_0.
pub fn div_coeff(a: &[f64], b: &[f64], w: &[f64], p: usize) -> f64 {
    let s: f64 = b[1..=p]
        .iter()
        .zip(w[..p].iter().rev())
        .map(|(x, y)| x * y)
        .sum();
    (a[p] - s) / b[0]
}

/// `w = sqrt(a)`: from w*w = a, w_p = (a_p - sum_{k=1}^{p-1} w_k w_{p-k}) / (2 w_0).
pub fn sqrt_coeff(a: &[f64], w: &[f64], p: usize) -> f64 {
    if p == 0 {
        return a[0].sqrt();
    }
    let s: f64 = w[1..p]
        .iter()
        .zip(w[1..p].iter().rev())
        .map(|(x, y)| x * y)
        .sum();
    (a[p] - s) / (2.0 * w[0])
}

/// `w = a^alpha` (a_0 > 0): from a w' = alpha a' w,
/// w_p = sum_{k=1}^{p} (alpha k - (p - k)) a_k w_{p-k} / (p a_0).
pub fn powf_coeff(a: &[f64], alpha: f64, w: &[f64], p: usize) -> f64 {
    if p == 0 {
        return a[0].powf(alpha);
    }
    // k and p - k counted in f64 (exact): no integer conversion per term.
    let pf = p as f64;
    let mut k = 0.0;
    let s: f64 = a[1..=p]
        .iter()
        .zip(w[..p].iter().rev())
        .map(|(x, y)| {
            k += 1.0;
            (alpha * k - (pf - k)) * x * y
        })
        .sum();
    s / (pf * a[0])
}

/// `w = exp(a)`: from w' = a' w, w_p = sum_{k=1}^{p} k a_k w_{p-k} / p.
pub fn exp_coeff(a: &[f64], w: &[f64], p: usize) -> f64 {
    if p == 0 {
        return a[0].exp();
    }
    k_weighted_conv(a, w, p) / p as f64
}

/// sum_{k=1}^{p} k a_k w_{p-k}, the convolution of the exponential and
/// trigonometric recurrences.
fn k_weighted_conv(a: &[f64], w: &[f64], p: usize) -> f64 {
    let mut k = 0.0;
    a[1..=p]
        .iter()
        .zip(w[..p].iter().rev())
        .map(|(x, y)| {
            k += 1.0;
            k * x * y
        })
        .sum()
}

/// `s = sin(a)` given `c = cos(a)`: s' = a' c, s_p = sum_{k=1}^{p} k a_k c_{p-k} / p.
pub fn sin_coeff(a: &[f64], c: &[f64], p: usize) -> f64 {
    if p == 0 {
        return a[0].sin();
    }
    k_weighted_conv(a, c, p) / p as f64
}

/// `c = cos(a)` given `s = sin(a)`: c' = -a' s, c_p = -sum_{k=1}^{p} k a_k s_{p-k} / p.
pub fn cos_coeff(a: &[f64], s: &[f64], p: usize) -> f64 {
    if p == 0 {
        return a[0].cos();
    }
    -k_weighted_conv(a, s, p) / p as f64
}

/// Evaluates a series at `a` by Horner's rule.
pub fn eval(c: &[f64], a: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &x| acc * a + x)
}

/// Evaluates the derivative d/da of a series at `a`.
pub fn eval_derivative(c: &[f64], a: f64) -> f64 {
    // Weights k = N down to 1, counted in f64 (exact) rather than converted.
    let mut k = c.len() as f64;
    c.iter().skip(1).rev().fold(0.0, |acc, &x| {
        k -= 1.0;
        acc * a + k * x
    })
}

/// A truncated power series `sum_{k=0}^{N} c_k a^k`, for direct use and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub c: Vec<f64>,
}

impl Series {
    /// The series `x0 + x1 a` truncated at `order`.
    pub fn variable(x0: f64, x1: f64, order: usize) -> Self {
        let mut c = vec![0.0; order + 1];
        c[0] = x0;
        if order >= 1 {
            c[1] = x1;
        }
        Self { c }
    }

    pub fn constant(x0: f64, order: usize) -> Self {
        Self::variable(x0, 0.0, order)
    }

    pub fn order(&self) -> usize {
        self.c.len() - 1
    }

    fn build(order: usize, mut coeff: impl FnMut(&[f64], usize) -> f64) -> Self {
        // w[p] is still 0 while coefficient p is computed: the recurrences read w[..p] only.
        let mut w = vec![0.0; order + 1];
        for p in 0..=order {
            w[p] = coeff(&w, p);
        }
        Self { c: w }
    }

    pub fn add(&self, o: &Self) -> Self {
        Self::build(self.order(), |_, p| self.c[p] + o.c[p])
    }
    pub fn sub(&self, o: &Self) -> Self {
        Self::build(self.order(), |_, p| self.c[p] - o.c[p])
    }
    pub fn mul(&self, o: &Self) -> Self {
        Self::build(self.order(), |_, p| mul_coeff(&self.c, &o.c, p))
    }
    pub fn div(&self, o: &Self) -> Self {
        Self::build(self.order(), |w, p| div_coeff(&self.c, &o.c, w, p))
    }
    pub fn sqrt(&self) -> Self {
        Self::build(self.order(), |w, p| sqrt_coeff(&self.c, w, p))
    }
    pub fn powf(&self, alpha: f64) -> Self {
        Self::build(self.order(), |w, p| powf_coeff(&self.c, alpha, w, p))
    }
    pub fn exp(&self) -> Self {
        Self::build(self.order(), |w, p| exp_coeff(&self.c, w, p))
    }
    pub fn eval(&self, a: f64) -> f64 {
        eval(&self.c, a)
    }
}

#[cfg(test)]
mod tests {
    //! Closed-form Maclaurin series to order 30 (Abramowitz & Stegun 3.6.8,
    //! 4.2.1): (1+x)^a = sum binom(a,k) x^k, 1/(1+x) = sum (-x)^k.
    use super::*;

    const N: usize = 30;

    fn binomial_series(alpha: f64) -> Vec<f64> {
        let mut c = vec![1.0];
        for k in 1..=N {
            let prev = c[k - 1];
            c.push(prev * (alpha - (k - 1) as f64) / k as f64);
        }
        c
    }

    fn assert_coeffs(got: &[f64], want: &[f64], tol: f64) {
        for (k, (g, w)) in got.iter().zip(want).enumerate() {
            let err = (g - w).abs() / w.abs().max(1.0);
            assert!(
                err <= tol,
                "coefficient {k}: got {g:e}, want {w:e}, error {err:e}"
            );
        }
    }

    #[test]
    fn sqrt_one_plus_x() {
        let x = Series::variable(1.0, 1.0, N);
        assert_coeffs(&x.sqrt().c, &binomial_series(0.5), 1e-13);
    }

    #[test]
    fn powf_one_plus_x() {
        let x = Series::variable(1.0, 1.0, N);
        for alpha in [-0.95, -0.5, 0.05, 1.7, 3.0] {
            assert_coeffs(&x.powf(alpha).c, &binomial_series(alpha), 1e-13);
        }
    }

    #[test]
    fn reciprocal_one_plus_x() {
        let x = Series::variable(1.0, 1.0, N);
        let one = Series::constant(1.0, N);
        let want: Vec<f64> = (0..=N)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert_coeffs(&one.div(&x).c, &want, 1e-13);
    }

    #[test]
    fn products_of_closed_forms() {
        // (1+x)^a (1+x)^b = (1+x)^(a+b); sqrt(1+x)^2 = 1+x; exp(x) exp(-x) = 1.
        let x = Series::variable(1.0, 1.0, N);
        let prod = x.powf(0.3).mul(&x.powf(-1.45));
        assert_coeffs(&prod.c, &binomial_series(0.3 - 1.45), 1e-13);
        let s = x.sqrt();
        assert_coeffs(&s.mul(&s).c, &x.c, 1e-13);
        let e = Series::variable(0.0, 1.0, N).exp();
        let fact: Vec<f64> = (0..=N)
            .scan(1.0, |f, k| {
                let v = 1.0 / *f;
                *f *= (k + 1) as f64;
                Some(v)
            })
            .collect();
        assert_coeffs(&e.c, &fact, 1e-13);
    }

    #[test]
    fn sin_cos_pair() {
        // sin(x), cos(x) Maclaurin coefficients.
        let x = [0.0, 1.0]
            .iter()
            .chain([0.0; N - 1].iter())
            .copied()
            .collect::<Vec<_>>();
        let (mut s, mut c) = (vec![], vec![]);
        for p in 0..=N {
            s.push(0.0);
            c.push(0.0);
            s[p] = sin_coeff(&x, &c, p);
            c[p] = cos_coeff(&x, &s, p);
        }
        let mut f = 1.0;
        for k in 0..=N {
            if k > 0 {
                f *= k as f64;
            }
            let (ws, wc) = match k % 4 {
                0 => (0.0, 1.0 / f),
                1 => (1.0 / f, 0.0),
                2 => (0.0, -1.0 / f),
                _ => (-1.0 / f, 0.0),
            };
            assert!(
                (s[k] - ws).abs() < 1e-16 && (c[k] - wc).abs() < 1e-16,
                "order {k}"
            );
        }
    }

    #[test]
    fn horner_and_derivative() {
        let c = [1.0, 2.0, 3.0];
        assert_eq!(eval(&c, 2.0), 17.0);
        assert_eq!(eval_derivative(&c, 2.0), 14.0);
    }
}

//! RODAS4: the stiffly accurate, L-stable Rosenbrock method of order 4 with
//! an embedded order 3 (Hairer & Wanner, Solving ODEs II, §VI.4, code
//! RODAS; 6 stages), for M y' = f(t, y) with a constant, possibly singular
//! M (index-1 DAEs). In the transformed stage variables k_i:
//!
//!   (M / (h γ) − J) k_i = f(t0 + α_i h, y0 + Σ_{j<i} a_ij k_j)
//!                         + M Σ_{j<i} (c_ij / h) k_j + γ_i h ∂f/∂t,
//!   y1 = y0 + Σ m_i k_i,   error estimate = k_6 (y1 minus the embedded
//!   order-3 solution),
//!
//! with J = ∂f/∂y and ∂f/∂t at (t0, y0): one factorization of
//! M/(h γ) − J per step and 6 solves, the cost model of an ANM step (one
//! factorization, N solves), with no iteration. Coefficients: HW's RODAS
//! (their transformed form, as also used by KPP's Rodas4).

/// The coefficients of a Rosenbrock method in transformed variables.
pub struct Tableau {
    pub gamma: f64,
    /// α_i: stage times as fractions of h.
    pub alpha: [f64; 6],
    /// γ_i = Σ_j γ_ij: weights of ∂f/∂t.
    pub gamma_i: [f64; 6],
    /// a_ij, j < i (row-major, strictly lower).
    pub a: [[f64; 6]; 6],
    /// c_ij, j < i.
    pub c: [[f64; 6]; 6],
    /// Weights of the solution.
    pub m: [f64; 6],
    /// Weights of the error estimate.
    pub e: [f64; 6],
}

pub const STAGES: usize = 6;
/// Order of the error estimate's leading term (order 3 embedded): the step
/// factor is err^(−1/4).
pub const ERROR_ORDER: f64 = 4.0;

const A61: f64 = 1.221224509226641;
const A62: f64 = 6.019134481288629;
const A63: f64 = 12.53708332932087;
const A64: f64 = -0.687886036105895;

pub const RODAS4: Tableau = Tableau {
    gamma: 0.25,
    alpha: [0.0, 0.386, 0.21, 0.63, 1.0, 1.0],
    gamma_i: [0.25, -0.1043, 0.1035, -0.03620000000000023, 0.0, 0.0],
    a: [
        [0.0; 6],
        [1.544, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.9466785280815826, 0.2557011698983284, 0.0, 0.0, 0.0, 0.0],
        [
            3.314825187068521,
            2.896124015972201,
            0.9986419139977817,
            0.0,
            0.0,
            0.0,
        ],
        [A61, A62, A63, A64, 0.0, 0.0],
        [A61, A62, A63, A64, 1.0, 0.0],
    ],
    c: [
        [0.0; 6],
        [-5.6688, 0.0, 0.0, 0.0, 0.0, 0.0],
        [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0, 0.0],
        [
            -0.1073529058151375,
            -9.594562251023355,
            -20.47028614809616,
            0.0,
            0.0,
            0.0,
        ],
        [
            7.496443313967647,
            -10.24680431464352,
            -33.99990352819905,
            11.7089089320616,
            0.0,
            0.0,
        ],
        [
            8.083246795921522,
            -7.981132988064893,
            -31.52159432874371,
            16.31930543123136,
            -6.058818238834054,
            0.0,
        ],
    ],
    m: [A61, A62, A63, A64, 1.0, 1.0],
    e: [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
};

#[cfg(test)]
mod tests {
    use super::*;

    /// One step of the scheme on the scalar y' = λ y + g(t), h = 1 after
    /// scaling (z = h λ), g linear in t with slope s (h-scaled): returns y1
    /// and the error estimate.
    fn scalar_step(z: f64, y0: f64, g0: f64, s: f64) -> (f64, f64) {
        let t = &RODAS4;
        let mut k = [0.0; STAGES];
        for i in 0..STAGES {
            let yi = y0 + (0..i).map(|j| t.a[i][j] * k[j]).sum::<f64>();
            let fi = z * yi + g0 + t.alpha[i] * s;
            let ci: f64 = (0..i).map(|j| t.c[i][j] * k[j]).sum();
            k[i] = (fi + ci + t.gamma_i[i] * s) / (1.0 / t.gamma - z);
        }
        let y1 = y0 + (0..STAGES).map(|i| t.m[i] * k[i]).sum::<f64>();
        let err = (0..STAGES).map(|i| t.e[i] * k[i]).sum::<f64>();
        (y1, err)
    }

    /// The stability function R(z) = y1 for y0 = 1 agrees with e^z to
    /// O(z^5) (order 4: the error falls 2^5 = 32× when z halves), and the
    /// method is L-stable (R(−1e8) ≈ 0) and A-stable along the imaginary
    /// axis (|R(i y)| ≤ 1).
    #[test]
    fn rodas4_stability_function() {
        let e1 = (scalar_step(-0.02, 1.0, 0.0, 0.0).0 - (-0.02f64).exp()).abs();
        let e2 = (scalar_step(-0.01, 1.0, 0.0, 0.0).0 - (-0.01f64).exp()).abs();
        let ratio = e1 / e2;
        assert!((25.0..40.0).contains(&ratio), "order: ratio {ratio}");
        assert!(scalar_step(-1e8, 1.0, 0.0, 0.0).0.abs() < 1e-6);
        for zr in [-1e3, -10.0, -1.0, -0.1] {
            assert!(scalar_step(zr, 1.0, 0.0, 0.0).0.abs() <= 1.0);
        }
        // The embedded solution is of order 3: the estimate falls 2^4.
        let d1 = scalar_step(-0.02, 1.0, 0.0, 0.0).1.abs();
        let d2 = scalar_step(-0.01, 1.0, 0.0, 0.0).1.abs();
        assert!((12.0..20.0).contains(&(d1 / d2)), "estimate {}", d1 / d2);
    }

    /// The ∂f/∂t terms: y' = −(y − t)/τ from the exact y(0) has the closed
    /// form y = t − τ (1 − e^(−t/τ)); one step of length h is exact to
    /// O(h^5) for h ≪ τ and tends to the stiff limit y ≈ t − τ for h ≫ τ.
    #[test]
    fn rodas4_nonautonomous_terms() {
        let tau = 1.0;
        let exact = |t: f64| t - tau * (1.0 - (-t / tau).exp());
        let err = |h: f64| {
            // f = −y/τ + t/τ: in h-scaled form z = −h/τ, g0 = 0, s = h²/τ
            // (the slope of h g(t0 + a h) in a).
            (scalar_step(-h / tau, 0.0, 0.0, h * h / tau).0 - exact(h)).abs()
        };
        let ratio = err(0.02) / err(0.01);
        assert!((25.0..40.0).contains(&ratio), "order with f_t: {ratio}");
        // τ = 1e-6, h = 1: y(1) = 1 − τ to round-off.
        let stiff = scalar_step(-1e6, 0.0, 0.0, 1e6).0;
        assert!((stiff - (1.0 - 1e-6)).abs() < 1e-9, "{stiff}");
    }
}

//! What IDA needs from a DAE F(t, y, y') = 0: its residual, its analytic
//! iteration matrix J = dF/dy + cj dF/dy', which components are differential,
//! and, for the friction cases, the output row and slip speed.

/// A dense n x n matrix, column-major (SUNDIALS' dense layout), zeroed before
/// each Jacobian evaluation.
pub struct Dense<'a> {
    pub n: usize,
    pub data: &'a mut [f64],
}

impl Dense<'_> {
    /// Adds v to entry (row i, column j).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        self.data[j * self.n + i] += v;
    }
}

/// An implicit DAE of index 1 for IDA.
pub trait Dae {
    /// Number of unknowns.
    fn dim(&self) -> usize;
    /// For each unknown: true if differential (y' appears), false if algebraic.
    fn differential(&self) -> Vec<bool>;
    /// r = F(t, y, y').
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]);
    /// J = dF/dy + cj dF/dy' (J is zeroed by the caller).
    fn jacobian(&self, t: f64, cj: f64, y: &[f64], yp: &[f64], j: &mut Dense);
}

/// A friction case solved by IDA: a [`Dae`] with its output columns.
pub trait FrictionDae: Dae {
    /// history.csv columns, starting with "t" (the same as `anm run`).
    fn columns(&self) -> &'static [&'static str];
    /// Names of the unknowns y, in order.
    fn unknowns(&self) -> &'static [&'static str];
    /// Initial guesses (y0, y0') for IDACalcIC at t = 0; the differential
    /// components of y0 are the exact initial state.
    fn initial_guess(&self) -> (Vec<f64>, Vec<f64>);
    /// One history row at time t.
    fn row(&self, t: f64, y: &[f64]) -> Vec<f64>;
    /// The slip speed v_s.
    fn slip(&self, t: f64, y: &[f64]) -> f64;
    /// Residual of the position-level constraints that the formulation only
    /// enforces in differentiated form (0 when there are none).
    fn constraint_drift(&self, _t: f64, _y: &[f64]) -> f64 {
        0.0
    }
    /// dG/dR_N = 2 R_N / K + h of the contact law G = R_N (R_N/K + h) −
    /// eta (delta − h) at y (None without contact). Positive on the law's
    /// physical root (R_N ≈ −K h in contact, eta (delta − h) / h open),
    /// negative on its other root, where the mass passes through the
    /// obstacle with a vanishing force.
    fn contact_branch(&self, _t: f64, _y: &[f64]) -> Option<f64> {
        None
    }
}

/// Finite-difference check of [`Dae::jacobian`]: the largest
/// |J_an - J_fd| / max(1, |J_fd|) over all entries (central differences).
pub fn jacobian_error(dae: &dyn Dae, t: f64, cj: f64, y: &[f64], yp: &[f64]) -> f64 {
    let n = dae.dim();
    let mut data = vec![0.0; n * n];
    dae.jacobian(t, cj, y, yp, &mut Dense { n, data: &mut data });
    let mut worst: f64 = 0.0;
    let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
    for j in 0..n {
        let e = 1e-6 * y[j].abs().max(1e-3);
        let (mut y1, mut y2) = (y.to_vec(), y.to_vec());
        y1[j] += e;
        y2[j] -= e;
        let (mut p1, mut p2) = (yp.to_vec(), yp.to_vec());
        p1[j] += cj * e;
        p2[j] -= cj * e;
        dae.residual(t, &y1, &p1, &mut rp);
        dae.residual(t, &y2, &p2, &mut rm);
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * e);
            let an = data[j * n + i];
            worst = worst.max((an - fd).abs() / fd.abs().max(1.0));
        }
    }
    worst
}

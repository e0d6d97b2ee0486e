//! A small static problem R(U, lambda) = 0 written once with tape arithmetic
//! becomes a [`ContinuationProblem`]: residual by order-0 evaluation, tangent by
//! the exact forward tangent pass, and the order-p right-hand side by
//! incremental propagation (coefficient p of R with U_p = lambda_p = 0).

use super::continuation::ContinuationProblem;
use super::tape::{Tape, TapeBuilder, Var};
use crate::error::Result;
use crate::linalg::SparseMatrix;

/// Records R(U, lambda): `record(b, u, lambda)` returns the residuals.
pub struct TapeProblem {
    tape: Tape,
    n: usize,
    /// Orders whose input coefficients are final in the tape.
    finalized: usize,
}

impl TapeProblem {
    pub fn new(
        n: usize,
        order: usize,
        record: impl for<'a> Fn(&'a TapeBuilder, &[Var<'a>], Var<'a>) -> Vec<Var<'a>>,
    ) -> Self {
        let b = TapeBuilder::new();
        let u = b.inputs(n);
        let lambda = b.input();
        let r = record(&b, &u, lambda);
        assert_eq!(
            r.len(),
            n,
            "a static problem needs as many residuals as unknowns"
        );
        Self {
            tape: b.finish(&r, order),
            n,
            finalized: 0,
        }
    }

    fn set_order(&mut self, p: usize, u: &[f64], lambda: f64) {
        for (i, &x) in u.iter().enumerate() {
            self.tape.set_input(i, p, x);
        }
        self.tape.set_input(self.n, p, lambda);
        self.tape.propagate(p);
    }
}

impl ContinuationProblem for TapeProblem {
    fn ndof(&self) -> usize {
        self.n
    }

    fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
        let mut x = u.to_vec();
        x.push(lambda);
        self.finalized = 0;
        Ok(self.tape.eval(&x))
    }

    fn tangent(&mut self, u: &[f64], lambda: f64) -> Result<(SparseMatrix, Vec<f64>)> {
        let mut x = u.to_vec();
        x.push(lambda);
        self.tape.eval(&x);
        self.finalized = 1;
        let cols: Vec<usize> = (0..=self.n).collect();
        let jac = self.tape.jacobian(&cols);
        let kt: Vec<Vec<f64>> = jac.iter().map(|row| row[..self.n].to_vec()).collect();
        let r_lambda = jac.iter().map(|row| row[self.n]).collect();
        Ok((SparseMatrix::from_dense(&kt), r_lambda))
    }

    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], lambda: &[f64]) -> Result<Vec<f64>> {
        // Orders finalized..p-1 are now known: propagate them with their real
        // values (order p-1 was last propagated with zeros), then order p with
        // U_p = lambda_p = 0.
        for k in self.finalized..p {
            self.set_order(k, &u[k], lambda[k]);
        }
        self.finalized = p;
        self.set_order(p, &vec![0.0; self.n], 0.0);
        Ok((0..self.n).map(|j| self.tape.output(j, p)).collect())
    }
}

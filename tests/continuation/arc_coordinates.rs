//! The engine's extra arc coordinates (ContinuationProblem::arc_coordinates,
//! src/series/path.rs) on a problem whose step is known in closed form.
//!
//! R(U, lambda) = K U − lambda F with K = diag(2, 4), F = (1, 1): the path
//! is the line U = lambda U_t, U_t = K⁻¹ F = (1/2, 1/4). With the
//! coordinate y = 3 U_0 + lambda / 2 (rows J = (3, 0), y_lambda = 1/2),
//! dy/dlambda along the path is y_t = 3/2 + 1/2 = 2, and the order-1
//! normalization |U_1|² + lambda_1² + y_1² = 1 (unit scales) gives
//! lambda_1 = 1 / sqrt(1 + |U_t|² + y_t²) = 1 / sqrt(5.3125); without the
//! coordinate 1 / sqrt(1.3125). Every order p ≥ 2 vanishes (a line).

use anm::linalg::SparseMatrix;
use anm::series::Path;
use anm::series::continuation::{ArcCoordinates, ContinuationConfig, ContinuationProblem};

/// `quadratic` adds U_0² / 2 to the first equation.
struct Line {
    with_arc: bool,
    quadratic: bool,
}

impl ContinuationProblem for Line {
    fn ndof(&self) -> usize {
        2
    }
    fn residual(&mut self, u: &[f64], lambda: f64) -> anm::Result<Vec<f64>> {
        let q = if self.quadratic {
            0.5 * u[0] * u[0]
        } else {
            0.0
        };
        Ok(vec![2.0 * u[0] + q - lambda, 4.0 * u[1] - lambda])
    }
    fn tangent(&mut self, u: &[f64], _lambda: f64) -> anm::Result<(SparseMatrix, Vec<f64>)> {
        let q = if self.quadratic { u[0] } else { 0.0 };
        let k = SparseMatrix::from_dense(&[vec![2.0 + q, 0.0], vec![0.0, 4.0]]);
        Ok((k, vec![-1.0, -1.0]))
    }
    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], _lambda: &[f64]) -> anm::Result<Vec<f64>> {
        let q: f64 = if self.quadratic {
            (1..p).map(|r| 0.5 * u[r][0] * u[p - r][0]).sum()
        } else {
            0.0
        };
        Ok(vec![q, 0.0])
    }
    fn arc_coordinates(&mut self) -> Option<ArcCoordinates> {
        self.with_arc.then(|| ArcCoordinates {
            rows: vec![vec![(0, 3.0)]],
            lambda: vec![0.5],
        })
    }
    fn arc_coordinates_rhs(&mut self, _p: usize) -> Vec<f64> {
        vec![0.0]
    }
}

fn first_step(with_arc: bool, quadratic: bool) -> anm::series::PathStep {
    let mut problem = Line {
        with_arc,
        quadratic,
    };
    let cfg = ContinuationConfig {
        order: 6,
        lambda_end: 1e6,
        ..Default::default()
    };
    let mut path = Path::new(&mut problem, vec![0.0, 0.0], 0.0, cfg);
    path.step().expect("one step")
}

#[test]
fn arc_coordinates_join_the_normalization_and_leave_a_line_straight() {
    for (with_arc, norm2) in [(false, 1.3125), (true, 5.3125)] {
        let step = first_step(with_arc, false);
        let l1 = step.lambda[1];
        let want = 1.0 / f64::sqrt(norm2);
        assert!(
            (l1 - want).abs() < 1e-14,
            "with_arc {with_arc}: {l1} vs {want}"
        );
        assert!(
            (step.u[1][0] - 0.5 * l1).abs() < 1e-14 && (step.u[1][1] - 0.25 * l1).abs() < 1e-14
        );
        for p in 2..step.u.len() {
            assert!(step.lambda[p].abs() < 1e-14 && step.u[p].iter().all(|x| x.abs() < 1e-14));
        }
        // The end lies on the line.
        assert!((step.u_end[0] - 0.5 * step.lambda_end).abs() < 1e-12);
    }
}

/// With U_0² / 2 in the first equation the terms no longer vanish; the
/// path parameter stays the pseudo-arclength in (U, lambda, y): for every
/// p ≥ 2, <U_p, U_1> + lambda_p lambda_1 + y_p y_1 = 0 with y_p = 3 U_0,p
/// + lambda_p / 2, and the order-1 normalization holds.
#[test]
fn arc_coordinates_join_the_orthogonality_of_every_order() {
    let step = first_step(true, true);
    let y = |p: usize| 3.0 * step.u[p][0] + 0.5 * step.lambda[p];
    let dot = |p: usize| {
        step.u[p][0] * step.u[1][0]
            + step.u[p][1] * step.u[1][1]
            + step.lambda[p] * step.lambda[1]
            + y(p) * y(1)
    };
    assert!((dot(1) - 1.0).abs() < 1e-14, "{}", dot(1));
    for p in 2..step.u.len() {
        let size = step.u[p][0].abs() + step.lambda[p].abs();
        assert!(size > 0.0, "order {p} vanishes");
        assert!(
            dot(p).abs() < 1e-14 * size.max(1.0),
            "order {p}: {}",
            dot(p)
        );
    }
}

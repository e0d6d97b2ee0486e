//! Tangential coordinates of a friction node on its obstacle: the
//! differential variables z of the implicit step ([`super::implicit_step`]).
//!
//! The kinematics t_a(x)·ẋ = w_a of [`super::friction_dae`] has a frame
//! that turns with the node on a cylinder, so it is not of the form
//! M ż = f with a constant M that a Rosenbrock method needs. Coordinates C(x)
//! with dC/dt = D(x) w make it so (z = C(x) algebraic, ż = D w
//! differential):
//!
//! - plane (normal n, frame t_1, t_2 fixed): C = (t_1·x, t_2·x), D = I;
//! - cylinder (centre c, axis e, radius R; y = P (x − c), ρ = |y|,
//!   n = y / ρ, t_2 = n × e): C = (e·x, R θ) with θ the angle of y from the
//!   node's radial direction u_0 at the step start towards v_0 = u_0 × e;
//!   dθ/dx = t_2ᵀ / ρ, so dC/dt = (w_1, (R / ρ) w_2), D = diag(1, R / ρ).
//!   A crowned roll (radius r(s) = R − κ s²) keeps this chart and the
//!   frame t_1 = e, t_2 = n × e = (y / ρ) × e: C is still a coordinate
//!   system and dC/dt = D w still holds exactly; t_1 leaves the surface's
//!   tangent plane by its slope r' = −2 κ s (≤ 2e-3 rad for a 0.5 mm
//!   crown over a 1 m face), so the friction force has a normal part of at
//!   most |r'| f R_N and the axial slip speed is short of the slip along
//!   the surface by 1 − 1/√(1 + r'²) (2e-6).

use super::friction_pair::plane_t1;
use crate::contact::Obstacle;
use nalgebra::{Matrix3, Vector3};

#[derive(Clone, Debug)]
pub enum Chart {
    Plane {
        t1: Vector3<f64>,
        t2: Vector3<f64>,
    },
    Cylinder {
        centre: Vector3<f64>,
        axis: Vector3<f64>,
        radius: f64,
        u0: Vector3<f64>,
        v0: Vector3<f64>,
    },
}

/// C(x), its gradient, D(x) and ∂(D w)/∂x at one point.
#[derive(Clone, Debug)]
pub struct ChartValue {
    pub c: [f64; 2],
    /// dC_a/dx.
    pub dc: [Vector3<f64>; 2],
    pub d: [f64; 2],
    /// ∂(D_a w_a)/∂x.
    pub ddw: [Vector3<f64>; 2],
}

impl Chart {
    /// The chart of a node at x (None on a cylinder's axis).
    pub fn new(obstacle: &Obstacle, x: &Vector3<f64>) -> Option<Self> {
        match obstacle {
            Obstacle::Plane { normal, .. } => {
                let t1 = plane_t1(normal);
                Some(Chart::Plane {
                    t1,
                    t2: normal.cross(&t1),
                })
            }
            Obstacle::Cylinder {
                centre,
                axis,
                radius,
                ..
            } => {
                let y = (Matrix3::identity() - axis * axis.transpose()) * (x - centre);
                let u0 = y.try_normalize(1e-12 * radius)?;
                Some(Chart::Cylinder {
                    centre: *centre,
                    axis: *axis,
                    radius: *radius,
                    u0,
                    v0: u0.cross(axis),
                })
            }
        }
    }

    /// The coordinates and their derivatives at x for the velocity w.
    pub fn eval(&self, x: &Vector3<f64>, w: [f64; 2]) -> ChartValue {
        match self {
            Chart::Plane { t1, t2 } => ChartValue {
                c: [t1.dot(x), t2.dot(x)],
                dc: [*t1, *t2],
                d: [1.0, 1.0],
                ddw: [Vector3::zeros(); 2],
            },
            Chart::Cylinder {
                centre,
                axis,
                radius,
                u0,
                v0,
            } => {
                let y = (Matrix3::identity() - axis * axis.transpose()) * (x - centre);
                let rho = y.norm();
                let n = y / rho;
                let t2 = n.cross(axis);
                let theta = y.dot(v0).atan2(y.dot(u0));
                let ratio = radius / rho;
                ChartValue {
                    c: [axis.dot(x), radius * theta],
                    dc: [*axis, t2 * ratio],
                    d: [1.0, ratio],
                    ddw: [Vector3::zeros(), n * (-ratio * w[1] / rho)],
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// dC/dx and ∂(D w)/∂x against central differences, and dC/dt = D w
    /// for a node moving at ẋ with w = (t_1·ẋ, t_2·ẋ) (the tape's frame).
    #[test]
    fn chart_derivatives_and_kinematics() {
        let cyl = Obstacle::cylinder(Vector3::new(0.1, 0.0, -0.5), Vector3::y(), 0.5).unwrap();
        let plane = Obstacle::plane(Vector3::zeros(), Vector3::new(0.1, 0.0, 1.0)).unwrap();
        let x = Vector3::new(0.3, 0.2, 0.01);
        let xdot = Vector3::new(0.05, -0.02, 0.01);
        for ob in [cyl, plane] {
            let chart = Chart::new(&ob, &(x + Vector3::new(0.01, 0.0, -0.02))).unwrap();
            let g = ob.gap(&x).unwrap();
            let (t1, t2) = match &ob {
                Obstacle::Plane { normal, .. } => {
                    (plane_t1(normal), normal.cross(&plane_t1(normal)))
                }
                Obstacle::Cylinder { axis, .. } => (*axis, g.n.cross(axis)),
            };
            let w = [t1.dot(&xdot), t2.dot(&xdot)];
            let v = chart.eval(&x, w);
            let h = 1e-6;
            let up = chart.eval(&(x + xdot * h), w);
            let down = chart.eval(&(x - xdot * h), w);
            for (a, &wa) in w.iter().enumerate() {
                let rate = (up.c[a] - down.c[a]) / (2.0 * h);
                assert!((rate - v.d[a] * wa).abs() < 1e-8, "dC/dt = D w ({a})");
                assert!((rate - v.dc[a].dot(&xdot)).abs() < 1e-8, "dC/dx ({a})");
                let dw = (up.d[a] - down.d[a]) * wa / (2.0 * h);
                assert!((dw - v.ddw[a].dot(&xdot)).abs() < 1e-8, "d(Dw)/dx ({a})");
            }
        }
    }
}

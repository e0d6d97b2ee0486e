//! Regularized power friction law, paper eqs. (5), (6), (11):
//!
//!   R_T = -f |R_N|_reg |v_s|_reg^(q-1) / Vc^q  v_s,
//!   |v|_reg = sqrt(v.v + omega^2 Vc^2),   |R_N|_reg = sqrt(R_N^2 + zeta^2).
//!
//! q = 0 is regularized Coulomb; q = 1 is viscous. With zeta = None the normal
//! force enters as R_N itself (eq. 5, used in §3.2 where R_N is known).
//!
//! The law holds for a scalar slip (the point-mass cases of §3) and for a
//! slip vector in the obstacle's tangent plane (a shell contact node, DESIGN
//! §7); the scalar law is the vector law along one axis. At a node x moving
//! at ẋ against an obstacle (gap h, outward normal n) whose surface moves at
//! w(p) at the contact point p = x − h n, the slip velocity is
//!
//!   v_s = P (ẋ − w(p)),  P = I − n nᵀ,
//!
//! with w = V for a translating obstacle and w = Ω e × (p − c) for one
//! turning about its axis e through c ([`slip`]).

use super::motion::Motion;
use super::obstacle::{Obstacle, Vec3};
use crate::series::{TapeBuilder, Var};
use nalgebra::Matrix3;

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

    /// |v|_reg of eq. (6) for a slip vector.
    pub fn slip_magnitude_vec(&self, vs: &Vec3) -> f64 {
        (vs.norm_squared() + (self.omega * self.vc).powi(2)).sqrt()
    }

    /// The factor c of R_T = c v_s: −f |R_N|_reg |v_s|_reg^(q−1) / Vc^q, with
    /// m = |v_s|_reg.
    fn slip_factor(&self, rn: f64, m: f64) -> f64 {
        -self.f * self.normal_magnitude(rn) * m.powf(self.q - 1.0) / self.vc.powf(self.q)
    }

    /// R_T for a scalar slip velocity v_s.
    pub fn force(&self, rn: f64, vs: f64) -> f64 {
        self.slip_factor(rn, self.slip_magnitude(vs)) * vs
    }

    /// R_T for a slip vector v_s (eqs. 5, 6, 11 with a vector).
    pub fn force_vec(&self, rn: f64, vs: &Vec3) -> Vec3 {
        vs * self.slip_factor(rn, self.slip_magnitude_vec(vs))
    }

    /// dR_T/dv_s = −f |R_N|_reg / Vc^q m^(q−3) (m² I + (q − 1) v_s v_sᵀ),
    /// m = |v_s|_reg, summed as omega² Vc² I + (|v_s|² I − v_s v_sᵀ) + q v_s v_sᵀ
    /// so that a small omega does not cancel (scalar: q v_s² + omega² Vc²).
    pub fn d_force_vec_d_slip(&self, rn: f64, vs: &Vec3) -> Matrix3<f64> {
        let m = self.slip_magnitude_vec(vs);
        if self.q == 1.0 && m == 0.0 {
            // The viscous law R_T = −f |R_N|_reg v_s / Vc at rest without
            // omega: m^(q−3) m² is 0 · ∞ in the sum below.
            return Matrix3::identity() * (-self.f * self.normal_magnitude(rn) / self.vc);
        }
        let c = -self.f * self.normal_magnitude(rn) / self.vc.powf(self.q) * m.powf(self.q - 3.0);
        let w2 = (self.omega * self.vc).powi(2);
        Matrix3::from_fn(|i, j| {
            let across = if i == j {
                w2 + (0..3)
                    .filter(|&k| k != i)
                    .map(|k| vs[k] * vs[k])
                    .sum::<f64>()
            } else {
                -vs[i] * vs[j]
            };
            c * (across + self.q * vs[i] * vs[j])
        })
    }

    /// dR_T/dR_N = R_T / |R_N|_reg · d|R_N|_reg/dR_N (vector slip).
    pub fn d_force_vec_d_normal(&self, rn: f64, vs: &Vec3) -> Vec3 {
        let dn = match self.zeta {
            Some(_) => rn / self.normal_magnitude(rn),
            None => 1.0,
        };
        vs * (-self.f * dn * self.slip_magnitude_vec(vs).powf(self.q - 1.0) / self.vc.powf(self.q))
    }

    /// dR_T/dv_s for a scalar slip: the (0, 0) entry of the vector law's
    /// derivative, −f |R_N|_reg / Vc^q m^(q−3) (q v_s² + omega² Vc²).
    pub fn d_force_d_slip(&self, rn: f64, vs: f64) -> f64 {
        self.d_force_vec_d_slip(rn, &Vec3::new(vs, 0.0, 0.0))[(0, 0)]
    }

    /// dR_T/dR_N for a scalar slip.
    pub fn d_force_d_normal(&self, rn: f64, vs: f64) -> f64 {
        self.d_force_vec_d_normal(rn, &Vec3::new(vs, 0.0, 0.0))[0]
    }

    /// Records the factor c of R_T = c v_s from R_N and |v_s|² on a tape.
    fn record_factor<'a>(&self, rn: Var<'a>, vs2: Var<'a>) -> Var<'a> {
        let normal = match self.zeta {
            Some(z) => (rn * rn + z * z).sqrt(),
            None => rn,
        };
        if self.q == 1.0 {
            // The viscous law: no power of the slip (whose series, at rest
            // without omega, would divide by its zero value).
            return -self.f / self.vc.powf(self.q) * normal;
        }
        let slip2 = vs2 + (self.omega * self.vc).powi(2);
        // |v|_reg^(q-1) = (v^2 + omega^2 Vc^2)^((q-1)/2): one power, no sqrt.
        -self.f / self.vc.powf(self.q) * normal * slip2.powf(0.5 * (self.q - 1.0))
    }

    /// Records R_T(R_N, v_s) on a tape.
    pub fn record<'a>(&self, rn: Var<'a>, vs: Var<'a>) -> Var<'a> {
        self.record_factor(rn, vs * vs) * vs
    }

    /// Records the vector R_T(R_N, v_s) on a tape.
    pub fn record_vec<'a>(&self, rn: Var<'a>, vs: [Var<'a>; 3]) -> [Var<'a>; 3] {
        let c = self.record_factor(rn, vs[0] * vs[0] + vs[1] * vs[1] + vs[2] * vs[2]);
        vs.map(|v| c * v)
    }

    /// The friction force on a node at x moving at ẋ, pressed with R_N
    /// against `obstacle` (where it is now) moving by `motion`, and its
    /// derivatives. None where the normal is undefined.
    pub fn nodal(
        &self,
        obstacle: &Obstacle,
        motion: &Motion,
        x: &Vec3,
        xdot: &Vec3,
        rn: f64,
    ) -> Option<NodalFriction> {
        let s = slip(obstacle, motion, x, xdot)?;
        let d = self.d_force_vec_d_slip(rn, &s.vs);
        Some(NodalFriction {
            force: self.force_vec(rn, &s.vs),
            d_x: d * s.d_x,
            d_xdot: d * s.d_xdot,
            d_rn: self.d_force_vec_d_normal(rn, &s.vs),
            slip: s.vs,
        })
    }
}

/// Friction force R_T at one node and its derivatives.
#[derive(Clone, Copy, Debug)]
pub struct NodalFriction {
    pub force: Vec3,
    /// dR_T/dx (through the normal and the contact point).
    pub d_x: Matrix3<f64>,
    /// dR_T/dẋ.
    pub d_xdot: Matrix3<f64>,
    /// dR_T/dR_N.
    pub d_rn: Vec3,
    /// The slip velocity v_s.
    pub slip: Vec3,
}

/// Slip velocity v_s = P (ẋ − w(p)) of a node and its derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Slip {
    pub vs: Vec3,
    /// dv_s/dx.
    pub d_x: Matrix3<f64>,
    /// dv_s/dẋ = P.
    pub d_xdot: Matrix3<f64>,
}

/// dw/dp of the obstacle's surface velocity: Ω [e]× for a turning
/// cylinder, Ω [n]× for a plane turning about its normal, 0 for a
/// translation (w = V everywhere).
fn surface_velocity_gradient(obstacle: &Obstacle, motion: &Motion) -> Matrix3<f64> {
    match (motion, obstacle) {
        (Motion::Rotate { omega }, Obstacle::Cylinder { axis, .. }) => axis.cross_matrix() * *omega,
        (Motion::Rotate { omega }, Obstacle::Plane { normal, .. }) => {
            normal.cross_matrix() * *omega
        }
        _ => Matrix3::zeros(),
    }
}

/// Slip velocity of a node at x moving at ẋ against `obstacle` (where it is
/// now) moving by `motion` (module doc). With r = ẋ − w(p):
///   dp/dx = I − n nᵀ − h dn/dx,   dr/dx = −(dw/dp) dp/dx,
///   dv_s/dx = P dr/dx − n rᵀ dn/dx − (n·r) dn/dx,   dv_s/dẋ = P.
/// None where the normal is undefined (a point on a cylinder's axis).
pub fn slip(obstacle: &Obstacle, motion: &Motion, x: &Vec3, xdot: &Vec3) -> Option<Slip> {
    let g = obstacle.gap(x)?;
    let n = g.n;
    let p = x - n * g.h;
    let r = xdot - motion.surface_velocity(obstacle, &p);
    let proj = Matrix3::identity() - n * n.transpose();
    let dp = proj - g.dn * g.h;
    let dr = -surface_velocity_gradient(obstacle, motion) * dp;
    let nr = n.dot(&r);
    Some(Slip {
        vs: proj * r,
        d_x: proj * dr - n * (r.transpose() * g.dn) - g.dn * nr,
        d_xdot: proj,
    })
}

/// Records the slip velocity v_s(x, ẋ) of [`slip`] on a tape (for its
/// Taylor series along a path: the normal of a cylinder is not polynomial).
pub fn record_slip<'a>(
    b: &'a TapeBuilder,
    obstacle: &Obstacle,
    motion: &Motion,
    x: [Var<'a>; 3],
    xdot: [Var<'a>; 3],
) -> [Var<'a>; 3] {
    let (n, h) = record_gap(b, obstacle, x);
    let w = record_surface_velocity(b, obstacle, motion, x, n, h);
    let r: [Var<'a>; 3] = std::array::from_fn(|i| xdot[i] - w[i]);
    let nr = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
    std::array::from_fn(|i| r[i] - nr * n[i])
}

/// Records the outward normal n and the gap h of a point x against
/// `obstacle` (obstacle::Obstacle::gap): a plane's fixed normal, or for a
/// cylinder y = P (x − c), d = |y|, n = y / d, h = d − r.
pub fn record_gap<'a>(
    b: &'a TapeBuilder,
    obstacle: &Obstacle,
    x: [Var<'a>; 3],
) -> ([Var<'a>; 3], Var<'a>) {
    let dot = |a: [Var<'a>; 3], c: &Vec3| a[0] * c[0] + a[1] * c[1] + a[2] * c[2];
    match obstacle {
        Obstacle::Plane { point, normal } => {
            let h = dot(x, normal) - point.dot(normal);
            (std::array::from_fn(|i| b.constant(normal[i])), h)
        }
        Obstacle::Cylinder {
            centre,
            axis,
            radius,
            crown,
        } => {
            let xc: [Var<'a>; 3] = std::array::from_fn(|i| x[i] - centre[i]);
            let along = dot(xc, axis);
            let y: [Var<'a>; 3] = std::array::from_fn(|i| xc[i] - along * axis[i]);
            let d = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
            // The crown's gradient 2 κ s a (obstacle.rs).
            let n: [Var<'a>; 3] =
                std::array::from_fn(|i| y[i] / d + along * (2.0 * crown * axis[i]));
            (n, d - *radius + along * along * *crown)
        }
    }
}

/// Records the surface velocity w(p) of `obstacle` moving by `motion` at
/// the contact point p = x − h n of a point x (Motion::surface_velocity).
pub fn record_surface_velocity<'a>(
    b: &'a TapeBuilder,
    obstacle: &Obstacle,
    motion: &Motion,
    x: [Var<'a>; 3],
    n: [Var<'a>; 3],
    h: Var<'a>,
) -> [Var<'a>; 3] {
    let p: [Var<'a>; 3] = std::array::from_fn(|i| x[i] - h * n[i]);
    match (motion, obstacle) {
        (Motion::Rotate { omega }, Obstacle::Cylinder { centre, axis, .. }) => {
            let q: [Var<'a>; 3] = std::array::from_fn(|i| p[i] - centre[i]);
            cross_const(axis, q, *omega)
        }
        (Motion::Rotate { omega }, Obstacle::Plane { point, normal }) => {
            let q: [Var<'a>; 3] = std::array::from_fn(|i| p[i] - point[i]);
            cross_const(normal, q, *omega)
        }
        _ => {
            let v = motion.velocity();
            std::array::from_fn(|i| b.constant(v[i]))
        }
    }
}

/// s (a × q) for a constant vector a.
fn cross_const<'a>(a: &Vec3, q: [Var<'a>; 3], s: f64) -> [Var<'a>; 3] {
    [
        (q[2] * a[1] - q[1] * a[2]) * s,
        (q[0] * a[2] - q[2] * a[0]) * s,
        (q[1] * a[0] - q[0] * a[1]) * s,
    ]
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

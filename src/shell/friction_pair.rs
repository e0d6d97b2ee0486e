//! Regularized friction at one shell contact node, recorded on a tape for its
//! Taylor series in time (issue 10 item 2, DESIGN §7).
//!
//! The node at x is paired with one obstacle (gap h, outward normal n). Its
//! velocity in the obstacle's tangent plane is carried by two unknowns
//! w = (t_1·ẋ, t_2·ẋ) in a right-handed frame (t_1, t_2, n) attached to the
//! node's position: a plane's frame is fixed; a cylinder of axis e has
//! t_1 = e, t_2 = n × e, turning with the node. The tape computes, from
//! x (3 inputs), w (2 inputs) and the motion factor m(t) of the obstacle's
//! surface velocity (1 input):
//!
//!   h, n                       (obstacle::Obstacle::gap, on the tape)
//!   R_N = R(h)                 (eq. 3, the root continuous through contact)
//!   v_s = t_1 w_1 + t_2 w_2 − m P w_obs(p),   p = x − h n,  P = I − n nᵀ
//!   R_T = −f |R_N|_reg |v_s|_reg^(q−1) / Vc^q v_s   (eqs. 5, 6, 11)
//!
//! (P ẋ = t_1 (t_1·ẋ) + t_2 (t_2·ẋ), so v_s is the slip of
//! contact::friction::slip.) Outputs: R_T (3), t_1 (3), t_2 (3), v_s (3),
//! R_N (1).

use crate::contact::normal::NormalLaw;
use crate::contact::{FrictionLaw, Motion, Obstacle, friction};
use crate::series::{Tape, TapeBuilder, Var};
use nalgebra::Vector3;

/// Output slots of the tape.
pub const FORCE: usize = 0;
pub const T1: usize = 3;
pub const T2: usize = 6;
pub const SLIP: usize = 9;
pub const RN: usize = 12;
const N_OUT: usize = 13;
/// Input slots: x (0..3), w (3..5), m (5).
pub const W: usize = 3;
pub const M: usize = 5;
pub const N_IN: usize = 6;

/// The tape of one node's friction force over one step.
pub struct FrictionPair {
    /// Index of the contact pair in the model.
    pub pair: usize,
    pub node: usize,
    pub obstacle: usize,
    pub tape: Tape,
}

impl FrictionPair {
    /// Records the tape about the gap h0 of the step start (it picks the
    /// expression of eq. 3 that is free of cancellation on that side).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        pair: usize,
        node: usize,
        obstacle_index: usize,
        obstacle: &Obstacle,
        motion: &Motion,
        normal: &NormalLaw,
        law: &FrictionLaw,
        h0: f64,
        order: usize,
    ) -> Self {
        let b = TapeBuilder::new();
        let inputs = b.inputs(N_IN);
        let x = [inputs[0], inputs[1], inputs[2]];
        let w = [inputs[W], inputs[W + 1]];
        let m = inputs[M];
        let outputs = record(&b, obstacle, motion, normal, law, h0, x, w, m);
        Self {
            pair,
            node,
            obstacle: obstacle_index,
            tape: b.finish(&outputs, order),
        }
    }

    /// Output vector (3 components from `slot`) at order p.
    pub fn out3(&self, slot: usize, p: usize) -> Vector3<f64> {
        Vector3::new(
            self.tape.output(slot, p),
            self.tape.output(slot + 1, p),
            self.tape.output(slot + 2, p),
        )
    }
}

fn cross<'a>(a: [Var<'a>; 3], c: [Var<'a>; 3]) -> [Var<'a>; 3] {
    [
        a[1] * c[2] - a[2] * c[1],
        a[2] * c[0] - a[0] * c[2],
        a[0] * c[1] - a[1] * c[0],
    ]
}

/// A unit vector normal to `n` (the plane's t_1): e_x projected, or e_y
/// when n is close to e_x.
pub fn plane_t1(n: &Vector3<f64>) -> Vector3<f64> {
    let e = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    (e - n * n.dot(&e)).normalize()
}

#[allow(clippy::too_many_arguments)]
fn record<'a>(
    b: &'a TapeBuilder,
    obstacle: &Obstacle,
    motion: &Motion,
    normal: &NormalLaw,
    law: &FrictionLaw,
    h0: f64,
    x: [Var<'a>; 3],
    w: [Var<'a>; 2],
    m: Var<'a>,
) -> Vec<Var<'a>> {
    let konst = |v: Vector3<f64>| -> [Var<'a>; 3] { std::array::from_fn(|i| b.constant(v[i])) };
    let (n, h) = friction::record_gap(b, obstacle, x);
    let (t1, t2) = match obstacle {
        Obstacle::Plane { normal, .. } => {
            let t1 = plane_t1(normal);
            (konst(t1), konst(normal.cross(&t1)))
        }
        Obstacle::Cylinder { axis, .. } => (konst(*axis), cross(n, konst(*axis))),
    };
    // Eq. (3): R = 2 eta (delta − h) / (h + s) for h >= 0, (K/2)(s − h)
    // for h < 0, s = sqrt(h² + 4 eta (delta − h) / K).
    let (k, eta, delta) = (normal.k, normal.eta, normal.delta);
    let s = (h * h + (b.constant(delta) - h) * (4.0 * eta / k)).sqrt();
    let rn = if h0 >= 0.0 {
        (b.constant(delta) - h) * (2.0 * eta) / (h + s)
    } else {
        (s - h) * (0.5 * k)
    };
    // Surface velocity of the obstacle at p = x − h n (full motion), projected.
    let w_obs = friction::record_surface_velocity(b, obstacle, motion, x, n, h);
    let nw = n[0] * w_obs[0] + n[1] * w_obs[1] + n[2] * w_obs[2];
    let slip: [Var<'a>; 3] =
        std::array::from_fn(|i| t1[i] * w[0] + t2[i] * w[1] - (w_obs[i] - nw * n[i]) * m);
    let force = law.record_vec(rn, slip);
    let mut out = Vec::with_capacity(N_OUT);
    out.extend(force);
    out.extend(t1);
    out.extend(t2);
    out.extend(slip);
    out.push(rn);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tape's R_N, v_s and R_T equal the direct laws (eq. 3 and
    /// contact::friction::nodal, which take ẋ whole) at a node moving at ẋ,
    /// with w = (t_1·ẋ, t_2·ẋ), against a turning cylinder and a
    /// translating plane; its Jacobian matches central differences.
    #[test]
    fn tape_matches_the_direct_law_and_differences() {
        let law = FrictionLaw {
            f: 0.2,
            q: 0.3,
            vc: 0.5,
            omega: 0.05,
            zeta: Some(0.01),
        };
        let cases = [
            (
                Obstacle::cylinder(Vector3::new(0.1, 0.0, -0.5), Vector3::y(), 0.5).unwrap(),
                Motion::Rotate { omega: 0.7 },
                Vector3::new(0.3, 0.2, 0.01),
            ),
            (
                Obstacle::plane(Vector3::zeros(), Vector3::new(0.1, 0.0, 1.0)).unwrap(),
                Motion::Translate {
                    velocity: Vector3::new(0.4, -0.1, 0.0),
                },
                Vector3::new(0.3, 0.2, -1e-5),
            ),
        ];
        let xdot = Vector3::new(0.05, -0.02, 0.01);
        let m = 0.8;
        for (ob, motion, x) in cases {
            let normal = NormalLaw {
                k: 1e6,
                eta: 1e-3,
                delta: 0.02,
            };
            let g = ob.gap(&x).unwrap();
            let mut fp = FrictionPair::new(0, 0, 0, &ob, &motion, &normal, &law, g.h, 3);
            let t1 = |fp: &mut FrictionPair, x: &Vector3<f64>| {
                let v = fp.tape.eval(&[x[0], x[1], x[2], 0.0, 0.0, m]);
                (
                    Vector3::new(v[T1], v[T1 + 1], v[T1 + 2]),
                    Vector3::new(v[T2], v[T2 + 1], v[T2 + 2]),
                )
            };
            let (a, c) = t1(&mut fp, &x);
            assert!((a.cross(&c) - g.n).norm() < 1e-14, "right-handed frame");
            let input = [x[0], x[1], x[2], a.dot(&xdot), c.dot(&xdot), m];
            let out = fp.tape.eval(&input);
            let rn = normal.force(g.h);
            assert!((out[RN] - rn).abs() <= 1e-12 * rn.abs());
            let scaled = match motion {
                Motion::Rotate { omega } => Motion::Rotate { omega: omega * m },
                Motion::Translate { velocity } => Motion::Translate {
                    velocity: velocity * m,
                },
                Motion::Fixed => Motion::Fixed,
            };
            let direct = law.nodal(&ob, &scaled, &x, &xdot, rn).unwrap();
            for i in 0..3 {
                assert!((out[SLIP + i] - direct.slip[i]).abs() < 1e-14);
                assert!(
                    (out[FORCE + i] - direct.force[i]).abs() <= 1e-12 * direct.force.norm(),
                    "force {i}: {} vs {}",
                    out[FORCE + i],
                    direct.force[i]
                );
            }
            // Jacobian against central differences.
            fp.tape.eval(&input);
            let jac = fp.tape.jacobian(&[0, 1, 2, 3, 4, 5]);
            for j in 0..N_IN {
                let hstep = 1e-7 * (1.0 + input[j].abs());
                let mut up = input;
                let mut down = input;
                up[j] += hstep;
                down[j] -= hstep;
                let fu = fp.tape.eval(&up);
                let fd = fp.tape.eval(&down);
                for o in 0..N_OUT {
                    let fdv = (fu[o] - fd[o]) / (2.0 * hstep);
                    let scale = 1.0 + fdv.abs() + jac[o][j].abs();
                    assert!(
                        (jac[o][j] - fdv).abs() <= 1e-5 * scale,
                        "d out {o} / d in {j}: {} vs {fdv}",
                        jac[o][j]
                    );
                }
            }
        }
    }
}

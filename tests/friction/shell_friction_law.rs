//! The friction law at a shell contact node (issue 10 item 1, DESIGN §7):
//! the vector law in the obstacle's tangent plane, the slip velocity against
//! translating and turning obstacles, their derivatives against finite
//! differences and their Taylor series against direct evaluation along a
//! path, as the point-mass laws are checked (src/contact/friction.rs).

use anm::contact::friction::{record_slip, slip};
use anm::contact::obstacle::Vec3;
use anm::contact::{FrictionLaw, Motion, Obstacle};
use anm::series::{TapeBuilder, taylor};

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

/// Obstacles (at their current place) and motions covering every
/// surface-velocity case.
fn cases() -> Vec<(Obstacle, Motion)> {
    let cyl =
        Obstacle::cylinder(Vec3::new(0.1, -0.2, 0.3), Vec3::new(0.2, 1.0, -0.1), 0.5).unwrap();
    let plane = Obstacle::plane(Vec3::new(0.0, 0.0, -0.1), Vec3::new(0.1, -0.2, 1.0)).unwrap();
    let trans = Motion::Translate {
        velocity: Vec3::new(0.3, -0.1, 0.05),
    };
    let rot = Motion::Rotate { omega: 1.7 };
    vec![
        (cyl.clone(), Motion::Fixed),
        (cyl.clone(), trans),
        (cyl, rot),
        (plane.clone(), trans),
        (plane, rot),
    ]
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn coulomb_limit_opposes_the_slip_with_f_times_the_normal_force() {
    // q = 0, omega -> 0: R_T = -f R_N v_s / |v_s| (eq. 5), any direction.
    let law = FrictionLaw {
        f: 0.3,
        q: 0.0,
        vc: 1.0,
        omega: 1e-9,
        zeta: None,
    };
    let vs = Vec3::new(0.3, -0.4, 1.2);
    let rt = law.force_vec(2.0, &vs);
    let want = -vs / vs.norm() * (0.3 * 2.0);
    assert!((rt - want).norm() < 1e-12, "{rt} vs {want}");
    // q = 1: R_T = -f R_N v_s / Vc (viscous) to the regularization only.
    let visc = FrictionLaw { q: 1.0, ..law };
    assert!((visc.force_vec(2.0, &vs) + vs * 0.6).norm() < 1e-15);
}

#[test]
fn the_scalar_law_is_the_vector_law_along_one_axis() {
    for law in laws() {
        for (rn, v) in [(0.7, -0.3), (1.5, 2.0), (-0.2, 0.0)] {
            for axis in 0..3 {
                let mut vs = Vec3::zeros();
                vs[axis] = v;
                let f = law.force_vec(rn, &vs);
                assert!(close(f[axis], law.force(rn, v), 1e-15));
                let d = law.d_force_vec_d_slip(rn, &vs);
                assert!(close(d[(axis, axis)], law.d_force_d_slip(rn, v), 1e-14));
            }
        }
    }
}

#[test]
fn vector_law_derivatives_match_finite_differences() {
    let h = 1e-6;
    for law in laws() {
        for (rn, vs) in [
            (0.7, Vec3::new(-0.3, 0.2, 0.1)),
            (0.0, Vec3::new(0.02, 0.0, -0.01)),
            (1.5, Vec3::new(2.0, -1.0, 0.5)),
            (-0.2, Vec3::zeros()),
        ] {
            let d = law.d_force_vec_d_slip(rn, &vs);
            for j in 0..3 {
                let mut e = Vec3::zeros();
                e[j] = h;
                let fd = (law.force_vec(rn, &(vs + e)) - law.force_vec(rn, &(vs - e))) / (2.0 * h);
                for i in 0..3 {
                    assert!(
                        close(d[(i, j)], fd[i], 1e-7),
                        "{law:?} dv[{i}][{j}] {} vs {}",
                        d[(i, j)],
                        fd[i]
                    );
                }
            }
            let dn = law.d_force_vec_d_normal(rn, &vs);
            let fd = (law.force_vec(rn + h, &vs) - law.force_vec(rn - h, &vs)) / (2.0 * h);
            assert!((dn - fd).norm() <= 1e-7 * (1.0 + dn.norm()), "{law:?}");
        }
    }
}

#[test]
fn slip_against_translating_and_turning_obstacles_in_closed_form() {
    // Plane z = 0 translating at V: v_s = P (ẋ − V), the normal part dropped.
    let plane = Obstacle::plane(Vec3::zeros(), Vec3::z()).unwrap();
    let m = Motion::Translate {
        velocity: Vec3::new(0.5, 0.2, -0.3),
    };
    let s = slip(
        &plane,
        &m,
        &Vec3::new(1.0, 2.0, 0.01),
        &Vec3::new(0.1, 0.0, 0.7),
    )
    .unwrap();
    assert!((s.vs - Vec3::new(-0.4, -0.2, 0.0)).norm() < 1e-15);
    // Cylinder of radius R about z turning at Omega: a node at rest on its
    // surface at angle phi slips at −Omega R (−sin phi, cos phi, 0); a node
    // carried by the surface does not slip.
    let (r, om, phi) = (0.3, 2.5, 0.7f64);
    let cyl = Obstacle::cylinder(Vec3::zeros(), Vec3::z(), r).unwrap();
    let rot = Motion::Rotate { omega: om };
    let x = Vec3::new(r * phi.cos(), r * phi.sin(), 0.4);
    let tangent = Vec3::new(-phi.sin(), phi.cos(), 0.0);
    let s = slip(&cyl, &rot, &x, &Vec3::zeros()).unwrap();
    assert!((s.vs + tangent * (om * r)).norm() < 1e-15, "{}", s.vs);
    let s = slip(&cyl, &rot, &x, &(tangent * (om * r) + Vec3::z() * 0.2)).unwrap();
    assert!((s.vs - Vec3::z() * 0.2).norm() < 1e-15, "{}", s.vs);
    // Off the surface (gap 0.01), the contact point is the projection on it.
    let x_off = x * ((r + 0.01) / r);
    let s = slip(&cyl, &rot, &x_off, &Vec3::zeros()).unwrap();
    assert!((s.vs + tangent * (om * r)).norm() < 1e-15);
}

#[test]
fn nodal_friction_derivatives_match_finite_differences() {
    let h = 1e-6;
    let x = Vec3::new(0.45, 0.1, 0.35);
    let xdot = Vec3::new(0.2, -0.4, 0.3);
    let rn = 0.8;
    for (obst, motion) in cases() {
        for law in laws() {
            let nf = law.nodal(&obst, &motion, &x, &xdot, rn).unwrap();
            let force =
                |x: &Vec3, xd: &Vec3, rn: f64| law.nodal(&obst, &motion, x, xd, rn).unwrap().force;
            for j in 0..3 {
                let mut e = Vec3::zeros();
                e[j] = h;
                let fx = (force(&(x + e), &xdot, rn) - force(&(x - e), &xdot, rn)) / (2.0 * h);
                let fv = (force(&x, &(xdot + e), rn) - force(&x, &(xdot - e), rn)) / (2.0 * h);
                for i in 0..3 {
                    assert!(
                        close(nf.d_x[(i, j)], fx[i], 1e-7),
                        "{obst:?} {motion:?} {law:?} d_x[{i}][{j}] {} vs {}",
                        nf.d_x[(i, j)],
                        fx[i]
                    );
                    assert!(
                        close(nf.d_xdot[(i, j)], fv[i], 1e-7),
                        "{obst:?} {motion:?} {law:?} d_xdot[{i}][{j}] {} vs {}",
                        nf.d_xdot[(i, j)],
                        fv[i]
                    );
                }
            }
            let fn_ = (force(&x, &xdot, rn + h) - force(&x, &xdot, rn - h)) / (2.0 * h);
            assert!((nf.d_rn - fn_).norm() <= 1e-7 * (1.0 + fn_.norm()));
            // The friction force lies in the tangent plane.
            let n = obst.gap(&x).unwrap().n;
            assert!(nf.force.dot(&n).abs() <= 1e-15 * (1.0 + nf.force.norm()));
        }
    }
}

#[test]
fn series_along_a_path_match_direct_evaluation_and_jacobian() {
    // Along x(a), ẋ(a), R_N(a) polynomial (a = t − t0), the recorded
    // R_T(x, ẋ, R_N) summed at a equals the direct law; the tape Jacobian at
    // a = 0 equals the analytic derivatives.
    let n_ord = 25;
    let x_s = [
        Vec3::new(0.45, 0.1, 0.35),
        Vec3::new(0.1, -0.2, 0.05),
        Vec3::new(-0.05, 0.02, 0.1),
    ];
    let v_s = [Vec3::new(0.2, -0.4, 0.3), Vec3::new(0.3, 0.1, -0.2)];
    let rn_s = [0.8, -0.3, 0.1];
    let at = |c: &[Vec3], a: f64| c.iter().rev().fold(Vec3::zeros(), |acc, ci| acc * a + ci);
    for (obst, motion) in cases() {
        for law in laws() {
            let b = TapeBuilder::new();
            let x: [_; 3] = std::array::from_fn(|_| b.input());
            let xd: [_; 3] = std::array::from_fn(|_| b.input());
            let rn = b.input();
            let vs = record_slip(&b, &obst, &motion, x, xd);
            let rt = law.record_vec(rn, vs);
            let mut tape = b.finish(&rt, n_ord);
            for p in 0..=n_ord {
                for k in 0..3 {
                    tape.set_input(k, p, x_s.get(p).map_or(0.0, |c| c[k]));
                    tape.set_input(3 + k, p, v_s.get(p).map_or(0.0, |c| c[k]));
                }
                tape.set_input(6, p, *rn_s.get(p).unwrap_or(&0.0));
                tape.propagate(p);
            }
            for a in [0.05, 0.15] {
                let want = law
                    .nodal(
                        &obst,
                        &motion,
                        &at(&x_s, a),
                        &at(&v_s, a),
                        taylor::eval(&rn_s, a),
                    )
                    .unwrap()
                    .force;
                for i in 0..3 {
                    let got = taylor::eval(tape.output_series(i), a);
                    assert!(
                        (got - want[i]).abs() <= 1e-12 * (1.0 + want.norm()),
                        "{obst:?} {motion:?} {law:?} a = {a}: {got} vs {}",
                        want[i]
                    );
                }
            }
            let jac = tape.jacobian(&[0, 1, 2, 3, 4, 5, 6]);
            let nf = law
                .nodal(&obst, &motion, &x_s[0], &v_s[0], rn_s[0])
                .unwrap();
            for (i, row) in jac.iter().enumerate() {
                for j in 0..3 {
                    assert!(close(row[j], nf.d_x[(i, j)], 1e-12));
                    assert!(close(row[3 + j], nf.d_xdot[(i, j)], 1e-12));
                }
                assert!(close(row[6], nf.d_rn[i], 1e-12));
            }
        }
    }
}

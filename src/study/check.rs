//! An independent check of a friction run's output: the physical equations of
//! the paper (§3.2 eq. 7; §3.3 eqs. 10a–d; §3.4 equilibrium in Cartesian
//! components) evaluated in plain f64 on every row of history.csv. It shares
//! nothing with the DAE models but the law functions, so it catches an error
//! in the models' formulation (e.g. the roller's polar coordinates).

use crate::scene::Kind;
use crate::scene::friction::{FrictionScene, Obstacle};

/// Largest normwise relative residual over all rows and equations: force
/// equations (equilibrium, friction) divided by the run's force scale S (the
/// largest |R_N|, |R_T|, k|u|, F t, f R_N seen), the contact law (N·m)
/// divided by S delta. The friction law is measured by its backward error: its
/// residual divided by max(S, |dR_T/dv_s| Vc), i.e. the output satisfies the
/// law exactly for a force within tol S or a slip velocity within tol Vc of
/// the reported one (the law is steep near zero slip when omega is small).
pub fn max_relative_residual(scene: &FrictionScene, columns: &[String], rows: &[Vec<f64>]) -> f64 {
    let col = |name: &str| columns.iter().position(|c| c == name);
    let force_scale = rows
        .iter()
        .flat_map(|r| {
            ["rn", "rt", "u", "ux", "uy"]
                .iter()
                .filter_map(|c| col(c).map(|j| (c, j)))
                .map(|(c, j)| {
                    if c.starts_with('u') {
                        scene.k * r[j].abs()
                    } else {
                        r[j].abs()
                    }
                })
                .collect::<Vec<_>>()
        })
        .fold(
            scene.friction.f * scene.normal_force.max(scene.load_rate * scene.t_end),
            f64::max,
        )
        .max(f64::MIN_POSITIVE);
    let rel = |terms: &[f64]| terms.iter().sum::<f64>().abs() / force_scale;
    let delta = scene.contact.map(|c| c.delta).unwrap_or(1.0);
    let rel_contact = |terms: &[f64]| terms.iter().sum::<f64>().abs() / (force_scale * delta);
    let law = scene.friction;
    let rel_friction = |rt: f64, rn: f64, slip: f64| {
        let scale = force_scale.max(law.d_force_d_slip(rn, slip).abs() * law.vc);
        (rt - law.force(rn, slip)).abs() / scale
    };
    let k = scene.k;
    let mut worst: f64 = 0.0;
    for r in rows {
        if r.iter().any(|x| !x.is_finite()) {
            return f64::INFINITY;
        }
        let t = r[0];
        let e = match (scene.kind, scene.obstacle) {
            (Kind::Friction1d, Obstacle::Plane { v }) => {
                let (u, vel) = (r[1], r[2]);
                vec![rel_friction(k * u, scene.normal_force, vel - v)]
            }
            (Kind::FrictionPlane, Obstacle::Plane { v }) => {
                let c = scene.contact.expect("plane scenes have a contact law");
                let (ux, uy, vx, rn, rt) = (r[1], r[2], r[3], r[5], r[6]);
                let h = c.delta + uy;
                vec![
                    rel(&[-k * ux, rt]),
                    rel(&[-k * uy, rn, -scene.load_rate * t]),
                    rel_contact(&[rn * rn / c.k, rn * h, -c.eta * (c.delta - h)]),
                    rel_friction(rt, rn, vx - v),
                ]
            }
            (
                Kind::FrictionRoller,
                Obstacle::Roller {
                    r: rad,
                    omega: spin,
                },
            ) => {
                let c = scene.contact.expect("roller scenes have a contact law");
                let (ux, uy, vx, vy, rn, rt) = (r[1], r[2], r[3], r[4], r[5], r[6]);
                // n = (x - C)/|x - C|, C = (0, -(delta + r)); t = n turned by -90°.
                let (dx, dy) = (ux, uy + c.delta + rad);
                let dist = (dx * dx + dy * dy).sqrt();
                let (nx, ny) = (dx / dist, dy / dist);
                let (tx, ty) = (ny, -nx);
                let h = dist - rad;
                let slip = vx * tx + vy * ty + spin * rad;
                vec![
                    rel(&[-k * ux, rn * nx, rt * tx]),
                    rel(&[-k * uy, rn * ny, rt * ty, -scene.load_rate * t]),
                    rel_contact(&[rn * rn / c.k, rn * h, -c.eta * (c.delta - h)]),
                    rel_friction(rt, rn, slip),
                ]
            }
            _ => unreachable!("validated scenes pair kinds and obstacles"),
        };
        worst = e.into_iter().fold(worst, f64::max);
    }
    worst
}

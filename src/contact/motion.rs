//! Rigid motion of an obstacle (DESIGN §7).
//!
//! The motion is parametrized by the path parameter s: the load parameter
//! lambda on a static path, the time t on a path in time.
//! - fixed: the obstacle stays where the scene puts it;
//! - translation with velocity V: every point of the obstacle moves by s V,
//!   so the gap of a point x at s is the gap of x − s V against the obstacle
//!   at s = 0 (the shape is rigid);
//! - rotation about the obstacle's own axis with angular velocity Omega: a
//!   plane or a cylinder turning about its axis keeps its shape and place;
//!   only its surface velocity Omega e × (p − c) changes, which friction
//!   reads (DESIGN §7).

use super::obstacle::{Obstacle, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    Fixed,
    /// Displacement per unit of the path parameter (m per unit lambda, or m/s).
    Translate {
        velocity: Vec3,
    },
    /// Angular velocity about the obstacle's axis (rad per unit lambda, or rad/s).
    Rotate {
        omega: f64,
    },
}

impl Motion {
    /// Displacement of the obstacle at path parameter s.
    pub fn shift(&self, s: f64) -> Vec3 {
        match self {
            Motion::Translate { velocity } => velocity * s,
            Motion::Fixed | Motion::Rotate { .. } => Vec3::zeros(),
        }
    }

    /// d(shift)/ds: the obstacle's translation velocity.
    pub fn velocity(&self) -> Vec3 {
        match self {
            Motion::Translate { velocity } => *velocity,
            Motion::Fixed | Motion::Rotate { .. } => Vec3::zeros(),
        }
    }

    /// Velocity of the obstacle's surface at point p (translation, or
    /// Omega e × (p − c) for a cylinder turning about its axis e through c).
    pub fn surface_velocity(&self, obstacle: &Obstacle, p: &Vec3) -> Vec3 {
        match (self, obstacle) {
            (Motion::Rotate { omega }, Obstacle::Cylinder { centre, axis, .. }) => {
                axis.cross(&(p - centre)) * *omega
            }
            (Motion::Rotate { omega }, Obstacle::Plane { point, normal }) => {
                normal.cross(&(p - point)) * *omega
            }
            _ => self.velocity(),
        }
    }
}

impl Obstacle {
    /// The obstacle moved rigidly by d.
    pub fn translated(&self, d: Vec3) -> Obstacle {
        match self {
            Obstacle::Plane { point, normal } => Obstacle::Plane {
                point: point + d,
                normal: *normal,
            },
            Obstacle::Cylinder {
                centre,
                axis,
                radius,
                crown,
            } => Obstacle::Cylinder {
                centre: centre + d,
                axis: *axis,
                radius: *radius,
                crown: *crown,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_translated_obstacle_sees_the_point_moved_back() {
        let cyl = Obstacle::cylinder(Vec3::new(1.0, 0.0, 0.5), Vec3::y(), 0.5).unwrap();
        let m = Motion::Translate {
            velocity: Vec3::new(0.0, 0.0, -0.1),
        };
        let x = Vec3::new(1.2, 0.3, -0.05);
        let s = 0.7;
        let g1 = cyl.translated(m.shift(s)).gap(&x).unwrap();
        let g2 = cyl.gap(&(x - m.shift(s))).unwrap();
        assert!((g1.h - g2.h).abs() < 1e-15 && (g1.n - g2.n).norm() < 1e-15);
    }

    #[test]
    fn a_turning_cylinder_moves_its_surface_tangentially() {
        let cyl = Obstacle::cylinder(Vec3::zeros(), Vec3::z(), 1.0).unwrap();
        let v = Motion::Rotate { omega: 2.0 }.surface_velocity(&cyl, &Vec3::new(1.0, 0.0, 0.3));
        assert!((v - Vec3::new(0.0, 2.0, 0.0)).norm() < 1e-15);
    }
}

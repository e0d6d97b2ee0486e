//! Rigid analytic obstacles: gap h and outward normal n of a point x.
//!
//! - plane through p with unit normal n: h = (x − p)·n, n constant;
//! - cylinder of centre c, unit axis a, radius r: with P = I − a aᵀ and
//!   y = P (x − c), d = |y|, h = d − r, n = y / d, dn/dx = (P − n nᵀ) / d;
//! - crowned cylinder (a roll whose radius falls parabolically from r at
//!   the centre's section, the industrial roll crown): with s = a·(x − c)
//!   the radius is r(s) = r − κ s², and the gap h = d − r(s) =
//!   d − r + κ s². Its gradient n = y / d + 2 κ s a is the direction of
//!   the reaction (R n is the derivative of the contact energy Φ(h(x))),
//!   dn/dx = (P − n_c n_cᵀ) / d + 2 κ a aᵀ with n_c = y / d. h is the
//!   distance to the surface to first order in the slope r' = −2 κ s:
//!   |n| = √(1 + r'²), 1 + 2e-6 for a 0.5 mm crown over a 1 m face.
//!
//! n points from the obstacle toward the point; the reaction R of eq. (3)
//! acts on the point as R n. The gap is written as a function of x only;
//! a moving or rotating obstacle (next issues) enters through the map
//! x ↦ (c(t), a(t)) or (p(t), n(t)), which this layout keeps separate.
//!
//! Along an ANM series x(a) = Σ x_p a^p the gap of a cylinder is not
//! polynomial; [`GapSeries`] propagates d² = y·y, d = sqrt(d²) and n = y / d
//! coefficient by coefficient (crate::series::taylor), O(p) per order.

// Node/dof/component loops read better with explicit indices.
#![allow(clippy::needless_range_loop)]

use crate::fe::prefetch::prefetch_growing;
use crate::series::taylor::{div_coeff, sqrt_coeff};
use nalgebra::{Matrix3, Vector3};

pub type Vec3 = Vector3<f64>;

#[derive(Clone, Debug, PartialEq)]
pub enum Obstacle {
    Plane {
        point: Vec3,
        normal: Vec3,
    },
    Cylinder {
        centre: Vec3,
        axis: Vec3,
        /// At the centre's section (s = 0).
        radius: f64,
        /// κ of r(s) = radius − κ s² (1/m); 0 for a straight cylinder.
        crown: f64,
    },
}

/// Gap, normal and normal derivative at a point.
#[derive(Clone, Copy, Debug)]
pub struct Gap {
    pub h: f64,
    pub n: Vec3,
    /// dn/dx.
    pub dn: Matrix3<f64>,
}

impl Obstacle {
    /// A plane; `normal` is normalized. None if it is zero.
    pub fn plane(point: Vec3, normal: Vec3) -> Option<Self> {
        let n = normal.try_normalize(0.0)?;
        Some(Obstacle::Plane { point, normal: n })
    }

    /// A cylinder; `axis` is normalized. None if it is zero or radius <= 0.
    pub fn cylinder(centre: Vec3, axis: Vec3, radius: f64) -> Option<Self> {
        let a = axis.try_normalize(0.0)?;
        (radius > 0.0 && radius.is_finite()).then_some(Obstacle::Cylinder {
            centre,
            axis: a,
            radius,
            crown: 0.0,
        })
    }

    /// A cylinder whose radius falls by `crown` from the centre's section
    /// to the ends of a face of length `face` centred there:
    /// r(s) = radius − crown (2 s / face)². None as for [`Self::cylinder`]
    /// or if the crown is negative, not below the radius, or the face is
    /// not positive.
    pub fn crowned_cylinder(
        centre: Vec3,
        axis: Vec3,
        radius: f64,
        crown: f64,
        face: f64,
    ) -> Option<Self> {
        let ok = crown >= 0.0 && crown < radius && face > 0.0 && face.is_finite();
        match Self::cylinder(centre, axis, radius)? {
            Obstacle::Cylinder {
                centre,
                axis,
                radius,
                ..
            } if ok => Some(Obstacle::Cylinder {
                centre,
                axis,
                radius,
                crown: 4.0 * crown / (face * face),
            }),
            _ => None,
        }
    }

    /// The gap h of [`Obstacle::gap`] alone (its value bit for bit, without
    /// the normal and its derivative): the kink search reads it dozens of
    /// times per step for every contact pair.
    pub fn distance(&self, x: &Vec3) -> Option<f64> {
        match self {
            Obstacle::Plane { point, normal } => Some((x - point).dot(normal)),
            Obstacle::Cylinder {
                centre,
                axis,
                radius,
                crown,
            } => {
                let (_, _, d, s) = axis_frame(x, centre, axis, *radius)?;
                Some(d - radius + crown * s * s)
            }
        }
    }

    /// Gap and normal at x. None where the normal is undefined (a point on
    /// the cylinder axis).
    pub fn gap(&self, x: &Vec3) -> Option<Gap> {
        match self {
            Obstacle::Plane { point, normal } => Some(Gap {
                h: (x - point).dot(normal),
                n: *normal,
                dn: Matrix3::zeros(),
            }),
            Obstacle::Cylinder {
                centre,
                axis,
                radius,
                crown,
            } => {
                let (p, y, d, s) = axis_frame(x, centre, axis, *radius)?;
                let nc = y / d;
                Some(Gap {
                    h: d - radius + crown * s * s,
                    n: nc + axis * (2.0 * crown * s),
                    dn: (p - nc * nc.transpose()) / d + axis * axis.transpose() * (2.0 * crown),
                })
            }
        }
    }
}

/// A point x about a cylinder's axis: the projector P = I − a aᵀ, y = P (x
/// − c), its distance d = |y| to the axis and its abscissa s = a·(x − c);
/// None on the axis (d ≤ 1e-12 r), where the normal is undefined.
fn axis_frame(
    x: &Vec3,
    centre: &Vec3,
    axis: &Vec3,
    radius: f64,
) -> Option<(Matrix3<f64>, Vec3, f64, f64)> {
    let p = Matrix3::identity() - axis * axis.transpose();
    let y = p * (x - centre);
    let d = y.norm();
    if d <= 1e-12 * radius {
        return None;
    }
    Some((p, y, d, axis.dot(&(x - centre))))
}

/// Series of the gap and normal of one point along an ANM step.
#[derive(Clone, Debug)]
pub struct GapSeries {
    obstacle_kind: Kind,
    /// Components of y_r (cylinder: P x_r shifted; plane: x_r), one series
    /// per component as the Taylor rules take them.
    y: [Vec<f64>; 3],
    d2: Vec<f64>,
    d: Vec<f64>,
    /// y / d (the straight cylinder's normal; the crown adds 2 κ s a).
    n: [Vec<f64>; 3],
    /// s = a·(x − c) (crowned cylinder; zeros otherwise).
    s: Vec<f64>,
    /// h_r.
    pub h: Vec<f64>,
}

#[derive(Clone, Debug)]
enum Kind {
    Plane(Vec3, Vec3),
    /// P, c, a, κ.
    Cylinder(Matrix3<f64>, Vec3, Vec3, f64),
}

impl GapSeries {
    /// Order 0 at position x0. None where the gap is undefined.
    pub fn start(obstacle: &Obstacle, x0: &Vec3) -> Option<Self> {
        let mut series = Self {
            obstacle_kind: Kind::Plane(Vec3::zeros(), Vec3::zeros()),
            y: Default::default(),
            d2: vec![],
            d: vec![],
            n: Default::default(),
            s: vec![],
            h: vec![],
        };
        series.restart(obstacle, x0)?;
        Some(series)
    }

    /// [`GapSeries::start`] in the buffers of an earlier series (no
    /// allocation once they hold the orders of a step). None where the gap
    /// is undefined (the series is then left unchanged).
    pub fn restart(&mut self, obstacle: &Obstacle, x0: &Vec3) -> Option<()> {
        let g = obstacle.gap(x0)?;
        let kind = match obstacle {
            Obstacle::Plane { point, normal } => Kind::Plane(*point, *normal),
            Obstacle::Cylinder {
                centre,
                axis,
                crown,
                ..
            } => Kind::Cylinder(
                Matrix3::identity() - axis * axis.transpose(),
                *centre,
                *axis,
                *crown,
            ),
        };
        let (y0, s0) = match &kind {
            Kind::Plane(p, _) => (x0 - p, 0.0),
            Kind::Cylinder(pm, c, a, _) => (pm * (x0 - c), a.dot(&(x0 - c))),
        };
        let d = y0.norm();
        let nc = match &kind {
            Kind::Plane(_, nrm) => *nrm,
            Kind::Cylinder(..) => y0 / d,
        };
        self.obstacle_kind = kind;
        let first = |list: &mut Vec<f64>, v: f64| {
            list.clear();
            list.push(v);
        };
        for k in 0..3 {
            first(&mut self.y[k], y0[k]);
            first(&mut self.n[k], nc[k]);
        }
        first(&mut self.d2, d * d);
        first(&mut self.d, d);
        first(&mut self.s, s0);
        first(&mut self.h, g.h);
        Some(())
    }

    pub fn orders(&self) -> usize {
        self.h.len()
    }

    /// Room for `orders` orders in every coefficient list, so that
    /// completing them allocates nothing.
    pub fn reserve(&mut self, orders: usize) {
        let more = orders.saturating_sub(self.orders());
        for list in self.y.iter_mut().chain(self.n.iter_mut()) {
            list.reserve(more);
        }
        for list in [&mut self.d2, &mut self.d, &mut self.s, &mut self.h] {
            list.reserve(more);
        }
    }

    fn push_y(&mut self, y: &Vec3) {
        for k in 0..3 {
            self.y[k].push(y[k]);
        }
    }

    /// Order-p coefficients (h_p, n_p) given x_p; pushes them if `keep`.
    fn order(&mut self, xp: &Vec3, keep: bool) -> (f64, Vec3) {
        let p = self.orders();
        match self.obstacle_kind.clone() {
            Kind::Plane(_, nrm) => {
                let hp = xp.dot(&nrm);
                if keep {
                    self.push_y(xp);
                    self.d2.push(0.0);
                    self.d.push(0.0);
                    for k in 0..3 {
                        self.n[k].push(0.0);
                    }
                    self.s.push(0.0);
                    self.h.push(hp);
                }
                (hp, Vec3::zeros())
            }
            Kind::Cylinder(pm, _, a, kappa) => {
                self.push_y(&(pm * xp));
                self.s.push(a.dot(xp));
                // (κ s²)_p by the Cauchy product.
                let crown_p = kappa * (0..=p).map(|r| self.s[r] * self.s[p - r]).sum::<f64>();
                let d2p: f64 = (0..=p)
                    .map(|r| (0..3).map(|k| self.y[k][r] * self.y[k][p - r]).sum::<f64>())
                    .sum();
                self.d2.push(d2p);
                let dp = sqrt_coeff(&self.d2, &self.d, p);
                self.d.push(dp);
                let mut np = Vec3::zeros();
                for k in 0..3 {
                    np[k] = div_coeff(&self.y[k], &self.d, &self.n[k], p);
                }
                let full_np = np + a * (2.0 * kappa * self.s[p]);
                let hp = dp + crown_p;
                if keep {
                    for k in 0..3 {
                        self.n[k].push(np[k]);
                    }
                    self.h.push(hp);
                } else {
                    for k in 0..3 {
                        self.y[k].pop();
                    }
                    self.d2.pop();
                    self.d.pop();
                    self.s.pop();
                }
                (hp, full_np)
            }
        }
    }

    /// Completes order p = orders() from the point's order-p increment.
    pub fn complete(&mut self, xp: &Vec3) -> (f64, Vec3) {
        self.order(xp, true)
    }

    /// Prefetches every coefficient list (fe::prefetch): a pair's series
    /// are small blocks scattered over the heap, each a cache miss.
    pub fn prefetch(&self) {
        for list in self.y.iter().chain(&self.n) {
            prefetch_growing(list);
        }
        for list in [&self.d2, &self.d, &self.s, &self.h] {
            prefetch_growing(list);
        }
    }

    /// Order p = orders() with x_p = 0 (not stored).
    pub fn starred(&mut self) -> (f64, Vec3) {
        self.order(&Vec3::zeros(), false)
    }

    /// n_r.
    pub fn normal(&self, r: usize) -> Vec3 {
        let nc = Vec3::new(self.n[0][r], self.n[1][r], self.n[2][r]);
        match &self.obstacle_kind {
            Kind::Cylinder(_, _, a, kappa) => nc + a * (2.0 * kappa * self.s[r]),
            Kind::Plane(..) => nc,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylinder_gap_normal_and_series_match_direct_evaluation() {
        let cyl =
            Obstacle::cylinder(Vec3::new(1.0, 0.0, 0.5001), Vec3::new(0.0, 2.0, 0.0), 0.5).unwrap();
        let g = cyl.gap(&Vec3::new(1.0, 0.3, 0.0)).unwrap();
        assert!((g.h - 1e-4).abs() < 1e-15 && (g.n - Vec3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
        gap_derivatives_and_series_agree(&cyl);
    }

    #[test]
    fn crowned_cylinder_gap_normal_and_series_match_direct_evaluation() {
        // Radius 0.5 at the centre's section y = 0, 0.45 at y = ±0.5.
        let roll = Obstacle::crowned_cylinder(
            Vec3::new(1.0, 0.0, 0.5001),
            Vec3::new(0.0, 2.0, 0.0),
            0.5,
            0.05,
            1.0,
        )
        .unwrap();
        // Under the roll at y = 0.5: 0.5001 from the axis, radius 0.45 there.
        let g = roll.gap(&Vec3::new(1.0, 0.5, 0.0)).unwrap();
        assert!((g.h - 0.0501).abs() < 1e-15, "{}", g.h);
        // n = gradient of h: −e_z + 2 κ s a with κ = 0.2, s = 0.5.
        assert!((g.n - Vec3::new(0.0, 0.2, -1.0)).norm() < 1e-15);
        // h by central differences of the gap itself.
        let x = Vec3::new(1.3, 0.1, 0.2);
        for j in 0..3 {
            let mut e = Vec3::zeros();
            e[j] = 1e-6;
            let fd = (roll.gap(&(x + e)).unwrap().h - roll.gap(&(x - e)).unwrap().h) / 2e-6;
            assert!((fd - roll.gap(&x).unwrap().n[j]).abs() < 1e-9);
        }
        gap_derivatives_and_series_agree(&roll);
        assert!(Obstacle::crowned_cylinder(Vec3::zeros(), Vec3::x(), 0.5, 0.6, 1.0).is_none());
        assert!(Obstacle::crowned_cylinder(Vec3::zeros(), Vec3::x(), 0.5, -0.1, 1.0).is_none());
        assert!(Obstacle::crowned_cylinder(Vec3::zeros(), Vec3::x(), 0.5, 0.1, 0.0).is_none());
    }

    /// dn/dx against central differences of n, and the gap's series along a
    /// quadratic x(a) against the gap evaluated at x(a); `distance` is the
    /// gap's h bit for bit.
    fn gap_derivatives_and_series_agree(cyl: &Obstacle) {
        let x = Vec3::new(1.3, 0.1, 0.2);
        let g = cyl.gap(&x).unwrap();
        for y in [x, Vec3::new(1.0, 0.5, 0.0), Vec3::new(-0.7, 3.0, 0.9)] {
            assert_eq!(
                cyl.distance(&y).map(f64::to_bits),
                cyl.gap(&y).map(|g| g.h.to_bits())
            );
        }
        for j in 0..3 {
            let mut e = Vec3::zeros();
            e[j] = 1e-6;
            let fd = (cyl.gap(&(x + e)).unwrap().n - cyl.gap(&(x - e)).unwrap().n) / 2e-6;
            assert!((fd - g.dn.column(j)).norm() < 1e-8);
        }
        // Series along x(a) = x0 + x1 a + x2 a^2.
        let xs = [x, Vec3::new(0.3, -0.2, 0.5), Vec3::new(-0.1, 0.4, 0.2)];
        let mut s = GapSeries::start(cyl, &xs[0]).unwrap();
        for p in 1..=20 {
            let xp = if p < 3 { xs[p] } else { Vec3::zeros() };
            let (hs, ns) = s.clone().starred();
            let (h, n) = s.complete(&xp);
            if p >= 3 {
                assert_eq!((hs, ns), (h, n));
            }
        }
        let a: f64 = 0.1;
        let xa = xs[0] + xs[1] * a + xs[2] * a * a;
        let ga = cyl.gap(&xa).unwrap();
        let h: f64 = s.h.iter().rev().fold(0.0, |acc, c| acc * a + c);
        let n: Vec3 = (0..s.orders())
            .rev()
            .fold(Vec3::zeros(), |acc, r| acc * a + s.normal(r));
        assert!((h - ga.h).abs() < 1e-13, "{h} vs {}", ga.h);
        assert!((n - ga.n).norm() < 1e-13);
    }
}

//! The assembled shell problem R(U, λ) = 0 that the ANM engine continues:
//!
//!   R = f_int(U) − λ F − λ Σ_c m_c × a3_c(U) − Σ_k R_k(h_k(U)) n_k(U),
//!
//! with f_int the condensed element forces, F the dead nodal loads (on v, or
//! on w for a dead through-thickness couple), m × a3 the follower couples and
//! R_k n_k the contact reactions of the active pairs (paper eqs. 2–3).
//!
//! A couple of moment m at a node is applied as a force pair ±f at the fibre
//! points x̄ ± h a3: its virtual work f·(δv + h δw) − f·(δv − h δw) = 2h f·δw
//! is a force F_w = 2h f on the director unknowns, of moment a3 × F_w. The
//! follower couple F_w = λ (m × a3) has moment a3 × (m × a3) = m |a3|² for
//! m ⟂ a3 (|a3|² = 1 + 2 E⁰_33) and is bilinear in (λ, w): it stays
//! polynomial, its series term is −Σ_{r=1}^{p−1} λ_r m × w_{p−r}.
//!
//! Series (order p ≥ 2, U_p = λ_p = 0): element convolutions
//! in nodal Gram form (see [`super::series`]), the follower term above, and per contact pair
//! the Taylor propagation of h, n (obstacle::GapSeries) and R (eq. 3,
//! NormalLaw::force_coeff), force coefficient Σ_{r=0}^{p} R_r n_{p−r}.

// Node/dof/component loops read better with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::element::ShellElement;
use super::kinematics::Vec3;
use super::material::Material;
use super::series::ElementSeries;
use crate::contact::obstacle::{GapSeries, Obstacle};
use crate::contact::search::{self, ContactPair};
use crate::error::{Error, Result};
use crate::linalg::SparseMatrix;
use crate::series::ContinuationProblem;

/// A follower couple at a node: director force λ (moment × a3).
#[derive(Clone, Debug)]
pub struct FollowerCouple {
    pub node: usize,
    pub moment: Vec3,
}

/// Contact reaction of one active pair at a state.
#[derive(Clone, Debug)]
pub struct NodalContact {
    pub node: usize,
    pub obstacle: usize,
    pub gap: f64,
    /// Normal reaction R (positive when pushed by the obstacle).
    pub r: f64,
    pub normal: Vec3,
}

struct PairSeries {
    pair: usize,
    gap: GapSeries,
    r: Vec<f64>,
}

pub struct ShellModel {
    pub x0: Vec<Vec3>,
    pub a30: Vec<Vec3>,
    pub elements: Vec<ShellElement>,
    /// Full dof (6 node + k, k = 0..3 v, 3..6 w) to free-dof index.
    pub free: Vec<Option<usize>>,
    ndof: usize,
    /// Dead load pattern F on the full dofs.
    pub dead: Vec<f64>,
    pub follower: Vec<FollowerCouple>,
    pub obstacles: Vec<Obstacle>,
    pub pairs: Vec<ContactPair>,
    pub search_distance: f64,
    active: Vec<usize>,
    // Series state of the current step.
    series_u0: Vec<f64>,
    el_series: Vec<ElementSeries>,
    pair_series: Vec<PairSeries>,
}

impl ShellModel {
    /// Elements from quads (node indices), reference positions and unit
    /// directors. Element errors carry the element index.
    pub fn new(
        x0: Vec<Vec3>,
        a30: Vec<Vec3>,
        quads: &[[usize; 4]],
        thickness: f64,
        material: Material,
    ) -> Result<Self> {
        let mut elements = Vec::with_capacity(quads.len());
        for (id, q) in quads.iter().enumerate() {
            let x: [Vec3; 4] = std::array::from_fn(|i| x0[q[i]]);
            let d: [Vec3; 4] = std::array::from_fn(|i| a30[q[i]]);
            elements.push(ShellElement::new(id, *q, &x, &d, thickness, &material)?);
        }
        let n = x0.len();
        let mut m = Self {
            x0,
            a30,
            elements,
            free: vec![None; 6 * n],
            ndof: 0,
            dead: vec![0.0; 6 * n],
            follower: vec![],
            obstacles: vec![],
            pairs: vec![],
            search_distance: f64::INFINITY,
            active: vec![],
            series_u0: vec![],
            el_series: vec![],
            pair_series: vec![],
        };
        m.set_constraints(&[]);
        Ok(m)
    }

    /// Fixes the listed (node, component) dofs to zero, all others free.
    pub fn set_constraints(&mut self, fixed: &[(usize, usize)]) {
        let mut is_fixed = vec![false; self.free.len()];
        for &(node, k) in fixed {
            is_fixed[6 * node + k] = true;
        }
        let mut next = 0;
        for (i, f) in self.free.iter_mut().enumerate() {
            *f = if is_fixed[i] {
                None
            } else {
                next += 1;
                Some(next - 1)
            };
        }
        self.ndof = next;
    }

    /// Adds obstacles and the contact pairs of `nodes`, delta = initial gap.
    pub fn set_contact(
        &mut self,
        obstacles: Vec<Obstacle>,
        nodes: &[usize],
        k: f64,
        eta: f64,
        distance: f64,
    ) -> std::result::Result<(), (usize, usize, f64)> {
        self.pairs = search::pairs(nodes, &self.x0, &obstacles, k, eta)?;
        self.obstacles = obstacles;
        self.search_distance = distance;
        self.active = search::active(&self.pairs, &self.x0, &self.obstacles, distance);
        Ok(())
    }

    pub fn n_nodes(&self) -> usize {
        self.x0.len()
    }

    /// Free-dof vector to full vector (zeros at fixed dofs).
    pub fn expand(&self, u: &[f64]) -> Vec<f64> {
        self.free.iter().map(|f| f.map_or(0.0, |i| u[i])).collect()
    }

    fn reduce(&self, full: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.ndof];
        for (f, v) in self.free.iter().zip(full) {
            if let Some(i) = f {
                out[*i] = *v;
            }
        }
        out
    }

    /// Current mid-surface positions from a full vector.
    pub fn positions(&self, full: &[f64]) -> Vec<Vec3> {
        (0..self.n_nodes())
            .map(|i| self.x0[i] + Vec3::new(full[6 * i], full[6 * i + 1], full[6 * i + 2]))
            .collect()
    }

    /// Current directors from a full vector.
    pub fn directors(&self, full: &[f64]) -> Vec<Vec3> {
        (0..self.n_nodes())
            .map(|i| self.a30[i] + Vec3::new(full[6 * i + 3], full[6 * i + 4], full[6 * i + 5]))
            .collect()
    }

    fn element_state(&self, e: &ShellElement, full: &[f64], incr: bool) -> ([Vec3; 4], [Vec3; 4]) {
        let x = std::array::from_fn(|i| {
            let n = e.nodes[i];
            let v = Vec3::new(full[6 * n], full[6 * n + 1], full[6 * n + 2]);
            if incr { v } else { self.x0[n] + v }
        });
        let d = std::array::from_fn(|i| {
            let n = e.nodes[i];
            let w = Vec3::new(full[6 * n + 3], full[6 * n + 4], full[6 * n + 5]);
            if incr { w } else { self.a30[n] + w }
        });
        (x, d)
    }

    fn vec3(full: &[f64], node: usize, off: usize) -> Vec3 {
        Vec3::new(
            full[6 * node + off],
            full[6 * node + off + 1],
            full[6 * node + off + 2],
        )
    }

    /// Contact reactions of the active pairs at the full state.
    pub fn contact_forces(&self, full: &[f64], lambda: f64) -> Result<Vec<NodalContact>> {
        let mut out = Vec::with_capacity(self.active.len());
        for &ip in &self.active {
            let pair = &self.pairs[ip];
            let x = self.x0[pair.node] + Self::vec3(full, pair.node, 0);
            let g = self.obstacles[pair.obstacle]
                .gap(&x)
                .ok_or_else(|| self.gap_error(pair.node, lambda))?;
            out.push(NodalContact {
                node: pair.node,
                obstacle: pair.obstacle,
                gap: g.h,
                r: pair.law.force(g.h),
                normal: g.n,
            });
        }
        Ok(out)
    }

    fn gap_error(&self, node: usize, lambda: f64) -> Error {
        Error::NonFinite {
            step: 0,
            param: "lambda",
            at: lambda,
            what: format!("contact gap of node {node} (on the obstacle axis)"),
        }
    }

    /// Full residual vector (all dofs, before removing the fixed ones).
    pub fn residual_full(&self, full: &[f64], lambda: f64) -> Result<Vec<f64>> {
        let mut r = vec![0.0; full.len()];
        for e in &self.elements {
            let (x, d) = self.element_state(e, full, false);
            let f = e.internal(&x, &d);
            for (i, &n) in e.nodes.iter().enumerate() {
                for k in 0..6 {
                    r[6 * n + k] += f[6 * i + k];
                }
            }
        }
        for (ri, fi) in r.iter_mut().zip(&self.dead) {
            *ri -= lambda * fi;
        }
        for c in &self.follower {
            let a3 = self.a30[c.node] + Self::vec3(full, c.node, 3);
            let fw = c.moment.cross(&a3) * lambda;
            for k in 0..3 {
                r[6 * c.node + 3 + k] -= fw[k];
            }
        }
        for c in self.contact_forces(full, lambda)? {
            for k in 0..3 {
                r[6 * c.node + k] -= c.r * c.normal[k];
            }
        }
        Ok(r)
    }

    fn check_finite(v: &[f64], lambda: f64, what: &str) -> Result<()> {
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                step: 0,
                param: "lambda",
                at: lambda,
                what: format!("{what} (entry {i}: node {}, dof {})", i / 6, i % 6),
            });
        }
        Ok(())
    }

    /// Refreshes the active contact set at the full state.
    pub fn update_active(&mut self, full: &[f64]) {
        let x = self.positions(full);
        self.active = search::active(&self.pairs, &x, &self.obstacles, self.search_distance);
    }

    /// The active set is frozen during a step: a candidate left out at the
    /// step start must not come within half the search distance of its
    /// obstacle before the next refresh, or its contact term would be
    /// missing (error, with the advice to enlarge the search distance).
    fn check_inactive(&self, full: &[f64], lambda: f64) -> Result<()> {
        if self.pairs.len() == self.active.len() {
            return Ok(());
        }
        let mut is_active = vec![false; self.pairs.len()];
        for &i in &self.active {
            is_active[i] = true;
        }
        for (i, p) in self.pairs.iter().enumerate() {
            if is_active[i] {
                continue;
            }
            let x = self.x0[p.node] + Self::vec3(full, p.node, 0);
            if let Some(g) = self.obstacles[p.obstacle].gap(&x)
                && g.h < 0.5 * self.search_distance
            {
                return Err(Error::ContactMissed {
                    param: "lambda",
                    at: lambda,
                    node: p.node + 1,
                    obstacle: p.obstacle,
                    gap: g.h,
                    distance: self.search_distance,
                });
            }
        }
        Ok(())
    }

    pub fn active_pairs(&self) -> &[usize] {
        &self.active
    }

    /// Order 0 of the step's series at u0: element series (which also give
    /// the element tangents) and contact pair series.
    fn start_series(&mut self, u0: &[f64]) -> Result<()> {
        let full = self.expand(u0);
        self.series_u0 = u0.to_vec();
        self.el_series = self
            .elements
            .iter()
            .map(|e| {
                let (x, d) = self.element_state(e, &full, false);
                ElementSeries::start(e, &x, &d)
            })
            .collect();
        let mut ps = Vec::with_capacity(self.active.len());
        for &ip in &self.active {
            let pair = &self.pairs[ip];
            let x = self.x0[pair.node] + Self::vec3(&full, pair.node, 0);
            let gap = GapSeries::start(&self.obstacles[pair.obstacle], &x)
                .ok_or_else(|| self.gap_error(pair.node, f64::NAN))?;
            let r0 = pair.law.force(gap.h[0]);
            ps.push(PairSeries {
                pair: ip,
                gap,
                r: vec![r0],
            });
        }
        self.pair_series = ps;
        Ok(())
    }

    fn complete_order(&mut self, um: &[f64]) {
        let full = self.expand(um);
        for (e, st) in self.elements.iter().zip(self.el_series.iter_mut()) {
            let x = std::array::from_fn(|i| Self::vec3(&full, e.nodes[i], 0));
            let d = std::array::from_fn(|i| Self::vec3(&full, e.nodes[i], 3));
            st.complete(e, &x, &d);
        }
        for ps in &mut self.pair_series {
            let pair = &self.pairs[ps.pair];
            let m = ps.gap.orders();
            ps.gap.complete(&Self::vec3(&full, pair.node, 0));
            let rm = pair.law.force_coeff(&ps.r, &ps.gap.h, m);
            ps.r.push(rm);
        }
    }
}

impl ContinuationProblem for ShellModel {
    fn ndof(&self) -> usize {
        self.ndof
    }

    fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
        let full = self.expand(u);
        self.check_inactive(&full, lambda)?;
        let r = self.residual_full(&full, lambda)?;
        Self::check_finite(&r, lambda, "residual")?;
        Ok(self.reduce(&r))
    }

    fn tangent(&mut self, u: &[f64], lambda: f64) -> Result<(SparseMatrix, Vec<f64>)> {
        let full = self.expand(u);
        self.update_active(&full);
        self.start_series(u)?;
        let mut k = SparseMatrix::new(self.ndof);
        k.entries
            .reserve(576 * self.elements.len() + 9 * (self.follower.len() + self.active.len()));
        let mut add = |free: &[Option<usize>], gi: usize, gj: usize, v: f64| {
            if let (Some(i), Some(j)) = (free[gi], free[gj]) {
                k.add(i, j, v);
            }
        };
        for (e, st) in self.elements.iter().zip(&self.el_series) {
            let ke = st.tangent();
            for a in 0..24 {
                let ga = 6 * e.nodes[a / 6] + a % 6;
                for b in 0..24 {
                    let gb = 6 * e.nodes[b / 6] + b % 6;
                    add(&self.free, ga, gb, ke[(a, b)]);
                }
            }
        }
        let mut rl = vec![0.0; full.len()];
        for (r, f) in rl.iter_mut().zip(&self.dead) {
            *r = -f;
        }
        for c in &self.follower {
            let a3 = self.a30[c.node] + Self::vec3(&full, c.node, 3);
            let fw = c.moment.cross(&a3);
            let m = c.moment;
            // d(-λ m × w)/dw = -λ [m]×.
            let mx = [[0.0, -m[2], m[1]], [m[2], 0.0, -m[0]], [-m[1], m[0], 0.0]];
            for i in 0..3 {
                rl[6 * c.node + 3 + i] -= fw[i];
                for j in 0..3 {
                    add(
                        &self.free,
                        6 * c.node + 3 + i,
                        6 * c.node + 3 + j,
                        -lambda * mx[i][j],
                    );
                }
            }
        }
        for &ip in &self.active {
            let pair = &self.pairs[ip];
            let x = self.x0[pair.node] + Self::vec3(&full, pair.node, 0);
            let g = self.obstacles[pair.obstacle]
                .gap(&x)
                .ok_or_else(|| self.gap_error(pair.node, lambda))?;
            let r = pair.law.force(g.h);
            let dr = pair.law.stiffness(g.h);
            for i in 0..3 {
                for j in 0..3 {
                    let v = -(dr * g.n[i] * g.n[j] + r * g.dn[(i, j)]);
                    add(&self.free, 6 * pair.node + i, 6 * pair.node + j, v);
                }
            }
        }
        if let Some(t) = k.entries.iter().find(|t| !t.val.is_finite()) {
            let i = self
                .free
                .iter()
                .position(|f| *f == Some(t.row))
                .unwrap_or(0);
            return Err(Error::NonFinite {
                step: 0,
                param: "lambda",
                at: lambda,
                what: format!(
                    "tangent matrix (entry {}: node {}, dof {})",
                    t.row,
                    i / 6,
                    i % 6
                ),
            });
        }
        Ok((k, self.reduce(&rl)))
    }

    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], lambda: &[f64]) -> Result<Vec<f64>> {
        let fresh = self.el_series.first().map_or(0, |s| s.orders());
        if fresh != p - 1 || self.series_u0 != u[0] {
            self.start_series(&u[0])?;
            for um in &u[1..p - 1] {
                self.complete_order(um);
            }
        }
        self.complete_order(&u[p - 1]);
        let mut rhs = vec![0.0; self.free.len()];
        for (e, st) in self.elements.iter().zip(&mut self.el_series) {
            let f = st.rhs(e);
            for (i, &n) in e.nodes.iter().enumerate() {
                for k in 0..6 {
                    rhs[6 * n + k] += f[6 * i + k];
                }
            }
        }
        if !self.follower.is_empty() {
            let fulls: Vec<Vec<f64>> = u[1..p].iter().map(|x| self.expand(x)).collect();
            for c in &self.follower {
                let mut s = Vec3::zeros();
                for r in 1..p {
                    s += c.moment.cross(&Self::vec3(&fulls[p - r - 1], c.node, 3)) * lambda[r];
                }
                for k in 0..3 {
                    rhs[6 * c.node + 3 + k] -= s[k];
                }
            }
        }
        for ps in &mut self.pair_series {
            let pair = &self.pairs[ps.pair];
            let (hs, ns) = ps.gap.starred();
            let mut h = ps.gap.h.clone();
            h.push(hs);
            let mut r = ps.r.clone();
            r.push(0.0);
            let rs = pair.law.force_coeff(&r, &h, p);
            let mut f = ns * ps.r[0] + ps.gap.normal(0) * rs;
            for q in 1..p {
                f += ps.gap.normal(p - q) * ps.r[q];
            }
            for k in 0..3 {
                rhs[6 * pair.node + k] -= f[k];
            }
        }
        Self::check_finite(&rhs, lambda[0], "series right-hand side")?;
        Ok(self.reduce(&rhs))
    }
}

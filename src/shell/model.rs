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
//! A follower pressure p on an element adds −λ f(x), f_a(x) = ∫ N_a p
//! (x,ξ × x,η) dξ dη, quadratic in the current positions x: f = B(x, x)
//! (crate::fe::surface_load). Its tangent is the load stiffness −λ ∂f/∂x
//! and its λ column −f(x); its series term at order p is
//! −Σ_{r=1}^{p−1} λ_r f_{p−r} − λ_0 Σ_{s=1}^{p−1} B(x_s, x_{p−s}), with
//! f_q = Σ_{s=0}^{q} B(x_s, x_{q−s}) and x_0 = X + v_0.
//!
//! Fixed dofs hold λ times their prescribed value (`prescribed`), so
//! their order-p coefficient is λ_p times it; an obstacle translating with
//! velocity V in λ enters as the relative position x − λ V.
//!
//! Series (order p ≥ 2, U_p = λ_p = 0): element convolutions
//! in nodal Gram form (see [`super::series`]), the follower term above, and per contact pair
//! the Taylor propagation of h, n (obstacle::GapSeries) and R (eq. 3,
//! NormalLaw::force_coeff), force coefficient Σ_{r=0}^{p} R_r n_{p−r}.

// Node/dof/component loops read better with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::element::{ElementMatrix, FullMapCache, ShellElement};
use super::geometric_map;
use super::kinematics::{NDOF_EL, PackedSym, Vec3};
use super::material::Material;
use super::series::ElementSeries;
use crate::contact::Motion;
use crate::contact::log_reaction::LogReaction;
use crate::contact::obstacle::{GapSeries, Obstacle};
use crate::contact::search::{self, ContactPair};
use crate::error::{Error, Result};
use crate::fe::dof::{Component, Dof, PER_NODE, index as dof};
use crate::fe::pattern::{ElementSlots, NO_SLOT, element_slots, node_block_structure};
use crate::fe::prefetch::prefetch_growing;
use crate::fe::surface_load;
use crate::linalg::{ColumnBlock, SparseMatrix, Structure};
use rayon::prelude::*;
use std::sync::Arc;

/// Elements whose tangent matrices are computed together (in parallel)
/// before being added: 4096 × 4.6 kB.
const TANGENT_CHUNK: usize = 4096;

/// Fewest elements per parallel task: below, the dispatch costs more than
/// the work (measured: the 40-element plate-cylinder ran 3× slower without).
const PAR_MIN: usize = 256;
/// Elements from which the series' inner terms are computed during the
/// solves ([`ContinuationProblem::rhs_prepass`]).
const PREPASS_MIN_ELEMENTS: usize = 1000;
use crate::series::ContinuationProblem;
use crate::series::continuation::{ArcCoordinates, Prepass};
use std::sync::atomic::{AtomicBool, Ordering};

/// A follower couple at a node: director force λ (moment × a3).
#[derive(Clone, Debug)]
pub struct FollowerCouple {
    pub node: usize,
    pub moment: Vec3,
}

/// A follower pressure on one element: force −λ f(x) (module doc).
#[derive(Clone, Debug)]
pub struct FollowerPressure {
    pub nodes: [usize; 4],
    pub pressure: f64,
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
    /// y = c ln(R + eta), the pair's arc coordinate.
    log_r: LogReaction,
    /// y*_p of the last right-hand side: the arc coordinate's order p
    /// with U_p = 0, lambda_p = 0 (from the reaction's r*_p), computed in
    /// the pairs' parallel pass while the pair's series are in cache.
    y_star: f64,
}

pub struct ShellModel {
    pub x0: Vec<Vec3>,
    /// The number each node goes by in outputs and messages (the mesh's
    /// `node_tags`: gmsh tags, or 1-based indices); see [`Self::node_tag`].
    pub node_tags: Vec<usize>,
    pub a30: Vec<Vec3>,
    pub elements: Vec<ShellElement>,
    /// Full dof (6 node + k, k = 0..3 v, 3..6 w) to free-dof index.
    pub free: Vec<Option<usize>>,
    ndof: usize,
    /// Dead load pattern F on the full dofs.
    pub dead: Vec<f64>,
    /// Prescribed values per unit lambda on the full dofs (fixed dofs hold
    /// lambda times this; zero elsewhere).
    pub prescribed: Vec<f64>,
    pub follower: Vec<FollowerCouple>,
    pub pressures: Vec<FollowerPressure>,
    /// Obstacles at lambda = 0 and their motion in lambda.
    pub obstacles: Vec<Obstacle>,
    pub motions: Vec<Motion>,
    pub pairs: Vec<ContactPair>,
    pub search_distance: f64,
    /// Characteristic length of the displacement unknowns in the step
    /// control (the director unknowns are dimensionless).
    pub length_scale: f64,
    /// Weight c of the contact pairs' arc coordinates c ln(R + eta)
    /// (contact::log_reaction); 0: none.
    pub contact_arclength: f64,
    /// Penalty law (eta = 0): the gap band |h| <= kink_band in which a pair
    /// keeps the piece it started a step on (series::kinks): nodes resting
    /// on the obstacle with reactions near zero sit at the kink within the
    /// round-off of their position, and would switch at every step. Set so
    /// that K kink_band, the force a pair may miss, is a tenth of the
    /// residual test's (run::build).
    pub kink_band: f64,
    active: Vec<usize>,
    // Series state of the current step.
    series_u0: Vec<f64>,
    series_lambda0: f64,
    el_series: Vec<ElementSeries>,
    pair_series: Vec<PairSeries>,
    /// Distinct element maps after geometric_map::share.
    distinct_maps: usize,
    /// The full state of the last residual and each element's Kg_0 there.
    state_kg: (Vec<f64>, Vec<PackedSym>),
    /// The order whose inner terms a job was handed (rhs_prepass).
    prepass_order: Option<usize>,
    /// The tangent's pattern (element connectivity of the free dofs), built
    /// on the first tangent after the constraints are set, with each
    /// element's slots in it (empty if they do not fit 32 bits).
    structure: Option<Arc<Structure>>,
    slots: Vec<ElementSlots>,
    /// Per contact pair, the slots of its node's translation rows in the
    /// node's three translation columns (each a run of 3 slots), found with
    /// the pattern and again when the pairs change; NO_SLOT where the node
    /// has a fixed translation or the slot does not fit 32 bits (the
    /// assembly searches then).
    pair_slots: Vec<[u32; 3]>,
    /// Series orders a step computes (ContinuationProblem::reserve_orders):
    /// the series buffers are sized for them at the step start, so that
    /// the parallel order loops allocate nothing.
    orders: usize,
}

impl ShellModel {
    /// The elements' node lists (the mesh's quadrilaterals).
    pub fn quads(&self) -> Vec<[usize; 4]> {
        self.elements.iter().map(|e| e.nodes).collect()
    }

    /// The number users know node `n` (0-based) by: its tag in the mesh
    /// file, or n + 1 for a built-in mesh.
    pub fn node_tag(&self, n: usize) -> usize {
        self.node_tags[n]
    }

    /// An unknown of the full vector as users read it: "node <tag> <component>".
    pub fn dof_label(&self, i: usize) -> String {
        let d = Dof::of_index(i);
        format!("node {} {}", self.node_tag(d.node), d.component)
    }

    /// Distinct element maps (geometric_map::share).
    pub fn distinct_maps(&self) -> usize {
        self.distinct_maps
    }

    /// Elements from quads (node indices), reference positions and unit
    /// directors. Element errors carry the element index.
    pub fn new(
        x0: Vec<Vec3>,
        a30: Vec<Vec3>,
        quads: &[[usize; 4]],
        thickness: f64,
        material: Material,
    ) -> Result<Self> {
        // In parallel (a million unknowns: 166,320 elements, each with its
        // 28×28 map); the first failing element in mesh order is reported.
        let built = quads
            .par_iter()
            .enumerate()
            .with_min_len(PAR_MIN)
            .map(|(id, q)| {
                let x: [Vec3; 4] = std::array::from_fn(|i| x0[q[i]]);
                let d: [Vec3; 4] = std::array::from_fn(|i| a30[q[i]]);
                ShellElement::with_map_apart(id, *q, &x, &d, thickness, &material)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .collect::<Result<Vec<_>>>()?;
        // The maps are allocated once per congruent class, here, on this
        // thread: not one per element on the pool's threads and then freed
        // (their holes between this thread's large blocks cost 0.58 GB of
        // peak at a million unknowns).
        let (mut elements, maps): (Vec<ShellElement>, Vec<_>) = built.into_iter().unzip();
        let (maps, distinct_maps) = geometric_map::share(maps);
        for (e, map) in elements.iter_mut().zip(maps) {
            e.set_map(map);
        }
        let n = x0.len();
        let mut m = Self {
            node_tags: (1..=n).collect(),
            x0,
            a30,
            elements,
            free: vec![None; PER_NODE * n],
            ndof: 0,
            dead: vec![0.0; PER_NODE * n],
            prescribed: vec![0.0; PER_NODE * n],
            follower: vec![],
            pressures: vec![],
            obstacles: vec![],
            motions: vec![],
            pairs: vec![],
            search_distance: f64::INFINITY,
            length_scale: 1.0,
            contact_arclength: 0.0,
            kink_band: 0.0,
            active: vec![],
            series_u0: vec![],
            series_lambda0: f64::NAN,
            el_series: vec![],
            pair_series: vec![],
            distinct_maps,
            state_kg: (vec![], vec![]),
            prepass_order: None,
            structure: None,
            slots: Vec::new(),
            pair_slots: Vec::new(),
            orders: 0,
        };
        m.set_constraints(&[]);
        Ok(m)
    }

    /// Fixes the listed (node, component) dofs to zero, all others free.
    pub fn set_constraints(&mut self, fixed: &[(usize, usize)]) {
        let mut is_fixed = vec![false; self.free.len()];
        for &(node, k) in fixed {
            is_fixed[dof(node, k)] = true;
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
        self.structure = None;
        self.slots.clear();
        self.pair_slots.clear();
    }

    /// Values per unit lambda of the fixed dofs (full vector; entries at
    /// free dofs are ignored): the fixed dof i holds lambda prescribed[i].
    pub fn set_prescribed(&mut self, prescribed: Vec<f64>) {
        assert_eq!(prescribed.len(), self.free.len());
        self.prescribed = prescribed;
    }

    /// Adds obstacles (fixed) and the contact pairs of `nodes`, delta =
    /// initial gap.
    pub fn set_contact(
        &mut self,
        obstacles: Vec<Obstacle>,
        nodes: &[usize],
        k: f64,
        eta: f64,
        distance: f64,
    ) -> std::result::Result<(), (usize, usize, f64)> {
        self.pairs = search::pairs(nodes, &self.x0, &obstacles, k, eta)?;
        self.pair_slots.clear();
        self.motions = vec![Motion::Fixed; obstacles.len()];
        self.obstacles = obstacles;
        self.search_distance = distance;
        self.active = search::active(&self.pairs, &self.x0, &self.obstacles, distance);
        Ok(())
    }

    /// Keeps, per node, only its pair with the obstacle nearest to it in
    /// the reference configuration (the smallest delta; the first on a
    /// tie). Friction needs one tangent frame per node, and in time the
    /// obstacles keep their place (docs/shell-friction.md).
    pub fn keep_nearest_pairs(&mut self) {
        let mut nearest: std::collections::HashMap<usize, (usize, f64)> =
            std::collections::HashMap::new();
        for p in &self.pairs {
            let e = nearest.entry(p.node).or_insert((p.obstacle, p.law.delta));
            if p.law.delta < e.1 {
                *e = (p.obstacle, p.law.delta);
            }
        }
        self.pairs.retain(|p| nearest[&p.node].0 == p.obstacle);
        self.pair_slots.clear();
        self.active = search::active(&self.pairs, &self.x0, &self.obstacles, self.search_distance);
    }

    pub fn n_nodes(&self) -> usize {
        self.x0.len()
    }

    /// Characteristic magnitude of each free unknown: `length_scale` for a
    /// displacement, 1 for a director component.
    pub fn scales(&self) -> Vec<f64> {
        let mut s = vec![0.0; self.ndof];
        for (i, f) in self.free.iter().enumerate() {
            if let Some(k) = f {
                s[*k] = if Dof::of_index(i).component.is_displacement() {
                    self.length_scale
                } else {
                    1.0
                };
            }
        }
        s
    }

    /// Sets the obstacles' motions in lambda (one per obstacle).
    pub fn set_motions(&mut self, motions: Vec<Motion>) {
        assert_eq!(motions.len(), self.obstacles.len());
        self.motions = motions;
    }

    /// The obstacles where their motion has taken them at lambda.
    pub fn obstacles_at(&self, lambda: f64) -> Vec<Obstacle> {
        self.obstacles
            .iter()
            .zip(&self.motions)
            .map(|(o, m)| o.translated(m.shift(lambda)))
            .collect()
    }

    /// Free-dof vector to full vector at lambda: fixed dofs hold
    /// lambda × their prescribed value.
    pub fn expand(&self, u: &[f64], lambda: f64) -> Vec<f64> {
        self.free
            .iter()
            .zip(&self.prescribed)
            .map(|(f, p)| f.map_or(lambda * p, |i| u[i]))
            .collect()
    }

    /// Full vector to free-dof vector (fixed dofs dropped).
    pub fn reduce(&self, full: &[f64]) -> Vec<f64> {
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
            .map(|i| self.position(full, i))
            .collect()
    }

    /// Current mid-surface position x = X + v of `node` from a full vector.
    pub fn position(&self, full: &[f64], node: usize) -> Vec3 {
        self.x0[node] + Self::vec3(full, node, 0)
    }

    /// The largest translation |x − X| of a node from a full vector.
    pub fn largest_translation(&self, full: &[f64]) -> f64 {
        (0..self.n_nodes())
            .map(|i| Self::vec3(full, i, 0).norm())
            .fold(0.0, f64::max)
    }

    /// Current directors from a full vector.
    pub fn directors(&self, full: &[f64]) -> Vec<Vec3> {
        (0..self.n_nodes())
            .map(|i| self.a30[i] + Self::vec3(full, i, 3))
            .collect()
    }

    fn element_state(&self, e: &ShellElement, full: &[f64], incr: bool) -> ([Vec3; 4], [Vec3; 4]) {
        let x = std::array::from_fn(|i| {
            let n = e.nodes[i];
            let v = Self::vec3(full, n, 0);
            if incr { v } else { self.x0[n] + v }
        });
        let d = std::array::from_fn(|i| {
            let n = e.nodes[i];
            let w = Self::vec3(full, n, 3);
            if incr { w } else { self.a30[n] + w }
        });
        (x, d)
    }

    /// Internal force of element `e` at the full state: 6 entries per node
    /// (force on v, then on w), in the element's node order.
    pub fn element_internal(&self, e: usize, full: &[f64]) -> [f64; 24] {
        let el = &self.elements[e];
        let (x, d) = self.element_state(el, full, false);
        el.internal(&x, &d)
    }

    /// Membrane force resultant of element `e` at the full state
    /// ([`ShellElement::membrane_resultant`], force per unit length).
    pub fn membrane_resultant(&self, e: usize, full: &[f64]) -> nalgebra::Matrix3<f64> {
        let el = &self.elements[e];
        let (x, d) = self.element_state(el, full, false);
        el.membrane_resultant(&x, &d)
    }

    fn vec3(full: &[f64], node: usize, off: usize) -> Vec3 {
        Vec3::new(
            full[dof(node, off)],
            full[dof(node, off + 1)],
            full[dof(node, off + 2)],
        )
    }

    /// Adds a 3 × 3 block on the translations of `node` to a matrix on the
    /// free unknowns (the entries of held translations are dropped).
    pub fn add_node_block(&self, k: &mut SparseMatrix, node: usize, block: &[[f64; 3]; 3]) {
        for i in 0..3 {
            for j in 0..3 {
                if let (Some(a), Some(b)) = (self.free[dof(node, i)], self.free[dof(node, j)]) {
                    k.add(a, b, block[i][j]);
                }
            }
        }
    }

    /// The contact part of the tangent alone (the pairs active at u; their
    /// law's stiffness and the normal's turning), on the free unknowns:
    /// what linearized buckling holds fixed at the base state.
    pub fn contact_tangent(&mut self, u: &[f64], lambda: f64) -> Result<SparseMatrix> {
        let full = self.expand(u, lambda);
        self.update_active(&full, lambda);
        let obstacles = self.obstacles_at(lambda);
        let mut k = SparseMatrix::new(self.ndof);
        for &ip in &self.active {
            let (node, kc) = self.contact_block(ip, &full, &obstacles, lambda)?;
            self.add_node_block(&mut k, node, &kc);
        }
        Ok(k)
    }

    /// The node of pair `ip` and its 3 × 3 tangent block
    /// −(R'(h) n nᵀ + R(h) dn/dx) (eq. 3 differentiated).
    fn contact_block(
        &self,
        ip: usize,
        full: &[f64],
        obstacles: &[Obstacle],
        lambda: f64,
    ) -> Result<(usize, [[f64; 3]; 3])> {
        let pair = &self.pairs[ip];
        let x = self.x0[pair.node] + Self::vec3(full, pair.node, 0);
        let g = obstacles[pair.obstacle]
            .gap(&x)
            .ok_or_else(|| self.gap_error(pair.node, lambda))?;
        let r = pair.law.force(g.h);
        let dr = pair.law.stiffness(g.h);
        let kc = std::array::from_fn(|i| {
            std::array::from_fn(|j| -(dr * g.n[i] * g.n[j] + r * g.dn[(i, j)]))
        });
        Ok((pair.node, kc))
    }

    /// Contact reactions of the active pairs at the full state, and of the
    /// left-out pairs of the penalty law that penetrate (a step ends at
    /// their first contact, series::kinks, but its end correction may
    /// carry them a round-off past it before they join the active set).
    pub fn contact_forces(&self, full: &[f64], lambda: f64) -> Result<Vec<NodalContact>> {
        let mut out = Vec::with_capacity(self.active.len());
        let obstacles = self.obstacles_at(lambda);
        let mut left_out = vec![];
        if self.active.len() < self.pairs.len() && self.pairs.iter().any(|p| p.law.is_piecewise()) {
            let is_active = self.active_mask();
            left_out = (0..self.pairs.len())
                .filter(|&i| !is_active[i] && self.pairs[i].law.is_piecewise())
                .collect();
        }
        for (k, &ip) in self.active.iter().chain(&left_out).enumerate() {
            let pair = &self.pairs[ip];
            let x = self.x0[pair.node] + Self::vec3(full, pair.node, 0);
            let g = obstacles[pair.obstacle]
                .gap(&x)
                .ok_or_else(|| self.gap_error(pair.node, lambda))?;
            if k >= self.active.len() && g.h >= 0.0 {
                continue;
            }
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
            what: format!(
                "contact gap of node {} (on the obstacle axis)",
                self.node_tag(node)
            ),
        }
    }

    /// Full residual vector (all dofs, before removing the fixed ones).
    pub fn residual_full(&self, full: &[f64], lambda: f64) -> Result<Vec<f64>> {
        self.residual_with(full, lambda, None)
    }

    /// [`ShellModel::residual_full`]; with `keep`, each element's Kg(σ) at
    /// this state too (ShellElement::internal_and_geometric), which the
    /// next series start at the same state takes instead of recomputing
    /// the strains and stresses. Elements in parallel by chunks, their
    /// forces added in element order (the sums of a sequential loop).
    fn residual_with(
        &self,
        full: &[f64],
        lambda: f64,
        keep: Option<&mut Vec<PackedSym>>,
    ) -> Result<Vec<f64>> {
        let with_kg = keep.is_some();
        // Into buffers allocated here (see series_rhs).
        let mut forces = vec![[0.0; NDOF_EL]; self.elements.len()];
        let mut kgs = vec![PackedSym::zeros(); if with_kg { self.elements.len() } else { 0 }];
        let elements = self.elements.par_chunks(PAR_MIN);
        if with_kg {
            forces
                .par_chunks_mut(PAR_MIN)
                .zip(kgs.par_chunks_mut(PAR_MIN))
                .zip(elements)
                .for_each(|((out, kg_out), chunk)| {
                    for (i, ((f, kg), e)) in out.iter_mut().zip(kg_out).zip(chunk).enumerate() {
                        if let Some(next) = chunk.get(i + 1) {
                            next.prefetch_state();
                        }
                        let (x, d) = self.element_state(e, full, false);
                        (*f, *kg) = e.internal_and_geometric(&x, &d);
                    }
                });
        } else {
            forces
                .par_chunks_mut(PAR_MIN)
                .zip(elements)
                .for_each(|(out, chunk)| {
                    for (i, (f, e)) in out.iter_mut().zip(chunk).enumerate() {
                        if let Some(next) = chunk.get(i + 1) {
                            next.prefetch_state();
                        }
                        let (x, d) = self.element_state(e, full, false);
                        *f = e.internal(&x, &d);
                    }
                });
        }
        let mut r = vec![0.0; full.len()];
        for (e, f) in self.elements.iter().zip(&forces) {
            for (i, &n) in e.nodes.iter().enumerate() {
                for k in 0..6 {
                    r[dof(n, k)] += f[6 * i + k];
                }
            }
        }
        if let Some(kept) = keep {
            *kept = kgs;
        }
        for (ri, fi) in r.iter_mut().zip(&self.dead) {
            *ri -= lambda * fi;
        }
        for c in &self.follower {
            let a3 = self.a30[c.node] + Self::vec3(full, c.node, 3);
            let fw = c.moment.cross(&a3) * lambda;
            for k in 0..3 {
                r[dof(c.node, 3 + k)] -= fw[k];
            }
        }
        for pr in &self.pressures {
            let f = surface_load::follower_forces(pr.pressure, &self.pressure_x(pr, full, true));
            for (i, &n) in pr.nodes.iter().enumerate() {
                for k in 0..3 {
                    r[dof(n, k)] -= lambda * f[i][k];
                }
            }
        }
        for c in self.contact_forces(full, lambda)? {
            for k in 0..3 {
                r[dof(c.node, k)] -= c.r * c.normal[k];
            }
        }
        Ok(r)
    }

    /// Nodal positions of a pressure element: X + v (`total`) or v alone
    /// (a series coefficient of order >= 1).
    fn pressure_x(&self, pr: &FollowerPressure, full: &[f64], total: bool) -> [Vec3; 4] {
        pr.nodes.map(|n| {
            let v = Self::vec3(full, n, 0);
            if total { self.x0[n] + v } else { v }
        })
    }

    fn check_finite(&self, v: &[f64], lambda: f64, what: &str) -> Result<()> {
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                step: 0,
                param: "lambda",
                at: lambda,
                what: format!("{what} (entry {i}: {})", self.dof_label(i)),
            });
        }
        Ok(())
    }

    /// Refreshes the active contact set at the full state at lambda.
    pub fn update_active(&mut self, full: &[f64], lambda: f64) {
        let x = self.positions(full);
        let obstacles = self.obstacles_at(lambda);
        self.active = search::active(&self.pairs, &x, &obstacles, self.search_distance);
    }

    /// The active set is frozen during a step: a candidate left out at the
    /// step start must not come within half the search distance of its
    /// obstacle before the next refresh, or its contact term would be
    /// missing (error, with the advice to enlarge the search distance). Not
    /// for the penalty law (eta = 0), whose left-out pairs enter the residual
    /// as soon as they penetrate ([`ShellModel::contact_forces`]).
    fn check_inactive(&self, full: &[f64], lambda: f64) -> Result<()> {
        if self.pairs.len() == self.active.len() {
            return Ok(());
        }
        let is_active = self.active_mask();
        let obstacles = self.obstacles_at(lambda);
        for (i, p) in self.pairs.iter().enumerate() {
            if is_active[i] {
                continue;
            }
            let x = self.x0[p.node] + Self::vec3(full, p.node, 0);
            // The penalty law carries nothing before contact, and its force
            // at a penetration is in the residual whether the pair is active
            // or not (contact_forces).
            if let Some(g) = obstacles[p.obstacle].gap(&x)
                && g.h < 0.5 * self.search_distance
                && !p.law.is_piecewise()
            {
                return Err(Error::ContactMissed {
                    param: "lambda",
                    at: lambda,
                    node: self.node_tag(p.node),
                    obstacle: p.obstacle,
                    gap: g.h,
                    distance: self.search_distance,
                });
            }
        }
        Ok(())
    }

    /// Per pair: whether it is in the active set.
    fn active_mask(&self) -> Vec<bool> {
        let mut is_active = vec![false; self.pairs.len()];
        for &i in &self.active {
            is_active[i] = true;
        }
        is_active
    }

    pub fn active_pairs(&self) -> &[usize] {
        &self.active
    }

    /// Adds an element matrix to the tangent: per column, the free rows of
    /// each node as one run of adjacent slots (one search per nodal block
    /// instead of one per entry); a fixed column j held at lambda p_j goes to
    /// the lambda column as K_ij p_j.
    fn scatter_element(
        &self,
        e: &ShellElement,
        slots: Option<&ElementSlots>,
        ke: &ElementMatrix,
        k: &mut SparseMatrix,
        rl: &mut [f64],
    ) {
        // Free rows of each node: (local row, free index).
        let (rows, counts) = self.element_rows(e);
        let (mut idx, mut vals) = ([0usize; 6], [0.0; 6]);
        for b in 0..24 {
            let gb = dof(e.nodes[b / 6], b % 6);
            match self.free[gb] {
                Some(j) => {
                    for a in 0..4 {
                        let run = &rows[a][..counts[a]];
                        for (m, &(la, i)) in run.iter().enumerate() {
                            idx[m] = i;
                            vals[m] = ke[(la, b)];
                        }
                        match slots.map(|s| s[b][a]) {
                            Some(slot) if slot != NO_SLOT => {
                                k.add_at_slots(slot as usize, &vals[..run.len()])
                            }
                            _ => k.add_sorted_rows(&idx[..run.len()], j, &vals[..run.len()]),
                        }
                    }
                }
                None => {
                    for a in 0..4 {
                        for &(la, _) in &rows[a][..counts[a]] {
                            let ga = dof(e.nodes[la / 6], la % 6);
                            rl[ga] += ke[(la, b)] * self.prescribed[gb];
                        }
                    }
                }
            }
        }
    }

    /// [`Self::scatter_element`] of `elements` restricted to the columns of
    /// `block`, their slots given; the fixed columns go to `rl` where given
    /// (to one block only).
    fn scatter_block(
        &self,
        elements: &[ShellElement],
        slots: &[ElementSlots],
        kes: &[ElementMatrix],
        block: ColumnBlock,
        mut rl: Option<&mut [f64]>,
    ) {
        for ((e, slots), ke) in elements.iter().zip(slots).zip(kes) {
            let (rows, counts) = self.element_rows(e);
            for (b, column) in slots.iter().enumerate() {
                let gb = dof(e.nodes[b / 6], b % 6);
                match self.free[gb] {
                    Some(j) if block.cols.contains(&j) => {
                        for (a, &slot) in column.iter().enumerate() {
                            let run = &rows[a][..counts[a]];
                            if run.is_empty() {
                                continue;
                            }
                            let at = slot as usize - block.first_slot;
                            for (v, &(la, _)) in
                                block.values[at..at + run.len()].iter_mut().zip(run)
                            {
                                *v += ke[(la, b)];
                            }
                        }
                    }
                    Some(_) => {}
                    None => {
                        if let Some(rl) = rl.as_deref_mut() {
                            for a in 0..4 {
                                for &(la, _) in &rows[a][..counts[a]] {
                                    let ga = dof(e.nodes[la / 6], la % 6);
                                    rl[ga] += ke[(la, b)] * self.prescribed[gb];
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// Free rows of each node of `e`: (local row, free index), and their
    /// numbers.
    fn element_rows(&self, e: &ShellElement) -> ([[(usize, usize); 6]; 4], [usize; 4]) {
        let mut rows = [[(0usize, 0usize); 6]; 4];
        let mut counts = [0usize; 4];
        for (a, &n) in e.nodes.iter().enumerate() {
            for c in 0..6 {
                if let Some(i) = self.free[dof(n, c)] {
                    rows[a][counts[a]] = (6 * a + c, i);
                    counts[a] += 1;
                }
            }
        }
        (rows, counts)
    }

    /// The first slot of node `node`'s translation rows in each of its
    /// translation columns, where the three are free and each column holds
    /// them as one run ([`ShellModel::pair_slots`]).
    fn translation_slots(s: &Structure, free: &[Option<usize>], node: usize) -> [u32; 3] {
        let rows = [0, 1, 2].map(|i| free[dof(node, i)]);
        let [Some(a), Some(b), Some(c)] = rows else {
            return [NO_SLOT; 3];
        };
        let run = |col: usize| {
            let first = s.slot(a, col)?;
            (s.slot(b, col) == Some(first + 1) && s.slot(c, col) == Some(first + 2))
                .then_some(())?;
            u32::try_from(first).ok().filter(|&k| k != NO_SLOT)
        };
        match [a, b, c].map(run) {
            [Some(x), Some(y), Some(z)] => [x, y, z],
            _ => [NO_SLOT; 3],
        }
    }

    /// Order 0 of the step's series at u0: element series (which also give
    /// the element tangents) and contact pair series.
    fn start_series(&mut self, u0: &[f64], lambda0: f64) -> Result<()> {
        let full = self.expand(u0, lambda0);
        self.series_u0 = u0.to_vec();
        self.series_lambda0 = lambda0;
        let obstacles = self.obstacles_at(lambda0);
        if self.el_series.len() == self.elements.len() {
            // Restarted in place: the last step's buffers are reused (no
            // allocation and release per element and step).
            // Kg_0 from the last residual where it was at this state.
            let kept = (self.state_kg.0 == full && self.state_kg.1.len() == self.elements.len())
                .then_some(&self.state_kg.1);
            let mut series = std::mem::take(&mut self.el_series);
            series
                .par_chunks_mut(PAR_MIN)
                .zip(self.elements.par_chunks(PAR_MIN))
                .enumerate()
                .for_each(|(c, (series, elements))| {
                    for (k, e) in elements.iter().enumerate() {
                        // The next element's record and first orders, which
                        // the solves have evicted since the last step.
                        if let (Some(next), Some(ne)) = (series.get(k + 1), elements.get(k + 1)) {
                            next.prefetch_start();
                            ne.prefetch_record();
                        }
                        let st = &mut series[k];
                        let (x, d) = self.element_state(e, &full, false);
                        match kept {
                            Some(kg) => st.restart_with(&x, &d, kg[c * PAR_MIN + k]),
                            None => st.restart(e, &x, &d),
                        }
                        st.reserve(self.orders);
                    }
                });
            self.el_series = series;
        } else {
            self.el_series = self
                .elements
                .par_iter()
                .with_min_len(PAR_MIN)
                .map(|e| {
                    let (x, d) = self.element_state(e, &full, false);
                    let mut st = ElementSeries::start(e, &x, &d);
                    st.reserve(self.orders);
                    st
                })
                .collect();
        }
        // Restarted in the last step's buffers while the active pairs are
        // the same, on both threads (no allocation): 12 small blocks per pair
        // allocated and released per step cost 1.3 ms of the 2,115-pair
        // strip's ~75 ms step (140×14). New series are built on one thread:
        // built on the pool's threads, they (0.3 GB of small blocks at a
        // million unknowns) raised the peak by 0.5 GB.
        let mut series = std::mem::take(&mut self.pair_series);
        let in_place = series.len() == self.active.len()
            && series
                .iter()
                .zip(&self.active)
                .all(|(ps, &ip)| ps.pair == ip);
        if !in_place {
            series.clear();
            series.reserve_exact(self.active.len());
        }
        let started = self.start_pairs(&mut series, in_place, &full, &obstacles);
        self.pair_series = series;
        started
    }

    /// The pairs' part of [`ShellModel::start_series`]: `series` holds the
    /// active pairs' series to restart (`in_place`) or is empty.
    fn start_pairs(
        &self,
        series: &mut Vec<PairSeries>,
        in_place: bool,
        full: &[f64],
        obstacles: &[Obstacle],
    ) -> Result<()> {
        let position = |ip: usize| {
            let node = self.pairs[ip].node;
            self.x0[node] + Self::vec3(full, node, 0)
        };
        let gap_error = |ip: usize| self.gap_error(self.pairs[ip].node, f64::NAN);
        if in_place {
            // In the last step's buffers, on every thread (no allocation);
            // the first pair in order whose gap is undefined is reported.
            let failed = series
                .par_iter_mut()
                .enumerate()
                .with_min_len(PAR_MIN)
                .filter_map(|(k, ps)| {
                    let pair = &self.pairs[ps.pair];
                    if ps
                        .gap
                        .restart(&obstacles[pair.obstacle], &position(ps.pair))
                        .is_none()
                    {
                        return Some(k);
                    }
                    ps.r.clear();
                    self.restart_reaction(ps);
                    None
                })
                .min();
            return failed.map_or(Ok(()), |k| Err(gap_error(series[k].pair)));
        }
        for &ip in &self.active {
            let pair = &self.pairs[ip];
            let gap = GapSeries::start(&obstacles[pair.obstacle], &position(ip))
                .ok_or_else(|| gap_error(ip))?;
            series.push(PairSeries {
                pair: ip,
                gap,
                r: Vec::with_capacity(self.orders),
                log_r: LogReaction::default(),
                y_star: 0.0,
            });
            self.restart_reaction(series.last_mut().expect("pushed"));
        }
        Ok(())
    }

    /// A pair's reaction series from its restarted gap: order 0, room for
    /// orders 0 … N − 1 completed and the starred order N pushed by the
    /// last right-hand side (N + 1 = self.orders).
    fn restart_reaction(&self, ps: &mut PairSeries) {
        let pair = &self.pairs[ps.pair];
        ps.gap.reserve(self.orders);
        ps.r.reserve(self.orders);
        ps.r.push(pair.law.force(ps.gap.h[0]));
        ps.log_r.restart(
            self.contact_arclength,
            &pair.law,
            ps.gap.h[0],
            ps.r[0],
            self.orders,
        );
        ps.y_star = 0.0;
    }

    /// Completes order m from (u_m, lambda_m): fixed dofs move by
    /// lambda_m × prescribed, a translating obstacle by lambda_m V, so a
    /// contact node's position relative to it moves by x_m − lambda_m V.
    fn complete_order(&mut self, um: &[f64], lm: f64) {
        let full = self.expand(um, lm);
        self.elements
            .par_iter()
            .zip(self.el_series.par_iter_mut())
            .with_min_len(PAR_MIN)
            .for_each(|(e, st)| {
                let (x, d) = Self::element_coefficients(e, &full);
                st.complete(e, &x, &d);
            });
        self.complete_pairs(&full, lm);
    }

    /// The order-m nodal positions and directors of element `e` from the
    /// full order-m vector.
    fn element_coefficients(e: &ShellElement, full: &[f64]) -> ([Vec3; 4], [Vec3; 4]) {
        (
            std::array::from_fn(|i| Self::vec3(full, e.nodes[i], 0)),
            std::array::from_fn(|i| Self::vec3(full, e.nodes[i], 3)),
        )
    }

    /// The contact pairs' part of [`ShellModel::complete_order`].
    fn complete_pairs(&mut self, full: &[f64], lm: f64) {
        let (pairs, motions) = (&self.pairs, &self.motions);
        self.pair_series
            .par_iter_mut()
            .with_min_len(PAR_MIN)
            .for_each(|ps| Self::complete_pair(pairs, motions, ps, full, lm));
    }

    /// Completes a pair's series with its node's order-m coefficients in
    /// `full` (the obstacle's motion lm V taken off).
    fn complete_pair(
        pairs: &[ContactPair],
        motions: &[Motion],
        ps: &mut PairSeries,
        full: &[f64],
        lm: f64,
    ) {
        let pair = &pairs[ps.pair];
        let m = ps.gap.orders();
        let v = motions[pair.obstacle].velocity();
        ps.gap.complete(&(Self::vec3(full, pair.node, 0) - v * lm));
        let rm = pair.law.force_coeff(&ps.r, &ps.gap.h, m);
        ps.r.push(rm);
        ps.log_r.complete(&ps.r);
    }

    /// A pair's order-p force without its unknown term: the law's order p
    /// with h_p = h*_p and r_p = 0, on the series themselves (pushed, then
    /// popped); keeps r*_p and y*_p for the arc coordinates.
    fn pair_force_star(pairs: &[ContactPair], ps: &mut PairSeries, p: usize) -> Vec3 {
        let pair = &pairs[ps.pair];
        let (hs, ns) = ps.gap.starred();
        ps.gap.h.push(hs);
        ps.r.push(0.0);
        let rs = pair.law.force_coeff(&ps.r, &ps.gap.h, p);
        ps.gap.h.pop();
        ps.r.pop();
        ps.y_star = ps.log_r.starred(rs, &ps.r, p);
        let mut f = ns * ps.r[0] + ps.gap.normal(0) * rs;
        for q in 1..p {
            f += ps.gap.normal(p - q) * ps.r[q];
        }
        f
    }
}

impl PairSeries {
    /// Prefetches the pair's series (fe::prefetch).
    fn prefetch(&self) {
        self.gap.prefetch();
        prefetch_growing(&self.r);
        self.log_r.prefetch();
    }
}

impl ContinuationProblem for ShellModel {
    fn ndof(&self) -> usize {
        self.ndof
    }

    fn unknown_scale(&self) -> Vec<f64> {
        self.scales()
    }

    /// Translations: the node's distance from the origin, at least the
    /// model's length scale (a node at the origin still meets neighbours a
    /// length away); director increments: 1 (|a3| = 1).
    fn resolution(&self, u: &[f64], lambda: f64) -> Option<Vec<f64>> {
        let full = self.expand(u, lambda);
        let mut m = vec![0.0; self.ndof];
        for (i, f) in self.free.iter().enumerate() {
            if let Some(k) = f {
                let node_dof = Dof::of_index(i);
                m[*k] = if node_dof.component.is_displacement() {
                    let v = |c| full[dof(node_dof.node, c)];
                    let x = self.x0[node_dof.node] + Vec3::new(v(0), v(1), v(2));
                    x.norm().max(self.length_scale)
                } else {
                    1.0
                };
            }
        }
        Some(m)
    }

    fn reserve_orders(&mut self, orders: usize) {
        self.orders = orders;
    }

    /// Contact events: the gap of every candidate pair over the width of
    /// its law's switch, g = h / w (NormalLaw::switch_width); not finite
    /// (ignored) where the gap is undefined. For the penalty law (w = 0)
    /// g = h / kink_band: its kinks are crossings of |g| = 1 (series::kinks).
    fn events(&self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
        let obstacles = self.obstacles_at(lambda);
        // The pairs' nodes only (Self::event_unknowns), as `expand` would
        // give them.
        let value = |d: usize| self.free[d].map_or(lambda * self.prescribed[d], |i| u[i]);
        Ok(self
            .pairs
            .iter()
            .map(|p| {
                let n = p.node;
                let x =
                    self.x0[n] + Vec3::new(value(dof(n, 0)), value(dof(n, 1)), value(dof(n, 2)));
                obstacles[p.obstacle].distance(&x).map_or(f64::NAN, |h| {
                    if p.law.is_piecewise() && self.kink_band > 0.0 {
                        h / self.kink_band
                    } else {
                        h / p.law.switch_width()
                    }
                })
            })
            .collect())
    }

    /// The free translations of the contact pairs' nodes: all that
    /// [`Self::events`] reads.
    fn event_unknowns(&self) -> Option<Vec<usize>> {
        let mut idx: Vec<usize> = self
            .pairs
            .iter()
            .flat_map(|p| (0..3).filter_map(move |c| self.free[dof(p.node, c)]))
            .collect();
        idx.sort_unstable();
        idx.dedup();
        Some(idx)
    }

    /// With the penalty law (eta = 0) the contact pairs' gaps are kinks:
    /// every step ends just past the first one (series::kinks).
    fn kinks(&self) -> bool {
        self.pairs.iter().any(|p| p.law.is_piecewise())
    }

    /// K times each translating obstacle's velocity on its candidates'
    /// translations: the force per unit lambda that the motion exerts once
    /// they touch, the scale of the residual test while nothing touches
    /// under the penalty law (dR/dlambda = 0 there).
    fn drive_floor(&self) -> Option<Vec<f64>> {
        let mut full = vec![0.0; PER_NODE * self.x0.len()];
        let mut any = false;
        for p in &self.pairs {
            if let Motion::Translate { velocity } = &self.motions[p.obstacle] {
                for (c, comp) in Component::DISPLACEMENT.iter().enumerate() {
                    full[Dof::new(p.node, *comp).index()] += p.law.k * velocity[c];
                }
                any = true;
            }
        }
        any.then(|| self.reduce(&full))
    }

    /// With `contact_arclength` = c > 0: y = c ln(R + eta) of every active
    /// pair (contact::log_reaction). Its row is dy/dh n on the node's free
    /// displacements; a fixed displacement (lambda × prescribed) and the
    /// obstacle's motion (the gap reads x − lambda V) go to dy/dlambda.
    fn arc_coordinates(&mut self) -> Option<ArcCoordinates> {
        if self.contact_arclength <= 0.0 || self.pair_series.is_empty() {
            return None;
        }
        let mut arc = ArcCoordinates::default();
        for ps in &self.pair_series {
            let pair = &self.pairs[ps.pair];
            // The gap's gradient is the order-0 normal.
            let g = ps.log_r.dy_dh * ps.gap.normal(0);
            let mut row = Vec::with_capacity(3);
            let mut yl = -g.dot(&self.motions[pair.obstacle].velocity());
            for i in 0..3 {
                let d = dof(pair.node, i);
                match self.free[d] {
                    Some(k) => row.push((k, g[i])),
                    None => yl += g[i] * self.prescribed[d],
                }
            }
            arc.rows.push(row);
            arc.lambda.push(yl);
        }
        Some(arc)
    }

    /// Computed by the last `series_rhs` (PairSeries::y_star): on one
    /// thread here the sums cost ~5 ms per step at 4,221 pairs, every
    /// pair's series a cache miss.
    fn arc_coordinates_rhs(&mut self, _p: usize) -> Vec<f64> {
        self.pair_series.iter().map(|ps| ps.y_star).collect()
    }

    fn residual(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>> {
        let full = self.expand(u, lambda);
        self.check_inactive(&full, lambda)?;
        let mut kept = std::mem::take(&mut self.state_kg.1);
        let r = self.residual_with(&full, lambda, Some(&mut kept));
        self.state_kg = (full, kept);
        let r = r?;
        self.check_finite(&r, lambda, "residual")?;
        Ok(self.reduce(&r))
    }

    fn tangent(&mut self, u: &[f64], lambda: f64) -> Result<(SparseMatrix, Vec<f64>)> {
        let full = self.expand(u, lambda);
        self.update_active(&full, lambda);
        self.start_series(u, lambda)?;
        let structure = match &self.structure {
            Some(s) => Arc::clone(s),
            None => {
                let s = Arc::new(node_block_structure(
                    self.x0.len(),
                    self.elements.iter().map(|e| &e.nodes[..]),
                    &self.free,
                    self.ndof,
                ));
                self.slots = self
                    .elements
                    .iter()
                    .map(|e| element_slots(&s, &e.nodes, &self.free))
                    .collect::<Option<_>>()
                    .unwrap_or_default();
                self.structure = Some(Arc::clone(&s));
                s
            }
        };
        // Found with the pattern, again after the pairs change.
        if self.pair_slots.len() != self.pairs.len() {
            self.pair_slots = self
                .pairs
                .iter()
                .map(|p| Self::translation_slots(&structure, &self.free, p.node))
                .collect();
        }
        let mut k = SparseMatrix::with_structure(structure);
        // dR/dlambda on the full dofs: −F, the follower couples' −m × a3,
        // and for a fixed dof j held at lambda p_j the column K_ij p_j.
        let mut rl = vec![0.0; full.len()];
        for (r, f) in rl.iter_mut().zip(&self.dead) {
            *r = -f;
        }
        // Element matrices in parallel, by chunks (bounded memory), added in
        // element order.
        for (chunk, (elements, series)) in self
            .elements
            .chunks(TANGENT_CHUNK)
            .zip(self.el_series.chunks(TANGENT_CHUNK))
            .enumerate()
        {
            let kes: Vec<_> = series
                .par_iter()
                .zip(elements.par_iter())
                .with_min_len(PAR_MIN)
                .map_init(FullMapCache::default, |cache, (st, e)| st.tangent(e, cache))
                .collect();
            let first = chunk * TANGENT_CHUNK;
            // One block per thread (one on one thread); element by element
            // with searches where the slots did not fit 32 bits.
            let blocks = (self.slots.len() == self.elements.len())
                .then(|| k.column_blocks(rayon::current_num_threads()))
                .flatten();
            match blocks {
                // Each thread adds to its own columns, every element in
                // order: the same sums as one thread.
                Some(blocks) => {
                    let slots = &self.slots[first..first + elements.len()];
                    let mut rl = Some(&mut rl[..]);
                    let work: Vec<_> = blocks.into_iter().map(|b| (b, rl.take())).collect();
                    work.into_par_iter().for_each(|(block, rl)| {
                        self.scatter_block(elements, slots, &kes, block, rl);
                    });
                }
                None => {
                    for (i, (e, ke)) in elements.iter().zip(&kes).enumerate() {
                        let slots = self.slots.get(first + i);
                        self.scatter_element(e, slots, ke, &mut k, &mut rl);
                    }
                }
            }
        }
        let prescribed = &self.prescribed;
        let add = |k: &mut SparseMatrix,
                   free: &[Option<usize>],
                   rl: &mut [f64],
                   gi: usize,
                   gj: usize,
                   v: f64| match (free[gi], free[gj]) {
            (Some(i), Some(j)) => k.add(i, j, v),
            (Some(_), None) => rl[gi] += v * prescribed[gj],
            _ => {}
        };
        for c in &self.follower {
            let a3 = self.a30[c.node] + Self::vec3(&full, c.node, 3);
            let fw = c.moment.cross(&a3);
            let m = c.moment;
            // d(-λ m × w)/dw = -λ [m]×.
            let mx = [[0.0, -m[2], m[1]], [m[2], 0.0, -m[0]], [-m[1], m[0], 0.0]];
            for i in 0..3 {
                rl[dof(c.node, 3 + i)] -= fw[i];
                for j in 0..3 {
                    add(
                        &mut k,
                        &self.free,
                        &mut rl,
                        dof(c.node, 3 + i),
                        dof(c.node, 3 + j),
                        -lambda * mx[i][j],
                    );
                }
            }
        }
        for pr in &self.pressures {
            let x = self.pressure_x(pr, &full, true);
            let f = surface_load::follower_forces(pr.pressure, &x);
            let kf = surface_load::follower_stiffness(pr.pressure, &x);
            for a in 0..12 {
                let ga = dof(pr.nodes[a / 3], a % 3);
                rl[ga] -= f[a / 3][a % 3];
                for b in 0..12 {
                    let gb = dof(pr.nodes[b / 3], b % 3);
                    add(&mut k, &self.free, &mut rl, ga, gb, -lambda * kf[a][b]);
                }
            }
        }
        let obstacles = self.obstacles_at(lambda);
        let blocks: Vec<_> = self
            .active
            .par_iter()
            .with_min_len(PAR_MIN)
            .map(|&ip| self.contact_block(ip, &full, &obstacles, lambda))
            .collect::<Result<_>>()?;
        for (&ip, (node, kc)) in self.active.iter().zip(blocks) {
            // The gap reads x − lambda V: the lambda column is −K_c V.
            let vel = self.motions[self.pairs[ip].obstacle].velocity();
            let rows = [0, 1, 2].map(|i| self.free[dof(node, i)]);
            if let [Some(a), Some(b), Some(c)] = rows {
                // A free node: its rows are one run of each column, at the
                // slots found when the pattern was built (a search per
                // column cost ~1 ms per tangent at 2,115 pairs).
                let slots = self.pair_slots.get(ip).filter(|s| !s.contains(&NO_SLOT));
                for (j, col) in [a, b, c].into_iter().enumerate() {
                    let run = [kc[0][j], kc[1][j], kc[2][j]];
                    match slots {
                        Some(s) => k.add_at_slots(s[j] as usize, &run),
                        None => k.add_sorted_rows(&[a, b, c], col, &run),
                    }
                }
                for i in 0..3 {
                    for j in 0..3 {
                        rl[dof(node, i)] -= kc[i][j] * vel[j];
                    }
                }
            } else {
                for i in 0..3 {
                    for j in 0..3 {
                        add(
                            &mut k,
                            &self.free,
                            &mut rl,
                            dof(node, i),
                            dof(node, j),
                            kc[i][j],
                        );
                        rl[dof(node, i)] -= kc[i][j] * vel[j];
                    }
                }
            }
        }
        if let Some((row, _, _)) = k.first_non_finite() {
            let i = self.free.iter().position(|f| *f == Some(row)).unwrap_or(0);
            return Err(Error::NonFinite {
                step: 0,
                param: "lambda",
                at: lambda,
                what: format!("tangent matrix (entry {row}: {})", self.dof_label(i)),
            });
        }
        Ok((k, self.reduce(&rl)))
    }

    /// The elements' inner terms of order p (series::ElementSeries::prepare)
    /// on one thread, while order p − 1 is solved on another: on large
    /// models the solve is sequential and the elements stream their series
    /// from memory, so the two overlap.
    /// Where the solve ends first, the job stops and the series' pass
    /// prepares the elements it did not reach (on both threads): the same
    /// terms, summed in the same order.
    fn rhs_prepass(&mut self, p: usize) -> Option<Prepass<'_>> {
        if p < 4 || self.el_series.len() < PREPASS_MIN_ELEMENTS {
            return None;
        }
        self.prepass_order = Some(p);
        let series = &mut self.el_series;
        Some(Box::new(move |done: &AtomicBool| {
            for i in 0..series.len() {
                if done.load(Ordering::Relaxed) {
                    break;
                }
                if let Some(after) = series.get(i + 2) {
                    after.prefetch_record();
                }
                if let Some(next) = series.get(i + 1) {
                    next.prefetch_inner();
                }
                series[i].prepare(p);
            }
        }))
    }

    fn series_rhs(&mut self, p: usize, u: &[Vec<f64>], lambda: &[f64]) -> Result<Vec<f64>> {
        let fresh = self.el_series.first().map_or(0, |s| s.orders());
        if fresh != p - 1 || self.series_u0 != u[0] || self.series_lambda0 != lambda[0] {
            self.start_series(&u[0], lambda[0])?;
            for m in 1..p - 1 {
                self.complete_order(&u[m], lambda[m]);
            }
        }
        // Order p − 1 completed and the order-p element terms in one pass
        // over the elements: each element's data (its map above all) is
        // read from memory once per order instead of twice. Chunks of
        // elements in parallel, each element prefetching the next one's
        // data while it computes (fe::prefetch); summed in element order
        // (the same sums as a sequential loop).
        let full = self.expand(&u[p - 1], lambda[p - 1]);
        // Into one buffer allocated here, on this thread: blocks allocated
        // on the pool's threads (the main thread is one of them) would
        // split the large free blocks of this thread's heap.
        let mut forces = vec![[0.0; NDOF_EL]; self.elements.len()];
        let mut pair_forces = vec![Vec3::zeros(); self.pair_series.len()];
        let (elements, el_series) = (&self.elements, &mut self.el_series);
        let (pairs, motions, pair_series) = (&self.pairs, &self.motions, &mut self.pair_series);
        let lm = lambda[p - 1];
        // Inner terms of order p were asked for: where the job stopped
        // before an element, they are computed here.
        let prepared = self.prepass_order.take() == Some(p);
        // The elements and the contact pairs at once: the threads that
        // finish one take work from the other.
        rayon::join(
            || {
                forces
                    .par_chunks_mut(PAR_MIN)
                    .zip(elements.par_chunks(PAR_MIN))
                    .zip(el_series.par_chunks_mut(PAR_MIN))
                    .for_each(|((out, elements), series)| {
                        let mut cache = FullMapCache::default();
                        for i in 0..elements.len() {
                            // Two elements ahead the records, one ahead the
                            // data the records point to.
                            if let (Some(e), Some(st)) = (elements.get(i + 2), series.get(i + 2)) {
                                e.prefetch_record();
                                st.prefetch_record();
                            }
                            if let (Some(e), Some(st)) = (elements.get(i + 1), series.get(i + 1)) {
                                if st.has_ahead(p) {
                                    st.prefetch_outer(e);
                                } else {
                                    st.prefetch(e);
                                }
                            }
                            let e = &elements[i];
                            if prepared && !series[i].has_ahead(p) {
                                series[i].prepare(p);
                            }
                            let (x, d) = Self::element_coefficients(e, &full);
                            out[i] = series[i].complete_and_rhs(e, &x, &d, &mut cache);
                        }
                    })
            },
            // Each pair completed with order p − 1, then its order-p force
            // (buffers sized at the step start: no allocation here).
            // Each pair prefetching the next one's series (12 small blocks).
            || {
                pair_forces
                    .par_chunks_mut(PAR_MIN)
                    .zip(pair_series.par_chunks_mut(PAR_MIN))
                    .for_each(|(out, series)| {
                        for i in 0..series.len() {
                            if let Some(next) = series.get(i + 1) {
                                next.prefetch();
                            }
                            let ps = &mut series[i];
                            Self::complete_pair(pairs, motions, ps, &full, lm);
                            out[i] = Self::pair_force_star(pairs, ps, p);
                        }
                    })
            },
        );
        let mut rhs = vec![0.0; self.free.len()];
        for (e, f) in self.elements.iter().zip(&forces) {
            for (i, &n) in e.nodes.iter().enumerate() {
                for k in 0..6 {
                    rhs[dof(n, k)] += f[6 * i + k];
                }
            }
        }
        if !self.follower.is_empty() {
            let fulls: Vec<Vec<f64>> = (1..p).map(|r| self.expand(&u[r], lambda[r])).collect();
            for c in &self.follower {
                let mut s = Vec3::zeros();
                for r in 1..p {
                    s += c.moment.cross(&Self::vec3(&fulls[p - r - 1], c.node, 3)) * lambda[r];
                }
                for k in 0..3 {
                    rhs[dof(c.node, 3 + k)] -= s[k];
                }
            }
        }
        if !self.pressures.is_empty() {
            // x_s of every order s < p (x_0 = X + v_0).
            let fulls: Vec<Vec<f64>> = (0..p).map(|r| self.expand(&u[r], lambda[r])).collect();
            for pr in &self.pressures {
                let xs: Vec<[Vec3; 4]> = (0..p)
                    .map(|s| self.pressure_x(pr, &fulls[s], s == 0))
                    .collect();
                let b = |i: usize, j: usize| {
                    surface_load::follower_bilinear(pr.pressure, &xs[i], &xs[j])
                };
                let mut total = [Vec3::zeros(); 4];
                let mut accumulate = |scale: f64, f: [Vec3; 4]| {
                    for i in 0..4 {
                        total[i] += f[i] * scale;
                    }
                };
                // λ_0 f*_p.
                for s in 1..p {
                    accumulate(lambda[0], b(s, p - s));
                }
                // λ_r f_{p−r}, r = 1..p−1.
                for r in 1..p {
                    let q = p - r;
                    for s in 0..=q {
                        accumulate(lambda[r], b(s, q - s));
                    }
                }
                for (i, &n) in pr.nodes.iter().enumerate() {
                    for k in 0..3 {
                        rhs[dof(n, k)] -= total[i][k];
                    }
                }
            }
        }
        // Added in pair order.
        for (ps, f) in self.pair_series.iter().zip(&pair_forces) {
            let node = self.pairs[ps.pair].node;
            for k in 0..3 {
                rhs[dof(node, k)] -= f[k];
            }
        }
        self.check_finite(&rhs, lambda[0], "series right-hand side")?;
        Ok(self.reduce(&rhs))
    }
}

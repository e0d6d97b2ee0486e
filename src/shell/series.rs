//! The element's internal force along one ANM step, in nodal Gram form.
//!
//! With the element's nodal vectors as the columns of Y (position
//! differences and directors, kinematics::NodalVectors), every strain
//! component is linear in the Gram matrix M = YᵀY − Y_refᵀY_ref
//! (kinematics::Point::gram_strain), the stresses are linear in the strains,
//! and the internal force on Y is f = Y Kg(σ) (on the element unknowns:
//! kinematics::element_force). Along the series Y(a) = Σ_r Y_r a^r:
//!
//! ```text
//! M_p  = Σ_{r=0}^{p} Y_rᵀ Y_{p−r},        Kg_p = K(M_p)      (p ≥ 1)
//! f_p  = Σ_{r=0}^{p} Y_r Kg_{p−r}
//! f*_p = Y_0 K(M*_p) + Σ_{r=1}^{p−1} Y_r Kg_{p−r},   M*_p = Σ_{r=1}^{p−1} Y_rᵀ Y_{p−r}
//! ```
//!
//! with K the element's precomputed linear map M ↦ Kg(σ(E(M)))
//! ([`ShellElement::packed_geometric`]) and f*_p the right-hand side of order p
//! (order-p unknowns set to zero). The convolutions run on 3×7 and 7×7
//! matrices instead of the 12 sampling points, and the strain-to-stress path
//! (ANS, EAS, material) costs one 28×28 product per order.
//!
//! Order 0 is taken pointwise from the full state
//! ([`ShellElement::state_geometric`]): M_0 would subtract two nearly equal
//! Gram matrices.

use super::element::{ElementMatrix, FullMapCache, ShellElement};
use super::kinematics::{
    NCOL, NDOF_EL, NDOF_Y, NSYM, NodalVectors, PackedSym, SYM_INDEX, SYM_PAIRS, Vec3, YMatrix,
    element_force, element_matrix, nodal_vectors, pack,
};
use crate::fe::prefetch::{prefetch, prefetch_growing, prefetch_spare};

/// Series of one element over an ANM step: nodal vectors and geometric
/// stiffnesses of every complete order.
///
/// Memory is what limits the model size (one of these per element): the
/// stiffnesses are stored packed (28 of the 49 entries of a symmetric 7×7),
/// and the order-1 map T = K(Y_0ᵀδY + δYᵀY_0) (28×21, 4.7 kB) is not stored
/// but rebuilt by the tangent, its only user; an order is completed through
/// K directly, Kg_m = K(M*_m) + K(Y_0ᵀY_m + Y_mᵀY_0).
#[derive(Clone)]
pub struct ElementSeries {
    y: Vec<NodalVectors>,
    kg: Vec<PackedSym>,
    /// Kg*_p = K(M*_p) of the last right-hand side, with its order p.
    kg_star: Option<(usize, PackedSym)>,
    /// The part of the order-q right-hand side computed ahead
    /// ([`ElementSeries::prepare`]), with its order q.
    ahead: Option<Ahead>,
}

/// The terms of the order-q right-hand side that do not read order q − 1
/// nor order 1 on the left: M_inner = Σ_{r=2}^{q−2} Y_rᵀY_{q−r} and
/// f_inner = Σ_{r=2}^{q−2} Y_r Kg_{q−r}.
#[derive(Clone)]
struct Ahead {
    order: usize,
    gram: PackedSym,
    force: NodalVectors,
}

/// A symmetric 7×7 sum held whole, rows padded to 8: every entry of a
/// Gram term is then one lane of a vector sum over the rows of Y, and the
/// 28 packed entries are picked once at the end. Each entry is the same sum
/// in the same order as entry by entry (Σ_d over the three rows, then
/// added pair after pair): the same results to the bit, and a convolution
/// of 7 pairs 92 → 48 ns per pair (a stand-alone benchmark).
type GramRows = [[f64; 8]; NCOL];

/// The three rows of Y, padded to 8.
fn rows_of(y: &NodalVectors) -> [[f64; 8]; 3] {
    let mut rows = [[0.0; 8]; 3];
    for (d, row) in rows.iter_mut().enumerate() {
        for (a, v) in row.iter_mut().take(NCOL).enumerate() {
            *v = y[(d, a)];
        }
    }
    rows
}

/// acc += YᵣᵀYₛ + YₛᵀYᵣ (yr, ys: rows of Yᵣ, Yₛ; ys = None: YᵣᵀYᵣ).
fn add_gram_rows(yr: &[[f64; 8]; 3], ys: Option<&[[f64; 8]; 3]>, acc: &mut GramRows) {
    for (a, out) in acc.iter_mut().enumerate() {
        let mut t = [-0.0; 8];
        for d in 0..3 {
            let ra = yr[d][a];
            match ys {
                Some(ys) => {
                    let sa = ys[d][a];
                    for ((v, s), r) in t.iter_mut().zip(&ys[d]).zip(&yr[d]) {
                        *v += ra * s + sa * r;
                    }
                }
                None => {
                    for (v, r) in t.iter_mut().zip(&yr[d]) {
                        *v += ra * r;
                    }
                }
            }
        }
        for (o, v) in out.iter_mut().zip(&t) {
            *o += v;
        }
    }
}

/// The packed upper triangle of a whole sum.
fn packed(acc: &GramRows) -> PackedSym {
    PackedSym::from_fn(|k, _| {
        let (a, b) = SYM_PAIRS[k];
        acc[a][b]
    })
}

/// Σ_{r=lo}^{p−lo} Y_rᵀ Y_{p−r}, packed: each pair (r, p−r) once.
fn gram_convolution(y: &[NodalVectors], p: usize, lo: usize) -> PackedSym {
    let mut acc = [[0.0; 8]; NCOL];
    let mut r = lo;
    while 2 * r < p {
        add_gram_rows(&rows_of(&y[r]), Some(&rows_of(&y[p - r])), &mut acc);
        r += 1;
    }
    if p.is_multiple_of(2) && p / 2 >= lo {
        add_gram_rows(&rows_of(&y[p / 2]), None, &mut acc);
    }
    packed(&acc)
}

/// m += YᵣᵀYₛ + YₛᵀYᵣ, packed.
fn add_gram_pair(yr: &NodalVectors, ys: &NodalVectors, m: &mut PackedSym) {
    let mut acc = [[0.0; 8]; NCOL];
    add_gram_rows(&rows_of(yr), Some(&rows_of(ys)), &mut acc);
    *m += packed(&acc);
}

/// f += Y Kg for a packed symmetric Kg, row by row of f: Kg unpacked to
/// rows padded to 8, so that each row of f is a sum of 7 scaled rows of Kg
/// that vectorizes (a column of f, 3 entries, does not). Every entry is the
/// same sum in the same order as column by column, Σ_a Y_da Kg_ab for
/// a = 0..7, then added to f: the same results to the bit. The three rows
/// are summed apart and added to f after (adding each row to f as it was
/// done made the product 1.7× slower: 52 against 30 ns in a loop of 12
/// products, same bits).
fn add_product(y: &NodalVectors, kg: &PackedSym, f: &mut NodalVectors) {
    let mut k = [[0.0; 8]; NCOL];
    for (a, row) in k.iter_mut().enumerate() {
        for (b, v) in row.iter_mut().take(NCOL).enumerate() {
            *v = kg[SYM_INDEX[a][b]];
        }
    }
    let mut rows = [[0.0; 8]; 3];
    for (d, acc) in rows.iter_mut().enumerate() {
        for (a, row) in k.iter().enumerate() {
            let yda = y[(d, a)];
            for (s, v) in acc.iter_mut().zip(row) {
                *s += yda * v;
            }
        }
    }
    for (d, acc) in rows.iter().enumerate() {
        for (b, s) in acc.iter().take(NCOL).enumerate() {
            f[(d, b)] += s;
        }
    }
}

impl ElementSeries {
    /// Order 0 at the state (x0, d0).
    pub fn start(e: &ShellElement, x0: &[Vec3; 4], d0: &[Vec3; 4]) -> Self {
        let mut series = Self {
            y: vec![],
            kg: vec![],
            kg_star: None,
            ahead: None,
        };
        series.restart(e, x0, d0);
        series
    }

    /// Room for `orders` orders (no allocation while they are completed).
    pub fn reserve(&mut self, orders: usize) {
        let more = orders.saturating_sub(self.y.len());
        self.y.reserve(more);
        self.kg.reserve(more);
    }

    /// Order 0 at the state (x0, d0), in the buffers of an earlier series.
    pub fn restart(&mut self, e: &ShellElement, x0: &[Vec3; 4], d0: &[Vec3; 4]) {
        self.restart_with(x0, d0, pack(&e.state_geometric(x0, d0)));
    }

    /// [`ElementSeries::restart`] with Kg_0 = Kg(σ(x0, d0)) given (from
    /// ShellElement::internal_and_geometric at the same state).
    pub fn restart_with(&mut self, x0: &[Vec3; 4], d0: &[Vec3; 4], kg0: PackedSym) {
        self.y.clear();
        self.kg.clear();
        self.y.push(nodal_vectors(x0, d0));
        self.kg.push(kg0);
        self.kg_star = None;
        self.ahead = None;
    }

    /// The inner terms of the order-q right-hand side ([`Ahead`]), from
    /// orders 2 … q − 2: computed while order q − 1 is being solved
    /// (ContinuationProblem::rhs_prepass), they leave to
    /// [`ElementSeries::complete_and_rhs`] only the terms with orders 0, 1
    /// and q − 1 and the products with the element's map. Needs orders
    /// 0 … q − 2 complete and q ≥ 4 (else nothing is done).
    pub fn prepare(&mut self, q: usize) {
        if q < 4 || self.y.len() != q - 1 {
            return;
        }
        let gram = gram_convolution(&self.y, q, 2);
        let mut force = NodalVectors::zeros();
        for r in 2..=q - 2 {
            add_product(&self.y[r], &self.kg[q - r], &mut force);
        }
        self.ahead = Some(Ahead {
            order: q,
            gram,
            force,
        });
    }

    /// Prefetches what [`ElementSeries::complete_and_rhs`] reads once the
    /// inner terms are ready: orders 0 and 1, the inner terms, the map.
    pub fn prefetch_outer(&self, e: &ShellElement) {
        prefetch(&self.y[..2.min(self.y.len())]);
        prefetch(&self.kg[..2.min(self.kg.len())]);
        prefetch_spare(&self.y, 1);
        prefetch_spare(&self.kg, 1);
        if let Some(a) = &self.ahead {
            prefetch(std::slice::from_ref(a));
        }
        e.prefetch_map();
    }

    /// Prefetches what [`ElementSeries::prepare`] reads: the series'
    /// orders, not the map.
    pub fn prefetch_inner(&self) {
        prefetch(&self.y);
        prefetch(&self.kg);
    }

    /// Prefetches what [`ElementSeries::restart_with`] writes: the record
    /// and the first slots of the orders.
    pub fn prefetch_start(&self) {
        self.prefetch_record();
        prefetch(&self.y[..1.min(self.y.len())]);
        prefetch(&self.kg[..1.min(self.kg.len())]);
    }

    /// Prefetches the series' own record (the headers of its orders and
    /// the inner terms): one element before [`ElementSeries::prefetch`] or
    /// [`ElementSeries::prefetch_outer`], which read those headers to find
    /// the orders (a read of a record the other thread wrote during the
    /// solve otherwise stalls the loop).
    pub fn prefetch_record(&self) {
        prefetch(std::slice::from_ref(self));
    }

    /// Whether the inner terms of order q are ready.
    pub fn has_ahead(&self, q: usize) -> bool {
        self.ahead.as_ref().is_some_and(|a| a.order == q)
    }

    /// Prefetches the series' data and the element's map (fe::prefetch):
    /// what [`ElementSeries::complete_and_rhs`] reads.
    pub fn prefetch(&self, e: &ShellElement) {
        prefetch_growing(&self.y);
        prefetch_growing(&self.kg);
        e.prefetch_map();
    }

    pub fn orders(&self) -> usize {
        self.y.len()
    }

    /// The condensed tangent at the step start, f_1 = K_t q_1: on Y,
    /// δf = δY Kg_0 + Y_0 K(Y_0ᵀδY + δYᵀY_0), the geometric part Kg_0 ⊗ I3
    /// and the material part Y_0 T; then mapped to the element unknowns.
    pub fn tangent(&self, e: &ShellElement, cache: &mut FullMapCache) -> ElementMatrix {
        let (y0, kg0) = (&self.y[0], &self.kg[0]);
        let jac = e.gram_jacobian(y0, cache);
        let mut k = YMatrix::zeros();
        // Column j: Y_0 times the column's packed matrix, unpacked on the fly
        // (entry (d, c) is packed at SYM_INDEX[d][c]).
        for (kc, t) in k
            .as_mut_slice()
            .chunks_exact_mut(NDOF_Y)
            .zip(jac.as_slice().chunks_exact(NSYM))
        {
            for (c, out) in kc.chunks_exact_mut(3).enumerate() {
                let mut acc = [0.0; 3];
                for d in 0..NCOL {
                    let v = t[SYM_INDEX[d][c]];
                    for (i, a) in acc.iter_mut().enumerate() {
                        *a += y0[(i, d)] * v;
                    }
                }
                out.copy_from_slice(&acc);
            }
        }
        // Kg_0 ⊗ I3.
        for a in 0..NCOL {
            for b in 0..NCOL {
                let g = kg0[SYM_INDEX[a][b]];
                for i in 0..3 {
                    k[(3 * a + i, 3 * b + i)] += g;
                }
            }
        }
        element_matrix(&k)
    }

    /// Completes order m = orders() from the order-m nodal increments:
    /// Kg_m = K(M*_m) + K(Y_0ᵀY_m + Y_mᵀY_0), with K(M*_m) from the
    /// right-hand side of order m when it was computed.
    pub fn complete(&mut self, e: &ShellElement, xm: &[Vec3; 4], dm: &[Vec3; 4]) {
        let m = self.y.len();
        let kg_star = match self.kg_star.take() {
            Some((p, kg)) if p == m => kg,
            _ if m == 1 => PackedSym::zeros(),
            _ => e.packed_geometric(&gram_convolution(&self.y, m, 1)),
        };
        let ym = nodal_vectors(xm, dm);
        let mut first = PackedSym::zeros();
        add_gram_pair(&self.y[0], &ym, &mut first);
        self.kg.push(kg_star + e.packed_geometric(&first));
        self.y.push(ym);
    }

    /// The element right-hand side f*_p of order p = orders(), in the
    /// element unknown layout (v, w per node).
    pub fn rhs(&mut self, e: &ShellElement) -> [f64; NDOF_EL] {
        let p = self.y.len();
        let kg_star = e.packed_geometric(&gram_convolution(&self.y, p, 1));
        self.force(p, kg_star)
    }

    /// [`ElementSeries::complete`] of order m, then [`ElementSeries::rhs`]
    /// of order m + 1, with one pass over the element's map for the two
    /// products K(Y_0ᵀY_m + Y_mᵀY_0) and K(M*_(m+1)): the map is the
    /// largest datum of an element, and the series streams every element
    /// once per order.
    pub fn complete_and_rhs(
        &mut self,
        e: &ShellElement,
        xm: &[Vec3; 4],
        dm: &[Vec3; 4],
        cache: &mut FullMapCache,
    ) -> [f64; NDOF_EL] {
        let m = self.y.len();
        let kg_star_m = match self.kg_star.take() {
            Some((p, kg)) if p == m => kg,
            _ if m == 1 => PackedSym::zeros(),
            _ => {
                self.complete(e, xm, dm);
                return self.rhs(e);
            }
        };
        let ym = nodal_vectors(xm, dm);
        let mut first = PackedSym::zeros();
        add_gram_pair(&self.y[0], &ym, &mut first);
        self.y.push(ym);
        let q = m + 1;
        let Some(ahead) = self.ahead.take().filter(|a| a.order == q) else {
            let (kg_first, kg_star) =
                e.packed_geometric_pair(&first, &gram_convolution(&self.y, q, 1), cache);
            self.kg.push(kg_star_m + kg_first);
            return self.force(q, kg_star);
        };
        // M*_q = M_inner + Y_1ᵀY_m + Y_mᵀY_1; f*_q = Y_0 K(M*_q) + Y_1 Kg_m
        // + f_inner + Y_m Kg_1 (q ≥ 4: orders 1 and m differ).
        let mut gram = ahead.gram;
        add_gram_pair(&self.y[1], &self.y[m], &mut gram);
        let (kg_first, kg_star) = e.packed_geometric_pair(&first, &gram, cache);
        self.kg.push(kg_star_m + kg_first);
        let mut f = ahead.force;
        add_product(&self.y[0], &kg_star, &mut f);
        add_product(&self.y[1], &self.kg[m], &mut f);
        add_product(&self.y[m], &self.kg[1], &mut f);
        self.kg_star = Some((q, kg_star));
        element_force(&f)
    }

    /// f*_p = Y_0 Kg*_p + Σ_{r=1}^{p−1} Y_r Kg_{p−r}, keeping Kg*_p for
    /// the completion of order p.
    fn force(&mut self, p: usize, kg_star: PackedSym) -> [f64; NDOF_EL] {
        let y = &self.y;
        let mut f = NodalVectors::zeros();
        add_product(&y[0], &kg_star, &mut f);
        for (yr, kg) in y[1..].iter().zip(self.kg[1..].iter().rev()) {
            add_product(yr, kg, &mut f);
        }
        self.kg_star = Some((p, kg_star));
        element_force(&f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{SMatrix, SVector};

    use crate::shell::element::tests::element;

    /// add_product row by row equals the column-by-column sums
    /// Σ_a Y_da Kg_ab (a = 0..7, in order) to the bit.
    #[test]
    fn product_by_rows_equals_the_column_sums_to_the_bit() {
        let y = NodalVectors::from_fn(|d, a| ((3 * a + d) as f64 * 0.37).sin());
        let kg = PackedSym::from_fn(|k, _| (k as f64 * 1.9 + 0.3).cos() * 1e4);
        let f0 = NodalVectors::from_fn(|d, a| (d + a) as f64 * 1e-3);
        let mut f = f0;
        add_product(&y, &kg, &mut f);
        for b in 0..NCOL {
            for d in 0..3 {
                let mut s = 0.0;
                for a in 0..NCOL {
                    s += y[(d, a)] * kg[SYM_INDEX[a][b]];
                }
                let want = f0[(d, b)] + s;
                assert_eq!(f[(d, b)].to_bits(), want.to_bits(), "({d}, {b})");
            }
        }
    }

    /// The Gram convolution held whole equals the entry-by-entry sums
    /// (Σ_d over the rows, pair after pair, the middle term last) to the
    /// bit, for odd and even orders and both lower bounds.
    #[test]
    fn gram_convolution_equals_the_entry_sums_to_the_bit() {
        let y: Vec<NodalVectors> = (0..9)
            .map(|r| {
                NodalVectors::from_fn(|d, a| ((3 * a + d + 11 * r) as f64 * 0.37).sin() * 1e-2)
            })
            .collect();
        for (p, lo) in [(7, 1), (8, 1), (8, 2), (5, 2)] {
            let m = gram_convolution(&y, p, lo);
            for (k, &(a, b)) in SYM_PAIRS.iter().enumerate() {
                let mut want = 0.0;
                let mut r = lo;
                while 2 * r < p {
                    let (yr, ys) = (&y[r], &y[p - r]);
                    want += (0..3)
                        .map(|d| yr[(d, a)] * ys[(d, b)] + ys[(d, a)] * yr[(d, b)])
                        .sum::<f64>();
                    r += 1;
                }
                if p % 2 == 0 && p / 2 >= lo {
                    let h = &y[p / 2];
                    want += (0..3).map(|d| h[(d, a)] * h[(d, b)]).sum::<f64>();
                }
                assert_eq!(m[k].to_bits(), want.to_bits(), "p {p}, lo {lo}, ({a}, {b})");
            }
        }
    }

    fn nodal(seed: f64, scale: f64) -> ([Vec3; 4], [Vec3; 4]) {
        let v =
            |i: usize| Vec3::from_fn(|k, _| scale * (seed * (3 * i + k + 1) as f64 * 0.61).sin());
        (
            std::array::from_fn(v),
            std::array::from_fn(|i| v(i + 4) * 0.5),
        )
    }

    /// Along the path Y(a) = Y_0 + a Y_1 + a² Y_2 the internal force is a
    /// polynomial of degree 6 in a (quadratic strain, linear stress, B
    /// linear): its coefficients f_p, from 7 evaluations, must equal
    /// f*_p + K_t q_p, the series right-hand side plus the order-p
    /// unknowns through the tangent at Y_0 (measured: 1e-12 relative, with
    /// f_p of the size of f_1).
    #[test]
    fn series_rhs_plus_tangent_term_is_the_taylor_coefficient_of_the_force() {
        let (e, x0, d0) = element();
        let (v0, w0) = nodal(1.0, 0.02);
        let ys = [nodal(2.0, 0.05), nodal(3.0, 0.03)];
        let (xs0, ds0): ([Vec3; 4], [Vec3; 4]) = (
            std::array::from_fn(|i| x0[i] + v0[i]),
            std::array::from_fn(|i| d0[i] + w0[i]),
        );
        let at = |a: f64| -> ([Vec3; 4], [Vec3; 4]) {
            (
                std::array::from_fn(|i| xs0[i] + ys[0].0[i] * a + ys[1].0[i] * a * a),
                std::array::from_fn(|i| ds0[i] + ys[0].1[i] * a + ys[1].1[i] * a * a),
            )
        };
        // Coefficients by interpolation at a = -3..3.
        let nodes: [f64; 7] = std::array::from_fn(|j| j as f64 - 3.0);
        let v = SMatrix::<f64, 7, 7>::from_fn(|j, p| nodes[j].powi(p as i32));
        let vinv = v.try_inverse().unwrap();
        let forces: Vec<[f64; NDOF_EL]> = nodes
            .iter()
            .map(|&a| {
                let (x, d) = at(a);
                e.internal(&x, &d)
            })
            .collect();
        let coeff = |p: usize| -> SVector<f64, NDOF_EL> {
            SVector::from_fn(|k, _| (0..7).map(|j| vinv[(p, j)] * forces[j][k]).sum())
        };
        let mut st = ElementSeries::start(&e, &xs0, &ds0);
        let kt = st.tangent(&e, &mut FullMapCache::default());
        let q = |p: usize| -> SVector<f64, NDOF_EL> {
            if p > 2 {
                return SVector::zeros();
            }
            let (x, d) = &ys[p - 1];
            SVector::from_fn(|a, _| {
                if a % 6 < 3 {
                    x[a / 6][a % 3]
                } else {
                    d[a / 6][a % 3]
                }
            })
        };
        st.complete(&e, &ys[0].0, &ys[0].1);
        let scale = coeff(1).norm();
        // The fused completion and right-hand side, from a copy one order
        // behind, must give the same right-hand side.
        let mut fused: Option<SVector<f64, NDOF_EL>> = None;
        for p in 2..=6 {
            let rhs = SVector::<f64, NDOF_EL>::from_column_slice(&st.rhs(&e));
            if let Some(f) = fused {
                let diff = (f - rhs).norm() / scale;
                assert!(
                    diff < 1e-14,
                    "order {p}: fused right-hand side off by {diff:.3e}"
                );
            }
            if p == 4 {
                // The other path to Kg_p: without the right-hand side's K(M*_p).
                let mut fresh = st.clone();
                fresh.kg_star = None;
                fresh.complete(&e, &[Vec3::zeros(); 4], &[Vec3::zeros(); 4]);
                let mut via_rhs = st.clone();
                via_rhs.complete(&e, &[Vec3::zeros(); 4], &[Vec3::zeros(); 4]);
                let diff = (fresh.kg[p] - via_rhs.kg[p]).norm() / via_rhs.kg[p].norm();
                assert!(diff < 1e-13, "Kg_{p} by two paths: {diff:.3e}");
            }
            let err = (rhs + kt * q(p) - coeff(p)).norm() / scale;
            assert!(err < 1e-10, "order {p}: relative error {err:.3e}");
            let (xp, dp) = if p <= 2 {
                ys[p - 1]
            } else {
                ([Vec3::zeros(); 4], [Vec3::zeros(); 4])
            };
            let mut ahead = st.clone();
            let f = SVector::from_column_slice(&ahead.complete_and_rhs(
                &e,
                &xp,
                &dp,
                &mut FullMapCache::default(),
            ));
            // With the inner terms of order p + 1 computed beforehand (as
            // during the solve of order p): the same right-hand side.
            if p + 1 >= 4 {
                let mut prepared = st.clone();
                prepared.prepare(p + 1);
                assert!(prepared.has_ahead(p + 1));
                let g = SVector::<f64, NDOF_EL>::from_column_slice(&prepared.complete_and_rhs(
                    &e,
                    &xp,
                    &dp,
                    &mut FullMapCache::default(),
                ));
                let diff = (f - g).norm() / scale;
                assert!(
                    diff < 1e-14,
                    "order {}: prepared right-hand side off by {diff:.3e}",
                    p + 1
                );
                assert_eq!(prepared.kg[p], ahead.kg[p]);
            }
            fused = Some(f);
            st.complete(&e, &xp, &dp);
        }
    }
}
